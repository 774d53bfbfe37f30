"""Feedback laws for the unicycle and the car-like robot, with reference trajectories.

==========================  ===========================================================================
law                         source
==========================  ===========================================================================
:class:`KanayamaTracking`   Y. Kanayama, Y. Kimura, F. Miyazaki, T. Noguchi, "A stable tracking control
                            method for an autonomous mobile robot", IEEE ICRA 1990, pp. 384-389
:class:`PointTracking`      input-output linearisation of a point ahead of the axle: B. Siciliano,
                            L. Sciavicco, L. Villani, G. Oriolo, *Robotics: Modelling, Planning and
                            Control*, Springer 2009, Sec. 11.6.1
:class:`PosturePolar`       posture regulation in polar coordinates: M. Aicardi, G. Casalino, A. Bicchi,
                            A. Balestrino, "Closed loop steering of unicycle-like vehicles via Lyapunov
                            techniques", IEEE Robot. Autom. Mag. 2(1), 1995; Siciliano et al. Sec. 11.6.2
:class:`CarTracking`        dynamic feedback linearisation of the car (flat output: rear-axle centre):
                            A. De Luca, G. Oriolo, C. Samson, "Feedback control of a nonholonomic
                            car-like robot", in *Robot Motion Planning and Control*, LNCIS 229,
                            Springer 1998, Sec. 4
:class:`SinusoidalParking`  steering by sinusoids in chained form: R. M. Murray, S. S. Sastry,
                            "Nonholonomic motion planning: steering using sinusoids", IEEE TAC 38(5),
                            1993, pp. 700-716 (chained form of the car: De Luca et al. 1998, Sec. 2)
==========================  ===========================================================================

A controller is called by :func:`qprr.wheeled.sim.simulate_wheeled` as ``u = ctrl.control(t, q, dt)``
once per step (the input is then held over dt); ``reset()`` clears its internal state.
The equations are written here from those sources (notation adapted); gains are arguments.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from ..charts import wrap_angle
from ..errors import InputError
from ..validation import as_real, as_vector


def _gain(name: str, value: float) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"gain {name} must be finite and > 0, got {value!r}")
    return v


# ============================================================================ references
@dataclass(frozen=True)
class Lemniscate:
    """Figure-eight reference for the reference point [m]: p(t) = c + a (sin wt, sin wt cos wt).

    ``derivatives(t)`` returns p, p', p'', p''' (world frame).  Speed |p'| >= a w / 2 > 0 everywhere.
    """

    a: float = 2.0
    w: float = 0.25
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        _check_path(self, "a")

    def derivatives(self, t: float) -> tuple[np.ndarray, ...]:
        t = as_real(t, "t", unit="s")
        a, w = self.a, self.w
        s, c = math.sin(w * t), math.cos(w * t)
        s2, c2 = math.sin(2 * w * t), math.cos(2 * w * t)
        p = np.array([self.center[0] + a * s, self.center[1] + 0.5 * a * s2])
        d1 = np.array([a * w * c, a * w * c2])
        d2 = np.array([-a * w * w * s, -2 * a * w * w * s2])
        d3 = np.array([-a * w**3 * c, -4 * a * w**3 * c2])
        return p, d1, d2, d3


@dataclass(frozen=True)
class Circle:
    """Circle of radius R [m] at angular rate w [rad/s] (counter-clockwise), centre ``center``."""

    R: float = 1.5
    w: float = 0.3
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        _check_path(self, "R")

    def derivatives(self, t: float) -> tuple[np.ndarray, ...]:
        t = as_real(t, "t", unit="s")
        R, w = self.R, self.w
        s, c = math.sin(w * t), math.cos(w * t)
        return (
            np.array([self.center[0] + R * c, self.center[1] + R * s]),
            np.array([-R * w * s, R * w * c]),
            np.array([-R * w * w * c, -R * w * w * s]),
            np.array([R * w**3 * s, -R * w**3 * c]),
        )


def _check_path(path, size: str) -> None:
    """The size (> 0 [m]), the rate w (finite [rad/s]) and the centre (2 numbers [m]) of a reference path."""
    object.__setattr__(path, size, as_real(getattr(path, size), size, positive=True, unit="m"))
    object.__setattr__(path, "w", as_real(path.w, "w", unit="rad/s"))
    object.__setattr__(path, "center", tuple(as_vector(path.center, 2, "center").tolist()))


def reference_posture(ref, t: float) -> tuple[float, float, float, float, float]:
    """(x_r, y_r, theta_r, v_r, omega_r) of a unicycle following ``ref`` forwards (flatness):
    theta_r = atan2(y', x'), v_r = |p'|, omega_r = (x' y'' - y' x'') / v_r^2."""
    p, d1, d2, _ = ref.derivatives(t)
    v = math.hypot(d1[0], d1[1])
    if v < 1e-9:
        raise InputError(f"reference speed is zero at t = {t} s: the heading is undefined")
    return float(p[0]), float(p[1]), math.atan2(d1[1], d1[0]), v, float((d1[0] * d2[1] - d1[1] * d2[0]) / v**2)


