"""The one conversion between the thesis coordinates and Pinocchio's.

Thesis: xi = [x, y, z, phi, theta, psi, r0, theta2, theta3] with p_world = [x, y, z] and
ZYX Euler angles R = Rz(psi) Ry(theta) Rx(phi) (Thesis (3.4)); rates xi_dot.

Pinocchio (free-flyer root): q = [p_world, quat_xyzw, r0, theta2, theta3] (nq = 10) and
v = [v_body, omega_body, r0_dot, theta2_dot, theta3_dot] (nv = 9), both velocities in B.

The rate map is v = S(xi) xi_dot with S = blockdiag(R^T, T(phi_b), I3), where
omega_body = T(phi_b) [phi_dot, theta_dot, psi_dot] (Thesis (3.25)-(3.26)).  S is also
the tangent map of xi -> q, so generalised forces transform as u_xi = S^T tau.
T is singular at theta = +-pi/2 (cos theta = 0): functions that need T^-1 raise
:class:`EulerSingularityError` when |cos theta| < ``EULER_TOL``.
"""

from __future__ import annotations

import struct
from math import atan2, cos, hypot, sin

import numpy as np
import pinocchio as pin

from .errors import DivergenceError, EulerSingularityError, NonFiniteError, ShapeError

EULER_TOL = 1e-6
"""|cos(theta)| below which ZYX Euler angles are treated as singular."""


def as_vector(x, n: int, name: str) -> np.ndarray:
    """``x`` as a finite float vector of length ``n``; raise naming ``name`` otherwise."""
    a = np.asarray(x, dtype=float)
    if a.shape != (n,):
        raise ShapeError(f"{name} must have shape ({n},), got shape {a.shape}")
    if not np.isfinite(a.sum()):  # a sum is finite iff every entry is (and far cheaper than isfinite().all())
        if not np.all(np.isfinite(a)):
            raise NonFiniteError(f"{name} must be finite, got {a.tolist()}")
    return a


_EX, _EY, _EZ = (pin.skew(np.eye(3)[i]) for i in range(3))


def rot_x(a: float) -> np.ndarray:
    c, s = cos(a), sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = cos(a), sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = cos(a), sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation(phi: float, theta: float, psi: float) -> np.ndarray:
    sf, cf, st, ct, sp, cp = sin(phi), cos(phi), sin(theta), cos(theta), sin(psi), cos(psi)
    return np.array([
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ])


def euler_to_rotation(euler_zyx) -> np.ndarray:
    """R_b = Rz(psi) Ry(theta) Rx(phi) for ``euler_zyx = [phi, theta, psi]``, expanded as Thesis (3.4)."""
    phi, theta, psi = as_vector(euler_zyx, 3, "euler_zyx").tolist()
    return _rotation(phi, theta, psi)


def _check_pitch(theta: float, what: str) -> None:
    if abs(cos(theta)) < EULER_TOL:
        raise EulerSingularityError(
            f"{what}: ZYX Euler angles are singular at pitch theta = {theta!r} rad "
            f"(|cos theta| < {EULER_TOL:g}); roll and yaw rates are not defined there"
        )


def rotation_to_euler(R) -> np.ndarray:
    """[phi, theta, psi] of a rotation matrix, theta in (-pi/2, pi/2) (Thesis (3.8), corrected).

    Raises :class:`EulerSingularityError` at theta = +-pi/2 where roll and yaw are not unique.
    The printed (3.8) swaps the roll and yaw formulas: see docs/thesis-errata.md.
    """
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3):
        raise ShapeError(f"R must have shape (3, 3), got {R.shape}")
    if not np.all(np.isfinite(R)):
        raise NonFiniteError("R must be finite")
    theta = atan2(-R[2, 0], hypot(R[2, 1], R[2, 2]))
    _check_pitch(theta, "rotation_to_euler")
    phi = atan2(R[2, 1], R[2, 2])
    psi = atan2(R[1, 0], R[0, 0])
    return np.array([phi, theta, psi])


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
    """S(xi) = blockdiag(R^T, T, I3) (9x9): v = S xi_dot, u_xi = S^T tau."""
    phi, theta, psi = as_vector(xi, 9, "xi")[3:6].tolist()
    S = np.eye(9)
    S[0:3, 0:3] = _rotation(phi, theta, psi).T
    S[3:6, 3:6] = _rate_matrix(phi, theta)
    return S


