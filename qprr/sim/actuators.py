"""The actuator stage between allocation and plant: rotor speeds with a first-order motor lag.

Without it (the default, and every thesis scenario) the simulator applies the allocated thrusts
at once.  With :class:`RotorDynamics` the allocator's thrusts are *commands*:

* rotor i turns at w_i [rad/s] and pushes f_i = b_i w_i^2 [N] along its axis (its drag torque
  kappa_i f_i, as in Thesis (3.31)-(3.36) with b, c: kappa = c / b);
* the commanded speed is w_c,i = sqrt(f_c,i / b_i), saturated to [w_min,i, w_max,i];
* the speed follows it with a first-order lag of time constant T_i:
  dw_i/dt = (w_c,i - w_i) / T_i, the command held over the control period.

The rotor speeds are extra states of the plant, integrated with the robot's (q, v) by the same
integrator (like an :class:`~qprr.sim.environment.Environment` state), so the integrators keep
their orders (tests/test_actuators.py measures them with the stage on).  The applied base wrench
Omega f(w) then varies inside a control period.  A run starts with the rotors at the speeds of
the first command (``initial="command"``), at the hover speeds of the initial configuration
(``initial="hover"``: a vehicle already flying) or at given speeds.

Where the numbers come from: the rotor descriptions of the named platforms carry a ``[motor]``
table (``qprr/data/*.rotors.toml``: borinot's upstream Gazebo model gives b = 4.511e-6 N s^2,
w_max = 2236 rad/s, T = 5 ms); the thesis's Q-PRR (b of its parameters, T chosen) comes from
:func:`qprr.thesis.realistic.qprr_rotor_dynamics`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, ShapeError
from ..validation import as_array, as_int, as_vector


def _per_rotor(value, n: int, name: str) -> np.ndarray:
    a = as_array(value, name)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ShapeError(f"{name} must be one value or {n} values (one per rotor, as thrust_factor), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be finite, got {a.tolist()}")
    return a


@dataclass(frozen=True)
class RotorDynamics:
    """First-order motor lag with speed limits and thrust b w^2 (module docstring), one entry per rotor.

    Parameters
    ----------
    thrust_factor : b_i [N s^2] (> 0): f_i = b_i w_i^2.
    time_constant : T_i [s] (> 0) of dw/dt = (w_c - w) / T.
    w_min, w_max : speed limits [rad/s], 0 <= w_min < w_max (finite).
    initial : "command" (the rotors start at the first commanded speeds), "hover" (at the speeds whose thrusts hold the
        initial configuration still: the allocation of its generalised gravity) or the initial speeds (n,) [rad/s].
    """

    thrust_factor: tuple[float, ...]
    time_constant: tuple[float, ...]
    w_min: tuple[float, ...]
    w_max: tuple[float, ...]
    initial: str | tuple[float, ...] = "command"

    def __post_init__(self) -> None:
        b = np.atleast_1d(as_array(self.thrust_factor, "thrust_factor", finite=True))
        n = b.shape[0]
        if b.ndim != 1 or n == 0:
            raise ShapeError(f"thrust_factor must be one value per rotor, got {self.thrust_factor!r}")
        fields = {"thrust_factor": b}
        for name in ("time_constant", "w_min", "w_max"):
            fields[name] = _per_rotor(getattr(self, name), n, name)
        if np.any(fields["thrust_factor"] <= 0.0):
            raise InputError(f"thrust_factor must be > 0 N s^2, got {fields['thrust_factor'].tolist()}")
        if np.any(fields["time_constant"] <= 0.0):
            raise InputError(f"time_constant must be > 0 s, got {fields['time_constant'].tolist()}")
        if np.any(fields["w_min"] < 0.0) or np.any(fields["w_max"] <= fields["w_min"]):
            raise InputError(f"speed limits need 0 <= w_min < w_max, got w_min = {fields['w_min'].tolist()}, w_max = {fields['w_max'].tolist()}")
        for name, a in fields.items():
            object.__setattr__(self, name, tuple(float(x) for x in a))
        if isinstance(self.initial, str):
            if self.initial not in ("command", "hover"):
                raise InputError(f"initial must be 'command', 'hover' or the initial rotor speeds, got {self.initial!r}")
        else:
            w0 = _per_rotor(self.initial, n, "initial")
            if np.any(w0 < np.array(self.w_min)) or np.any(w0 > np.array(self.w_max)):
                raise InputError(f"initial rotor speeds {w0.tolist()} outside [w_min, w_max]")
            object.__setattr__(self, "initial", tuple(float(x) for x in w0))

    @property
    def n_rotors(self) -> int:
        return len(self.thrust_factor)

    @classmethod
    def for_rotors(cls, rotors: Sequence, thrust_factor, time_constant, *, w_min=None, w_max=None, initial="command") -> RotorDynamics:
        """The stage for a rotor set: speed limits from the thrust bounds, w = sqrt(f / b), unless given.

        ``rotors``: :class:`qprr.rotors.Rotor` objects (e.g. ``platform.rotors``); their f_max must be
        finite when ``w_max`` is not given.
        """
        n = len(rotors)
        b = _per_rotor(thrust_factor, n, "thrust_factor")
        if np.any(b <= 0.0):
            raise InputError(f"thrust_factor must be > 0 N s^2, got {b.tolist()}")
        if w_max is None:
            f_max = np.array([r.f_max for r in rotors])
            if not np.all(np.isfinite(f_max)):
                raise InputError("rotors without a finite f_max: give w_max")
            w_max = np.sqrt(f_max / b)
        if w_min is None:
            w_min = np.sqrt(np.array([r.f_min for r in rotors]) / b)
        return cls(tuple(b), time_constant, w_min, w_max, initial)

    def thrust(self, w) -> np.ndarray:
        """f = b w^2 [N] of rotor speeds ``w`` [rad/s]."""
        w = as_vector(w, self.n_rotors, "w")
        return np.asarray(self.thrust_factor) * w * w

    def speed_command(self, f_command) -> np.ndarray:
        """w_c = sqrt(f_c / b) saturated to [w_min, w_max] [rad/s] (negative commands give w_min)."""
        f = np.maximum(as_vector(f_command, self.n_rotors, "f_command"), 0.0)
        return np.clip(np.sqrt(f / np.asarray(self.thrust_factor)), self.w_min, self.w_max)

    def step_response(self, t, w0, w_command) -> np.ndarray:
        """Exact speed of the lag from ``w0`` under a constant command: w_c + (w0 - w_c) exp(-t / T) (rows: times)."""
        t = as_array(t, "t", finite=True, ndim=1)[:, None]
        w_c = np.clip(as_vector(w_command, self.n_rotors, "w_command"), self.w_min, self.w_max)
        return w_c + (as_vector(w0, self.n_rotors, "w0") - w_c) * np.exp(-t / np.asarray(self.time_constant))

    def bind(self, n_rotors: int) -> _BoundRotors:
        """The runtime object the simulator integrates (checks the number of rotors)."""
        if as_int(n_rotors, "n_rotors") != self.n_rotors:
            raise ShapeError(f"RotorDynamics has {self.n_rotors} rotors, the platform {n_rotors} (n_rotors)")
        return _BoundRotors(self)


class _BoundRotors:
    """Per-run state of :class:`RotorDynamics`: the held speed command and the rates (plain arrays)."""

    def __init__(self, spec: RotorDynamics) -> None:
        self.spec = spec
        self.b = np.array(spec.thrust_factor)
        self.inv_T = 1.0 / np.array(spec.time_constant)
        self.w_min, self.w_max = np.array(spec.w_min), np.array(spec.w_max)
        self.w_cmd = np.zeros(spec.n_rotors)
        self.n = spec.n_rotors

    def command(self, f_command: np.ndarray) -> np.ndarray:
        """Hold the speed command of the allocated thrusts (a control tick); returns it."""
        self.w_cmd[:] = self.speeds_of(f_command)
        return self.w_cmd

    def thrust(self, w: np.ndarray) -> np.ndarray:
        return self.b * w * w

    def speeds_of(self, f: np.ndarray) -> np.ndarray:
        """Speeds [rad/s] that produce the thrusts ``f`` (saturated to the speed limits)."""
        return np.clip(np.sqrt(np.maximum(np.asarray(f, dtype=float), 0.0) / self.b), self.w_min, self.w_max)

    def rate(self, w: np.ndarray) -> np.ndarray:
        """dw/dt = (w_c - w) / T."""
        return (self.w_cmd - w) * self.inv_T

    def initial(self) -> np.ndarray | str:
        """Initial speeds (n,), or the rule "command" / "hover" the simulator applies at the first tick."""
        return self.spec.initial if isinstance(self.spec.initial, str) else np.array(self.spec.initial)


MOTOR_KEYS = ("thrust_factor", "time_constant", "w_min", "w_max")
"""Keys of the ``[motor]`` table of a rotor description (one value, or one per rotor)."""


def rotor_dynamics_from_mapping(desc, rotors, **overrides) -> RotorDynamics:
    """:class:`RotorDynamics` from the ``motor`` table of a rotor description (``qprr/data/*.rotors.toml``).

    ``overrides`` replace entries of the table (same keys, plus ``initial``); missing speed limits
    come from the rotors' thrust bounds (:meth:`RotorDynamics.for_rotors`).
    """
    from ..errors import UnknownNameError

    table = dict(desc.get("motor", {})) if isinstance(desc, Mapping) else {}
    for key in list(table) + [k for k in overrides if k != "initial"]:
        if key not in MOTOR_KEYS:
            raise UnknownNameError("motor key", key, MOTOR_KEYS)
    table.update(overrides)
    missing = [k for k in ("thrust_factor", "time_constant") if k not in table]
    if missing:
        raise InputError(f"no motor data {missing} for this rotor set: give them (thrust_factor [N s^2], time_constant [s])")
    return RotorDynamics.for_rotors(
        rotors,
        table["thrust_factor"],
        table["time_constant"],
        w_min=table.get("w_min"),
        w_max=table.get("w_max"),
        initial=table.get("initial", "command"),
    )


def time_constant_of(t: np.ndarray, w: np.ndarray, w0: float, w_final: float) -> float:
    """The time constant [s] a logged step response reaches 1 - 1/e of its step at (linear interpolation)."""
    frac = (np.asarray(w, dtype=float) - w0) / (w_final - w0)
    k = int(np.argmax(frac >= 1.0 - math.exp(-1.0)))
    if k == 0 or frac[k] < 1.0 - math.exp(-1.0):
        raise InputError("the response never reaches 63.2 % of its step")
    target = 1.0 - math.exp(-1.0)
    return float(t[k - 1] + (target - frac[k - 1]) / (frac[k] - frac[k - 1]) * (t[k] - t[k - 1]))


__all__ = ["MOTOR_KEYS", "RotorDynamics", "rotor_dynamics_from_mapping", "time_constant_of"]
