"""Singularities of the arm over its joint space: det(J J^T), manipulability, condition number, distance.

Thesis Sec. 4.4.3 studies det(J^gamma) = det(J J^T) (4.42)-(4.45) of the whole system's 6 x 9
Jacobian (4.12) at zero Euler angles and finds it never vanishes ((4.46)-(4.48): at least 6.02
for r0 in {-0.04, 0, 0.04} m): the base's six coordinates alone span every end-effector twist,
so the *system* is never singular.  What a designer needs is where the *arm* loses mobility,
which the thesis does not map.  :func:`singularity` computes over the joint grid:

* ``det_system``: the thesis's det(J J^T) with the 6 x (6 + n) Jacobian at zero Euler angles
  (Thesis (4.44); J = [[I, -hat(p_eb), J_v], [0, I, J_w]] in B);
* the arm's task Jacobian J_t (rows of the arm Jacobian in B, (4.26) for the Q-PRR): ``task``
  "pose" (all six rows, the angular ones times a length ``length`` so that every singular
  value is in metres) or "position"; rows that vanish at every configuration (y, omega_x,
  omega_z of a planar arm) are dropped.  Its singular values sigma_1 >= ... >= sigma_r (r the
  generic rank), the manipulability w = prod sigma_i (Yoshikawa: sqrt(det(J_t J_t^T)) for a
  full-row-rank J_t), the condition number sigma_1 / sigma_r;
* the singular set: where the rank drops.  When J_t is square (the Q-PRR's rows x, z, omega_y
  against r0, theta2, theta3: det = -L d2 s2, (4.28)) the set is the zero level of det J_t,
  found exactly where det changes sign between grid neighbours; otherwise the configurations
  with sigma_r / sigma_1 < ``tol``;
* the distance from every configuration to the singular set in joint space (revolute joints in
  rad, prismatic joints in metres divided by ``length``), by an exact Euclidean distance
  transform of the grid.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np
from scipy import ndimage

from ..errors import InputError, UnknownNameError
from ..model import Platform
from ._common import (
    JointGrid,
    MapStatus,
    check_arm_platform,
    check_int,
    check_locked,
    check_pos,
    check_progress,
    joint_ranges,
    lever_lengths,
    make_grid,
)
from .budget import SampleChoice, check_budget, check_clock, grid_work, within_budget
from .chain import ArmChain

TASKS = ("pose", "position")


@dataclass(frozen=True)
class SingularityResult:
    """Singularity measures over ``grid`` (n configurations; see the module docstring).

    ``rows``: the task rows kept (names of [v_x, v_y, v_z, w_x, w_y, w_z] in B); ``length`` [m]:
    scale of the angular rows and of the prismatic joints in distances; ``rank``: generic rank of
    J_t; ``sigma`` (n, r) [m]; ``manipulability`` (n,) [m^r]; ``condition`` (n,); ``det_task``
    (n,) [m^r] signed det J_t (square J_t only, else None); ``det_system`` (n,) the thesis's
    det(J J^T) (4.44) [mixed units, as printed]; ``singular`` (n,) grid points next to the
    singular set; ``distance`` (n,) to it (inf if the set is empty).
    """

    platform_name: str
    task: str
    grid: JointGrid
    rows: tuple[str, ...]
    length: float
    rank: int
    sigma: np.ndarray
    manipulability: np.ndarray
    condition: np.ndarray
    det_task: np.ndarray | None
    det_system: np.ndarray
    singular: np.ndarray
    distance: np.ndarray
    status: MapStatus
    reason: str
    sampling: SampleChoice | None = None

    def summary(self) -> str:
        g = self.grid
        i = int(np.argmin(self.det_system))
        lines = [
            f"singularities of {self.platform_name}: task {self.task!r} rows {list(self.rows)}, generic rank {self.rank}, "
            f"length scale {self.length:.4g} m, {g.size} configurations",
            f"  manipulability in [{self.manipulability.min():.4g}, {self.manipulability.max():.4g}] m^{self.rank}; "
            f"condition number median {np.median(self.condition):.4g}",
            f"  singular set: {100 * self.singular.mean():.2f}% of the grid points next to it; "
            f"median distance {np.median(self.distance):.4g} (rad or m/length)",
            f"  system det(J J^T) (base + arm Jacobian at zero Euler angles): min {self.det_system[i]:.6g} at q_arm = "
            f"{np.round(g.configurations(i, i + 1)[0], 4).tolist()}, max {self.det_system.max():.6g}",
        ]
        if self.reason:
            lines.append(f"  status {self.status.value}: {self.reason}")
        if self.sampling is not None:
            lines.append(f"  {self.sampling.describe()}")
        return "\n".join(lines)


ROW_NAMES = ("v_x", "v_y", "v_z", "w_x", "w_y", "w_z")


def system_det(J_arm: np.ndarray, p_eb: np.ndarray) -> np.ndarray:
    """det(J J^T) of the 6 x (6 + n) system Jacobian at zero Euler angles, Thesis (4.42)-(4.44).

    J = [[I, -hat(p_eb), J_v], [0, I, J_w]] with the arm Jacobian ``J_arm`` (m, 6, n) and the
    end effector ``p_eb`` (m, 3) in B (= world at zero Euler angles, base at the origin).
    """
    m = J_arm.shape[0]
    H = np.zeros((m, 3, 3))
    H[:, 0, 1], H[:, 0, 2], H[:, 1, 2] = -p_eb[:, 2], p_eb[:, 1], -p_eb[:, 0]
    H[:, 1, 0], H[:, 2, 0], H[:, 2, 1] = p_eb[:, 2], -p_eb[:, 1], p_eb[:, 0]
    A = J_arm @ J_arm.transpose(0, 2, 1)
    A[:, 0:3, 0:3] += np.eye(3) + H @ H.transpose(0, 2, 1)
    A[:, 0:3, 3:6] -= H
    A[:, 3:6, 0:3] -= H.transpose(0, 2, 1)
    A[:, 3:6, 3:6] += np.eye(3)
    return np.linalg.det(A)


@dataclass(frozen=True)
class SingularityOptions:
    """Settings of :func:`singularity` (each can also be given to it as a keyword).

    ``n_samples``: joint-grid size; ``task``: "pose" (six rows, angular ones scaled by ``length``) or
    "position"; ``length`` [m]: default the arm's reach, the largest revolute lever of
    :func:`qprr.analysis._common.lever_lengths` (1 m for an arm without revolute joints); ``locked``,
    ``ranges``: as in :func:`qprr.analysis.workspace`; ``frame``: the frame mapped (name or id; default
    the end effector); ``tol``: sigma_r / sigma_1 below which a configuration counts as singular
    (non-square J_t); ``budget``, ``clock``: wall time [s] the map may take, ``n_samples`` then chosen from pilot
    runs timed with ``clock`` (:mod:`qprr.analysis.budget`; None: ``n_samples`` is used).
    """

    n_samples: int = 200_000
    task: str = "pose"
    length: float | None = None
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    frame: object = None
    tol: float = 1e-3
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings, checked however the options are built
        check_int("n_samples", self.n_samples, 8)
        check_budget(self.budget)
        check_clock(self.clock)
        if self.task not in TASKS:
            raise UnknownNameError("singularity task", self.task, TASKS)
        if self.length is not None:
            check_pos("length", self.length)
        check_pos("tol", self.tol)


def _reach(platform: Platform, ranges) -> float:
    """The default ``length`` [m]: the largest revolute lever (1 m without revolute joints)."""
    levers = lever_lengths(platform, joint_ranges(platform, ranges))
    rev = [levers[i] for i, j in enumerate(platform.arm) if j.kind == "revolute"]
    return float(max(rev)) if rev and max(rev) > 0 else 1.0


def _task_rows(chain: ArmChain, grid, fid: int, task: str, free: list[int]) -> list[int]:
    """Task rows that do not vanish everywhere: probed on a few hundred configurations spread over the grid."""
    rows_all = list(range(6)) if task == "pose" else [0, 1, 2]
    probe = grid.configurations(0, grid.size)[:: max(1, grid.size // 512)]
    Jp = chain.jacobian(chain.pose(probe), fid)[:, :, free]
    scale = np.abs(Jp).max()
    return [r for r in rows_all if np.abs(Jp[:, r, :]).max() > 1e-12 * max(scale, 1e-300)]


def _jacobian_maps(chain: ArmChain, grid, fid: int, rows: list[int], free: list[int], length: float, progress):
    """(squared singular values (n, min(k, na)), det J_t (n,) or None if J_t is not square, det(J J^T) of (4.42)) on the grid."""
    n, na, k = grid.size, len(free), len(rows)
    w_rows = np.array([1.0 if r < 3 else length for r in rows])
    sig2 = np.empty((n, min(k, na)))
    det_task = np.empty(n) if k == na else None
    det_sys = np.empty(n)
    for start, q in grid.chunks():
        sl = slice(start, start + len(q))
        pose = chain.pose(q)
        J = chain.jacobian(pose, fid)
        det_sys[sl] = system_det(J, chain.frame_position(pose, fid))
        Jt = J[:, rows, :][:, :, free] * w_rows[None, :, None]
        sig2[sl] = np.linalg.svd(Jt, compute_uv=False) ** 2  # not eigenvalues of J J^T: they lose the small sigma
        if det_task is not None:
            det_task[sl] = np.linalg.det(Jt)
        if progress:
            progress((start + len(q)) / n, "singularity map")
    return sig2, det_task, det_sys


def _singular_set(det_task, sig_r: np.ndarray, square: bool, sq_shape: tuple[int, ...], tol: float) -> np.ndarray:
    """Singular grid points: where det J_t vanishes or changes sign between neighbours (square J_t), else sigma_r <= tol sigma_1."""
    if not square:
        return (sig_r[:, -1] <= tol * sig_r[:, 0]).reshape(sq_shape)
    D = det_task.reshape(sq_shape)
    sing = np.abs(D) <= 1e-12 * np.abs(D).max()
    for ax in range(D.ndim):  # a sign change between neighbours: both sides are next to the zero set
        a = np.take(D, range(D.shape[ax] - 1), axis=ax)
        b = np.take(D, range(1, D.shape[ax]), axis=ax)
        ch = (a * b) < 0
        sing |= np.pad(ch, [(0, 1) if i == ax else (0, 0) for i in range(D.ndim)])
        sing |= np.pad(ch, [(1, 0) if i == ax else (0, 0) for i in range(D.ndim)])
    return sing


def singularity(platform: Platform, options: SingularityOptions | None = None, *, progress=None, **settings) -> SingularityResult:
    """Singularity maps of ``frame`` (default: the end effector) over the arm's joint grid.

    ``options``: :class:`SingularityOptions`, and/or its fields as keywords (``singularity(p,
    n_samples=2e4, task="position")``; an unknown keyword is a TypeError); ``progress``: None, True
    (stderr) or a callable (fraction, message).
    """
    o = options if options is not None else SingularityOptions()
    if not isinstance(o, SingularityOptions):
        raise InputError(f"options must be a SingularityOptions, got {type(o).__name__}")
    o = replace(o, **settings) if settings else o
    check_arm_platform(platform)
    work = grid_work(platform, [check_locked(platform, o.locked)], o.ranges)
    return within_budget(o, lambda oo, pr: _singularity(platform, oo, pr), work, check_progress(progress))


def _singularity(platform: Platform, o: SingularityOptions, progress) -> SingularityResult:
    """:func:`singularity` at ``o.n_samples``."""
    tol = check_pos("tol", o.tol)
    fid = platform.ee_frame if o.frame is None else platform.frame_id(o.frame)
    grid = make_grid(platform, o.n_samples, o.locked, o.ranges)
    length = check_pos("length", _reach(platform, o.ranges) if o.length is None else o.length)
    chain = ArmChain(platform)
    free = [a for a in range(platform.n_arm) if grid.shape[a] > 1]  # locked joints are no columns of J_t
    rows = _task_rows(chain, grid, fid, o.task, free)
    sig2, det_task, det_sys = _jacobian_maps(chain, grid, fid, rows, free, length, progress)
    sigma = np.sqrt(np.clip(sig2, 0.0, None))
    rank = int(np.max(np.sum(sigma > 1e-9 * np.maximum(sigma[:, :1], 1e-300), axis=1)))
    sig_r = sigma[:, :rank]
    manip = np.prod(sig_r, axis=1)
    with np.errstate(divide="ignore"):
        cond = np.where(sig_r[:, -1] > 0, sig_r[:, 0] / sig_r[:, -1], np.inf)
    sq_shape = tuple(grid.shape[a] for a in free)
    sing = _singular_set(det_task, sig_r, det_task is not None and rank == len(rows), sq_shape, tol)
    spacing = [(grid.axes[a][1] - grid.axes[a][0]) / (length if platform.arm[a].kind == "prismatic" else 1.0) for a in free]
    if sing.any():
        dist = ndimage.distance_transform_edt(~sing, sampling=spacing).reshape(-1)
        status, reason = MapStatus.OK, ""
    else:
        dist = np.full(grid.size, np.inf)
        status, reason = MapStatus.OK, "no singular configuration on the grid (distance = inf)"
    return SingularityResult(
        platform.name,
        o.task,
        grid,
        tuple(ROW_NAMES[r] for r in rows),
        length,
        rank,
        sig_r,
        manip,
        cond,
        det_task,
        det_sys,
        sing.reshape(-1),
        dist,
        status,
        reason,
    )
