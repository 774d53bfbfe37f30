"""The MPC's node models built from crocoddyl's compiled models, and the self-test that guards them.

One node (:class:`NativeNode`) is crocoddyl's ``DifferentialActionModelFreeFwdDynamics`` with the
platform's ``ActuationModelFloatingBaseThrusters`` (a = ABA(q, v, W u)) and a ``CostModelSum`` of

* ``state``: ``ResidualModelState`` (x (-) x_ref, LOCAL) with ``ActivationModelWeightedQuad``;
* ``ee``: ``ResidualModelFramePlacement`` (log6(M_ref^-1 M_ee)) with ``ActivationModelWeightedQuad``;
* ``cog``: :class:`CoGOffsetResidual`, E (c_B - a) (the CoM's offset from the thrust axis in the body
  frame, Thesis (3.78) for coplanar rotors).  crocoddyl has no residual in a frame that moves with
  the state (``ResidualModelCoMPosition`` is the CoM in the world frame), so this one small residual
  is written here, on the CoM, its Jacobian and the base placement that the dynamics already
  computed (the armature is set, to zeros, so that crocoddyl 3.2.1's free-forward dynamics take the
  ``computeAllTerms`` path that computes them; on its default ABA path they stay stale);
* ``limits``: ``ResidualModelState`` against the neutral state with the unweighted
  ``ActivationModelQuadraticBarrier`` on the arm joints' soft limits, times a cost weight
  (crocoddyl 3.2.1's ``ActivationModelWeightedQuadraticBarrier`` does not square the weight in its
  Hessian);
* ``control`` (running nodes): ``ResidualModelControl`` with ``ActivationModelWeightedQuad``.

The same costs as :class:`qprr.control.mpc_reference.PlatformDynamics` (tests/test_mpc.py checks
dynamics, costs and derivatives against it at random states).

:func:`self_test` checks that the installed crocoddyl reads the installed pinocchio's ``Model``:
a crocoddyl wheel compiled against another pinocchio reads the members after a layout change at
wrong offsets, silently (crocoddyl 3.2.1, built on pin 4.0, with pin 4.1: the dynamics lose
gravity, frame residuals read garbage).  It runs a free body at rest (u = 0 must give gravity) and
a frame translation residual (a frame at [0, 0, 0.5] m must be there).
"""

from __future__ import annotations

import importlib.metadata

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .mpc_reference import NodeSpec

try:
    import crocoddyl
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    from ..errors import MissingDependencyError
    from .mpc_stats import INSTALL

    raise MissingDependencyError("crocoddyl", "the receding-horizon MPC (qprr.control.mpc)", INSTALL) from exc

SELF_TEST_TOL = 1e-9
"""Largest error (m/s^2, m) the self-test accepts; a consistent pair agrees to rounding."""


def versions() -> str:
    """Installed versions of the pair: "crocoddyl X, pin Y" (distribution metadata)."""
    out = []
    for dist in ("crocoddyl", "pin"):
        try:
            out.append(f"{dist} {importlib.metadata.version(dist)}")
        except importlib.metadata.PackageNotFoundError:
            out.append(f"{dist} (no distribution metadata; module {pin.__version__ if dist == 'pin' else crocoddyl.__version__})")
    return ", ".join(out)


def self_test() -> str:
    """ "" when crocoddyl's compiled models agree with pinocchio on a test body, else what disagreed.

    A free-flyer body (1 kg) with a frame at [0, 0, 0.5] m: the free-forward dynamics at rest with
    u = 0 must return the model's gravity (LOCAL, at the identity pose), the frame translation
    residual the frame's position.
    """
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
    model.appendBodyToJoint(j, pin.Inertia(1.0, np.zeros(3), np.eye(3)), pin.SE3.Identity())
    fid = model.addFrame(pin.Frame("probe", j, 0, pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.5])), pin.FrameType.OP_FRAME))
    state = crocoddyl.StateMultibody(model)
    actuation = crocoddyl.ActuationModelFull(state)
    costs = crocoddyl.CostModelSum(state, actuation.nu)
    probe = crocoddyl.ResidualModelFrameTranslation(state, fid, np.zeros(3), actuation.nu)
    costs.addCost("probe", crocoddyl.CostModelResidual(state, probe), 1.0)
    dam = crocoddyl.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    data = dam.createData()
    dam.calc(data, state.zero(), np.zeros(actuation.nu))
    a_expected = np.r_[model.gravity.linear, np.zeros(3)]
    problems = []
    err = float(np.max(np.abs(np.array(data.xout) - a_expected)))
    if not err <= SELF_TEST_TOL:
        problems.append(
            f"free-forward dynamics at rest with u = 0 give {np.array(data.xout).round(6).tolist()} m/s^2, not gravity {a_expected.tolist()}"
        )
    r = np.array(data.costs.costs["probe"].residual.r)
    if not float(np.max(np.abs(r - [0.0, 0.0, 0.5]))) <= SELF_TEST_TOL:
        problems.append("a frame at [0, 0, 0.5] m is read elsewhere (frame translation residual wrong)")
    return "; ".join(problems)


