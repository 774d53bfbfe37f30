"""The thesis chart: the one conversion between xi = [x, y, z, phi, theta, psi, q_arm] and Pinocchio's (q, v).

Thesis coordinates (any number n of arm joints, xi of size 6 + n): p_world = [x, y, z] and ZYX
Euler angles R = Rz(psi) Ry(theta) Rx(phi) (Thesis (3.4)); rates xi_dot.

Pinocchio (free-flyer root): q = [p_world, quat_xyzw, q_arm] (nq = 7 + n) and
v = [v_body, omega_body, q_arm_dot] (nv = 6 + n), both base velocities in B.

The rate map is v = S(xi) xi_dot with S = blockdiag(R^T, T(phi_b), I_n), where
omega_body = T(phi_b) [phi_dot, theta_dot, psi_dot] (Thesis (3.25)-(3.26)).  S is also the
tangent map of xi -> q, so generalised forces transform as u_xi = S^T tau (Thesis (5.40)-(5.43)
with R_Q = S^T).  T is singular at theta = +-pi/2 (cos theta = 0): functions that need T^-1
raise :class:`EulerSingularityError` when |cos theta| < ``EULER_TOL``.

Everything that rotates, maps rates or maps forces between the two coordinate systems lives
here, in three forms: array functions (validated, for users and tests), :class:`State` (the
same maps on plain floats with cached trigonometry, for loops that run every millisecond) and
batch functions over logged runs (``*_batch``).  Tests check the three against each other.
"""

from __future__ import annotations

import math
from math import atan2, cos, hypot, sin

import numpy as np
import pinocchio as pin

from .errors import DivergenceError, EulerSingularityError, InputError, ShapeError
from .validation import as_array, as_int, as_matrix, as_real, as_vector

EULER_TOL = 1e-6
"""|cos(theta)| below which ZYX Euler angles are treated as singular."""

_PI = math.pi
_TWO_PI = 2.0 * math.pi


def as_xi(xi, name: str = "xi", n: int | None = None) -> np.ndarray:
    """A thesis-coordinate vector: 1-D, finite, 6 + n_arm entries (``n`` checked when given)."""
    a = as_array(xi, name)
    if a.ndim != 1 or a.shape[0] < 6 or (n is not None and a.shape[0] != n):
        want = f"({n},)" if n is not None else "(6 + n_arm,)"
        raise ShapeError(f"{name} must have shape {want}, got shape {a.shape}")
    # a finite sum means every entry is finite (as_vector's test, which names the entries otherwise)
    return a if np.isfinite(a.sum()) else as_vector(a, a.shape[0], name)


def xi_names(n_arm: int, arm_names=None) -> tuple[str, ...]:
    """Names of the thesis coordinates: x, y, z, phi, theta, psi, then the arm joints (default q1..qn)."""
    n_arm = as_int(n_arm, "n_arm", lo=0)
    arm = tuple(arm_names) if arm_names is not None else tuple(f"q{i + 1}" for i in range(n_arm))
    if len(arm) != n_arm:
        raise ShapeError(f"arm_names must hold n_arm = {n_arm} names, got {len(arm)}")
    return ("x", "y", "z", "phi", "theta", "psi", *arm)


def wrap_angle(a):
    """Angle(s) wrapped to [-pi, pi) [rad] (a real number or an array of any shape, elementwise: NaN stays NaN)."""
    if not isinstance(a, float):
        a = as_array(a, "angle a") if not isinstance(a, (int, np.integer, np.floating)) or isinstance(a, bool) else float(a)
    return (a + _PI) % _TWO_PI - _PI


# ============================================================================ ZYX rotation
_EX, _EY, _EZ = (pin.skew(np.eye(3)[i]) for i in range(3))


def rot_x(a: float) -> np.ndarray:
    """Rotation by ``a`` [rad] about x."""
    a = as_real(a, "angle a")
    c, s = cos(a), sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    """Rotation by ``a`` [rad] about y."""
    a = as_real(a, "angle a")
    c, s = cos(a), sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    """Rotation by ``a`` [rad] about z."""
    a = as_real(a, "angle a")
    c, s = cos(a), sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation_entries(sf, cf, st, ct, sp, cp):
    """Entries of Rz(psi) Ry(theta) Rx(phi), row-major, from the sines and cosines (Thesis (3.4))."""
    return (cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf, sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf, -st, ct * sf, ct * cf)


