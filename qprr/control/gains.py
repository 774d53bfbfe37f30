"""Default gains derived from the platform: mass, inertia, actuator authority and bandwidth targets.

Every controller of :mod:`qprr.control` closes its loops on the exactly linearised error dynamics
of each thesis coordinate (x, y, z, phi, theta, psi, then the arm joints).  A coordinate with a
bandwidth ``w`` [rad/s] gets the critically damped pole placement

* the attitude: ``(s + w)^3 = s^3 + 3 w s^2 + 3 w^2 s + w^3``, i.e. ``k_D = 3 w``, ``k_P = 3 w^2``, ``k_I = w^3``;
* position and arm without an integral (the impedance filters' loops, :func:`idc_gains` by default):
  ``(s + w)^2 = s^2 + 2 w s + w^2``, i.e. ``k_D = 2 w``, ``k_P = w^2``;
* position and arm of the inverse-dynamics controllers (:func:`derive_idc`, :func:`derive_dsid`): the same double
  pole and an integral pole r times slower, ``(s + w)^2 (s + w_I)``, ``w_I = w / r``: ``k_D = 2 w + w_I``,
  ``k_P = w^2 + 2 w w_I``, ``k_I = w^2 w_I`` ("Integral action" below).

The bandwidths come from the actuator authority (:class:`Authority`, read from the platform at its
neutral configuration) and the error at which a loop may spend all of it (:class:`Targets`):

* position: ``w_a = sqrt(a / e_pos)`` with ``a = (sum f_max a_z - m g) / m`` the hover thrust
  margin per unit mass [m/s^2] (a P-term at the error ``e_pos`` asks for the whole margin);
* attitude (roll, pitch): ``w_t = sqrt(tau_k / (I_k e_att))`` with ``tau_k`` the torque the rotors
  add about body axis k around the hover thrusts (each rotor moves by at most
  ``min(f_max - f_h, f_h - f_min)``), ``I_k`` the base's rotational inertia at B;
* the cascade: the attitude loop runs ``ratio`` times faster than the position loop, so
  ``w_pos = min(w_a, w_t / ratio, cap / ratio)`` and ``w_att = ratio w_pos`` on roll and pitch;
  yaw gets ``min(ratio w_pos, sqrt(tau_z / (I_z e_att)))`` (drag torques are weak);
* each arm joint j: ``w_j = min(sqrt(effort_j / (M_jj e_arm)), w_att)`` with ``M_jj`` the joint's
  inertia in the mass matrix: no faster than the attitude loop, which must reject the arm's
  reaction on the base (measured on examples/my_platform with a 0.35 kg payload: arm poles at
  17 and 32 rad/s saturate the rotors on 73 % of the steps and the run diverges; at ``w_att``
  it holds).

The force-level gains (the impedance filters' M, D, K) are those bandwidths times the inertia
each coordinate moves: ``M = m`` (or ``I_z``, ``M_jj``), ``K = M w^2``, ``D = 2 M w`` (critically
damped); the end-effector impedance (``opspace-impedance``) has ``K = m w_pos^2`` with the desired
mass ``M_d = m / ratio^2`` (its own frequency is then ``w_att``; with ``M_d = m`` it was too slow to
reach a wall on borinot_flying_arm_2), critically damped, so scaling the masses, inertias and actuators by k scales them by k and leaves the
acceleration gains unchanged.

**Rotor lag.**  First-order rotors (``Targets.rotor_time_constant`` T > 0, e.g. ``qprr simulate
motor-lag``) bound two loops: ``w_att <= 0.1 / T`` (the attitude crossover, about 3 w_att for
(s + w)^3, then sees at most atan(0.3) = 17 deg of rotor lag; w_pos follows as w_att / ratio) and
the roll/pitch reference filter of (6.17) ``omega_f <= 0.075 / T`` (the controller's own default,
50 rad/s for the IDC family, is kept when smaller).  The filter is what diverged: its output's
acceleration feeds the attitude command with a gain up to omega_f^2, and the IDC's arm torques,
applied at once, react on the base while the rotors' counter-wrench lags, so the arm and the
attitude drive each other (measured, motor-lag on examples/my_platform at T = 5 ms: the error grows
by x2.4 every 2 ms from the first arm motion; on a 4 s run omega_f = 20 settles, 25 and 50 diverge;
at T = 10 ms 10 settles, 15 leaves 2.4 m errors).  With the bounds, motor-lag settles at T = 5, 10 and 20 ms on the Q-PRR,
borinot_flying_arm_2, HEX-RRR and examples/my_platform.  T = 0 (the default): no bound.

**Integral action.**  A constant disturbance (a payload the controller is not told about, a mean wind) leaves a PD
loop off by force / (inertia k_P); the integral removes it.  An unannounced payload multiplies what a loop moves by
mu (true over model inertia) and mu s^3 + k_D s^2 + k_P s + k_I is Hurwitz only while mu < k_D k_P / k_I =
(2 r + 1)(r + 2) / r: r = 2 on x, y, z (:data:`INTEGRAL_RATIO_POSITION`, margin 10: the total mass grows at most to
what the rotors lift, mu <= 4.7 on the registered platforms), r = 10 on the arm (:data:`INTEGRAL_RATIO_ARM`, margin
25: 0.4 kg at the Q-PRR's wrist makes theta3 17 times heavier; measured, r = 5 lets grasp-drop on the Q-PRR diverge).
Anti-windup: :class:`~qprr.control.inverse_dynamics.AntiWindup` ``CONDITIONAL`` (a coordinate stops integrating
while its command saturates the rotors or its joint's effort) and each integral's contribution clamped to the
acceleration the actuators give the coordinate (:func:`integral_limits`).  Measured (tests/test_integral_action.py):
0.4 kg and a 5 m/s wind leave < 1 mm at the end effector of the Q-PRR, borinot_flying_arm_2 and examples/my_platform
(15 to 370 mm without the position and arm integrals).  It is asked for with ``Targets(integral=True)`` (a gains file's
or a mission's ``[controller.targets] integral = true``) and is off by default: the integral poles this robustness
needs are slow (w / 10 on the arm), so what they hold is unwound slowly once the disturbance goes -- measured on the
3 s generic missions, after a release of 10 % of the mass the Q-PRR's and HEX-RRR's arms end 0.27-0.30 rad off (PD: on
the reference), and HEX-RRR's fly-to ends 4 cm off after the integral of its fast move; and beyond the margin (the
Q-PRR's grasp-drop holding 0.35 kg for 2 s at reach 0.3) the loop diverges where the PD only sags.

**MFC.**  The iPID (6.37) realises y'' = v only through its estimate F_est = y''_meas - alpha u_prev,
which a constant alpha makes a loop of its own: with beta = (B^-1)_ii the true inverse inertia and
T_c the control period, alpha u integrates (v - y'') at the rate g = beta / (alpha T_c), and the
error polynomial becomes s^4 + g s^3 + g k_D s^2 + g k_P s + g k_I, Hurwitz for (s + w)^3 gains only
when g > 9 w / 8.  beta changes with the arm's posture (examples/my_platform's turret: 116 to 34 500
kg^-1 m^-2 between the arm reached out and folded along the turret axis), so:

* ``alpha_i = (lambda / 1.5) max_q beta_i(q)``, lambda the largest eigenvalue of
  diag(1 / max beta) B^-1(q) over the workspace (:func:`workspace_inverse_inertia`, a grid of the
  joint ranges): the estimator's step matrix I - diag(1/alpha) B^-1 keeps its eigenvalues in
  (-0.5, 1) everywhere (contraction needs < 2; the class's rule reads alpha = 3 beta at the initial
  state only);
* ``w_i <= g_i / 4`` with ``g_i = min_q beta_i(q) / (alpha_i T_c)`` (``Targets.control_period``, 1 ms:
  the simulator's default step), on top of the bandwidths above.

On examples/my_platform the turret's g is 2.4 rad/s at 1 ms: its loop runs at 0.60 rad/s and
hover-reach tracks it to 0.20 rad RMSE (the class's K_P = 60, K_I = 8, K_D = 35: 0.24 rad, on the
edge of the quartic's stability; the previous derived (s + 9.6)^3: 1.2 rad, unstable); the limit
is the control period, 0.08 rad at 0.5 ms and 0.018 rad at 0.25 ms (``Targets(control_period=...)``
with ``simulate(..., dt=...)``).  On hover-reach the arm joints of the Q-PRR, borinot_flying_arm_2,
HEX-RRR and examples/my_platform (but its turret) track 5 to 75 times better (RMSE) than with the class's gains.

:func:`platform_gains` returns the constructor keyword arguments
of a controller (``make_controller(name, platform, **platform_gains(name, platform))``, which is
also :func:`qprr.control.make_controller`'s default);
:func:`load_gains` reads overrides from a TOML file; :func:`gain_lines` prints them.  The
thesis's printed tables are registered gain sets (:data:`qprr.registry.GAIN_TABLES`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..charts import rate_map
from ..errors import InputError, UnknownNameError
from ..model import Platform, check_platform
from ..validation import read_toml
from .impedance import ImpedanceGains
from .inverse_dynamics import AntiWindup, IDCGains
from .mfc import MFCGains
from .opspace_impedance import EndEffectorImpedance
from .registry import CONTROLLERS, GAIN_ARGUMENTS, NoGains, has_derived_gains


@dataclass(frozen=True)
class Targets:
    """Bandwidth targets: the errors at which a loop spends its whole authority, the cascade ratio, the cap.

    ``position_error`` [m], ``attitude_error`` [rad], ``arm_error`` [m or rad] (> 0); ``ratio``
    (>= 1): attitude bandwidth over position bandwidth; ``cap`` [rad/s]: the largest bandwidth of any
    loop (a fraction of the control rate; 1 kHz control: 40 rad/s keeps w dt < 0.05);
    ``rotor_time_constant`` T [s] (>= 0) of first-order rotors (0: instantaneous or unknown): when
    known it bounds the attitude loop and the roll/pitch reference filter (module docstring, "Rotor lag");
    ``control_period`` [s] (> 0): the period the MFC's estimator differences the rates over (the
    simulator's default step, 1 ms; module docstring, "MFC"); ``integral``: the inverse-dynamics controllers' position
    and arm loops get integral action with anti-windup (module docstring, "Integral action"; off by default).
    """

    position_error: float = 1.0
    attitude_error: float = 0.5
    arm_error: float = 0.5
    ratio: float = 5.0
    cap: float = 40.0
    rotor_time_constant: float = 0.0
    control_period: float = 1e-3
    integral: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.integral, bool):
            raise InputError(f"gain target integral must be true or false (integral action on position and arm), got {self.integral!r}")
        T = self.rotor_time_constant
        if not (isinstance(T, (int, float)) and math.isfinite(T) and T >= 0.0):
            raise InputError(f"gain target rotor_time_constant must be a finite number >= 0 s (0: instantaneous rotors), got {T!r}")
        for name in ("position_error", "attitude_error", "arm_error", "cap", "control_period"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0.0):
                raise InputError(f"gain target {name} must be a finite number > 0, got {v!r}")
        if not (isinstance(self.ratio, (int, float)) and math.isfinite(self.ratio) and self.ratio >= 1.0):
            raise InputError(f"gain target ratio must be a number >= 1 (attitude over position bandwidth), got {self.ratio!r}")


@dataclass(frozen=True)
class Authority:
    """What the actuators can do against what they move (SI): the inputs of the bandwidth formulas (module docstring).

    ``mass`` m [kg]; ``inertia`` (3,) diagonal of the base's rotational inertia at B, body axes [kg m^2];
    ``thrust_margin`` [N] (sum f_max a_z - m g); ``torque`` (3,) [N m] about the body axes around hover;
    ``arm_inertia`` (n_arm,) [kg m^2 or kg]; ``arm_effort`` (n_arm,) [N m or N] (inf: unlimited);
    ``inverse_inertia`` ((min, max), ...) per coordinate of xi: the range of (B^-1)_ii over the arm's
    workspace at level attitude (B = S^T M S, Thesis (5.53); x, y, z averaged as the MFC's alpha is)
    [1/kg or 1/(kg m^2)]; () when not measured (the MFC's gains need it); ``coupling``: the largest
    eigenvalue of diag(1 / max (B^-1)_ii) B^-1 over that workspace (:func:`workspace_inverse_inertia`).
    """

    mass: float
    inertia: tuple[float, float, float]
    thrust_margin: float
    torque: tuple[float, float, float]
    arm_inertia: tuple[float, ...]
    arm_effort: tuple[float, ...]
    inverse_inertia: tuple[tuple[float, float], ...] = ()
    coupling: float = 1.0

    @classmethod
    def from_platform(cls, platform: Platform) -> Authority:
        """Read at the neutral configuration: M = crba(q_neutral) (LOCAL), rotor bounds, arm effort limits."""
        platform = check_platform(platform)
        m = platform.total_mass
        M = pin.crba(platform.model, platform.data(), platform.neutral_q())
        A = np.asarray(platform.rotor_matrix)
        f_lo, f_hi = np.asarray(platform.thrust_min), np.asarray(platform.thrust_max)
        az = A[2]
        margin = float(np.sum(np.where(az > 0.0, f_hi * az, 0.0))) - m * platform.g
        if not margin > 0.0:
            raise InputError(
                f"the rotors cannot hover the platform (thrust margin {margin:.4g} N <= 0): no gains derive from "
                "its authority; raise f_max in the rotor file (or give the controller its gains= explicitly)"
            )
        hover = np.zeros(6)
        hover[2] = m * platform.g
        f_h = np.clip(np.linalg.pinv(A) @ hover, f_lo, f_hi)
        swing = np.minimum(f_hi - f_h, f_h - f_lo)
        torque = np.abs(A[3:6]) @ np.maximum(swing, 0.0)
        n = platform.n_arm
        return cls(
            m,
            tuple(float(v) for v in np.diag(M)[3:6]),
            margin,
            tuple(float(v) for v in torque),
            tuple(float(v) for v in np.diag(M)[6 : 6 + n]),
            tuple(float(v) for v in platform.arm_effort_limits),
            *workspace_inverse_inertia(platform),
        )

    def scaled(self, k: float) -> Authority:
        """Every mass, inertia, force and torque times ``k`` (a geometrically similar, k times heavier robot)."""
        return Authority(
            k * self.mass,
            tuple(k * v for v in self.inertia),
            k * self.thrust_margin,
            tuple(k * v for v in self.torque),
            tuple(k * v for v in self.arm_inertia),
            tuple(k * v for v in self.arm_effort),
            tuple((lo / k, hi / k) for lo, hi in self.inverse_inertia),
            self.coupling,
        )


WORKSPACE_SAMPLES = 256
"""Arm configurations (a grid, at most this many) over which :func:`workspace_inverse_inertia` reads B^-1."""


def workspace_inverse_inertia(platform: Platform) -> tuple[tuple[tuple[float, float], ...], float]:
    """The MFC's inputs over a grid of the arm's joint ranges at level attitude (B = S^T M S, Thesis (5.53)).

    Returns ((min, max) of (B^-1)_ii per coordinate of xi (x, y, z share their mean, as in the MFC's
    alpha), the largest eigenvalue of diag(1 / max_q (B^-1)_ii) B^-1(q) over the grid).  Each joint takes
    ``max(2, floor(WORKSPACE_SAMPLES^(1/n_arm)))`` values from its lower to its upper limit (neutral -+ pi
    where unlimited) and its neutral value.
    """
    platform = check_platform(platform)
    n = platform.n_arm
    q0 = platform.neutral_q()
    k = max(2, int(math.floor(WORKSPACE_SAMPLES ** (1.0 / n)))) if n else 1
    axes = [  # the neutral value too: a folded arm (the inertia about a joint smallest) is often there
        np.unique(np.append(np.linspace(lo if math.isfinite(lo) else c - math.pi, hi if math.isfinite(hi) else c + math.pi, k), c))
        for lo, hi, c in zip(platform.arm_lower, platform.arm_upper, q0[7:])
    ]
    S = rate_map(platform.neutral_xi())  # level base: the Euler-rate map at phi = theta = 0 (arm rows: identity)
    data = platform.data()
    inverses = []
    for q_arm in itertools.product(*axes) if n else [()]:
        q = q0.copy()
        q[7:] = q_arm
        inverses.append(np.linalg.inv(S.T @ pin.crba(platform.model, data, q) @ S))
    d = np.array([np.diag(Bi) for Bi in inverses])
    d[:, 0:3] = d[:, 0:3].mean(axis=1, keepdims=True)
    lo, hi = d.min(axis=0), d.max(axis=0)
    lam = max(float(np.linalg.eigvals(Bi / hi[:, None]).real.max()) for Bi in inverses)
    return tuple((float(a), float(b)) for a, b in zip(lo, hi)), lam


def bandwidths(authority: Authority, targets: Targets = Targets()) -> np.ndarray:
    """w [rad/s] per thesis coordinate (6 + n_arm), by the formulas of the module docstring."""
    a, t = authority, targets

    def w_of(force, inertia, error):
        return math.sqrt(force / (inertia * error)) if inertia > 0.0 and force > 0.0 else math.inf

    w_lift = w_of(a.thrust_margin, a.mass, t.position_error)
    w_tilt = min(w_of(a.torque[k], a.inertia[k], t.attitude_error) for k in (0, 1))
    w_pos = min(w_lift, w_tilt / t.ratio, t.cap / t.ratio, rotor_bound(ROTOR_LAG_ATTITUDE, t) / t.ratio)
    w_att = t.ratio * w_pos
    w_yaw = min(w_att, w_of(a.torque[2], a.inertia[2], t.attitude_error))
    w_arm = [min(w_of(e, i, t.arm_error), w_att) for e, i in zip(a.arm_effort, a.arm_inertia)]
    return np.array([w_pos] * 3 + [w_att, w_att, w_yaw] + w_arm)


ROTOR_LAG_ATTITUDE = 0.1
"""w_att T <= 0.1 when the rotor time constant T is known (module docstring, "Rotor lag")."""
ROTOR_LAG_FILTER = 0.075
"""omega_f T <= 0.075 for the roll/pitch reference filter when T is known (module docstring, "Rotor lag")."""


def rotor_bound(c: float, targets: Targets) -> float:
    """c / T [rad/s] with T the rotor time constant of ``targets`` (inf when T = 0: instantaneous rotors)."""
    T = targets.rotor_time_constant
    return c / T if T > 0.0 else math.inf


def tilt_filter(default: float, targets: Targets) -> float:
    """Bandwidth [rad/s] of the roll/pitch reference filter: the controller's ``default``, at most 0.075 / T."""
    return min(default, rotor_bound(ROTOR_LAG_FILTER, targets))


INTEGRAL_RATIO_POSITION = 2.0
"""With integral action the x, y, z error polynomial is (s + w)^2 (s + w / 2) (module docstring, "Integral action")."""
INTEGRAL_RATIO_ARM = 10.0
"""With integral action an arm joint's error polynomial is (s + w)^2 (s + w / 10) (module docstring, "Integral action")."""


def idc_gains(w: np.ndarray, *, integral: bool = False, **kwargs) -> IDCGains:
    """(s + w)^2 on position and arm, (s + w)^3 on the attitude (module docstring); with ``integral`` the position and arm
    polynomials get a slower integral pole, (s + w)^2 (s + w / r) with r = :data:`INTEGRAL_RATIO_POSITION` or
    :data:`INTEGRAL_RATIO_ARM`; ``kwargs`` to :class:`IDCGains` (the anti-windup's ``integral_limit``: :func:`integral_limits`)."""
    w = np.asarray(w, dtype=float)
    cubic = np.zeros(w.shape[0], dtype=bool)
    cubic[3:6] = True
    kp = np.where(cubic, 3.0 * w**2, w**2)
    kd = np.where(cubic, 3.0 * w, 2.0 * w)
    ki = np.where(cubic, w**3, 0.0)
    if integral:  # (s^2 + 2 w s + w^2)(s + w_I) = s^3 + (2 w + w_I) s^2 + (w^2 + 2 w w_I) s + w^2 w_I
        w_i = w / np.where(np.arange(w.shape[0]) < 3, INTEGRAL_RATIO_POSITION, INTEGRAL_RATIO_ARM)
        kp = np.where(cubic, kp, w**2 + 2.0 * w * w_i)
        kd = np.where(cubic, kd, 2.0 * w + w_i)
        ki = np.where(cubic, ki, w**2 * w_i)
    return IDCGains(kp=tuple(kp), kd=tuple(kd), ki=tuple(ki), **kwargs)


def integral_limits(authority: Authority) -> tuple[float, ...]:
    """The clamp of each integral of the derived IDC gains (:class:`~qprr.control.inverse_dynamics.AntiWindup`): the
    acceleration the actuators give the coordinate (module docstring, "Integral action"): thrust margin over mass on
    x, y, z, torque over inertia on the angles, effort over the joint's inertia M_jj on the arm (inf: no bound)."""
    if not isinstance(authority, Authority):
        raise InputError(f"authority must be a qprr.control.gains.Authority (Authority.from_platform), got {type(authority).__name__}")
    a = authority

    def ratio(force, inertia):
        return force / inertia if inertia > 0.0 and force > 0.0 else math.inf

    base = [ratio(a.thrust_margin, a.mass)] * 3 + [ratio(a.torque[k], a.inertia[k]) for k in range(3)]
    return tuple(base + [ratio(e, i) for e, i in zip(a.arm_effort, a.arm_inertia)])


def impedance_gains(authority: Authority, w: np.ndarray) -> ImpedanceGains:
    """Impedance filters (6.74)-(6.75) on (x, y, z, psi) and the arm: M = the moved inertia, K = M w^2, D = 2 M w."""
    m = np.array([authority.mass] * 3 + [authority.inertia[2]] + list(authority.arm_inertia))
    ww = np.concatenate([w[0:3], w[5:6], w[6:]])
    K, D = m * ww**2, 2.0 * m * ww
    return ImpedanceGains(
        M_base=tuple(m[:4]), D_base=tuple(D[:4]), K_base=tuple(K[:4]), M_arm=tuple(m[4:]) or 1.0, D_arm=tuple(D[4:]) or 1.0, K_arm=tuple(K[4:]) or 1.0
    )


MFC_EIGENVALUE = 1.5
"""The MFC's alpha puts the estimator's largest eigenvalue at 1.5 (< 2: contraction; module docstring, "MFC")."""
MFC_ESTIMATOR = 4.0
"""w_i <= g_i / 4 with g_i the slowest rate of the MFC's estimator (module docstring, "MFC")."""


def mfc_gains(authority: Authority, w: np.ndarray, targets: Targets) -> MFCGains:
    """iPID (6.37): (s + w_i)^3 per coordinate, w_i bounded by its estimator's rate; alpha from the workspace (module docstring, "MFC")."""
    if len(authority.inverse_inertia) != w.shape[0]:
        raise InputError(
            f"MFC gains need the inverse-inertia range of all {w.shape[0]} coordinates (Authority.from_platform reads it), "
            f"got {len(authority.inverse_inertia)}"
        )
    lo, hi = (np.array(v) for v in zip(*authority.inverse_inertia))
    alpha = (authority.coupling / MFC_EIGENVALUE) * hi
    g = lo / (alpha * targets.control_period)  # slowest estimator rate [rad/s], at the largest inertia
    w = np.minimum(w, g / MFC_ESTIMATOR)  # the iPID no faster than a quarter of its estimator
    f = tilt_filter(MFCGains.filter_omega, targets)
    return MFCGains(kp=tuple(3.0 * w**2), kd=tuple(3.0 * w), ki=tuple(w**3), alpha=tuple(alpha), filter_omega=f)


def derive_idc(authority: Authority, targets: Targets) -> dict[str, object]:
    """``idc``, ``layered-idc``, ``payload-idc`` (and ``decoupled``, :func:`derive_decoupled`): (s + w)^3 on the attitude, (s + w)^2 (s + w / r) with
    anti-windup on position and arm (module docstring, "Integral action"); the roll/pitch reference filter at the
    class's 50 rad/s unless the rotors lag."""
    w = bandwidths(authority, targets)
    return {"gains": idc_gains(w, filter_omega=tilt_filter(IDCGains.filter_omega, targets), **_integral_action(authority, targets))}


def _integral_action(authority: Authority, targets: Targets) -> dict[str, object]:
    """The keywords of :func:`idc_gains` that turn the integral action on when ``targets.integral`` asks for it (module
    docstring, "Integral action"), else none."""
    if not targets.integral:
        return {}
    return {"integral": True, "anti_windup": AntiWindup.CONDITIONAL, "integral_limit": integral_limits(authority)}


def derive_dsid(authority: Authority, targets: Targets) -> dict[str, object]:
    """``dsid``: the arm loop must dominate the gravity mismatch dG/dq (q - q_d): arm poles at the cap."""
    w = bandwidths(authority, targets)
    w[6:] = targets.cap
    return {"gains": idc_gains(w, filter_omega=tilt_filter(20.0, targets), **_integral_action(authority, targets))}


def _refuse_integral(targets: Targets, controller: str) -> None:
    """A derivation without integral action refuses ``targets.integral`` rather than fly without what was asked for."""
    if targets.integral:
        raise InputError(
            f"gain target integral = true: the derived gains of {controller} have no integral action to turn on (it is "
            "derived for idc, dsid, layered-idc and payload-idc); remove integral from the targets"
        )


def derive_decoupled(authority: Authority, targets: Targets) -> dict[str, object]:
    """``decoupled``: the IDC's gains (:func:`derive_idc`) without the integral action, which its per-joint loops would
    integrate with no anti-windup: ``targets.integral`` is refused."""
    _refuse_integral(targets, "decoupled")
    return derive_idc(authority, targets)


def derive_mfc(authority: Authority, targets: Targets) -> dict[str, object]:
    """``mfc``: :func:`mfc_gains` (module docstring, "MFC")."""
    _refuse_integral(targets, "mfc")
    return {"gains": mfc_gains(authority, bandwidths(authority, targets), targets)}


def derive_impedance(authority: Authority, targets: Targets) -> dict[str, object]:
    """``impedance``: the IDC's gains and the impedance filters (6.74)-(6.75) of :func:`impedance_gains`."""
    _refuse_integral(targets, "impedance")
    w = bandwidths(authority, targets)
    return {"gains": idc_gains(w, filter_omega=tilt_filter(IDCGains.filter_omega, targets)), "impedance": impedance_gains(authority, w)}


def derive_opspace_impedance(authority: Authority, targets: Targets) -> dict[str, object]:
    """``opspace-impedance``: the impedance only, K = m w_pos^2 with M_d = m / ratio^2 (its own frequency is w_att);
    its posture loops keep IDCGains.default (measured on borinot_flying_arm_2: derived posture loops at w_att with the
    end-effector task diverge in contact)."""
    _refuse_integral(targets, "opspace-impedance")
    w = bandwidths(authority, targets)
    return {"impedance": EndEffectorImpedance.from_frequency(w[3], 1.0, authority.mass / targets.ratio**2)}


def derive(controller: str, authority: Authority, targets: Targets) -> dict[str, object]:
    """Constructor keyword arguments of ``controller`` from an :class:`Authority` (no platform needed): the
    :class:`~qprr.control.registry.DerivedGains` of its entry in :data:`~qprr.control.registry.CONTROLLERS`."""
    entry = CONTROLLERS[controller]
    if not has_derived_gains(entry):
        raise InputError(f"controller {controller!r} has no gains derived from a platform: {entry.gains.reason}")
    kwargs = entry.gains.derive(authority, targets)
    if not isinstance(kwargs, dict) or set(kwargs) != set(entry.gains.arguments):
        got = sorted(kwargs) if isinstance(kwargs, dict) else type(kwargs).__name__
        raise InputError(f"the gain derivation of controller {controller!r} returned {got}, not its declared arguments {list(entry.gains.arguments)}")
    return kwargs


def platform_gains(controller: str, platform: Platform, targets: Targets | None = None, overrides: dict | None = None) -> dict[str, object]:
    """Keyword arguments of ``make_controller(controller, platform, ...)``: gains derived from ``platform`` (module docstring).

    ``targets``: :class:`Targets` (default: its defaults); ``overrides``: ``{argument: {field: value}}``
    replacing fields of the derived objects (e.g. ``{"gains": {"kp": [...]}}``; a number for a
    per-coordinate field applies to every coordinate).
    """
    if controller not in GAIN_ARGUMENTS:
        raise UnknownNameError("controller with platform-derived gains", controller, tuple(GAIN_ARGUMENTS))
    targets = Targets() if targets is None else targets
    if not isinstance(targets, Targets):
        raise InputError(f"targets must be a qprr.control.gains.Targets, got {type(targets).__name__}")
    kwargs = derive(controller, Authority.from_platform(platform), targets)
    for arg, fields in (overrides or {}).items():
        if arg not in kwargs:
            raise UnknownNameError(f"gain argument of {controller!r}", arg, tuple(kwargs))
        kwargs[arg] = replace_fields(kwargs[arg], fields, platform.n_xi, f"{controller}.{arg}")
    return kwargs


def replace_fields(obj, fields: dict, n_xi: int, where: str):
    """A copy of the dataclass ``obj`` with ``fields`` (a gains file's table: field -> value) replaced; an unknown field
    is refused with the valid ones, a number given for a per-coordinate field (a tuple of ``n_xi``) applies to every
    coordinate, a list becomes a tuple; the copy's own checks run (``__post_init__``).  ``where`` names the table."""
    if not isinstance(fields, dict):
        raise InputError(f"gain overrides of {where} must be a table of field = value, got {fields!r}")
    valid = tuple(f.name for f in dataclasses.fields(obj))
    changes = {}
    for name, value in fields.items():
        if name not in valid:
            raise UnknownNameError(f"field of {where}", name, valid)
        current = getattr(obj, name)
        if isinstance(current, tuple) and isinstance(value, (int, float)) and len(current) == n_xi:
            value = (float(value),) * n_xi
        changes[name] = tuple(value) if isinstance(value, list) else value
    return dataclasses.replace(obj, **changes)


def load_gains(source: str | Path | Mapping, controller: str, platform: Platform, where: str = "") -> dict[str, object]:
    """Constructor keyword arguments from a TOML file: ``[targets]`` (fields of :class:`Targets`) re-derives,
    then ``[<controller>.<argument>]`` tables replace fields (e.g. ``[idc.gains] kp = [...]``).

    A controller with no derived gains but settings a file may set (:class:`~qprr.control.registry.NoGains`'s
    ``settings``, e.g. ``[mpc.weights]``, ``[mpc.settings]``) gets those tables as dicts (its factory builds them).
    A file for another controller's tables only raises (it would silently change nothing).  ``source``: the file's
    path, or its tables as a mapping (a mission file's ``[controller]`` tables), called ``where`` in the messages."""
    if isinstance(source, Mapping):
        table, where = dict(source), where or "gains tables"
    else:
        path = Path(source)
        table, where = read_toml(path, "gains file", "a TOML file: [targets] and [<controller>.gains] tables"), f"gains file {str(path)!r}"
    settable = {n: e.gains.settings for n, e in CONTROLLERS.items() if isinstance(e.gains, NoGains) and e.gains.settings}
    valid = ("targets", *GAIN_ARGUMENTS, *settable)
    extra = [k for k in table if k not in valid]
    if extra:
        raise UnknownNameError(f"table of {where}", extra[0], valid)
    if controller in settable:
        return _settings_tables(where, table, controller, settable[controller])
    if set(table) - {"targets"} and controller not in table:
        raise InputError(
            f"{where} has tables for {sorted(set(table) - {'targets'})}, not for the controller {controller!r}: add a [{controller}.gains] table"
        )
    try:
        targets = Targets(**table.get("targets", {}))
    except TypeError as exc:
        raise InputError(f"{where}: [targets] takes {[f.name for f in dataclasses.fields(Targets)]} ({exc})") from exc
    return platform_gains(controller, platform, targets, table.get(controller))


def _settings_tables(where: str, table: dict, controller: str, names: tuple[str, ...]) -> dict[str, object]:
    """The ``[<controller>.<argument>]`` tables of a gains file (``where``) for a controller without derived gains (as dicts)."""
    if "targets" in table:
        raise InputError(
            f"{where}: [targets] does not apply to controller {controller!r}, which derives no gains from "
            f"bandwidth targets; set its {', '.join(f'[{controller}.{n}]' for n in names)} tables instead"
        )
    if controller not in table:
        raise InputError(f"{where} has no table for the controller {controller!r}: add [{controller}.{names[0]}]")
    mine = table[controller]
    for name, fields in mine.items():
        if name not in names:
            raise UnknownNameError(f"table of [{controller}] in {where}", name, names)
        if not isinstance(fields, dict):
            raise InputError(f"{where}: [{controller}.{name}] must be a table of field = value, got {fields!r}")
    return {name: dict(fields) for name, fields in mine.items()}


def gain_lines(kwargs: dict[str, object], names: tuple[str, ...]) -> list[str]:
    """Readable lines of a controller's gain arguments: one row per coordinate ``names`` (xi's names)."""
    lines = []
    for arg, obj in kwargs.items():
        if isinstance(obj, dict):  # a settings table of a controller without derived gains (:func:`load_gains`)
            lines.append(f"{arg}: the fields the file sets (the others at the class's defaults)")
            lines += [f"  {name} = {value}" for name, value in obj.items()]
            continue
        lines.append(f"{arg}: {type(obj).__name__}")
        fields = dataclasses.fields(obj) if dataclasses.is_dataclass(obj) else ()
        vectors = [f.name for f in fields if isinstance(getattr(obj, f.name), tuple) and len(getattr(obj, f.name)) == len(names)]
        if vectors:
            width = max(12, *(len(v) + 2 for v in vectors))  # a column as wide as its longest heading
            lines.append(f"  {'coordinate':<14}" + "".join(f"{v:>{width}}" for v in vectors))
            for i, n in enumerate(names):
                lines.append(f"  {n:<14}" + "".join(f"{getattr(obj, v)[i]:>{width}.5g}" for v in vectors))
        for f in fields:
            if f.name in vectors:
                continue
            value = getattr(obj, f.name)
            if isinstance(value, Enum):  # a setting by name (the anti-windup)
                lines.append(f"  {f.name} = {value.value}")
                continue
            shown = np.round(np.asarray(value, dtype=float), 6).tolist() if value is not None else None
            lines.append(f"  {f.name} = {shown}")
    return lines


__all__ = [
    "GAIN_ARGUMENTS",
    "MFC_ESTIMATOR",
    "MFC_EIGENVALUE",
    "ROTOR_LAG_ATTITUDE",
    "ROTOR_LAG_FILTER",
    "Authority",
    "Targets",
    "bandwidths",
    "derive",
    "derive_decoupled",
    "derive_dsid",
    "derive_idc",
    "derive_impedance",
    "derive_mfc",
    "derive_opspace_impedance",
    "gain_lines",
    "idc_gains",
    "impedance_gains",
    "integral_limits",
    "INTEGRAL_RATIO_ARM",
    "INTEGRAL_RATIO_POSITION",
    "load_gains",
    "mfc_gains",
    "platform_gains",
    "replace_fields",
    "rotor_bound",
    "tilt_filter",
    "workspace_inverse_inertia",
]
