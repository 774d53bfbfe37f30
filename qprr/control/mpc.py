"""Receding-horizon model predictive control (MPC) on crocoddyl, with the rotor thrust bounds.

Not in the thesis: the controller it calls "MPC" (Annex A.2) is inverse dynamics at the desired
state (qprr's ``dsid``) and optimises nothing over a horizon.  This one does, on the full
coupled model of any :class:`~qprr.model.Platform` (the same Pinocchio model the simulator
integrates), with its rotor set.  Install: ``pip install "qprr[mpc]"`` (crocoddyl 3.2.1 with
pin 4.0.x, the pair its wheel is compiled for; docs/mpc.md).

Optimal control problem, solved every MPC period h (default 10 ms, 100 Hz) over N nodes
(default 40: a 0.4 s horizon), from the measured state x_0 = (q, v):

    min  sum_{k<N} h l_k(x_k, u_k) + l_N(x_N)
    s.t. x_{k+1} = F_h(x_k, u_k),  the flow of a = ABA(q, v, W u) over h with u held, by crocoddyl's
         RK2 (default) or RK3/RK4 (``IntegratedActionModelRK``), or its semi-implicit Euler
         x_{k+1} = x_k (+) [h (v_k + h a_k), h a_k] (``integrator="euler"``);
         f_min,i <= u_k,i <= f_max,i (rotors),  |u_k,j| <= effort limit j (arm joints)

RK2 is the default because semi-implicit Euler advances the position with the end-of-step
velocity: its prediction leads by about h v / 2, and on the static mission's climb (2 m/s)
that showed as a 4.5 mm z error at h = 10 ms (2.2 mm at 5 ms, first order) against 0.8 mm
with RK2, RK3 or RK4.  RK2 costs two model evaluations per node.

* u = [f_1 .. f_n (rotor thrusts, N), arm efforts (N or N m)];  W (nv x nu) is crocoddyl's
  ``ActuationModelFloatingBaseThrusters`` built from the platform's rotors: rotor column
  [a_i; p_i x a_i + spin_i kappa_i a_i] (a_i axis, p_i position in B), identity on the arm
  joints.  It equals the platform's N of Thesis (5.44)-(5.46) (``Platform.actuation_matrix``,
  checked in tests/test_mpc.py for the Q-PRR and the hexarotors), so tau = W u is Pinocchio's
  generalised force.
* l_k = 1/2 sum of weighted squared residuals (:class:`MPCWeights`; by default the Q-PRR's tuned weights with the
  thrust weight relative to the platform's hover thrusts, :func:`platform_weights`):

  - ``state``: x_k (-) x_ref(t_k) in the tangent space (LOCAL): base position, attitude
    (roll/pitch and yaw weighted apart), arm joints and the velocities;
  - ``ee``: log6(M_ref^-1 M_ee(q)) of the end-effector pose (LOCAL), M_ref = FK(q_ref);
  - ``cog``: the offset of the system's centre of mass from the thrust axis, in the plane normal
    to it ([x_cm, y_cm] in B for coplanar rotors, Thesis (3.78); :func:`qprr.kinematics.cog_offset_body`);
    off by default (``MPCWeights.cog = 0``): on crocoddyl's native models it is the one Python
    residual and roughly doubles the solve time, against no measurable change of the static
    mission's tracking (docs/mpc.md, "Measured");
  - ``joint limits``: a quadratic barrier on each arm joint past its soft limit (the model's
    position limits, where the simulator has its mechanical stops; ``joint_limit_margin``
    moves them inside: 0 by default, as the static mission asks for r0 = 0.04 m, the stop);
  - ``control``: u - u_ref, u_ref = W^+ RNEA(q_ref, v_ref, a_ref) clipped to the bounds (the
    inputs that realise the reference acceleration; hover thrusts at rest).

  l_N: the state, end-effector, CoG and joint-limit terms times ``terminal_factor`` (no control term).
* References: the trajectory (thesis coordinates, any number of arm joints) sampled where each node's
  cost is evaluated (the simulator hands it over before the run: ``uses_preview``): the state and
  end-effector references of node k at t_k + h / 2 with the RK nodes (the mean time of crocoddyl's
  quadrature of the running cost; t_k with Euler; :data:`COST_TIME`), its control reference at
  t_k + h / 2 (the input is held over [t_k, t_k + h]), the terminal ones at t_N; roll and pitch
  are the feedforward tilt of Thesis (6.17) applied to the whole robot's centre-of-mass
  acceleration (z_B along c_ddot + g e3: the rotors are its only external force besides gravity),
  with the tilt's rates and accelerations by central differences (:meth:`MPCController.tilt`,
  ``MPCSettings.tilt_reference = "system"``); ``"base"``: along p_ddot_d + g e3 of the base, as the
  IDC's feedforward filter does, rates 0 (the behaviour before issue 35: on examples/my_platform's
  hover-reach its reference inputs could not realise the reference while the arm swung, and the
  MPC's position error was 20 times the IDC's; docs/mpc.md).
  Without a trajectory the current reference is extrapolated (second order) over the horizon.
  The feedforward tilt at the current time is written into ``ref`` (the logged roll/pitch
  references).
* Solver: crocoddyl's Box-FDDP (controls projected on the bounds in the line search, box-QP
  gains once the guess is feasible).  The bounds it plans with are shrunk by ``bound_margin``
  (1e-9 N) so that rounding in the allocator's exact path f = Omega_z^-1 w never reads a
  thrust planned on its bound as a violation.
* Warm start: the previous plan shifted by one node and rolled out from the measured state
  under the plan's own feedback gains (a dynamically feasible guess; see
  :meth:`MPCController._warm_start`).  The problem's nodes are rotated with
  ``ShootingProblem.circularAppend``: only the new last node and the terminal node get new
  references.  The first solve starts from the reference inputs with ``first_max_iter`` iterations.
* Zero-order hold: the controller is called by the 1 kHz simulator; it solves every
  round(h / dt) calls and returns the held tau = W u_0 in between (``output = "pinocchio"``).
  Inside the rotor bounds the simulator's allocator takes its exact path and applies
  f = u_0 (tested).  The solve happens at the sampling instant (no computation delay).

Status of every solve (:class:`SolveStatus`): ``converged`` (crocoddyl's stopping test met),
``iteration-limit`` (not converged within ``max_iter`` iterations but finite, inside the bounds
and dynamically feasible to ``feasibility_tol``: accepted, as real-time MPC does), ``failed``
(the solver raised, or the plan is non-finite, leaves the bounds or keeps dynamic gaps above
``feasibility_tol``).  A failed solve is not applied: the controller falls back
(:class:`Fallback`) to ``previous-plan`` (the last accepted plan, advanced to the current
time) while that plan covers the current time, else to ``hover`` (W^+ g(q) at the measured
configuration, clipped to the bounds); each fallback increments ``fallback_count`` and
records its time and reason in ``events``.  :meth:`MPCController.stats` returns every solve's
wall time, iterations, status and the margin of its planned thrusts to the rotor bounds.

Backends (``MPCSettings.backend``).  ``native``: every node is crocoddyl's compiled
``DifferentialActionModelFreeFwdDynamics`` with ``ActuationModelFloatingBaseThrusters`` and
crocoddyl's state, frame-placement and control residuals, plus one small residual for the CoG
term (:mod:`qprr.control.mpc_native`); ``python``: the same node written on pinocchio's Python
API (:mod:`qprr.control.mpc_reference`, the tested reference, about 6 times slower).  A crocoddyl
wheel paired with a pinocchio it was not compiled for reads pinocchio's ``Model`` at wrong
offsets without any error (crocoddyl 3.2.1 is built on pin 4.0; with pin 4.1 its dynamics lose
gravity and its frame residuals read garbage), so this module runs :func:`qprr.control.mpc_native.self_test`
once at import: when it fails, a ``RuntimeWarning`` names the installed versions and the fix
(:data:`FIX`), ``backend="auto"`` (the default) uses the Python models and ``backend="native"``
raises.  :attr:`MPCController.backend` and :meth:`MPCController.stats` say which was used.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, fields, replace

import numpy as np
import pinocchio as pin

from ..actuation import Allocator
from ..charts import State, euler_to_rotation, xi_ddot_to_a, xi_to_qv
from ..errors import InputError, MissingDependencyError, UnknownNameError
from ..model import Platform
from ..trajectory import Trajectory
from ..validation import as_int, as_real, as_vector
from .base import Controller, Reference, check_reset
from .filters import tilt_6_17
from .gains import Authority
from .mpc_stats import BACKENDS, INSTALL, Fallback, MPCStats, SolveStatus, chatter_fraction, health_warnings

try:
    import crocoddyl
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise MissingDependencyError("crocoddyl", "the receding-horizon MPC (qprr.control.mpc)", INSTALL) from exc

from . import mpc_native  # after the crocoddyl check (it needs crocoddyl)
from .mpc_reference import LieState, NodeSpec, PlatformDynamics

FIX = 'pip install "crocoddyl==3.2.1" "pin==4.0.*"'
"""Install command that restores a consistent crocoddyl / pinocchio pair (the ``mpc`` extra's pins)."""

NATIVE_PROBLEM = mpc_native.self_test()
""""" when crocoddyl's compiled models read the installed pinocchio correctly (checked once, at import), else what failed."""

if NATIVE_PROBLEM:
    warnings.warn(
        f"qprr.control.mpc: crocoddyl's compiled models do not read the installed pinocchio correctly ({mpc_native.versions()}: "
        f"{NATIVE_PROBLEM}); the MPC uses its Python models (about 6 times slower).  Fix: {FIX}",
        RuntimeWarning,
        stacklevel=2,
    )

INTEGRATORS = ("euler", "rk2", "rk3", "rk4")

TILT_REFERENCES = ("system", "base")
"""``MPCSettings.tilt_reference``: the acceleration the feedforward roll/pitch (6.17) is read from (:meth:`MPCController.tilt`)."""
E3_CROSS = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
"""The cross-product matrix of e3: E3_CROSS u = e3 x u (numpy's cross costs ten times more on 3-vectors)."""
TILT_STEP = 2e-3
"""Step [s] of the central differences that give the feedforward tilt's rates and accelerations (``"system"``)."""
TILT_AUTHORITY_SHARE = 0.1
"""The feedforward tilt's rates are used where its acceleration is at most this share of the rotors' roll/pitch torque
over the base's inertia (:class:`~qprr.control.gains.Authority`), else held at 0 (:meth:`MPCController._tilt_motion`).
Measured on aggressive-reach (Q-PRR, where the reference asks for free fall and then 0.8 rad): share 1 left 21 % of the
solves at the iteration limit and theta2 at 2.3e-2 rad RMSE, 0.1 12.7 % and 1.2e-2 rad ("base": 10.3 %, 1.1e-2 rad)."""
SYSTEM_TILT_PASSES = 10
"""At most this many passes of (6.17) on the system's centre-of-mass acceleration after the base's (:meth:`MPCController.tilt`)."""
SYSTEM_TILT_TOL = 1e-9
"""[rad] The passes stop once a pass changes the tilt by less (:meth:`MPCController.tilt`)."""

COST_TIME = {"euler": 0.0, "rk2": 0.5, "rk3": 0.5, "rk4": 0.5}
"""Where in its interval [t_k, t_k + h] a running node's cost is evaluated, as a fraction of h, per integrator.

crocoddyl's ``IntegratedActionModelRK`` charges h sum_i b_i l(x at stage i) with the stage times c_i h: RK2 (explicit
midpoint) b = (0, 1), c = (0, 1/2); RK3 b = (1/4, 0, 3/4), c = (0, 1/3, 2/3); RK4 b = (1/6, 1/3, 1/3, 1/6),
c = (0, 1/2, 1/2, 1) (c: crocoddyl 3.2.1's ``set_rk_type``; b: read off the stages' costs of one node): a quadrature
of the cost over the interval whose weighted mean time sum_i b_i c_i is 1/2 in all three.
``IntegratedActionModelEuler`` charges h l(x_k, u_k), at the interval's start (0).  The node's state and
end-effector references are sampled there (:meth:`MPCController._references`); tests/test_mpc.py checks it on a
constant-speed climb, planned exactly with RK2 and Euler."""


# ================================================================================ settings
def _positive(obj, names: tuple[str, ...], allow_zero: bool) -> None:
    for name in names:
        as_real(getattr(obj, name), f"{type(obj).__name__}.{name}", positive=not allow_zero, nonnegative=allow_zero)


@dataclass(frozen=True)
class MPCWeights:
    """Cost weights (each multiplies 1/2 r^2 of its residual entries; running costs are also times h).

    Units: 1/m^2 for positions, 1/rad^2 for angles, (s/m)^2, (s/rad)^2 for rates, 1/N^2 for
    thrusts; ``arm`` / ``arm_velocity`` apply to every arm joint in its own unit;
    ``arm_acceleration`` weights the acceleration tau_j / M_jj an arm effort deviation gives its
    own joint (s^4/m^2 or s^4/rad^2; M_jj: mass matrix diagonal at the neutral configuration);
    ``joint_limits`` weights an arm joint's overshoot past its soft limit (1/m^2 or 1/rad^2).
    With a joint weight q and this weight r, the joint's LQR bandwidth is about (q / r)^(1/4).
    ``tilt`` is roll and pitch of the base (x, y of the LOCAL rotation error), ``yaw`` its z.
    ``cog`` [1/m^2] weights the CoG's offset from the thrust axis (body frame); 0 (the default) leaves
    the term out (module docstring).

    These defaults were tuned on the thesis's Q-PRR (3.52 kg, 4 rotors); the controller's default weights on any
    platform are these mapped onto it by :func:`platform_weights` (the thrust weight relative to its hover thrusts).
    """

    position: float = 100.0
    tilt: float = 10.0
    yaw: float = 100.0
    arm: float = 1e4
    linear_velocity: float = 20.0
    angular_velocity: float = 1.0
    arm_velocity: float = 1.0
    ee_position: float = 10.0
    ee_orientation: float = 1.0
    cog: float = 0.0
    joint_limits: float = 1e6
    thrust: float = 1.0
    arm_acceleration: float = 1e-2
    terminal_factor: float = 10.0

    def __post_init__(self) -> None:
        _positive(self, tuple(f.name for f in fields(self)), allow_zero=True)


REFERENCE_HOVER_THRUST_SQUARED = 297.4258956816
"""|f_h|^2 [N^2], the squared norm of the hover thrusts (:meth:`qprr.actuation.Allocator.hover_thrusts`) of the platform the
defaults of :class:`MPCWeights` were tuned on: the thesis's Q-PRR (``qprr.load()``, 3.5196 kg on 4 rotors, 8.623 N
each; tests/test_mpc.py reads it from the model)."""


def platform_weights(platform: Platform, reference: MPCWeights | None = None) -> MPCWeights:
    """The MPC's default weights on ``platform``: ``reference`` (default :class:`MPCWeights`, tuned on the Q-PRR) with
    the thrust residuals measured relative to the platform's hover thrusts f_h (the rotor thrusts that hold it still,
    level, arm at 0: :meth:`qprr.actuation.Allocator.hover_thrusts`; m g / n each on n upright rotors under the CoM),

        thrust = thrust_ref |f_h,ref|^2 / |f_h|^2      (|f_h,ref|^2 = :data:`REFERENCE_HOVER_THRUST_SQUARED`),

    so that the cost w |u - u_ref|^2 is w_ref |f_h,ref|^2 |(u - u_ref) / |f_h||^2, a fraction of the platform's own hover
    thrust.  For n coplanar upright rotors under the CoM |f_h|^2 = (m g)^2 / n, and a collective force change dF spread over the
    rotors costs (thrust / n) dF^2 = thrust_ref |f_h,ref|^2 (dF / m g)^2: a collective acceleration dF / m costs what
    it costs the Q-PRR on every mass and rotor count (to the ratio of the gravities), and the LQR poles it places
    against the state weights are the Q-PRR's (a geometrically similar robot k times heavier,
    :meth:`~qprr.control.gains.Authority.scaled`, gets thrust / k^2 and the same closed loop).  The other weights are
    kept: they are in the units of the errors (m, rad, m/s, rad/s), whose acceptable sizes the bandwidth
    :class:`~qprr.control.gains.Targets` take the same on every platform, and the arm efforts are already weighted
    through the joint acceleration they give (tau_j / M_jj), which makes the arm's LQR bandwidth
    (arm / arm_acceleration)^(1/4) platform-independent.  On the Q-PRR this returns ``reference`` (the factor is 1 to
    rounding).  Measured on the 10 s hover-reach (docs/mpc.md, "Weights from the platform"): position and arm RMSE
    within 10 % of the Q-PRR's fixed weights on borinot_flying_arm_2 and examples/my_platform, no solve at the
    iteration limit.
    """
    reference = MPCWeights() if reference is None else reference
    if not isinstance(reference, MPCWeights):
        raise InputError(f"reference must be an MPCWeights (the weights to map onto the platform), got {type(reference).__name__}")
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform (the MPC's weights follow its hover thrusts), got {type(platform).__name__}")
    f_h = Allocator(platform).hover_thrusts()  # InputError naming the platform when its rotors cannot hover it
    norm2 = float(f_h @ f_h)
    return replace(reference, thrust=reference.thrust * REFERENCE_HOVER_THRUST_SQUARED / norm2)


@dataclass(frozen=True)
class MPCSettings:
    """Horizon, rate and solver settings.

    ``rate`` [Hz]: solves per second (the node spacing is h = 1 / rate); ``horizon``: number of
    nodes N (horizon N h); ``backend``: the node models, ``"native"`` (crocoddyl's compiled models;
    an error when their self-test failed), ``"python"`` (:mod:`qprr.control.mpc_reference`) or
    ``"auto"`` (native when the self-test passed, else python); ``threads``: crocoddyl's threads
    over the native nodes (``ShootingProblem.nthreads``; Python nodes run in one); 1 by default:
    its OpenMP threads spin at barriers, and beside the simulator on 2 shared cores 2 threads made
    each solve 3 times slower in CPU time and 4-5 times in wall time (docs/mpc.md); more is a
    request crocoddyl refuses, with a warning, once Python-derived models exist in the process;
    ``max_iter``: Box-FDDP iterations per solve; ``first_max_iter``: for the cold start;
    ``th_stop``: crocoddyl's stopping threshold; ``feasibility_tol``: largest
    dynamic gap of an accepted plan; ``bound_margin`` [N]: the thrust bounds are planned
    this far inside; ``max_tilt`` [rad]: clamp of the feedforward tilt (6.17);
    ``joint_limit_margin``: the arm joints' soft limits are the model's position limits shrunk by
    this fraction of their range (the simulator's mechanical stops sit at the limits);
    ``tilt_reference``: ``"system"`` (the roll/pitch reference points the thrust along the whole robot's centre-of-mass
    acceleration, with its rates) or ``"base"`` (along the base's, rates 0; the behaviour before issue 35), module
    docstring and :meth:`MPCController.tilt`;
    ``warn_iteration_limit``, ``warn_chatter``: a completed run whose solves stopped at the iteration limit, or whose
    inputs chattered (:func:`~qprr.control.mpc_stats.chatter_fraction`), on more than this fraction of the solves ends
    "completed with warnings" (:meth:`MPCController.run_warnings`).
    """

    rate: float = 100.0
    horizon: int = 40
    backend: str = "auto"
    threads: int = 1
    integrator: str = "rk2"
    max_iter: int = 10
    first_max_iter: int = 200
    th_stop: float = 1e-6
    feasibility_tol: float = 1e-3
    bound_margin: float = 1e-9
    max_tilt: float = 0.8
    init_reg: float = 1e-9
    joint_limit_margin: float = 0.0
    tilt_reference: str = "system"
    warn_iteration_limit: float = 0.05
    warn_chatter: float = 0.05

    def __post_init__(self) -> None:
        _positive(self, ("rate", "th_stop", "feasibility_tol", "max_tilt", "init_reg"), allow_zero=False)
        _positive(self, ("bound_margin",), allow_zero=True)
        if not as_real(self.joint_limit_margin, "MPCSettings.joint_limit_margin", nonnegative=True) < 0.5:
            raise InputError(f"MPCSettings.joint_limit_margin must be in [0, 0.5), got {self.joint_limit_margin!r}")
        for name in ("warn_iteration_limit", "warn_chatter"):
            if not 0.0 <= as_real(getattr(self, name), f"MPCSettings.{name}") <= 1.0:
                raise InputError(f"MPCSettings.{name} is a fraction of the solves, in [0, 1]; got {getattr(self, name)!r}")
        for name in ("horizon", "max_iter", "first_max_iter", "threads"):
            as_int(getattr(self, name), f"MPCSettings.{name}", lo=1)
        if self.backend not in ("auto", *BACKENDS):
            raise UnknownNameError("backend", self.backend, ("auto", *BACKENDS))
        if self.tilt_reference not in TILT_REFERENCES:
            raise UnknownNameError("tilt_reference", self.tilt_reference, TILT_REFERENCES)
        if self.integrator not in INTEGRATORS:
            raise UnknownNameError("integrator", self.integrator, INTEGRATORS)
        if not self.max_tilt < math.pi / 2:
            raise InputError(f"MPCSettings.max_tilt must be < pi/2 rad, got {self.max_tilt!r}")


# ================================================================================ platform
def _check_platform(platform: Platform) -> tuple[list, np.ndarray, np.ndarray]:
    """Crocoddyl thrusters and the input bounds (u_lb, u_ub) of ``platform``; finite bounds are required.

    (Rotor positions, unit axes, spins and kappa are validated by :class:`qprr.rotors.Rotor` and the
    free-flyer root by :class:`~qprr.model.Platform`.)
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    limits = np.array(platform.arm_effort_limits, dtype=float)
    bad = [j.name for j, e in zip(platform.arm, limits) if not (math.isfinite(e) and e > 0.0)]
    if bad:
        raise InputError(
            f"platform {platform.name!r}: the MPC needs finite effort limits > 0 on every arm joint; "
            f"joints {bad} have {[float(limits[platform.arm_names.index(b)]) for b in bad]}"
        )
    thrusters = []
    for i, r in enumerate(platform.rotors):
        if not math.isfinite(r.f_max):
            raise InputError(f"platform {platform.name!r}: rotor {i + 1} ({r.name!r}) has no finite f_max; the MPC needs thrust bounds")
        a = np.array(r.axis_body)
        # a rotation whose z axis is a (any completion: the thrust and its torque depend on z only)
        R = _frame_with_z(a)
        # crocoddyl: CW adds +ctorque * z to the torque, CCW subtracts it; spin +1 = reaction along +axis
        kind = crocoddyl.ThrusterType.CW if r.spin == 1 else crocoddyl.ThrusterType.CCW
        thrusters.append(crocoddyl.Thruster(pin.SE3(R, np.array(r.position_body)), r.kappa, kind, r.f_min, r.f_max))
    u_lb = np.concatenate([platform.thrust_min, -limits])
    u_ub = np.concatenate([platform.thrust_max, limits])
    return thrusters, u_lb, u_ub


def _frame_with_z(a: np.ndarray) -> np.ndarray:
    """A rotation matrix whose third column is the unit vector ``a``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, a)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(a, x), a])


