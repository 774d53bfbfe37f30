"""Inverse-dynamics control of Thesis Sec. 6.3.1 (IDC) and its desired-state variant (Annex A.2).

Virtual accelerations (outer loops), per coordinate i of xi:

    alpha_i = xi_ddot_d,i + k_D,i (xi_dot_d,i - xi_dot_i) + k_P,i (xi_d,i - xi_i) + k_I,i int (xi_d,i - xi_i)

which is the position PD (6.23), the attitude PID (6.20) and the arm PD (6.24) (with k_I = 0
where the thesis has no integral), or (A.3) with K_P, K_D for all nine.  Roll and pitch
references come from the thrust vector u_fb (6.17):
theta_r = atan((u_x c_psi + u_y s_psi) / u_z), phi_r = asin((u_x s_psi - u_y c_psi) / |u_fb|).

Inner loop: u = B alpha + C xi_dot + G, i.e. (6.19), (6.21), (6.22) stacked, computed as
u = S^T RNEA(q, v, S alpha + S_dot xi_dot) (one Pinocchio call instead of B and C).

* :class:`InverseDynamicsController` (IDC, Sec. 6.3.1) evaluates the model at the measured state.
* :class:`DesiredStateInverseDynamics` evaluates it at the desired state,
  u = B(xi_d) alpha + C(xi_d, xi_dot_d) xi_dot_d + G(xi_d) (Annex A.2 (A.2)-(A.3)).  The
  thesis calls this controller "commande predictive (MPC)"; it predicts nothing and
  optimises nothing over a horizon, so it is named for what it is.

Choices the thesis leaves open, stated here:

* u_fb used in (6.17) is (6.21) evaluated with alpha_phi = alpha_theta = 0: (6.21) contains
  B_p phi alpha_phi, which depends on the very references (6.17) produces (an algebraic
  loop); the term is kept in the applied u.
* The rates and accelerations of phi_r, theta_r that (6.20) needs come from a second-order
  command filter (Remark 4 asks for numerical differentiation with noise-robust filters);
  the filtered angles are the logged references (:class:`~qprr.control.base.TiltReference`:
  the part of (6.17) due to the reference acceleration is filtered at 700 rad/s, the rest
  at ``filter_omega``).
* psi in (6.17) is the measured yaw; tilt references are clamped to ``max_tilt``; when
  u_fb,z < 5 % of the weight (Hypothesis 2 violated: more than free-fall deceleration asked)
  the last tilt reference is held.
* ``realizable`` (default True): (6.19)-(6.22) assume the whole u_fb is applied, but rotors
  only push along z_B, so the body-lateral part of u_fb is lost and the coupled attitude and
  arm accelerations then differ from alpha.  With ``realizable`` the two body-lateral
  accelerations are left to the dynamics (partial feedback linearisation): the applied
  force has no body-lateral part and the seven actuated accelerations equal alpha exactly.

Gains: :meth:`IDCGains.table_6_2` are the printed ones.  Their attitude PIDs are unstable
under exact linearisation (the error obeys e''' + k_D e'' + k_P e' + k_I e = 0 and
k_D k_P < k_I for phi (60 < 70), theta (6.6 < 14) and psi (0.3 < 1.7), Routh-Hurwitz);
:meth:`IDCGains.default` keeps the printed position and arm gains and replaces the
attitude ones (documented there).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..coordinates import as_vector, write_floats
from ..errors import InputError
from ..model import Robot
from .base import Controller, Reference, State, TiltReference

_PI = math.pi
_TWO_PI = 2.0 * math.pi
_rnea, _crba = pin.rnea, pin.crba
_PACK3 = struct.Struct("=3d").pack  # exact key of three floats (tells -0.0 from 0.0)


def _nine(x, name: str) -> tuple[float, ...]:
    a = as_vector(x, 9, name)
    if np.any(a < 0):
        raise InputError(f"{name} must be >= 0, got {a.tolist()}")
    return tuple(float(v) for v in a)


@dataclass(frozen=True)
class IDCGains:
    """Per-coordinate gains (order x, y, z, phi, theta, psi, r0, theta2, theta3) of the outer loops.

    ``filter_omega`` [rad/s]: bandwidth of the roll/pitch command filter; ``max_tilt`` [rad].
    """

    kp: tuple[float, ...] = (1.4, 1.4, 1.4, 20.0, 6.0, 1.5, 16.0, 16.0, 16.0)
    kd: tuple[float, ...] = (0.3, 0.3, 0.3, 3.0, 1.1, 0.2, 3.0, 3.0, 3.0)
    ki: tuple[float, ...] = (0.0, 0.0, 0.0, 70.0, 14.0, 1.7, 0.0, 0.0, 0.0)
    filter_omega: float = 50.0
    max_tilt: float = 0.8

    def __post_init__(self) -> None:
        for name in ("kp", "kd", "ki"):
            object.__setattr__(self, name, _nine(getattr(self, name), name))
        if not (self.filter_omega > 0 and 0 < self.max_tilt < math.pi / 2):
            raise InputError(f"need filter_omega > 0 and 0 < max_tilt < pi/2, got {self.filter_omega!r}, {self.max_tilt!r}")

    @classmethod
    def table_6_2(cls) -> IDCGains:
        """Printed Table 6.2: K_pP = 1.4 I3, K_pD = 0.3 I3, K_qP = 16 I3, K_qD = 3 I3, attitude PIDs (20, 70, 3), (6, 14, 1.1), (1.5, 1.7, 0.2)."""
        return cls()

    @classmethod
    def default(cls) -> IDCGains:
        """Table 6.2 position and arm gains; attitude PIDs retuned to be stable.

        The printed attitude gains make e''' + k_D e'' + k_P e' + k_I e = 0 unstable (module
        docstring).  Replacement: each angle gets the characteristic polynomial (s + w)^3 with
        w = 10 rad/s (k_D = 3w, k_P = 3w^2, k_I = w^3): well damped and about ten times faster
        than the position loop (sqrt(1.4) = 1.2 rad/s), as a cascade needs.
        """
        w = 10.0
        att_p, att_i, att_d = 3 * w * w, w**3, 3 * w
        base = cls()
        kp = base.kp[0:3] + (att_p,) * 3 + base.kp[6:9]
        kd = base.kd[0:3] + (att_d,) * 3 + base.kd[6:9]
        ki = (0.0,) * 3 + (att_i,) * 3 + (0.0,) * 3
        return cls(kp=kp, kd=kd, ki=ki)

    @classmethod
    def desired_state_default(cls) -> IDCGains:
        """Gains of the desired-state controller: (A.3)'s K_P = 30 with K_D = 2 sqrt(30) on
        position, the retuned attitude PIDs of :meth:`default`, stiffer arm loops, roll/pitch
        filter 20 rad/s.

        * Position: Table 6.2's K_P = 30, the gain (A.3) is written with, and K_D = 2 sqrt(K_P)
          = 10.95 (critical damping, double pole at -5.5 rad/s) instead of the printed 18.
          The printed K_D = 18 puts the position loop's crossover at 18 rad/s (2.9 Hz), beyond
          what the thrust-direction cascade (20 rad/s roll/pitch filter, (s + 10)^3 attitude
          loops) delivers: the vehicle then keeps a barely damped 3 Hz roll/pitch oscillation
          (+-1 deg on the static mission after 10 s; at hover a 1 mm offset rings at 3 Hz and
          decays at only 0.1-0.25 /s; the IDC with the same gains does the same, so it is the
          gains, not the desired-state model).  With K_D = 10.95 the same offset decays at
          2.9 /s and the oscillation is gone (docs/notes-spikes.md).
        * Roll/pitch: the feedback part of the reference stays slow (``filter_omega`` =
          20 rad/s): B is 2.5 cm below the CoG, so a pitch acceleration moves B sideways at
          once and K_D on the velocity of B feeds that back into the pitch reference (with
          K_D = 18, 30 rad/s tracks poorly and 50 diverges; with K_D = 10.95, 20 to 50 rad/s
          all track).
        * Arm: k_P = w^2, k_D = 2 w with w = 50 rad/s.  Our arm stands above B (z_B up,
          Thesis (3.58)): an inverted pendulum.  The IDC cancels its gravity torque at the
          measured configuration; the desired-state controller uses G(xi_d), so the mismatch
          dG/dq (q - q_d) acts as a negative stiffness (about 0.05 N m/rad on theta3 and
          0.5 N m/rad on theta2 against B_qq k_qP = 0.004 and 0.09 with k_qP = 16).  Measured
          on the static mission: w <= 25 rad/s diverges, 30 is marginal, 40 and more track.
        """
        base = cls.default()
        w = 50.0
        kp_pos = 30.0
        kp = (kp_pos,) * 3 + base.kp[3:6] + (w * w,) * 3
        kd = (2.0 * math.sqrt(kp_pos),) * 3 + base.kd[3:6] + (2 * w,) * 3
        return cls(kp=kp, kd=kd, ki=base.ki, filter_omega=20.0, max_tilt=base.max_tilt)

    @classmethod
    def annex_a3(cls) -> IDCGains:
        """(A.3) with Table 6.2's K_P = 30 I9, K_D = 18 I9 (no integral), as for the desired-state controller."""
        return cls(kp=(30.0,) * 9, kd=(18.0,) * 9, ki=(0.0,) * 9)


class InverseDynamicsController(Controller):
    """IDC of Thesis Sec. 6.3.1 ((6.17), (6.19)-(6.24)); the model is evaluated at the measured state.

    ``step`` returns u = B(xi) alpha + C(xi, xi_dot) xi_dot + G(xi); as Pinocchio's tau = S^-T u
    (``output = "pinocchio"``: that is what it computes; the simulator logs u).
    """

    name = "idc"
    output = "pinocchio"  # returns tau = S^-T u at the measured state (the simulator logs u)
    _reuse_mass = False  # the measured arm joints change at every step: no point in reusing M
    default_gains = staticmethod(IDCGains.default)

    def __init__(self, robot: Robot, gains: IDCGains | None = None, *, realizable: bool = True) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.gains = self.default_gains() if gains is None else gains
        if not isinstance(self.gains, IDCGains):
            raise InputError(f"gains must be an IDCGains, got {type(self.gains).__name__}")
        self.realizable = bool(realizable)
        self.dt = 1e-3
        self.reset(State(), Reference(), 1e-3)

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        self.dt = dt
        self.integral = [0.0] * 9
        p = self.robot.params
        self.tilt = TiltReference(self.gains.filter_omega, self.gains.max_tilt, 0.05 * p.total_mass * p.g)
        self._g = p.g
        self._started = False
        # the outer loops' gains looked up once (see :meth:`_alpha_plan`)
        self._loops_outer = self._alpha_plan((0, 1, 2, 5, 6, 7, 8))
        self._loops_tilt = self._alpha_plan((3, 4))
        self._abuf = np.zeros(9)  # the accelerations handed to RNEA
        self._mass_key = None  # arm joints of the reused mass-matrix rows (see step)
        self._mass_rows = None

    # ------------------------------------------------------------------ pieces
    def _alpha(self, x, xd, r, rd, rdd, idx, al: list[float]) -> list[float]:
        """Virtual accelerations alpha_i into ``al`` for the coordinates ``idx``: (6.20), (6.23), (6.24), (A.3).

        ``x``, ``xd``: measured xi, xi_dot; ``r``, ``rd``, ``rdd``: references (plain lists).
        """
        return self._alpha_loops(x, xd, r, rd, rdd, self._alpha_plan(idx), al)

    def _alpha_plan(self, idx) -> tuple[tuple, tuple]:
        """Gains of the coordinates ``idx`` for :meth:`_alpha_loops`: ((i, k_P, k_D) without
        integral action, ...), ((i, k_P, k_D, k_I) with integral action or yaw (wrapped error), ...)."""
        g = self.gains
        plain = tuple((i, g.kp[i], g.kd[i]) for i in idx if i != 5 and not g.ki[i])
        other = tuple((i, g.kp[i], g.kd[i], g.ki[i]) for i in idx if i == 5 or g.ki[i])
        return plain, other

    def _alpha_loops(self, x, xd, r, rd, rdd, plan, al: list[float]) -> list[float]:
        """:meth:`_alpha` for a :meth:`_alpha_plan` (gains looked up once, in :meth:`reset`)."""
        plain, other = plan
        for i, kp, kd in plain:  # PD: alpha = xi_ddot_d + k_D e_dot + k_P e
            al[i] = rdd[i] + kd * (rd[i] - xd[i]) + kp * (r[i] - x[i])
        integ, dt = self.integral, self.dt
        for i, kp, kd, ki in other:  # + k_I int e; the yaw error wrapped to [-pi, pi)
            e = r[i] - x[i]
            if i == 5:
                e = (e + _PI) % _TWO_PI - _PI
            a = rdd[i] + kd * (rd[i] - xd[i]) + kp * e
            if ki:
                integ[i] += e * dt
                a += ki * integ[i]
            al[i] = a
        return al

    def _model_state(self, state: State, r: list, rd: list) -> State:
        """State at which B, C, G are evaluated: the measured one (``r``, ``rd``: reference lists)."""
        return state

    def _attitude_references(self, state: State, ref: Reference, u_fb) -> None:
        """(6.17) -> :class:`TiltReference` -> phi_d, theta_d and their rates written into ``ref``."""
        self.tilt.update(state.xi[5], u_fb, ref.xi_ddot[0:3].tolist(), self._g, self.dt)
        self.tilt.write(ref)
        self._started = True

    # ------------------------------------------------------------------ step
    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """u = B alpha + C xi_dot + G with alpha from (6.20), (6.23), (6.24) and roll/pitch from (6.17)."""
        x, xd = state._xi, state._xd
        r, rd, rdd = ref.xi.tolist(), ref.xi_dot.tolist(), ref.xi_ddot.tolist()
        ms = self._model_state(state, r, rd)
        model, data, q, v = self.model, self.data, ms.q, ms.v
        alpha = self._alpha_loops(x, xd, r, rd, rdd, self._loops_outer, [0.0] * 9)
        a = ms.accel_to_v_list(alpha)
        abuf = self._abuf
        write_floats(abuf, a)  # = np.array(a), into a buffer RNEA only reads
        t0 = _rnea(model, data, q, v, abuf).tolist()
        tilt = self.tilt
        # u_fb of (6.21) with alpha_phi = alpha_theta = 0: R times the body force of RNEA (State.lin_to_world)
        f0, f1, f2 = t0[0:3]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = ms._r
        u_fb = (r00 * f0 + r01 * f1 + r02 * f2, r10 * f0 + r11 * f1 + r12 * f2, r20 * f0 + r21 * f1 + r22 * f2)
        tilt.update(x[5], u_fb, rdd[0:3], self._g, self.dt)
        tilt.write(ref)
        self._started = True
        r[3], r[4] = tilt.x
        rd[3], rd[4] = tilt.xd
        rdd[3], rdd[4] = tilt.xdd
        self._alpha_loops(x, xd, r, rd, rdd, self._loops_tilt, alpha)
        # omega_dot change of the roll/pitch accelerations: T [alpha_phi, alpha_theta, 0] (State.euler_accel_to_omega_dot)
        a3, a4 = alpha[3], alpha[4]
        sf, cf = ms.sf, ms.cf
        d3, d4, d5 = a3, cf * a4, -sf * a4  # T(phi, theta) [a3, a4, 0]
        if self.realizable:
            # body-lateral accelerations d0, d1 chosen so that the applied force has no
            # body-lateral part: (tau0 + M delta)[0:2] = 0 with M[0:2, 0:2] = m I2
            if self._reuse_mass:
                # M (CRBA, local convention) depends on the arm joints only: reused while they
                # are bit for bit those of the previous step (a held desired arm pose)
                xm = ms._xi
                key = _PACK3(xm[6], xm[7], xm[8])
                if key != self._mass_key:
                    self._mass_rows = _crba(model, data, q)[0:2, 0:6].tolist()
                    self._mass_key = key
                (m, _, _, m03, m04, m05), (_, _, _, m13, m14, m15) = self._mass_rows
            else:
                M = _crba(model, data, q)  # Pinocchio 3+: full symmetric matrix
                (m, _, _, m03, m04, m05), (_, _, _, m13, m14, m15) = M[0:2, 0:6].tolist()
            a[0] -= (t0[0] + m03 * d3 + m04 * d4 + m05 * d5) / m
            a[1] -= (t0[1] + m13 * d3 + m14 * d4 + m15 * d5) / m
        a[3] += d3
        a[4] += d4
        a[5] += d5
        write_floats(abuf, a)
        tau = _rnea(model, data, q, v, abuf)
        return tau if self.output == "pinocchio" else ms.force_to_xi(tau)


class DesiredStateInverseDynamics(InverseDynamicsController):
    """Inverse dynamics evaluated at the desired state, Thesis Annex A.2 (A.2)-(A.3) (the thesis's "MPC").

    u = B(xi_d) y + C(xi_d, xi_dot_d) xi_dot_d + G(xi_d), y = xi_ddot_d + K_D e_dot + K_P e (A.3).
    The desired roll and pitch are those of (6.17) (the previous step's filtered values enter
    the model, the current ones the feedback).

    Default gains: :meth:`IDCGains.desired_state_default` ((A.3)'s K_P = 30, K_D = 2 sqrt(30) on
    position; it says what had to change elsewhere and why).  Table 6.2's K_P = 30 I9,
    K_D = 18 I9 on all nine coordinates (:meth:`IDCGains.annex_a3`) diverge: on the arm for
    the reason given there, and on attitude because (A.3) has no integral and a 1.8 rad/s
    slow pole.  (A fully actuated model, where u_fb is applied directly, has neither issue.)
    """

    name = "dsid"
    output = "xi"  # tau is computed at the desired state: u = S_d^T tau_d is what applies
    _reuse_mass = True  # the desired arm pose is often held: M(q_d) is reused while it is
    default_gains = staticmethod(IDCGains.desired_state_default)

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        super().reset(state, ref, dt)
        self._desired = State()

    def _model_state(self, state: State, r: list, rd: list) -> State:
        xi_d, xi_dot_d = list(r), list(rd)
        if self._started:  # roll/pitch of the desired state: the (6.17) references of the last step
            xi_d[3], xi_d[4] = self.tilt.x
            xi_dot_d[3], xi_dot_d[4] = self.tilt.xd
        else:  # first step: none yet, use the measured tilt
            xi_d[3], xi_d[4] = state._xi[3], state._xi[4]
        self._desired._from_xi(state.t, xi_d, xi_dot_d, False, True)  # update_xi(..., arrays=False, reuse=True)
        return self._desired