def rate_map_derivatives(xi) -> np.ndarray:
    """dS/dxi_k for k = phi, theta, psi as an array of shape (3, 9, 9) (S depends on nothing else)."""
    phi, theta, psi = as_vector(xi, 9, "xi")[3:6].tolist()
    Rx, Ry, Rz = rot_x(phi), rot_y(theta), rot_z(psi)
    dR = (Rz @ Ry @ Rx @ _EX, Rz @ Ry @ _EY @ Rx, Rz @ _EZ @ Ry @ Rx)
    sf, cf, st, ct = sin(phi), cos(phi), sin(theta), cos(theta)
    dT = (
        np.array([[0.0, 0.0, 0.0], [0.0, -sf, cf * ct], [0.0, -cf, -sf * ct]]),
        np.array([[0.0, 0.0, -ct], [0.0, 0.0, -sf * st], [0.0, 0.0, -cf * st]]),
        np.zeros((3, 3)),
    )
    out = np.zeros((3, 9, 9))
    for k in range(3):
        out[k, 0:3, 0:3] = dR[k].T
        out[k, 3:6, 3:6] = dT[k]
    return out


def xi_to_q(xi) -> np.ndarray:
    """Pinocchio configuration q (nq = 10) of thesis coordinates xi."""
    xi = as_vector(xi, 9, "xi")
    hf, ht, hp = 0.5 * xi[3], 0.5 * xi[4], 0.5 * xi[5]
    cf, sf, ct, st, cp, sp = cos(hf), sin(hf), cos(ht), sin(ht), cos(hp), sin(hp)
    q = np.empty(10)
    q[0:3] = xi[0:3]
    # quaternion of Rz(psi) Ry(theta) Rx(phi), (x, y, z, w) order as in Pinocchio
    q[3] = sf * ct * cp - cf * st * sp
    q[4] = cf * st * cp + sf * ct * sp
    q[5] = cf * ct * sp - sf * st * cp
    q[6] = cf * ct * cp + sf * st * sp
    q[7:10] = xi[6:9]
    return q


def q_to_xi(q) -> np.ndarray:
    """Thesis coordinates of a Pinocchio configuration (raises at the Euler singularity)."""
    q = as_vector(q, 10, "q")
    norm = np.linalg.norm(q[3:7])
    if not abs(norm - 1.0) < 1e-6:
        raise ShapeError(f"q[3:7] must be a unit quaternion (x, y, z, w), got norm {norm!r}")
    R = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
    return np.concatenate([q[0:3], rotation_to_euler(R), q[7:10]])


def xi_dot_to_v(xi, xi_dot) -> np.ndarray:
    """Pinocchio velocity v = S(xi) xi_dot (body-frame linear and angular velocity)."""
    return rate_map(xi) @ as_vector(xi_dot, 9, "xi_dot")


def v_to_xi_dot(xi, v) -> np.ndarray:
    """Thesis rates xi_dot = S(xi)^-1 v (raises at the Euler singularity)."""
    xi = as_vector(xi, 9, "xi")
    v = as_vector(v, 9, "v")
    _check_pitch(xi[4], "v_to_xi_dot")
    S = rate_map(xi)
    out = np.empty(9)
    out[0:3] = S[0:3, 0:3].T @ v[0:3]
    out[3:6] = np.linalg.solve(S[3:6, 3:6], v[3:6])
    out[6:9] = v[6:9]
    return out


def xi_to_qv(xi, xi_dot) -> tuple[np.ndarray, np.ndarray]:
    """(q, v) of thesis coordinates and rates."""
    return xi_to_q(xi), xi_dot_to_v(xi, xi_dot)


def qv_to_xi(q, v) -> tuple[np.ndarray, np.ndarray]:
    """(xi, xi_dot) of a Pinocchio state (raises at the Euler singularity)."""
    xi = q_to_xi(q)
    return xi, v_to_xi_dot(xi, v)


def rate_map_dot(xi, xi_dot) -> np.ndarray:
    """dS/dt along xi_dot."""
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    dS = rate_map_derivatives(xi)
    return np.tensordot(xi_dot[3:6], dS, axes=1)


def xi_ddot_to_a(xi, xi_dot, xi_ddot) -> np.ndarray:
    """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot."""
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    return rate_map(xi) @ as_vector(xi_ddot, 9, "xi_ddot") + rate_map_dot(xi, xi_dot) @ xi_dot


