"""The MPC's node models written on pinocchio's Python API: the tested reference and the fallback.

:class:`LieState` (x = (q, v), pinocchio's integrate/difference and their Jacobians) and
:class:`PlatformDynamics` (a = ABA(q, v, W u), the costs of :mod:`qprr.control.mpc` and their
Gauss-Newton derivatives).  :mod:`qprr.control.mpc_native` builds the same node from crocoddyl's
compiled models, about 6 times faster; tests/test_mpc.py checks the two against each other at
random states.  The controller uses these when crocoddyl's compiled models fail their self-test
(a crocoddyl wheel paired with a pinocchio it was not built for; docs/mpc.md), or on request
(``MPCSettings(backend="python")``).  Each node evaluation costs tens of microseconds of Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..kinematics import com_jacobian_body_from

try:
    import crocoddyl
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    from ..errors import MissingDependencyError
    from .mpc_stats import INSTALL

    raise MissingDependencyError("crocoddyl", "the receding-horizon MPC (qprr.control.mpc)", INSTALL) from exc


@dataclass(frozen=True)
class NodeSpec:
    """What one MPC node needs, shared by both backends.

    ``W`` (nv x nu) tau = W u; ``ee_frame`` index; ``weights``: per residual entry, in the order
    state (2 nv), end effector (6: position, orientation), CoG (2), joint-limit overshoot (nv - 6),
    then on running nodes the controls (nu); ``terminal``; ``u_scale`` (nu,) the control residual is
    u_scale (u - u_ref); ``q_lo``, ``q_hi`` (nv - 6,) the arm's soft limits; ``axis_point`` (3,) a
    point of the thrust axis in B [m]; ``axis_basis`` (2 x 3) rows spanning the plane normal to it.
    """

    W: np.ndarray
    ee_frame: int
    weights: np.ndarray
    terminal: bool
    u_scale: np.ndarray
    q_lo: np.ndarray
    q_hi: np.ndarray
    axis_point: np.ndarray
    axis_basis: np.ndarray

    def split(self, nv: int) -> dict[str, np.ndarray]:
        """The weights by term: ``state``, ``ee``, ``cog``, ``limits`` and (running nodes) ``control``."""
        w = self.weights
        n = 2 * nv
        out = {"state": w[:n], "ee": w[n : n + 6], "cog": w[n + 6 : n + 8], "limits": w[n + 8 : n + 8 + nv - 6]}
        if not self.terminal:
            out["control"] = w[n + 8 + nv - 6 :]
        return out


class LieState(crocoddyl.StateAbstract):
    """x = (q, v) with tangent dx = (dq, dv): q (+) dq = ``pin.integrate`` (LOCAL), as crocoddyl's StateMultibody.

    Integrate, diff and their Jacobians are pinocchio's integrate, difference, dIntegrate,
    dDifference and dIntegrateTransport.
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

    def __init__(self, state: LieState, spec: NodeSpec) -> None:
        if not isinstance(spec, NodeSpec):
            raise InputError(f"spec must be a NodeSpec, got {type(spec).__name__}")
        nu = spec.W.shape[1]
        crocoddyl.DifferentialActionModelAbstract.__init__(self, state, nu, len(spec.weights))
        model = state.model
        self.model = model
        self.spec = spec
        self._pdata = model.createData()
        nq, nv = model.nq, model.nv
        self._nq, self._nv = nq, nv
        self.x_ref = state.zero()
        self.M_ref_inv = pin.SE3.Identity()
        self.u_ref = np.zeros(nu)
        # constant pieces of the derivatives
        self._nx_res = 2 * nv + 8 + (nv - 6)  # residual rows that depend on the state only
        self._w_u = spec.weights[self._nx_res :]
        self._Luu = np.diag(self._w_u * spec.u_scale**2) if not spec.terminal else None
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
        M_rel = self.M_ref_inv * pin.updateFramePlacement(m, self._pdata, self.spec.ee_frame)
        x_ref = self.x_ref
        q_arm = q[7:]
        over = np.minimum(q_arm - self.spec.q_lo, 0.0) + np.maximum(q_arm - self.spec.q_hi, 0.0)
        e_cog = self.spec.axis_basis @ (c_b - self.spec.axis_point)
        r = np.concatenate((pin.difference(m, x_ref[:nq], q), v - x_ref[nq:], pin.log6(M_rel).vector, e_cog, over))
        return r, M_rel

    def residuals(self, x) -> dict[str, np.ndarray]:
        """The state-dependent residuals at x by term: ``state`` (2 nv), ``ee`` (6), ``cog`` (2), ``limits`` (nv - 6)."""
        m, d, nq, nv = self.model, self._pdata, self._nq, self._nv
        q, v = np.asarray(x[:nq], dtype=float), np.asarray(x[nq:], dtype=float)
        c_b = d.oMi[1].actInv(pin.centerOfMass(m, d, q, False))
        r, _ = self._residual_x(q, v, c_b)
        n = 2 * nv
        return {"state": r[:n], "ee": r[n : n + 6], "cog": r[n + 6 : n + 8], "limits": r[n + 8 :]}

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
            data.xout[:] = pin.aba(m, d, q, v, self.spec.W @ u)
        c_b = d.oMi[1].actInv(pin.centerOfMass(m, d, q, False))  # forward kinematics at q, then the CoM in B
        r, _ = self._residual_x(q, v, c_b)
        cost = float(np.dot(self.spec.weights[: r.shape[0]] * r, r))
        if u is not None:
            ru = self.spec.u_scale * (u - self.u_ref)
            cost += float(np.dot(self._w_u * ru, ru))
        data.cost = 0.5 * cost

    def _calc_diff(self, data, x, u) -> None:
        m, d, nq, nv = self.model, self._pdata, self._nq, self._nv
        q, v = x[:nq], x[nq:]
        if u is not None:
            ddq_dq, ddq_dv, Minv = pin.computeABADerivatives(m, d, q, v, self.spec.W @ u)
            data.Fx[:, :nv] = ddq_dq
            data.Fx[:, nv:] = ddq_dv
            data.Fu[:, :] = Minv @ self.spec.W
        # jacobianCenterOfMass also computes the joint Jacobians (documented), used by getFrameJacobian
        J_cog = self.spec.axis_basis @ com_jacobian_body_from(d, pin.jacobianCenterOfMass(m, d, q, False))
        c_b = d.oMi[1].actInv(d.com[0])
        r, M_rel = self._residual_x(q, v, c_b)
        Rx = self._Rx
        Rx[:nv, :nv] = pin.dDifference(m, self.x_ref[:nq], q, pin.ARG1)
        Rx[2 * nv : 2 * nv + 6, :nv] = pin.Jlog6(M_rel) @ pin.getFrameJacobian(m, d, self.spec.ee_frame, pin.LOCAL)
        Rx[2 * nv + 6 : 2 * nv + 8, :nv] = J_cog
        q_arm = q[7:]
        Rx[2 * nv + 8 :, 6:nv] = np.diag(((q_arm < self.spec.q_lo) | (q_arm > self.spec.q_hi)).astype(float))
        w = self.spec.weights[: r.shape[0]]
        data.Lx[:] = Rx.T @ (w * r)
        data.Lxx[:, :] = Rx.T @ (w[:, None] * Rx)
        if u is not None:
            ru = self.spec.u_scale * (u - self.u_ref)
            data.Lu[:] = self.spec.u_scale * (self._w_u * ru)
            data.Luu[:, :] = self._Luu
            data.Lxu[:, :] = 0.0

    def createData(self):
        return crocoddyl.DifferentialActionDataAbstract(self)


__all__ = ["LieState", "NodeSpec", "PlatformDynamics"]
