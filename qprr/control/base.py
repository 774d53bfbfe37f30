"""What every controller shares: the state it reads, the reference it tracks, the step contract.

A controller is an object with one method, :meth:`Controller.step`, called once per control
period by the simulator:

    u = controller.step(t, state, ref)

* ``state`` (:class:`State`) holds the measured Pinocchio state (q, v), the thesis
  coordinates (xi, xi_dot) and the rotation/trigonometric values the maps below need;
* ``ref`` (:class:`Reference`) holds xi_d, xi_dot_d, xi_ddot_d from the trajectory.  Roll
  and pitch are not given by the trajectory: a controller that derives references itself
  (roll/pitch from (6.17), the BSG's r0 and theta3) writes them into ``ref`` so the log
  records what was actually tracked;
* ``u`` (9,) is the desired generalised force in thesis coordinates
  u = [u_fb (world force, N), u_tau (Euler-angle torques, N m), u_mu (arm efforts)]
  (Thesis (5.40)).  The simulator maps it to Pinocchio's tau = S^-T u and allocates it
  to the rotors (:mod:`qprr.allocation`).

Adding a controller means writing a subclass; the simulator does not change.

The maps between thesis and Pinocchio coordinates (S of :mod:`qprr.coordinates`) are
re-implemented here in closed form on plain floats because they run at every step;
``tests/test_control.py`` checks them against :mod:`qprr.coordinates`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from ..errors import DivergenceError


class State:
    """Measured state at one step (updated in place by :meth:`update`; no allocation per step).

    Attributes: ``q`` (10,), ``v`` (9,) Pinocchio; ``xi`` (9,), ``xi_dot`` (9,) thesis;
    ``R`` (3, 3) body-to-world rotation (property); trigonometric values of phi and theta;
    ``u_applied`` (9,): the generalised force the actuators applied during the previous step
    (thesis coordinates, u = R_Q N f, disturbances excluded) - the "measured input" of the
    model-free controller; filled only for controllers with ``uses_applied_force = True``.
    """

    __slots__ = ("t", "q", "v", "xi", "xi_dot", "u_applied", "_r", "_v", "_xd", "sf", "cf", "st", "ct")

    def __init__(self) -> None:
        self.t = 0.0
        self.q = np.zeros(10)
        self.q[6] = 1.0
        self.v = np.zeros(9)
        self.xi = np.zeros(9)
        self.xi_dot = np.zeros(9)
        self.u_applied = np.zeros(9)
        self._r = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
        self._v = [0.0] * 9
        self._xd = [0.0] * 9
        self.sf, self.cf, self.st, self.ct = 0.0, 1.0, 0.0, 1.0

    @property
    def R(self) -> np.ndarray:
        """Body-to-world rotation R_b (3, 3) (a new array)."""
        return np.array(self._r).reshape(3, 3)

    def update_xi(self, t: float, xi, xi_dot, arrays: bool = True) -> None:
        """Fill the state from thesis coordinates (used to evaluate a model at a desired state).

        ``arrays=False`` skips writing the ``xi`` / ``xi_dot`` arrays (q, v and the maps are set).
        """
        x, y, z, phi, theta, psi, r0, t2, t3 = xi.tolist() if isinstance(xi, np.ndarray) else xi
        xd = xi_dot.tolist() if isinstance(xi_dot, np.ndarray) else list(xi_dot)
        c1, s1 = math.cos(0.5 * phi), math.sin(0.5 * phi)
        c2, s2 = math.cos(0.5 * theta), math.sin(0.5 * theta)
        c3, s3 = math.cos(0.5 * psi), math.sin(0.5 * psi)
        # sin/cos of the full angles from the half angles
        sf, cf = 2.0 * s1 * c1, c1 * c1 - s1 * s1
        st, ct = 2.0 * s2 * c2, c2 * c2 - s2 * s2
        sp, cp = 2.0 * s3 * c3, c3 * c3 - s3 * s3
        r = (cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf,
             sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf,
             -st, ct * sf, ct * cf)
        px, py, pz, pd, td, sd = xd[0:6]
        # v = S xi_dot: v_lin = R^T p_dot, omega = T euler_dot
        v = [r[0] * px + r[3] * py + r[6] * pz, r[1] * px + r[4] * py + r[7] * pz, r[2] * px + r[5] * py + r[8] * pz,
             pd - st * sd, cf * td + sf * ct * sd, -sf * td + cf * ct * sd, xd[6], xd[7], xd[8]]
        self.t = t
        # quaternion of Rz(psi) Ry(theta) Rx(phi), (x, y, z, w)
        self.q = np.array((x, y, z, s1 * c2 * c3 - c1 * s2 * s3, c1 * s2 * c3 + s1 * c2 * s3,
                           c1 * c2 * s3 - s1 * s2 * c3, c1 * c2 * c3 + s1 * s2 * s3, r0, t2, t3))
        self.v = np.array(v)
        self._r = r
        self._v = v
        self._xd = xd
        self.sf, self.cf, self.st, self.ct = sf, cf, st, ct
        if arrays:
            self.xi = np.array((x, y, z, phi, theta, psi, r0, t2, t3))
            self.xi_dot = np.array(xd)

    def update(self, t: float, q: np.ndarray, v: np.ndarray) -> None:
        """Fill every field from (q, v); raise DivergenceError at the Euler singularity or on NaN."""
        self.t = t
        self.q = q
        self.v = v
        x, y, z, qx, qy, qz, qw, r0, t2, t3 = q.tolist()
        vl = v.tolist()
        xx, yy, zz = qx * qx, qy * qy, qz * qz
        xy, xz, yz, wx, wy, wz = qx * qy, qx * qz, qy * qz, qw * qx, qw * qy, qw * qz
        r = (1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy),
             2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx),
             2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy))
        self._r = r
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = r
        ch = math.hypot(r21, r22)
        if not ch > 1e-6:  # also catches NaN
            raise DivergenceError(f"t = {t:.4f} s: pitch theta reached +-pi/2 (ZYX Euler singularity) or the attitude is NaN; q = {q.tolist()}")
        theta = math.atan2(-r20, ch)
        phi = math.atan2(r21, r22)
        # sin/cos of phi and theta straight from R: R[2,1] = c_theta s_phi, R[2,2] = c_theta c_phi
        sf, cf, st, ct = r21 / ch, r22 / ch, -r20, ch
        self.sf, self.cf, self.st, self.ct = sf, cf, st, ct
        self.xi[:] = (x, y, z, phi, theta, math.atan2(r10, r00), r0, t2, t3)
        vx, vy, vz, wx_, wy_, wz_, q1, q2, q3 = vl
        # world velocity p_dot = R v_lin; Euler rates = T^-1 omega_body (Thesis (3.25) inverted)
        psi_d = (sf * wy_ + cf * wz_) / ct
        xd = [r00 * vx + r01 * vy + r02 * vz, r10 * vx + r11 * vy + r12 * vz, r20 * vx + r21 * vy + r22 * vz,
              wx_ + st * psi_d, cf * wy_ - sf * wz_, psi_d, q1, q2, q3]
        self._v = vl
        self._xd = xd
        self.xi_dot[:] = xd

    # --------------------------------------------------------------- coordinate maps
    def accel_to_v(self, xi_ddot) -> np.ndarray:
        """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot (cf. :func:`qprr.coordinates.xi_ddot_to_a`)."""
        ax, ay, az, pdd, tdd, sdd, q1, q2, q3 = xi_ddot.tolist() if isinstance(xi_ddot, np.ndarray) else xi_ddot
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self._r
        vx, vy, vz, wx, wy, wz = self._v[0:6]
        _, _, _, pd, td, sd = self._xd[0:6]
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        # a_lin = R^T p_ddot - omega x v_lin  (v_lin = R^T p_dot)
        bx = r00 * ax + r10 * ay + r20 * az - (wy * vz - wz * vy)
        by = r01 * ax + r11 * ay + r21 * az - (wz * vx - wx * vz)
        bz = r02 * ax + r12 * ay + r22 * az - (wx * vy - wy * vx)
        # a_ang = T euler_ddot + T_dot euler_dot
        a0 = pdd - st * sdd - ct * td * sd
        a1 = cf * tdd + sf * ct * sdd - sf * pd * td + (cf * ct * pd - sf * st * td) * sd
        a2 = -sf * tdd + cf * ct * sdd - cf * pd * td + (-sf * ct * pd - cf * st * td) * sd
        return np.array((bx, by, bz, a0, a1, a2, q1, q2, q3))

    def lin_to_world(self, f_body) -> tuple[float, float, float]:
        """R f for a body-frame 3-vector (plain floats)."""
        f0, f1, f2 = f_body
        r = self._r
        return (r[0] * f0 + r[1] * f1 + r[2] * f2, r[3] * f0 + r[4] * f1 + r[5] * f2, r[6] * f0 + r[7] * f1 + r[8] * f2)

    def euler_accel_to_omega_dot(self, a0: float, a1: float, a2: float) -> tuple[float, float, float]:
        """T(phi, theta) [a0, a1, a2]: change of omega_dot (body) for a change of Euler accelerations."""
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        return (a0 - st * a2, cf * a1 + sf * ct * a2, -sf * a1 + cf * ct * a2)

    def force_to_xi(self, tau) -> np.ndarray:
        """Thesis generalised force u = S^T tau (Thesis (5.40)-(5.43) with R_Q = S^T)."""
        f0, f1, f2, m0, m1, m2, a, b, c = tau.tolist() if isinstance(tau, np.ndarray) else tau
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self._r
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        return np.array((
            r00 * f0 + r01 * f1 + r02 * f2,
            r10 * f0 + r11 * f1 + r12 * f2,
            r20 * f0 + r21 * f1 + r22 * f2,
            m0,
            cf * m1 - sf * m2,
            -st * m0 + sf * ct * m1 + cf * ct * m2,
            a, b, c,
        ))

    def force_from_xi(self, u) -> np.ndarray:
        """Pinocchio generalised force tau = S^-T u (inverse of :meth:`force_to_xi`)."""
        u0, u1, u2, m0, m1, m2, a, b, c = u.tolist() if isinstance(u, np.ndarray) else u
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = self._r
        sf, cf, st, ct = self.sf, self.cf, self.st, self.ct
        w = (m2 + st * m0) / ct
        return np.array((
            r00 * u0 + r10 * u1 + r20 * u2,
            r01 * u0 + r11 * u1 + r21 * u2,
            r02 * u0 + r12 * u1 + r22 * u2,
            m0,
            cf * m1 + sf * w,
            -sf * m1 + cf * w,
            a, b, c,
        ))


class Reference:
    """Reference at one step: ``xi``, ``xi_dot``, ``xi_ddot`` (9,) each, thesis coordinates.

    The simulator points these at rows of its log (pre-filled from the trajectory);
    controllers overwrite the entries they generate (roll, pitch, BSG joints).
    """

    __slots__ = ("xi", "xi_dot", "xi_ddot")

    def __init__(self, xi=None, xi_dot=None, xi_ddot=None) -> None:
        self.xi = np.zeros(9) if xi is None else xi
        self.xi_dot = np.zeros(9) if xi_dot is None else xi_dot
        self.xi_ddot = np.zeros(9) if xi_ddot is None else xi_ddot


class Controller(ABC):
    """Base class: ``step(t, state, ref) -> u`` (see the module docstring)."""

    name: str = "controller"
    uses_applied_force: bool = False
    """Set True to have the simulator fill ``state.u_applied`` (costs ~2 us per step)."""
    output: str = "xi"
    """What :meth:`step` returns: "xi" (default), u in thesis coordinates; or "pinocchio",
    tau = S^-T u at the measured state (a controller that computes tau anyway saves two
    coordinate changes per step; the simulator still logs u)."""

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        """Called once before the run with the initial state and the control period ``dt`` [s]."""
        self.dt = dt

    @abstractmethod
    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """Desired generalised force (9,): u in thesis coordinates (or tau if ``output == "pinocchio"``)."""


class CommandFilter:
    """Second-order critically damped filter giving a reference with consistent derivatives.

    x_f'' = w^2 (x_raw - x_f) - 2 w x_f', stepped by semi-implicit Euler
    (a = w^2 (x_raw - x) - 2 w xd, xd += dt a, x += dt xd): (x, xd, a) are exactly consistent
    (a plant that integrates a the same way follows x step for step) and ``xdd`` is the
    acceleration actually used over the step.  The scheme is stable for w dt < 0.83: the
    bandwidth used is min(omega, 0.7 / dt).
    ``n`` channels; ``x``, ``xd``, ``xdd`` after :meth:`update`.
    """

    __slots__ = ("omega", "x", "xd", "xdd", "_init")

    def __init__(self, n: int, omega: float) -> None:
        self.omega = float(omega)
        self.x = [0.0] * n
        self.xd = [0.0] * n
        self.xdd = [0.0] * n
        self._init = False

    def reset(self, values) -> None:
        self.x = [float(v) for v in values]
        self.xd = [0.0] * len(self.x)
        self.xdd = [0.0] * len(self.x)
        self._init = True

    def update(self, raw, dt: float) -> None:
        if not self._init:
            self.reset(raw)
        w = min(self.omega, 0.7 / dt)
        w2, w2x = w * w, 2.0 * w
        x, xd, xdd = self.x, self.xd, self.xdd
        for i, r in enumerate(raw):
            acc = w2 * (r - x[i]) - w2x * xd[i]
            xdd[i] = acc
            xd[i] += dt * acc
            x[i] += dt * xd[i]


class TiltReference:
    """Roll/pitch references of Thesis (6.17) with the rates and accelerations (6.20) needs.

    (6.17): theta_r = atan((u_x c_psi + u_y s_psi) / u_z), phi_r = asin((u_x s_psi - u_y c_psi) / |u|).

    The reference is split into a feedforward part, (6.17) applied to the reference
    acceleration (u = p_ddot_d + g e3: it depends on the trajectory only), and the rest
    (feedback and coupling terms of u_fb).  Each goes through a critically damped
    second-order :class:`CommandFilter` that also gives its rates (Remark 4: numerical
    differentiation with noise-robust filters): the feedforward through a fast one
    (``omega_ff`` = 700 rad/s, lag 3 ms; no loop closes through it, and it smooths the steps
    of the tilt rate where a quintic phase starts with non-zero jerk), the rest through
    ``omega``.  Filtering the whole of (6.17) with one filter costs either a lag of ~2/omega
    on the nominal tilt or, with a fast filter, feeds the high-frequency content of u_fb
    (arm reactions, the sideways motion of B under pitch acceleration) back into the
    attitude loop, which diverges under disturbances; the split avoids both.

    When u_z < ``uz_min`` (Hypothesis 2 violated: the reference asks for more than free-fall
    deceleration) the last raw reference is held.  Angles are clamped to ``max_tilt``.
    """

    __slots__ = ("omega", "omega_ff", "max_tilt", "uz_min", "filter", "ff_filter", "x", "xd", "xdd", "_ff", "_ffd", "_n", "_raw")

    def __init__(self, omega: float, max_tilt: float, uz_min: float, omega_ff: float = 700.0) -> None:
        self.omega, self.max_tilt, self.uz_min = float(omega), float(max_tilt), float(uz_min)
        self.omega_ff = float(omega_ff)
        self.reset()

    def reset(self) -> None:
        self.filter = CommandFilter(2, self.omega)
        self.ff_filter = CommandFilter(2, self.omega_ff)
        self.x, self.xd, self.xdd = [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]
        self._ff = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
        self._ffd = [0.0, 0.0]
        self._n = 0
        self._raw = None

    def _tilt(self, ux: float, uy: float, uz: float, cp: float, sp: float) -> tuple[float, float]:
        lim = self.max_tilt
        norm = math.sqrt(ux * ux + uy * uy + uz * uz)
        theta = max(-lim, min(lim, math.atan((ux * cp + uy * sp) / uz)))
        phi = max(-lim, min(lim, math.asin((ux * sp - uy * cp) / norm)))
        return phi, theta

    def update(self, psi: float, u_fb, a_ref, g: float, dt: float) -> None:
        """Advance one step: ``u_fb`` (3,) world force asked for, ``a_ref`` (3,) reference acceleration [m/s^2]."""
        cp, sp = math.cos(psi), math.sin(psi)
        ax, ay, az = a_ref
        azg = az + g
        ff = self._tilt(ax, ay, azg, cp, sp) if azg > 0.05 * g else self._ff[0]
        ux, uy, uz = u_fb
        if uz > self.uz_min:
            raw = self._raw = self._tilt(ux, uy, uz, cp, sp)
        else:
            raw = self._raw if self._raw is not None else ff
        if self._n == 0:
            self.filter.reset((raw[0] - ff[0], raw[1] - ff[1]))
            self.ff_filter.reset(ff)
        self._n += 1
        self._ff[0] = ff
        # both second-order filters, semi-implicit Euler (see CommandFilter), unrolled
        fb, ffl = self.filter, self.ff_filter
        w = min(fb.omega, 0.7 / dt)
        wf = min(ffl.omega, 0.7 / dt)
        out_x, out_xd, out_xdd = self.x, self.xd, self.xdd
        for i in (0, 1):
            e = raw[i] - ff[i]
            a1 = w * w * (e - fb.x[i]) - 2.0 * w * fb.xd[i]
            fb.xdd[i] = a1
            fb.xd[i] += dt * a1
            fb.x[i] += dt * fb.xd[i]
            a2 = wf * wf * (ff[i] - ffl.x[i]) - 2.0 * wf * ffl.xd[i]
            ffl.xdd[i] = a2
            ffl.xd[i] += dt * a2
            ffl.x[i] += dt * ffl.xd[i]
            out_x[i] = ffl.x[i] + fb.x[i]
            out_xd[i] = ffl.xd[i] + fb.xd[i]
            out_xdd[i] = a2 + a1

    def write(self, ref: "Reference") -> None:
        """Store the current references in ``ref`` (entries 3, 4 of xi, xi_dot, xi_ddot)."""
        ref.xi[3], ref.xi[4] = self.x
        ref.xi_dot[3], ref.xi_dot[4] = self.xd
        ref.xi_ddot[3], ref.xi_ddot[4] = self.xdd