class FeedbackLaw(ABC):
    """A feedback law for :func:`qprr.wheeled.sim.simulate_wheeled`: ``control(t, q, dt)`` returns the inputs at time ``t`` [s]
    and state ``q``; :meth:`reset` forgets a previous run (the simulator calls it at the start; default: nothing)."""

    @abstractmethod
    def control(self, t: float, q, dt: float) -> np.ndarray:
        """The inputs at ``t`` for the state ``q`` (``dt``: the step [s])."""

    def reset(self) -> None:
        """Forget the previous run (default: nothing to forget)."""
        return None


# ============================================================================ unicycle
class KanayamaTracking(FeedbackLaw):
    """Trajectory tracking for the unicycle (Kanayama et al. 1990).

    Error in the robot frame e = R^T(theta) (p_r - p), e_theta = theta_r - theta;
    v = v_r cos e_theta + k_x e_x, omega = omega_r + v_r (k_y e_y + k_theta sin e_theta).
    Locally asymptotically stable for v_r > 0 (Lyapunov function (e_x^2 + e_y^2)/2 +
    (1 - cos e_theta)/k_y).  Inputs (v, omega) of :class:`~qprr.wheeled.robots.Unicycle`.
    """

    def __init__(self, reference, kx: float = 1.0, ky: float = 4.0, ktheta: float = 3.0):
        self.reference = reference
        self.kx, self.ky, self.kt = _gain("kx", kx), _gain("ky", ky), _gain("ktheta", ktheta)

    def reset(self) -> None:
        pass

    def control(self, t: float, q, dt: float) -> np.ndarray:
        x, y, th = as_vector(q, 3, "q (unicycle)")
        xr, yr, thr, vr, wr = reference_posture(self.reference, t)
        c, s = math.cos(th), math.sin(th)
        ex, ey = c * (xr - x) + s * (yr - y), -s * (xr - x) + c * (yr - y)
        et = wrap_angle(thr - th)
        return np.array([vr * math.cos(et) + self.kx * ex, wr + vr * (self.ky * ey + self.kt * math.sin(et))])


class PointTracking(FeedbackLaw):
    """Tracking of the point B = (x + b cos theta, y + b sin theta) ahead of the axle.

    Input-output linearisation (Siciliano et al. 2009, Sec. 11.6.1): B_dot = T(theta) (v, omega)
    with T = [[cos th, -b sin th], [sin th, b cos th]] invertible for b != 0, so
    (v, omega) = T^-1 (p_d' + K (p_d - B)) makes each coordinate of B converge exponentially
    (rate ``k`` [1/s]); the heading is left free (zero dynamics).
    """

    def __init__(self, reference, b: float = 0.2, k: float = 2.0):
        self.reference = reference
        self.b, self.k = _gain("b", b), _gain("k", k)

    def reset(self) -> None:
        pass

    def control(self, t: float, q, dt: float) -> np.ndarray:
        x, y, th = as_vector(q, 3, "q (unicycle)")
        c, s = math.cos(th), math.sin(th)
        p, d1, _, _ = self.reference.derivatives(t)
        w = d1 + self.k * (p - np.array([x + self.b * c, y + self.b * s]))
        return np.array([c * w[0] + s * w[1], (-s * w[0] + c * w[1]) / self.b])


