"""The settings of a simulation, written once: :class:`SimConfig` (numerics, screens, logging) and :class:`SimInputs`.

:func:`qprr.sim.simulate` takes both as keyword arguments (``simulate(p, c, ref, 5.0, dt=2e-3,
xi0=...)``) or as objects (``config=SimConfig(...)``, ``inputs=SimInputs(...)``); the keyword
form is turned into these objects by :func:`config_and_inputs`, so every setting has one default (the
field's) and is validated once (in ``__post_init__``).  The scenario registries take their
defaults from here (``SimConfig.dt``).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass

from ..errors import InputError, UnknownNameError
from ..validation import as_int, as_real
from .integrators import DEFAULT_INTEGRATOR, INTEGRATORS

_GIB = 2.0**30


@dataclass(frozen=True)
class Limits:
    """Runaway bounds: a state beyond them stops the run with DivergenceError."""

    position: float = 1e3  # m
    linear_velocity: float = 100.0  # m/s
    angular_velocity: float = 100.0  # rad/s
    joint_velocity: float = 100.0  # m/s or rad/s

    def __post_init__(self) -> None:
        for name in ("position", "linear_velocity", "angular_velocity", "joint_velocity"):
            object.__setattr__(self, name, as_real(getattr(self, name), f"limits {name}", positive=True, allow_inf=True))


def _physical_memory() -> float:
    """Bytes of physical memory (8 GiB where the system does not say)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return 8.0 * _GIB