def _rotation(phi: float, theta: float, psi: float) -> np.ndarray:
    return np.array(_rotation_entries(sin(phi), cos(phi), sin(theta), cos(theta), sin(psi), cos(psi))).reshape(3, 3)


def euler_to_rotation(euler_zyx) -> np.ndarray:
    """R_b = Rz(psi) Ry(theta) Rx(phi) for ``euler_zyx = [phi, theta, psi]``, expanded as Thesis (3.4)."""
    phi, theta, psi = as_vector(euler_zyx, 3, "euler_zyx").tolist()
    return _rotation(phi, theta, psi)


def euler_to_rotation_batch(euler: np.ndarray) -> np.ndarray:
    """R = Rz(psi) Ry(theta) Rx(phi) for rows [phi, theta, psi] (m, 3): shape (m, 3, 3) (Thesis (3.4))."""
    e = as_array(euler, "euler", ndim=2)  # NaN rows pass: logs of diverged runs
    if e.shape[1] != 3:
        raise ShapeError(f"euler must have shape (m, 3), got shape {e.shape}")
    entries = _rotation_entries(np.sin(e[:, 0]), np.cos(e[:, 0]), np.sin(e[:, 1]), np.cos(e[:, 1]), np.sin(e[:, 2]), np.cos(e[:, 2]))
    return np.stack(entries, axis=-1).reshape(-1, 3, 3)


def check_pitch(theta: float, what: str) -> None:
    """Raise :class:`EulerSingularityError` naming ``what`` when the ZYX pitch ``theta`` [rad] is at the Euler singularity."""
    if abs(cos(theta)) < EULER_TOL:
        raise EulerSingularityError(
            f"{what}: ZYX Euler angles are singular at pitch theta = {theta!r} rad "
            f"(|cos theta| < {EULER_TOL:g}); roll and yaw rates are not defined there"
        )


def check_rotation(R, name: str = "R", tol: float = 1e-9) -> np.ndarray:
    """``R`` as a 3x3 rotation matrix (finite, R^T R = I within ``tol``, det = +1), else InputError."""
    tol = as_real(tol, "tol", positive=True)
    R = as_matrix(R, (3, 3), name)
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    det = float(np.linalg.det(R))
    if not err <= tol or not det > 0.0:
        raise InputError(f"{name} must be a rotation matrix (R^T R = I, det R = +1): |R^T R - I| = {err:.3g}, det R = {det:.6g}")
    return R


def rotation_to_euler(R) -> np.ndarray:
    """[phi, theta, psi] of a rotation matrix, theta in (-pi/2, pi/2) (Thesis (3.8), corrected).

    Raises :class:`EulerSingularityError` at theta = +-pi/2 where roll and yaw are not unique,
    :class:`InputError` if ``R`` is not a rotation.  The printed (3.8) swaps the roll and yaw
    formulas: see docs/thesis-errata.md.
    """
    R = check_rotation(R, "R", 1e-6)
    theta = atan2(-R[2, 0], hypot(R[2, 1], R[2, 2]))
    check_pitch(theta, "rotation_to_euler")
    return np.array([atan2(R[2, 1], R[2, 2]), theta, atan2(R[1, 0], R[0, 0])])


def unit_quaternion(quat_xyzw, name: str = "quat_xyzw") -> np.ndarray:
    """A quaternion (x, y, z, w) of norm 1 (within 1e-6), else ShapeError naming ``name`` (off the unit sphere)."""
    qa = as_vector(quat_xyzw, 4, name)
    norm = float(np.linalg.norm(qa))
    if not abs(norm - 1.0) < 1e-6:
        raise ShapeError(f"{name} must be a unit quaternion (x, y, z, w), got {qa.tolist()} of norm {norm!r}")
    return qa


# ============================================================================ rate maps
def euler_rate_matrix(euler_zyx) -> np.ndarray:
    """T(phi_b) with omega_body = T [phi_dot, theta_dot, psi_dot] (Thesis (3.25)).

    The world-frame angular velocity is omega_world = R_b T phi_b_dot.
    """
    phi, theta, _ = as_vector(euler_zyx, 3, "euler_zyx").tolist()
    return _rate_matrix(phi, theta)