def a_to_xi_ddot(xi, xi_dot, a) -> np.ndarray:
    """Thesis accelerations xi_ddot = S^-1 (a - S_dot xi_dot) (raises at the Euler singularity)."""
    xi = as_vector(xi, 9, "xi")
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    _check_pitch(xi[4], "a_to_xi_ddot")
    rhs = as_vector(a, 9, "a") - rate_map_dot(xi, xi_dot) @ xi_dot
    return np.linalg.solve(rate_map(xi), rhs)


# ------------------------------------------------------------------ the hot-loop form
_PACKERS = {n: struct.Struct(f"={n}d").pack_into for n in (3, 7, 9, 10)}
_F8 = np.dtype(np.float64)


def write_floats(arr: np.ndarray, values) -> np.ndarray:
    """``arr[:] = values`` for a float64 vector, straight into its buffer when it can (half the cost).

    ``values`` is a sequence of Python floats of ``len(arr)``; any other array (not float64,
    not C-contiguous, other length) takes the plain numpy assignment.
    """
    pack = _PACKERS.get(len(values))
    if pack is not None and arr.dtype is _F8:
        try:
            pack(arr, 0, *values)
            return arr
        except (TypeError, struct.error):  # not C-contiguous, or too small
            pass
    arr[:] = values
    return arr


