"""Operational-space impedance control of the end effector on the inverse-dynamics core, Thesis (6.72)-(6.73).

Goal: the end-effector position p_e (world axes) obeys, about its reference p_r,

    M_d e_ddot + D_d e_dot + K_d e = h,        e = p_e - p_r   (world axes),                 (6.71)

h the force the environment exerts on the end effector (world axes), M_d, D_d, K_d symmetric
positive definite 3 x 3 matrices (:class:`EndEffectorImpedance`).  A constant h deflects the end
effector by K_d^-1 h; each axis of a diagonal impedance rings at omega_n = sqrt(K/M) with damping
ratio zeta = D / (2 sqrt(K M)).  p_r is the end effector at the trajectory's xi_d with the
trajectory's own roll and pitch (level for a hover), not at the roll/pitch references (6.17)
computes: a fixed point in the world while hovering.  The end-effector orientation is not part
of the task; it follows the posture.

Formulation.  (6.72)-(6.73) are u = B y + n + J^T h_e with y = J_A^-1 M_d^-1 (M_d chi_ddot_d +
K_D e_dot + K_P e - M_d J_A_dot xi_dot - h_A): an end-effector acceleration a* mapped to joint
accelerations through the inverse of the Jacobian, and the measured wrench cancelled.  On an
aerial manipulator J is 3 x (6 + n) and the platform cannot apply any generalised force (coplanar
rotors push along z_B only), so the law is an *acceleration task* on the inverse-dynamics core
(:class:`~qprr.control.inverse_dynamics.InverseDynamicsController`):

1. The core's loops give the IDC's accelerations towards xi_d: hover, attitude, posture; its
   (6.17) gives the roll/pitch references; its ``realizable`` step leaves the base accelerations
   the rotors cannot produce to the dynamics (partial feedback linearisation).
2. The impedance asks for a* = p_ddot_r + M_d^-1 (h - D_d e_dot - K_d e) (with a wrist sensor), or
   a* = p_ddot_r - Lambda^-1 (D_d e_dot + K_d e) (without: M_d = Lambda, below).
3. :meth:`OperationalSpaceImpedance.task_accelerations` changes the accelerations of the *task
   coordinates* c - the arm joints and z on a platform that tilts to move sideways (the
   coordinates the rotors and the arm move at once; x and y go through the tilt, a cascade
   whose lag and, for an end effector below the rotors, non-minimum-phase zero sqrt(g/d) an
   impedance cannot go through), every coordinate on a fully actuated one - by the smallest
   change (weighted by W) that makes the *realised* end-effector acceleration equal a*.  The
   realised acceleration accounts for the core's realizable step exactly: with a the
   accelerations the core has set, f the feedforward and l the unproducible base rows,

       a_real = a + S_c da - E_l (tau(a) + f + M S_c da)_l / m,    tau = RNEA,
       J (a_real - a0) + J_dot v = a*   =>   A da = a* - J_dot v - J (a - a0 - E_l (tau(a) + f)_l / m),

   A = J (I - E_l M_l / m) S_c, solved as da = W A^T (A W A^T)^+ (...) with a damped inverse
   (``damping``) where A loses rank (a planar arm cannot move sideways).  The posture stays in
   the null space of A.  With a tilt strategy the core calls it twice per step: before (6.17),
   so that the thrust direction includes the task, and after the roll/pitch accelerations are
   set, to correct for them.
4. With a wrist sensor the measured wrench is cancelled on every coordinate, f = -S^T J^T h
   (the J^T h_e of (6.72)); its unproducible part is left to the dynamics like the rest, and
   the tilt leans into the force.

The end-effector acceleration then equals a* at every control step along the task directions,
on any platform, up to the sampling of a digital controller (zero-order hold: first order in the
control period, tests/test_opspace_impedance.py measures it); the directions A cannot reach
(e.g. sideways for the Q-PRR's planar arm) are held by the hover loop instead.  W: ``"range"``
(default; each task coordinate in proportion to its half range, so the 17 g slider of the
Q-PRR does not run into its stops first) or ``"inertia"`` (W = B_cc^-1, Khatib's dynamically
consistent inverse J_bar = B^-1 J^T Lambda with Lambda of (5.51); with every coordinate free the
output is then u = J^T (Lambda a* + mu + p) + N^T (B alpha_0 + n) - J^T h, N = I - J^T J_bar^T,
with Lambda, mu, p of :func:`qprr.analysis.opspace_model_xi`).

Without a sensor, the contact force accelerates the end effector by Lambda^-1 h with Lambda the
operational-space inertia of the free system (:func:`qprr.analysis.opspace_model`), since the
controller does not know h: a* above with M_d = Lambda gives Lambda e_ddot + D_d e_dot + K_d e = h,
the same static deflection K_d^-1 h, an apparent mass Lambda(q) that is not a parameter, and
the posture pushed by h.  Its fastest mode D / lambda_min(Lambda) must stay well inside the
control rate: the Q-PRR's slider makes its x inertia 0.02-0.5 kg (docs/analysis.md), too light
against a stiff contact (use a sensor).

Sign: h is the wrench ON the robot (Thesis (6.59)); the printed (6.71)/(6.73) take the one the
robot exerts (Siciliano's convention, see :mod:`qprr.control.impedance`); here the end effector
yields along h.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg import expm

from .. import charts as ch
from ..charts import State
from ..errors import InputError, UnknownNameError
from ..model import Platform
from ..validation import as_array, as_vector
from .base import Reference
from .inverse_dynamics import IDCGains, InverseDynamicsController


def _spd(x, name: str, positive: bool = True) -> np.ndarray:
    """A 3 x 3 symmetric positive definite matrix from a number, 3 diagonal values or a 3 x 3 matrix."""
    a = as_array(x, name)
    if a.ndim == 0 or a.shape == (1,):
        a = float(a.reshape(())) * np.eye(3)
    elif a.shape == (3,):
        a = np.diag(a)
    elif a.shape != (3, 3):
        raise InputError(f"{name} must be a number, 3 diagonal values or a 3 x 3 matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.abs(a - a.T).max() > 1e-12 * max(np.abs(a).max(), 1.0):
        raise InputError(f"{name} must be a finite symmetric matrix, got {a.tolist()}")
    w = np.linalg.eigvalsh(0.5 * (a + a.T))
    if (w.min() <= 0.0) if positive else (w.min() < 0.0):
        raise InputError(f"{name} must be positive {'definite' if positive else 'semi-definite'}, eigenvalues {w.tolist()}")
    return 0.5 * (a + a.T)


@dataclass(frozen=True)
class EndEffectorImpedance:
    """Desired impedance of the end-effector position, world axes: M e_ddot + D e_dot + K e = h (module docstring).

    ``stiffness`` K [N/m], ``damping`` D [N s/m] (positive semi-definite), ``mass`` M [kg] or None
    (the natural operational-space inertia: no force sensor needed).  Each is given as a
    number, 3 diagonal values or a 3 x 3 symmetric matrix and stored as 3 x 3.
    """

    stiffness: np.ndarray
    damping: np.ndarray
    mass: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness", _spd(self.stiffness, "stiffness"))
        object.__setattr__(self, "damping", _spd(self.damping, "damping", positive=False))
        if self.mass is not None:
            object.__setattr__(self, "mass", _spd(self.mass, "mass"))

    @classmethod
    def from_frequency(cls, omega_n, zeta=1.0, mass=1.0) -> EndEffectorImpedance:
        """Diagonal impedance with natural frequency ``omega_n`` [rad/s] and damping ratio ``zeta`` per axis
        (numbers or 3 values): K = M omega_n^2, D = 2 zeta omega_n M, M = ``mass`` [kg] (number or 3 values)."""
        w = np.broadcast_to(as_array(omega_n, "omega_n"), (3,)).astype(float)
        z = np.broadcast_to(as_array(zeta, "zeta"), (3,)).astype(float)
        m = np.broadcast_to(as_array(mass, "mass"), (3,)).astype(float)
        if not (np.all(np.isfinite(w) & (w > 0)) and np.all(np.isfinite(z) & (z >= 0)) and np.all(np.isfinite(m) & (m > 0))):
            raise InputError(f"need omega_n > 0 rad/s, zeta >= 0, mass > 0 kg, got {omega_n!r}, {zeta!r}, {mass!r}")
        return cls(m * w * w, 2.0 * z * w * m, m)

    def natural_frequency(self) -> np.ndarray:
        """omega_n [rad/s] of each mode: sqrt of the generalised eigenvalues of (K, M) (per axis when diagonal)."""
        if self.mass is None:
            raise InputError("the natural frequency needs a mass (mass=None uses the configuration-dependent Lambda)")
        return np.sqrt(np.linalg.eigvals(np.linalg.solve(self.mass, self.stiffness)).real)

    def damping_ratio(self) -> np.ndarray:
        """zeta = D / (2 sqrt(K M)) per axis (diagonal impedances only)."""
        if self.mass is None:
            raise InputError("the damping ratio needs a mass (mass=None uses the configuration-dependent Lambda)")
        mats = (self.mass, self.damping, self.stiffness)
        if any(np.abs(a - np.diag(np.diag(a))).max() > 0.0 for a in mats):
            raise InputError("damping_ratio is defined per axis for diagonal M, D, K")
        m, d, k = (np.diag(a) for a in mats)
        return d / (2.0 * np.sqrt(k * m))

    def deflection(self, h) -> np.ndarray:
        """Static deflection K^-1 h [m] under a constant force ``h`` (3,) [N]."""
        return np.linalg.solve(self.stiffness, as_vector(h, 3, "h"))

    def response(self, t, h, e0=None, e_dot0=None) -> tuple[np.ndarray, np.ndarray]:
        """(e, e_dot) (m, 3) of the ideal model M e_ddot + D e_dot + K e = h along the uniform times ``t``,
        ``h`` (m, 3) held constant over each interval (exact zero-order-hold discretisation)."""
        if self.mass is None:
            raise InputError("the ideal response needs a mass")
        t = as_array(t, "t")
        h = as_array(h, "h")
        if t.ndim != 1 or t.size < 2 or h.shape != (t.size, 3):
            raise InputError(f"need t (m,) with m >= 2 and h (m, 3), got {t.shape} and {h.shape}")
        dt = float(t[1] - t[0])
        if not dt > 0 or np.abs(np.diff(t) - dt).max() > 1e-9 * max(1.0, abs(t[-1])):
            raise InputError("t must be uniformly spaced and increasing")
        Mi = np.linalg.inv(self.mass)
        A = np.zeros((9, 9))
        A[0:3, 3:6] = np.eye(3)
        A[3:6, 0:3] = -Mi @ self.stiffness
        A[3:6, 3:6] = -Mi @ self.damping
        A[3:6, 6:9] = Mi
        E = expm(A * dt)
        Phi, Gam = E[0:6, 0:6], E[0:6, 6:9]
        x = np.zeros(6)
        x[0:3] = 0.0 if e0 is None else as_vector(e0, 3, "e0")
        x[3:6] = 0.0 if e_dot0 is None else as_vector(e_dot0, 3, "e_dot0")
        out = np.empty((t.size, 6))
        for k in range(t.size):
            out[k] = x
            x = Phi @ x + Gam @ h[k]
        return out[:, 0:3], out[:, 3:6]


WEIGHTINGS = ("range", "inertia")
"""How the task is shared among its coordinates: "range" (each in proportion to its half range), "inertia"
(B_cc^-1, Khatib's dynamically consistent inverse)."""

BASE_RANGE = 0.1
"""Half range [m] given to a base translation in the "range" weighting (it has no limit)."""

CORE_OPTIONS = ("tilt", "output", "name")
"""Keywords of :class:`OperationalSpaceImpedance` passed on to :class:`InverseDynamicsController`."""


class OperationalSpaceImpedance(InverseDynamicsController):
    """End-effector impedance (Thesis (6.72)-(6.73)) as a task on the inverse-dynamics core (module docstring).

    Parameters
    ----------
    platform : any platform.
    impedance : :class:`EndEffectorImpedance` (default: omega_n = 4 rad/s, zeta = 1, M = 1 kg with a
        sensor; K = 16 N/m, D = 8 N s/m and M = Lambda without).
    gains : :class:`IDCGains` of the hover, attitude and posture loops (default :meth:`IDCGains.default`).
    ee_sensor : ``ee_sensor(t) -> h`` (6,) world wrench on the end effector [N, N m] (e.g.
        ``contact.measured``), or None (no force measurement: ``impedance.mass`` must be None).
    coordinates : the coordinates the task moves (names or indices of xi); default: the arm joints
        and z on a platform that tilts to move sideways, every coordinate on a fully actuated one.
    weighting : "range" (default) or "inertia", how the task is shared among ``coordinates``
        (:data:`WEIGHTINGS`).
    damping : damping of the task inverse near singular directions, relative to what the base's
        own translation gives (a direction served by the task coordinates 100 times less than by a
        base translation is about half damped at the default 0.01).
    **core : ``tilt``, ``output``, ``name``, keywords passed to :class:`InverseDynamicsController`
        (the core here is always ``realizable``, evaluated at the measured state).

    ``history()`` returns the logged end-effector position, reference, error, force and a*.
    """

    name = "opspace-impedance"

    def __init__(
        self,
        platform: Platform,
        impedance: EndEffectorImpedance | None = None,
        gains: IDCGains | None = None,
        *,
        ee_sensor: Callable[[float], np.ndarray] | None = None,
        coordinates=None,
        weighting: str = "range",
        damping: float = 0.01,
        **core,
    ) -> None:
        if not isinstance(platform, Platform):
            raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
        if ee_sensor is not None and not callable(ee_sensor):
            raise InputError(f"ee_sensor must be a callable t -> wrench (6,) or None, got {type(ee_sensor).__name__}")
        if impedance is None:
            impedance = EndEffectorImpedance.from_frequency(4.0, 1.0, 1.0) if ee_sensor is not None else EndEffectorImpedance(16.0, 8.0, None)
        if not isinstance(impedance, EndEffectorImpedance):
            raise InputError(f"impedance must be an EndEffectorImpedance, got {type(impedance).__name__}")
        if ee_sensor is None and impedance.mass is not None:
            raise InputError(
                "a desired end-effector mass needs the contact force: give ee_sensor, or mass=None for the natural operational-space inertia"
            )
        if weighting not in WEIGHTINGS:
            raise UnknownNameError("weighting", weighting, WEIGHTINGS)
        self.weighting = weighting
        if not (isinstance(damping, (int, float)) and math.isfinite(damping) and damping >= 0.0):
            raise InputError(f"damping must be a number >= 0, got {damping!r}")
        self.impedance = impedance
        self.ee_sensor = ee_sensor
        from ..analysis.opspace import RateMapState, opspace_terms_xi  # the analysis package loads only with this controller

        self._terms = opspace_terms_xi
        self._state = RateMapState
        self._tdata = platform.model.createData()
        self._rdata = platform.model.createData()
        self._rstate = State(platform.n_arm)
        self._zeros = [0.0] * platform.n_xi
        self._M_inv = None if impedance.mass is None else np.linalg.inv(impedance.mass)
        unknown = sorted(set(core) - set(CORE_OPTIONS))
        if unknown:
            raise InputError(
                f"OperationalSpaceImpedance got unknown keyword argument(s) {unknown}: the options passed to "
                f"the inverse-dynamics core are {CORE_OPTIONS}"
            )
        super().__init__(platform, gains, realizable=True, **core)
        self.coordinates = self._task_coordinates(coordinates)
        self._W = None if weighting == "inertia" else self._range_weights()
        # damping of the task inverse: eigenvalues of A W A^T below ~ damping x that of the base's own translation
        scale = 1.0 / platform.total_mass if weighting == "inertia" else BASE_RANGE**2
        self._eps2 = (float(damping) * scale) ** 2

    def _range_weights(self) -> np.ndarray:
        """W_ii = (half range)^2 of each task coordinate: arm joints their limits; base translations BASE_RANGE, base angles pi/2."""
        P = self.platform
        half = np.concatenate(
            [[BASE_RANGE] * 3, [0.5 * math.pi] * 3, np.where(np.isfinite(P.arm_upper - P.arm_lower), 0.5 * (P.arm_upper - P.arm_lower), math.pi)]
        )
        return half[list(self.coordinates)] ** 2

    def _task_coordinates(self, coordinates) -> tuple[int, ...]:
        n, names = self.platform.n_xi, self.platform.xi_names
        if coordinates is None:
            if self.tilt_mode == "none":
                return tuple(range(n))
            return (2, *range(6, n))
        out = []
        for c in coordinates:
            if isinstance(c, str):
                if c not in names:
                    raise UnknownNameError("coordinate", c, names)
                out.append(names.index(c))
            elif isinstance(c, (int, np.integer)) and not isinstance(c, bool) and 0 <= c < n:
                out.append(int(c))
            else:
                raise InputError(f"coordinates must be names or indices of xi (0..{n - 1}), got {c!r}")
        if not out or len(set(out)) != len(out):
            raise InputError(f"coordinates must be distinct and not empty, got {coordinates!r}")
        return tuple(out)

    def _new_run(self) -> None:
        super()._new_run()
        self._h = np.zeros(6)
        self._step_t = None
        self.log: list[np.ndarray] = []

    def reference(self, ref: Reference) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p_r, p_dot_r, p_ddot_r) (3,) each, world: the end effector at the trajectory's (xi_d, xi_dot_d, xi_ddot_d)."""
        if not isinstance(ref, Reference) or np.shape(ref.xi) != (self.platform.n_xi,):
            raise InputError(
                f"ref must be a qprr.control.Reference of the platform's {self.platform.n_xi} thesis coordinates, got {type(ref).__name__}"
            )
        return self._reference(ref)

    def _reference(self, ref: Reference) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`reference` unchecked (every control tick, on the simulator's own reference)."""
        model, data, fid, rs = self.platform.model, self._rdata, self.platform.ee_frame, self._rstate
        rs.update_xi(0.0, ref.xi, ref.xi_dot, arrays=False, reuse=True)
        pin.forwardKinematics(model, data, rs.q, rs.v, rs.accel_to_v(ref.xi_ddot))
        pin.updateFramePlacement(model, data, fid)
        vel = pin.getFrameVelocity(model, data, fid, pin.LOCAL_WORLD_ALIGNED).linear
        acc = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED).linear
        return data.oMf[fid].translation.copy(), vel.copy(), acc.copy()

    def update_references(self, t: float, state: State, ref: Reference) -> None:
        """Keep the end-effector reference of the trajectory's xi_d before (6.17) overwrites its roll and pitch."""
        self._ref = self._reference(ref)

    def feedforward(self, t: float, state: State) -> list[float] | None:
        """-u_e(h) = -S^T J^T h with a wrist sensor (the J^T h_e of (6.72), h read here for the step); None without."""
        if self.ee_sensor is None:
            return None
        self._h = h = as_vector(self.ee_sensor(t), 6, "ee_sensor(t)").copy()
        J = pin.computeFrameJacobian(self.platform.model, self._tdata, state.q, self.platform.ee_frame, pin.LOCAL_WORLD_ALIGNED)
        return state.force_to_xi_list(-(J.T @ h))

    def task_accelerations(self, t: float, state: State, ref: Reference, a: list[float], ff: list[float] | None) -> list[float]:
        """The change of the coordinates ``coordinates`` that makes the realised end-effector acceleration a* (module docstring)."""
        imp, P = self.impedance, self.platform
        if self._step_t != t:  # first call of this step: the model, the reference and a*
            S = ch.rate_map(state.xi)
            a0 = np.array(state.accel_to_v_list(self._zeros))  # S_dot xi_dot: the acceleration at xi_ddot = 0
            m = self._terms(P.model, self._tdata, P.ee_frame, self._state(state.q, state.v, a0, S), (0, 1, 2), self.coordinates, operational=False)
            p_r, v_r, a_r = self._ref
            e = m.position - p_r
            e_dot = m.velocity[0:3] - v_r
            spring = imp.damping @ e_dot + imp.stiffness @ e
            Jv = m.J_v[0:3]
            if self._M_inv is not None:
                a_star = a_r + self._M_inv @ (self._h[0:3] - spring)
            else:  # M_d = Lambda of the free system: Lambda^-1 = J M^-1 J^T
                a_star = a_r - (Jv @ np.linalg.solve(m.M, Jv.T)) @ spring
            # realised acceleration (module docstring, step 3): a_real = a + S_c da - E_l (tau(a) + ff + M S_c da)_l / m,
            # so A da = rhs with A = J (I - E_l M_l / m) S_c, the same at both calls of the step
            c = list(self.coordinates)
            Sd = S[:, c]
            lost = self._lost
            if lost:
                Ml = m.M[lost]
                mass = np.diag(Ml[:, lost])
                Ad = Jv @ Sd - Jv[:, lost] @ ((Ml / mass[:, None]) @ Sd)
            else:
                mass, Ad = None, Jv @ Sd
            if self._W is None:
                X = np.linalg.solve(m.B[np.ix_(c, c)], Ad.T)  # B_cc^-1 A^T: the inertia-weighted (dynamically consistent) inverse
            else:
                X = self._W[:, None] * Ad.T
            w, V = np.linalg.eigh(0.5 * ((Ad @ X) + (Ad @ X).T))
            w = np.maximum(w, 0.0)
            den = w * w + self._eps2
            gain = np.divide(w, den, out=np.zeros_like(w), where=den > 1e-300)
            self._step = (a0, m, a_star, Sd @ (X @ ((V * gain) @ V.T)), mass)
            self._step_t = t
            self.log.append(np.concatenate([[t], m.position, p_r, e, self._h[0:3], a_star]))
        a0, m, a_star, G, mass = self._step
        Jv = m.J_v[0:3]
        a = np.asarray(a)
        rhs = a_star - m.drift[0:3] - Jv @ (a - a0)
        if mass is not None:
            lost = self._lost
            tau = pin.rnea(P.model, self._tdata, state.q, state.v, a)
            if ff is not None:
                tau = tau + np.asarray(ff)
            rhs += Jv[:, lost] @ (tau[lost] / mass)
        return (G @ rhs).tolist()

    def history(self) -> dict[str, np.ndarray]:
        """Per control step: ``t``; ``p_e``, ``p_r``, ``e`` = p_e - p_r [m]; ``h`` the measured force [N] (zeros
        without a sensor); ``a_star`` the task acceleration [m/s^2] (world axes, (m, 3) each)."""
        a = np.array(self.log) if self.log else np.zeros((0, 16))
        return {"t": a[:, 0], "p_e": a[:, 1:4], "p_r": a[:, 4:7], "e": a[:, 7:10], "h": a[:, 10:13], "a_star": a[:, 13:16]}