def _rate_matrix(phi: float, theta: float) -> np.ndarray:
    sf, cf, st, ct = sin(phi), cos(phi), sin(theta), cos(theta)
    return np.array([[1.0, 0.0, -st], [0.0, cf, sf * ct], [0.0, -sf, cf * ct]])


def rate_map(xi) -> np.ndarray:
    """S(xi) = blockdiag(R^T, T, I_n) (square, 6 + n): v = S xi_dot, u_xi = S^T tau."""
    xi = as_xi(xi)
    phi, theta, psi = xi[3:6].tolist()
    S = np.eye(xi.shape[0])
    S[0:3, 0:3] = _rotation(phi, theta, psi).T
    S[3:6, 3:6] = _rate_matrix(phi, theta)
    return S


def rate_map_derivatives(xi) -> np.ndarray:
    """dS/dxi_k for k = phi, theta, psi as an array of shape (3, 6 + n, 6 + n) (S depends on nothing else)."""
    xi = as_xi(xi)
    phi, theta, psi = xi[3:6].tolist()
    Rx, Ry, Rz = rot_x(phi), rot_y(theta), rot_z(psi)
    dR = (Rz @ Ry @ Rx @ _EX, Rz @ Ry @ _EY @ Rx, Rz @ _EZ @ Ry @ Rx)
    sf, cf, st, ct = sin(phi), cos(phi), sin(theta), cos(theta)
    dT = (
        np.array([[0.0, 0.0, 0.0], [0.0, -sf, cf * ct], [0.0, -cf, -sf * ct]]),
        np.array([[0.0, 0.0, -ct], [0.0, 0.0, -sf * st], [0.0, 0.0, -cf * st]]),
        np.zeros((3, 3)),
    )
    n = xi.shape[0]
    out = np.zeros((3, n, n))
    for k in range(3):
        out[k, 0:3, 0:3] = dR[k].T
        out[k, 3:6, 3:6] = dT[k]
    return out


def rate_map_dot(xi, xi_dot) -> np.ndarray:
    """dS/dt along xi_dot."""
    xi = as_xi(xi)
    xi_dot = as_vector(xi_dot, xi.shape[0], "xi_dot")
    return np.tensordot(xi_dot[3:6], rate_map_derivatives(xi), axes=1)


# ============================================================================ conversions
def xi_to_q(xi) -> np.ndarray:
    """Pinocchio configuration q (7 + n) of thesis coordinates xi (6 + n)."""
    xi = as_xi(xi)
    hf, ht, hp = 0.5 * xi[3], 0.5 * xi[4], 0.5 * xi[5]
    cf, sf, ct, st, cp, sp = cos(hf), sin(hf), cos(ht), sin(ht), cos(hp), sin(hp)
    q = np.empty(xi.shape[0] + 1)
    q[0:3] = xi[0:3]
    # quaternion of Rz(psi) Ry(theta) Rx(phi), (x, y, z, w) order as in Pinocchio
    q[3] = sf * ct * cp - cf * st * sp
    q[4] = cf * st * cp + sf * ct * sp
    q[5] = cf * ct * sp - sf * st * cp
    q[6] = cf * ct * cp + sf * st * sp
    q[7:] = xi[6:]
    return q


def q_to_xi(q) -> np.ndarray:
    """Thesis coordinates of a Pinocchio configuration (raises at the Euler singularity)."""
    q = as_array(q, "q")
    if q.ndim != 1 or q.shape[0] < 7:
        raise ShapeError(f"q must have shape (7 + n_arm,), got shape {q.shape}")
    q = as_vector(q, q.shape[0], "q")
    qa = unit_quaternion(q[3:7], "q[3:7]")
    R = pin.Quaternion(qa[3], qa[0], qa[1], qa[2]).toRotationMatrix()
    return np.concatenate([q[0:3], rotation_to_euler(R), q[7:]])


def xi_dot_to_v(xi, xi_dot) -> np.ndarray:
    """Pinocchio velocity v = S(xi) xi_dot (body-frame linear and angular velocity)."""
    S = rate_map(xi)
    return S @ as_vector(xi_dot, S.shape[0], "xi_dot")


