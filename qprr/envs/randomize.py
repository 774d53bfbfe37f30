"""Domain randomisation of the learning environments, in the campaign vocabulary (docs/campaigns.md, docs/rl.md).

A :class:`Randomization` maps names to values drawn anew at every episode of every environment:

=================  =========  ==================================================================================
name               unit       what (the campaign / scenario option it is named after)
=================  =========  ==================================================================================
``model.mass``     factor     base body's mass and rotational inertia (:meth:`qprr.sim.batch.BatchSimulator.
                              set_mass_scale`; the campaigns' ``model.mass`` also scales the arm links)
``model.payload``  kg         point mass at the end-effector frame, unknown to the controller (Carry: the mass
                              of the carried payload, attached when it is picked)
``mean_wind``      m/s        horizontal mean wind speed, heading uniform in [0, 2 pi) (``hover-wind``'s)
``gust``           m/s        peak of a "1 - cos" gust (:class:`qprr.sim.wind.Gust`'s shape), heading uniform,
                              lasting 0.2 x the episode, starting uniformly in [0.1, 0.7] x the episode
``drag``           N s/m      linear drag coefficient K_1 of the base (``hover-wind``'s ``drag``; the wind acts
                              through it: D of Thesis (5.36), :class:`qprr.sim.wind.AerodynamicDrag`)
``tau``            s          rotor time constant of a first-order lag on the thrusts (``motor-lag``'s ``tau``)
``sensor_noise``   SI         standard deviation of Gaussian noise on every coordinate of the measured state
                              (m, rad, m/s, rad/s and the joints' units): what the observation and the reference
                              mode's controller see
=================  =========  ==================================================================================

A value is a number (fixed), a pair ``(low, high)`` (uniform) or a campaign distribution
(:class:`qprr.campaign.spec.Distribution` or its table, e.g. ``{"dist": "normal", "mean": 1.0, "std": 0.05,
"low": 0.8, "high": 1.2}``).  Every value a distribution can take must be in the name's range (masses >= 0, the mass
factor > 0...), checked when the environment is built.

Draws (:meth:`Randomization.draw`), one row per episode, from the episode's generator in this order: one value per
name given as a distribution, in the order of :data:`RANDOMIZE_KEYS`; then the mean wind's heading (when
``mean_wind`` is given), the gust's heading and start (when ``gust`` is given).

The plant models (vectorised over the environments, SI units):

* wind w(t) = w_mean + w_gust(t) in world axes, sampled at the middle of each control period and held over it;
* drag on the base in body axes, F_B = -K_1 (v_B - R^T w) (the linear term of Thesis (5.36)'s D, as
  :class:`qprr.sim.wind.AerodynamicDrag` has it), evaluated at every integration stage;
* rotor lag: f' = (f_c - f) / T with the command f_c held over the period h: exactly
  f(t_k + h) = f_c + (f(t_k) - f_c) e^(-h/T), whose mean over the period, f_c + (f(t_k) - f_c) (T / h) (1 - e^(-h/T)),
  is the thrust the plant holds (the period's impulse is exact).  Around an operating speed the thrust of a rotor
  with first-order speed dynamics (:mod:`qprr.sim.actuators`) lags with the same time constant to first order.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..campaign.spec import Distribution
from ..errors import InputError, UnknownNameError
from ..sim.batch import rotate
from ..validation import as_array, as_name, as_real

RANDOMIZE_KEYS = ("model.mass", "model.payload", "mean_wind", "gust", "drag", "tau", "sensor_noise")
"""The names a :class:`Randomization` takes, in the order their values are drawn."""

_RANGES = {
    "model.mass": (0.0, False, "a mass factor > 0 (1: the nominal airframe)"),
    "model.payload": (0.0, True, "a mass >= 0 kg"),
    "mean_wind": (0.0, True, "a wind speed >= 0 m/s"),
    "gust": (0.0, True, "a gust peak >= 0 m/s"),
    "drag": (0.0, True, "a drag coefficient >= 0 N s/m"),
    "tau": (0.0, True, "a time constant >= 0 s (0: no lag)"),
    "sensor_noise": (0.0, True, "a standard deviation >= 0 (SI units)"),
}
"""name -> (lower bound, bound included, what the value is)."""

GUST_LENGTH = 0.2
"""Duration of the gust as a fraction of the episode (the ``hover-wind`` mission's 1 - cos gust)."""
GUST_START = (0.1, 0.7)
"""The gust starts uniformly in this fraction of the episode."""


@dataclass(frozen=True)
class Draw:
    """One episode's perturbations (SI units; the nominal robot in still air by default)."""

    mass_scale: float = 1.0
    payload: float = 0.0
    mean_wind_world: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gust_peak_world: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gust_start: float = 0.0
    drag: float = 0.0
    tau: float = 0.0
    sensor_noise: float = 0.0


@dataclass(frozen=True)
class Randomization:
    """Names of :data:`RANDOMIZE_KEYS` -> a number or a :class:`~qprr.campaign.spec.Distribution` (module docstring).

    Build with :meth:`from_mapping`; ``entries`` are (name, value) in the draw order.
    """

    entries: tuple[tuple[str, float | Distribution], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.entries, (tuple, list)) or not all(isinstance(e, (tuple, list)) and len(e) == 2 for e in self.entries):
            raise InputError(
                f"Randomization.entries must be (name, value) pairs, got {self.entries!r}: "
                "build it with Randomization.from_mapping({'model.mass': (0.9, 1.1), ...})"
            )
        for key, _ in self.entries:
            if not isinstance(key, str) or key not in RANDOMIZE_KEYS:
                raise UnknownNameError("randomisation name (randomize)", key, RANDOMIZE_KEYS)
        keys = [key for key, _ in self.entries]
        if keys != [key for key in RANDOMIZE_KEYS if key in keys]:
            raise InputError(f"Randomization.entries must name each of {RANDOMIZE_KEYS} at most once, in that order (the draw order), got {keys}")
        object.__setattr__(self, "entries", tuple((key, _value(key, value)) for key, value in self.entries))
        if (self.has("mean_wind") or self.has("gust")) and not _may_be_positive(self.value("drag")):
            raise InputError(
                "randomize: the wind acts on the robot through the base's drag, and 'drag' is 0: "
                "give randomize['drag'] > 0 N s/m as well (the hover-wind mission uses 0.3)"
            )

    @classmethod
    def from_mapping(cls, mapping) -> Randomization:
        """From ``{name: number | (low, high) | distribution table | Distribution}``; every name and range checked."""
        if isinstance(mapping, Randomization):
            return mapping
        if not isinstance(mapping, Mapping):
            raise InputError(
                f"randomize must be a mapping of names to values, e.g. {{'model.mass': (0.9, 1.1), 'tau': 0.02}}, got {type(mapping).__name__}"
            )
        for key in mapping:
            if key not in RANDOMIZE_KEYS:
                raise UnknownNameError("randomisation name (randomize)", key, RANDOMIZE_KEYS)
        return cls(tuple((key, mapping[key]) for key in RANDOMIZE_KEYS if key in mapping))

    def has(self, key: str) -> bool:
        """True when ``key`` (a name of :data:`RANDOMIZE_KEYS`) is randomised (given)."""
        as_name(key, "key", RANDOMIZE_KEYS, "randomisation name")
        return any(k == key for k, _ in self.entries)

    def value(self, key: str) -> float | Distribution | None:
        """The number or distribution given for ``key`` (a name of :data:`RANDOMIZE_KEYS`; None: not given)."""
        as_name(key, "key", RANDOMIZE_KEYS, "randomisation name")
        return next((v for k, v in self.entries if k == key), None)

    def draw(self, rng: np.random.Generator, duration: float) -> Draw:
        """One episode's :class:`Draw` from ``rng`` (the draw order of the module docstring); ``duration`` [s]."""
        check_rng(rng)
        duration = as_real(duration, "duration", positive=True, unit="s")
        values = {k: (v.sample(rng) if isinstance(v, Distribution) else v) for k, v in self.entries}
        mean = _horizontal(values.get("mean_wind", 0.0), rng) if self.has("mean_wind") else (0.0, 0.0, 0.0)
        peak, start = (0.0, 0.0, 0.0), 0.0
        if self.has("gust"):
            peak = _horizontal(values["gust"], rng)
            start = float(rng.uniform(*GUST_START)) * duration
        return Draw(
            mass_scale=float(values.get("model.mass", 1.0)),
            payload=float(values.get("model.payload", 0.0)),
            mean_wind_world=mean,
            gust_peak_world=peak,
            gust_start=start,
            drag=float(values.get("drag", 0.0)),
            tau=float(values.get("tau", 0.0)),
            sensor_noise=float(values.get("sensor_noise", 0.0)),
        )


def check_rng(rng, name: str = "rng") -> np.random.Generator:
    """``rng`` if it is a numpy Generator (every draw of the environments comes from one), else an InputError naming ``name``."""
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"{name} must be a numpy.random.Generator (numpy.random.default_rng(seed)), got {type(rng).__name__} {rng!r}")
    return rng


