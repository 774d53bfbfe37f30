"""``qprr check``: every checked thesis equation against the running Pinocchio model.

Each :class:`Check` evaluates one printed closed form of :mod:`qprr.thesis.printed` (and, for a
misprint, its corrected form) against the model at seeded random states and returns an
:class:`Evidence` (max error of the printed form, of the corrected form, and the
counter-example).  The verdict rule:

* printed form within tolerance: ``correct`` (or ``correct under <convention>`` when the
  check names the convention under which the printed form was evaluated);
* printed form out of tolerance and corrected form within: ``misprint (corrected form holds)``;
* anything else: ``FAIL`` (exit code 1).

Rows whose optional dependency is missing are ``skipped`` and do not fail.
``docs/thesis-errata.md`` explains every row; ``tests/test_thesis.py`` proves each one.
"""

from __future__ import annotations

import importlib
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

import numpy as np
import pinocchio as pin

from .. import charts as ch
from .. import dynamics as dyn
from .. import kinematics as kin
from ..actuation import Allocator, input_map_matrix
from ..charts import check_rotation, unit_quaternion
from ..errors import InputError, ShapeError
from ..model import Platform, check_platform
from ..nomenclature import mdh
from ..validation import as_array, as_int, as_vector
from . import printed as th
from .robot import ARM_JOINTS, EE_FRAME, load_qprr, params_of, rotor_set

SEED = 20210101
N_STATES = 12


class _Skip(Exception):
    """Raised by a check whose optional dependency is missing."""


@dataclass(frozen=True)
class Evidence:
    """What a check measured: max errors of the printed and corrected forms, and the evidence text."""

    printed_error: float
    corrected_error: float | None = None
    detail: str = ""


@dataclass(frozen=True)
class Check:
    """One row of the table: a thesis equation, the quantity compared, how, and the tolerance."""

    equation: str
    quantity: str
    run: Callable[[CheckContext], Evidence]
    tolerance: float
    convention: str | None = None


class CheckStatus(str, Enum):
    """The outcome of one check (:attr:`CheckResult.status`, equal to its string)."""

    PASS = "pass"
    FAIL = "fail"
    SKIPPED = "skipped"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class CheckResult:
    """Outcome of one check.  ``status`` (:class:`CheckStatus`) is "pass", "fail" or "skipped"; ``reason`` the evidence."""

    equation: str
    quantity: str
    printed_error: float | None
    corrected_error: float | None
    tolerance: float
    verdict: str
    status: CheckStatus
    reason: str

    @property
    def ok(self) -> bool:
        return self.status != CheckStatus.FAIL


@dataclass
class CheckContext:
    """The Q-PRR platform and the seeded random states every check uses."""

    platform: Platform
    data: pin.Data
    rng: np.random.Generator
    states: list = field(default_factory=list)
    cache: dict = field(default_factory=dict)

    @property
    def params(self):
        return params_of(self.platform)

    @property
    def d(self):
        return th.d_lengths(self.params)

    def random_xi(self, rng: np.random.Generator | None = None, max_tilt: float = 1.3) -> np.ndarray:
        """A random xi: position in [-2, 2]^3 m, |phi|, |theta| < max_tilt, any psi, arm inside its limits."""
        rng = rng or self.rng
        p = self.params
        return np.concatenate(
            [
                rng.uniform(-2.0, 2.0, 3),
                rng.uniform(-max_tilt, max_tilt, 2),
                rng.uniform(-np.pi, np.pi, 1),
                rng.uniform(p.lower_limits, p.upper_limits),
            ]
        )


def make_context(platform: Platform | None = None, seed: int = SEED, n_states: int = N_STATES) -> CheckContext:
    """The context of the checks on ``platform`` (default: the thesis's Q-PRR, :func:`qprr.thesis.load_qprr`)."""
    seed = as_int(seed, "seed", lo=0)
    n_states = as_int(n_states, "n_states", lo=1)
    platform = platform if platform is not None else load_qprr("thesis")
    params_of(platform)  # a Q-PRR, or InputError
    ctx = CheckContext(platform, platform.data(), np.random.default_rng(seed))
    ctx.states = [(ctx.random_xi(), ctx.rng.normal(size=9)) for _ in range(n_states)]
    return ctx


# ----------------------------------------------------------------------------- helpers
def _maxabs(a) -> float:
    return float(np.max(np.abs(np.asarray(a, dtype=float))))


def _wrap(a) -> np.ndarray:
    return (np.asarray(a, dtype=float) + np.pi) % (2 * np.pi) - np.pi


def _R(xi) -> np.ndarray:
    """R_b from Pinocchio's own RPY routine (independent of qprr.charts)."""
    return pin.rpy.rpyToMatrix(float(xi[3]), float(xi[4]), float(xi[5]))


def _q(xi) -> np.ndarray:
    return ch.xi_to_q(xi)


def body_rate_fd(euler, euler_dot, h: float = 1e-6) -> np.ndarray:
    """omega_body = (R^T R_dot)^vee by central differences on SO(3) (Thesis (3.19))."""
    e, w = np.asarray(euler, dtype=float), np.asarray(euler_dot, dtype=float)
    Rm, Rp = pin.rpy.rpyToMatrix(*(e - h * w)), pin.rpy.rpyToMatrix(*(e + h * w))
    return pin.log3(Rm.T @ Rp) / (2 * h)


def _plus(ctx: CheckContext) -> Platform:
    """The context's Q-PRR with the "+" rotor layout of Thesis (3.34)-(3.36) (the printed allocation rows use it)."""
    if ctx.platform.rotors == rotor_set(ctx.params, "plus"):
        return ctx.platform
    if "plus" not in ctx.cache:
        ctx.cache["plus"] = load_qprr(ctx.params, layout="plus")
    return ctx.cache["plus"]


_TURN_X = pin.SE3(ch.rot_x(np.pi), np.zeros(3))


def ned_configuration(q) -> np.ndarray:
    """The configuration at which our z-up model (gravity -g e3) feels what ``q`` feels in an NED world (gravity +g e3).

    Thesis (3.42)-(3.43) take gravity along +e3.  Turning the whole robot by pi about the world
    x axis (p_b -> Rx(pi) p_b, R_b -> Rx(pi) R_b) keeps every body-frame quantity and every
    joint value and turns the gravity seen in B, R_b^T (-g e3), into R_b^T (+g e3); centres of
    mass map as c -> Rx(pi) c, so e3 . c changes sign.  Potential energies and gravity wrenches
    of the NED world at ``q`` are therefore those of the z-up model at the returned configuration.
    """
    q = as_array(q, "q", finite=True, ndim=1)
    if q.shape[0] < 7:
        raise ShapeError(f"q must be a configuration (7 + n_arm,), got shape {q.shape}")
    unit_quaternion(q[3:7], "q[3:7]")
    q = np.array(q, dtype=float)
    q[0:7] = pin.SE3ToXYZQUAT(_TURN_X * pin.XYZQUATToSE3(q[0:7]))
    return q


def fixed_base_arm(platform: Platform, base_rotation=None) -> tuple[pin.Model, pin.Data]:
    """The arm with the free-flyer locked at the origin with orientation ``base_rotation`` (Sec. 5.5 model)."""
    check_platform(platform)
    if base_rotation is not None:
        base_rotation = check_rotation(base_rotation, "base_rotation", 1e-9)
    q_ref = pin.neutral(platform.model)
    if base_rotation is not None:
        q_ref[3:7] = pin.Quaternion(np.asarray(base_rotation, dtype=float)).coeffs()
    model = pin.buildReducedModel(platform.model, [1], q_ref)  # joint 1: the free flyer
    return model, model.createData()


def christoffel(model: pin.Model, data: pin.Data, q, v) -> np.ndarray:
    """C_ij = sum_k 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) v_k for a model with nq = nv (Thesis (5.35)).

    dM/dq_k from RNEA derivatives: d(M e_j)/dq = dtau/dq(q, 0, e_j) - dg/dq.
    """
    if not isinstance(model, pin.Model) or not isinstance(data, pin.Data):
        raise InputError(f"model and data must be a pinocchio.Model and its Data, got {type(model).__name__}, {type(data).__name__}")
    if model.nq != model.nv:
        raise InputError(f"christoffel needs a model with nq = nv (a fixed-base arm), got nq = {model.nq}, nv = {model.nv}")
    if len(data.oMf) != model.nframes:
        raise ShapeError("data was made for another model: use model.createData()")
    q, v = as_vector(q, model.nq, "q"), as_vector(v, model.nv, "v")
    n = model.nv
    dg = pin.computeGeneralizedGravityDerivatives(model, data, q).copy()
    dM = np.zeros((n, n, n))  # dM[i, j, k] = dM_ij / dq_k
    for j in range(n):
        dtau, _, _ = pin.computeRNEADerivatives(model, data, q, np.zeros(n), np.eye(n)[j])
        dM[:, j, :] = dtau - dg
    return 0.5 * (np.einsum("ijk,k->ij", dM, v) + np.einsum("ikj,k->ij", dM, v) - np.einsum("jki,k->ij", dM, v))


def _mass_matrix(model: pin.Model, data: pin.Data, q) -> np.ndarray:
    M = pin.crba(model, data, q)
    return np.triu(M) + np.triu(M, 1).T


def _arm_samples(ctx: CheckContext, n: int = N_STATES):
    rng = np.random.default_rng(SEED + 7)
    p = ctx.params
    return [(rng.uniform(p.lower_limits, p.upper_limits), rng.normal(size=3), rng.normal(size=3)) for _ in range(n)]


def _bad_entries(err: np.ndarray, tol: float, names) -> str:
    idx = [names[i] for i in np.flatnonzero(np.max(err.reshape(err.shape[0], -1), axis=0) > tol)]
    return ", ".join(idx) if idx else "none"


# ------------------------------------------------------------------------------ chapter 3
def _c_3_4(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.rotation_3_4(*xi[3:6]) - _R(xi)) for xi, _ in ctx.states)
    return Evidence(err, None, "printed entries vs pinocchio.rpy.rpyToMatrix(phi, theta, psi) = Rz Ry Rx")


def _c_3_8(ctx: CheckContext) -> Evidence:
    ep, ec, worst = 0.0, 0.0, None
    for xi, _ in ctx.states:
        R = _R(xi)
        e1 = _maxabs(_wrap(th.euler_3_8(R) - xi[3:6]))
        ec = max(ec, _maxabs(_wrap(th.euler_3_8_corrected(R) - xi[3:6])))
        if e1 > ep:
            ep, worst = e1, (xi[3:6], th.euler_3_8(R))
    return Evidence(
        ep,
        ec,
        f"(phi, theta, psi) = {np.round(worst[0], 3).tolist()} -> printed (3.8) returns {np.round(worst[1], 3).tolist()}: roll and yaw swapped",
    )


def _c_3_25(ctx: CheckContext) -> Evidence:
    e_body, e_world = 0.0, 0.0
    for xi, xid in ctx.states:
        w_fd = body_rate_fd(xi[3:6], xid[3:6])
        Tw = th.T_3_25(xi[3], xi[4]) @ xid[3:6]
        e_body = max(e_body, _maxabs(Tw - w_fd))
        e_world = max(e_world, _maxabs(Tw - _R(xi) @ w_fd))
    return Evidence(
        e_body,
        None,
        f"T phi_dot vs (R^T R_dot)^vee by central differences; as a world-frame rate "
        f"(R omega_body), as (3.15) suggests, the error would be {e_world:.2g} rad/s",
    )


def _c_3_36(ctx: CheckContext) -> Evidence:
    p = ctx.params
    Om = _plus(ctx).rotor_matrix
    ep = max(_maxabs(Om[2:6] - th.allocation_3_36(p.arm_length, p.drag_factor)), _maxabs(Om[0:2]))
    ec = max(_maxabs(Om[2:6] - th.allocation_3_36_corrected(p.arm_length, p.thrust_factor, p.drag_factor)), _maxabs(Om[0:2]))
    return Evidence(
        ep,
        ec,
        f"yaw row printed c = {p.drag_factor:g} N m s^2, the force map needs c/b = {p.kappa:g} m "
        "(tau_i = c w_i^2 = (c/b) f_i); rows 1-3 agree with the rotor frames of the URDF",
    )


def _c_3_37(ctx: CheckContext) -> Evidence:
    p = ctx.params
    model_w2 = p.thrust_factor * _plus(ctx).rotor_matrix[2:6]  # u = Omega_z (b w^2)
    P = th.allocation_3_37(p.thrust_factor, p.arm_length, p.drag_factor)
    scale = _maxabs(model_w2)
    ep = _maxabs(P - model_w2) / scale
    ec = _maxabs(th.allocation_3_37_corrected(p.thrust_factor, p.arm_length, p.drag_factor) - model_w2) / scale
    return Evidence(
        ep,
        ec,
        f"relative to max|entry|; row 3 printed (-lb, 0, lb, 0) = {np.round(P[2], 8).tolist()}, model and (3.34): "
        f"tau_theta = bl(w1^2 - w3^2) -> {np.round(model_w2[2], 8).tolist()}",
    )


def _c_det_3_37(ctx: CheckContext) -> Evidence:
    p = ctx.params
    b, l, c = p.thrust_factor, p.arm_length, p.drag_factor
    true = np.linalg.det(b * _plus(ctx).rotor_matrix[2:6])
    printed_matrix = np.linalg.det(th.allocation_3_37(b, l, c))
    ep = abs(th.det_3_37(b, l, c) - printed_matrix) / abs(printed_matrix)
    ec = abs(th.det_3_37_corrected(b, l, c) - true) / abs(true)
    return Evidence(
        ep,
        ec,
        f"relative error vs the determinant of the (3.37) matrix as printed: the statement holds for that "
        f"matrix. Not a separate misprint: with row 3 corrected (row (3.37) above) the model map's determinant "
        f"is {true:.4g} = -8 c l^2 b^3 (rel. err {ec:.1g}); invertibility holds either way",
    )


def _c_A1(ctx: CheckContext) -> Evidence:
    p = ctx.params
    l, b, c = p.arm_length, p.thrust_factor, p.drag_factor
    model_inv = Allocator(_plus(ctx)).Omega_P_inv  # inv(Omega[2:6]): the exact path of the four-rotor allocation
    ep = _maxabs(th.rotor_inverse_A1(l, p.kappa) - model_inv)
    ec = _maxabs(th.rotor_inverse_A1_corrected(l, b, c) - model_inv)
    selfc = _maxabs(th.rotor_inverse_A1(l, c) @ th.allocation_3_36(l, c) - np.eye(4))
    return Evidence(
        ep,
        ec,
        f"printed inverse read with c -> c/b vs inv(Omega_z); the printed inverse is not even the inverse "
        f"of its own (A.1) matrix: max|A1 (A.1) - I| = {selfc:.3g} (tau_theta column signs of f1, f3)",
    )


def _arm_states(ctx: CheckContext):
    return [(ch.euler_to_rotation(xi[3:6]), xi[6:9], xi) for xi, _ in ctx.states]


def _c_3_42(ctx: CheckContext) -> Evidence:
    up, du = ctx.platform, ctx.data
    ep = ec = 0.0
    for R, q_arm, xi in _arm_states(ctx):
        x0 = xi.copy()
        x0[0:3] = 0.0  # (3.42) has no p_b term: base at the origin (the multirotor then has U = 0)
        q = _q(x0)
        printed = th.potential_3_42(R, q_arm, ctx.params)
        ep = max(ep, abs(printed - dyn.potential_energy(up, du, ned_configuration(q))))
        ec = max(ec, abs(-printed - dyn.potential_energy(up, du, q)))
    return Evidence(
        ep,
        ec,
        "vs Pinocchio potential energy with gravity +g e3 (NED, as (3.42) implies), base at the origin; "
        "in the z-up world of (5.27)-(5.29) the sign is opposite: U = -U_(3.42) there",
    )


def _c_3_43(ctx: CheckContext) -> Evidence:
    ep = ec = flip = 0.0
    for R, q_arm, xi in _arm_states(ctx):
        q = _q(xi)
        printed = th.arm_torque_3_43(R, q_arm, ctx.params)
        ep = max(ep, _maxabs(printed - kin.arm_gravity_torque_body(ctx.platform, ctx.data, ned_configuration(q))))
        model_up = kin.arm_gravity_torque_body(ctx.platform, ctx.data, q)
        ec = max(ec, _maxabs(th.arm_torque_3_43_corrected(R, q_arm, ctx.params) - model_up))
        flip = max(flip, _maxabs(printed - model_up))
    return Evidence(
        ep,
        ec,
        f"vs RNEA torque of the arm on B with gravity +g e3 (NED of (3.42)); in our z-up model the printed "
        f"sign is opposite (max error {flip:.3g} N m), -m_G g xi_c x R_b^T e3 holds",
    )


def _c_3_44(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.arm_com_3_44(xi[6:9], ctx.params) - kin.arm_com(ctx.platform, ctx.data, _q(xi))[2]) for xi, _ in ctx.states)
    return Evidence(err, None, "arm CoM in B vs Pinocchio subtree CoM (Hypothesis 1 link CoMs of (3.78))")


def _c_3_58(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.T_eb_3_58(xi[6:9], ctx.d) - kin.ee_placement_body(ctx.platform, ctx.data, _q(xi)).homogeneous) for xi, _ in ctx.states)
    return Evidence(err, None, "^bT_eb vs Pinocchio end-effector placement relative to B")


def _c_3_61(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    worst = None
    for xi, _ in ctx.states:
        p = kin.ee_placement(ctx.platform, ctx.data, _q(xi)).translation
        e = _maxabs(th.p_e_3_61(xi, ctx.d) - p)
        ec = max(ec, _maxabs(th.p_e_3_61_corrected(xi, ctx.d) - p))
        if e > ep:
            ep, worst = e, (xi, th.p_e_3_61(xi, ctx.d)[1], p[1])
    return Evidence(
        ep,
        ec,
        f"y_e printed with c_theta c_psi x_eb: at xi = {np.round(worst[0], 3).tolist()} printed y_e = "
        f"{worst[1]:.4f}, model {worst[2]:.4f}; (3.65) prints the right c_theta s_psi",
    )


def _c_3_62(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.R_e_3_62(*xi[3:6], xi[7], xi[8]) - kin.ee_placement(ctx.platform, ctx.data, _q(xi)).rotation) for xi, _ in ctx.states)
    return Evidence(err, None, "R_e entries vs Pinocchio end-effector rotation")


def _c_3_64(ctx: CheckContext) -> Evidence:
    ep = zyx = 0.0
    for xi, _ in ctx.states:
        R = kin.ee_placement(ctx.platform, ctx.data, _q(xi)).rotation
        if np.hypot(R[0, 2], R[1, 2]) < 1e-6:  # (3.64) assumes r13, r23 not both zero
            continue
        ang = th.euler_3_64(R)
        ep = max(ep, _maxabs(th.zyz_to_rotation(ang) - R))
        zyx = max(zyx, _maxabs(th.rotation_3_4(*ang) - R))
    return Evidence(
        ep,
        None,
        f"Rz(phi_e) Ry(theta_e) Rz(psi_e) rebuilds R_e; read as ZYX angles like (3.4)/(3.8) the same numbers give a rotation off by {zyx:.3g}",
    )


def _c_3_65(ctx: CheckContext) -> Evidence:
    err = 0.0
    for xi, _ in ctx.states:
        M = kin.ee_placement(ctx.platform, ctx.data, _q(xi))
        chi = th.fk_3_65(xi, ctx.d)
        err = max(err, _maxabs(chi[0:3] - M.translation))
        if np.hypot(M.rotation[0, 2], M.rotation[1, 2]) > 1e-6:  # ZYZ angles defined
            err = max(err, _maxabs(th.zyz_to_rotation(chi[3:6]) - M.rotation))
    return Evidence(err, None, "position vs Pinocchio; angles rebuild R_e through Rz Ry Rz")


def _hover_states(ctx: CheckContext):
    rng = np.random.default_rng(SEED + 3)
    out = []
    while len(out) < N_STATES:
        xi = ctx.random_xi(rng)
        xi[3:5] = 0.0
        s23 = np.sin(xi[7] + xi[8])
        if abs(s23) > 1e-3 and (len(out) % 2 == 0) == (s23 > 0):  # alternate the sign of s23
            out.append(xi)
    return out


def _c_3_68_pos(ctx: CheckContext) -> Evidence:
    err = 0.0
    for xi in _hover_states(ctx):
        p = kin.ee_placement(ctx.platform, ctx.data, _q(xi)).translation
        err = max(err, _maxabs(th.hover_fk_3_68(*xi[0:3], xi[5], xi[6:9], ctx.d)[0:3] - p))
    return Evidence(err, None, "lines 1-3 at phi = theta = 0 vs Pinocchio")


def _c_3_68_ang(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    worst = None
    for xi in _hover_states(ctx):
        R = kin.ee_placement(ctx.platform, ctx.data, _q(xi)).rotation
        ref = th.euler_3_64(R)
        printed = th.hover_fk_3_68(*xi[0:3], xi[5], xi[6:9], ctx.d)[3:6]
        e = _maxabs(_wrap(printed - ref))
        ec = max(ec, _maxabs(_wrap(th.hover_fk_3_68_corrected(*xi[0:3], xi[5], xi[6:9], ctx.d)[3:6] - ref)))
        if e > ep:
            ep, worst = e, (xi, printed, ref)
    return Evidence(
        ep,
        ec,
        f"lines 4-6 vs (3.64) of the model R_e at phi = theta = 0: psi = {worst[0][5]:.3f}, "
        f"theta2 + theta3 = {worst[0][7] + worst[0][8]:.3f} -> printed {np.round(worst[1], 3).tolist()}, "
        f"true {np.round(worst[2], 3).tolist()}",
    )


def _c_3_78_xy(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.com_3_78(xi[6:9], ctx.params)[0:2] - kin.com_body(ctx.platform, ctx.data, _q(xi))[0:2]) for xi, _ in ctx.states)
    return Evidence(err, None, "x_cm, y_cm in B vs Pinocchio centre of mass")


def _c_3_78_z(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    for xi, _ in ctx.states:
        z = kin.com_body(ctx.platform, ctx.data, _q(xi))[2]
        ep = max(ep, abs(th.com_3_78(xi[6:9], ctx.params)[2] - z))
        ec = max(ec, abs(th.com_3_78_corrected(xi[6:9], ctx.params)[2] - z))
    m1, m2, m3 = (k.mass for k in ctx.params.links)
    return Evidence(
        ep,
        ec,
        f"printed sum m_i (d0 + d1) overcounts link 1 by m1 d1/2 = {m1 * ctx.params.d1 / 2:.3g} kg m and "
        f"(m2 + m3) d2 c2 / 2 undercounts link 3 by m3 d2 c2 / 2 ({m3 * ctx.params.d2 / 2:.3g} c2 kg m)",
    )


def _c_3_80(ctx: CheckContext) -> Evidence:
    err = max(abs(th.x_cm_3_80(xi[6:9], ctx.params) - kin.com_body(ctx.platform, ctx.data, _q(xi))[0]) for xi, _ in ctx.states)
    return Evidence(err, None, "F(r0, theta2, theta3) vs Pinocchio x_cm")


# ------------------------------------------------------------ modified Denavit-Hartenberg
def _urdf_arm(ctx: CheckContext):
    """The URDF arm with its base locked at the origin (frames in B), cached per context."""
    if "urdf_arm" not in ctx.cache:
        ctx.cache["urdf_arm"] = fixed_base_arm(ctx.platform)
    return ctx.cache["urdf_arm"]


def urdf_arm_frames(model: pin.Model, data: pin.Data, q_arm) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """(joint placements in B (4x4) of r0, theta2, theta3; their joint axes in B; the end-effector pose in B).

    ``model`` is the URDF arm with a locked base (:func:`fixed_base_arm`).  A joint axis is the
    angular (revolute) or linear (prismatic) part of the joint's own column of its WORLD Jacobian.
    """
    pin.computeJointJacobians(model, data, q_arm)
    pin.updateFramePlacements(model, data)
    placements, axes = [], []
    for name in ARM_JOINTS:
        jid = model.getJointId(name)
        placements.append(data.oMi[jid].homogeneous.copy())
        col = pin.getJointJacobian(model, data, jid, pin.WORLD)[:, model.joints[jid].idx_v]
        axes.append(col[3:6].copy() if np.linalg.norm(col[3:6]) > 0.5 else col[0:3].copy())
    return placements, axes, data.oMf[model.getFrameId(EE_FRAME)].homogeneous.copy()


def mdh_frame_errors(frames, model: pin.Model, data: pin.Data, q_arm) -> dict[str, float]:
    """Frame-by-frame distance between an MDH chain and the URDF arm at ``q_arm``.

    ``frames`` = [^bT_1, ^bT_2, ^bT_3, ^bT_4, ^bT_eb] (4x4, in B).  Returns max-abs errors of:
    "origins" (R_1..R_3 vs the URDF joint frames, R_4 vs the end effector), "axes" (z_1..z_3
    vs the URDF joint axes, sign included), "end effector" (^bT_eb vs the URDF pose) and
    "offsets" R_urdf^T R_mdh of R_1..R_3 (returned for the caller to compare across q).
    """
    placements, axes, ee = urdf_arm_frames(model, data, q_arm)
    frames = [np.asarray(F, dtype=float) for F in frames]
    origins = [F[0:3, 3] - M[0:3, 3] for F, M in zip(frames[0:3], placements)]
    origins.append(frames[3][0:3, 3] - ee[0:3, 3])
    return {
        "origins": _maxabs(origins),
        "axes": _maxabs([F[0:3, 2] - a for F, a in zip(frames[0:3], axes)]),
        "end effector": _maxabs(frames[4] - ee),
        "offsets": np.array([M[0:3, 0:3].T @ F[0:3, 0:3] for F, M in zip(frames[0:3], placements)]),
    }


def _arm_qs(ctx: CheckContext) -> list[np.ndarray]:
    return [xi[6:9] for xi, _ in ctx.states]


def _chain_vs_urdf(ctx: CheckContext, frames_fn) -> tuple[float, dict[str, float]]:
    """Max frame-by-frame error of ``frames_fn(q_arm)`` over the seeded arm states (offsets must stay constant)."""
    model, data = _urdf_arm(ctx)
    worst = {"origins": 0.0, "axes": 0.0, "end effector": 0.0, "offsets": 0.0}
    ref = None
    for q in _arm_qs(ctx):
        e = mdh_frame_errors(frames_fn(q), model, data, q)
        ref = e["offsets"] if ref is None else ref
        e["offsets"] = _maxabs(e["offsets"] - ref)
        worst = {k: max(worst[k], e[k]) for k in worst}
    return max(worst.values()), worst


def _fmt(errs: dict[str, float]) -> str:
    return ", ".join(f"{k} {v:.1g}" for k, v in errs.items())


def _mdh_chain(rows, transform=None):
    kw = {} if transform is None else {"transform": transform}
    return lambda q: mdh.chain(rows, q, base=th.T_b0_3_49(), tool=th.T_4eb_3_51(), **kw)


def _c_3_27(ctx: CheckContext) -> Evidence:
    rows = th.table_3_4_corrected(ctx.d)
    err, parts = _chain_vs_urdf(ctx, _mdh_chain(rows))
    model = mdh.build_model(rows, base=th.T_b0_3_49(), tool=th.T_4eb_3_51())
    data = model.createData()
    urdf, udata = _urdf_arm(ctx)
    tool, ee = model.getFrameId(mdh.TOOL_FRAME), urdf.getFrameId(EE_FRAME)
    e_pin = 0.0
    for q in _arm_qs(ctx):
        frames = _mdh_chain(rows)(q)
        pin.framesForwardKinematics(model, data, q)
        e_pin = max(e_pin, max(_maxabs(data.oMf[model.getFrameId(mdh.frame_name(j))].homogeneous - frames[j - 1]) for j in range(1, 5)))
        J = pin.computeFrameJacobian(model, data, q, tool, pin.LOCAL_WORLD_ALIGNED)
        Ju = pin.computeFrameJacobian(urdf, udata, q, ee, pin.LOCAL_WORLD_ALIGNED)
        e_pin = max(e_pin, _maxabs(J - Ju))
    return Evidence(
        max(err, e_pin),
        None,
        f"chain (3.29)-(3.30) of the product (3.27) with Table 3.4 (alpha = pi/2 on the theta2 "
        f"row, as (3.53)), ^bT_0 (3.49), ^4T_eb (3.51), frame by frame vs the URDF: {_fmt(parts)}; the Pinocchio "
        f"model built from the table (qprr.nomenclature.mdh.build_model): frames and end-effector Jacobian vs the URDF {e_pin:.1g}",
    )


def _c_3_28(ctx: CheckContext) -> Evidence:
    rows = th.table_3_4_corrected(ctx.d)
    ep, parts = _chain_vs_urdf(ctx, _mdh_chain(rows, th.mdh_3_28))
    ec, _ = _chain_vs_urdf(ctx, _mdh_chain(rows, th.mdh_3_28_corrected))
    rng = np.random.default_rng(SEED + 28)
    direct = orth = 0.0
    for _ in range(N_STATES):
        a, d, t, r = rng.uniform(-np.pi, np.pi), rng.normal(), rng.uniform(-np.pi, np.pi), rng.normal()
        P = th.mdh_3_28(a, d, t, r)
        direct = max(direct, _maxabs(P - mdh.kk_transform(a, d, t, r)))
        orth = max(orth, _maxabs(P[0:3, 0:3].T @ P[0:3, 0:3] - np.eye(3)))
        ec = max(ec, _maxabs(th.mdh_3_28_corrected(a, d, t, r) - mdh.kk_transform(a, d, t, r)))
    return Evidence(
        max(ep, direct),
        ec,
        f"entry (1,2) printed +sin(theta), the product (3.27) gives -sin(theta): vs the product "
        f"{direct:.2g}; as printed R^T R - I reaches {orth:.2g} (not a rotation); chained as in (3.29) vs the URDF: "
        f"{_fmt(parts)}",
    )


def _c_table_3_4(ctx: CheckContext) -> Evidence:
    ep, parts = _chain_vs_urdf(ctx, _mdh_chain(th.table_3_4(ctx.d)))
    ec, _ = _chain_vs_urdf(ctx, _mdh_chain(th.table_3_4_corrected(ctx.d)))
    z2 = mdh.chain(th.table_3_4(ctx.d), np.zeros(3), base=th.T_b0_3_49())[1][0:3, 2]
    return Evidence(
        ep,
        ec,
        f"printed alpha = pi on the theta2 row puts z_2 = {np.round(z2, 12).tolist()} (the slider axis), "
        f"the URDF joint theta2 turns about +y_B; frame by frame: {_fmt(parts)}; alpha = pi/2, as (3.53) is printed, holds",
    )


def _required_tool(ctx: CheckContext, q) -> np.ndarray:
    """^4T_eb that ends the chain (3.49) + Table 3.4 (corrected) on the URDF end effector: (^bT_4)^-1 ^bT_eb."""
    model, data = _urdf_arm(ctx)
    T_b4 = mdh.chain(th.table_3_4_corrected(ctx.d), q, base=th.T_b0_3_49())[-1]
    return np.linalg.solve(T_b4, urdf_arm_frames(model, data, q)[2])


def _c_3_48(ctx: CheckContext) -> Evidence:
    model, data = _urdf_arm(ctx)
    stated = _maxabs(th.T_b0_3_48() - th.T_b0_3_49())
    req = 0.0
    for q in _arm_qs(ctx):  # ^bT_0 that ends (3.27)-(3.30) with (3.51) on the URDF end effector
        T_0eb = mdh.chain(th.table_3_4_corrected(ctx.d), q, tool=th.T_4eb_3_51())[-1]
        req = max(req, _maxabs(urdf_arm_frames(model, data, q)[2] @ np.linalg.inv(T_0eb) - th.T_b0_3_49()))
    return Evidence(
        max(stated, req),
        None,
        f"Rot(y, pi/2) Rot(z, pi) vs the printed matrix (3.49): {stated:.1g}; the ^bT_0 the URDF "
        f"requires (end effector times the inverse of ^0T_eb) vs (3.49): {req:.1g}; z_0 = x_B, the slider axis",
    )


def _c_3_50(ctx: CheckContext) -> Evidence:
    ep = max(_maxabs(th.T_4eb_3_50() - _required_tool(ctx, q)) for q in _arm_qs(ctx))
    ec = max(_maxabs(th.T_4eb_3_50_corrected() - _required_tool(ctx, q)) for q in _arm_qs(ctx))
    return Evidence(
        ep,
        ec,
        f"Rot(y, pi/2) Rot(z, -pi/2) = {np.round(th.T_4eb_3_50()[0:3, 0:3], 12).astype(int).tolist()} vs the "
        f"^4T_eb the URDF requires ((^bT_4)^-1 ^bT_eb, constant): the matrix printed as its result (3.51) is "
        f"Rot(y, pi/2) Rot(z, +pi/2)",
    )


def _c_3_51(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.T_4eb_3_51() - _required_tool(ctx, q)) for q in _arm_qs(ctx))
    return Evidence(err, None, "printed matrix vs the ^4T_eb the URDF requires ((^bT_4)^-1 ^bT_eb, constant over q)")