def v_to_xi_dot(xi, v) -> np.ndarray:
    """Thesis rates xi_dot = S(xi)^-1 v (raises at the Euler singularity)."""
    xi = as_xi(xi)
    v = as_vector(v, xi.shape[0], "v")
    check_pitch(xi[4], "v_to_xi_dot")
    S = rate_map(xi)
    out = np.empty(xi.shape[0])
    out[0:3] = S[0:3, 0:3].T @ v[0:3]
    out[3:6] = np.linalg.solve(S[3:6, 3:6], v[3:6])
    out[6:] = v[6:]
    return out


def xi_to_qv(xi, xi_dot) -> tuple[np.ndarray, np.ndarray]:
    """(q, v) of thesis coordinates and rates."""
    return xi_to_q(xi), xi_dot_to_v(xi, xi_dot)


def qv_to_xi(q, v) -> tuple[np.ndarray, np.ndarray]:
    """(xi, xi_dot) of a Pinocchio state (raises at the Euler singularity)."""
    xi = q_to_xi(q)
    return xi, v_to_xi_dot(xi, v)


def xi_ddot_to_a(xi, xi_dot, xi_ddot) -> np.ndarray:
    """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot."""
    S = rate_map(xi)
    xi_dot = as_vector(xi_dot, S.shape[0], "xi_dot")
    return S @ as_vector(xi_ddot, S.shape[0], "xi_ddot") + rate_map_dot(xi, xi_dot) @ xi_dot


def a_to_xi_ddot(xi, xi_dot, a) -> np.ndarray:
    """Thesis accelerations xi_ddot = S^-1 (a - S_dot xi_dot) (raises at the Euler singularity)."""
    xi = as_xi(xi)
    xi_dot = as_vector(xi_dot, xi.shape[0], "xi_dot")
    check_pitch(xi[4], "a_to_xi_ddot")
    rhs = as_vector(a, xi.shape[0], "a") - rate_map_dot(xi, xi_dot) @ xi_dot
    return np.linalg.solve(rate_map(xi), rhs)


def force_to_xi(xi, tau) -> np.ndarray:
    """Thesis generalised force u = S^T tau of a Pinocchio one (Thesis (5.40)-(5.43), R_Q = S^T)."""
    S = rate_map(xi)
    return S.T @ as_vector(tau, S.shape[0], "tau")


def force_from_xi(xi, u) -> np.ndarray:
    """Pinocchio generalised force tau = S^-T u of a thesis one (raises at the Euler singularity)."""
    xi = as_xi(xi)
    check_pitch(xi[4], "force_from_xi")
    return np.linalg.solve(rate_map(xi).T, as_vector(u, xi.shape[0], "u"))