def _value(key: str, x) -> float | Distribution:
    """A value of ``randomize[key]`` as a number or a Distribution, its range checked against :data:`_RANGES`."""
    if isinstance(x, Distribution):
        dist = x
    elif isinstance(x, Mapping):
        dist = Distribution.from_mapping(x, f"randomize[{key!r}]")
    elif isinstance(x, (tuple, list)) and len(x) == 2:
        low, high = _number(x[0], key), _number(x[1], key)
        if not low <= high:
            raise InputError(f"randomize[{key!r}] = {tuple(x)!r}: a range (low, high) needs low <= high: did you mean {(high, low)!r}?")
        dist = Distribution("uniform", low=low, high=high)
    elif isinstance(x, (tuple, list)):
        raise InputError(f"randomize[{key!r}] must be a number, a pair (low, high) or a distribution table, got {x!r}")
    else:
        dist = None
        lo = hi = _number(x, key)
    if dist is not None:
        lo, hi = _support(dist, key)
    floor, included, what = _RANGES[key]
    if not (lo >= floor if included else lo > floor):
        given = f"a distribution reaching down to {lo!r}" if dist is not None else repr(lo)
        fix = f"give the normal distribution low = {floor!r} or above" if dist is not None and dist.kind == "normal" else "give values in that range"
        raise InputError(f"randomize[{key!r}] must stay {what}, got {given}: {fix}")
    return dist if dist is not None else float(lo)


def _number(x, key: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)) or not math.isfinite(x):
        raise InputError(f"randomize[{key!r}] must be a finite number, a pair (low, high) or a distribution table, got {x!r}")
    return float(x)


def _support(dist: Distribution, key: str) -> tuple[float, float]:
    """(smallest, largest) value ``dist`` can draw."""
    if dist.kind == "choice":
        values = [_number(v, key) for v in dist.values]
        return min(values), max(values)
    if dist.kind == "normal":
        return (-math.inf if dist.low is None else dist.low), (math.inf if dist.high is None else dist.high)
    return float(dist.low), float(dist.high)


def _may_be_positive(value) -> bool:
    if value is None:
        return False
    if isinstance(value, Distribution):
        return _support(value, "drag")[1] > 0.0
    return value > 0.0


def _horizontal(speed: float, rng: np.random.Generator) -> tuple[float, float, float]:
    """A horizontal vector of length ``speed`` with a heading uniform in [0, 2 pi) (world x, y, z)."""
    heading = float(rng.uniform(0.0, 2.0 * math.pi))
    return (speed * math.cos(heading), speed * math.sin(heading), 0.0)


# ----------------------------------------------------------------------------------- the plant models, vectorised
def wind_world(mean: np.ndarray, peak: np.ndarray, start: np.ndarray, length: float, t: np.ndarray) -> np.ndarray:
    """w(t) (n, 3) [m/s], world axes: the mean wind plus the "1 - cos" gust peak / 2 (1 - cos(2 pi (t - t0) / d)) on
    [t0, t0 + d] (MIL-F-8785C's shape, :class:`qprr.sim.wind.Gust`); ``t`` (n,) [s], ``length`` d [s]."""
    s = (t - start) / length
    on = (s >= 0.0) & (s <= 1.0)
    shape = np.where(on, 0.5 * (1.0 - np.cos(2.0 * math.pi * s)), 0.0)
    return mean + shape[:, None] * peak


def drag_force(q: np.ndarray, v: np.ndarray, wind: np.ndarray, drag: np.ndarray) -> np.ndarray:
    """The generalised force (n, nv) of the base drag F_B = -K_1 (v_B - R^T w) (body axes, at B; module docstring).

    A copy whose state is not finite (it terminates at the end of the step) gets no force."""
    quat_inverse = q[:, 3:7] * np.array([-1.0, -1.0, -1.0, 1.0])
    wind_body = rotate(quat_inverse, wind)
    force = np.zeros_like(v)
    force[:, 0:3] = -drag[:, None] * (v[:, 0:3] - wind_body)
    return np.where(np.isfinite(force), force, 0.0)


def lag_factors(tau: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """(e^(-h/T), (T / h)(1 - e^(-h/T))) per copy for time constants ``tau`` (n,) [s] and the period h [s]: the
    end-of-period and mean-over-the-period weights of the exact first-order lag (module docstring); (0, 0) at T = 0."""
    tau = as_array(tau, "tau", finite=True, ndim=1)
    if (tau < 0.0).any():
        raise InputError(f"tau must be rotor time constants >= 0 s (0: no lag), got {tau.tolist()}")
    period = as_real(period, "period", positive=True, unit="s")
    lagged = tau > 0.0
    safe = np.where(lagged, tau, 1.0)
    end = np.where(lagged, np.exp(-period / safe), 0.0)
    mean = np.where(lagged, (safe / period) * (1.0 - end), 0.0)
    return end, mean


__all__ = ["GUST_LENGTH", "GUST_START", "RANDOMIZE_KEYS", "Draw", "Randomization", "check_rng", "drag_force", "lag_factors", "wind_world"]