def _c_3_52(ctx: CheckContext) -> Evidence:
    d0, d1, d2, d3 = ctx.d
    rows, printed_rows = th.table_3_4_corrected(ctx.d), th.table_3_4(ctx.d)
    e_kk = e_tab = 0.0
    for q in _arm_qs(ctx):
        r0, t2, t3 = q
        printed = (th.T_01_3_52(r0, d0), th.T_12_3_53(t2, d1), th.T_23_3_54(t3, d2), th.T_34_3_55(d3))
        values = (r0, t2, t3, 0.0)
        e_kk = max(e_kk, max(_maxabs(P - row.transform(v)) for P, row, v in zip(printed, rows, values)))
        e_tab = max(e_tab, _maxabs(printed[1] - printed_rows[1].transform(t2)))
    err, parts = _chain_vs_urdf(ctx, lambda q: th.mdh_frames_3_56(q, ctx.d))
    return Evidence(
        max(e_kk, err),
        None,
        f"each printed matrix vs (3.27) of its row {e_kk:.1g}; chained, frame by frame vs the URDF: "
        f"{_fmt(parts)}; (3.53) is printed with alpha = pi/2: vs (3.27) of the printed Table 3.4 row (alpha = pi) "
        f"it is off by {e_tab:.2g}",
    )


def _c_3_56(ctx: CheckContext) -> Evidence:
    model, data = _urdf_arm(ctx)
    e_urdf = max(_maxabs(th.T_eb_3_56(q, ctx.d) - urdf_arm_frames(model, data, q)[2]) for q in _arm_qs(ctx))
    e_58 = max(_maxabs(th.T_eb_3_56(q, ctx.d) - th.T_eb_3_58(q, ctx.d)) for q in _arm_qs(ctx))
    return Evidence(
        max(e_urdf, e_58),
        None,
        f"product of the printed (3.49), (3.52)-(3.55), (3.51) vs the URDF end effector ({e_urdf:.1g}) and vs (3.58) ({e_58:.1g})",
    )


# ------------------------------------------------------------------ payload in (3.76)-(3.78)
PAYLOAD_MASS, PAYLOAD_OFFSET = 0.1, 0.03
"""m_l [kg] (the 0.1 kg of Sec. 6.4.1) and d_cl [m] of the payload rows."""


def _payload(ctx: CheckContext):
    if "payload" not in ctx.cache:
        from ..payload import Payload, com_with_payload

        held = Payload(PAYLOAD_MASS, com_ee=(0.0, 0.0, PAYLOAD_OFFSET))
        ctx.cache["payload"] = (held, com_with_payload)
    return ctx.cache["payload"]


def _c_3_76(ctx: CheckContext) -> Evidence:
    err = 0.0
    for xi, _ in ctx.states:
        M = kin.ee_placement_body(ctx.platform, ctx.data, _q(xi))
        err = max(err, _maxabs(th.payload_com_3_76(xi[6:9], ctx.d, PAYLOAD_OFFSET) - M.act(np.array([0.0, 0.0, PAYLOAD_OFFSET]))))
    return Evidence(
        err,
        None,
        f"p_cl at d_cl = {PAYLOAD_OFFSET} m beyond the end effector along link 3 vs Pinocchio (end-effector placement in B applied to (0, 0, d_cl))",
    )


def _c_3_78_payload(ctx: CheckContext) -> Evidence:
    held, com_with_payload = _payload(ctx)
    m_l, d_cl = PAYLOAD_MASS, PAYLOAD_OFFSET
    ep = ec = ez = 0.0
    worst = None
    for xi, _ in ctx.states:
        ref = com_with_payload(ctx.platform, ctx.data, xi[6:9], held)
        printed = th.com_3_78(xi[6:9], ctx.params, m_l=m_l, d_cl=d_cl)
        e = abs(printed[0] - ref[0])
        ez = max(ez, abs(printed[2] - ref[2]))
        ec = max(ec, _maxabs(th.com_3_78_corrected(xi[6:9], ctx.params, m_l=m_l, d_cl=d_cl) - ref))
        if e > ep:
            ep, worst = e, (xi[6:9], printed[0], ref[0])
    return Evidence(
        ep,
        ec,
        f"x_cm (whose only misprint is the payload term) with m_l = {m_l} kg at d_cl = {d_cl} m vs Pinocchio "
        f"(qprr.payload.com_with_payload): at q_arm = {np.round(worst[0], 3).tolist()} printed {worst[1]:.5f} m, model "
        f"{worst[2]:.5f} m; printed - true = (1 - m_l[kg]) x_cl / m_G: '+ x_cl' adds a length to kg m; z_cm is off by "
        f"{ez:.2g} m (payload term and the z_cm misprint above); the corrected form (m_l p_cl, (3.76)) holds in x, y, z",
    )


# ------------------------------------------------------------------------------ chapter 4
def _ee_body_fd(ctx: CheckContext, q_arm, h: float = 1e-6) -> np.ndarray:
    """J_eb by central differences: [d p_eb; log3(R_eb^- ^T R_eb^+) expressed in B] / 2h."""
    J = np.zeros((6, 3))
    for k in range(3):
        dq = np.eye(3)[k] * h
        Mp = th.T_eb_3_58(q_arm + dq, ctx.d)
        Mm = th.T_eb_3_58(q_arm - dq, ctx.d)
        J[0:3, k] = (Mp[0:3, 3] - Mm[0:3, 3]) / (2 * h)
        J[3:6, k] = Mm[0:3, 0:3] @ pin.log3(Mm[0:3, 0:3].T @ Mp[0:3, 0:3]) / (2 * h)
    return J


def _c_4_26(ctx: CheckContext) -> Evidence:
    e_model = e_fd = 0.0
    for xi, _ in ctx.states:
        J = th.J_eb_4_26(xi[6:9], ctx.d)
        e_model = max(e_model, _maxabs(J - kin.arm_jacobian_body(ctx.platform, ctx.data, xi[6:9])))
        e_fd = max(e_fd, _maxabs(J - _ee_body_fd(ctx, xi[6:9])))
    return Evidence(max(e_model, e_fd), None, f"vs Pinocchio arm Jacobian ({e_model:.1g}) and central differences of (3.58) on SE(3) ({e_fd:.1g})")


def _c_4_27(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.J_4_27(xi[6:9], ctx.d) - kin.arm_jacobian_body(ctx.platform, ctx.data, xi[6:9])[[0, 2, 4]]) for xi, _ in ctx.states)
    return Evidence(err, None, "rows (x, z, omega_y) of the Pinocchio arm Jacobian")


def _c_4_28(ctx: CheckContext) -> Evidence:
    err = max(
        abs(th.det_4_28(xi[7], ctx.params.d2) - np.linalg.det(kin.arm_jacobian_body(ctx.platform, ctx.data, xi[6:9])[[0, 2, 4]]))
        for xi, _ in ctx.states
    )
    return Evidence(err, None, "det of the reduced Pinocchio arm Jacobian")