# -------------------------------------------------------------------- batch forms (logs)
def _batch(R, xi, name: str, values) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R (m, 3, 3), xi (m, 6 + n), values (m, 6 + n)) of the batch functions, checked (NaN rows pass: logs of diverged runs)."""
    xi = as_array(xi, "xi", ndim=2)
    if xi.shape[1] < 6:
        raise ShapeError(f"xi must have shape (m, 6 + n_arm), got shape {xi.shape}")
    R = as_array(R, "R")
    if R.shape != (xi.shape[0], 3, 3):
        raise ShapeError(f"R must have shape ({xi.shape[0]}, 3, 3) (one rotation per row of xi), got shape {R.shape}")
    values = as_array(values, name)
    if values.shape != xi.shape:
        raise ShapeError(f"{name} must have the shape of xi {xi.shape}, got shape {values.shape}")
    return R, xi, values


def force_from_xi_batch(R: np.ndarray, xi: np.ndarray, u: np.ndarray) -> np.ndarray:
    """tau = S^-T u row by row (m, 6 + n): R^T u_p, T^-T u_tau, u_arm (``R`` (m, 3, 3) of the rows of ``xi``)."""
    R, xi, u = _batch(R, xi, "u", u)
    tau = np.empty_like(u)
    tau[:, 0:3] = np.einsum("nji,nj->ni", R, u[:, 0:3])
    sf, cf = np.sin(xi[:, 3]), np.cos(xi[:, 3])
    st, ct = np.sin(xi[:, 4]), np.cos(xi[:, 4])
    m0, m1, m2 = u[:, 3], u[:, 4], u[:, 5]
    w = (m2 + st * m0) / ct
    tau[:, 3] = m0
    tau[:, 4] = cf * m1 + sf * w
    tau[:, 5] = -sf * m1 + cf * w
    tau[:, 6:] = u[:, 6:]
    return tau


def force_to_xi_batch(R: np.ndarray, xi: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """u = S^T tau row by row (m, 6 + n): R tau_lin, T^T tau_ang, tau_arm."""
    R, xi, tau = _batch(R, xi, "tau", tau)
    u = np.empty_like(tau)
    u[:, 0:3] = np.einsum("nij,nj->ni", R, tau[:, 0:3])
    sf, cf = np.sin(xi[:, 3]), np.cos(xi[:, 3])
    st, ct = np.sin(xi[:, 4]), np.cos(xi[:, 4])
    m0, m1, m2 = tau[:, 3], tau[:, 4], tau[:, 5]
    u[:, 3] = m0
    u[:, 4] = cf * m1 - sf * m2
    u[:, 5] = -st * m0 + sf * ct * m1 + cf * ct * m2
    u[:, 6:] = tau[:, 6:]
    return u


def to_body_batch(R: np.ndarray, p_world: np.ndarray, origin_world: np.ndarray) -> np.ndarray:
    """R^T (p - origin) row by row: world points (m, 3) in the body frames (m, 3, 3) at ``origin_world`` (m, 3)."""
    p_world = as_array(p_world, "p_world", ndim=2)
    m = p_world.shape[0]
    if p_world.shape[1] != 3:
        raise ShapeError(f"p_world must have shape (m, 3), got shape {p_world.shape}")
    R = as_array(R, "R")
    if R.shape != (m, 3, 3):
        raise ShapeError(f"R must have shape ({m}, 3, 3) (one rotation per point), got shape {R.shape}")
    origin_world = as_array(origin_world, "origin_world")
    if origin_world.shape != (m, 3):
        raise ShapeError(f"origin_world must have shape ({m}, 3), got shape {origin_world.shape}")
    return np.einsum("nji,nj->ni", R, p_world - origin_world)


# ============================================================================ hot-loop form
class State:
    # The array maps above on plain floats, for loops that run every millisecond (simulator,
    # controllers): one xi <-> (q, v) update caches R_b and the trigonometry that S, S_dot and
    # S^-T need, so each map below is a few multiplications on Python floats (cheaper than numpy
    # on vectors of 6 + n entries).  Arm entries are carried through by slicing.
    """Measured state at one step (updated in place by :meth:`update`; no allocation per step).

    Attributes (set by :meth:`update` / :meth:`set_from_xi`; read them, do not assign them): ``t`` [s];
    ``q`` (7 + n,), ``v`` (6 + n,) Pinocchio; ``xi``, ``xi_dot`` (6 + n,) thesis; ``sf``, ``cf``, ``st``,
    ``ct``: sin/cos of phi and theta; ``n_arm`` arm joints (``State(platform.n_arm)``); and, for controllers
    that compute on plain floats, the same values as tuples of Python floats: ``xi_floats``,
    ``xi_dot_floats``, ``rotation_floats`` (R_b row-major: r00, r01, r02, r10, ..., r22) and
    ``u_applied_floats``.

    Properties: ``R`` (3, 3) body-to-world rotation (a new array); ``u_applied`` (6 + n,): the generalised
    force the actuators applied during the previous step (thesis coordinates, disturbances excluded) -
    the "measured input" of the model-free controller, filled only for controllers with
    ``uses_applied_force = True``; ``arm`` (q_arm, a new list).

    Maps (tests check them against the array functions of this module):

    * :meth:`update` ``(t, q, v, v_bound=None)``: every field from (q, v);
    * :meth:`update_xi` / :meth:`set_from_xi` ``(t, xi, xi_dot, arrays, reuse)``: every field from (xi, xi_dot);
    * :meth:`accel_to_v_list` / :meth:`accel_to_v`: Pinocchio's a = S xi_ddot + S_dot xi_dot;
    * :meth:`force_to_xi_list` / :meth:`force_to_xi`: u = S^T tau (Thesis (5.40)-(5.43), R_Q = S^T);
    * :meth:`force_from_xi`: tau = S^-T u;
    * :meth:`lin_to_world`, :meth:`lin_to_body`, :meth:`euler_accel_to_omega_dot`.
    """

    __slots__ = (
        "t",
        "n_arm",
        "q",
        "v",
        "xi",
        "xi_dot",
        "sf",
        "cf",
        "st",
        "ct",
        "xi_floats",
        "xi_dot_floats",
        "rotation_floats",
        "u_applied_floats",
        "_v",
        "_qv",
    )

    def __init__(self, n_arm: int) -> None:
        if not (isinstance(n_arm, (int, np.integer)) and n_arm >= 0):
            raise InputError(f"n_arm must be an integer >= 0 (the platform's platform.n_arm), got {n_arm!r}")
        n = 6 + int(n_arm)
        self.n_arm = int(n_arm)
        self.t = 0.0
        self.q = np.zeros(n + 1)
        self.q[6] = 1.0
        self.v = np.zeros(n)
        self.xi = np.zeros(n)
        self.xi_dot = np.zeros(n)
        self.u_applied_floats = (0.0,) * n
        self.rotation_floats = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
        self._v = (0.0,) * n
        self.xi_floats = (0.0,) * n
        self.xi_dot_floats = (0.0,) * n
        self._qv = None
        self.sf, self.cf, self.st, self.ct = 0.0, 1.0, 0.0, 1.0

    @property
    def R(self) -> np.ndarray:
        """Body-to-world rotation R_b (3, 3) (a new array)."""
        return np.array(self.rotation_floats).reshape(3, 3)

    @property
    def u_applied(self) -> np.ndarray:
        """Generalised force applied during the previous step, thesis coordinates (a new array)."""
        return np.array(self.u_applied_floats)

    @u_applied.setter
    def u_applied(self, value) -> None:
        self.u_applied_floats = tuple(as_vector(value, 6 + self.n_arm, "u_applied").tolist())

    def set_applied(self, tau: np.ndarray) -> None:
        """Store u_applied = S^T tau for the Pinocchio generalised force ``tau`` the actuators applied."""
        self.u_applied_floats = tuple(self.force_to_xi_list(tau))

    @property
    def arm(self) -> list[float]:
        """Arm joint positions q_arm (a new list of floats)."""
        return list(self.xi_floats[6:])

    # ------------------------------------------------------------------ filling the state
    def update(self, t: float, q: np.ndarray, v: np.ndarray, v_bound: float | None = None) -> bool:
        """Fill every field from Pinocchio's (q, v) (float64 arrays, kept by reference as ``q`` and ``v``).

        Returns True; or False, with only ``t``, ``q`` and ``v`` set, when the norm of v is NaN or not
        below ``v_bound`` (the simulator's per-tick velocity screen).  Raises DivergenceError at the
        Euler singularity (theta = +-pi/2) or on a NaN attitude.
        """
        self.t = t
        self.q = q
        self.v = v
        ql = q.tolist()
        self._v = vl = v.tolist()
        if v_bound is not None and not hypot(*vl) < v_bound:
            return False
        x, y, z, qx, qy, qz, qw = ql[:7]
        vx, vy, vz, wx_, wy_, wz_ = vl[:6]
        # R_b of the unit quaternion (x, y, z, w)
        xx, yy, zz = qx * qx, qy * qy, qz * qz
        xy, xz, yz, wx, wy, wz = qx * qy, qx * qz, qy * qz, qw * qx, qw * qy, qw * qz
        r00, r01, r02 = 1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)
        r10, r11, r12 = 2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)
        r20, r21, r22 = 2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)
        self.rotation_floats = (r00, r01, r02, r10, r11, r12, r20, r21, r22)
        ch = hypot(r21, r22)
        if not ch > 1e-6:  # also catches NaN
            raise DivergenceError(f"t = {t:.4f} s: pitch theta reached +-pi/2 (ZYX Euler singularity) or the attitude is NaN; q = {q.tolist()}")
        # sin/cos of phi and theta straight from R: R[2,1] = c_theta s_phi, R[2,2] = c_theta c_phi
        self.sf = sf = r21 / ch
        self.cf = cf = r22 / ch
        self.st = st = -r20
        self.ct = ch
        self.xi_floats = xi = (x, y, z, atan2(r21, r22), atan2(-r20, ch), atan2(r10, r00), *ql[7:])
        self.xi[...] = xi
        # world velocity p_dot = R v_lin; Euler rates = T^-1 omega_body (Thesis (3.25) inverted)
        psi_d = (sf * wy_ + cf * wz_) / ch
        self.xi_dot_floats = xd = (
            r00 * vx + r01 * vy + r02 * vz,
            r10 * vx + r11 * vy + r12 * vz,
            r20 * vx + r21 * vy + r22 * vz,
            wx_ + st * psi_d,
            cf * wy_ - sf * wz_,
            psi_d,
            *vl[6:],
        )
        self.xi_dot[...] = xd
        return True

    def set_from_xi(self, t: float, xi, xi_dot, arrays: bool = True, reuse: bool = False) -> None:
        """Fill every field from thesis coordinates given as sequences of Python floats (lists or tuples).

        The form of :meth:`update_xi` for controllers that evaluate a model at another state on plain
        floats (desired state, locked arm): no conversion, no check.  ``arrays=False`` skips writing
        the ``xi`` / ``xi_dot`` arrays (q, v, the maps and the float views are set); ``reuse=True``
        writes q and v into two arrays this State owns and overwrites at each such call (no
        allocation; a caller that keeps ``q`` or ``v`` must copy them).
        """
        x, y, z, phi, theta, psi = xi[:6]
        c1, s1 = cos(0.5 * phi), sin(0.5 * phi)
        c2, s2 = cos(0.5 * theta), sin(0.5 * theta)
        c3, s3 = cos(0.5 * psi), sin(0.5 * psi)
        # sin/cos of the full angles from the half angles
        sf, cf = 2.0 * s1 * c1, c1 * c1 - s1 * s1
        st, ct = 2.0 * s2 * c2, c2 * c2 - s2 * s2
        sp, cp = 2.0 * s3 * c3, c3 * c3 - s3 * s3
        r = r00, r01, r02, r10, r11, r12, r20, r21, r22 = _rotation_entries(sf, cf, st, ct, sp, cp)
        px, py, pz, pd, td, sd = xi_dot[:6]
        # v = S xi_dot: v_lin = R^T p_dot, omega = T euler_dot
        v = (
            r00 * px + r10 * py + r20 * pz,
            r01 * px + r11 * py + r21 * pz,
            r02 * px + r12 * py + r22 * pz,
            pd - st * sd,
            cf * td + r21 * sd,
            -sf * td + r22 * sd,
            *xi_dot[6:],
        )
        # quaternion of Rz(psi) Ry(theta) Rx(phi), (x, y, z, w)
        qt = (x, y, z, s1 * c2 * c3 - c1 * s2 * s3, c1 * s2 * c3 + s1 * c2 * s3, c1 * c2 * s3 - s1 * s2 * c3, c1 * c2 * c3 + s1 * s2 * s3, *xi[6:])
        self.t = t
        if reuse:
            if self._qv is None:
                self._qv = (np.zeros(len(qt)), np.zeros(len(v)))
            self.q, self.v = self._qv
            self.q[...] = qt
            self.v[...] = v
        else:
            self.q = np.array(qt)
            self.v = np.array(v)
        self.rotation_floats = r
        self._v = v
        self.xi_dot_floats = xd = tuple(xi_dot)
        self.sf, self.cf, self.st, self.ct = sf, cf, st, ct
        self.xi_floats = xi_t = (x, y, z, phi, theta, psi, *xi[6:])
        if arrays:
            self.xi = np.array(xi_t)
            self.xi_dot = np.array(xd)

    def update_xi(self, t: float, xi, xi_dot, arrays: bool = True, reuse: bool = False) -> None:
        """Fill the state from thesis coordinates (used to evaluate a model at a desired state).

        ``xi``, ``xi_dot``: arrays or sequences (6 + n,).  ``arrays`` and ``reuse``: as for :meth:`set_from_xi`.
        """
        self.set_from_xi(
            t,
            xi.tolist() if isinstance(xi, np.ndarray) else tuple(xi),
            xi_dot.tolist() if isinstance(xi_dot, np.ndarray) else tuple(xi_dot),
            arrays,
            reuse,
        )

    # ------------------------------------------------------------------ maps at the current state
    def accel_to_v_list(self, xi_ddot) -> list[float]:
        """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot as a list of floats (``xi_ddot``: a sequence of floats)."""
        ax, ay, az, pdd, tdd, sdd = xi_ddot[:6]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self.rotation_floats
        vx, vy, vz, wx, wy, wz = self._v[:6]
        pd, td, sd = self.xi_dot_floats[3:6]
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        # a_lin = R^T p_ddot - omega x v_lin  (v_lin = R^T p_dot);  a_ang = T euler_ddot + T_dot euler_dot
        return [
            r00 * ax + r10 * ay + r20 * az - (wy * vz - wz * vy),
            r01 * ax + r11 * ay + r21 * az - (wz * vx - wx * vz),
            r02 * ax + r12 * ay + r22 * az - (wx * vy - wy * vx),
            pdd - st * sdd - ct * td * sd,
            cf * tdd + sf * ct * sdd - sf * pd * td + (cf * ct * pd - sf * st * td) * sd,
            -sf * tdd + cf * ct * sdd - cf * pd * td + (-sf * ct * pd - cf * st * td) * sd,
            *xi_ddot[6:],
        ]

    def accel_to_v(self, xi_ddot) -> np.ndarray:
        """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot (cf. :func:`xi_ddot_to_a`)."""
        return np.array(self.accel_to_v_list(xi_ddot.tolist() if isinstance(xi_ddot, np.ndarray) else xi_ddot))

    def force_to_xi_list(self, tau) -> list[float]:
        """Thesis generalised force u = S^T tau (Thesis (5.40)-(5.43) with R_Q = S^T) as a list of floats."""
        tau = tau.tolist() if isinstance(tau, np.ndarray) else tau
        f0, f1, f2, m0, m1, m2 = tau[:6]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self.rotation_floats
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        return [
            r00 * f0 + r01 * f1 + r02 * f2,
            r10 * f0 + r11 * f1 + r12 * f2,
            r20 * f0 + r21 * f1 + r22 * f2,
            m0,
            cf * m1 - sf * m2,
            -st * m0 + sf * ct * m1 + cf * ct * m2,
            *tau[6:],
        ]

    def force_to_xi(self, tau) -> np.ndarray:
        """Thesis generalised force u = S^T tau (Thesis (5.40)-(5.43) with R_Q = S^T)."""
        return np.array(self.force_to_xi_list(tau))

    def force_from_xi(self, u, out: np.ndarray | None = None) -> np.ndarray:
        """Pinocchio generalised force tau = S^-T u (into ``out``, a float64 array, if given)."""
        u = u.tolist() if isinstance(u, np.ndarray) else u
        u0, u1, u2, m0, m1, m2 = u[:6]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self.rotation_floats
        sf, cf = self.sf, self.cf
        w = (m2 + self.st * m0) / self.ct
        tau = (
            r00 * u0 + r10 * u1 + r20 * u2,
            r01 * u0 + r11 * u1 + r21 * u2,
            r02 * u0 + r12 * u1 + r22 * u2,
            m0,
            cf * m1 + sf * w,
            -sf * m1 + cf * w,
            *u[6:],
        )
        if out is None:
            return np.array(tau)
        out[...] = tau
        return out

    def lin_to_world(self, f_body) -> tuple[float, float, float]:
        """R f for a body-frame 3-vector (plain floats)."""
        f0, f1, f2 = f_body
        r = self.rotation_floats
        return (r[0] * f0 + r[1] * f1 + r[2] * f2, r[3] * f0 + r[4] * f1 + r[5] * f2, r[6] * f0 + r[7] * f1 + r[8] * f2)

    def lin_to_body(self, f_world) -> tuple[float, float, float]:
        """R^T f for a world-frame 3-vector (plain floats)."""
        f0, f1, f2 = f_world
        r = self.rotation_floats
        return (r[0] * f0 + r[3] * f1 + r[6] * f2, r[1] * f0 + r[4] * f1 + r[7] * f2, r[2] * f0 + r[5] * f1 + r[8] * f2)

    def euler_accel_to_omega_dot(self, a0: float, a1: float, a2: float) -> tuple[float, float, float]:
        """T(phi, theta) [a0, a1, a2]: change of omega_dot (body) for a change of Euler accelerations."""
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        return (a0 - st * a2, cf * a1 + sf * ct * a2, -sf * a1 + cf * ct * a2)
