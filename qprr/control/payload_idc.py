"""Layered inverse-dynamics control with payload compensation, Thesis Sec. 6.4.2.2 ((6.53)-(6.57)).

The unknown-mass model (6.53) is B xi_ddot + C xi_dot + G = u - B_c xi_ddot - G_c (- C_c xi_dot).
The controller linearises it with the model it believes:

    u = (B + B_c(m_hat)) alpha + (C + C_c(m_hat)) xi_dot + G + G_c(m_hat),

evaluated as u = S^T RNEA_hat(q, v, S alpha + S_dot xi_dot) on a model copy whose link 3
carries a point mass m_hat at the end effector (:class:`qprr.payload.PayloadModel`).  C_c is
kept (the thesis neglects it; RNEA gives it for free).  m_hat comes from ``payload``:

* ``"estimate"`` (default): :class:`qprr.payload.MassEstimator` on the torque residual;
* ``"known"``: the true mass, given as ``known_mass`` (the known-mass model (6.40));
* ``"none"``: no compensation (nominal model, as :mod:`qprr.control.idc`).

Outer loops (virtual accelerations alpha, one group per layer):

* position (6.23)/(6.78): alpha_p = p_ddot_d + K_pD e_p_dot + K_pP e_p + K_pI int e_p;
* attitude (6.56)/(6.20): alpha_* = *_ddot_d + k_D e_dot + k_P e + k_I int e, roll/pitch
  references from the thrust vector (6.17) through a second-order command filter;
* arm (6.57)/(6.79): alpha_q = q_ddot_d + K_qD e_q_dot + K_qP e_q + K_qI int e_q.

:class:`LayeredGains` holds all of them; ``table_6_5()`` / ``table_6_7()`` are the printed
tables; :meth:`LayeredGains.unstable_axes` applies Routh-Hurwitz to the error dynamics
e''' + k_D e'' + k_P e' + k_I e = 0 that exact linearisation leaves on every axis.  The printed
attitude PI of (6.56) (k_D = 0) gives s^3 + k_P s + k_I, whose roots sum to zero: unstable
for every k_I > 0.  :meth:`LayeredGains.payload_default` keeps the printed position gains of
Table 6.5, replaces the attitude PI by the PID with characteristic polynomial (s + 15)^3
(three times the position loop's natural frequency sqrt(20) = 4.5 rad/s) and the barely
damped arm PID by (s + 10)^3.

The 9x9 K_P = 48 I9, K_D = 25 I9 of Table 6.5 belong to the generic form (6.54) of which the
layers are the per-group instances; they are not used on top of the layer gains.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..coordinates import as_vector
from ..errors import InputError, UnknownNameError
from ..model import Robot
from ..payload import MassEstimator, PayloadModel
from .base import CommandFilter, Controller, Reference, State

Triple = tuple[float, float, float]
PAYLOAD_MODES = ("estimate", "known", "none")


@dataclass(frozen=True)
class LayeredGains:
    """Per-axis gains of the three layers; ``filter_omega`` [rad/s] of the roll/pitch command filter, ``max_tilt`` [rad]."""

    kp_pos: Triple = (20.0, 20.0, 20.0)
    kd_pos: Triple = (2.0, 2.0, 2.0)
    ki_pos: Triple = (0.0, 0.0, 0.0)
    kp_att: Triple = (20.0, 40.0, 20.0)
    kd_att: Triple = (0.0, 0.0, 0.0)
    ki_att: Triple = (5.0, 2.0, 2.0)
    kp_arm: Triple = (10.0, 10.0, 10.0)
    kd_arm: Triple = (2.0, 2.0, 2.0)
    ki_arm: Triple = (15.0, 15.0, 15.0)
    filter_omega: float = 50.0
    max_tilt: float = 0.8

    def __post_init__(self) -> None:
        for name in ("kp_pos", "kd_pos", "ki_pos", "kp_att", "kd_att", "ki_att", "kp_arm", "kd_arm", "ki_arm"):
            v = getattr(self, name)
            if len(v) != 3 or not all(np.isfinite(x) and x >= 0.0 for x in v):
                raise InputError(f"gain {name} must be 3 finite numbers >= 0, got {v!r}")
        if not (self.filter_omega > 0.0 and 0.0 < self.max_tilt < math.pi / 2):
            raise InputError(f"need filter_omega > 0 and 0 < max_tilt < pi/2, got {self.filter_omega!r}, {self.max_tilt!r}")

    @classmethod
    def table_6_5(cls) -> LayeredGains:
        """Thesis Table 6.5 as printed: position PD (20, 2), attitude PI (6.56), arm PID (10, 2, 15)."""
        return cls()

    @classmethod
    def payload_default(cls) -> LayeredGains:
        """Table 6.5 position PD kept; attitude and arm retuned (module docstring).

        Attitude: the printed PI is unstable; PID of (s + 15)^3.  Arm: the printed PID
        (10, 2, 15) is stable but its error polynomial s^3 + 2 s^2 + 10 s + 15 has roots
        -0.20 +- 3.05j (damping ratio 0.065: a disturbance rings for ~20 s); PID of (s + 10)^3.
        Inverse dynamics makes the arm's stiffness to torque errors k_P times the link inertia
        (~2.5e-4 kg m^2 for theta3), so a payload release (0.07 N m step on theta3 until the
        estimate follows) needs the faster arm loop.
        """
        return replace(cls.table_6_5(), **_pid_cubed("att", 15.0), **_pid_cubed("arm", 10.0))

    @classmethod
    def table_6_7(cls) -> LayeredGains:
        """Thesis Table 6.7 as printed: position PD (6, 5), attitude PD (5, 2; 5, 2; 25, 4.5), arm PI (8, 2)."""
        return cls(kp_pos=(6.0,) * 3, kd_pos=(5.0,) * 3, ki_pos=(0.0,) * 3,
                   kp_att=(5.0, 5.0, 25.0), kd_att=(2.0, 2.0, 4.5), ki_att=(0.0,) * 3,
                   kp_arm=(8.0,) * 3, kd_arm=(0.0,) * 3, ki_arm=(2.0,) * 3)

    @classmethod
    def impedance_default(cls) -> LayeredGains:
        """Table 6.7 position PD kept (poles -2, -3); attitude and arm retuned.

        Attitude: the printed PD (k_P = 5, k_D = 2: poles -1 +- 2j) is slower than the position
        loop it serves; PD of (s + 15)^2.  Arm: the printed PI (6.79) has no rate term
        (s^3 + 8 s + 2, unstable); PID of (s + 5)^3.
        The roll/pitch command filter is slowed to 20 rad/s: the impedance filter's
        reference acceleration steps by h/M_D (2 m/s^2 for h_b = 0.2 N, M_D = 0.1 kg) when the
        force switches, i.e. a 0.2 rad step of the (6.17) pitch command; at 50 rad/s the
        filtered command then asks for 565 rad/s^2 (5.6 N m, beyond the rotors' 4.5 N m).
        """
        w = 15.0
        return replace(cls.table_6_7(), kp_att=(w * w,) * 3, kd_att=(2 * w,) * 3, ki_att=(0.0,) * 3, filter_omega=20.0,
                       **_pid_cubed("arm", 5.0))

    def characteristic_polynomials(self) -> dict[str, np.ndarray]:
        """Closed-loop error polynomial per axis under exact linearisation: [1, k_D, k_P, k_I] (or [1, k_D, k_P] if k_I = 0)."""
        names = (("x", "y", "z"), ("phi", "theta", "psi"), ("r0", "theta2", "theta3"))
        groups = ((self.kd_pos, self.kp_pos, self.ki_pos), (self.kd_att, self.kp_att, self.ki_att), (self.kd_arm, self.kp_arm, self.ki_arm))
        out = {}
        for axis_names, (kd, kp, ki) in zip(names, groups):
            for i, n in enumerate(axis_names):
                out[n] = np.array([1.0, kd[i], kp[i], ki[i]]) if ki[i] > 0.0 else np.array([1.0, kd[i], kp[i]])
        return out

    def unstable_axes(self) -> list[str]:
        """Axes whose error polynomial is not Hurwitz (Routh: cubic needs k_D, k_I > 0 and k_D k_P > k_I; quadratic k_D, k_P > 0)."""
        bad = []
        for n, c in self.characteristic_polynomials().items():
            ok = (c[1] > 0 and c[2] > 0 and c[3] > 0 and c[1] * c[2] > c[3]) if len(c) == 4 else (c[1] > 0 and c[2] > 0)
            if not ok:
                bad.append(n)
        return bad


def _pid_cubed(group: str, w: float) -> dict:
    """Gains giving the error polynomial (s + w)^3: k_D = 3w, k_P = 3w^2, k_I = w^3."""
    return {f"kd_{group}": (3 * w,) * 3, f"kp_{group}": (3 * w * w,) * 3, f"ki_{group}": (w**3,) * 3}


class LayeredIDC(Controller):
    """Layered inverse dynamics: u = B_hat alpha + C_hat xi_dot + G_hat (+ feedforward), Thesis (6.19)-(6.22) / (6.55).

    With ``ee_sensor`` / ``base_sensor`` and ``compensate`` the measured interaction is
    cancelled, u += -u_e(h) (Thesis (6.76)); the controller is then named "layered-idc-ft".
    A wrist sensor read inside the loop is one step late; cancelling it unfiltered against a
    stiff contact makes a limit cycle (push-thrust, 500 N/m: contact force 1.35 +- 2.0 N
    instead of the 1.47 N of friction), which ``sensor_filter`` = 50 rad/s removes (+- 0.04 N).
    Subclasses change the references (:meth:`update_references`), the feedforward
    (:meth:`feedforward`) or the model (``self.pm``).
    """

    name = "layered-idc"

    def __init__(self, robot: Robot, gains: LayeredGains | None = None, *,
                 ee_sensor: Callable[[float], np.ndarray] | None = None,
                 base_sensor: Callable[[float], np.ndarray] | None = None, compensate: bool = True,
                 sensor_filter: float | None = None) -> None:
        if sensor_filter is not None and not (np.isfinite(sensor_filter) and sensor_filter > 0.0):
            raise InputError(f"sensor_filter must be None or a bandwidth > 0 rad/s, got {sensor_filter!r}")
        self.sensor_filter = sensor_filter
        self._h_f = None
        self.robot = robot
        self.gains = LayeredGains.payload_default() if gains is None else gains
        self.pm = PayloadModel(robot)
        self.dt = 1e-3
        self.ee_sensor = ee_sensor
        self.base_sensor = base_sensor
        self.compensate = bool(compensate)
        self._jdata = robot.model.createData()
        self._u_e = np.zeros(9)
        self._h_b = np.zeros(4)
        if ee_sensor is not None or base_sensor is not None:
            self.name = "layered-idc-ft" if compensate else "layered-idc"

    # ----------------------------------------------------------------- hooks
    def measure(self, t: float, state: State) -> tuple[np.ndarray, np.ndarray]:
        """(h_b (4,), u_e (9,)) from the sensors: u_e = S^T J_e^T h_ee (6.59) + h_b on [x, y, z, psi].

        ``ee_sensor(t)`` is the world wrench on the end effector (6,); ``base_sensor(t)`` the
        generalised force (4,) on [x, y, z, psi].  With ``sensor_filter`` = w the end-effector
        wrench passes a first-order low-pass filter h_f' = w (h - h_f) (exact ZOH step).
        """
        u_e = np.zeros(9)
        h_b = np.zeros(4)
        if self.ee_sensor is not None:
            h = as_vector(self.ee_sensor(t), 6, "ee_sensor(t)")
            if self.sensor_filter is not None:
                if self._h_f is None:
                    self._h_f = h.copy()
                else:
                    self._h_f += (1.0 - math.exp(-self.sensor_filter * self.dt)) * (h - self._h_f)
                h = self._h_f
            if np.any(h != 0.0):
                J = pin.computeFrameJacobian(self.robot.model, self._jdata, state.q, self.robot.ee_frame, pin.LOCAL_WORLD_ALIGNED)
                u_e = state.force_to_xi(J.T @ h)
        if self.base_sensor is not None:
            h_b = as_vector(self.base_sensor(t), 4, "base_sensor(t)")
            u_e[[0, 1, 2, 5]] += h_b
        return h_b, u_e

    def update_references(self, t: float, state: State, ref: Reference) -> None:
        """Change ``ref`` in place before the outer loops (default: nothing)."""

    def feedforward(self, t: float, state: State) -> np.ndarray | None:
        """Generalised force added to the inverse-dynamics output: -u_e(h) of (6.76) when compensating measured wrenches."""
        if self.compensate and (self.ee_sensor is not None or self.base_sensor is not None):
            return -self._u_e
        return None

    # ----------------------------------------------------------------- run
    def reset(self, state: State, ref: Reference, dt: float) -> None:
        self.dt = dt
        self._h_f = None
        self.int_pos = np.zeros(3)
        self.int_att = np.zeros(3)
        self.int_arm = np.zeros(3)
        self.filter = CommandFilter(2, self.gains.filter_omega)
        self._started = False
        self._raw = (0.0, 0.0)
        self._uz_min = 0.05 * self.robot.params.total_mass * self.robot.params.g

    def _model_force(self, state: State, alpha: np.ndarray) -> np.ndarray:
        a = state.accel_to_v(alpha)
        tau = pin.rnea(self.pm.model, self.pm.data, state.q, state.v, a)
        return state.force_to_xi(tau)

    def _outer(self, state: State, ref: Reference) -> np.ndarray:
        g, dt = self.gains, self.dt
        x, xd = state.xi, state.xi_dot
        e = ref.xi - x
        ed = ref.xi_dot - xd
        alpha = np.zeros(9)
        self.int_pos += dt * e[0:3]
        alpha[0:3] = ref.xi_ddot[0:3] + np.multiply(g.kd_pos, ed[0:3]) + np.multiply(g.kp_pos, e[0:3]) + np.multiply(g.ki_pos, self.int_pos)
        self.int_arm += dt * e[6:9]
        alpha[6:9] = ref.xi_ddot[6:9] + np.multiply(g.kd_arm, ed[6:9]) + np.multiply(g.kp_arm, e[6:9]) + np.multiply(g.ki_arm, self.int_arm)
        e_psi = _wrap(e[5])
        self.int_att[2] += dt * e_psi
        alpha[5] = ref.xi_ddot[5] + g.kd_att[2] * ed[5] + g.kp_att[2] * e_psi + g.ki_att[2] * self.int_att[2]
        return alpha

    def _attitude_references(self, state: State, ref: Reference, u_fb: np.ndarray) -> None:
        """Thesis (6.17): theta_r = atan((u_x c_psi + u_y s_psi) / u_z), phi_r = asin((u_x s_psi - u_y c_psi) / |u_fb|)."""
        ux, uy, uz = (float(v) for v in u_fb)
        if uz > self._uz_min:
            psi = state.xi[5]
            cp, sp = math.cos(psi), math.sin(psi)
            lim = self.gains.max_tilt
            theta_r = max(-lim, min(lim, math.atan((ux * cp + uy * sp) / uz)))
            phi_r = max(-lim, min(lim, math.asin((ux * sp - uy * cp) / math.sqrt(ux * ux + uy * uy + uz * uz))))
            self._raw = (phi_r, theta_r)
        else:  # Hypothesis 2 violated (u_fb,z <= 0): hold the last tilt reference
            phi_r, theta_r = self._raw
        if not self._started:
            self.filter.reset((phi_r, theta_r))
            self._started = True
        self.filter.update((phi_r, theta_r), self.dt)
        ref.xi[3], ref.xi[4] = self.filter.x
        ref.xi_dot[3], ref.xi_dot[4] = self.filter.xd
        ref.xi_ddot[3], ref.xi_ddot[4] = self.filter.xdd

    def _attitude_alpha(self, state: State, ref: Reference, alpha: np.ndarray) -> None:
        g = self.gains
        for i in (0, 1):
            j = 3 + i
            e = ref.xi[j] - state.xi[j]
            self.int_att[i] += self.dt * e
            alpha[j] = ref.xi_ddot[j] + g.kd_att[i] * (ref.xi_dot[j] - state.xi_dot[j]) + g.kp_att[i] * e + g.ki_att[i] * self.int_att[i]

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """Roll/pitch from (6.17) with u_fb evaluated at alpha_phi = alpha_theta = 0, then the full u."""
        if self.ee_sensor is not None or self.base_sensor is not None:
            self._h_b, self._u_e = self.measure(t, state)
        self.update_references(t, state, ref)
        alpha = self._outer(state, ref)
        ff = self.feedforward(t, state)
        u0 = self._model_force(state, alpha)
        if ff is not None:
            u0 = u0 + ff
        self._attitude_references(state, ref, u0[0:3])
        self._attitude_alpha(state, ref, alpha)
        u = self._model_force(state, alpha)
        if ff is not None:
            u = u + ff
        self.last_alpha = alpha
        return u


class PayloadIDC(LayeredIDC):
    """Layered IDC whose model carries the payload m_hat (estimated, known or none), Thesis (6.53)-(6.57).

    ``mass_log`` records m_hat at every step (one entry per call of :meth:`step`).
    """

    def __init__(self, robot: Robot, gains: LayeredGains | None = None, *, payload: str = "estimate",
                 known_mass: float = 0.0, estimator: MassEstimator | None = None, com_ee=(0.0, 0.0, 0.0)) -> None:
        if payload not in PAYLOAD_MODES:
            raise UnknownNameError("payload mode", payload, PAYLOAD_MODES)
        super().__init__(robot, gains)
        self.pm = PayloadModel(robot, com_ee)
        self.mode = payload
        self.known_mass = float(known_mass)
        if payload == "known" and not (np.isfinite(self.known_mass) and self.known_mass >= 0.0):
            raise InputError(f"known_mass must be >= 0 kg, got {known_mass!r}")
        self.estimator = estimator if estimator is not None else (MassEstimator(robot, com_ee=com_ee) if payload == "estimate" else None)
        self.name = {"estimate": "payload-idc", "known": "payload-idc-known", "none": "payload-idc-none"}[payload]
        self.mass_log: list[float] = []

    def set_known_mass(self, mass: float) -> None:
        """Change the known payload mass (mode "known"): e.g. a scheduled release the controller is told about."""
        self.known_mass = float(mass)

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        super().reset(state, ref, dt)
        if self.estimator is not None:
            self.estimator.reset()
        self._prev = None
        self.mass_log = []
        self.pm.set_mass(self.known_mass if self.mode == "known" else 0.0)

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        if self.mode == "estimate":
            if self._prev is not None:
                q0, v0, tau0 = self._prev
                self.pm.set_mass(self.estimator.update(q0, v0, tau0, state.v, self.dt))
        elif self.mode == "known":
            if self.known_mass != self.pm.mass:
                self.pm.set_mass(self.known_mass)
        u = super().step(t, state, ref)
        if self.mode == "estimate":
            tau = state.force_from_xi(u)
            tau[0] = tau[1] = 0.0  # rotors produce no body-lateral force: applied = allocated (no saturation assumed)
            self._prev = (state.q.copy(), state.v.copy(), tau)
        self.mass_log.append(self.pm.mass)
        return u


def _wrap(a: float) -> float:
    """Angle difference wrapped to (-pi, pi]."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi
