"""Reference trajectories in thesis coordinates xi = [x, y, z, phi, theta, psi, r0, theta2, theta3].

* :func:`transition` is the law of Thesis (6.16) with its first four time derivatives.
* :class:`MultiPhase` chains such transitions per coordinate (the missions of Thesis
  Sec. 6.3.1.4 and 6.3.3.3); :func:`static_mission`, :func:`dynamic_mission` build them.
* :class:`Spiral` is the spiral of Thesis (6.25) after a vertical climb.

A trajectory is any object with ``sample(t) -> TrajectorySample`` for an array of times;
the simulator samples the whole horizon once before the loop (references depend on time
only).  Roll and pitch references are not given by the trajectory: the controllers derive
them from the thrust vector (Thesis (6.17)), so their entries stay 0 here.

About (6.16): the thesis calls it "an order-5 polynomial interpolation" with T_s "the
sampling period".  The printed law is L tau^5 / (tau^5 + (1 - tau)^5) with tau = (t - t1)/T_s:
a rational function, not a polynomial, and it only reaches L at t2 when T_s = t2 - t1 is the
transition *duration*.  Its first four derivatives vanish at both ends, but its peak speed
is 5 L / T and its peak acceleration 38.1 L / T^2 (2.7 and 6.6 times the minimum-jerk
quintic's 1.875 L / T and 5.77 L / T^2).  For the 10 m climb in 5 s of the missions that
is a deceleration of 15.2 m/s^2 = 1.55 g: the rotors would have to pull downwards.  The
quintic polynomial the text names (``law="quintic"``, peak 2.3 m/s^2) is feasible in
acceleration but not for a multirotor: its jerk jumps from 0 to 60 L / T^3 at both ends of a
phase.  A multirotor moves sideways by tilting its thrust (6.17), so the tilt follows the
horizontal acceleration and the tilt *rate* its jerk (theta ~ a_x / g, theta_dot ~ j_x / g):
the quintic asks the tilt rate to step (0.15 rad/s at the start of the x phase of the
mission, 0.29 rad/s at the end of the y phase), i.e. an infinite angular acceleration
(docs/notes-spikes.md).  The missions therefore use the minimum-snap septic
(``law="septic"``, the default: rate, acceleration and jerk zero at both ends, like the
printed law, peak acceleration 7.51 L / T^2 = 3.0 m/s^2 for the climb); the quintic and the
printed formula stay available as ``law="quintic"`` and ``law="thesis"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .coordinates import as_vector
from .errors import InputError, ShapeError

XI_NAMES = ("x", "y", "z", "phi", "theta", "psi", "r0", "theta2", "theta3")
"""Names of the nine thesis coordinates, in order."""

_INDEX = {name: i for i, name in enumerate(XI_NAMES)}


@dataclass(frozen=True)
class TrajectorySample:
    """Reference positions, rates and accelerations, each of shape (n, 9) (thesis coordinates)."""

    t: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    xi_ddot: np.ndarray


def _sigmoid(tau: np.ndarray, order: int) -> list[np.ndarray]:
    """s(tau) = tau^5 / (tau^5 + (1 - tau)^5) and its derivatives up to ``order`` on [0, 1].

    Quotient rule in Leibniz form: with s D = a, D = a + b,
    s^(n) = (a^(n) - sum_{k=1..n} C(n, k) D^(k) s^(n-k)) / D.
    """
    tau = np.clip(tau, 0.0, 1.0)
    w = 1.0 - tau
    # a = tau^5 and b = (1 - tau)^5 with their derivatives with respect to tau
    a = [tau**5, 5 * tau**4, 20 * tau**3, 60 * tau**2, 120 * tau]
    b = [w**5, -5 * w**4, 20 * w**3, -60 * w**2, 120 * w]
    D = [ai + bi for ai, bi in zip(a, b)]
    binom = ((1,), (1, 1), (1, 2, 1), (1, 3, 3, 1), (1, 4, 6, 4, 1))
    s = [a[0] / D[0]]
    for n in range(1, order + 1):
        acc = a[n].copy()
        for k in range(1, n + 1):
            acc -= binom[n][k] * D[k] * s[n - k]
        s.append(acc / D[0])
    return s


def _quintic(tau: np.ndarray, order: int) -> list[np.ndarray]:
    """Minimum-jerk quintic s = 10 tau^3 - 15 tau^4 + 6 tau^5 and its derivatives on [0, 1]."""
    x = np.clip(tau, 0.0, 1.0)
    s = [x**3 * (10 - 15 * x + 6 * x * x), 30 * x**2 * (1 - x) ** 2, 60 * x * (1 - x) * (1 - 2 * x),
         60 - 360 * x + 360 * x * x, -360 + 720 * x]
    return s[: order + 1]


def _septic(tau: np.ndarray, order: int) -> list[np.ndarray]:
    """Minimum-snap septic s = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 and its derivatives on [0, 1].

    s' = 140 tau^3 (1 - tau)^3, s'' = 420 tau^2 (1 - tau)^2 (1 - 2 tau),
    s''' = 840 tau (1 - tau) (1 - 5 tau + 5 tau^2): rate, acceleration and jerk vanish at both ends.
    """
    x = np.clip(tau, 0.0, 1.0)
    w = 1.0 - x
    s = [x**4 * (35 - 84 * x + 70 * x * x - 20 * x**3), 140 * (x * w) ** 3, 420 * (x * w) ** 2 * (1 - 2 * x),
         840 * x * w * (1 - 5 * x + 5 * x * x), 840 - 10080 * x + 25200 * x * x - 16800 * x**3]
    return s[: order + 1]


LAWS = ("septic", "quintic", "thesis")
"""Transition laws: "septic" (the missions' default: the minimum-snap polynomial, rate,
acceleration and jerk zero at both ends), "quintic" (the order-5 polynomial the text of
Sec. 6.3.1.2 names) and "thesis" (the rational formula printed as (6.16))."""

DEFAULT_LAW = "septic"
"""Transition law of the missions and of :class:`MultiPhase` (module docstring: why not the quintic)."""

_LAW_FUNCTIONS = {"septic": _septic, "quintic": _quintic, "thesis": _sigmoid}


def transition(t, t1: float, t2: float, start: float = 0.0, end: float = 1.0, order: int = 3,
               law: str = DEFAULT_LAW) -> list[np.ndarray]:
    """Smooth transition of Thesis (6.16) from ``start`` (t <= t1) to ``end`` (t >= t2).

    sigma(t) = start + (end - start) s((t - t1) / T), T = t2 - t1 (the thesis's T_s, printed
    as a sampling period), with ``law``:

    * "thesis": s(tau) = tau^5 / (tau^5 + (1 - tau)^5), the printed formula (peak
      acceleration 38.1 L / T^2);
    * "quintic": s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5, the "order-5 polynomial
      interpolation" the text names (peak acceleration 5.77 L / T^2, jerk 60 L / T^3 at
      both ends);
    * "septic" (default): s(tau) = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7, the
      minimum-snap polynomial: jerk zero at both ends (peak acceleration 7.51 L / T^2).

    Returns [sigma, sigma_dot, sigma_ddot, sigma_dddot, ...][: order + 1] shaped like ``t``.
    """
    if not (np.isfinite(t1) and np.isfinite(t2) and t2 > t1):
        raise InputError(f"transition needs finite t1 < t2, got t1 = {t1!r}, t2 = {t2!r}")
    if order not in (0, 1, 2, 3, 4):
        raise InputError(f"order must be 0..4, got {order!r}")
    if law not in LAWS:
        from .errors import UnknownNameError

        raise UnknownNameError("transition law", law, LAWS)
    t = np.asarray(t, dtype=float)
    T = t2 - t1
    tau = (t - t1) / T
    inside = (tau > 0.0) & (tau < 1.0)
    s = _LAW_FUNCTIONS[law](tau, order)
    out = [start + (end - start) * s[0]]
    for n in range(1, order + 1):
        out.append(np.where(inside, (end - start) * s[n] / T**n, 0.0))
    return out


@dataclass(frozen=True)
class Phase:
    """One transition of one coordinate: ``coordinate`` goes to ``value`` between t1 and t2 [s]."""

    coordinate: str
    t1: float
    t2: float
    value: float

    def __post_init__(self) -> None:
        if self.coordinate not in _INDEX:
            from .errors import UnknownNameError

            raise UnknownNameError("coordinate", self.coordinate, XI_NAMES)
        if not (np.isfinite(self.t1) and np.isfinite(self.t2) and self.t2 > self.t1 >= 0.0):
            raise InputError(f"phase {self.coordinate!r}: need 0 <= t1 < t2, got t1 = {self.t1!r}, t2 = {self.t2!r}")
        if not np.isfinite(self.value):
            raise InputError(f"phase {self.coordinate!r}: value must be finite, got {self.value!r}")


@dataclass(frozen=True)
class MultiPhase:
    """Sequence of (6.16) transitions per coordinate from ``xi0`` (phases of one coordinate must not overlap)."""

    phases: tuple[Phase, ...]
    xi0: tuple[float, ...] = (0.0,) * 9
    name: str = "multi-phase"
    law: str = DEFAULT_LAW

    def __post_init__(self) -> None:
        as_vector(self.xi0, 9, "xi0")
        if self.law not in LAWS:
            from .errors import UnknownNameError

            raise UnknownNameError("transition law", self.law, LAWS)
        for c in XI_NAMES:
            ph = sorted((p for p in self.phases if p.coordinate == c), key=lambda p: p.t1)
            for p, nxt in zip(ph, ph[1:]):
                if nxt.t1 < p.t2:
                    raise InputError(f"phases of {c!r} overlap: [{p.t1}, {p.t2}] and [{nxt.t1}, {nxt.t2}]")

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = t.shape[0]
        xi = np.tile(np.asarray(self.xi0, dtype=float), (n, 1))
        xd = np.zeros((n, 9))
        xdd = np.zeros((n, 9))
        current = list(self.xi0)
        for p in sorted(self.phases, key=lambda p: (p.coordinate, p.t1)):
            i = _INDEX[p.coordinate]
            s, sd, sdd = transition(t, p.t1, p.t2, 0.0, p.value - current[i], order=2, law=self.law)
            xi[:, i] += s
            xd[:, i] += sd
            xdd[:, i] += sdd
            current[i] = p.value
        return TrajectorySample(t, xi, xd, xdd)

    def final(self) -> np.ndarray:
        """xi at the end of the last phase."""
        return self.sample([max(p.t2 for p in self.phases)]).xi[0]


STATIC_TARGET = (3.0, 6.0, 10.0, 0.0, 0.04, 0.2, 0.6)
"""xi_d = [x_b, y_b, z_b, psi, r0, theta2, theta3] of Thesis Sec. 6.3.1.4."""


def static_mission(target=STATIC_TARGET, *, z_phase=(0.0, 5.0), x_phase=(5.0, 10.0), y_phase=(10.0, 15.0),
                   arm_phase=(15.0, 25.0), law: str = DEFAULT_LAW) -> MultiPhase:
    """The mission of Thesis Sec. 6.3.1.4 / 6.3.3.3: climb in z 0-5 s, x 5-10 s, y 10-15 s, arm 15-25 s.

    ``target`` = [x, y, z, psi, r0, theta2, theta3] (default [3, 6, 10, 0, 0.04, 0.2, 0.6]).
    The arm starts straight (r0 = theta2 = theta3 = 0); yaw is held at ``psi``.
    """
    x, y, z, psi, r0, t2, t3 = as_vector(target, 7, "target")
    phases = [Phase("z", *z_phase, z), Phase("x", *x_phase, x), Phase("y", *y_phase, y)]
    phases += [Phase(c, *arm_phase, val) for c, val in (("r0", r0), ("theta2", t2), ("theta3", t3)) if val != 0.0]
    xi0 = (0.0, 0.0, 0.0, 0.0, 0.0, psi, 0.0, 0.0, 0.0)
    return MultiPhase(tuple(phases), xi0, name="static-mission", law=law)


def dynamic_mission(p_target=(3.0, 6.0, 10.0), theta2_d: float = -0.5, *, arm_phase=(15.0, 25.0),
                    law: str = DEFAULT_LAW) -> MultiPhase:
    """Mission of Thesis Sec. 6.3.3.3: same flight phases, theta2 -> ``theta2_d`` in 15-25 s.

    r0 and theta3 references are left at 0: the CoG stabiliser (BSG) computes them.
    """
    x, y, z = as_vector(p_target, 3, "p_target")
    phases = (Phase("z", 0.0, 5.0, z), Phase("x", 5.0, 10.0, x), Phase("y", 10.0, 15.0, y),
              Phase("theta2", *arm_phase, float(theta2_d)))
    return MultiPhase(phases, name="dynamic-mission", law=law)


@dataclass(frozen=True)
class Spiral:
    """Thesis (6.25) after a climb: x_d = (t - t_f)/5 sin(2 pi t / 20), y_d = (t - t_f)/5 cos(2 pi t / 20).

    ``t_f`` is the start of the spiral (the thesis: "the instant the spiral starts"); before
    it the vehicle climbs to ``z`` with (6.16) over [0, ``climb_time``].  Radius grows at
    ``rate`` = 1/5 m/s and one turn takes ``period`` = 20 s.

    The printed law starts with a speed of rate (|sin|, |cos|)(w t_f) (0.2 m/s in x for
    t_f = 5 s, w = 2 pi / period) and an acceleration of magnitude 2 rate w (0.126 m/s^2,
    in y), not 0: the reference velocity and acceleration step at t_f, and with them the
    thrust direction (6.17) (a tilt step, i.e. an infinite angular acceleration).  The spiral is
    therefore faded in: x_d, y_d are (6.25) times the septic transition sigma(t) from 0 at
    t_f to 1 at t_f + ``blend`` [s] (default 2 s); since r = 0 at t_f and sigma is flat to
    third order there, the reference starts at rest with zero acceleration and jerk, and it
    is exactly (6.25) from t_f + ``blend`` on.  ``blend=0`` gives the printed law.
    """

    z: float = 10.0
    climb_time: float = 5.0
    t_f: float = 5.0
    rate: float = 0.2
    period: float = 20.0
    arm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    blend: float = 2.0
    name: str = field(default="spiral", compare=False)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.blend) and self.blend >= 0.0):
            raise InputError(f"spiral blend must be a duration >= 0 s, got {self.blend!r}")

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = t.shape[0]
        xi = np.zeros((n, 9))
        xd = np.zeros((n, 9))
        xdd = np.zeros((n, 9))
        z, zd, zdd = transition(t, 0.0, self.climb_time, 0.0, self.z, order=2)
        xi[:, 2], xd[:, 2], xdd[:, 2] = z, zd, zdd
        xi[:, 6:9] = self.arm
        on = t >= self.t_f
        w = 2.0 * np.pi / self.period
        r = self.rate * (t - self.t_f)
        s, c = np.sin(w * t), np.cos(w * t)
        # (6.25) and its derivatives: p = r (sin, cos)(w t)
        p = (r * s, r * c)
        pd = (self.rate * s + r * w * c, self.rate * c - r * w * s)
        pdd = (2 * self.rate * w * c - r * w * w * s, -2 * self.rate * w * s - r * w * w * c)
        if self.blend > 0.0:  # sigma p and its derivatives (Leibniz)
            sg, sgd, sgdd = transition(t, self.t_f, self.t_f + self.blend, 0.0, 1.0, order=2, law="septic")
            pdd = tuple(sgdd * a + 2.0 * sgd * b + sg * c2 for a, b, c2 in zip(p, pd, pdd))
            pd = tuple(sgd * a + sg * b for a, b in zip(p, pd))
            p = tuple(sg * a for a in p)
        for i in (0, 1):
            xi[:, i] = np.where(on, p[i], 0.0)
            xd[:, i] = np.where(on, pd[i], 0.0)
            xdd[:, i] = np.where(on, pdd[i], 0.0)
        return TrajectorySample(t, xi, xd, xdd)


@dataclass(frozen=True)
class Hold:
    """Constant reference ``xi`` (hover tests)."""

    xi: tuple[float, ...] = (0.0,) * 9
    name: str = field(default="hold", compare=False)

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        x = as_vector(self.xi, 9, "xi")
        n = t.shape[0]
        return TrajectorySample(t, np.tile(x, (n, 1)), np.zeros((n, 9)), np.zeros((n, 9)))


def check_sample(sample: TrajectorySample, n: int) -> None:
    """Raise ShapeError/NonFiniteError if a trajectory returned wrong arrays for n times."""
    for name in ("xi", "xi_dot", "xi_ddot"):
        a = getattr(sample, name)
        if a.shape != (n, 9):
            raise ShapeError(f"trajectory sample {name} must have shape ({n}, 9), got {a.shape}")
        if not np.all(np.isfinite(a)):
            from .errors import NonFiniteError

            raise NonFiniteError(f"trajectory sample {name} has non-finite entries")