def fit_second_order(t, y, y_final=None) -> tuple[float, float, float]:
    """(omega_n [rad/s], zeta, y_inf) of an underdamped step response y(t) from t = 0 (at rest at 0 before).

    Least squares on y = y_inf (1 - e^(-zeta w t) (cos(w_d t) + zeta w / w_d sin(w_d t))), w_d = w sqrt(1 - zeta^2),
    started from the logarithmic decrement of the first peaks.  ``y_final`` fixes y_inf if given.
    """
    from scipy.optimize import least_squares

    t = as_array(t, "t")
    y = as_array(y, "y")
    if t.ndim != 1 or t.shape != y.shape or t.size < 10:
        raise InputError(f"need t and y of one shape (m,), m >= 10, got {t.shape} and {y.shape}")

    def model(p):
        w, z, yi = p[0], p[1], (p[2] if y_final is None else y_final)
        wd = w * math.sqrt(max(1.0 - z * z, 1e-12))
        return yi * (1.0 - np.exp(-z * w * t) * (np.cos(wd * t) + z * w / wd * np.sin(wd * t)))

    yi0 = float(y[-max(1, y.size // 10) :].mean()) if y_final is None else float(y_final)
    k = int(np.argmax(np.abs(y - yi0) * (np.sign(y - yi0) == np.sign(yi0))))  # first overshoot peak
    over = max(abs(y[k] - yi0) / max(abs(yi0), 1e-300), 1e-4)
    z0 = -math.log(over) / math.sqrt(math.pi**2 + math.log(over) ** 2)
    w0 = math.pi / max(t[k], 1e-6) / math.sqrt(max(1.0 - z0 * z0, 1e-6))
    p0 = [w0, min(max(z0, 0.01), 0.95)] + ([yi0] if y_final is None else [])
    lo = [1e-6, 0.0] + ([-np.inf] if y_final is None else [])
    hi = [np.inf, 0.999] + ([np.inf] if y_final is None else [])
    res = least_squares(lambda p: model(p) - y, p0, bounds=(lo, hi), x_scale="jac")
    w, z = float(res.x[0]), float(res.x[1])
    return w, z, float(res.x[2]) if y_final is None else float(y_final)
