"""Disturbances on the generalised forces: known in advance (sampled at the control ticks) or state-dependent.

* :class:`Disturbance` (base class): u_ext(t) in thesis coordinates, e.g. the white noise (6.27)
  (:class:`WhiteNoise`) and finite pulses (6.28) (:class:`Pulse`) of Thesis Sec. 6.3.2; the
  simulator samples it at the control ticks and holds it over each period;
* :class:`StateDisturbance` (base class): tau(t, q, v) in Pinocchio's coordinates, evaluated at
  every integration stage (:class:`BaseDrag`, the wind's drag of :mod:`qprr.sim.wind`); a subclass may
  draw its randomness once per run (:meth:`StateDisturbance.realize`) and report time series
  (:meth:`StateDisturbance.report`);
* :class:`Disturbances`: a sum of both kinds.

A disturbance of your own subclasses one of the two base classes: the simulator tells the kinds apart by
their class.

Components are indices of the thesis coordinates xi = [x, y, z, phi, theta, psi, q_arm]: an
amplitude or a pulse vector must match the platform's 6 + n_arm entries (checked when the
simulator samples it).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, ShapeError
from ..validation import as_array, as_int, as_real


def check_values_args(t, rng, n_xi) -> tuple[np.ndarray, int]:
    """(t, n_xi) of a :meth:`Disturbance.values` call checked: t a 1-D finite array of times [s], rng a numpy Generator
    (or None where unused), n_xi >= 6."""
    t = as_array(t, "t", finite=True, ndim=1)
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise InputError(f"rng must be a numpy.random.Generator (np.random.default_rng(seed)), got {type(rng).__name__}")
    return t, as_int(n_xi, "n_xi", lo=6)


class Disturbance(ABC):
    """Additive generalised force u_ext(t) of Thesis (6.27), thesis coordinates, known in advance.

    Sampled at the control ticks and held over each control period (a noise sample, a pulse
    edge sit on the control grid).  A subclass defines :meth:`values`."""

    @abstractmethod
    def values(self, t: np.ndarray, rng: np.random.Generator, n_xi: int) -> np.ndarray:
        """u_ext at the control ticks ``t`` (m,), shape (m, n_xi)."""


class StateDisturbance(ABC):
    """A disturbance that depends on the state, evaluated at every integration stage.

    A subclass defines :meth:`generalized_force`, which returns tau (nv,) in Pinocchio's coordinates (the free
    flyer's entries are a body wrench [force; moment] in B at its origin); it may override :meth:`realize` (draw its
    randomness once per run) and :meth:`report` (time series for the result)."""

    @abstractmethod
    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """tau (nv,) at time ``t`` [s] and state (q, v)."""

    def realize(self, t_ticks: np.ndarray, rng: np.random.Generator, period: float) -> StateDisturbance:
        """The disturbance of one run, its random parts drawn from the run's ``rng`` at the control ticks ``t_ticks``
        (spaced by ``period`` [s]); the simulator calls it once per run, after sampling the timed disturbances.
        Default: itself (nothing to draw)."""
        return self

    def report(self) -> dict[str, np.ndarray]:
        """Named time series of the run (one row per control tick) for :attr:`qprr.sim.SimResult.series`.
        Default: none."""
        return {}


@dataclass(frozen=True)
class BaseDrag(StateDisturbance):
    """Linear aerodynamic drag on the multirotor: force -c_lin v_B, moment -c_ang omega_B (body axes, at B).

    ``linear`` [N s/m], ``angular`` [N m s/rad]; isotropic, so the world force is -c_lin p_dot.
    A :class:`StateDisturbance`."""

    linear: float = 0.0
    angular: float = 0.0

    def __post_init__(self) -> None:
        for name in ("linear", "angular"):
            c = getattr(self, name)
            if not (isinstance(c, (int, float)) and np.isfinite(c) and c >= 0.0):
                raise InputError(f"drag coefficient {name} must be finite and >= 0, got {c!r}")

    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        tau = np.zeros(v.shape[0])
        tau[0:3] = -self.linear * v[0:3]
        tau[3:6] = -self.angular * v[3:6]
        return tau


def _components(components, n_xi: int) -> list[int]:
    comps = list(range(n_xi)) if components is None else list(components)
    if any(not isinstance(c, (int, np.integer)) or not 0 <= c < n_xi for c in comps):
        raise InputError(f"disturbance components must be indices 0..{n_xi - 1} of xi, got {components!r}")
    return comps


@dataclass(frozen=True)
class WhiteNoise(Disturbance):
    """Uniform white noise in [-amplitude, amplitude] on the selected generalised forces (Sec. 6.3.2.1, (6.27)).

    ``components``: indices of xi (None: all 6 + n_arm); ``amplitude``: one value or one per
    component (N for x, y, z and prismatic joints; N m for the angles and revolute joints); a new
    value per ``sample_time`` [s] (default: every control tick), held in between.
    """

    amplitude: float | tuple[float, ...] = 0.3
    components: tuple[int, ...] | None = None
    sample_time: float | None = None

    def __post_init__(self) -> None:
        amp = as_array(self.amplitude, "noise amplitude")
        if amp.ndim > 1 or not np.all(np.isfinite(amp)) or np.any(amp < 0):
            raise InputError(f"noise amplitude must be finite and >= 0, got {self.amplitude!r}")
        if self.components is not None and amp.ndim == 1 and amp.shape[0] != len(self.components):
            raise ShapeError(f"noise amplitude has {amp.shape[0]} entries for {len(self.components)} components")
        if self.sample_time is not None and not (np.isfinite(self.sample_time) and self.sample_time > 0):
            raise InputError(f"sample_time must be > 0 s, got {self.sample_time!r}")

    def values(self, t: np.ndarray, rng: np.random.Generator, n_xi: int) -> np.ndarray:
        t, n_xi = check_values_args(t, rng, n_xi)
        if rng is None:
            raise InputError("rng must be a numpy.random.Generator for noise, got None")
        comps = _components(self.components, n_xi)
        amp = np.asarray(self.amplitude, dtype=float)
        if amp.ndim == 1 and amp.shape[0] != len(comps):
            raise ShapeError(f"noise amplitude has {amp.shape[0]} entries for the {len(comps)} components {comps}")
        amp = np.broadcast_to(amp, (len(comps),))
        n = t.shape[0]
        out = np.zeros((n, n_xi))
        if self.sample_time is None:
            idx = np.arange(n)
            m = n
        else:
            idx = np.floor((t - t[0]) / self.sample_time + 1e-9).astype(int)
            m = int(idx[-1]) + 1
        draws = rng.uniform(-1.0, 1.0, size=(m, len(comps))) * amp
        out[:, comps] = draws[idx]
        return out


@dataclass(frozen=True)
class Pulse(Disturbance):
    """Finite pulse Gamma [H(t - t1) - H(t - t2)] (Thesis (6.28)); ``gamma`` (6 + n_arm,) per generalised force."""

    t1: float
    t2: float
    gamma: tuple[float, ...]

    def __post_init__(self) -> None:
        g = as_array(self.gamma, "gamma")
        if g.ndim != 1 or g.shape[0] < 6 or not np.all(np.isfinite(g)):
            raise InputError(f"gamma must be 6 + n_arm finite values, got {self.gamma!r}")
        object.__setattr__(self, "t1", as_real(self.t1, "t1", unit="s"))
        object.__setattr__(self, "t2", as_real(self.t2, "t2", unit="s"))
        if not self.t2 > self.t1:
            raise InputError(f"pulse needs t1 < t2, got t1 = {self.t1!r}, t2 = {self.t2!r}")

    def values(self, t: np.ndarray, rng: np.random.Generator | None = None, n_xi: int | None = None) -> np.ndarray:
        t = as_array(t, "t", finite=True, ndim=1)
        if rng is not None and not isinstance(rng, np.random.Generator):
            raise InputError(f"rng must be None or a numpy.random.Generator, got {type(rng).__name__}")
        if n_xi is not None:
            n_xi = as_int(n_xi, "n_xi", lo=6)
        gamma = np.asarray(self.gamma, dtype=float)
        if n_xi is not None and gamma.shape[0] != n_xi:
            raise ShapeError(f"pulse gamma has {gamma.shape[0]} entries, the platform's xi has {n_xi}")
        on = ((t >= self.t1) & (t < self.t2)).astype(float)
        return on[:, None] * gamma[None, :]


@dataclass(frozen=True)
class Disturbances(Disturbance):
    """Sum of several disturbances (:class:`Disturbance` and :class:`StateDisturbance` may be mixed): its
    :meth:`values` are those of the timed parts; the simulator evaluates the state-dependent parts at every stage."""

    parts: tuple

    def __post_init__(self) -> None:
        if not isinstance(self.parts, (tuple, list)) or not self.parts:
            raise InputError(f"parts must be a non-empty tuple of disturbances, got {self.parts!r:.80}")
        for p in self.parts:
            if not isinstance(p, (Disturbance, StateDisturbance)):
                raise InputError(f"parts: {_NOT_A_DISTURBANCE}, got {type(p).__name__}")
        object.__setattr__(self, "parts", tuple(self.parts))

    def values(self, t: np.ndarray, rng: np.random.Generator, n_xi: int) -> np.ndarray:
        t, n_xi = check_values_args(t, rng, n_xi)
        out = np.zeros((t.shape[0], n_xi))
        for p in self.parts:
            if isinstance(p, Disturbance):
                out += p.values(t, rng, n_xi)
        return out


_NOT_A_DISTURBANCE = (
    "a disturbance is a qprr.sim.Disturbance (values(t, rng, n_xi): known in advance) or a qprr.sim.StateDisturbance "
    "(generalized_force(t, q, v): state-dependent); subclass one of them"
)


def split(disturbance) -> tuple[Disturbance | None, list[StateDisturbance]]:
    """(the timed part, a :class:`Disturbance`, or None; the state-dependent parts, :class:`StateDisturbance`)."""
    if disturbance is None:
        return None, []
    parts = disturbance.parts if isinstance(disturbance, Disturbances) else (disturbance,)
    timed, state = [], []
    for p in parts:
        if isinstance(p, StateDisturbance):
            state.append(p)
        elif isinstance(p, Disturbance):
            timed.append(p)
        else:
            raise InputError(f"{_NOT_A_DISTURBANCE}, got {type(p).__name__}")
    if not timed:
        return None, state
    return (timed[0] if len(timed) == 1 else Disturbances(tuple(timed))), state