class State:
    # The functions above on plain floats, for loops that run every millisecond (simulator,
    # controllers): one xi <-> (q, v) update caches R_b and the trigonometry that S, S_dot
    # and S^-T need, so each map below is a few multiplications.  The plain-float copies
    # ``_xi``, ``_xd``, ``_v`` (and ``_ua``) let controllers skip array round trips.
    """Measured state at one step (updated in place by :meth:`update`; no allocation per step).

    Attributes: ``q`` (10,), ``v`` (9,) Pinocchio; ``xi`` (9,), ``xi_dot`` (9,) thesis;
    ``R`` (3, 3) body-to-world rotation (property); trigonometric values of phi and theta;
    ``u_applied`` (9,): the generalised force the actuators applied during the previous step
    (thesis coordinates, u = R_Q N f, disturbances excluded) - the "measured input" of the
    model-free controller; filled only for controllers with ``uses_applied_force = True``
    (stored as floats by :meth:`set_applied`; reading the property builds the array).
    """

    __slots__ = ("t", "q", "v", "xi", "xi_dot", "_ua", "_r", "_v", "_xi", "_xd", "_qv", "sf", "cf", "st", "ct")

    def __init__(self) -> None:
        self.t = 0.0
        self.q = np.zeros(10)
        self.q[6] = 1.0
        self.v = np.zeros(9)
        self.xi = np.zeros(9)
        self.xi_dot = np.zeros(9)
        self._ua = [0.0] * 9
        self._r = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
        self._v = [0.0] * 9
        self._xi = (0.0,) * 9
        self._xd = [0.0] * 9
        self._qv = None
        self.sf, self.cf, self.st, self.ct = 0.0, 1.0, 0.0, 1.0

    @property
    def R(self) -> np.ndarray:
        """Body-to-world rotation R_b (3, 3) (a new array)."""
        return np.array(self._r).reshape(3, 3)

    @property
    def u_applied(self) -> np.ndarray:
        """Generalised force applied during the previous step, thesis coordinates (9,) (a new array)."""
        return np.array(self._ua)

    @u_applied.setter
    def u_applied(self, value) -> None:
        self._ua = as_vector(value, 9, "u_applied").tolist()

    def set_applied(self, tau: np.ndarray) -> None:
        """Store u_applied = S^T tau for the Pinocchio generalised force ``tau`` the actuators applied."""
        self._ua = self.force_to_xi_list(tau)

    def update_xi(self, t: float, xi, xi_dot, arrays: bool = True, reuse: bool = False) -> None:
        """Fill the state from thesis coordinates (used to evaluate a model at a desired state).

        ``arrays=False`` skips writing the ``xi`` / ``xi_dot`` arrays (q, v and the maps are set).
        ``reuse=True`` writes q and v into two arrays this State owns and overwrites at each
        such call (no allocation; a caller that keeps ``q`` or ``v`` must copy them).
        """
        self._from_xi(t, xi.tolist() if isinstance(xi, np.ndarray) else xi,
                      xi_dot.tolist() if isinstance(xi_dot, np.ndarray) else list(xi_dot), arrays, reuse)

    def _from_xi(self, t: float, xi, xd: list, arrays: bool, reuse: bool) -> None:
        """:meth:`update_xi` for ``xi`` a sequence and ``xd`` a list of floats (kept as ``_xd``)."""
        x, y, z, phi, theta, psi, r0, t2, t3 = xi
        c1, s1 = cos(0.5 * phi), sin(0.5 * phi)
        c2, s2 = cos(0.5 * theta), sin(0.5 * theta)
        c3, s3 = cos(0.5 * psi), sin(0.5 * psi)
        # sin/cos of the full angles from the half angles
        sf, cf = 2.0 * s1 * c1, c1 * c1 - s1 * s1
        st, ct = 2.0 * s2 * c2, c2 * c2 - s2 * s2
        sp, cp = 2.0 * s3 * c3, c3 * c3 - s3 * s3
        r00, r01, r02 = cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf
        r10, r11, r12 = sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf
        r20, r21, r22 = -st, ct * sf, ct * cf
        px, py, pz, pd, td, sd, q1, q2, q3 = xd
        # v = S xi_dot: v_lin = R^T p_dot, omega = T euler_dot
        v = [r00 * px + r10 * py + r20 * pz, r01 * px + r11 * py + r21 * pz, r02 * px + r12 * py + r22 * pz,
             pd - st * sd, cf * td + r21 * sd, -sf * td + r22 * sd, q1, q2, q3]
        self.t = t
        # quaternion of Rz(psi) Ry(theta) Rx(phi), (x, y, z, w)
        qt = (x, y, z, s1 * c2 * c3 - c1 * s2 * s3, c1 * s2 * c3 + s1 * c2 * s3,
              c1 * c2 * s3 - s1 * s2 * c3, c1 * c2 * c3 + s1 * s2 * s3, r0, t2, t3)
        if reuse:
            if self._qv is None:
                self._qv = (np.zeros(10), np.zeros(9))
            self.q, self.v = qv = self._qv
            write_floats(qv[0], qt)
            write_floats(qv[1], v)
        else:
            self.q = np.array(qt)
            self.v = np.array(v)
        self._r = (r00, r01, r02, r10, r11, r12, r20, r21, r22)
        self._v = v
        self._xd = xd
        self.sf, self.cf, self.st, self.ct = sf, cf, st, ct
        xi_t = (x, y, z, phi, theta, psi, r0, t2, t3)
        self._xi = xi_t
        if arrays:
            self.xi = np.array(xi_t)
            self.xi_dot = np.array(xd)

    def update(self, t: float, q: np.ndarray, v: np.ndarray) -> None:
        """Fill every field from (q, v); raise DivergenceError at the Euler singularity or on NaN."""
        self.t = t
        self.q = q
        self.v = v
        x, y, z, qx, qy, qz, qw, r0, t2, t3 = q.tolist()
        self._v = vl = v.tolist()
        vx, vy, vz, wx_, wy_, wz_, q1, q2, q3 = vl
        xx, yy, zz = qx * qx, qy * qy, qz * qz
        xy, xz, yz, wx, wy, wz = qx * qy, qx * qz, qy * qz, qw * qx, qw * qy, qw * qz
        r00, r01, r02 = 1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)
        r10, r11, r12 = 2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)
        r20, r21, r22 = 2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)
        self._r = (r00, r01, r02, r10, r11, r12, r20, r21, r22)
        ch = hypot(r21, r22)
        if not ch > 1e-6:  # also catches NaN
            raise DivergenceError(f"t = {t:.4f} s: pitch theta reached +-pi/2 (ZYX Euler singularity) or the attitude is NaN; q = {q.tolist()}")
        # sin/cos of phi and theta straight from R: R[2,1] = c_theta s_phi, R[2,2] = c_theta c_phi
        self.sf = sf = r21 / ch
        self.cf = cf = r22 / ch
        self.st = st = -r20
        self.ct = ch
        self._xi = xi = (x, y, z, atan2(r21, r22), atan2(-r20, ch), atan2(r10, r00), r0, t2, t3)
        write_floats(self.xi, xi)
        # world velocity p_dot = R v_lin; Euler rates = T^-1 omega_body (Thesis (3.25) inverted)
        psi_d = (sf * wy_ + cf * wz_) / ch
        self._xd = xd = [r00 * vx + r01 * vy + r02 * vz, r10 * vx + r11 * vy + r12 * vz, r20 * vx + r21 * vy + r22 * vz,
                         wx_ + st * psi_d, cf * wy_ - sf * wz_, psi_d, q1, q2, q3]
        write_floats(self.xi_dot, xd)

    # --------------------------------------------------------------- coordinate maps
    def accel_to_v_list(self, xi_ddot) -> list[float]:
        """:meth:`accel_to_v` as a list of floats (``xi_ddot``: a sequence of 9 floats)."""
        ax, ay, az, pdd, tdd, sdd, q1, q2, q3 = xi_ddot
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self._r
        vx, vy, vz, wx, wy, wz, _, _, _ = self._v
        _, _, _, pd, td, sd, _, _, _ = self._xd
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        # a_lin = R^T p_ddot - omega x v_lin  (v_lin = R^T p_dot);  a_ang = T euler_ddot + T_dot euler_dot
        return [r00 * ax + r10 * ay + r20 * az - (wy * vz - wz * vy),
                r01 * ax + r11 * ay + r21 * az - (wz * vx - wx * vz),
                r02 * ax + r12 * ay + r22 * az - (wx * vy - wy * vx),
                pdd - st * sdd - ct * td * sd,
                cf * tdd + sf * ct * sdd - sf * pd * td + (cf * ct * pd - sf * st * td) * sd,
                -sf * tdd + cf * ct * sdd - cf * pd * td + (-sf * ct * pd - cf * st * td) * sd,
                q1, q2, q3]

    def accel_to_v(self, xi_ddot) -> np.ndarray:
        """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot (cf. :func:`qprr.coordinates.xi_ddot_to_a`)."""
        return np.array(self.accel_to_v_list(xi_ddot.tolist() if isinstance(xi_ddot, np.ndarray) else xi_ddot))

    def lin_to_world(self, f_body) -> tuple[float, float, float]:
        """R f for a body-frame 3-vector (plain floats)."""
        f0, f1, f2 = f_body
        r = self._r
        return (r[0] * f0 + r[1] * f1 + r[2] * f2, r[3] * f0 + r[4] * f1 + r[5] * f2, r[6] * f0 + r[7] * f1 + r[8] * f2)

    def euler_accel_to_omega_dot(self, a0: float, a1: float, a2: float) -> tuple[float, float, float]:
        """T(phi, theta) [a0, a1, a2]: change of omega_dot (body) for a change of Euler accelerations."""
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        return (a0 - st * a2, cf * a1 + sf * ct * a2, -sf * a1 + cf * ct * a2)

    def force_to_xi_list(self, tau) -> list[float]:
        """:meth:`force_to_xi` as a list of floats."""
        f0, f1, f2, m0, m1, m2, a, b, c = tau.tolist() if isinstance(tau, np.ndarray) else tau
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self._r
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        return [r00 * f0 + r01 * f1 + r02 * f2,
                r10 * f0 + r11 * f1 + r12 * f2,
                r20 * f0 + r21 * f1 + r22 * f2,
                m0,
                cf * m1 - sf * m2,
                -st * m0 + sf * ct * m1 + cf * ct * m2,
                a, b, c]

    def force_to_xi(self, tau) -> np.ndarray:
        """Thesis generalised force u = S^T tau (Thesis (5.40)-(5.43) with R_Q = S^T)."""
        return np.array(self.force_to_xi_list(tau))

    def force_from_xi(self, u, out: np.ndarray | None = None) -> np.ndarray:
        """Pinocchio generalised force tau = S^-T u (inverse of :meth:`force_to_xi`).

        ``out``: a C-contiguous float64 (9,) array to write tau into (returned), else a new array.
        """
        u0, u1, u2, m0, m1, m2, a, b, c = u.tolist() if isinstance(u, np.ndarray) else u
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self._r
        sf, cf = self.sf, self.cf
        w = (m2 + self.st * m0) / self.ct
        tau = (r00 * u0 + r10 * u1 + r20 * u2,
               r01 * u0 + r11 * u1 + r21 * u2,
               r02 * u0 + r12 * u1 + r22 * u2,
               m0,
               cf * m1 + sf * w,
               -sf * m1 + cf * w,
               a, b, c)
        return np.array(tau) if out is None else write_floats(out, tau)
