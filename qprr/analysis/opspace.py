"""Operational-space model at the end effector (Thesis Sec. 5.4, (5.47)-(5.52)), and its map.

With the joint-space model M(q) a + h(q, v) = tau (Thesis (5.36); h = C v + g) and the
end-effector twist x_dot = [p_dot; omega] = J v (Pinocchio's LOCAL_WORLD_ALIGNED frame
Jacobian, the geometric J of (5.48)), a wrench F applied through tau = J^T F (5.47) gives

    Lambda x_ddot + mu + p = F,       Lambda = (J M^-1 J^T)^-1,
    mu = Lambda (J M^-1 (h - g) - J_dot v),   p = Lambda J M^-1 g,

(Khatib's operational-space model; J_bar = M^-1 J^T Lambda is the dynamically consistent
inverse, mu = J_bar^T (h - g) - Lambda J_dot v, p = J_bar^T g).  This is (5.51)-(5.52) with
B_A = Lambda, C_A x_dot = mu, G_A = p.  The printed (5.50)-(5.51) invert J_A, which is 6 x 9
for the Q-PRR (it has no inverse): they hold only for a square J (docs/thesis-errata.md,
rows (5.50)-(5.51)); the form above is the one for any number of joints.  The analytic form
with Euler-angle rates follows from (5.48)-(5.49): Lambda_A = T_A^T Lambda T_A.

In thesis coordinates (:func:`opspace_model_xi`: xi_dot, B = S^T M S, n = C xi_dot + G of
(5.36)) the same model reads Lambda^-1 = J_xi B^-1 J_xi^T, mu = J_bar^T (n - G) - Lambda J_xi_dot xi_dot,
p = J_bar^T G (Lambda, mu, p do not depend on the coordinates).  There some coordinates may be
*locked* (zero acceleration, their constraint forces workless): ``coordinates`` lists the free
ones and the model is that of the system moving along them only, Lambda_c^-1 = J_c B_cc^-1 J_c^T.
The operational-space impedance controller (:mod:`qprr.control.opspace_impedance`) uses it
with roll and pitch locked (they belong to the attitude loop of an under-actuated platform).

For the floating-base platform J has full row rank (the base twist alone spans every
end-effector twist), so Lambda always exists.  ``fixed_base=True`` uses the arm alone
(:meth:`Platform.arm_model`), whose J may have a lower rank: Lambda is then taken on the
row space (pseudo-inverse), and ``rank`` says so.

:func:`opspace_map` evaluates, over a grid of arm configurations (base at rest at the
origin), the effective mass the end effector shows along x, y, z (1 / (u^T Lambda^-1 u), the
inertia felt pushing it) and the condition number of Lambda.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..errors import InputError
from ..kinematics import check_q
from ..model import Platform, check_data
from ..validation import as_vector
from ._common import JointGrid, MapStatus, check_arm_platform, check_int, check_locked, check_progress, make_grid
from .budget import SampleChoice, check_budget, check_clock, grid_work, within_budget


@dataclass(frozen=True)
class OpSpaceModel:
    """Operational-space model at one state (see the module docstring).

    ``J`` (6, nv), ``J_dot_v`` (6,): [classical linear acceleration; angular acceleration] at
    a = 0; ``M`` (nv, nv); ``Lambda``, ``Lambda_inv`` (6, 6) [kg, kg m, kg m^2 blocks];
    ``J_bar`` (nv, 6); ``mu``, ``p`` (6,) [N, N m]; ``h``, ``g`` (nv,) nonlinear effects and
    gravity; ``rank`` of J (6 for the floating base).
    """

    q: np.ndarray
    v: np.ndarray
    frame: int
    J: np.ndarray
    J_dot_v: np.ndarray
    M: np.ndarray
    Lambda: np.ndarray
    Lambda_inv: np.ndarray
    J_bar: np.ndarray
    mu: np.ndarray
    p: np.ndarray
    h: np.ndarray
    g: np.ndarray
    rank: int

    def acceleration(self, F) -> np.ndarray:
        """x_ddot = Lambda^-1 (F - mu - p) [m/s^2, rad/s^2] under tau = J^T F alone, (5.52)."""
        F = as_vector(F, 6, "F")
        return self.Lambda_inv @ (F - self.mu - self.p)


def opspace_model(platform: Platform, data: pin.Data, q, v=None, frame=None, *, fixed_base: bool = False) -> OpSpaceModel:
    """The operational-space model of ``frame`` (default: the end effector) at (q, v), Thesis (5.47)-(5.52).

    ``q``, ``v``: Pinocchio configuration and velocity of the platform (``fixed_base``: of the
    arm model, nq = nv = n_arm, and ``data`` from ``platform.arm_model().createData()``).
    """
    check_arm_platform(platform)
    if not isinstance(data, pin.Data):
        raise InputError(f"data must be a pinocchio.Data, got {type(data).__name__}")
    model = platform.arm_model() if fixed_base else platform.model
    if len(data.oMf) != model.nframes:
        raise InputError(
            f"data was made for another model ({len(data.oMf)} frames, this one has {model.nframes}): use "
            f"{'platform.arm_model().createData()' if fixed_base else 'platform.data()'}"
        )
    fid = platform.ee_frame if frame is None else platform.frame_id(frame)
    if fixed_base:
        fid = model.getFrameId(platform.model.frames[fid].name)
        q = as_vector(q, model.nq, "q")
    else:
        q = check_q(platform, q)
    v = np.zeros(model.nv) if v is None else as_vector(v, model.nv, "v")
    pin.computeAllTerms(model, data, q, v)
    M = np.triu(data.M) + np.triu(data.M, 1).T
    h = data.nle.copy()
    g = pin.computeGeneralizedGravity(model, data, q).copy()
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
    acc = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
    Jdv = np.concatenate([acc.linear, acc.angular])
    Minv_JT = np.linalg.solve(M, J.T)
    Li = J @ Minv_JT
    Li = 0.5 * (Li + Li.T)
    rank = int(np.linalg.matrix_rank(Li, tol=1e-10 * max(np.abs(Li).max(), 1e-300)))
    L = np.linalg.inv(Li) if rank == 6 else np.linalg.pinv(Li, rcond=1e-10, hermitian=True)
    Jbar = Minv_JT @ L
    mu = Jbar.T @ (h - g) - L @ Jdv
    p = Jbar.T @ g
    return OpSpaceModel(q.copy(), v.copy(), fid, J, Jdv, M, L, Li, Jbar, mu, p, h, g, rank)


ROWS = {"pose": (0, 1, 2, 3, 4, 5), "position": (0, 1, 2), "orientation": (3, 4, 5)}
"""Named row sets of the end-effector twist [p_dot; omega] (world axes)."""


@dataclass(frozen=True)
class OpSpaceModelXi:
    """Operational-space model in thesis coordinates, some coordinates possibly locked (see the module docstring).

    ``position`` (3,) [m] and ``velocity`` (6,) = [p_dot; omega] [m/s, rad/s] of the frame (world
    axes); ``J`` (6, 6 + n) the thesis Jacobian of the twist, [p_dot; omega] = J xi_dot (Thesis
    (4.11)-(4.13)); ``drift`` (6,) = J_dot xi_dot, the classical end-effector acceleration at
    xi_ddot = 0 [m/s^2, rad/s^2]; ``B`` (6 + n, 6 + n), ``n`` = C xi_dot + G and ``G`` (6 + n,) of
    (5.36); ``J_v`` (6, nv) and ``M`` (nv, nv) the same in Pinocchio's coordinates (J = J_v S,
    B = S^T M S).  On the ``rows`` (r of the twist) and the free ``coordinates`` (indices into xi):
    ``Lambda``, ``Lambda_inv`` (r, r); ``J_bar`` (n_c, r) the dynamically consistent inverse of
    J_c = J[rows][:, coordinates]; ``mu``, ``p`` (r,); ``rank`` of J_c.
    """

    xi: np.ndarray
    xi_dot: np.ndarray
    frame: int
    rows: tuple[int, ...]
    coordinates: tuple[int, ...]
    position: np.ndarray
    velocity: np.ndarray
    J: np.ndarray
    drift: np.ndarray
    B: np.ndarray
    n: np.ndarray
    G: np.ndarray
    J_v: np.ndarray
    M: np.ndarray
    Lambda: np.ndarray
    Lambda_inv: np.ndarray
    J_bar: np.ndarray
    mu: np.ndarray
    p: np.ndarray
    rank: int

    @property
    def J_c(self) -> np.ndarray:
        """J_c (r, n_c): the ``rows`` of ``J``, columns of the free coordinates."""
        return self.J[np.ix_(self.rows, self.coordinates)]

    def acceleration(self, F) -> np.ndarray:
        """End-effector acceleration (rows) under u_c = J_c^T F alone on the free coordinates: Lambda^-1 (F - mu - p)."""
        F = as_vector(F, len(self.rows), "F")
        return self.Lambda_inv @ (F - self.mu - self.p)


def _check_selection(values, n: int, name: str, names=None) -> tuple[int, ...]:
    if isinstance(values, str) and names is not None:
        if values not in names:
            from ..errors import UnknownNameError

            raise UnknownNameError(name, values, tuple(names))
        return names[values]
    try:
        idx = tuple(int(i) for i in values)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be indices in [0, {n}), got {values!r}") from exc
    if not idx or len(set(idx)) != len(idx) or min(idx) < 0 or max(idx) >= n or any(i != v for i, v in zip(idx, values)):
        raise InputError(f"{name} must be distinct indices in [0, {n}), got {values!r}")
    return idx


def opspace_model_xi(platform: Platform, data: pin.Data, xi, xi_dot=None, frame=None, *, rows="pose", coordinates=None) -> OpSpaceModelXi:
    """The operational-space model of ``frame`` (default: end effector) in thesis coordinates, Thesis (5.47)-(5.52).

    Parameters
    ----------
    xi, xi_dot : thesis coordinates and rates (6 + n_arm,) [m, rad, m/s, rad/s].
    rows : "pose", "position", "orientation" or indices into the twist [p_dot; omega] (world axes).
    coordinates : the free coordinates (indices into xi; default: all); the others are locked.

    Returns :class:`OpSpaceModelXi`; ``position`` (3,) and ``velocity`` (6,) of the frame (world).
    With every coordinate free and ``rows="pose"``, Lambda, mu, p equal those of
    :func:`opspace_model` at the same state (tests/test_analysis_opspace.py).
    """
    check_data(check_arm_platform(platform), data)
    n_xi = platform.n_xi
    xi = ch.as_xi(xi, "xi", n_xi)
    w = np.zeros(n_xi) if xi_dot is None else as_vector(xi_dot, n_xi, "xi_dot")
    ch.check_pitch(xi[4], "opspace_model_xi")
    rows = _check_selection(rows, 6, "rows", ROWS)
    cols = tuple(range(n_xi)) if coordinates is None else _check_selection(coordinates, n_xi, "coordinates")
    fid = platform.ee_frame if frame is None else platform.frame_id(frame)
    S = ch.rate_map(xi)
    a0 = ch.rate_map_dot(xi, w) @ w  # Pinocchio acceleration at xi_ddot = 0
    return opspace_terms_xi(platform.model, data, fid, RateMapState(ch.xi_to_q(xi), S @ w, a0, S, xi.copy(), w.copy()), rows, cols)


@dataclass(frozen=True)
class RateMapState:
    """A checked Pinocchio state with the thesis rate map, what :func:`opspace_terms_xi` reads.

    ``q`` (nq,), ``v`` = S xi_dot (nv,) [LOCAL], ``a0`` = S_dot xi_dot (nv,) (Pinocchio's acceleration at
    xi_ddot = 0), ``S`` (nv, 6 + n) the rate map xi_dot -> v (:func:`qprr.charts.rate_map`); ``xi``,
    ``xi_dot``: the thesis coordinates and rates, copied into the result (None if not at hand).
    """

    q: np.ndarray
    v: np.ndarray
    a0: np.ndarray
    S: np.ndarray
    xi: np.ndarray | None = None
    xi_dot: np.ndarray | None = None


def opspace_terms_xi(
    model: pin.Model, data: pin.Data, fid: int, state: RateMapState, rows: tuple[int, ...], cols: tuple[int, ...], *, operational: bool = True
) -> OpSpaceModelXi:
    """:func:`opspace_model_xi` from a checked :class:`RateMapState` (no input checks; for control loops that hold it
    already, e.g. :class:`qprr.charts.State`).  ``operational=False`` stops after the kinematics and the mass matrices
    (``n``, ``G``, ``Lambda``, ``Lambda_inv``, ``J_bar``, ``mu``, ``p`` None, ``rank`` -1)."""
    q, v, a0, S = state.q, state.v, state.a0, state.S
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    B = S.T @ M @ S
    if operational:
        n = S.T @ pin.rnea(model, data, q, v, a0)  # C xi_dot + G
        G = S.T @ pin.computeGeneralizedGravity(model, data, q)
    Jv = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
    pin.forwardKinematics(model, data, q, v, a0)
    pin.updateFramePlacement(model, data, fid)
    acc = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
    J = Jv @ S
    twist = Jv @ v
    drift = np.concatenate([acc.linear, acc.angular])
    kin = (state.xi, state.xi_dot, fid, tuple(rows), tuple(cols), data.oMf[fid].translation.copy(), twist, J, drift, B)
    if not operational:
        return OpSpaceModelXi(*kin, None, None, Jv, M, None, None, None, None, None, -1)
    L, Li, Jbar, mu, p, rank = _task_space(J, B, n, G, drift, list(rows), list(cols))
    return OpSpaceModelXi(*kin, n, G, Jv, M, L, Li, Jbar, mu, p, rank)


def _task_space(J, B, n, G, drift, r: list[int], c: list[int]):
    """(Lambda, Lambda^-1, J_bar, mu, p, rank) on the rows ``r`` and free coordinates ``c``, Thesis (5.47)-(5.52)."""
    Jc = J[np.ix_(r, c)]
    X = np.linalg.solve(B[np.ix_(c, c)], Jc.T)
    Li = Jc @ X
    Li = 0.5 * (Li + Li.T)
    rank = int(np.linalg.matrix_rank(Li, tol=1e-10 * max(np.abs(Li).max(), 1e-300)))
    L = np.linalg.inv(Li) if rank == len(r) else np.linalg.pinv(Li, rcond=1e-10, hermitian=True)
    Jbar = X @ L
    mu = Jbar.T @ (n - G)[c] - L @ drift[r]
    p = Jbar.T @ G[c]
    return L, Li, Jbar, mu, p, rank


@dataclass(frozen=True)
class OpSpaceMap:
    """Effective end-effector mass over ``grid`` (base at rest at the origin, v = 0).

    ``mass_xyz`` (n, 3) [kg]: 1 / (u^T Lambda^-1 u) for u = x, y, z of the world (= B);
    ``inertia_xyz`` (n, 3) [kg m^2] the same for rotations; ``condition`` (n,) of Lambda;
    ``gravity_force`` (n, 3) [N]: the linear part of p.
    """

    platform_name: str
    grid: JointGrid
    ee_body: np.ndarray
    mass_xyz: np.ndarray
    inertia_xyz: np.ndarray
    condition: np.ndarray
    gravity_force: np.ndarray
    status: MapStatus
    reason: str
    sampling: SampleChoice | None = None

    def summary(self) -> str:
        lo, hi = self.mass_xyz.min(axis=0), self.mass_xyz.max(axis=0)
        more = f"\n  {self.sampling.describe()}" if self.sampling is not None else ""
        return (
            f"operational space of {self.platform_name} ({self.grid.size} configurations): effective mass along x, y, z in "
            f"[{lo[0]:.4g}, {hi[0]:.4g}], [{lo[1]:.4g}, {hi[1]:.4g}], [{lo[2]:.4g}, {hi[2]:.4g}] kg; "
            f"condition number of Lambda in [{self.condition.min():.4g}, {self.condition.max():.4g}]{more}"
        )


@dataclass(frozen=True)
class OpSpaceOptions:
    """Settings of :func:`opspace_map` (each can also be given to it as a keyword).

    ``n_samples``: joint-grid size; ``locked``, ``ranges``: as in :func:`qprr.analysis.workspace`; ``frame``: the
    frame mapped (name or id; default the end effector); ``budget``, ``clock``: wall time [s] the map may take,
    ``n_samples`` then chosen from pilot runs timed with ``clock`` (:mod:`qprr.analysis.budget`; None: ``n_samples``
    is used)."""

    n_samples: int = 20_000
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    frame: object = None
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings, checked however the options are built
        check_int("n_samples", self.n_samples, 2)
        check_budget(self.budget)
        check_clock(self.clock)


def opspace_map(platform: Platform, options: OpSpaceOptions | None = None, *, progress=None, **settings) -> OpSpaceMap:
    """Effective mass and conditioning of the operational-space inertia over the arm's joint grid (one Pinocchio
    evaluation per configuration: CRBA, the frame Jacobian and a Cholesky solve).

    ``options``: :class:`OpSpaceOptions`, and/or its fields as keywords (``opspace_map(p, n_samples=300)``; an unknown
    keyword is a TypeError); ``progress``: None, True (stderr) or a callable (fraction, message)."""
    o = options if options is not None else OpSpaceOptions()
    if not isinstance(o, OpSpaceOptions):
        raise InputError(f"options must be an OpSpaceOptions, got {type(o).__name__}")
    o = replace(o, **settings) if settings else o
    check_arm_platform(platform)
    work = grid_work(platform, [check_locked(platform, o.locked)], o.ranges)
    return within_budget(o, lambda oo, pr: _opspace_map(platform, oo, pr), work, check_progress(progress))


def _opspace_map(platform: Platform, o: OpSpaceOptions, progress) -> OpSpaceMap:
    """:func:`opspace_map` at ``o.n_samples``.  The triangular solves are numpy's: scipy's ``solve_triangular`` on
    these 6-10 column matrices took 10-20 ms a call on a loaded 2-core machine (its BLAS threads waiting for a core),
    numpy's solve about 0.1 ms."""
    grid = make_grid(platform, o.n_samples, o.locked, o.ranges)
    frame = o.frame
    model = platform.model
    data = platform.data()
    fid = platform.ee_frame if frame is None else platform.frame_id(frame)
    n = grid.size
    ee, mass, inert, cond, grav = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty((n, 3))
    q = pin.neutral(model)
    for start, qa in grid.chunks(2048):
        for i, row in enumerate(qa):
            q[7:] = row
            M = pin.crba(model, data, q)
            M = np.triu(M) + np.triu(M, 1).T
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
            c = np.linalg.cholesky(M)
            X = np.linalg.solve(c, J.T)  # M = c c^T (c lower triangular): J M^-1 J^T = X^T X
            Li = X.T @ X
            k = start + i
            ee[k] = data.oMf[fid].translation
            d = np.diag(Li)
            mass[k], inert[k] = 1.0 / d[0:3], 1.0 / d[3:6]
            w = np.linalg.eigvalsh(Li)
            cond[k] = w[-1] / w[0]
            g = pin.computeGeneralizedGravity(model, data, q)
            grav[k] = np.linalg.solve(Li, X.T @ np.linalg.solve(c, g))[0:3]
        if progress:
            progress((start + len(qa)) / n, "operational-space map")
    return OpSpaceMap(platform.name, grid, ee, mass, inert, cond, grav, MapStatus.OK, "")
