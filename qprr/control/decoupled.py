"""Decoupled control, Thesis Sec. 6.2.2 and Fig. 6.2: a multirotor controller and a fixed-base arm controller designed apart.

The coupled controllers of qprr (:mod:`qprr.control.inverse_dynamics`) invert the whole model
(5.36): the base and the arm see each other's motion.  The decoupled approach the thesis
describes (Sec. 6.2.2: "the multirotor tries to hold its flight while compensating the
disturbances of the manipulator; the manipulator tries to hold its end effector while
compensating the disturbances caused by the motion of the multirotor") builds two controllers
on two models and treats the coupling between them as a disturbance:

* **multirotor**: inverse dynamics of the vehicle as one rigid body: the multirotor with the
  arm *locked* at its measured configuration (the composite mass, CoM and inertia change with
  the arm, as the adaptive decoupled schemes Sec. 6.2.2 cites account for), outer loops, (6.17)
  tilt references and allocation-aware partial linearisation exactly as the coupled IDC
  (:class:`~qprr.control.inverse_dynamics.InverseDynamicsController`).  It ignores the arm's
  velocities and accelerations: the reaction of a moving arm on the base (the Coriolis and
  inertial coupling terms of B and C in (5.36)) is a disturbance to it.
* **arm**: computed-torque control of the fixed-base arm of Thesis Sec. 5.5,
  u = B(q_eb) alpha_q + C(q_eb, q_eb_dot) q_eb_dot + G(q_eb) (5.53), alpha_q of (6.24) (plus
  the integral term of the gains, if any), on :meth:`Platform.arm_model` (the base link is the
  fixed root).  G: ``arm_gravity="level"`` (the base assumed level, as Sec. 5.5's fixed base;
  default) or ``"measured"`` (gravity turned into B with the measured attitude, an IMU reading).
  The base's motion (its acceleration and rotation rate) is a disturbance to it.

With the arm fixed (a platform whose arm joints are locked, :func:`lock_arm`), there is no
arm and no coupling: the decoupled controller is the coupled IDC, to the last bit
(tests/test_decoupled.py).  The comparison the thesis argues for (coupled control reacts to
the arm's motion, decoupled control suffers it) is measured by ``qprr compare decoupled``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..charts import State
from ..errors import InputError, UnknownNameError
from ..model import Platform, from_model
from .base import Controller, Reference, check_reset
from .inverse_dynamics import IDCGains, InverseDynamicsController

ARM_GRAVITY = ("level", "measured")


def fixed_base_inverse_dynamics(arm_model: pin.Model, data: pin.Data, q_arm, q_arm_dot, q_arm_ddot, gravity_base=None) -> np.ndarray:
    """u = B(q) q_ddot + C(q, q_dot) q_dot + G(q) of a fixed-base arm, Thesis (5.53) (RNEA).

    ``gravity_base`` (3,) [m/s^2]: the gravity vector in the base frame (default the model's,
    -g z_B: a level base).  ``arm_model`` is not modified (its gravity is swapped for the call
    and restored).
    """
    if gravity_base is None:
        return pin.rnea(arm_model, data, q_arm, q_arm_dot, q_arm_ddot).copy()
    saved = arm_model.gravity.linear.copy()
    try:
        arm_model.gravity.linear = np.asarray(gravity_base, dtype=float)
        return pin.rnea(arm_model, data, q_arm, q_arm_dot, q_arm_ddot).copy()
    finally:
        arm_model.gravity.linear = saved


class _LockedArmIDC(InverseDynamicsController):
    """The IDC core on the vehicle with its arm locked at the measured configuration.

    The model is evaluated at the measured q with the arm rates set to zero and the arm
    accelerations left at zero (no outer loop on the arm joints): RNEA's base rows are then the
    Newton-Euler equations of the composite rigid body (multirotor + locked arm).
    """

    name = "decoupled-base"

    def _new_run(self) -> None:
        super()._new_run()
        self._locked = State(self.platform.n_arm)

    def _alpha_plan(self, idx) -> tuple[tuple, tuple, tuple]:
        return super()._alpha_plan(tuple(i for i in idx if i < 6))

    def _model_state(self, state: State, r: list, rd: list) -> State:
        if self.platform.n_arm == 0:
            return state
        xd = list(state.xi_dot_floats)
        xd[6:] = [0.0] * self.platform.n_arm
        self._locked.set_from_xi(state.t, state.xi_floats, xd, False, True)  # arrays=False, reuse=True
        return self._locked


class DecoupledController(Controller):
    """Multirotor inverse dynamics (arm locked) + fixed-base arm computed torque, Thesis Sec. 6.2.2 / Fig. 6.2.

    Parameters
    ----------
    platform : the platform controlled.
    gains : :class:`IDCGains` of the coupled IDC: its position and attitude gains drive the
        multirotor controller, its arm gains the arm controller (default :meth:`IDCGains.default`),
        so that both schemes are compared at equal gains.
    arm_gravity : "level" (Sec. 5.5: fixed, level base) or "measured" (gravity in B from the attitude).
    tilt, realizable : passed to the multirotor's inverse-dynamics core.

    Returns Pinocchio's tau (``output = "pinocchio"``): the base wrench of the multirotor
    controller and the arm efforts of the arm controller.
    """

    name = "decoupled"
    output = "pinocchio"

    def __init__(
        self, platform: Platform, gains: IDCGains | None = None, *, arm_gravity: str = "level", tilt: str | None = None, realizable: bool = True
    ) -> None:
        if not isinstance(platform, Platform):
            raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
        if arm_gravity not in ARM_GRAVITY:
            raise UnknownNameError("arm gravity model", arm_gravity, ARM_GRAVITY)
        self.platform = platform
        self.base = _LockedArmIDC(platform, gains, tilt=tilt, realizable=realizable, output="pinocchio")
        self.gains = self.base.gains
        self.arm_gravity = arm_gravity
        n = platform.n_arm
        self.arm_model = platform.arm_model() if n else None
        self.arm_data = self.arm_model.createData() if n else None
        g = self.gains
        self._arm_gains = [(6 + k, g.kp[6 + k], g.kd[6 + k], g.ki[6 + k]) for k in range(n)]
        self._g_world = np.array(platform.model.gravity.linear)
        self.dt = None  # the control period: set by reset(state, ref, dt), called by the simulator
        self._integral = [0.0] * n

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        self.dt = check_reset(self, state, ref, dt)
        self.base.reset(state, ref, dt)
        self._integral = [0.0] * self.platform.n_arm

    def arm_accelerations(self, state: State, ref: Reference) -> np.ndarray:
        """alpha_q = q_ddot_d + K_D e_dot + K_P e + K_I int e of the arm joints, Thesis (6.24) (updates the integral)."""
        x, xd = state.xi_floats, state.xi_dot_floats
        r, rd, rdd = ref.xi, ref.xi_dot, ref.xi_ddot
        out = np.empty(self.platform.n_arm)
        for k, (i, kp, kd, ki) in enumerate(self._arm_gains):
            e = float(r[i]) - x[i]
            a = float(rdd[i]) + kd * (float(rd[i]) - xd[i]) + kp * e
            if ki:
                self._integral[k] += e * self.dt
                a += ki * self._integral[k]
            out[k] = a
        return out

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """tau = [base wrench of the multirotor controller; arm efforts of the arm controller]."""
        tau = np.array(self.base.step(t, state, ref), dtype=float)
        if self.platform.n_arm:
            qa, va = state.q[7:], state.v[6:]
            g_base = None if self.arm_gravity == "level" else state.R.T @ self._g_world
            tau[6:] = fixed_base_inverse_dynamics(self.arm_model, self.arm_data, qa, va, self.arm_accelerations(state, ref), g_base)
        return tau


def lock_arm(platform: Platform, q_arm=None, *, name: str | None = None) -> Platform:
    """The platform with its arm joints locked at ``q_arm`` (default: the neutral posture): a rigid multirotor.

    The arm's links become part of the base body (``pin.buildReducedModel``); the rotors, the
    end-effector frame and gravity are kept.  A new platform: ``platform`` is not modified.
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    q = platform.neutral_q()
    if q_arm is not None:
        q[7:] = platform.check_arm_limits(q_arm)
    model = pin.buildReducedModel(platform.model, [j.joint_id for j in platform.arm], q)
    ee_name = platform.model.frames[platform.ee_frame].name
    return from_model(
        model,
        platform.rotors,
        ee_frame=ee_name,
        name=name or f"{platform.name}-locked",
        provenance={**platform.provenance, "arm": f"locked at {q[7:].tolist()}"},
    )


__all__ = ["ARM_GRAVITY", "DecoupledController", "fixed_base_inverse_dynamics", "lock_arm"]
