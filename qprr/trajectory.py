"""Reference trajectories in thesis coordinates xi = [x, y, z, phi, theta, psi, q_arm] (any platform).

* :func:`transition` is the law of Thesis (6.16) with its first four time derivatives.
* :class:`MultiPhase` chains such transitions per coordinate (:func:`line_phases`: the path
  option y = a x + b of Sec. 6.3.1.2; the missions of Thesis
  Sec. 6.3.1.4 and 6.3.3.3 are built in :mod:`qprr.thesis.missions`); :func:`hover_and_reach`
  is a mission for any platform.
* :class:`Spiral` is the spiral of Thesis (6.25) after a vertical climb; :class:`Hold` a constant.

A trajectory is any object with ``sample(t) -> TrajectorySample`` for an array of times (the
:class:`Trajectory` protocol);
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
from typing import Protocol, runtime_checkable

import numpy as np

from .charts import as_xi, xi_names
from .errors import InputError, ShapeError, UnknownNameError
from .validation import as_array, as_int, as_interval, as_real, as_vector


@dataclass(frozen=True)
class TrajectorySample:
    """Reference positions, rates and accelerations, each of shape (m, 6 + n_arm) (thesis coordinates)."""

    t: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    xi_ddot: np.ndarray


@runtime_checkable
class Trajectory(Protocol):
    """What the simulator and the controllers follow: ``sample(t)`` for an array of times ``t`` (m,) [s] returns the
    :class:`TrajectorySample` there.  :class:`MultiPhase`, :class:`Spiral` and :class:`Hold` are trajectories; so is any
    class of yours with that method (``isinstance(obj, Trajectory)`` checks it)."""

    def sample(self, t) -> TrajectorySample: ...


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
    s = [x**3 * (10 - 15 * x + 6 * x * x), 30 * x**2 * (1 - x) ** 2, 60 * x * (1 - x) * (1 - 2 * x), 60 - 360 * x + 360 * x * x, -360 + 720 * x]
    return s[: order + 1]


def _septic(tau: np.ndarray, order: int) -> list[np.ndarray]:
    """Minimum-snap septic s = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 and its derivatives on [0, 1].

    s' = 140 tau^3 (1 - tau)^3, s'' = 420 tau^2 (1 - tau)^2 (1 - 2 tau),
    s''' = 840 tau (1 - tau) (1 - 5 tau + 5 tau^2): rate, acceleration and jerk vanish at both ends.
    """
    x = np.clip(tau, 0.0, 1.0)
    w = 1.0 - x
    s = [
        x**4 * (35 - 84 * x + 70 * x * x - 20 * x**3),
        140 * (x * w) ** 3,
        420 * (x * w) ** 2 * (1 - 2 * x),
        840 * x * w * (1 - 5 * x + 5 * x * x),
        840 - 10080 * x + 25200 * x * x - 16800 * x**3,
    ]
    return s[: order + 1]


LAWS = ("septic", "quintic", "thesis")
"""Transition laws: "septic" (the missions' default: the minimum-snap polynomial, rate,
acceleration and jerk zero at both ends), "quintic" (the order-5 polynomial the text of
Sec. 6.3.1.2 names) and "thesis" (the rational formula printed as (6.16))."""

DEFAULT_LAW = "septic"
"""Transition law of the missions and of :class:`MultiPhase` (module docstring: why not the quintic)."""

_LAW_FUNCTIONS = {"septic": _septic, "quintic": _quintic, "thesis": _sigmoid}


def _times(t) -> np.ndarray:
    """Sample times ``t`` [s] (a number or any array of finite numbers)."""
    return as_array(t, "t", finite=True)


def transition(t, t1: float, t2: float, start: float = 0.0, end: float = 1.0, order: int = 3, law: str = DEFAULT_LAW) -> list[np.ndarray]:
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
    t1, t2 = as_real(t1, "t1", unit="s"), as_real(t2, "t2", unit="s")
    start, end = as_real(start, "start"), as_real(end, "end")
    if not t2 > t1:
        raise InputError(f"transition needs t1 < t2, got t1 = {t1!r}, t2 = {t2!r}")
    order = as_int(order, "order", lo=0, hi=4)
    if law not in LAWS:
        raise UnknownNameError("transition law", law, LAWS)
    t = _times(t)
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
    """One transition of one coordinate: ``coordinate`` (a name of xi, e.g. "z", "theta2", or its index)
    goes to ``value`` between t1 and t2 [s]."""

    coordinate: str | int
    t1: float
    t2: float
    value: float

    def __post_init__(self) -> None:
        if not isinstance(self.coordinate, (str, int)) or isinstance(self.coordinate, bool):
            raise InputError(f"phase coordinate must be a name or an index of xi, got {self.coordinate!r}")
        for name in ("t1", "t2", "value"):
            object.__setattr__(self, name, as_real(getattr(self, name), f"phase {self.coordinate!r}: {name}"))
        if not (np.isfinite(self.t1) and np.isfinite(self.t2) and self.t2 > self.t1 >= 0.0):
            raise InputError(f"phase {self.coordinate!r}: need 0 <= t1 < t2, got t1 = {self.t1!r}, t2 = {self.t2!r}")
        if not np.isfinite(self.value):
            raise InputError(f"phase {self.coordinate!r}: value must be finite, got {self.value!r}")


@dataclass(frozen=True)
class MultiPhase:
    """Sequence of (6.16) transitions per coordinate from ``xi0`` (phases of one coordinate must not overlap).

    ``names``: the names of xi's entries (default x, y, z, phi, theta, psi, q1..qn; pass
    ``platform.xi_names`` to use the arm joints' names).
    """

    phases: tuple[Phase, ...]
    xi0: tuple[float, ...] = (0.0,) * 9
    name: str = "multi-phase"
    law: str = DEFAULT_LAW
    names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        xi0 = as_xi(self.xi0, "xi0")
        if not isinstance(self.phases, (tuple, list)):
            raise InputError(f"phases must be a tuple of Phase, got {type(self.phases).__name__}")
        names = tuple(self.names) if self.names is not None else xi_names(xi0.shape[0] - 6)
        if len(names) != xi0.shape[0]:
            raise InputError(f"names has {len(names)} entries for xi0 of {xi0.shape[0]}")
        object.__setattr__(self, "names", names)
        if self.law not in LAWS:
            raise UnknownNameError("transition law", self.law, LAWS)
        index = self._index
        for p in self.phases:
            if not isinstance(p, Phase):
                raise InputError(f"phases must be Phase objects, got {type(p).__name__}")
            index(p.coordinate)
        for c in range(len(names)):
            ph = sorted((p for p in self.phases if index(p.coordinate) == c), key=lambda p: p.t1)
            for p, nxt in zip(ph, ph[1:]):
                if nxt.t1 < p.t2:
                    raise InputError(f"phases of {names[c]!r} overlap: [{p.t1}, {p.t2}] and [{nxt.t1}, {nxt.t2}]")

    def _index(self, coordinate) -> int:
        if isinstance(coordinate, str):
            if coordinate not in self.names:
                raise UnknownNameError("coordinate", coordinate, self.names)
            return self.names.index(coordinate)
        if not 0 <= coordinate < len(self.names):
            raise UnknownNameError("coordinate index", coordinate, tuple(str(i) for i in range(len(self.names))))
        return int(coordinate)

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(_times(t))
        if t.ndim != 1:
            raise ShapeError(f"t must be a number or a 1-D array of times, got shape {t.shape}")
        n = t.shape[0]
        m = len(self.names)
        xi = np.tile(np.asarray(self.xi0, dtype=float), (n, 1))
        xd = np.zeros((n, m))
        xdd = np.zeros((n, m))
        current = list(self.xi0)
        for p in sorted(self.phases, key=lambda p: (self._index(p.coordinate), p.t1)):
            i = self._index(p.coordinate)
            s, sd, sdd = transition(t, p.t1, p.t2, 0.0, p.value - current[i], order=2, law=self.law)
            xi[:, i] += s
            xd[:, i] += sd
            xdd[:, i] += sdd
            current[i] = p.value
        return TrajectorySample(t, xi, xd, xdd)

    def final(self) -> np.ndarray:
        """xi at the end of the last phase."""
        return self.sample([max(p.t2 for p in self.phases)]).xi[0]


def line_phases(a: float, b: float, x_start: float, x_end: float, t1: float, t2: float, coordinates=("x", "y")) -> tuple[Phase, Phase]:
    """The path option y = a x + b of Thesis Sec. 6.3.1.2 (the "(6.16)" phases): x and y move together on a line.

    Two :class:`Phase` objects, x from ``x_start`` to ``x_end`` and y from a x_start + b to a x_end + b, over the
    same [t1, t2] with the same law: since both follow start + (end - start) s(t), y(t) = a x(t) + b at every t
    (the horizontal path is the straight segment, instead of the x-then-y "half rectangle" of Fig. 6.13).  The
    trajectory's initial y must be a x_start + b (:class:`MultiPhase` starts y there when ``xi0`` says so).
    ``coordinates``: the names (or indices) of the two coordinates (default x, y).
    """
    a, b, x_start, x_end = (as_real(v, name) for name, v in (("a", a), ("b", b), ("x_start", x_start), ("x_end", x_end)))
    cx, cy = coordinates
    return Phase(cx, t1, t2, float(x_end)), Phase(cy, t1, t2, float(a * x_end + b))


def hover_and_reach(
    platform, p_hover=(0.0, 0.0, 2.0), q_arm=None, *, climb=(0.0, 3.0), reach=(3.0, 6.0), psi: float = 0.0, law: str = DEFAULT_LAW
) -> MultiPhase:
    """A mission for any platform: climb from the origin to ``p_hover`` [m] (world), then move the arm to ``q_arm``.

    ``q_arm`` (default: 60 % of the way from the neutral posture to the upper limit of each joint)
    must lie inside the joint limits; the arm starts at its neutral posture; yaw held at ``psi``.
    """
    from .model import check_platform

    p = as_vector(p_hover, 3, "p_hover")
    q0 = check_platform(platform).neutral_q()[7:]
    climb, reach = as_interval(climb, "climb", lo=0.0), as_interval(reach, "reach", lo=0.0)
    psi = as_real(psi, "psi", unit="rad")
    if q_arm is None:
        hi = np.where(np.isfinite(platform.arm_upper), platform.arm_upper, q0 + 1.0)
        q_arm = q0 + 0.6 * (hi - q0)
    q_arm = platform.check_arm_limits(q_arm)
    phases = [Phase(i, *climb, float(p[i])) for i in range(3) if p[i] != 0.0]
    phases += [Phase(6 + k, *reach, float(q_arm[k])) for k in range(platform.n_arm) if q_arm[k] != q0[k]]
    xi0 = (0.0, 0.0, 0.0, 0.0, 0.0, float(psi), *q0.tolist())
    return MultiPhase(tuple(phases), xi0, name="hover-and-reach", law=law, names=platform.xi_names)


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
    arm: tuple[float, ...] = (0.0, 0.0, 0.0)
    blend: float = 2.0
    name: str = field(default="spiral", compare=False)

    def __post_init__(self) -> None:
        for name, kw in (
            ("z", {}),
            ("climb_time", {"positive": True}),
            ("t_f", {"nonnegative": True}),
            ("rate", {}),
            ("period", {"positive": True}),
            ("blend", {"nonnegative": True}),
        ):
            object.__setattr__(self, name, as_real(getattr(self, name), f"spiral {name}", **kw))
        object.__setattr__(self, "arm", tuple(as_array(self.arm, "spiral arm", finite=True, ndim=1).tolist()))

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(_times(t))
        if t.ndim != 1:
            raise ShapeError(f"t must be a number or a 1-D array of times, got shape {t.shape}")
        n = t.shape[0]
        m = 6 + len(self.arm)
        xi = np.zeros((n, m))
        xd = np.zeros((n, m))
        xdd = np.zeros((n, m))
        z, zd, zdd = transition(t, 0.0, self.climb_time, 0.0, self.z, order=2)
        xi[:, 2], xd[:, 2], xdd[:, 2] = z, zd, zdd
        xi[:, 6:] = self.arm
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
    """Constant reference ``xi`` (6 + n_arm values, e.g. ``Hold(platform.neutral_xi())``: hover tests)."""

    xi: tuple[float, ...]
    name: str = field(default="hold", compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "xi", tuple(as_xi(self.xi, "xi").tolist()))

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(_times(t))
        if t.ndim != 1:
            raise ShapeError(f"t must be a number or a 1-D array of times, got shape {t.shape}")
        x = np.array(self.xi)
        n = t.shape[0]
        return TrajectorySample(t, np.tile(x, (n, 1)), np.zeros((n, x.shape[0])), np.zeros((n, x.shape[0])))