class PosturePolar(FeedbackLaw):
    """Posture regulation of the unicycle to ``goal`` = (x_g, y_g, theta_g) (Aicardi et al. 1995).

    In the goal frame: rho = |p|, gamma = atan2(y, x) - theta + pi, delta = gamma + theta;
    v = k1 rho cos gamma, omega = k2 gamma + k1 (sin gamma cos gamma / gamma)(gamma + k3 delta).
    Smooth in polar coordinates, discontinuous at the goal in Cartesian ones (as any
    stabilising law must be: Brockett's condition); rho, gamma, delta -> 0 for k1, k2, k3 > 0.
    """

    def __init__(self, goal, k1: float = 1.0, k2: float = 3.0, k3: float = 2.0, tol: float = 1e-9):
        self.goal = as_vector(goal, 3, "goal (x, y, theta)")
        self.k1, self.k2, self.k3 = _gain("k1", k1), _gain("k2", k2), _gain("k3", k3)
        self.tol = float(tol)

    def reset(self) -> None:
        pass

    def control(self, t: float, q, dt: float) -> np.ndarray:
        x, y, th = as_vector(q, 3, "q (unicycle)")
        xg, yg, thg = self.goal
        c, s = math.cos(thg), math.sin(thg)
        xl, yl = c * (x - xg) + s * (y - yg), -s * (x - xg) + c * (y - yg)  # robot in the goal frame
        thl = wrap_angle(th - thg)
        rho = math.hypot(xl, yl)
        if rho < self.tol:
            return np.array([0.0, -self.k2 * thl])
        gamma = wrap_angle(math.atan2(yl, xl) - thl + math.pi)
        delta = wrap_angle(gamma + thl)
        sc = math.sin(gamma) * math.cos(gamma) / gamma if abs(gamma) > 1e-9 else 1.0
        return np.array([self.k1 * rho * math.cos(gamma), self.k2 * gamma + self.k1 * sc * (gamma + self.k3 * delta)])


# ============================================================================ car
class CarTracking(FeedbackLaw):
    """Trajectory tracking of the rear-axle centre of the car by dynamic feedback linearisation.

    De Luca, Oriolo, Samson 1998, Sec. 4: for x_dot = v cos th, y_dot = v sin th, th_dot =
    v tan psi / D, psi_dot = u2 (rear-wheel drive; :class:`~qprr.wheeled.robots.Car`) and
    the flat output p = (x, y), add two integrators on the speed (state v, a = v_dot, new
    input a_dot).  Then p''' = M [a_dot, u2] + f with M = [(cos th, sin th), v^2/(D cos^2 psi)
    (-sin th, cos th)] (columns; invertible for v != 0) and f = 3 a v tan psi / D (-sin th,
    cos th) - v^3 tan^2 psi / D^2 (cos th, sin th).  With p''' = p_d''' + k2 (p_d'' - p'') +
    k1 (p_d' - p') + k0 (p_d - p) the error obeys e''' + k2 e'' + k1 e' + k0 e = 0; the gains
    place the three poles at -``pole`` [1/s].  The internal v, a are integrated exactly over
    each step (a_dot held).  Inputs (u1, u2) = (v, psi_dot).
    """

    def __init__(self, reference, D: float, pole: float = 1.5):
        self.reference = reference
        self.D = _gain("D", D)
        lam = _gain("pole", pole)
        self.k = (lam**3, 3 * lam**2, 3 * lam)
        self.reset()

    def reset(self) -> None:
        _, d1, d2, _ = self.reference.derivatives(0.0)
        self.v = math.hypot(d1[0], d1[1])
        self.a = float(d1 @ d2) / self.v if self.v > 0 else 0.0

    def control(self, t: float, q, dt: float) -> np.ndarray:
        x, y, th, psi = as_vector(q, 4, "q (car)")
        D, v, a = self.D, self.v, self.a
        if abs(v) < 1e-6:
            raise InputError(f"CarTracking: speed {v:.3g} m/s: the linearising feedback is singular at v = 0")
        c, s, tp = math.cos(th), math.sin(th), math.tan(psi)
        p = np.array([x, y])
        d1 = v * np.array([c, s])
        d2 = a * np.array([c, s]) + v * v * tp / D * np.array([-s, c])
        pd, pd1, pd2, pd3 = self.reference.derivatives(t)
        k0, k1, k2 = self.k
        r = pd3 + k2 * (pd2 - d2) + k1 * (pd1 - d1) + k0 * (pd - p)
        f = 3 * a * v * tp / D * np.array([-s, c]) - v**3 * tp * tp / D**2 * np.array([c, s])
        g = v * v / (D * math.cos(psi) ** 2)
        w = r - f
        a_dot = c * w[0] + s * w[1]
        u2 = (-s * w[0] + c * w[1]) / g
        self.v = v + a * dt + 0.5 * a_dot * dt * dt
        self.a = a + a_dot * dt
        return np.array([v, u2])


