"""How wrong a fixed PX4 mixer becomes as the arm moves the centre of gravity (a design map).

PX4's mix is built once from the ``CA_*`` geometry exported at a pose q0 (:func:`qprr.flightstack.px4.geometry_from_platform`).
When the arm moves to q, the rotors stay where they are on the base but the centre of gravity moves from c(q0) to c(q),
so the wrench the same motor commands produce *about the true centre of gravity* changes: each rotor's moment gains
-(C dc) x F_i (dc = c(q) - c(q0), C the FLU -> FRD map, F_i its thrust), while its thrust is unchanged.

For a unit request e (normalised setpoints: roll, pitch, yaw torque, vertical thrust; lateral thrusts too for a fully
actuated set) the mix gives the commands u = M0 e; the intended wrench is w0 = E0 u (what PX4 believes it produces)
and the actual one E(q) u.  The relative error of request e at q is

    || S (E(q) - E0) u || / || S w0 ||,       S = diag(1/L, 1/L, 1/L, 1, 1, 1)

with torques divided by the rotor span L [m] (largest rotor distance from the centre of gravity at q0) so that a
torque and a force compare.  The map reports the worst over the requests; it is 0 at q0 and, for a vehicle with
parallel rotors, equals |dc| projected on the rotor plane / L for the thrust request.  The hover torque offset
|dc x m g| [N m] is the torque the attitude controller must supply at hover to hold the pose q with the mix of q0.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from ..errors import InputError
from ..model import Platform, check_platform
from ..validation import as_int
from ..viz.plots import new_figure, save_figure
from .frames import frd_from_body
from .px4 import AXES, coms_body_at, geometry_from_rotors

DEFAULT_RESOLUTION = 41
"""Grid points per joint of the map (41 x 41 for two joints)."""
DEFAULT_SAMPLES = 2000
"""Random arm configurations over the whole joint box (arms with more than the map's joints)."""
MAX_CANDIDATES = 400
"""Candidate poses q0 tried when searching the one with the smallest worst error."""


@dataclass(frozen=True)
class MixerErrorResult:
    """The fixed mixer's error over an arm's range (:func:`mixer_error`).

    platform_name; joint_names (all arm joints) and map_joints (indices of the one or two joints of the map);
    kinds ("revolute" [rad] / "prismatic" [m]) of the map joints; q0 (n_arm,) the export pose; axes: the map's joint
    values (one array per map joint); error_map: worst relative error over the requests at each map point (the other
    joints at q0), shape of the grid; requests: the request names; worst_error, worst_q: the largest error over the map
    and the samples, and where; worst_hover_torque [N m]: |dc x m g| there; best_q0, best_worst_error: the export pose
    among the candidates with the smallest worst error over the same configurations, and that error; span [m]."""

    platform_name: str
    joint_names: tuple[str, ...]
    map_joints: tuple[int, ...]
    kinds: tuple[str, ...]
    q0: np.ndarray
    axes: tuple[np.ndarray, ...]
    error_map: np.ndarray
    requests: tuple[str, ...]
    worst_error: float
    worst_q: np.ndarray
    worst_hover_torque: float
    best_q0: np.ndarray
    best_worst_error: float
    span: float
    n_configurations: int

    def summary(self) -> str:
        q0 = np.round(self.q0, 4).tolist()
        best = np.round(self.best_q0, 4).tolist()
        return "\n".join(
            [
                f"fixed PX4 mixer of {self.platform_name} exported at q_arm = {q0} ({self.n_configurations} arm configurations, "
                f"requests {', '.join(self.requests)}, torques over the rotor span {self.span:.4g} m)",
                f"  worst wrench error {100 * self.worst_error:.3g} % at q_arm = {np.round(self.worst_q, 4).tolist()} "
                f"(hover torque offset {self.worst_hover_torque:.4g} N m about the true centre of gravity)",
                f"  best export pose q_arm = {best}: worst error {100 * self.best_worst_error:.3g} %",
            ]
        )

    def plot(self, path: str | Path | None = None):
        """The error map over the map joints (a line for one joint), q0 and the best pose marked; saved to ``path``
        (.png, .pdf, .svg) when given.  Returns the figure."""
        fig = new_figure((7.5, 5.5))
        ax = fig.add_subplot(1, 1, 1)
        shown = [_display(a, k) for a, k in zip(self.axes, self.kinds)]
        labels = [f"{self.joint_names[j]} [{'deg' if k == 'revolute' else 'm'}]" for j, k in zip(self.map_joints, self.kinds)]
        at = [[_display(np.array([q[j]]), k)[0] for j, k in zip(self.map_joints, self.kinds)] for q in (self.q0, self.best_q0)]
        pct = 100.0 * self.error_map
        if len(self.map_joints) == 1:
            ax.plot(shown[0], pct, color="C0", lw=2, label="worst error over the requests")
            ax.axvline(at[0][0], color="k", ls="--", label="export pose q0")
            ax.axvline(at[1][0], color="C2", ls=":", label=f"best export pose {np.round(self.best_q0, 3).tolist()}")
            ax.set_xlabel(labels[0])
            ax.set_ylabel("worst relative wrench error [%]")
            ax.legend(loc="upper center")
        else:
            mesh = ax.pcolormesh(shown[0], shown[1], pct.T, shading="auto", cmap="viridis")
            fig.colorbar(mesh, ax=ax, label="worst relative wrench error [%]")
            ax.contour(shown[0], shown[1], pct.T, colors="w", linewidths=0.6, levels=6)
            ax.plot(*at[0], "k*", ms=14, mec="w", label="export pose q0")
            ax.plot(*at[1], "o", color="C1", ms=8, mec="w", label=f"best export pose {np.round(self.best_q0, 3).tolist()}")
            ax.set_xlabel(labels[0])
            ax.set_ylabel(labels[1])
            ax.legend(loc="upper right", fontsize=8)
        others = [j for j in range(len(self.joint_names)) if j not in self.map_joints]
        rest = f"; other joints at q0 ({', '.join(self.joint_names[j] for j in others)})" if others else ""
        ax.set_title(f"{self.platform_name}: fixed PX4 mixer vs the moving centre of gravity{rest}", fontsize=9)
        if path is not None:
            save_figure(fig, path, dpi=110)
        return fig


def _display(values: np.ndarray, kind: str) -> np.ndarray:
    return np.degrees(values) if kind == "revolute" else np.asarray(values)


def _request_rows(fully_actuated: bool) -> tuple[int, ...]:
    return (0, 1, 2, 3, 4, 5) if fully_actuated else (0, 1, 2, 5)


def _errors(platform: Platform, c0: np.ndarray, coms: np.ndarray, rows: Sequence[int]) -> tuple[np.ndarray, float]:
    """(N,) worst relative error over the requests ``rows`` at the centres of gravity ``coms`` (N, 3) of the mix
    exported with the centre of gravity at ``c0``; and the rotor span L [m] (see the module docstring)."""
    g0 = geometry_from_rotors(platform.rotors, c0, check=False)
    E0 = g0.effectiveness()
    U = g0.mix()[:, list(rows)]  # (n, R): the commands of each unit request
    span = max(math.hypot(*r.position_frd) for r in g0.rotors)
    w0 = E0 @ U  # (6, R) intended wrenches
    w0[0:3] /= span
    norm0 = np.linalg.norm(w0, axis=0)
    force = E0[3:6] @ U  # (3, R) the force each request produces (unchanged by the arm)
    dc = frd_from_body(coms - c0)  # (N, 3)
    err = np.linalg.norm(np.cross(dc[:, None, :], force.T[None, :, :]), axis=2) / span  # (N, R)
    rel = np.where(norm0 > 0, err / np.where(norm0 > 0, norm0, 1.0), 0.0)
    return rel.max(axis=1), span


def _best_pose(platform: Platform, Q: np.ndarray, coms: np.ndarray, rows, box, starts: np.ndarray) -> tuple[np.ndarray, float]:
    """The export pose with the smallest worst error over the configurations Q (centres of gravity ``coms``): the best
    of at most :data:`MAX_CANDIDATES` of them and ``starts``, refined by Nelder-Mead inside the joint ``box``."""
    pick = np.linspace(0, len(Q) - 1, min(MAX_CANDIDATES, len(Q))).round().astype(int)
    cands = np.vstack([starts, Q[pick]])
    c_cands = np.vstack([coms_body_at(platform, starts), coms[pick]])
    worst = np.array([_errors(platform, c, coms, rows)[0].max() for c in c_cands])
    b = int(np.argmin(worst))

    def cost(qa: np.ndarray) -> float:
        qa = np.clip(qa, box[0], box[1])
        return float(_errors(platform, coms_body_at(platform, qa[None, :])[0], coms, rows)[0].max())

    res = minimize(cost, cands[b], method="Nelder-Mead", bounds=list(zip(box[0], box[1])), options={"maxfev": 150, "xatol": 1e-4, "fatol": 1e-6})
    if res.fun < worst[b]:
        return np.clip(res.x, box[0], box[1]), float(res.fun)
    return cands[b].copy(), float(worst[b])


def map_joint_indices(platform: Platform, joints) -> tuple[int, ...]:
    """Indices of the map's joints: ``joints`` (names or indices, one or two), default the first two arm joints."""
    n = platform.n_arm
    if n == 0:
        raise InputError(f"platform {platform.name!r} has no arm: a fixed mixer's error comes from the arm moving the centre of gravity")
    if joints is None:
        return tuple(range(min(n, 2)))
    joints = (joints,) if isinstance(joints, (str, int)) else tuple(joints)
    if not 1 <= len(joints) <= 2:
        raise InputError(f"joints: give one or two arm joints for the map, got {list(joints)!r}")
    out = []
    for j in joints:
        if isinstance(j, str):
            if j not in platform.arm_names:
                raise InputError(f"joints: {j!r} is not an arm joint of {platform.name!r}; its joints: {', '.join(platform.arm_names)}")
            out.append(platform.arm_names.index(j))
        else:
            out.append(as_int(j, "joints", lo=0, hi=n - 1))
    if len(set(out)) != len(out):
        raise InputError(f"joints: the two map joints must differ, got {list(joints)!r}")
    return tuple(out)


def joint_box(platform: Platform) -> tuple[np.ndarray, np.ndarray]:
    """The arm's joint box (lower, upper); an unbounded revolute joint spans [-pi, pi], an unbounded slider is refused."""
    platform = check_platform(platform)
    lo, hi = platform.arm_lower.copy(), platform.arm_upper.copy()
    for k, j in enumerate(platform.arm):
        if not (math.isfinite(lo[k]) and math.isfinite(hi[k])):
            if j.kind != "revolute":
                raise InputError(f"arm joint {j.name!r} has no position limits: give them in the URDF to map the mixer error")
            lo[k], hi[k] = -math.pi, math.pi
    return lo, hi


def neutral_arm(platform: Platform) -> np.ndarray:
    """The arm joints of :meth:`~qprr.model.Platform.neutral_q` (n_arm,): the default export pose."""
    platform = check_platform(platform)
    return platform.neutral_q()[platform.nq - platform.n_arm :]


def arm_grid(platform: Platform, q0, joints: tuple[int, ...], resolution: int) -> tuple[np.ndarray, tuple[np.ndarray, ...], np.ndarray]:
    """(q0, axes, Q): the arm pose ``q0`` (default neutral, else checked against the limits), the ``resolution`` values
    of each of the map's ``joints`` (indices of :func:`map_joint_indices`) across :func:`joint_box`, and the arm
    configurations Q (resolution^len(joints), n_arm) of that grid, the other joints at q0 (the mixer map and
    ArduPilot's factor table)."""
    q0 = neutral_arm(platform) if q0 is None else platform.check_arm_limits(q0, "q0")
    lo, hi = joint_box(platform)
    axes = tuple(np.linspace(lo[j], hi[j], resolution) for j in joints)
    mesh = np.meshgrid(*axes, indexing="ij")
    Q = np.tile(q0, (mesh[0].size, 1))
    for k, j in enumerate(joints):
        Q[:, j] = mesh[k].ravel()
    return q0, axes, Q


def mixer_error(
    platform: Platform,
    q0=None,
    *,
    joints=None,
    resolution: int = DEFAULT_RESOLUTION,
    samples: int = DEFAULT_SAMPLES,
    seed: int = 0,
) -> MixerErrorResult:
    """The error of PX4's mix exported at the arm pose ``q0`` (default: neutral) over the arm's range, and the export
    pose that minimises the worst error (see the module docstring).

    ``joints``: the one or two arm joints of the map (names or indices; default the first two), gridded with
    ``resolution`` points each, the other joints at q0; arms with more joints are also sampled over their whole joint
    box (``samples`` configurations, seeded by ``seed``).  The best pose is searched among the map's points and the
    samples (at most :data:`MAX_CANDIDATES`, q0 and the neutral pose), each judged on every configuration, the best
    refined by Nelder-Mead."""
    platform = check_platform(platform)
    mj = map_joint_indices(platform, joints)
    resolution = as_int(resolution, "resolution", lo=2, hi=401)
    samples = as_int(samples, "samples", lo=0, hi=1_000_000)
    q0, axes, grid = arm_grid(platform, q0, mj, resolution)
    lo, hi = joint_box(platform)
    rng = np.random.default_rng(as_int(seed, "seed", lo=0))
    extra = rng.uniform(lo, hi, (samples if platform.n_arm > len(mj) else 0, platform.n_arm))
    Q = np.vstack([grid, extra])
    coms = coms_body_at(platform, np.vstack([Q, q0[None, :]]))
    coms, c0 = coms[:-1], coms[-1]
    rows = _request_rows(platform.fully_actuated)
    err, span = _errors(platform, c0, coms, rows)
    k = int(np.argmax(err))
    hover = float(np.linalg.norm(np.cross(coms[k] - c0, [0.0, 0.0, platform.total_mass * platform.g])))
    best_q0, best = _best_pose(platform, Q, coms, rows, (lo, hi), np.vstack([q0, neutral_arm(platform)]))
    return MixerErrorResult(
        platform.name,
        platform.arm_names,
        mj,
        tuple(platform.arm[j].kind for j in mj),
        np.array(q0, dtype=float),
        axes,
        err[: grid.shape[0]].reshape(tuple(a.size for a in axes)),
        tuple(AXES[r] for r in rows),
        float(err[k]),
        Q[k].copy(),
        hover,
        best_q0,
        best,
        float(span),
        len(Q),
    )