def _c_4_12(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    for xi, _ in ctx.states:
        J = kin.jacobian_xi(ctx.platform, ctx.data, xi)
        ep = max(ep, _maxabs(th.J_e_4_12(xi, ctx.d) - J))
        ec = max(ec, _maxabs(th.J_e_4_12_corrected(xi, ctx.d) - J))
    return Evidence(ep, ec, "lower middle block printed T(phi_b) (body rate) where omega_e (world) needs R_b T(phi_b)")


def _pose_fd(ctx: CheckContext, xi, xid, h: float = 1e-6) -> np.ndarray:
    pp, Rp = kin.ee_pose_xi(ctx.platform, ctx.data, xi + h * xid)
    pm, Rm = kin.ee_pose_xi(ctx.platform, ctx.data, xi - h * xid)
    return np.concatenate([(pp - pm) / (2 * h), pin.log3(Rp @ Rm.T) / (2 * h)])


def _c_4_13(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(kin.jacobian_xi(ctx.platform, ctx.data, xi) @ xid - _pose_fd(ctx, xi, xid)) for xi, xid in ctx.states)
    return Evidence(err, None, "model J_e xi_dot vs central differences of the world pose (log3 for the rotation)")


def _zero_euler_det(platform: Platform, data: pin.Data, q_arm) -> float:
    J = kin.jacobian_xi(platform, data, np.concatenate([np.zeros(6), q_arm]))
    return float(np.linalg.det(J @ J.T))


def _c_4_44(ctx: CheckContext) -> Evidence:
    rng = np.random.default_rng(SEED + 44)
    p = ctx.params
    other = load_qprr(p.with_changes(d3=0.25))  # (4.44) has no d3: check it on a second arm too
    do = other.data()
    err = 0.0
    for _ in range(N_STATES):
        q_arm = rng.uniform([-0.04, -np.pi, -np.pi], [0.04, np.pi, np.pi])
        ref = th.det_JJt_4_44(q_arm[0], q_arm[1], ctx.d)
        err = max(err, abs(ref - _zero_euler_det(ctx.platform, ctx.data, q_arm)), abs(ref - _zero_euler_det(other, do, q_arm)))
    return Evidence(
        err,
        None,
        "vs det(J J^T) of the 6x9 model Jacobian (4.13) at zero Euler angles, for d3 = 0.10 and 0.25 m "
        "and random theta3: the true determinant depends on neither",
    )


def _sol_check(fn, r0):
    def run(ctx: CheckContext) -> Evidence:
        grid = np.linspace(-np.pi, np.pi, 73)
        e44 = max(abs(fn(t) - th.det_JJt_4_44(r0, t, ctx.d)) for t in grid)
        emod = max(abs(fn(t) - _zero_euler_det(ctx.platform, ctx.data, np.array([r0, t, 0.3]))) for t in grid)
        lo = min(fn(t) for t in grid)
        return Evidence(
            max(e44, emod),
            None,
            f"printed 4-digit numbers vs (4.44) ({e44:.1g}) and vs the model det(J J^T) "
            f"({emod:.1g}) with d0 + d1 = 0.095, d2 = 0.18, theta2 on a grid; min over theta2 = {lo:.4f} (never 0)",
        )

    return run


def doolittle(A) -> tuple[np.ndarray, np.ndarray]:
    """A = L U with L unit lower triangular and U upper triangular, no pivoting (the unique such
    factorisation when the leading minors of A are non-zero, as for the J_L J_U of Thesis (4.42))."""
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    L, U = np.eye(n), np.zeros((n, n))
    for i in range(n):
        U[i, i:] = A[i, i:] - L[i, :i] @ U[:i, i:]
        L[i + 1 :, i] = (A[i + 1 :, i] - L[i + 1 :, :i] @ U[:i, i]) / U[i, i]
    return L, U


def _lu_samples(ctx: CheckContext):
    """(q_arm, J J^T of the model at zero Euler angles, its Doolittle factors), cached per context."""
    if "lu" not in ctx.cache:
        out = []
        for q in _arm_qs(ctx):
            J = kin.jacobian_xi(ctx.platform, ctx.data, np.concatenate([np.zeros(6), q]))
            A = J @ J.T
            out.append((q, A, *doolittle(A)))
        ctx.cache["lu"] = out
    return ctx.cache["lu"]


def _lu_entry(name: str, L: np.ndarray, U: np.ndarray) -> float:
    return float((L if name[0] == "a" else U)[int(name[1]) - 1, int(name[2]) - 1])


def _lu_check(names: tuple[str, ...], what: str):
    def run(ctx: CheckContext) -> Evidence:
        ep, ec = {n: 0.0 for n in names}, 0.0
        for q, _, L, U in _lu_samples(ctx):
            printed, corrected = th.lu_factors_4_42(q, ctx.d), th.lu_factors_4_42_corrected(q, ctx.d)
            for n in names:
                ref = _lu_entry(n, L, U)
                ep[n] = max(ep[n], abs(printed[n] - ref))
                ec = max(ec, abs(corrected[n] - ref))
        wrong = [n for n in names if ep[n] > 1e-10]
        return Evidence(
            max(ep.values()),
            ec if wrong else None,
            "each factor vs the Doolittle factorisation (unit lower J_L, unique) of the model J J^T at zero Euler "
            "angles (J of (4.13)): " + ", ".join(f"{n} {e:.1g}" for n, e in ep.items()) + (f"; {what}" if what else ""),
        )

    return run


def _c_4_42_pattern(ctx: CheckContext) -> Evidence:
    zeros = prod = 0.0
    for q, A, L, U in _lu_samples(ctx):
        Lc, Uc = th.lu_matrices_4_42(th.lu_factors_4_42_corrected(q, ctx.d))
        zeros = max(zeros, _maxabs(L[(Lc == 0) & ~np.eye(6, dtype=bool)]), _maxabs(U[Uc == 0]))
        prod = max(prod, _maxabs(Lc @ Uc - A))
    return Evidence(
        max(zeros, prod),
        None,
        f"the model's Doolittle factors vanish where (4.42) prints 0 ({zeros:.1g}); J_L J_U rebuilt "
        f"from the factors (a31 = b13/b11 is not printed) equals J J^T ({prod:.1g})",
    )


def _c_4_43(ctx: CheckContext) -> Evidence:
    with_printed = with_corrected = ident = 0.0
    for q, A, _, U in _lu_samples(ctx):
        det = np.linalg.det(A)
        ident = max(ident, abs(np.prod(np.diag(U)) - det) / det)
        with_printed = max(with_printed, abs(th.det_4_43(th.lu_factors_4_42(q, ctx.d)) - det) / det)
        with_corrected = max(with_corrected, abs(th.det_4_43(th.lu_factors_4_42_corrected(q, ctx.d)) - det) / det)
    return Evidence(
        ident,
        with_corrected,
        f"relative error of the identity det(J J^T) = prod of Doolittle's diagonal b_ii of the "
        f"model; with the (4.42) factors as printed the product is off by {with_printed:.2g} through b55 alone (its "
        f"own row), with the corrected b55 by {with_corrected:.1g}",
    )


def _c_4_43_text(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    for _, _, L, U in _lu_samples(ctx):
        ep = max(ep, abs(np.linalg.det(U) - 1.0))
        ec = max(ec, abs(np.linalg.det(L) - 1.0))
    return Evidence(
        ep,
        ec,
        f"the text after (4.43) says det(J_U) = 1: |det(J_U) - 1| reaches {ep:.3g}; the unit-diagonal factor "
        f"is J_L (|det(J_L) - 1| {ec:.1g}), which is what makes det(J J^T) = det(J_U)",
    )


def _c_4_24(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    for xi, xi_dot in ctx.states:
        q, qd = xi[6:9], xi_dot[6:9]
        T_beb = mdh.chain(th.table_3_4_corrected(ctx.d), q, base=th.T_b0_3_49(), tool=th.T_4eb_3_51())[-1]
        v_eb = T_beb[:3, :3].T @ (kin.arm_jacobian_body(ctx.platform, ctx.data, q)[0:3] @ qd)
        ep = max(ep, _maxabs(th.v_ee_4_24(q, qd, ctx.d) - v_eb))
        ec = max(ec, _maxabs(th.v_ee_4_24(q, qd, ctx.d, corrected=True) - v_eb))
    return Evidence(
        ep,
        ec,
        "Pinocchio's end-effector velocity relative to B (arm Jacobian), in the eb axes of the MDH chain "
        "(3.49), Table 3.4, (3.51): the theta2_dot coefficient of row 1 is d2 c3 + d3, printed d2 s3 + d3",
    )


def _c_5_20(ctx: CheckContext) -> Evidence:
    ep = ec = fd_err = 0.0
    h = 1e-6
    for xi, _ in ctx.states:
        q = xi[6:9]
        _, Jo_ref = th.link_jacobians_5_20(q, ctx.d)
        Jp_fd = np.zeros((3, 3, 3))  # central differences of the link centres of mass (3.78)
        for j in range(3):
            e = np.zeros(3)
            e[j] = h
            Jp_fd[:, :, j] = (th.link_coms_3_78(q + e, ctx.d) - th.link_coms_3_78(q - e, ctx.d)) / (2 * h)
        for index in ("printed", "mdh"):
            Jp, Jo = th.link_jacobians_5_20_frames(q, ctx.d, index)
            err = max(_maxabs(Jp - Jp_fd), _maxabs(Jo - Jo_ref))
            ep, ec = (max(ep, err), ec) if index == "printed" else (ep, max(ec, err))
        fd_err = max(fd_err, _maxabs(th.link_jacobians_5_20(q, ctx.d)[0] - Jp_fd))
    return Evidence(
        ep,
        ec,
        "columns built from the thesis's own MDH frames (Table 3.4 after (3.49)) vs central differences of the "
        "link CoMs (3.78) and the joint axes: with z_(j-1), p_(j-1) as printed, joint 2's column is about z_1 = x_B (the "
        f"slider axis); with the modified-DH index z_j, p_j it holds (differences vs the closed form: {fd_err:.1g})",
    )


def _c_4_45(ctx: CheckContext) -> Evidence:
    rng = np.random.default_rng(SEED + 45)
    p = ctx.params
    pts, dets = [], []
    for _ in range(6 * N_STATES):
        q = np.array([rng.uniform(*p.r0_limits), rng.uniform(-np.pi, np.pi), rng.uniform(*p.theta3_limits)])
        pts.append(q)
        dets.append(_zero_euler_det(ctx.platform, ctx.data, q))
    dets = np.array(dets)
    Bp = np.array([th.basis_4_45(q[0], q[1]) for q in pts])
    lam, *_ = np.linalg.lstsq(Bp, dets, rcond=None)  # the best constants the printed basis allows
    ep = _maxabs(Bp @ lam - dets)
    ec = max(abs(th.det_JJt_4_45_corrected(q[0], q[1], ctx.d) - dt) for q, dt in zip(pts, dets))
    return Evidence(
        ep,
        ec,
        f"best constant lambda_1..8 (least squares over {len(pts)} random (r0, theta2, theta3)) still misses the "
        f"model det(J J^T) by {ep:.2g}: (4.44) has 4 d2 r0 s2 (coefficient of s2 = {4 * p.d2:.4f} r0, cf. -0.0288 "
        f"and +0.0288 in (4.46), (4.48)) and no constant s2 term; with r0 s2 in place of s2 and the lambda of (4.44) "
        f"it is exact",
    )


# ------------------------------------------------------------------------------ chapter 5
_BLOCK_SLICES = {"B11": (0, 0), "B12": (0, 3), "B13": (0, 6), "B22": (3, 3), "B23": (3, 6), "B33": (6, 6)}


def _block_check(*names: str):
    def run(ctx: CheckContext) -> Evidence:
        ep = ec = 0.0
        worst = ""
        for xi, xid in ctx.states:
            B = dyn.dynamics_xi(ctx.platform, ctx.data, xi, xid)[0]
            P, Cc = th.B_blocks_5_2_2(xi, ctx.params), th.B_blocks_5_2_2_corrected(xi, ctx.params)
            for n in names:
                i, j = _BLOCK_SLICES[n]
                ref = B[i : i + 3, j : j + 3]
                e = _maxabs(getattr(P, n) - ref)
                if e > ep:
                    ep = e
                    worst = f"{n}: printed {np.round(getattr(P, n), 5).tolist()} vs model {np.round(ref, 5).tolist()}"
                ec = max(ec, _maxabs(getattr(Cc, n) - ref))
        return Evidence(ep, ec, "vs B = S^T M S from Pinocchio CRBA" + (f"; worst {worst}" if ep > 1e-9 else ""))

    return run


def _c_5_15(ctx: CheckContext) -> Evidence:
    model = pin.Model(ctx.platform.model)
    for j in (joint.joint_id for joint in ctx.platform.arm):  # keep the multirotor only
        model.inertias[j] = pin.Inertia.Zero()
    data = model.createData()
    ep = ec = 0.0
    for xi, xid in ctx.states:
        v = np.zeros(9)
        v[3:6] = body_rate_fd(xi[3:6], xid[3:6])
        ke = pin.computeKineticEnergy(model, data, _q(xi), v)
        ep = max(ep, abs(th.kinetic_multirotor_5_15(xi[3:6], xid[3:6], ctx.params) - ke))
        ec = max(ec, abs(th.kinetic_multirotor_5_15_corrected(xi[3:6], xid[3:6], ctx.params) - ke))
    return Evidence(
        ep,
        ec,
        "vs Pinocchio kinetic energy of the multirotor alone with omega_body from differences of R_b; "
        "Q = R_b^T T mixes the body rate T phi_dot with the world-frame tensor R_b I_b R_b^T",
    )


def _c_5_25(ctx: CheckContext) -> Evidence:
    err = 0.0
    for xi, xid in ctx.states:
        B = dyn.dynamics_xi(ctx.platform, ctx.data, xi, xid)[0]
        q, v = ch.xi_to_qv(xi, xid)
        err = max(err, abs(0.5 * xid @ B @ xid - dyn.kinetic_energy(ctx.platform, ctx.data, q, v)))
    return Evidence(err, None, "model: 1/2 xi_dot^T B xi_dot vs Pinocchio kinetic energy")


def _c_5_29(ctx: CheckContext) -> Evidence:
    err = max(abs(th.potential_5_29(xi, ctx.params) - dyn.potential_energy(ctx.platform, ctx.data, _q(xi))) for xi, _ in ctx.states)
    return Evidence(err, None, "vs Pinocchio potential energy (gravity -g e3, z up)")


def _c_5_35(ctx: CheckContext) -> Evidence:
    h = 1e-6
    err = skew = 0.0
    pf, data = ctx.platform, ctx.data
    for xi, xid in ctx.states[:4]:
        B, C, _ = dyn.dynamics_xi(pf, data, xi, xid)
        dB = np.zeros((9, 9, 9))  # dB[:, :, k] = dB/dxi_k
        for k in range(9):
            e = np.eye(9)[k] * h
            dB[:, :, k] = (dyn.dynamics_xi(pf, data, xi + e, xid)[0] - dyn.dynamics_xi(pf, data, xi - e, xid)[0]) / (2 * h)
        C_fd = 0.5 * (np.einsum("ijk,k->ij", dB, xid) + np.einsum("ikj,k->ij", dB, xid) - np.einsum("jki,k->ij", dB, xid))
        err = max(err, _maxabs(C - C_fd))
        Bdot = np.einsum("ijk,k->ij", dB, xid)
        N = Bdot - 2 * C
        skew = max(skew, _maxabs(N + N.T))
    return Evidence(
        max(err, skew),
        None,
        f"model C vs Christoffel symbols of central differences of B ({err:.1g}); B_dot - 2C skew-symmetric (Hypothesis 7) to {skew:.1g}",
    )


def _c_5_37(ctx: CheckContext) -> Evidence:
    h = 1e-6
    err = 0.0
    for xi, xid in ctx.states:
        G = dyn.dynamics_xi(ctx.platform, ctx.data, xi, xid)[2]

        def U(x):
            return dyn.potential_energy(ctx.platform, ctx.data, _q(x))

        fd = np.array([(U(xi + h * e) - U(xi - h * e)) / (2 * h) for e in np.eye(9)])
        err = max(err, _maxabs(G - fd))
    return Evidence(err, None, "model G vs central differences of the potential energy in xi")


def _c_5_39(ctx: CheckContext) -> Evidence:
    err = 0.0
    rng = np.random.default_rng(SEED + 39)
    for xi, xid in ctx.states:
        u = rng.normal(size=9)
        B, C, G = dyn.dynamics_xi(ctx.platform, ctx.data, xi, xid)
        err = max(err, _maxabs(dyn.forward_dynamics_xi(ctx.platform, ctx.data, xi, xid, u) - np.linalg.solve(B, u - C @ xid - G)))
    return Evidence(err, None, "model: ABA on the Lie group (converted to xi_ddot) vs B^-1 (u - C xi_dot - G)")


def _virtual_power_error(RQ_fn, ctx: CheckContext) -> float:
    rng = np.random.default_rng(SEED + 41)
    err = 0.0
    for xi, xid in ctx.states:
        f_body, tau_body, mu = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        u = RQ_fn(xi) @ np.concatenate([f_body, tau_body, mu])
        power = (_R(xi) @ f_body) @ xid[0:3] + tau_body @ body_rate_fd(xi[3:6], xid[3:6]) + mu @ xid[6:9]
        err = max(err, abs(u @ xid - power))
    return err


def _rq_check(fn):
    def run(ctx: CheckContext) -> Evidence:
        ep = _virtual_power_error(fn, ctx)
        ec = max(_virtual_power_error(th.R_Q_corrected, ctx), max(_maxabs(th.R_Q_corrected(xi) - input_map_matrix(xi)) for xi, _ in ctx.states))
        return Evidence(
            ep,
            ec,
            "u^T xi_dot vs the power f_world . p_dot + tau_body . omega_body + mu . q_arm_dot "
            "(omega_body by differences of R_b); the corrected middle block is T^T",
        )

    return run


def _c_5_46(ctx: CheckContext) -> Evidence:
    p = ctx.params
    N = _plus(ctx).actuation_matrix
    ep = _maxabs(th.N_5_46(p.arm_length, p.drag_factor) - N)
    ec = _maxabs(th.N_5_46_corrected(p.arm_length, p.thrust_factor, p.drag_factor) - N)
    return Evidence(ep, ec, "vs the model's N (rotor frames of the URDF); same yaw-row c vs c/b issue as (3.36)")


def _c_5_54(ctx: CheckContext) -> Evidence:
    model, data = fixed_base_arm(ctx.platform)
    err = max(_maxabs(th.arm_B_5_54(q, ctx.params) - _mass_matrix(model, data, q)) for q, _, _ in _arm_samples(ctx))
    return Evidence(err, None, "vs CRBA of the arm with the base locked")


_ARM_B_NAMES = [f"b{i}{j}" for i in range(1, 4) for j in range(1, 4)]


def _c_5_5_B(ctx: CheckContext) -> Evidence:
    model, data = fixed_base_arm(ctx.platform)
    ep = ec = 0.0
    errs = []
    for q, _, _ in _arm_samples(ctx):
        M = _mass_matrix(model, data, q)
        e = np.abs(th.arm_B_5_5(q, ctx.params) - M)
        errs.append(e.ravel())
        ep = max(ep, e.max())
        ec = max(ec, _maxabs(th.arm_B_5_5_corrected(q, ctx.params) - M))
    bad = _bad_entries(np.array(errs), 1e-10, _ARM_B_NAMES)
    I2, I3 = ctx.params.links[1].inertia, ctx.params.links[2].inertia
    return Evidence(
        ep,
        ec,
        f"vs CRBA with the base locked; wrong entries: {bad} (b22 uses I_z2 = {I2[2]:g} for the joint-axis "
        f"moment I_y2 = {I2[1]:g}; b33 adds I_z3 + s23^2 (I_x3 - I_z3) = {I3[2]:g} + s23^2 ({I3[0] - I3[2]:g}))",
    )


def _c_5_5_C(ctx: CheckContext) -> Evidence:
    model, data = fixed_base_arm(ctx.platform)
    ep = ec = 0.0
    errs = []
    for q, qd, _ in _arm_samples(ctx):
        Cm = christoffel(model, data, q, qd)
        e = np.abs(th.arm_C_5_5(q, qd, ctx.params) - Cm)
        errs.append(e.ravel())
        ep = max(ep, e.max())
        ec = max(ec, _maxabs(th.arm_C_5_5_corrected(q, qd, ctx.params) - Cm))
    bad = _bad_entries(np.array(errs), 1e-10, [n.replace("b", "c") for n in _ARM_B_NAMES])
    return Evidence(
        ep,
        ec,
        f"vs Christoffel symbols of the locked-base CRBA (exact derivatives from RNEA); wrong entries: {bad} "
        "(they differentiate the spurious s23^2 (I_x3 - I_z3) of b33)",
    )


def _c_5_5_G(ctx: CheckContext) -> Evidence:
    down_x = ch.rot_y(np.pi / 2)  # x_B points down: gravity in B is +g x_B
    model, data = fixed_base_arm(ctx.platform, down_x)
    lm, ld = fixed_base_arm(ctx.platform)
    ep = level = 0.0
    for q, _, _ in _arm_samples(ctx):
        ep = max(ep, _maxabs(th.arm_G_5_5(q, ctx.params) - pin.computeGeneralizedGravity(model, data, q)))
        level = max(level, _maxabs(th.arm_G_5_5(q, ctx.params) - pin.computeGeneralizedGravity(lm, ld, q)))
    return Evidence(
        ep,
        None,
        "vs Pinocchio generalised gravity of the locked-base arm with the base pitched by +pi/2 "
        f"(gravity +g x_B, along the slider); with the base level (z up) it would be off by {level:.3g}",
    )


def _u_check(i: int, what: str):
    def run(ctx: CheckContext) -> Evidence:
        model, data = fixed_base_arm(ctx.platform, ch.rot_y(np.pi / 2))
        ep = ec = 0.0
        for q, qd, qdd in _arm_samples(ctx):
            tau = pin.rnea(model, data, q, qd, qdd)[i]
            ep = max(ep, abs(th.arm_u_5_5(q, qd, qdd, ctx.params)[i] - tau))
            ec = max(ec, abs(th.arm_u_5_5_corrected(q, qd, qdd, ctx.params)[i] - tau))
        return Evidence(ep, ec, f"vs RNEA of the locked-base arm (gravity +g x_B as the printed G); {what}")

    return run


def _c_conversion(ctx: CheckContext) -> Evidence:
    err = 0.0
    rng = np.random.default_rng(SEED + 9)
    for xi, xid in ctx.states:
        q, v = ch.xi_to_qv(xi, xid)
        xi2, xid2 = ch.qv_to_xi(q, v)
        xidd = rng.normal(size=9)
        a = ch.xi_ddot_to_a(xi, xid, xidd)
        err = max(err, _maxabs(_wrap(xi2 - xi)), _maxabs(xid2 - xid), _maxabs(ch.a_to_xi_ddot(xi, xid, a) - xidd))
        # v is the tangent of q(xi(t)): pin.difference of q at xi -+ h xi_dot over 2h
        h = 1e-6
        v_fd = pin.difference(ctx.platform.model, ch.xi_to_q(xi - h * xid), ch.xi_to_q(xi + h * xid)) / (2 * h)
        err = max(err, _maxabs(v_fd - v))
    return Evidence(err, None, "xi -> (q, v) -> xi round trip, accelerations, and v = pin.difference of q(xi(t))")


def _symbolic_errors(ctx: CheckContext) -> dict:
    """Max |Pinocchio - sympy| of B, C, G at three states (computed once per context)."""
    if "symbolic" in ctx.cache:
        return ctx.cache["symbolic"]
    try:
        import sympy  # noqa: F401
    except ImportError as exc:
        raise _Skip('skipped (pip install "qprr[test]")') from exc
    try:
        symbolic = importlib.import_module("qprr.thesis.symbolic")
    except ImportError as exc:
        raise _Skip(f"skipped (qprr.thesis.symbolic not available: {exc})") from exc
    sm = symbolic.symbolic_model(ctx.params)
    err = {"B": 0.0, "C": 0.0, "G": 0.0}
    for xi, xid in ctx.states[:3]:
        sym = [np.asarray(x, dtype=float) for x in sm.dynamics(xi, xid)]
        pin_ = dyn.dynamics_xi(ctx.platform, ctx.data, xi, xid)
        for name, a, b in zip("BCG", sym, pin_):
            err[name] = max(err[name], _maxabs(a - b))
    ctx.cache["symbolic"] = err
    return err


def _symbolic_check(name: str):
    def run(ctx: CheckContext) -> Evidence:
        return Evidence(
            _symbolic_errors(ctx)[name],
            None,
            f"{name} of the Lagrange model derived symbolically (qprr.thesis.symbolic, sympy, no Pinocchio) vs CRBA/RNEA in xi coordinates",
        )

    return run


# ------------------------------------------------------------------------------ chapter 6
def _level_states(ctx: CheckContext, phi: float = 0.0, psi: float | None = None, max_pitch: float = 0.4) -> list[np.ndarray]:
    """The seeded states with roll ``phi``, |pitch| < ``max_pitch`` (and yaw ``psi`` when given): Sec. 6.3.3's hypotheses."""
    out = []
    for xi, _ in ctx.states:
        x = xi.copy()
        x[3], x[4] = phi, xi[4] * max_pitch / 1.3  # the seeded pitches lie in (-1.3, 1.3) (CheckContext.random_xi)
        if psi is not None:
            x[5] = psi
        out.append(x)
    return out


def _c_6_29(ctx: CheckContext) -> Evidence:
    err = 0.0
    for xi, _ in ctx.states:
        q = _q(xi)
        err = max(err, _maxabs(th.p_c_6_29(xi[0:3], _R(xi), kin.com_body(ctx.platform, ctx.data, q)) - kin.com_world(ctx.platform, ctx.data, q)))
    return Evidence(err, None, "p_b + R_b p_cm (p_cm: Pinocchio CoM in B) vs Pinocchio CoM in the world frame")


def _c_6_29_rate(ctx: CheckContext) -> Evidence:
    h = 1e-6
    ep = e_world = 0.0
    for xi, xid in ctx.states:
        q, v = ch.xi_to_qv(xi, xid)
        pin.centerOfMass(ctx.platform.model, ctx.data, q, v)
        vcom = ctx.data.vcom[0].copy()
        p_cm = kin.com_body(ctx.platform, ctx.data, q)
        darm = np.concatenate([np.zeros(6), xid[6:9]]) * h
        p_cm_dot = (kin.com_body(ctx.platform, ctx.data, _q(xi + darm)) - kin.com_body(ctx.platform, ctx.data, _q(xi - darm))) / (2 * h)
        omega_body, R = v[3:6], _R(xi)
        ep = max(ep, _maxabs(th.p_c_dot_6_29(xid[0:3], R, omega_body, p_cm, p_cm_dot) - vcom))
        e_world = max(e_world, _maxabs(th.p_c_dot_6_29(xid[0:3], R, R @ omega_body, p_cm, p_cm_dot) - vcom))
    return Evidence(
        ep,
        None,
        f"vs Pinocchio CoM velocity (p_cm_dot by central differences along the arm joints) with omega_b = "
        f"T phi_b_dot, the body rate; with the world rate R_b T phi_b_dot (as (4.7) reads omega_b) it is off by "
        f"{e_world:.2g} m/s",
    )


def _c_6_30_xy(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.com_6_30(xi[6:9], ctx.params)[0:2] - kin.com_body(ctx.platform, ctx.data, _q(xi))[0:2]) for xi, _ in ctx.states)
    return Evidence(err, None, "x_cm, y_cm in B vs Pinocchio centre of mass")


def _c_6_30_z(ctx: CheckContext) -> Evidence:
    ep = ec = 0.0
    for xi, _ in ctx.states:
        z = kin.com_body(ctx.platform, ctx.data, _q(xi))[2]
        ep = max(ep, abs(th.com_6_30(xi[6:9], ctx.params)[2] - z))
        ec = max(ec, abs(th.com_3_78_corrected(xi[6:9], ctx.params)[2] - z))
    m1 = ctx.params.links[0].mass
    return Evidence(
        ep,
        ec,
        f"(6.30c) fixes the (m2/2 + m3) d2 c2 of (3.78) but keeps sum m_i (d0 + d1): link 1's CoM is at d0 + d1/2, "
        f"printed - true = m1 d1 / (2 m_G) = {m1 * ctx.params.d1 / 2 / ctx.params.total_mass:.3g} m at every q",
    )


def _pitch_only_offsets(ctx: CheckContext, phi: float = 0.0, psi: float = 0.0):
    """(theta, p_cm in B, p_c - p_b in the world) from Pinocchio at roll ``phi``, yaw ``psi``."""
    for xi in _level_states(ctx, phi, psi):
        q = _q(xi)
        yield xi[4], kin.com_body(ctx.platform, ctx.data, q), kin.com_world(ctx.platform, ctx.data, q) - xi[0:3]


def _c_6_31(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.p_cm_prime_6_31(t, p) - w) for t, p, w in _pitch_only_offsets(ctx))
    rolled = max(_maxabs(th.p_cm_prime_6_31(t, p) - w) for t, p, w in _pitch_only_offsets(ctx, phi=0.3))
    return Evidence(
        err,
        None,
        f"R_theta p_cm vs Pinocchio p_c - p_b (world axes) at phi = psi = 0, |theta| < 0.4; at phi = 0.3 rad "
        f"it is off by {rolled:.2g} m. A rigid pitch leaves p_cm in B (hence x_cm, the thrust-line offset) unchanged",
    )


def _c_6_32(ctx: CheckContext) -> Evidence:
    err = max(_maxabs(th.nabla_p_cm_6_32(t, p) - (w - p)) for t, p, w in _pitch_only_offsets(ctx))
    return Evidence(err, None, "(R_theta - I) p_cm vs Pinocchio (p_c - p_b) - p_cm at phi = psi = 0")


def _ee_pitch_error(ctx: CheckContext, xi, theta_e: float) -> float:
    """|R_e - Rz(psi) Ry(theta_e)| with R_e from Pinocchio."""
    R_e = kin.ee_placement(ctx.platform, ctx.data, _q(xi)).rotation
    return _maxabs(R_e - ch.rot_z(xi[5]) @ ch.rot_y(theta_e))


def _c_6_34(ctx: CheckContext) -> Evidence:
    ep = e_roll = e_zyz = 0.0
    for xi in _level_states(ctx):
        te = th.theta_e_6_34(xi[4], xi[7], xi[8])
        ep = max(ep, _ee_pitch_error(ctx, xi, te))
        zyz = th.euler_3_64(kin.ee_placement(ctx.platform, ctx.data, _q(xi)).rotation)[1]
        e_zyz = max(e_zyz, abs(float(_wrap(zyz - te))))
    for xi in _level_states(ctx, phi=0.2):
        e_roll = max(e_roll, _ee_pitch_error(ctx, xi, th.theta_e_6_34(xi[4], xi[7], xi[8])))
    return Evidence(
        ep,
        None,
        f"R_e of Pinocchio vs Rz(psi) Ry(theta + theta2 + theta3) at phi = 0 (any psi); read as the ZYZ "
        f"theta_e of (3.64) (in [0, pi]) it is off by {e_zyz:.2g} rad; at phi = 0.2 rad R_e is off by {e_roll:.2g}",
    )


def _c_6_35(ctx: CheckContext) -> Evidence:
    from ..control import make_controller
    from .bsg import CogStabilizer
    from .gains import mfc

    bsg = CogStabilizer(ctx.platform, make_controller("mfc", ctx.platform, gains=mfc()))  # the thesis's MFC gains
    rng = np.random.default_rng(SEED + 35)
    p = ctx.params
    err = e_roll = 0.0
    n = clamped = 0
    while n < N_STATES:
        theta, theta2_d, theta_e_d, psi = rng.uniform(-0.3, 0.3), rng.uniform(-0.6, 0.6), rng.uniform(-0.4, 0.4), rng.uniform(-np.pi, np.pi)
        bsg.theta_e_d = theta_e_d
        r0_d, theta3_d = bsg.joint_references(theta, theta2_d)
        if not (p.r0_limits[0] < r0_d < p.r0_limits[1] and p.theta3_limits[0] < theta3_d < p.theta3_limits[1]):
            clamped += 1  # clamped references cannot reach x_cm = 0 (documented in qprr.thesis.bsg)
            continue
        n += 1
        for phi in (0.0, 0.2):
            xi = np.array([0.0, 0.0, 0.0, phi, theta, psi, r0_d, theta2_d, theta3_d])
            e = max(abs(kin.com_body(ctx.platform, ctx.data, _q(xi))[0]), _ee_pitch_error(ctx, xi, theta_e_d))
            if phi == 0.0:
                err = max(err, e)
            else:
                e_roll = max(e_roll, e)
    return Evidence(
        err,
        None,
        f"CogStabilizer.joint_references(theta, theta2_d) -> (r0_d, theta3_d) from (6.35) and x_cm = 0 of "
        f"(6.33), put into the model: Pinocchio x_cm in B and R_e vs Rz(psi) Ry(theta_e^d), {n} states with "
        f"|theta| < 0.3 ({clamped} with clamped references skipped); at phi = 0.2 rad the end effector is off by {e_roll:.2g}",
    )


# ---------------------------------------------------------------------------- registry
CONV_ZYZ = "ZYZ Euler angles for the end effector (R_e = Rz Ry Rz)"
CONV_PITCH = "phi = psi = 0 (Hypothesis 4 of Sec. 6.3.3), p'_cm in world axes"

CHECKS: tuple[Check, ...] = (
    Check("(3.4)", "R_b = Rz(psi) Ry(theta) Rx(phi), entries", _c_3_4, 1e-12),
    Check("(3.8)", "ZYX angles from R_b", _c_3_8, 1e-9),
    Check("(3.25)", "T(phi_b): omega = T phi_b_dot", _c_3_25, 1e-7, "omega in the body frame B (3.19), not inertial as (3.15) says"),
    Check("(3.27)", "MDH chain (3.27), (3.29)-(3.30) vs URDF frames", _c_3_27, 1e-12),
    Check("(3.28)", "MDH transform written out", _c_3_28, 1e-12),
    Check("(3.36)", "allocation [f_b; tau_b] = A f (force form)", _c_3_36, 1e-12),
    Check("(3.37)", "allocation u = A w^2", _c_3_37, 1e-12),
    Check("(3.37)", "det of the (3.37) matrix as printed = 8 c l^2 b^3", _c_det_3_37, 1e-9),
    Check("(A.1)", "rotor-force inverse f = A^-1 u", _c_A1, 1e-9),
    Check("(3.42)", "arm potential U = -sum m g e3^T R_b xi_ci", _c_3_42, 1e-10, "NED gravity +g e3"),
    Check("(3.43)", "arm torque on B: m_G g xi_c x R_b^T e3", _c_3_43, 1e-10, "NED gravity +g e3 of (3.42)"),
    Check("(3.44)", "arm CoM xi_c in B", _c_3_44, 1e-12),
    Check("Tab. 3.4", "MDH parameter table through (3.27)", _c_table_3_4, 1e-12),
    Check("(3.48)", "^bT_0 = Rot(y, pi/2) Rot(z, pi), matrix (3.49)", _c_3_48, 1e-12),
    Check("(3.50)", "^4T_eb = Rot(y, pi/2) Rot(z, -pi/2)", _c_3_50, 1e-12),
    Check("(3.51)", "^4T_eb matrix", _c_3_51, 1e-12),
    Check("(3.52)", "^0T_1 .. ^3T_4 matrices (3.52)-(3.55)", _c_3_52, 1e-12),
    Check("(3.56)", "^bT_eb, product of the printed matrices", _c_3_56, 1e-12),
    Check("(3.58)", "^bT_eb, end effector in B", _c_3_58, 1e-12),
    Check("(3.61)", "p_e expanded", _c_3_61, 1e-10),
    Check("(3.62)", "R_e = R_b R_eb, entries", _c_3_62, 1e-12),
    Check("(3.64)", "end-effector angles from R_e", _c_3_64, 1e-10, CONV_ZYZ),
    Check("(3.65)", "full direct geometric model chi_e", _c_3_65, 1e-10, CONV_ZYZ),
    Check("(3.68)", "hover FK, lines 1-3 (position)", _c_3_68_pos, 1e-12),
    Check("(3.68)", "hover FK, lines 4-6 (phi_e, theta_e, psi_e)", _c_3_68_ang, 1e-9),
    Check("(3.78)", "CoG x_cm, y_cm in B", _c_3_78_xy, 1e-12),
    Check("(3.78)", "CoG z_cm in B", _c_3_78_z, 1e-12),
    Check("(3.76)", "payload centre p_cl in B", _c_3_76, 1e-12),
    Check("(3.78)", "CoG with payload m_l: '+ x_cl' for m_l x_cl", _c_3_78_payload, 1e-12),
    Check("(3.80)", "x_cm = F(r0, theta2, theta3)", _c_3_80, 1e-12),
    Check("(4.24)", "^eb v_4: end-effector velocity in the eb axes", _c_4_24, 1e-12),
    Check("(4.26)", "arm Jacobian J_eb (6x3) in B", _c_4_26, 1e-8),
    Check("(4.27)", "reduced arm Jacobian J_eb* (3x3)", _c_4_27, 1e-12),
    Check("(4.28)", "det J_eb* = -d2 s2", _c_4_28, 1e-12),
    Check("(4.12)", "J_e assembled from J_b, T_A, J_eb", _c_4_12, 1e-10),
    Check("(4.13)", "model J_e vs differences of the pose", _c_4_13, 1e-7),
    Check("(4.44)", "det(J J^T) at zero Euler angles", _c_4_44, 1e-10),
    Check("(4.42)", "J J^T = J_L J_U, sparsity pattern", _c_4_42_pattern, 1e-12),
    Check("(4.42)", "L factors a42, a51, a62, a64", _lu_check(("a42", "a51", "a62", "a64"), ""), 1e-12),
    Check(
        "(4.42)",
        "L factor a53",
        _lu_check(("a53",), "a53 = b35 / b33 (the printed text has an unmatched parenthesis and lacks the terms of b33)"),
        1e-12,
    ),
    Check("(4.42)", "U factors b_ij except b55", _lu_check(tuple(n for n in th.LU_U_NAMES if n != "b55"), ""), 1e-12),
    Check(
        "(4.42)",
        "U factor b55",
        _lu_check(
            ("b55",),
            "b55 = 3 - b15^2/b11 - b35^2/b33: the printed last denominator has "
            "d2^4 s2 c2 and 2 d2 d3 s23 c23 where b33 has d2^2 sin 2theta2 and "
            "2 d2 d3 sin(2theta2 + theta3)",
        ),
        1e-12,
    ),
    Check("(4.43)", "det(J J^T) = b11 b22 b33 b44 b55 b66 (identity)", _c_4_43, 1e-12),
    Check("(4.43) text", "the unit-determinant factor (det(J_U) = 1 in the text)", _c_4_43_text, 1e-12),
    Check("(4.45)", "det(J J^T) in the lambda basis", _c_4_45, 1e-10),
    Check("(4.46)", "sol(-0.04, theta2) numbers", _sol_check(th.sol_4_46, -0.04), 2e-4, "4-digit rounding of the printed coefficients"),
    Check("(4.47)", "sol(0, theta2) numbers", _sol_check(th.sol_4_47, 0.0), 2e-4, "4-digit rounding of the printed coefficients"),
    Check("(4.48)", "sol(0.04, theta2) numbers", _sol_check(th.sol_4_48, 0.04), 2e-4, "4-digit rounding of the printed coefficients"),
    Check("5.2.2", "B11, B12, B13", _block_check("B11", "B12", "B13"), 1e-10),
    Check("5.2.2", "B22", _block_check("B22"), 1e-10),
    Check("5.2.2", "B23", _block_check("B23"), 1e-10),
    Check("5.2.2", "B33", _block_check("B33"), 1e-10),
    Check("(5.20)", "link Jacobian columns from the MDH frames: z_(j-1), p_(j-1)", _c_5_20, 1e-8),
    Check("(5.15)", "multirotor kinetic energy with Q = R_b^T T", _c_5_15, 1e-8),
    Check("(5.25)", "model kinetic energy 1/2 xi_dot^T B xi_dot", _c_5_25, 1e-10),
    Check("(5.29)", "potential energy U (z up)", _c_5_29, 1e-10),
    Check("(5.35)", "model C: Christoffel of B, B_dot - 2C skew", _c_5_35, 1e-6),
    Check("(5.37)", "model G = dU/dxi", _c_5_37, 1e-6),
    Check("(5.39)", "model forward dynamics", _c_5_39, 1e-8),
    Check("(5.41)", "R_Q = diag(R_b, R_b^T T, I3)", _rq_check(th.R_Q_5_41), 1e-7),
    Check("(5.43)", "R_Q = diag(R_b, R_b T, I3)", _rq_check(th.R_Q_5_43), 1e-7),
    Check("(5.46)", "N = diag(Omega, I3) with Omega of (5.45)", _c_5_46, 1e-12),
    Check("(5.54)", "fixed-base arm B = sum m Jp^T Jp + Jo^T I Jo", _c_5_54, 1e-12),
    Check("5.5", "fixed-base arm b_ij", _c_5_5_B, 1e-12),
    Check("5.5.1", "fixed-base arm c_ij", _c_5_5_C, 1e-12),
    Check("5.5.2", "fixed-base arm G", _c_5_5_G, 1e-12, "gravity +g x_B (slider axis vertical, pointing down)"),
    Check("5.5.3", "u(1), prismatic force", _u_check(0, "the theta2_ddot coefficient halves its m3 part"), 1e-10),
    Check("5.5.3", "u(2), theta2 torque", _u_check(1, "m2 d2^2/2 (b22: /4), I_z2, theta3_dot for theta3_ddot, b33 terms"), 1e-10),
    Check("5.5.3", "u(3), theta3 torque", _u_check(2, "the spurious (I_x3 - I_z3) terms of b33"), 1e-10),
    Check("(6.29)", "p_c = p_b + R_b p_cm", _c_6_29, 1e-12),
    Check("(6.29)'", "p_c_dot = p_b_dot + R_b (w x p_cm + p_cm_dot)", _c_6_29_rate, 1e-7, "omega_b the body rate T phi_b_dot (3.25)"),
    Check("(6.30ab)", "CoG x_cm, y_cm in B", _c_6_30_xy, 1e-12),
    Check("(6.30c)", "CoG z_cm in B", _c_6_30_z, 1e-12),
    Check("(6.31)", "p'_cm = R_theta p_cm", _c_6_31, 1e-12, CONV_PITCH),
    Check("(6.32)", "nabla p_cm = (R_theta - I) p_cm", _c_6_32, 1e-12, CONV_PITCH),
    Check(
        "(6.34)",
        "theta_e = theta + theta2 + theta3",
        _c_6_34,
        1e-12,
        "phi = 0, theta_e the pitch of R_e = Rz(psi) Ry(theta_e), not the ZYZ theta_e of (3.64)",
    ),
    Check(
        "(6.35)",
        "BSG references (r0_d, theta3_d) in the model",
        _c_6_35,
        1e-12,
        "phi = 0 (Hypothesis 4 of Sec. 6.3.3), references inside the joint limits",
    ),
    Check("conv.", "xi <-> (q, v, a) round trips", _c_conversion, 1e-7),
    Check("(5.36)", "B: Pinocchio vs sympy", _symbolic_check("B"), 1e-9),
    Check("(5.36)", "C: Pinocchio vs sympy", _symbolic_check("C"), 1e-9),
    Check("(5.36)", "G: Pinocchio vs sympy", _symbolic_check("G"), 1e-9),
)


# ---------------------------------------------------------------------------- running
def evaluate_check(check: Check, ctx: CheckContext) -> CheckResult:
    """Run one check and apply the verdict rule."""
    try:
        ev = check.run(ctx)
    except _Skip as exc:
        return CheckResult(check.equation, check.quantity, None, None, check.tolerance, str(exc), CheckStatus.SKIPPED, str(exc))
    except Exception as exc:  # a crashing check is a failing check, reported with its cause
        return CheckResult(check.equation, check.quantity, None, None, check.tolerance, "FAIL", CheckStatus.FAIL, f"{type(exc).__name__}: {exc}")
    tol = check.tolerance
    printed_ok = bool(np.isfinite(ev.printed_error) and ev.printed_error <= tol)
    corrected_ok = ev.corrected_error is not None and bool(np.isfinite(ev.corrected_error) and ev.corrected_error <= tol)
    if printed_ok:
        verdict = f"correct under {check.convention}" if check.convention else "correct"
        status = CheckStatus.PASS
        if ev.corrected_error is not None and not corrected_ok:
            verdict, status = "FAIL (corrected form does not hold)", CheckStatus.FAIL
    elif corrected_ok:
        verdict, status = "misprint (corrected form holds)", CheckStatus.PASS
    else:
        verdict, status = "FAIL", CheckStatus.FAIL
    return CheckResult(check.equation, check.quantity, ev.printed_error, ev.corrected_error, tol, verdict, status, ev.detail)


def run_checks(platform: Platform | None = None, on_result: Callable[[CheckResult], None] | None = None) -> list[CheckResult]:
    """Evaluate every check of :data:`CHECKS` on ``platform`` (default: the thesis's Q-PRR), calling ``on_result`` after each."""
    ctx = make_context(platform)
    results = []
    for check in CHECKS:
        r = evaluate_check(check, ctx)
        results.append(r)
        if on_result is not None:
            on_result(r)
    return results


def _format_error(r: CheckResult) -> str:
    if r.printed_error is None:
        return "-"
    if r.corrected_error is None or r.printed_error <= r.tolerance:
        return f"{r.printed_error:.1e}"
    return f"{r.printed_error:.1e} -> {r.corrected_error:.1e}"


HEADER = f"{'equation':<9} {'quantity':<46} {'max error':<19} verdict"


def format_row(r: CheckResult) -> str:
    return f"{r.equation:<9} {r.quantity:<46} {_format_error(r):<19} {r.verdict}"


def print_check_table(verbose: bool = False) -> int:
    """Print the table row by row; return 0 only if every check holds (skipped rows do not fail).

    "max error" is the largest error of the printed form over the seeded states; for a
    misprint it reads "printed -> corrected".
    """
    t0 = time.perf_counter()
    print("qprr check: the thesis's closed forms against the Pinocchio model (docs/thesis-errata.md)")
    print(HEADER)
    print("-" * len(HEADER.expandtabs()) + "-" * 30)

    def show(r: CheckResult) -> None:
        print(format_row(r), flush=True)
        if verbose and r.reason:
            print(f"{'':<10}{r.reason}", flush=True)

    results = run_checks(on_result=show)
    n_fail = sum(not r.ok for r in results)
    n_mis = sum(r.verdict.startswith("misprint") for r in results)
    n_skip = sum(r.status == CheckStatus.SKIPPED for r in results)
    print(
        f"\n{len(results)} checks: {len(results) - n_fail - n_skip} hold ({n_mis} of them misprints whose corrected form holds), "
        f"{n_skip} skipped, {n_fail} failed  [{time.perf_counter() - t0:.1f} s]"
    )
    return 0 if n_fail == 0 else 1


if __name__ == "__main__":
    sys.exit(print_check_table("-v" in sys.argv))