class CoGOffsetResidual(crocoddyl.ResidualModelAbstract):
    """r = E (c_B - a): the system CoM's offset from the thrust axis, in the plane normal to it (body frame).

    c_B = R^T (c - p) from the CoM c, the base placement (R, p) the dynamics computed (world);
    Jacobian (LOCAL base velocities): E (R^T J_c - [I, -[c_B]x, 0]), as
    :func:`qprr.kinematics.com_jacobian_body_from`.  Reads ``com[0]``, ``Jcom`` and ``oMi[1]`` of the
    shared pinocchio data: the node's dynamics must compute them (armature set, see the module docstring).
    """

    def __init__(self, state, nu: int, axis_point: np.ndarray, axis_basis: np.ndarray) -> None:
        crocoddyl.ResidualModelAbstract.__init__(self, state, 2, nu, True, False, False)
        self.E = np.array(axis_basis, dtype=float)
        self.Ea = self.E @ np.asarray(axis_point, dtype=float)
        self.nv = state.nv

    def calc(self, data, x, u=None) -> None:
        p = data.shared.pinocchio
        M = p.oMi[1]
        data.r[:] = (self.E @ M.rotation.T) @ (p.com[0] - M.translation) - self.Ea

    def calcDiff(self, data, x, u=None) -> None:
        p = data.shared.pinocchio
        M = p.oMi[1]
        J = (self.E @ M.rotation.T) @ p.Jcom
        J[:, 0:3] -= self.E
        J[:, 3:6] += self.E @ pin.skew(M.actInv(p.com[0]))
        data.Rx[:, : self.nv] = J


class NativeNode:
    """One MPC node on crocoddyl's compiled models (module docstring): ``dam`` and :meth:`set_reference`.

    ``state``: crocoddyl's ``StateMultibody`` of the MPC's model; ``actuation``: its
    ``ActuationModelFloatingBaseThrusters``; ``spec``: the node's weights and constants.  A term whose
    weights are all zero is left out (the CoG term then costs nothing).
    """

    def __init__(self, state, actuation, spec: NodeSpec) -> None:
        if not isinstance(spec, NodeSpec):
            raise InputError(f"spec must be a NodeSpec, got {type(spec).__name__}")
        nu, nv = actuation.nu, state.nv
        w = spec.split(nv)
        costs = crocoddyl.CostModelSum(state, nu)
        self.state_residual = crocoddyl.ResidualModelState(state, state.zero(), nu)
        costs.addCost("state", crocoddyl.CostModelResidual(state, crocoddyl.ActivationModelWeightedQuad(w["state"]), self.state_residual), 1.0)
        self.ee_residual = crocoddyl.ResidualModelFramePlacement(state, spec.ee_frame, pin.SE3.Identity(), nu)
        costs.addCost("ee", crocoddyl.CostModelResidual(state, crocoddyl.ActivationModelWeightedQuad(w["ee"]), self.ee_residual), 1.0)
        self.with_cog = bool(np.any(w["cog"] > 0.0))
        if self.with_cog:
            cog = CoGOffsetResidual(state, nu, spec.axis_point, spec.axis_basis)
            costs.addCost("cog", crocoddyl.CostModelResidual(state, crocoddyl.ActivationModelWeightedQuad(w["cog"]), cog), 1.0)
        limited = np.isfinite(spec.q_lo) | np.isfinite(spec.q_hi)
        if np.any(limited) and np.any(w["limits"] > 0.0):
            if np.ptp(w["limits"]) != 0.0:
                raise InputError(f"the joint-limit weights must be equal (one cost weight), got {w['limits'].tolist()}")
            inf = np.full(nv, np.inf)
            lb = np.r_[-inf[:6], spec.q_lo, -inf]
            ub = np.r_[inf[:6], spec.q_hi, inf]
            barrier = crocoddyl.ActivationModelQuadraticBarrier(crocoddyl.ActivationBounds(lb, ub))
            limits = crocoddyl.ResidualModelState(state, state.zero(), nu)
            costs.addCost("limits", crocoddyl.CostModelResidual(state, barrier, limits), float(w["limits"][0]))
        self.control_residual = None
        if not spec.terminal:
            self.control_residual = crocoddyl.ResidualModelControl(state, np.zeros(nu))
            act = crocoddyl.ActivationModelWeightedQuad(w["control"] * spec.u_scale**2)
            costs.addCost("control", crocoddyl.CostModelResidual(state, act, self.control_residual), 1.0)
        self.costs = costs
        self.dam = crocoddyl.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
        if self.with_cog:  # the computeAllTerms path, which computes the CoM and its Jacobian (module docstring)
            self.dam.armature = np.zeros(nv)

    def set_reference(self, x_ref: np.ndarray, M_ref: pin.SE3, u_ref: np.ndarray) -> None:
        """x_ref = (q_ref, v_ref), M_ref the end-effector pose (world), u_ref (nu,) (ignored on the terminal node)."""
        self.state_residual.reference = x_ref
        self.ee_residual.reference = M_ref
        if self.control_residual is not None:
            self.control_residual.reference = u_ref


__all__ = ["SELF_TEST_TOL", "CoGOffsetResidual", "NativeNode", "self_test", "versions"]
