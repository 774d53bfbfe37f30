"""One inverse-dynamics core for any platform, of which the thesis's model-based controllers are configurations.

Virtual accelerations (outer loops), per coordinate i of xi = [x, y, z, phi, theta, psi, q_arm]:

    alpha_i = xi_ddot_d,i + k_D,i (xi_dot_d,i - xi_dot_i) + k_P,i (xi_d,i - xi_i) + k_I,i int (xi_d,i - xi_i)

(the position PD (6.23), the attitude PID (6.20), the arm PD (6.24), or (A.3), (6.54)-(6.57),
(6.77)-(6.79); the yaw error is wrapped).  Roll and pitch references come from the thrust vector
u_fb, Thesis (6.17): theta_r = atan((u_x c_psi + u_y s_psi) / u_z),
phi_r = asin((u_x s_psi - u_y c_psi) / |u_fb|), with u_fb the world force of the model at
alpha_phi = alpha_theta = 0 (an algebraic loop otherwise) and rates from a command filter
(:mod:`qprr.control.filters`).  Inner loop: u = B alpha + C xi_dot + G ((6.19), (6.21), (6.22)
stacked), computed as u = S^T RNEA(q, v, S alpha + S_dot xi_dot) (one Pinocchio call instead of
B and C).

:class:`InverseDynamicsController` is that core; its options make the thesis's controllers:

==============================  =============================================================
configuration                   options
==============================  =============================================================
IDC (Sec. 6.3.1)                model at the measured state, split tilt filter, realizable
desired-state ID (Annex A.2)    ``at="desired"``: B, C, G at (xi_d, xi_dot_d) ((A.2)-(A.3));
                                the thesis calls it "MPC" though it predicts nothing
layered IDC (Sec. 6.4.2)        ``tilt="single"``, ``realizable=False``, a payload model and the
                                measured wrench cancelled ((6.76)) - :class:`LayeredIDC`
payload IDC ((6.53)-(6.57))     the model carries the estimated/known payload - :class:`PayloadIDC`
impedance (Sec. 6.4.3.3)        impedance-filtered references - :class:`qprr.control.impedance.ImpedanceController`
end-effector impedance          an end-effector acceleration task (:meth:`task_accelerations`) and the
((6.72)-(6.73))                 measured wrench cancelled - :class:`qprr.control.opspace_impedance.OperationalSpaceImpedance`
==============================  =============================================================

* ``realizable`` (default True): (6.19)-(6.22) assume the whole u_fb is applied, but coplanar
  rotors only push along z_B, so the part of the base wrench the rotors cannot produce (the
  body-lateral force) is lost and the coupled attitude and arm accelerations then differ from
  alpha.  With ``realizable`` the base accelerations along those directions are left to the
  dynamics (partial feedback linearisation): the applied wrench has no unproducible part and
  the actuated accelerations equal alpha exactly.  A fully actuated platform has nothing to
  drop: the whole u is applied.
* ``tilt``: "split" (:class:`~qprr.control.filters.TiltReference`: the part of (6.17) due to
  the reference acceleration filtered at 700 rad/s, the rest at ``filter_omega``) or "single"
  (:class:`~qprr.control.filters.SingleTiltReference`); "none" for a fully actuated platform
  flying at the attitude of the trajectory (roll/pitch references as given).
* psi in (6.17) is the measured yaw; tilt references are clamped to ``max_tilt``; when
  u_fb,z < 5 % of the weight (Hypothesis 2 violated) the last tilt reference is held.

* ``payload_awareness`` (:class:`PayloadAwareness`): the model carries a payload at the end effector, announced
  (mass from given times on, (6.40)) or estimated online (Sec. 6.4.2); without it an unannounced payload is left to the
  integrals.  The integrals of :class:`IDCGains` may be guarded against the actuator bounds (:class:`AntiWindup`,
  ``integral_limit``); the gains derived from a platform are (:mod:`qprr.control.gains`, "Integral action").

Gains: :class:`IDCGains` (per-coordinate vectors); under exact linearisation each error obeys
e''' + k_D e'' + k_P e' + k_I e = 0 whatever the platform, so the defaults suit any platform.
The thesis's printed tables are in :mod:`qprr.thesis.gains`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sized
from dataclasses import dataclass
from enum import Enum

import numpy as np
import pinocchio as pin

from ..actuation import Allocator
from ..charts import State
from ..dynamics.friction import JointFriction
from ..errors import InputError, UnknownNameError
from ..model import Platform, check_platform
from ..payload import MassEstimator, PayloadModel
from ..validation import as_array, as_real, as_vector
from .base import Controller, Reference, check_reset, not_reset
from .filters import SingleTiltReference, TiltReference

_PI = math.pi
_TWO_PI = 2.0 * math.pi
_rnea, _crba = pin.rnea, pin.crba

TILTS = ("split", "single", "none")
MODEL_STATES = ("measured", "desired")


def _gain_vector(x, n: int, name: str) -> tuple[float, ...]:
    a = as_vector(x, n, name)
    if np.any(a < 0):
        raise InputError(f"{name} must be >= 0, got {a.tolist()}")
    return tuple(float(v) for v in a)


class AntiWindup(str, Enum):
    """How the integrals of :class:`IDCGains` (k_I > 0) are kept from winding up against the actuator bounds.

    ``NONE``: plain integration (the thesis's PIDs, flown as printed or retuned).  ``CONDITIONAL``: a coordinate stops
    integrating while its command saturates, judged on the controller's own output of the previous tick (one tick
    late, 1 ms in the default loop): an arm joint j while |tau_j| exceeds its effort limit and its error would push the
    integral further the same way; the six base coordinates while the exact allocation of the base wrench
    (f = Omega_P^+ w_P, :class:`qprr.actuation.Allocator`'s first try) leaves a rotor outside [f_min, f_max].  Either
    way :attr:`IDCGains.integral_limit` clamps what each integral contributes.
    """

    NONE = "none"
    CONDITIONAL = "conditional"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class IDCGains:
    """Per-coordinate gains of the outer loops, order x, y, z, phi, theta, psi, then the arm joints.

    ``kp``, ``kd``, ``ki``: tuples of 6 + n_arm values >= 0; ``filter_omega`` [rad/s]: bandwidth
    of the roll/pitch command filter; ``max_tilt`` [rad]; ``anti_windup`` (:class:`AntiWindup`, default
    none); ``integral_limit``: per coordinate the largest |k_I int e| the integral may add to alpha
    (m/s^2, rad/s^2 or m/s^2 of a prismatic joint; inf: no clamp, the default), the clamp of the
    anti-windup.  Build with :meth:`default` (any platform) or :meth:`from_groups`; the thesis's
    tables: :mod:`qprr.thesis.gains`; derived from a platform: :func:`qprr.control.gains.idc_gains`.
    """

    kp: tuple[float, ...]
    kd: tuple[float, ...]
    ki: tuple[float, ...]
    filter_omega: float = 50.0
    max_tilt: float = 0.8
    anti_windup: AntiWindup = AntiWindup.NONE
    integral_limit: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        n = len(self.kp) if isinstance(self.kp, Sized) and not isinstance(self.kp, str) else -1
        if n < 6:
            raise InputError(f"kp must have 6 + n_arm entries, got {self.kp!r}")
        for name in ("kp", "kd", "ki"):
            object.__setattr__(self, name, _gain_vector(getattr(self, name), n, name))
        if self.anti_windup not in tuple(AntiWindup):
            raise UnknownNameError("anti-windup", self.anti_windup, tuple(a.value for a in AntiWindup))
        object.__setattr__(self, "anti_windup", AntiWindup(self.anti_windup))
        limit = (math.inf,) * n if self.integral_limit is None else self.integral_limit
        limit = np.asarray(as_array(limit, "integral_limit"), dtype=float)
        if limit.shape != (n,) or not np.all(limit > 0.0):  # NaN fails too
            raise InputError(f"integral_limit must be {n} values > 0, one per coordinate (m/s^2 or rad/s^2; inf: no clamp), got {limit.tolist()}")
        object.__setattr__(self, "integral_limit", tuple(float(v) for v in limit))
        object.__setattr__(self, "filter_omega", as_real(self.filter_omega, "filter_omega", positive=True, unit="rad/s"))
        object.__setattr__(self, "max_tilt", as_real(self.max_tilt, "max_tilt", positive=True, unit="rad"))
        if not self.max_tilt < math.pi / 2:
            raise InputError(f"max_tilt must be < pi/2 rad, got {self.max_tilt!r}")

    @property
    def n_xi(self) -> int:
        return len(self.kp)

    @classmethod
    def from_groups(cls, n_arm: int, position=(4.0, 4.0, 0.0), attitude=(300.0, 30.0, 1000.0), arm=(36.0, 12.0, 0.0), **kwargs) -> IDCGains:
        """Gains from (k_P, k_D, k_I) per group: ``position`` (x, y, z), ``attitude`` (phi, theta, psi), ``arm``.

        Each group entry may be a number (all coordinates of the group) or a tuple per coordinate.
        """

        def expand(v, n):
            a = np.broadcast_to(as_array(v, "gain"), (n,))
            return tuple(float(x) for x in a)

        kp = expand(position[0], 3) + expand(attitude[0], 3) + expand(arm[0], n_arm)
        kd = expand(position[1], 3) + expand(attitude[1], 3) + expand(arm[1], n_arm)
        ki = expand(position[2], 3) + expand(attitude[2], 3) + expand(arm[2], n_arm)
        return cls(kp=kp, kd=kd, ki=ki, **kwargs)

    @classmethod
    def default(cls, n_arm: int) -> IDCGains:
        """Defaults for any platform: position (s + 2)^2 (k_P = 4, k_D = 4), attitude (s + 10)^3
        (k_P = 300, k_D = 30, k_I = 1000: five times faster than the position loop, as a cascade
        needs), arm (s + 6)^2 (k_P = 36, k_D = 12).  Critically damped error dynamics."""
        return cls.from_groups(n_arm)

    @classmethod
    def desired_state_default(cls, n_arm: int) -> IDCGains:
        """Defaults of the desired-state controller: those of :meth:`default` with the arm at (s + 50)^2
        and the roll/pitch reference filter at 20 rad/s.

        The model is evaluated at the desired state, so its gravity term cancels G(q_d), not G(q): the
        mismatch dG/dq (q - q_d) acts on the arm as a stiffness of either sign (negative for an arm
        standing above B, an inverted pendulum), which the arm loop must dominate; measured on the
        Q-PRR and the hextilt, (s + 6)^2 lets the arm drift by radians, (s + 50)^2 tracks.
        """
        return cls.from_groups(n_arm, arm=(2500.0, 100.0, 0.0), filter_omega=20.0)

    def characteristic_polynomials(self, names=None) -> dict[str, np.ndarray]:
        """Closed-loop error polynomial per coordinate under exact linearisation: [1, k_D, k_P, k_I] (or [1, k_D, k_P])."""
        names = names or tuple(f"xi{i}" for i in range(self.n_xi))
        return {n: (np.array([1.0, kd, kp, ki]) if ki > 0.0 else np.array([1.0, kd, kp])) for n, kp, kd, ki in zip(names, self.kp, self.kd, self.ki)}

    def unstable_axes(self, names=None) -> list[str]:
        """Coordinates whose error polynomial is not Hurwitz (Routh: cubic needs k_D, k_I > 0 and k_D k_P > k_I; quadratic k_D, k_P > 0)."""
        bad = []
        for n, c in self.characteristic_polynomials(names).items():
            ok = (c[1] > 0 and c[2] > 0 and c[3] > 0 and c[1] * c[2] > c[3]) if len(c) == 4 else (c[1] > 0 and c[2] > 0)
            if not ok:
                bad.append(n)
        return bad


@dataclass(frozen=True)
class PayloadAwareness:
    """What the model of an inverse-dynamics controller knows of a payload at the end effector (Thesis Sec. 6.4).

    ``announced``: ((time [s], mass [kg]), ...) in time order: from each time on the model carries that mass (a
    mission's payload events told to the controller: the known-mass model (6.40)); ``estimate``: the mass is estimated
    online from the torque residual instead (:class:`~qprr.payload.MassEstimator`, Sec. 6.4.2, forgetting with
    ``time_constant`` [s]; it takes the commanded force as the applied one).  ``com_ee`` [m]: the payload's point in
    the end-effector frame.  Without it (``payload_awareness=None``) the model is the nominal one and an unannounced
    payload is left to the integral action (:class:`IDCGains`' k_I).
    """

    announced: tuple[tuple[float, float], ...] = ()
    estimate: bool = False
    time_constant: float = 0.05
    com_ee: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        events = []
        for k, ev in enumerate(self.announced):
            if not isinstance(ev, (tuple, list)) or len(ev) != 2:
                raise InputError(f"PayloadAwareness.announced[{k}] must be a pair (time [s], mass [kg]), got {ev!r}")
            events.append((as_real(ev[0], f"announced[{k}] time", nonnegative=True, unit="s"), _mass(ev[1], f"announced[{k}] mass")))
        if [t for t, _ in events] != sorted(t for t, _ in events):
            raise InputError(f"PayloadAwareness.announced must be in time order, got times {[t for t, _ in events]}")
        if events and self.estimate:
            raise InputError("PayloadAwareness: give announced payload events or estimate=True, not both (the estimate would replace them)")
        object.__setattr__(self, "announced", tuple(events))
        object.__setattr__(self, "estimate", bool(self.estimate))
        object.__setattr__(self, "time_constant", as_real(self.time_constant, "time_constant", positive=True, unit="s"))
        object.__setattr__(self, "com_ee", tuple(float(v) for v in as_vector(self.com_ee, 3, "com_ee")))

    def mass_at(self, t: float) -> float:
        """The announced mass [kg] at ``t`` [s] (the last event at or before t, within 1e-12 s as the simulator applies them)."""
        t = as_real(t, "t", unit="s")
        m = 0.0
        for time, mass in self.announced:
            if time <= t + 1e-12:
                m = mass
        return m


class InverseDynamicsController(Controller):
    """The inverse-dynamics core (module docstring): u = B_hat alpha + C_hat xi_dot + G_hat (+ feedforward).

    Parameters
    ----------
    platform : the platform controlled (its model is copied when a payload model is used).
    gains : :class:`IDCGains` (default :meth:`IDCGains.default`).
    at : "measured" (IDC) or "desired" (B, C, G at the desired state, Annex A.2).
    realizable : leave the unproducible base accelerations to the dynamics (module docstring).
    tilt : "split", "single" or "none" (default "split"; "none" on a fully actuated platform).
    output : "pinocchio" (return tau, the default at the measured state) or "xi" (return u).
    name : the name logged in results.
    """

    name = "idc"

    def __init__(
        self,
        platform: Platform,
        gains: IDCGains | None = None,
        *,
        at: str = "measured",
        realizable: bool = True,
        tilt: str | None = None,
        output: str | None = None,
        name: str | None = None,
        payload_awareness: PayloadAwareness | None = None,
    ) -> None:
        check_platform(platform)
        if payload_awareness is not None and not isinstance(payload_awareness, PayloadAwareness):
            raise InputError(f"payload_awareness must be a qprr.control.PayloadAwareness or None, got {type(payload_awareness).__name__}")
        if at not in MODEL_STATES:
            raise UnknownNameError("model state", at, MODEL_STATES)
        tilt = tilt or ("none" if platform.fully_actuated else "split")
        if tilt not in TILTS:
            raise UnknownNameError("tilt reference", tilt, TILTS)
        output = output or ("pinocchio" if at == "measured" else "xi")
        if output not in ("pinocchio", "xi"):
            raise UnknownNameError("controller output", output, ("pinocchio", "xi"))
        self.platform = platform
        self.gains = IDCGains.default(platform.n_arm) if gains is None else gains
        if not isinstance(self.gains, IDCGains):
            raise InputError(f"gains must be an IDCGains, got {type(self.gains).__name__}")
        if self.gains.n_xi != platform.n_xi:
            raise InputError(f"gains have {self.gains.n_xi} entries, the platform's xi has {platform.n_xi}")
        self.at = at
        self.realizable = bool(realizable)
        self.tilt_mode = tilt
        self.output = output
        if name is not None:
            self.name = name
        self.model = platform.model
        self.data = platform.model.createData()
        self._friction = JointFriction.from_model(platform.model)  # nominal joint friction of the URDF (None: none)
        self.payload_awareness = payload_awareness
        self._carried = None  # the model's payload (PayloadAwareness): a copy of the model whose end effector carries it
        self._estimator = None
        if payload_awareness is not None:
            self._carried = PayloadModel(platform, payload_awareness.com_ee)
            self.model, self.data = self._carried.model, self._carried.data
            if payload_awareness.estimate:
                self._estimator = MassEstimator(platform, time_constant=payload_awareness.time_constant, com_ee=payload_awareness.com_ee)
        self._guards(platform)
        self._zero6 = [0.0] * 6
        # base directions the rotors cannot produce (coplanar rotors: the body-lateral force)
        Omega = platform.rotor_matrix
        self._lost = [i for i in range(6) if np.abs(Omega[i]).max() <= 1e-12] if self.realizable else []
        contiguous = self._lost and self._lost == list(range(self._lost[0], self._lost[-1] + 1))
        self._lost_rows = slice(self._lost[0], self._lost[-1] + 1) if contiguous else self._lost  # a slice is 4x cheaper
        # hooks a configuration overrides (skipped in the loop when it does not)
        cls = type(self)
        self._refs_hook = cls.update_references is not InverseDynamicsController.update_references
        self._ff_hook = cls.feedforward is not InverseDynamicsController.feedforward
        self._task_hook = cls.task_accelerations is not InverseDynamicsController.task_accelerations
        self.dt = None  # the control period: set by reset(state, ref, dt), called by the simulator
        self._new_run()

    def _guards(self, platform: Platform) -> None:
        """The guarded integrals (:class:`AntiWindup` CONDITIONAL) of the base and of the arm, with what they are judged on."""
        g = self.gains
        on = g.anti_windup is AntiWindup.CONDITIONAL
        self._base_guard = tuple(i for i in range(6) if on and g.ki[i])
        limits = platform.arm_effort_limits
        self._arm_guard = tuple((6 + j, float(limits[j])) for j in range(platform.n_arm) if on and g.ki[6 + j] and math.isfinite(limits[j]))
        self._allocator = Allocator(platform) if self._base_guard else None
        Omega = platform.rotor_matrix
        self._rows_unproducible = [i for i in range(6) if np.abs(Omega[i]).max() <= 1e-12]  # rows the rotors cannot push along

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        """Start a run: the control period ``dt`` [s] (checked with the state and reference), then :meth:`_new_run`."""
        self.dt = check_reset(self, state, ref, dt)
        self._new_run()

    def _new_run(self) -> None:
        """Fresh per-run values (integrals, filters, buffers, caches); a configuration extends it for its own."""
        n = self.platform.n_xi
        self.integral = [0.0] * n
        self._windup = [0] * n  # AntiWindup: 0 integrate, +-1 the arm effort saturated that way, 2 the rotors saturated
        self._last_tick = None  # (q, v, tau) of the last tick, for the payload estimator
        if self._carried is not None:
            if self._estimator is not None:
                self._estimator.reset()
            self._carried.set_mass(self.payload_awareness.mass_at(0.0))
        g = self.gains
        uz_min = 0.05 * self.platform.total_mass * self.platform.g
        if self.tilt_mode == "split":
            self.tilt = TiltReference(g.filter_omega, g.max_tilt, uz_min)
        elif self.tilt_mode == "single":
            self.tilt = SingleTiltReference(g.filter_omega, g.max_tilt, uz_min)
        else:
            self.tilt = None
        self._g = self.platform.g
        self._started = False
        tilt_idx = (3, 4) if self.tilt is not None else ()
        self._loops_outer = self._alpha_plan(tuple(i for i in range(n) if i not in tilt_idx))
        self._loops_tilt = self._alpha_plan(tilt_idx)
        self._abuf = np.zeros(self.platform.nv)  # the accelerations handed to RNEA
        self._mass_key = None  # arm joints of the reused mass-matrix rows (desired state)
        self._mass_rows = None
        self._desired = State(self.platform.n_arm) if self.at == "desired" else None

    # ------------------------------------------------------------------ pieces
    def _alpha_plan(self, idx) -> tuple[tuple, tuple, tuple]:
        """Gains of the coordinates ``idx``: ((i, k_P, k_D) without integral action, ...),
        ((i, k_P, k_D, k_I) with plain integral action or yaw (wrapped error), ...),
        ((i, k_P, k_D, k_I, cap) with a guarded integral (:class:`AntiWindup`; |int e| <= cap = limit / k_I), ...)."""
        g = self.gains
        guarded = g.anti_windup is AntiWindup.CONDITIONAL or any(math.isfinite(v) for v in g.integral_limit)
        plain = tuple((i, g.kp[i], g.kd[i]) for i in idx if i != 5 and not g.ki[i])
        other = tuple((i, g.kp[i], g.kd[i], g.ki[i]) for i in idx if (i == 5 or g.ki[i]) and not (guarded and g.ki[i]))
        guard = tuple((i, g.kp[i], g.kd[i], g.ki[i], g.integral_limit[i] / g.ki[i]) for i in idx if guarded and g.ki[i])
        return plain, other, guard

    def _alpha_loops(self, x, xd, r, rd, rdd, plan, al: list[float], dt: float) -> list[float]:
        """Virtual accelerations (6.20), (6.23), (6.24), (A.3) of a plan into ``al`` (plain float lists; dt [s] for the integrals)."""
        plain, other, guard = plan
        for i, kp, kd in plain:  # PD: alpha = xi_ddot_d + k_D e_dot + k_P e
            al[i] = rdd[i] + kd * (rd[i] - xd[i]) + kp * (r[i] - x[i])
        integ = self.integral
        for i, kp, kd, ki in other:  # + k_I int e; the yaw error wrapped to [-pi, pi)
            e = r[i] - x[i]
            if i == 5:
                e = (e + _PI) % _TWO_PI - _PI
            a = rdd[i] + kd * (rd[i] - xd[i]) + kp * e
            if ki:
                integ[i] += e * dt
                a += ki * integ[i]
            al[i] = a
        hold = self._windup
        for i, kp, kd, ki, cap in guard:  # + k_I int e, integrated unless its command saturates (AntiWindup), clamped
            e = r[i] - x[i]
            if i == 5:
                e = (e + _PI) % _TWO_PI - _PI
            h = hold[i]  # 0: integrate; +-1: saturated that way, integrate only back; 2: rotors saturated, hold
            if h == 0 or (h != 2 and e * h < 0.0):
                integ[i] = min(cap, max(-cap, integ[i] + e * dt))
            al[i] = rdd[i] + kd * (rd[i] - xd[i]) + kp * e + ki * integ[i]
        return al

    def _saturation(self, tau: np.ndarray) -> None:
        """Which guarded integrals hold at the next tick (:class:`AntiWindup` CONDITIONAL), from the Pinocchio force ``tau``
        this tick commands: the base ones while the exact allocation leaves a rotor outside its bounds, an arm joint's
        while its effort exceeds the limit (then +1 or -1: the sign of the excess)."""
        hold = self._windup
        if self._base_guard:
            alloc = self._allocator
            f = alloc.Omega_P_inv.dot(tau[alloc.rows])
            h = 0 if (np.all(alloc.f_min <= f) and np.all(f <= alloc.f_max)) else 2
            for i in self._base_guard:
                hold[i] = h
        for i, limit in self._arm_guard:
            t = float(tau[i])
            hold[i] = 1 if t > limit else (-1 if t < -limit else 0)

    def _model_state(self, state: State, r: list, rd: list) -> State:
        """State at which B, C, G are evaluated: the measured one, or the desired one (Annex A.2)."""
        if self._desired is None:
            return state
        xi_d, xi_dot_d = list(r), list(rd)
        if self.tilt is not None:
            if self._started:  # roll/pitch of the desired state: the (6.17) references of the last step
                xi_d[3], xi_d[4] = self.tilt.x
                xi_dot_d[3], xi_dot_d[4] = self.tilt.xd
            else:  # first step: none yet, use the measured tilt
                x = state.xi_floats
                xi_d[3], xi_d[4] = x[3], x[4]
        self._desired.set_from_xi(state.t, xi_d, xi_dot_d, False, True)  # arrays=False, reuse=True
        return self._desired

    def update_references(self, t: float, state: State, ref: Reference) -> None:
        """Change ``ref`` in place before the outer loops (default: nothing; impedance filters do)."""

    def feedforward(self, t: float, state: State) -> list[float] | None:
        """Generalised force (thesis coordinates) added to the model's output (default: none)."""
        return None

    def task_accelerations(self, t: float, state: State, ref: Reference, a: list[float], ff: list[float] | None) -> list[float] | None:
        """A change of the accelerations the loops have set (default: None, no change); the operational-space
        impedance adds its end-effector task here.

        ``a``: Pinocchio's acceleration the inverse dynamics would realise (nv floats), before the base
        directions the rotors cannot push along are left to the dynamics; ``ff``: the feedforward in
        Pinocchio coordinates (nv floats) or None.  Returns the change (nv floats) or None.  With a tilt
        strategy it is called twice per step: before (6.17), whose thrust direction then includes the
        change, with the roll/pitch accelerations not set yet, and after them (a correction (6.17) does
        not see); without, once.
        """
        return None

    def _mass_rows_of(self, ms: State, model, data, q) -> list:
        """Rows of M for the unproducible base directions; at the desired state reused while its arm joints are unchanged.

        M (CRBA, local convention) depends on the arm joints only, so at a held desired arm
        pose the rows of the previous step are exact."""
        if self._desired is not None:
            key = np.array([*ms.xi_floats[6:], self.payload_mass]).tobytes()  # the arm joints bit for bit (-0.0 is not 0.0), the payload
            if key != self._mass_key:
                self._mass_rows = _crba(model, data, q)[self._lost_rows, 0:6].tolist()
                self._mass_key = key
            return self._mass_rows
        return _crba(model, data, q)[self._lost_rows, 0:6].tolist()  # Pinocchio 3+: full symmetric matrix

    # ------------------------------------------------------------------ step
    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """u = B alpha + C xi_dot + G with alpha from the outer loops and roll/pitch from (6.17)."""
        dt = self._dt  # the control period (read once: this runs every tick)
        if dt is None:
            raise not_reset(self)
        if self._carried is not None:
            self._update_payload(t, state, dt)
        if self._refs_hook:
            self.update_references(t, state, ref)
        x, xd = state.xi_floats, state.xi_dot_floats
        r, rd, rdd = ref.xi.tolist(), ref.xi_dot.tolist(), ref.xi_ddot.tolist()
        ms = self._model_state(state, r, rd)
        model, data, q, v = self.model, self.data, ms.q, ms.v
        alpha = self._alpha_loops(x, xd, r, rd, rdd, self._loops_outer, [0.0] * len(r), dt)
        a = ms.accel_to_v_list(alpha)
        abuf = self._abuf
        ff = self.feedforward(t, state) if self._ff_hook else None
        ffv = None if ff is None else ms.force_from_xi(ff).tolist()
        tilt = self.tilt
        if self._task_hook and tilt is not None:  # first pass, seen by (6.17): roll/pitch accelerations not set yet
            da = self.task_accelerations(t, state, ref, a, ffv)
            if da is not None:
                a = [ai + di for ai, di in zip(a, da)]
        if tilt is not None:
            abuf[...] = a  # a buffer RNEA only reads
            t0 = _rnea(model, data, q, v, abuf).tolist()
            u_fb = ms.lin_to_world(t0[0:3])  # u_fb of (6.21) at alpha_phi = alpha_theta = 0: R times RNEA's body force
            if ff is not None:
                u_fb = (u_fb[0] + ff[0], u_fb[1] + ff[1], u_fb[2] + ff[2])
            tilt.update(x[5], u_fb, rdd[0:3], self._g, dt)
            tilt.write(ref)
            self._started = True
            r[3], r[4] = tilt.x
            rd[3], rd[4] = tilt.xd
            rdd[3], rdd[4] = tilt.xdd
            self._alpha_loops(x, xd, r, rd, rdd, self._loops_tilt, alpha, dt)
            # omega_dot change of the roll/pitch accelerations: T [alpha_phi, alpha_theta, 0] (State.euler_accel_to_omega_dot)
            a3, a4 = alpha[3], alpha[4]
            sf, cf = ms.sf, ms.cf
            d3, d4, d5 = a3, cf * a4, -sf * a4  # T(phi, theta) [a3, a4, 0]
        else:
            d3 = d4 = d5 = 0.0
        if self._task_hook:  # (second pass with) the roll/pitch accelerations
            da = self.task_accelerations(t, state, ref, [a[0], a[1], a[2], a[3] + d3, a[4] + d4, a[5] + d5, *a[6:]], ffv)
            if da is not None:
                a = [ai + di for ai, di in zip(a, da)]
                if tilt is not None:
                    abuf[...] = a
                    t0 = _rnea(model, data, q, v, abuf).tolist()
        if self._lost:
            # base accelerations along the unproducible directions chosen so that the applied
            # wrench has no component there: (tau0 + M delta)[lost] = 0, with M[lost, lost] = m I
            # (the free flyer's translational block) and delta zero elsewhere but the attitude change
            if tilt is None:
                abuf[...] = a
                t0 = _rnea(model, data, q, v, abuf).tolist()
            rows = self._mass_rows_of(ms, model, data, q)
            if ffv is not None:  # the feedforward is applied too: its unproducible part is left to the dynamics as well
                t0 = [ti + fi for ti, fi in zip(t0, ffv)]
            for i, row in zip(self._lost, rows):
                a[i] -= (t0[i] + row[3] * d3 + row[4] * d4 + row[5] * d5) / row[i]
        a[3] += d3
        a[4] += d4
        a[5] += d5
        abuf[...] = a
        tau = _rnea(model, data, q, v, abuf)
        if self._friction is not None:  # the URDF's joint friction (F_v of (5.36), Coulomb): feedforward at the reference arm rates
            tau = tau - self._friction.generalized_force(self._zero6 + rd[6:])
        if self._base_guard or self._arm_guard or self._estimator is not None:
            self._after_step(state, tau if ff is None else tau + np.array(ffv))
        if self.output == "pinocchio":
            if ff is not None:
                tau = tau + np.array(ffv)
            return tau
        u = ms.force_to_xi_list(tau)
        if ff is not None:
            u = [ui + fi for ui, fi in zip(u, ff)]
        return np.array(u)

    def _update_payload(self, t: float, state: State, dt: float) -> None:
        """The model's payload at this tick (:class:`PayloadAwareness`): the announced mass, or the estimate updated with
        the last tick's step (Sec. 6.4.2)."""
        if self._estimator is None:
            m = self.payload_awareness.mass_at(t)
            if m != self._carried.mass:
                self._carried.set_mass(m)
        elif self._last_tick is not None:
            q0, v0, tau0 = self._last_tick
            self._carried.set_mass(self._estimator.update(q0, v0, tau0, state.v, dt))

    def _after_step(self, state: State, tau: np.ndarray) -> None:
        """What the next tick needs of this one's command ``tau`` (Pinocchio force): the anti-windup's saturation, the
        estimator's step (the rows no rotor produces set to zero: they are not applied)."""
        self._saturation(tau)
        if self._estimator is not None:
            applied = np.array(tau, dtype=float)
            applied[self._rows_unproducible] = 0.0
            self._last_tick = (state.q.copy(), state.v.copy(), applied)

    @property
    def payload_mass(self) -> float:
        """The payload mass [kg] the model carries now (0 without :class:`PayloadAwareness`)."""
        return 0.0 if self._carried is None else self._carried.mass


class DesiredStateInverseDynamics(InverseDynamicsController):
    """Inverse dynamics evaluated at the desired state, Thesis Annex A.2 (A.2)-(A.3) (the thesis's "MPC").

    u = B(xi_d) y + C(xi_d, xi_dot_d) xi_dot_d + G(xi_d), y = xi_ddot_d + K_D e_dot + K_P e (A.3); the
    desired roll and pitch are those of (6.17) (the previous step's filtered values enter the
    model, the current ones the feedback).  Returns u in thesis coordinates: tau is computed at
    the desired state, so u = S_d^T tau_d is what applies.
    """

    name = "dsid"

    def __init__(self, platform: Platform, gains: IDCGains | None = None, **kwargs) -> None:
        if gains is None and isinstance(platform, Platform):
            gains = IDCGains.desired_state_default(platform.n_arm)
        super().__init__(platform, gains, at="desired", **kwargs)


# ======================================================================= Sec. 6.4 layered
class LayeredIDC(InverseDynamicsController):
    """The layered inverse dynamics of Thesis Sec. 6.4: u = B_hat alpha + C_hat xi_dot + G_hat - u_e(h), (6.53)-(6.57), (6.76).

    The core with ``tilt="single"``, ``realizable=False``, output in thesis coordinates, the
    model of :class:`~qprr.payload.PayloadModel` (a copy whose end-effector link carries a
    payload mass, zero here) and, with sensors, the measured interaction cancelled:
    ``ee_sensor(t) -> h`` (6,) world wrench on the end effector, ``base_sensor(t) -> h_b`` (4,)
    generalised force on [x, y, z, psi]; u += -u_e(h) (Thesis (6.76)), u_e = S^T J_e^T h (6.59)
    + h_b.  A wrist sensor read inside the loop is one step late; cancelling it unfiltered against
    a stiff contact makes a limit cycle, which ``sensor_filter`` [rad/s] (first-order low-pass,
    exact ZOH step) removes.  Named "layered-idc-ft" when it compensates a sensor.
    """

    name = "layered-idc"

    def __init__(
        self,
        platform: Platform,
        gains: IDCGains | None = None,
        *,
        ee_sensor: Callable[[float], np.ndarray] | None = None,
        base_sensor: Callable[[float], np.ndarray] | None = None,
        compensate: bool = True,
        sensor_filter: float | None = None,
        com_ee=(0.0, 0.0, 0.0),
    ) -> None:
        check_platform(platform)
        if sensor_filter is not None:
            sensor_filter = as_real(sensor_filter, "sensor_filter", positive=True, unit="rad/s")
        for label, sensor in (("ee_sensor", ee_sensor), ("base_sensor", base_sensor)):
            if sensor is not None and not callable(sensor):
                raise InputError(f"{label} must be None or a callable t -> wrench, got {sensor!r}")
        self.sensor_filter = sensor_filter
        self.ee_sensor = ee_sensor
        self.base_sensor = base_sensor
        self.compensate = bool(compensate)
        self.pm = PayloadModel(platform, com_ee)
        super().__init__(platform, gains, tilt="single" if not platform.fully_actuated else "none", realizable=False, output="xi")
        self.model, self.data = self.pm.model, self.pm.data
        self._jdata = platform.model.createData()
        if ee_sensor is not None or base_sensor is not None:
            self.name = "layered-idc-ft" if compensate else "layered-idc"

    def _new_run(self) -> None:
        super()._new_run()
        self._h_f = None
        self._u_e = np.zeros(self.platform.n_xi)
        self._h_b = np.zeros(4)

    def measure(self, t: float, state: State) -> tuple[np.ndarray, np.ndarray]:
        """(h_b (4,), u_e (6 + n_arm,)) from the sensors: u_e = S^T J_e^T h_ee (6.59) + h_b on [x, y, z, psi]."""
        u_e = np.zeros(self.platform.n_xi)
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
                J = pin.computeFrameJacobian(self.platform.model, self._jdata, state.q, self.platform.ee_frame, pin.LOCAL_WORLD_ALIGNED)
                u_e = state.force_to_xi(J.T @ h)
        if self.base_sensor is not None:
            h_b = as_vector(self.base_sensor(t), 4, "base_sensor(t)")
            u_e[[0, 1, 2, 5]] += h_b
        return h_b, u_e

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        if self.ee_sensor is not None or self.base_sensor is not None:
            self._h_b, self._u_e = self.measure(t, state)
        return super().step(t, state, ref)

    def feedforward(self, t: float, state: State) -> list[float] | None:
        """-u_e(h) of (6.76) when compensating measured wrenches."""
        if self.compensate and (self.ee_sensor is not None or self.base_sensor is not None):
            return (-self._u_e).tolist()
        return None


PAYLOAD_MODES = ("estimate", "known", "none")


class PayloadIDC(LayeredIDC):
    """Layered IDC whose model carries the payload m_hat (estimated, known or none), Thesis (6.53)-(6.57).

    ``payload``: "estimate" (:class:`~qprr.payload.MassEstimator` on the torque residual),
    "known" (``known_mass``, the known-mass model (6.40)) or "none" (nominal model).
    ``mass_log`` records m_hat at every step.
    """

    def __init__(
        self,
        platform: Platform,
        gains: IDCGains | None = None,
        *,
        payload: str = "estimate",
        known_mass: float = 0.0,
        estimator: MassEstimator | None = None,
        com_ee=(0.0, 0.0, 0.0),
    ) -> None:
        check_platform(platform)
        if payload not in PAYLOAD_MODES:
            raise UnknownNameError("payload mode", payload, PAYLOAD_MODES)
        if estimator is not None and not isinstance(estimator, MassEstimator):
            raise InputError(f"estimator must be a qprr.payload.MassEstimator, got {type(estimator).__name__}")
        self.mode = payload
        self.known_mass = _mass(known_mass, "known_mass")
        self.estimator = estimator if estimator is not None else (MassEstimator(platform, com_ee=com_ee) if payload == "estimate" else None)
        self.mass_log: list[float] = []
        super().__init__(platform, gains, com_ee=com_ee)
        self.name = {"estimate": "payload-idc", "known": "payload-idc-known", "none": "payload-idc-none"}[payload]

    def set_known_mass(self, mass: float) -> None:
        """Change the known payload mass (mode "known"): e.g. a scheduled release the controller is told about."""
        self.known_mass = _mass(mass, "mass")

    def _new_run(self) -> None:
        super()._new_run()
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
            for i in self._unproducible:
                tau[i] = 0.0  # rotors produce no force there: applied = allocated (no saturation assumed)
            self._prev = (state.q.copy(), state.v.copy(), tau)
        self.mass_log.append(self.pm.mass)
        return u

    @property
    def _unproducible(self) -> list[int]:
        Omega = self.platform.rotor_matrix
        return [i for i in range(6) if np.abs(Omega[i]).max() <= 1e-12]


def _mass(m, name: str) -> float:
    return as_real(m, name, nonnegative=True, unit="kg")