@dataclass(frozen=True)
class SimConfig:
    """How a run is computed, screened and logged (validated on construction).

    Parameters
    ----------
    dt : integration step [s].
    integrator : ``"midpoint"`` (second order, the default), ``"rk4"`` (fourth order) or ``"euler"``
        (semi-implicit, first order), all on the Lie group, or a plug-in's: a name of the registry
        :data:`qprr.sim.integrators.INTEGRATORS`.
    control_period : period of the digital controller [s], an integer multiple of ``dt``
        (default None: ``dt``).  The controller, the allocation, the disturbance samples and the
        payload changes act at the control ticks; the result has one row per tick.
    seed : seeds the noise and the wind turbulence (None: fresh entropy).
    limits : the runaway bounds (:class:`Limits`).
    joint_stops : the arm joints end at mechanical stops at their limits
        (:func:`qprr.sim.stops.apply_joint_stops`); the initial state and every arm reference must
        then lie inside the limits.
    progress : a text progress bar on stderr.
    scenario : the label the result carries.
    max_log_bytes : bound on the memory of the run's logs and reference samples [bytes]; None
        (default): half the machine's physical memory.  A duration whose logs exceed it is refused
        before anything is allocated (:meth:`ticks`).
    """

    dt: float = 1e-3
    integrator: str = DEFAULT_INTEGRATOR
    control_period: float | None = None
    seed: int | None = 0
    limits: Limits = Limits()
    joint_stops: bool = True
    progress: bool = False
    scenario: str = "custom"
    max_log_bytes: float | None = None

    def __post_init__(self) -> None:
        dt = self.dt
        if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not (math.isfinite(dt) and dt > 0.0):
            raise InputError(f"dt must be a positive number of seconds, got {dt!r}")
        object.__setattr__(self, "dt", float(dt))
        if self.integrator not in INTEGRATORS:
            raise UnknownNameError("integrator", self.integrator, tuple(INTEGRATORS))
        self._check_period()
        if self.seed is not None:
            object.__setattr__(self, "seed", as_int(self.seed, "seed", lo=0))
        if not isinstance(self.limits, Limits):
            raise InputError(f"limits must be a qprr.sim.Limits, got {type(self.limits).__name__}")
        for name in ("joint_stops", "progress"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(f"{name} must be True or False, got {getattr(self, name)!r}")
        if not isinstance(self.scenario, str):
            raise InputError(f"scenario must be a label (str), got {self.scenario!r}")
        if self.max_log_bytes is not None:
            object.__setattr__(self, "max_log_bytes", as_real(self.max_log_bytes, "max_log_bytes", positive=True, unit="bytes"))

    def _check_period(self) -> None:
        cp = self.control_period
        if cp is None:
            return
        if isinstance(cp, bool) or not isinstance(cp, (int, float)) or not (math.isfinite(cp) and cp > 0.0):
            raise InputError(f"control_period must be a positive number of seconds, got {cp!r}")
        substeps = int(round(cp / self.dt))
        if substeps < 1 or abs(substeps * self.dt - cp) > 1e-9 * cp:
            raise InputError(f"control_period = {cp!r} s must be an integer multiple of dt = {self.dt!r} s")
        object.__setattr__(self, "control_period", float(cp))

    @property
    def period(self) -> float:
        """The controller's period [s]: ``control_period``, or ``dt`` when it is None."""
        return self.dt if self.control_period is None else self.control_period

    @property
    def substeps(self) -> int:
        """Integration steps per control period."""
        return 1 if self.control_period is None else int(round(self.control_period / self.dt))

    @property
    def log_bound(self) -> float:
        """The bound on the logs' memory actually applied [bytes] (``max_log_bytes`` or half the physical memory)."""
        return self.max_log_bytes if self.max_log_bytes is not None else 0.5 * _physical_memory()

    def ticks(self, duration, bytes_per_tick: int) -> int:
        """Number of control ticks of a run of ``duration`` seconds (its rows), checked against :attr:`log_bound`.

        ``duration`` must be a number of seconds >= the control period; ``bytes_per_tick`` is what one
        row of the logs and reference samples takes.  A run whose logs would exceed the bound is
        refused with an error naming the duration and the step (e.g. ``--duration 1e12``)."""
        period = self.period
        if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not (math.isfinite(duration) and duration >= period):
            raise InputError(f"duration must be a number of seconds >= the control period {period!r} s, got {duration!r}")
        n = duration / period  # a float: an absurd duration must not build an absurd integer first
        need = n * bytes_per_tick
        if need > self.log_bound:
            raise InputError(
                f"duration = {duration!r} s at a control period of {period!r} s (dt = {self.dt!r} s) is {n:.3g} "
                f"control ticks: the logs would take {_size(need)}, more than the {_size(self.log_bound)} allowed "
                "(max_log_bytes; default half the physical memory); shorten the duration or lengthen "
                "control_period"
            )
        return int(round(n))


@dataclass(frozen=True)
class SimInputs:
    """What a run starts from and what acts on it, besides the platform, the controller and the reference.

    Parameters
    ----------
    xi0, xi_dot0 : initial state (default: the reference at t = 0, at rest).
    disturbance : a :class:`~qprr.sim.disturbances.Disturbance`, a
        :class:`~qprr.sim.disturbances.StateDisturbance` or a
        :class:`~qprr.sim.disturbances.Disturbances` sum.
    external_wrench : an :class:`~qprr.sim.environment.Environment` (contact model) or a callable
        ``(t, q, v) -> h`` (6,), the world wrench at the end effector, evaluated at every stage.
    payload : a :class:`~qprr.sim.payload.PayloadSchedule` (the plant's model is a copy).
    allocator : default ``Allocator(platform)`` (:class:`qprr.actuation.Allocator`).
    actuators : a :class:`~qprr.sim.actuators.RotorDynamics` (motor lag, speed limits, thrust b w^2)
        between allocation and plant; None (default): thrusts applied as allocated.
    plant : the robot simulated when it differs from the platform, the model the controller and
        the allocation know (:func:`qprr.sim.mismatch.perturbed`); default: the platform.

    These are checked against the platform by :func:`qprr.sim.simulate`.
    """

    xi0: object = None
    xi_dot0: object = None
    disturbance: object = None
    external_wrench: object = None
    payload: object = None
    allocator: object = None
    actuators: object = None
    plant: object = None


_CONFIG_FIELDS = tuple(f.name for f in dataclasses.fields(SimConfig))
_INPUT_FIELDS = tuple(f.name for f in dataclasses.fields(SimInputs))


def config_and_inputs(config: SimConfig | None, inputs: SimInputs | None, options: dict) -> tuple[SimConfig, SimInputs]:
    """(config, inputs) of a :func:`~qprr.sim.simulate` call: keyword ``options`` are fields of either, given over the objects.

    An unknown keyword raises :class:`~qprr.errors.UnknownNameError` listing the valid ones."""
    if config is not None and not isinstance(config, SimConfig):
        raise InputError(f"config must be a qprr.sim.SimConfig, got {type(config).__name__}")
    if inputs is not None and not isinstance(inputs, SimInputs):
        raise InputError(f"inputs must be a qprr.sim.SimInputs, got {type(inputs).__name__}")
    unknown = [k for k in options if k not in _CONFIG_FIELDS and k not in _INPUT_FIELDS]
    if unknown:
        raise UnknownNameError("simulate option", unknown[0], _CONFIG_FIELDS + _INPUT_FIELDS)
    settings = {k: v for k, v in options.items() if k in _CONFIG_FIELDS}
    given = {k: v for k, v in options.items() if k in _INPUT_FIELDS}
    config = SimConfig(**settings) if config is None else dataclasses.replace(config, **settings) if settings else config
    inputs = SimInputs(**given) if inputs is None else dataclasses.replace(inputs, **given) if given else inputs
    return config, inputs


def _size(n_bytes: float) -> str:
    """A byte count in binary units (KiB ... EiB)."""
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n_bytes < 1024.0:
            return f"{n_bytes:.3g} {unit}"
        n_bytes /= 1024.0
    return f"{n_bytes:.3g} EiB"