class SinusoidalParking(FeedbackLaw):
    """Open-loop steering of the car between postures by sinusoids in chained form.

    Chained form of the rear-wheel-drive car (De Luca et al. 1998): z1 = x, z2 = tan psi /
    (D cos^3 th), z3 = tan th, z4 = y, with z1' = v1, z2' = v2, z3' = z2 v1, z4' = z3 v1 and
    v1 = u1 cos th.  Murray and Sastry's algorithm (1993, Sec. III): phase 1 drives z1, z2 to
    the goal with constant inputs; phase 2 applies v1 = a sin(w t), v2 = b cos(w t) over one
    period, which returns z1, z2 and moves z3 by pi a b / w^2; phase 3 applies v1 = a sin(w t),
    v2 = b cos(2 w t), which returns z1, z2, z3 and moves z4 by pi a^2 b / (4 w^3).  b of each
    phase is computed from the state measured at the phase's start (so the zero-order-hold
    error of the earlier phases is corrected; a phase with nothing to correct is skipped, the
    robot waiting), each phase lasts ``T`` seconds; the goal must have |theta| < pi/2.
    ``duration`` = 3 T.
    """

    def __init__(self, goal, D: float, T: float = 8.0, a: float = 1.0):
        self.goal = as_vector(goal, 4, "goal (x, y, theta, psi)")
        if abs(self.goal[2]) >= math.pi / 2 or abs(self.goal[3]) >= math.pi / 2:
            raise InputError(f"goal {self.goal.tolist()}: the chained form needs |theta| < pi/2 and |psi| < pi/2")
        self.D, self.T, self.amp = _gain("D", D), _gain("T", T), _gain("a", a)
        self.duration = 3 * self.T
        self.reset()

    def reset(self) -> None:
        self._phase = -1
        self._coef = (0.0, 0.0)

    def chained(self, q) -> np.ndarray:
        """z = (z1, z2, z3, z4) of the posture q = (x, y, theta, psi)."""
        x, y, th, psi = q
        c = math.cos(th)
        return np.array([x, math.tan(psi) / (self.D * c**3), math.tan(th), y])

    def control(self, t: float, q, dt: float) -> np.ndarray:
        q = as_vector(q, 4, "q (car)")
        phase = min(2, int(t // self.T))
        tau = t - phase * self.T
        w = 2 * math.pi / self.T
        if phase != self._phase:  # plan the phase from the measured state
            z, zg = self.chained(q), self.chained(self.goal)
            if phase == 0:
                self._coef = ((zg[0] - z[0]) / self.T, (zg[1] - z[1]) / self.T)
            elif phase == 1:
                self._coef = (self.amp, (zg[2] - z[2]) * w * w / (math.pi * self.amp))
            else:
                self._coef = (self.amp, (zg[3] - z[3]) * 4 * w**3 / (math.pi * self.amp**2))
            if phase > 0 and abs(self._coef[1]) < 1e-12:  # nothing to correct in this phase: stay still
                self._coef = (0.0, 0.0)
            self._phase = phase
        if t >= self.duration:
            return np.zeros(2)
        c1, c2 = self._coef
        if phase == 0:
            v1, v2 = c1, c2
        elif phase == 1:
            v1, v2 = c1 * math.sin(w * tau), c2 * math.cos(w * tau)
        else:
            v1, v2 = c1 * math.sin(w * tau), c2 * math.cos(2 * w * tau)
        _, _, th, psi = q
        c, tp = math.cos(th), math.tan(psi)
        u1 = v1 / c
        th_dot = u1 * tp / self.D
        # z2' = v2 solved for psi_dot: z2' = (psi_dot / cos^2 psi + 3 tan psi tan th th_dot) / (D cos^3 th)
        psi_dot = (self.D * c**3 * v2 - 3 * tp * math.tan(th) * th_dot) * math.cos(psi) ** 2
        return np.array([u1, psi_dot])


__all__ = ["CarTracking", "Circle", "KanayamaTracking", "Lemniscate", "PointTracking", "PosturePolar", "SinusoidalParking", "reference_posture"]