def _extrapolate(xi, xi_dot, xi_ddot, d: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reference sample (xi, xi_dot, xi_ddot) extrapolated to second order by ``d`` seconds."""
    return xi + d * xi_dot + 0.5 * d * d * xi_ddot, xi_dot + d * xi_ddot, xi_ddot


def _check_trajectory(trajectory) -> None:
    if trajectory is not None and not isinstance(trajectory, Trajectory):
        raise InputError(f"trajectory must have a sample(t) method (qprr.trajectory.Trajectory), got {type(trajectory).__name__}")


def _resolve_backend(requested: str) -> str:
    """The node models to use for ``MPCSettings.backend`` (module docstring, "Backends")."""
    if requested == "python":
        return "python"
    if NATIVE_PROBLEM:
        if requested == "native":
            raise InputError(
                f"MPCSettings.backend = 'native': crocoddyl's compiled models do not read the installed pinocchio "
                f"correctly ({mpc_native.versions()}: {NATIVE_PROBLEM}); fix: {FIX}, or use backend='python' or 'auto'"
            )
        return "python"
    return "native"


# ============================================================================= controller
class MPCController(Controller):
    """Receding-horizon MPC with rotor thrust bounds on crocoddyl (see the module docstring).

    Parameters
    ----------
    platform
        The :class:`~qprr.model.Platform` controlled: its model (free-flyer root), rotors (finite
        thrust bounds needed), arm effort limits (finite), end-effector frame and thrust axis.
    trajectory
        Reference (``sample(t) -> TrajectorySample`` in thesis coordinates) previewed over the
        horizon.  The simulator replaces it by the run's trajectory (``uses_preview``); without
        any, the current reference is extrapolated (second order).
    weights, settings
        :class:`MPCWeights` (None: :func:`platform_weights`, the Q-PRR's tuned weights mapped onto ``platform``),
        :class:`MPCSettings` (defaults if None).

    After a run: :meth:`stats`, ``fallback_count``, ``events`` [(t, status, reason, fallback)],
    :attr:`planned_thrusts` (the latest plan), ``max_bound_violation`` [N] over every plan.
    """

    name = "mpc"
    output = "pinocchio"
    uses_preview = True

    def __init__(self, platform: Platform, trajectory=None, *, weights: MPCWeights | None = None, settings: MPCSettings | None = None) -> None:
        self.settings = MPCSettings() if settings is None else settings
        if weights is not None and not isinstance(weights, MPCWeights):
            raise InputError(f"weights must be an MPCWeights (None: platform_weights(platform)), got {type(weights).__name__}")
        if not isinstance(self.settings, MPCSettings):
            raise InputError(f"settings must be an MPCSettings, got {type(self.settings).__name__}")
        _check_trajectory(trajectory)
        self.backend = _resolve_backend(self.settings.backend)
        thrusters, u_lb, u_ub = _check_platform(platform)
        self.weights = platform_weights(platform) if weights is None else weights
        self.platform = platform
        self.trajectory = trajectory
        n_rot = platform.n_rotors
        model = platform.model
        if model.names[1] != "root_joint":  # crocoddyl looks the free flyer up by this name (a copy; the platform's stays)
            model = pin.Model(model)
            model.names[1] = "root_joint"
        self.model = model
        self.n_rotors = n_rot
        self.u_lb, self.u_ub = u_lb, u_ub
        m = self.settings.bound_margin
        self._plan_lb = u_lb + np.r_[np.full(n_rot, m), np.zeros(len(u_lb) - n_rot)]
        self._plan_ub = u_ub - np.r_[np.full(n_rot, m), np.zeros(len(u_ub) - n_rot)]
        self._data = model.createData()
        self._q_body = pin.neutral(model)  # the base at the origin, level (:meth:`_arm_com`)
        authority = Authority.from_platform(platform)
        # [rad/s^2] roll and pitch: the largest tilt acceleration the reference may ask (:meth:`_tilt_motion`)
        self._tilt_authority = TILT_AUTHORITY_SHARE * np.array(authority.torque[0:2]) / np.array(authority.inertia[0:2])
        multibody = crocoddyl.StateMultibody(model)
        self.actuation = crocoddyl.ActuationModelFloatingBaseThrusters(multibody, thrusters)
        self.state = multibody if self.backend == "native" else LieState(model)
        self.W = np.array(self.actuation.Wthrust)  # tau = W u
        self.W_pinv = np.linalg.pinv(self.W)
        self.nu = self.actuation.nu
        self.g = float(np.linalg.norm(model.gravity.linear))
        self.h = 1.0 / self.settings.rate
        self.ee_frame = int(platform.ee_frame)
        self._u_scale, self._q_lo, self._q_hi = self._scales_and_limits()
        self._build_problem()
        self.dt = None
        self._hold_steps = None  # set by reset
        self._clear()

    def _scales_and_limits(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Control scale s (1 for the rotors, 1 / M_jj for arm joint j) and the arm's soft limits (lo, hi).

        Arm efforts are weighted through the joint acceleration they give, tau_j / M_jj (at the
        neutral configuration): one weight suits a 0.1 kg wrist and a 0.5 kg slider alike.  The soft
        limits are the arm's position limits shrunk by ``joint_limit_margin`` of their range.
        """
        pf = self.platform
        M = pin.crba(self.model, self._data, pf.neutral_q())
        u_scale = np.r_[np.ones(self.n_rotors), 1.0 / np.diag(M)[6:]]
        lo, hi = np.array(pf.arm_lower), np.array(pf.arm_upper)
        span = np.where(np.isfinite(hi - lo), hi - lo, 0.0)
        q_lo = np.where(np.isfinite(lo), lo + self.settings.joint_limit_margin * span, -np.inf)
        q_hi = np.where(np.isfinite(hi), hi - self.settings.joint_limit_margin * span, np.inf)
        return u_scale, q_lo, q_hi

    # ------------------------------------------------------------------ problem
    def _state_weights(self, factor: float = 1.0) -> np.ndarray:
        w, nv = self.weights, self.model.nv
        n_arm = nv - 6
        pos = [w.position] * 3 + [w.tilt, w.tilt, w.yaw] + [w.arm] * n_arm
        vel = [w.linear_velocity] * 3 + [w.angular_velocity] * 3 + [w.arm_velocity] * n_arm
        return factor * np.array(pos + vel, dtype=float)

    def node_spec(self, terminal: bool) -> NodeSpec:
        """Weights and constants of a running (``terminal=False``) or the terminal node (:class:`NodeSpec`)."""
        w, nu, nr = self.weights, self.nu, self.n_rotors
        factor = w.terminal_factor if terminal else 1.0
        parts = [
            self._state_weights(factor),
            factor * np.array([w.ee_position] * 3 + [w.ee_orientation] * 3),
            np.full(2, factor * w.cog),
            np.full(self.model.nv - 6, factor * w.joint_limits),
        ]
        if not terminal:
            parts.append(np.r_[np.full(nr, w.thrust), np.full(nu - nr, w.arm_acceleration)])
        return NodeSpec(
            W=self.W,
            ee_frame=self.ee_frame,
            weights=np.concatenate(parts),
            terminal=terminal,
            u_scale=self._u_scale,
            q_lo=self._q_lo,
            q_hi=self._q_hi,
            axis_point=np.array(self.platform.thrust_axis[0]),
            axis_basis=np.array(self.platform.thrust_axis_basis),
        )

    def _node(self, terminal: bool) -> tuple:
        """One node: (integrated action model, the object whose ``set_reference`` sets its references)."""
        spec = self.node_spec(terminal)
        if self.backend == "native":
            refs = mpc_native.NativeNode(self.state, self.actuation, spec)
            dam = refs.dam
        else:
            refs = dam = PlatformDynamics(self.state, spec)
        h = 0.0 if terminal else self.h
        if self.settings.integrator == "euler":
            iam = crocoddyl.IntegratedActionModelEuler(dam, h)
        else:
            order = {"rk2": crocoddyl.RKType.two, "rk3": crocoddyl.RKType.three, "rk4": crocoddyl.RKType.four}
            iam = crocoddyl.IntegratedActionModelRK(dam, order[self.settings.integrator], h)
        iam.u_lb, iam.u_ub = self._plan_lb, self._plan_ub
        return iam, refs

    def _build_problem(self) -> None:
        N = self.settings.horizon
        nodes = [self._node(False) for _ in range(N)]
        self._terminal, self._terminal_res = self._node(True)
        self._nodes = list(nodes)  # (model, dynamics) in node order, rotated with the problem
        x0 = self.state.zero()
        self.problem = crocoddyl.ShootingProblem(x0, [m for m, _ in nodes], self._terminal)
        if self.problem.nthreads != self.settings.threads:  # (crocoddyl runs a problem with Python parts in one thread and
            self.problem.nthreads = self.settings.threads  # warns when told to use more)
        self.solver = crocoddyl.SolverBoxFDDP(self.problem)
        self.solver.th_stop = self.settings.th_stop

    # ------------------------------------------------------------------ references
    def reference(self, xi, xi_dot, xi_ddot) -> tuple[np.ndarray, pin.SE3, np.ndarray]:
        """(x_ref = (q, v), M_ee_ref (world), u_ref) the MPC tracks for one reference sample (thesis coordinates).

        Roll and pitch: the feedforward tilt of :meth:`tilt` (its rates by central differences of the sample's
        second-order extrapolation, :data:`TILT_STEP`); u_ref = W^+ RNEA(q_ref, v_ref, a_ref) clipped to the bounds
        (module docstring).
        """
        n = self.platform.n_xi
        sample = (as_vector(xi, n, "xi"), as_vector(xi_dot, n, "xi_dot"), as_vector(xi_ddot, n, "xi_ddot"))
        lo, hi = (_extrapolate(*sample, d) for d in (-TILT_STEP, TILT_STEP))
        return self._reference(*sample, self._tilt_motion(lo, sample, hi))

    def tilt(self, xi, xi_dot, xi_ddot) -> np.ndarray:
        """Feedforward roll and pitch [rad] of one reference sample: Thesis (6.17) on a reference acceleration.

        ``tilt_reference = "base"``: on the base's, p_ddot_d + g e3.  ``"system"`` (default): on the whole robot's
        centre-of-mass acceleration c_ddot + g e3, the direction the total thrust must point in by Newton's law for
        the system, m c_ddot = f - m g e3 (the rotors are its only external force besides gravity, Thesis (5.29)).  With
        the tilt's rates 0, as in the reference, the base turns at omega = psi_dot e3 (world), so

            c_ddot = p_ddot + R r_ddot + 2 omega x R r_dot + omega_dot x R r + omega x (omega x R r),

        R = Rz(psi) Ry(theta) Rx(phi) (Thesis (3.4)), r, r_dot, r_ddot the centre of mass's offset from B in the body
        frame and its rates from the arm's motion (Pinocchio's ``centerOfMass`` with the base at rest at the origin).
        R depends on the tilt sought: passes from the base's tilt until one changes it by less than
        :data:`SYSTEM_TILT_TOL` (at most :data:`SYSTEM_TILT_PASSES`; each pass shrinks the change by the arm's share of
        the motion: 4 to 8 passes on random samples of examples/my_platform, 1.8 on average on its hover-reach).
        Held level when the acceleration asks for less than 5 % of g upward.
        """
        n = self.platform.n_xi
        return self._tilt(as_vector(xi, n, "xi"), as_vector(xi_dot, n, "xi_dot"), as_vector(xi_ddot, n, "xi_ddot"))[0]

    def _tilt(self, xi, xi_dot, xi_ddot) -> tuple[np.ndarray, bool]:
        """:meth:`tilt` and whether it is a smooth function of the sample there: False where (6.17) is clamped to
        ``max_tilt`` or held level (the reference asks for less than 5 % of g upward)."""
        xi = np.asarray(xi, dtype=float)
        xi_dot = np.asarray(xi_dot, dtype=float)
        xi_ddot = np.asarray(xi_ddot, dtype=float)
        psi = xi[5]
        cp, sp = math.cos(psi), math.sin(psi)
        acc = xi_ddot[0:3]
        angles = np.zeros(2)
        system = self.settings.tilt_reference == "system"
        if system:
            r, r_dot, r_ddot = self._arm_com(xi, xi_dot, xi_ddot)
            w, w_dot = float(xi_dot[5]), float(xi_ddot[5])  # omega = w e3, omega_dot = w_dot e3 (world): the yaw's
        for k in range(1 + (SYSTEM_TILT_PASSES if system else 0)):
            previous = angles.copy()
            if k:  # the system's centre-of-mass acceleration [m/s^2] (world) at the tilt of the previous pass
                R = euler_to_rotation((angles[0], angles[1], psi))
                c, c_dot, c_ddot = R @ r, R @ r_dot, R @ r_ddot
                # c_ddot + 2 omega x c_dot + omega_dot x c + omega x (omega x c), with e3 x u = E3_CROSS u
                acc = xi_ddot[0:3] + c_ddot + E3_CROSS @ (2.0 * w * c_dot + w_dot * c + w * w * (E3_CROSS @ c))
            az = acc[2] + self.g
            lifted = az > 0.05 * self.g
            angles[:] = tilt_6_17(acc[0], acc[1], az, cp, sp, self.settings.max_tilt) if lifted else (0.0, 0.0)
            if k and np.max(np.abs(angles - previous)) < SYSTEM_TILT_TOL:
                break
        return angles, bool(lifted and np.all(np.abs(angles) < self.settings.max_tilt))

    def _arm_com(self, xi, xi_dot, xi_ddot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(r, r_dot, r_ddot) [m, m/s, m/s^2]: the system's centre of mass in the body frame B and its rates when only the
        arm moves (Pinocchio's ``centerOfMass`` with the base at rest at the origin)."""
        q = self._q_body
        q[7:] = xi[6:]
        v = np.zeros(self.model.nv)
        a = np.zeros(self.model.nv)
        v[6:] = xi_dot[6:]
        a[6:] = xi_ddot[6:]
        data = self._data
        pin.centerOfMass(self.model, data, q, v, a)
        return data.com[0].copy(), data.vcom[0].copy(), data.acom[0].copy()

    def _tilt_motion(self, lo, mid, hi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(angles, rates, accelerations) of the feedforward tilt at the sample ``mid`` (module docstring): central
        differences over the samples ``lo``, ``hi`` :data:`TILT_STEP` before and after with ``"system"``; rates 0 with
        ``"base"`` (the tilt of (6.17) held between samples), and with ``"system"`` where one of the three is clamped or
        held level (a jump there made the differences 200 rad/s and 2e5 rad/s^2 on aggressive-reach, which diverged) or
        whose acceleration exceeds :data:`TILT_AUTHORITY_SHARE` of the rotors' (``_tilt_authority``)."""
        a1, smooth = self._tilt(*mid)
        if self.settings.tilt_reference == "base":
            return a1, np.zeros(2), np.zeros(2)
        (a0, smooth0), (a2, smooth2) = self._tilt(*lo), self._tilt(*hi)
        rates, accelerations = (a2 - a0) / (2.0 * TILT_STEP), (a2 - 2.0 * a1 + a0) / TILT_STEP**2
        if not (smooth0 and smooth and smooth2 and np.all(np.abs(accelerations) <= self._tilt_authority)):
            return a1, np.zeros(2), np.zeros(2)  # a clamp, the level hold or a turn beyond TILT_AUTHORITY_SHARE: held
        return a1, rates, accelerations

    def _reference(self, xi, xi_dot, xi_ddot, tilt) -> tuple[np.ndarray, pin.SE3, np.ndarray]:
        """:meth:`reference` on vectors of the right size with the tilt's (angles, rates, accelerations) given."""
        xi = np.array(xi, dtype=float)
        xi_dot = np.array(xi_dot, dtype=float)
        xi_ddot = np.array(xi_ddot, dtype=float)
        xi[3:5], xi_dot[3:5], xi_ddot[3:5] = tilt
        q, v = xi_to_qv(xi, xi_dot)
        a = xi_ddot_to_a(xi, xi_dot, xi_ddot)
        data = self._data
        tau = pin.rnea(self.model, data, q, v, a)
        u_ref = np.clip(self.W_pinv @ tau, self._plan_lb, self._plan_ub)
        pin.framesForwardKinematics(self.model, data, q)
        return np.concatenate([q, v]), data.oMf[self.ee_frame].copy(), u_ref

    def _references(self, t: float, ref: Reference, ks) -> list:
        """References of the nodes k in ``ks`` for a solve at time t (k = N: the terminal node), t_k = t + k h.

        A running node's cost is crocoddyl's quadrature of the cost over [t_k, t_k + h] against one reference, so its
        state and end-effector references are the trajectory at the quadrature's mean time t_k + c h (:data:`COST_TIME`:
        c = 1/2 for the RK nodes, 0 for Euler), and its control reference is the inverse dynamics at t_k + h / 2,
        whose acceleration the input held over the interval gives on average to second order.  The terminal node's
        cost is at t_N.  (Referenced at t_k, the RK2 plan lagged the climb of hover-reach by 0.5 mm, 3 times the IDC's
        error: docs/mpc.md, "Tracking against the IDC on other platforms".)  The tilt's rates: :meth:`_tilt_motion`.
        """
        N, h = self.settings.horizon, self.h
        c = COST_TIME[self.settings.integrator]
        state_times = [t + (k + (c if k < N else 0.0)) * h for k in ks]
        control_times = [t + (k + 0.5) * h for k in ks]
        times = np.array(state_times + control_times)
        mid = self._samples(t, ref, times)
        if self.settings.tilt_reference == "base":
            lo = hi = mid
        else:
            lo, hi = self._samples(t, ref, times - TILT_STEP), self._samples(t, ref, times + TILT_STEP)
        first = {tk: i for i, tk in reversed(list(enumerate(times)))}  # RK nodes: a state time is its control time
        tilts = [self._tilt_motion(lo[i], mid[i], hi[i]) if first[tk] == i else None for i, tk in enumerate(times)]
        tilts = [tilts[first[tk]] for tk in times]
        out = []
        for i in range(len(ks)):
            x, M, u = self._reference(*mid[i], tilts[i])
            j = len(ks) + i
            if control_times[i] != state_times[i]:
                u = self._reference(*mid[j], tilts[j])[2]
            out.append((x, M, u))
        return out

    def _samples(self, t: float, ref: Reference, times: np.ndarray) -> list:
        """(xi, xi_dot, xi_ddot) of the reference at ``times`` [s]: the previewed trajectory, else the current reference
        extrapolated to second order from t."""
        if self.trajectory is not None:
            s = self.trajectory.sample(times)
            return [(s.xi[i], s.xi_dot[i], s.xi_ddot[i]) for i in range(len(times))]
        return [_extrapolate(ref.xi, ref.xi_dot, ref.xi_ddot, tk - t) for tk in times]

    @staticmethod
    def _set(node, reference) -> None:
        node.set_reference(*reference)

    # ------------------------------------------------------------------ Controller API
    def set_preview(self, trajectory) -> None:
        """The run's trajectory, previewed over the horizon (the simulator calls this before :meth:`reset`)."""
        _check_trajectory(trajectory)
        self.trajectory = trajectory

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        """Prepare a run: MPC period = round(h / dt) simulator steps; the first step solves cold."""
        dt = check_reset(self, state, ref, dt)
        m = round(self.h / dt)
        if m < 1 or abs(m * dt - self.h) > 1e-9 * self.h:
            raise InputError(f"the MPC period 1/rate = {self.h!r} s must be a whole number of simulator steps dt = {dt!r} s")
        self.dt = dt
        self._hold_steps = m
        self._clear()

    def _clear(self) -> None:
        """Forget the plans, counters and logs (a new run)."""
        self._calls = 0
        self._started = False
        self._tau = np.zeros(self.model.nv)
        self._u = np.zeros(self.nu)
        self._plan_us = None  # last accepted plan: controls, states, feedback gains
        self._plan_xs = None
        self._plan_K = None
        self._plan_age = 0
        self.fallback_count = 0
        self.events = []
        self.max_bound_violation = 0.0
        self._log = {
            k: [] for k in ("t", "solve_time", "solve_cpu", "step_time", "iterations", "status", "cost", "gap", "thrust_margin", "fallback", "u")
        }

    @property
    def planned_thrusts(self) -> np.ndarray | None:
        """Rotor thrusts of the latest solver plan, shape (N, n_rotors) [N] (None before the first solve)."""
        if not self._started:
            return None
        return np.array(self.solver.us)[:, : self.n_rotors]

    def stats(self) -> MPCStats:
        """Per-solve log of the run so far (:class:`MPCStats`)."""
        L = self._log
        return MPCStats(
            backend=self.backend,
            t=np.array(L["t"]),
            solve_time=np.array(L["solve_time"]),
            solve_cpu=np.array(L["solve_cpu"]),
            step_time=np.array(L["step_time"]),
            iterations=np.array(L["iterations"], dtype=int),
            status=tuple(L["status"]),
            cost=np.array(L["cost"]),
            gap=np.array(L["gap"]),
            thrust_margin=np.array(L["thrust_margin"]),
            fallback=tuple(L["fallback"]),
            u=np.array(L["u"]).reshape(-1, self.nu),
        )

    def report(self) -> tuple[dict[str, float], dict[str, np.ndarray]]:
        """Metrics ``mpc_*`` of :meth:`MPCStats.summary` (times in s, margins in N, counts) and the per-solve series
        ``mpc_t``, ``mpc_solve_time``, ``mpc_solve_cpu``, ``mpc_iterations``, ``mpc_thrust_margin`` (copied into the result)."""
        st = self.stats()
        metrics = {f"mpc_{k}": v for k, v in st.summary().items()}
        metrics["mpc_min_plan_thrust_margin_N"] = metrics.pop("mpc_min_thrust_margin_N")
        metrics["mpc_max_plan_bound_violation_N"] = float(self.max_bound_violation)
        metrics["mpc_chatter_fraction"] = chatter_fraction(st.u, self.u_lb, self.u_ub)
        series = {
            "mpc_t": st.t,
            "mpc_solve_time": st.solve_time,
            "mpc_solve_cpu": st.solve_cpu,
            "mpc_iterations": st.iterations.astype(float),
            "mpc_thrust_margin": st.thrust_margin,
        }
        return metrics, series

    def run_warnings(self) -> tuple[str, ...]:
        """:func:`~qprr.control.mpc_stats.health_warnings` of the run so far (the settings' ``warn_*`` thresholds)."""
        limits = (self.settings.warn_iteration_limit, self.settings.warn_chatter)
        return health_warnings(self.stats(), self.u_lb, self.u_ub, limits)

    def _write_tilt(self, ref: Reference) -> None:
        """Write the feedforward tilt (:meth:`tilt`) of the current reference into ``ref`` (the logged reference)."""
        ref.xi[3:5] = self._tilt(ref.xi, ref.xi_dot, ref.xi_ddot)[0]  # the simulator's reference: checked vectors
        ref.xi_dot[3] = ref.xi_dot[4] = 0.0
        ref.xi_ddot[3] = ref.xi_ddot[4] = 0.0

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """tau = W u_0 of the current plan (re-solved every round(h / dt) calls, held in between)."""
        if self._hold_steps is None:
            raise InputError("MPCController.reset(state, ref, dt) must be called before step (the simulator does)")
        self._write_tilt(ref)
        if self._calls % self._hold_steps == 0:
            self._update(t, state, ref)
        self._calls += 1
        return self._tau

    # ------------------------------------------------------------------ one MPC update
    def _update(self, t: float, state: State, ref: Reference) -> None:
        t0 = time.perf_counter()
        N = self.settings.horizon
        problem = self.problem
        x0 = np.concatenate([state.q, state.v])
        problem.x0 = x0
        if not self._started:
            refs = self._references(t, ref, range(N + 1))
            for (_, res), r in zip(self._nodes, refs[:N]):
                self._set(res, r)
            self._set(self._terminal_res, refs[N])
            us = [r[2] for r in refs[:N]]
            xs = self.problem.rollout(us)
            max_iter = self.settings.first_max_iter
        else:
            # rotate the nodes: the first one (time t - h) becomes the last (time t + (N - 1) h)
            first, res = self._nodes.pop(0)
            r_last, r_term = self._references(t, ref, (N - 1, N))
            self._set(res, r_last)
            if self.backend == "native":
                problem.circularAppend(first, problem.runningDatas[0])
            else:
                problem.circularAppend(first)  # (new data: crocoddyl cannot check a Python model's data)
            self._nodes.append((first, res))
            self._set(self._terminal_res, r_term)
            xs, us = self._warm_start(x0)
            max_iter = self.settings.max_iter
        solver = self.solver
        t1, c1 = time.perf_counter(), time.thread_time()
        reason = ""
        try:
            converged = solver.solve(xs, us, max_iter, True, self.settings.init_reg)
        except Exception as exc:  # crocoddyl raises RuntimeError on NaN/bad input; any error is a failed solve
            converged, reason = False, f"solver raised {type(exc).__name__}: {exc}"
        t2, c2 = time.perf_counter(), time.thread_time()
        self._started = True
        status, plan_us, margin, gap = self._check(converged, reason)
        fallback = ""
        if status is not SolveStatus.FAILED:
            self._plan_us = plan_us
            self._plan_xs = [np.array(x) for x in solver.xs]
            self._plan_K = [np.array(K) for K in solver.K]
            self._plan_age = 0
            u = plan_us[0]
        else:
            self._plan_age += 1
            if self._plan_us is not None and self._plan_age < N:
                fallback = Fallback.PREVIOUS_PLAN.value
                u = self._plan_us[self._plan_age]
            else:
                fallback = Fallback.HOVER.value
                u = self._hover(state)
            self.fallback_count += 1
            self.events.append((t, status.value, self._last_reason, fallback))
        self._u = np.array(u, dtype=float)
        self._tau = self.W @ self._u
        L = self._log
        L["t"].append(t)
        L["solve_time"].append(t2 - t1)
        L["solve_cpu"].append(c2 - c1)
        L["iterations"].append(int(solver.iter))
        L["status"].append(status.value)
        L["cost"].append(float(solver.cost))
        L["gap"].append(gap)
        L["thrust_margin"].append(margin)
        L["fallback"].append(fallback)
        L["u"].append(self._u.copy())
        L["step_time"].append(time.perf_counter() - t0)

    def _warm_start(self, x0: np.ndarray) -> tuple[list, list]:
        """A dynamically feasible guess: the last accepted plan shifted to the current time, rolled out
        from the measured state ``x0`` under its own feedback, u_k = clip(u_k* - K_k (x_k (-) x_k*)).

        Box-FDDP computes its box-QP gains from the first iteration only on a feasible guess (on
        an infeasible one it clamps unconstrained steps, whose predicted decrease is wrong when a
        bound is active: observed as rejected line searches).  The feedback keeps the rollout
        close to the plan (an open-loop rollout of the shifted controls diverges over 0.4 s).
        """
        N = self.settings.horizon
        lb, ub = self._plan_lb, self._plan_ub
        if self._plan_us is None:  # no plan yet (the cold start failed): hold the last control
            us = [np.clip(self._u, lb, ub)] * N
            return self.problem.rollout(us), us
        s = self._plan_age + 1
        st = self.state
        xs, us = [x0], []
        for k, (model, data) in enumerate(zip(self.problem.runningModels, self.problem.runningDatas)):
            j = min(k + s, N - 1)
            x_plan = self._plan_xs[min(k + s, N)]
            u = np.clip(self._plan_us[j] - self._plan_K[j] @ st.diff(x_plan, xs[k]), lb, ub)
            model.calc(data, xs[k], u)
            us.append(u)
            xs.append(np.array(data.xnext))
        return xs, us

    def _check(self, converged: bool, reason: str):
        """Status of the solve just made, the plan's controls, its thrust margin [N] and dynamic gap."""
        solver = self.solver
        us = np.array(solver.us)
        nr = self.n_rotors
        f = us[:, :nr]
        margin = float(np.min(np.minimum(f - self.u_lb[:nr], self.u_ub[:nr] - f))) if np.all(np.isfinite(f)) else float("nan")
        gap = float("nan")
        if not reason:
            if not (np.all(np.isfinite(us)) and all(np.all(np.isfinite(x)) for x in solver.xs) and math.isfinite(solver.cost)):
                reason = "non-finite plan"
            else:
                over = float(np.max(np.maximum(self.u_lb - us, us - self.u_ub)))
                self.max_bound_violation = max(self.max_bound_violation, over)
                gap = self._gap()
                if over > 0.0:
                    reason = f"plan exceeds the input bounds by {over:.3g}"
                elif not gap <= self.settings.feasibility_tol:
                    reason = f"dynamic gap {gap:.3g} > feasibility_tol {self.settings.feasibility_tol:g} after {solver.iter} iterations"
        self._last_reason = reason
        if reason:
            return SolveStatus.FAILED, us, margin, gap
        return (SolveStatus.CONVERGED if converged else SolveStatus.ITERATION_LIMIT), us, margin, gap

    def _gap(self) -> float:
        """Largest dynamic gap |f(x_k, u_k) (-) x_k+1| of the solver's (xs, us) (0 when crocoddyl flags it feasible).

        crocoddyl's ``ffeas`` is the gap of the iterate the last direction was computed at, not
        of the one a full step (which closes every gap) produced, so it is recomputed here.
        """
        solver = self.solver
        if solver.isFeasible:
            return 0.0
        xs, us = solver.xs, solver.us
        st, worst = self.state, 0.0
        for k, (model, data) in enumerate(zip(self.problem.runningModels, self.problem.runningDatas)):
            model.calc(data, xs[k], us[k])
            worst = max(worst, float(np.max(np.abs(st.diff(np.array(data.xnext), np.array(xs[k + 1]))))))
        return worst

    def _hover(self, state: State) -> np.ndarray:
        """Fallback ``hover``: W^+ g(q) at the measured configuration (at rest), clipped to the bounds."""
        zero = np.zeros(self.model.nv)
        g = pin.rnea(self.model, self._data, np.asarray(state.q, dtype=float), zero, zero)
        return np.clip(self.W_pinv @ g, self._plan_lb, self._plan_ub)


__all__ = [
    "FIX",
    "NATIVE_PROBLEM",
    "Fallback",
    "LieState",
    "MPCController",
    "MPCSettings",
    "MPCStats",
    "MPCWeights",
    "NodeSpec",
    "PlatformDynamics",
    "REFERENCE_HOVER_THRUST_SQUARED",
    "SolveStatus",
    "platform_weights",
]
