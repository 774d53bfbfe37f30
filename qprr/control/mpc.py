"""Receding-horizon model predictive control (MPC) on crocoddyl, with the rotor thrust bounds.

Not in the thesis: the controller it calls "MPC" (Annex A.2) is inverse dynamics at the desired
state (qprr's ``dsid``) and optimises nothing over a horizon.  This one does, on the full
coupled model of any :class:`~qprr.platform.Platform` (the same Pinocchio model the simulator
integrates), with its rotor set.  Install crocoddyl without its dependencies (see "Installing"
below): ``pip install --no-deps crocoddyl==3.2.1 libcrocoddyl==3.2.1``.

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
* l_k = 1/2 sum of weighted squared residuals (:class:`MPCWeights`):

  - ``state``: x_k (-) x_ref(t_k) in the tangent space (LOCAL): base position, attitude
    (roll/pitch and yaw weighted apart), arm joints and the velocities;
  - ``ee``: log6(M_ref^-1 M_ee(q)) of the end-effector pose (LOCAL), M_ref = FK(q_ref);
  - ``cog``: the offset of the system's centre of mass from the thrust axis, in the plane normal
    to it ([x_cm, y_cm] in B for coplanar rotors, Thesis (3.78); :func:`qprr.kinematics.cog_offset_body`);
  - ``joint limits``: a quadratic barrier on each arm joint past its soft limit (the model's
    position limits, where the simulator has its mechanical stops; ``joint_limit_margin``
    moves them inside: 0 by default, as the static mission asks for r0 = 0.04 m, the stop);
  - ``control``: u - u_ref, u_ref = W^+ RNEA(q_ref, v_ref, a_ref) clipped to the bounds (the
    inputs that realise the reference acceleration; hover thrusts at rest).

  l_N: the state, end-effector, CoG and joint-limit terms times ``terminal_factor`` (no control term).
* References: the trajectory (thesis coordinates, any number of arm joints) sampled at the node
  times (the simulator hands it over before the run: ``uses_preview``); roll and pitch
  are the feedforward tilt of Thesis (6.17) applied to the reference acceleration (the tilt
  that points z_B along p_ddot_d + g e3, as the IDC's feedforward filter does), their rates 0.
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

Why not crocoddyl's multibody models.  The PyPI wheel crocoddyl 3.2.1 (the only one built on
cmeel-boost 1.90, which pin 4.1 uses) was compiled against pinocchio 4.0's headers.  Pinocchio
4.1 inserted four members in ``ModelTpl`` (lower/upper acceleration and jerk limits) before
``frames``, ``supports``, ``subtrees`` and ``gravity``, so crocoddyl's compiled code reads
those at the wrong offsets: measured with pin 4.1.0, its ``DifferentialActionModelFreeFwdDynamics``
returns ABA without gravity (9.81 m/s^2 off), ``ResidualModelFrameTranslation`` returns
[0, 0, 3e-322] for a frame at [0, 0, 0.5], frame-placement residuals are NaN and solves
segfault; with pin 4.0.0 the same script agrees with pinocchio to 0.  The members before the
insertion (nq, nv, joints, names, position and velocity limits) are read correctly.  So this
module uses crocoddyl's core (Box-FDDP, the shooting problem, the RK/Euler integrated models)
and its ``ActuationModelFloatingBaseThrusters`` (which reads only names and joints), and
evaluates the dynamics, costs and state operations with pinocchio's Python API
(:class:`LieState`, :class:`PlatformDynamics`).  The price is Python work per node: about
17 us per model evaluation and 55 us per derivative evaluation on the machine of
benchmarks/mpc_benchmark.py.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields
from enum import Enum

import numpy as np
import pinocchio as pin

from ..charts import State, as_int, as_real, as_vector, xi_ddot_to_a, xi_to_qv
from ..errors import InputError, MissingDependencyError, UnknownNameError
from ..kinematics import com_jacobian_body_from
from ..platform import Platform
from . import MPC_INSTALL as INSTALL  # the extra's install command (docs/mpc.md, "Installing")
from .base import Controller, Reference, check_reset
from .filters import tilt_6_17

try:
    import crocoddyl
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise MissingDependencyError("crocoddyl", "the receding-horizon MPC (qprr.control.mpc)", INSTALL) from exc

INTEGRATORS = ("euler", "rk2", "rk3", "rk4")


class SolveStatus(str, Enum):
    """Outcome of one MPC solve (see the module docstring)."""

    CONVERGED = "converged"
    ITERATION_LIMIT = "iteration-limit"
    FAILED = "failed"


class Fallback(str, Enum):
    """What the controller applies after a failed solve."""

    PREVIOUS_PLAN = "previous-plan"
    HOVER = "hover"


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
    cog: float = 100.0
    joint_limits: float = 1e6
    thrust: float = 1.0
    arm_acceleration: float = 1e-2
    terminal_factor: float = 10.0

    def __post_init__(self) -> None:
        _positive(self, tuple(f.name for f in fields(self)), allow_zero=True)


@dataclass(frozen=True)
class MPCSettings:
    """Horizon, rate and solver settings.

    ``rate`` [Hz]: solves per second (the node spacing is h = 1 / rate); ``horizon``: number of
    nodes N (horizon N h); ``max_iter``: Box-FDDP iterations per solve; ``first_max_iter``:
    for the cold start; ``th_stop``: crocoddyl's stopping threshold; ``feasibility_tol``: largest
    dynamic gap of an accepted plan; ``bound_margin`` [N]: the thrust bounds are planned
    this far inside; ``max_tilt`` [rad]: clamp of the feedforward tilt (6.17);
    ``joint_limit_margin``: the arm joints' soft limits are the model's position limits shrunk by
    this fraction of their range (the simulator's mechanical stops sit at the limits).
    """

    rate: float = 100.0
    horizon: int = 40
    integrator: str = "rk2"
    max_iter: int = 10
    first_max_iter: int = 200
    th_stop: float = 1e-6
    feasibility_tol: float = 1e-3
    bound_margin: float = 1e-9
    max_tilt: float = 0.8
    init_reg: float = 1e-9
    joint_limit_margin: float = 0.0

    def __post_init__(self) -> None:
        _positive(self, ("rate", "th_stop", "feasibility_tol", "max_tilt", "init_reg"), allow_zero=False)
        _positive(self, ("bound_margin",), allow_zero=True)
        if not as_real(self.joint_limit_margin, "MPCSettings.joint_limit_margin", nonnegative=True) < 0.5:
            raise InputError(f"MPCSettings.joint_limit_margin must be in [0, 0.5), got {self.joint_limit_margin!r}")
        for name in ("horizon", "max_iter", "first_max_iter"):
            as_int(getattr(self, name), f"MPCSettings.{name}", lo=1)
        if self.integrator not in INTEGRATORS:
            raise UnknownNameError("integrator", self.integrator, INTEGRATORS)
        if not self.max_tilt < math.pi / 2:
            raise InputError(f"MPCSettings.max_tilt must be < pi/2 rad, got {self.max_tilt!r}")


@dataclass
class MPCStats:
    """Per-solve log of a run: one entry per MPC period.

    ``t`` [s] solve instants; ``solve_time`` [s] wall time of crocoddyl's ``solve``;
    ``solve_cpu`` [s] the CPU time of this thread during it (less sensitive to a loaded machine);
    ``step_time`` [s] wall time of the whole MPC update (references, shift, solve, checks);
    ``iterations``; ``status`` (:class:`SolveStatus` values); ``cost``; ``gap`` dynamic
    infeasibility after the solve; ``thrust_margin`` [N] min over the plan of the distance of
    every planned thrust to its nearest bound (negative: a bound exceeded); ``fallback``
    ("" or a :class:`Fallback` value); ``u`` (n, nu) the control applied from each solve on
    (rotor thrusts [N], then arm efforts).
    """

    t: np.ndarray
    solve_time: np.ndarray
    solve_cpu: np.ndarray
    step_time: np.ndarray
    iterations: np.ndarray
    status: tuple[str, ...]
    cost: np.ndarray
    gap: np.ndarray
    thrust_margin: np.ndarray
    fallback: tuple[str, ...]
    u: np.ndarray

    def summary(self, skip_first: bool = True) -> dict[str, float]:
        """Median and 95th percentile of the solve time [s] (the cold first solve left out by default), counts."""
        sel = slice(1, None) if skip_first and len(self.t) > 1 else slice(None)
        st = self.solve_time[sel]
        return {
            "solves": float(len(self.t)),
            "median_solve_s": float(np.median(st)) if st.size else float("nan"),
            "p95_solve_s": float(np.percentile(st, 95)) if st.size else float("nan"),
            "max_solve_s": float(np.max(st)) if st.size else float("nan"),
            "median_solve_cpu_s": float(np.median(self.solve_cpu[sel])) if st.size else float("nan"),
            "p95_solve_cpu_s": float(np.percentile(self.solve_cpu[sel], 95)) if st.size else float("nan"),
            "median_iterations": float(np.median(self.iterations[sel])) if st.size else float("nan"),
            "converged": float(sum(s == SolveStatus.CONVERGED.value for s in self.status)),
            "iteration_limit": float(sum(s == SolveStatus.ITERATION_LIMIT.value for s in self.status)),
            "failed": float(sum(s == SolveStatus.FAILED.value for s in self.status)),
            "min_thrust_margin_N": float(np.min(self.thrust_margin)) if self.thrust_margin.size else float("nan"),
        }


# ====================================================================== state and dynamics
class LieState(crocoddyl.StateAbstract):
    """x = (q, v) with tangent dx = (dq, dv): q (+) dq = ``pin.integrate`` (LOCAL), as crocoddyl's StateMultibody.

    Written on pinocchio's Python API (see "Why not crocoddyl's multibody models" in the module
    docstring): integrate, diff and their Jacobians are pinocchio's integrate, difference,
    dIntegrate, dDifference and dIntegrateTransport.
    """

    def __init__(self, model: pin.Model) -> None:
        if not isinstance(model, pin.Model):
            raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__}")
        crocoddyl.StateAbstract.__init__(self, model.nq + model.nv, 2 * model.nv)
        self.model = model
        self._nq, self._nv = model.nq, model.nv

    def zero(self) -> np.ndarray:
        return np.concatenate([pin.neutral(self.model), np.zeros(self._nv)])

    def rand(self) -> np.ndarray:
        m = self.model
        q = pin.randomConfiguration(m, -np.ones(m.nq), np.ones(m.nq))
        return np.concatenate([q, np.random.default_rng().uniform(-1.0, 1.0, self._nv)])

    def diff(self, x0, x1) -> np.ndarray:
        nq = self._nq
        return np.concatenate([pin.difference(self.model, x0[:nq], x1[:nq]), x1[nq:] - x0[nq:]])

    def integrate(self, x, dx) -> np.ndarray:
        nq, nv = self._nq, self._nv
        return np.concatenate([pin.integrate(self.model, x[:nq], dx[:nv]), x[nq:] + dx[nv:]])

    def _block(self, Jq: np.ndarray, sign: float) -> np.ndarray:
        nv = self._nv
        J = np.zeros((2 * nv, 2 * nv))
        J[:nv, :nv] = Jq
        J[nv:, nv:] = sign * np.eye(nv)
        return J

    def Jdiff(self, x0, x1, firstsecond=crocoddyl.Jcomponent.both):
        nq = self._nq
        q0, q1 = x0[:nq], x1[:nq]
        if firstsecond == crocoddyl.Jcomponent.first:
            return self._block(pin.dDifference(self.model, q0, q1, pin.ARG0), -1.0)
        if firstsecond == crocoddyl.Jcomponent.second:
            return self._block(pin.dDifference(self.model, q0, q1, pin.ARG1), 1.0)
        return [self.Jdiff(x0, x1, crocoddyl.Jcomponent.first), self.Jdiff(x0, x1, crocoddyl.Jcomponent.second)]

    def Jintegrate(self, x, dx, firstsecond=crocoddyl.Jcomponent.both):
        q, dq = x[: self._nq], dx[: self._nv]
        if firstsecond == crocoddyl.Jcomponent.first:
            return self._block(pin.dIntegrate(self.model, q, dq, pin.ARG0), 1.0)
        if firstsecond == crocoddyl.Jcomponent.second:
            return self._block(pin.dIntegrate(self.model, q, dq, pin.ARG1), 1.0)
        return [self.Jintegrate(x, dx, crocoddyl.Jcomponent.first), self.Jintegrate(x, dx, crocoddyl.Jcomponent.second)]

    def JintegrateTransport(self, x, dx, Jin, firstsecond):
        nv = self._nv
        arg = pin.ARG0 if firstsecond == crocoddyl.Jcomponent.first else pin.ARG1
        out = np.array(Jin, dtype=float)
        out[:nv] = pin.dIntegrateTransport(self.model, x[: self._nq], dx[:nv], out[:nv], arg)
        return out


class PlatformDynamics(crocoddyl.DifferentialActionModelAbstract):
    """Continuous-time node of the MPC: a = ABA(q, v, W u) and l = 1/2 r^T diag(w) r (Gauss-Newton Hessian).

    r = [x (-) x_ref (2 nv); log6(M_ref^-1 M_ee) (6); e_cog (2); joint-limit overshoot (n_arm);
    s (u - u_ref) (nu)], the last block on running nodes only; the overshoot of arm joint j is
    min(q_j - lo_j, 0) + max(q_j - hi_j, 0) (a quadratic barrier on the soft limits lo, hi); s =
    ``u_scale`` (1 for the rotors, 1 / M_jj for arm joint j).  e_cog = E (c_B - a) is the CoG
    offset from the thrust axis (point a, the rows of E span the plane normal to it: the
    platform's ``thrust_axis`` and ``thrust_axis_basis``), [x_cm, y_cm] of Thesis (3.78) for
    coplanar rotors (:func:`qprr.kinematics.cog_offset_body`; Jacobian E times
    :func:`qprr.kinematics.com_jacobian_body_from`).
    Derivatives: ``pin.computeABADerivatives`` (Fx), M^-1 W (Fu), dDifference, Jlog6 times the
    LOCAL frame Jacobian, the CoM Jacobian in B (checked against finite differences in
    tests/test_mpc.py).  References are set with :meth:`set_reference`.
    """

    def __init__(self, state: LieState, W: np.ndarray, ee_frame: int, weights: np.ndarray, terminal: bool,
                 u_lb: np.ndarray, u_ub: np.ndarray, u_scale: np.ndarray, q_lo: np.ndarray, q_hi: np.ndarray,
                 axis_point: np.ndarray, axis_basis: np.ndarray) -> None:
        nu = W.shape[1]
        crocoddyl.DifferentialActionModelAbstract.__init__(self, state, nu, len(weights))
        model = state.model
        self.model = model
        self._pdata = model.createData()
        self._axis_point, self._axis_basis = axis_point, axis_basis
        self.W = W
        self.ee_frame = ee_frame
        self.weights = weights
        self.terminal = terminal
        self.u_lb, self.u_ub = u_lb, u_ub
        nq, nv = model.nq, model.nv
        self._nq, self._nv, self._nu = nq, nv, nu
        self.x_ref = state.zero()
        self.M_ref_inv = pin.SE3.Identity()
        self.u_ref = np.zeros(nu)
        self.u_scale = u_scale
        # constant pieces of the derivatives
        self._q_lo, self._q_hi = q_lo, q_hi  # arm joints (q[7:]), the soft limits
        self._nx_res = 2 * nv + 8 + (nv - 6)  # residual rows that depend on the state only
        self._w_u = weights[self._nx_res :]
        self._Luu = np.diag(self._w_u * u_scale**2) if not terminal else None
        self._Rx = np.zeros((self._nx_res, 2 * nv))  # residual Jacobian without the control rows
        self._Rx[nv : 2 * nv, nv:] = np.eye(nv)

    def set_reference(self, x_ref: np.ndarray, M_ref: pin.SE3, u_ref: np.ndarray) -> None:
        """x_ref = (q_ref, v_ref), M_ref the end-effector pose (world), u_ref (nu,)."""
        self.x_ref = x_ref
        self.M_ref_inv = M_ref.inverse()
        self.u_ref = u_ref

    def _residual_x(self, q, v, c_b) -> tuple[np.ndarray, pin.SE3]:
        """State part of r (everything but the control block); the kinematics of ``_pdata`` at q are up to date."""
        m, nq = self.model, self._nq
        M_rel = self.M_ref_inv * pin.updateFramePlacement(m, self._pdata, self.ee_frame)
        x_ref = self.x_ref
        q_arm = q[7:]
        over = np.minimum(q_arm - self._q_lo, 0.0) + np.maximum(q_arm - self._q_hi, 0.0)
        e_cog = self._axis_basis @ (c_b - self._axis_point)
        r = np.concatenate((pin.difference(m, x_ref[:nq], q), v - x_ref[nq:], pin.log6(M_rel).vector, e_cog, over))
        return r, M_rel

    # crocoddyl calls these from C++: a Python exception escaping them aborts the process
    # (boost::python::error_already_set is no std::exception), so any failure becomes NaN
    # outputs, which crocoddyl's line search and backward pass reject as such
    def calc(self, data, x, u=None) -> None:
        try:
            self._calc(data, x, u)
        except Exception:
            data.cost = math.nan
            if u is not None:
                data.xout[:] = math.nan

    def calcDiff(self, data, x, u=None) -> None:
        try:
            self._calc_diff(data, x, u)
        except Exception:
            data.Lx[:] = math.nan
            if u is not None:
                data.Fx[:, :] = math.nan

    def _calc(self, data, x, u) -> None:
        m, d, nq = self.model, self._pdata, self._nq
        q, v = x[:nq], x[nq:]
        if u is not None:
            data.xout[:] = pin.aba(m, d, q, v, self.W @ u)
        c_b = d.oMi[1].actInv(pin.centerOfMass(m, d, q, False))  # forward kinematics at q, then the CoM in B
        r, _ = self._residual_x(q, v, c_b)
        cost = float(np.dot(self.weights[: r.shape[0]] * r, r))
        if u is not None:
            ru = self.u_scale * (u - self.u_ref)
            cost += float(np.dot(self._w_u * ru, ru))
        data.cost = 0.5 * cost

    def _calc_diff(self, data, x, u) -> None:
        m, d, nq, nv = self.model, self._pdata, self._nq, self._nv
        q, v = x[:nq], x[nq:]
        if u is not None:
            ddq_dq, ddq_dv, Minv = pin.computeABADerivatives(m, d, q, v, self.W @ u)
            data.Fx[:, :nv] = ddq_dq
            data.Fx[:, nv:] = ddq_dv
            data.Fu[:, :] = Minv @ self.W
        # jacobianCenterOfMass also computes the joint Jacobians (documented), used by getFrameJacobian
        J_cog = self._axis_basis @ com_jacobian_body_from(d, pin.jacobianCenterOfMass(m, d, q, False))
        c_b = d.oMi[1].actInv(d.com[0])
        r, M_rel = self._residual_x(q, v, c_b)
        Rx = self._Rx
        Rx[:nv, :nv] = pin.dDifference(m, self.x_ref[:nq], q, pin.ARG1)
        Rx[2 * nv : 2 * nv + 6, :nv] = pin.Jlog6(M_rel) @ pin.getFrameJacobian(m, d, self.ee_frame, pin.LOCAL)
        Rx[2 * nv + 6 : 2 * nv + 8, :nv] = J_cog
        q_arm = q[7:]
        Rx[2 * nv + 8 :, 6:nv] = np.diag(((q_arm < self._q_lo) | (q_arm > self._q_hi)).astype(float))
        w = self.weights[: r.shape[0]]
        data.Lx[:] = Rx.T @ (w * r)
        data.Lxx[:, :] = Rx.T @ (w[:, None] * Rx)
        if u is not None:
            ru = self.u_scale * (u - self.u_ref)
            data.Lu[:] = self.u_scale * (self._w_u * ru)
            data.Luu[:, :] = self._Luu
            data.Lxu[:, :] = 0.0

    def createData(self):
        return crocoddyl.DifferentialActionDataAbstract(self)


# ================================================================================ platform
def _check_platform(platform: Platform) -> tuple[list, np.ndarray, np.ndarray]:
    """Crocoddyl thrusters and the input bounds (u_lb, u_ub) of ``platform``; finite bounds are required.

    (Rotor positions, unit axes, spins and kappa are validated by :class:`qprr.rotors.Rotor` and the
    free-flyer root by :class:`~qprr.platform.Platform`.)
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    limits = np.array(platform.arm_effort_limits, dtype=float)
    bad = [j.name for j, e in zip(platform.arm, limits) if not (math.isfinite(e) and e > 0.0)]
    if bad:
        raise InputError(f"platform {platform.name!r}: the MPC needs finite effort limits > 0 on every arm joint; "
                         f"joints {bad} have {[float(limits[platform.arm_names.index(b)]) for b in bad]}")
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


# ============================================================================= controller
class MPCController(Controller):
    """Receding-horizon MPC with rotor thrust bounds on crocoddyl (see the module docstring).

    Parameters
    ----------
    platform
        The :class:`~qprr.platform.Platform` controlled: its model (free-flyer root), rotors (finite
        thrust bounds needed), arm effort limits (finite), end-effector frame and thrust axis.
    trajectory
        Reference (``sample(t) -> TrajectorySample`` in thesis coordinates) previewed over the
        horizon.  The simulator replaces it by the run's trajectory (``uses_preview``); without
        any, the current reference is extrapolated (second order).
    weights, settings
        :class:`MPCWeights`, :class:`MPCSettings` (defaults if None).

    After a run: :meth:`stats`, ``fallback_count``, ``events`` [(t, status, reason, fallback)],
    :attr:`planned_thrusts` (the latest plan), ``max_bound_violation`` [N] over every plan.
    """

    name = "mpc"
    output = "pinocchio"
    uses_preview = True

    def __init__(self, platform: Platform, trajectory=None, *, weights: MPCWeights | None = None,
                 settings: MPCSettings | None = None) -> None:
        self.weights = MPCWeights() if weights is None else weights
        self.settings = MPCSettings() if settings is None else settings
        if not isinstance(self.weights, MPCWeights):
            raise InputError(f"weights must be an MPCWeights, got {type(self.weights).__name__}")
        if not isinstance(self.settings, MPCSettings):
            raise InputError(f"settings must be an MPCSettings, got {type(self.settings).__name__}")
        if trajectory is not None and not callable(getattr(trajectory, "sample", None)):
            raise InputError(f"trajectory must have a sample(t) method, got {type(trajectory).__name__}")
        thrusters, u_lb, u_ub = _check_platform(platform)
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
        # crocoddyl's actuation model needs its StateMultibody; only W (and nu) are taken from it
        # (module docstring: its multibody dynamics do not read pinocchio 4.1's Model correctly)
        self.actuation = crocoddyl.ActuationModelFloatingBaseThrusters(crocoddyl.StateMultibody(model), thrusters)
        self.state = LieState(model)
        self.W = np.array(self.actuation.Wthrust)  # tau = W u
        self.W_pinv = np.linalg.pinv(self.W)
        self.nu = self.actuation.nu
        self.g = float(np.linalg.norm(model.gravity.linear))
        self.h = 1.0 / self.settings.rate
        self.ee_frame = int(platform.ee_frame)
        # arm efforts are weighted through the joint acceleration they give, tau_j / M_jj (at the
        # neutral configuration): one weight suits a 0.1 kg wrist and a 0.5 kg slider alike
        M = pin.crba(model, self._data, platform.neutral_q())
        self._u_scale = np.r_[np.ones(n_rot), 1.0 / np.diag(M)[6:]]
        # soft joint limits: the arm's position limits shrunk by joint_limit_margin of their range
        lo, hi = np.array(platform.arm_lower), np.array(platform.arm_upper)
        span = np.where(np.isfinite(hi - lo), hi - lo, 0.0)
        self._q_lo = np.where(np.isfinite(lo), lo + self.settings.joint_limit_margin * span, -np.inf)
        self._q_hi = np.where(np.isfinite(hi), hi - self.settings.joint_limit_margin * span, np.inf)
        self._build_problem()
        self.dt = None
        self._hold_steps = None  # set by reset
        self._clear()

    # ------------------------------------------------------------------ problem
    def _state_weights(self, factor: float = 1.0) -> np.ndarray:
        w, nv = self.weights, self.model.nv
        n_arm = nv - 6
        pos = [w.position] * 3 + [w.tilt, w.tilt, w.yaw] + [w.arm] * n_arm
        vel = [w.linear_velocity] * 3 + [w.angular_velocity] * 3 + [w.arm_velocity] * n_arm
        return factor * np.array(pos + vel, dtype=float)

    def _node(self, terminal: bool) -> tuple:
        """One node: (integrated action model, its :class:`PlatformDynamics`)."""
        w, nu, nr = self.weights, self.nu, self.n_rotors
        factor = w.terminal_factor if terminal else 1.0
        parts = [self._state_weights(factor), factor * np.array([w.ee_position] * 3 + [w.ee_orientation] * 3), np.full(2, factor * w.cog),
                 np.full(self.model.nv - 6, factor * w.joint_limits)]
        if not terminal:
            parts.append(np.r_[np.full(nr, w.thrust), np.full(nu - nr, w.arm_acceleration)])
        dam = PlatformDynamics(self.state, self.W, self.ee_frame, np.concatenate(parts), terminal, self._plan_lb, self._plan_ub,
                               self._u_scale, self._q_lo, self._q_hi, np.array(self.platform.thrust_axis[0]),
                               np.array(self.platform.thrust_axis_basis))
        h = 0.0 if terminal else self.h
        if self.settings.integrator == "euler":
            iam = crocoddyl.IntegratedActionModelEuler(dam, h)
        else:
            order = {"rk2": crocoddyl.RKType.two, "rk3": crocoddyl.RKType.three, "rk4": crocoddyl.RKType.four}
            iam = crocoddyl.IntegratedActionModelRK(dam, order[self.settings.integrator], h)
        iam.u_lb, iam.u_ub = self._plan_lb, self._plan_ub
        return iam, dam

    def _build_problem(self) -> None:
        N = self.settings.horizon
        nodes = [self._node(False) for _ in range(N)]
        self._terminal, self._terminal_res = self._node(True)
        self._nodes = list(nodes)  # (model, dynamics) in node order, rotated with the problem
        x0 = self.state.zero()
        self.problem = crocoddyl.ShootingProblem(x0, [m for m, _ in nodes], self._terminal)
        self.solver = crocoddyl.SolverBoxFDDP(self.problem)
        self.solver.th_stop = self.settings.th_stop

    # ------------------------------------------------------------------ references
    def reference(self, xi, xi_dot, xi_ddot) -> tuple[np.ndarray, pin.SE3, np.ndarray]:
        """(x_ref = (q, v), M_ee_ref (world), u_ref) the MPC tracks for one reference sample (thesis coordinates).

        Roll and pitch: the feedforward tilt (6.17) of the reference acceleration; u_ref = W^+
        RNEA(q_ref, v_ref, a_ref) clipped to the bounds (module docstring).
        """
        n = self.platform.n_xi
        return self._reference(as_vector(xi, n, "xi"), as_vector(xi_dot, n, "xi_dot"), as_vector(xi_ddot, n, "xi_ddot"))

    def _reference(self, xi, xi_dot, xi_ddot) -> tuple[np.ndarray, pin.SE3, np.ndarray]:
        """:meth:`reference` on vectors of the right size (the per-node path of :meth:`_references`)."""
        xi = np.array(xi, dtype=float)
        xi_dot = np.array(xi_dot, dtype=float)
        xi_ddot = np.array(xi_ddot, dtype=float)
        psi = xi[5]
        az = xi_ddot[2] + self.g
        if az > 0.05 * self.g:  # (6.17) on p_ddot_d + g e3 (held level when it asks for less than free fall)
            xi[3], xi[4] = tilt_6_17(xi_ddot[0], xi_ddot[1], az, math.cos(psi), math.sin(psi), self.settings.max_tilt)
        else:
            xi[3] = xi[4] = 0.0
        xi_dot[3] = xi_dot[4] = 0.0
        xi_ddot[3] = xi_ddot[4] = 0.0
        q, v = xi_to_qv(xi, xi_dot)
        a = xi_ddot_to_a(xi, xi_dot, xi_ddot)
        data = self._data
        tau = pin.rnea(self.model, data, q, v, a)
        u_ref = np.clip(self.W_pinv @ tau, self._plan_lb, self._plan_ub)
        pin.framesForwardKinematics(self.model, data, q)
        return np.concatenate([q, v]), data.oMf[self.ee_frame].copy(), u_ref

    def _references(self, t: float, ref: Reference, ks) -> list:
        """References at the node times t + k h for k in ``ks``."""
        times = np.array([t + k * self.h for k in ks])
        if self.trajectory is not None:
            s = self.trajectory.sample(times)
            return [self._reference(s.xi[i], s.xi_dot[i], s.xi_ddot[i]) for i in range(len(ks))]
        out = []
        for tk in times:  # second-order extrapolation of the current reference
            d = tk - t
            out.append(self._reference(ref.xi + d * ref.xi_dot + 0.5 * d * d * ref.xi_ddot,
                                          ref.xi_dot + d * ref.xi_ddot, ref.xi_ddot))
        return out

    @staticmethod
    def _set(dam: PlatformDynamics, reference) -> None:
        dam.set_reference(*reference)

    # ------------------------------------------------------------------ Controller API
    def set_preview(self, trajectory) -> None:
        """The run's trajectory, previewed over the horizon (the simulator calls this before :meth:`reset`)."""
        if trajectory is not None and not callable(getattr(trajectory, "sample", None)):
            raise InputError(f"trajectory must have a sample(t) method, got {type(trajectory).__name__}")
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
        self._log = {k: [] for k in ("t", "solve_time", "solve_cpu", "step_time", "iterations", "status", "cost", "gap",
                                     "thrust_margin", "fallback", "u")}

    @property
    def planned_thrusts(self) -> np.ndarray | None:
        """Rotor thrusts of the latest solver plan, shape (N, n_rotors) [N] (None before the first solve)."""
        if not self._started:
            return None
        return np.array(self.solver.us)[:, : self.n_rotors]

    def stats(self) -> MPCStats:
        """Per-solve log of the run so far (:class:`MPCStats`)."""
        L = self._log
        return MPCStats(t=np.array(L["t"]), solve_time=np.array(L["solve_time"]), solve_cpu=np.array(L["solve_cpu"]),
                        step_time=np.array(L["step_time"]),
                        iterations=np.array(L["iterations"], dtype=int), status=tuple(L["status"]), cost=np.array(L["cost"]),
                        gap=np.array(L["gap"]), thrust_margin=np.array(L["thrust_margin"]), fallback=tuple(L["fallback"]),
                        u=np.array(L["u"]).reshape(-1, self.nu))

    def report(self) -> tuple[dict[str, float], dict[str, np.ndarray]]:
        """Metrics ``mpc_*`` of :meth:`MPCStats.summary` (times in s, margins in N, counts) and the per-solve series
        ``mpc_t``, ``mpc_solve_time``, ``mpc_solve_cpu``, ``mpc_iterations``, ``mpc_thrust_margin`` (copied into the result)."""
        st = self.stats()
        metrics = {f"mpc_{k}": v for k, v in st.summary().items()}
        metrics["mpc_min_plan_thrust_margin_N"] = metrics.pop("mpc_min_thrust_margin_N")
        metrics["mpc_max_plan_bound_violation_N"] = float(self.max_bound_violation)
        metrics["mpc_fallbacks"] = float(self.fallback_count)
        series = {"mpc_t": st.t, "mpc_solve_time": st.solve_time, "mpc_solve_cpu": st.solve_cpu,
                  "mpc_iterations": st.iterations.astype(float), "mpc_thrust_margin": st.thrust_margin}
        return metrics, series

    def _write_tilt(self, ref: Reference) -> None:
        """Write the feedforward tilt (6.17) of the current reference acceleration into ``ref`` (the logged reference)."""
        a = ref.xi_ddot
        az = a[2] + self.g
        if az > 0.05 * self.g:
            psi = ref.xi[5]
            ref.xi[3], ref.xi[4] = tilt_6_17(a[0], a[1], az, math.cos(psi), math.sin(psi), self.settings.max_tilt)
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


__all__ = ["Fallback", "MPCController", "MPCSettings", "MPCStats", "MPCWeights", "LieState", "PlatformDynamics", "SolveStatus"]
