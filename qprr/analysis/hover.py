"""Hover feasibility and thrust margin over the arm's configuration space and a payload-mass range.

At each arm configuration (base level, at rest, a point payload m at the end effector) the
rotors must produce the base wrench w(m) = w_0 + m w_1 (the base rows of Pinocchio's
generalised gravity; :class:`qprr.analysis.chain.Statics`) and the arm joints the efforts
tau(m) = tau_0 + m tau_1.  With the wrench set Z of the rotors
(:mod:`qprr.analysis.wrenchset`) every question is exact:

* **hover-feasible**: w(m) in Z (an allocation within [f_min, f_max] exists) and
  |tau(m)| <= the effort limits;
* **thrusts**: the allocation :class:`qprr.actuation.Allocator` makes when it is exact (the
  minimum-norm one, f = Omega_P^+ w; unique for four coplanar rotors and for six tilted ones)
  and each rotor's margin to f_min and f_max;
* **thrust margin**: the largest s such that *some* allocation keeps every thrust in
  [f_min + s, f_max - s] (:meth:`WrenchSet.thrust_margin`; for a square rotor matrix, the
  allocation's own smallest margin);
* **attitude authority left**: the largest roll, pitch and yaw torque [N m] (and, for a fully
  actuated platform, the largest force along x, y, z of B) still producible on top of w(m),
  each in the weaker of its two directions;
* **payload envelope**: the largest m each configuration can hold, min of the rotor limit
  (the ray from w_0 along w_1 leaving Z) and the effort limit (each joint affine in m).

With a collision model (:mod:`qprr.analysis.collision`) the configurations where the arm hits the body, a
propeller disc or itself are flagged (``collision_free``) and every fraction is reported twice:
over all configurations and over the collision-free ones (``feasible_free_fraction``).

Thesis Sec. 6.4.1.1 states the capacity question ("the payload depends on the thrust if the
mission is transport, on the joint torques if it is manipulation"); none of the thesis's
anchors maps it.  Maps here are over configurations; :mod:`qprr.analysis.capacity` projects
them onto the workspace.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from ..actuation import Allocator
from ..errors import InputError
from ..model import Platform
from ..validation import as_vector
from ._common import (
    JointGrid,
    MapStatus,
    check_arm_platform,
    check_int,
    check_locked,
    check_masses,
    check_progress,
    collision_mask,
    fraction_error,
    make_grid,
    make_payload_mount,
    resolve_collision,
)
from .budget import SampleChoice, check_budget, check_clock, grid_work, within_budget
from .chain import ArmChain, Statics
from .wrenchset import WrenchSet, wrench_set


@dataclass(frozen=True)
class PayloadLimits:
    """Largest payload [kg] per configuration, by limit (n,) each.

    ``rotors``: the rotors can hold the wrench (with ``torque_reserve`` left about every axis);
    ``effort``: every arm joint within its effort limit, ``effort_joint`` the index of the joint
    that binds first (-1 if none), ``effort_per_joint`` (n, n_arm) the limit of each joint
    (:func:`effort_payload_limits`); ``collective``: the collective-thrust limit
    F_max / g - m_platform (a scalar: the transport mission of Thesis Sec. 6.4.1.1).  A value
    < 0 means even the empty platform breaks that limit there (-inf: w_0 cannot be produced
    at all).  :func:`qprr.payload.payload_capacity` reads its numbers from here.
    """

    rotors: np.ndarray
    effort: np.ndarray
    effort_joint: np.ndarray
    collective: float
    effort_per_joint: np.ndarray | None = None

    @property
    def total(self) -> np.ndarray:
        return np.minimum(self.rotors, self.effort)


def check_reserve(torque_reserve) -> np.ndarray:
    """``torque_reserve`` as three torques [N m] >= 0 about x, y, z of B (a scalar applies to all three)."""
    try:
        r = np.broadcast_to(np.asarray(torque_reserve, dtype=float), (3,)).copy()
    except (TypeError, ValueError) as exc:
        raise InputError(f"torque_reserve must be one torque or three (roll, pitch, yaw) in N m, got {torque_reserve!r}") from exc
    if not np.all(np.isfinite(r)) or np.any(r < 0.0):
        raise InputError(f"torque_reserve must be finite and >= 0 N m, got {torque_reserve!r}")
    return r


def payload_limits(st: Statics, W: WrenchSet, effort_limits: np.ndarray, g: float, torque_reserve=0.0) -> PayloadLimits:
    """Per configuration, the payload limits of :class:`PayloadLimits` from the affine statics ``st``."""
    reserve = check_reserve(torque_reserve)
    Wr = W.shrunk(reserve) if np.any(reserve > 0.0) else W
    lo, hi = Wr.ray(st.wrench0, st.wrench1)
    inside = Wr.contains(st.wrench0)
    rot = np.where(inside & (lo <= hi), hi, -np.inf)
    lim = effort_payload_limits(st.tau_arm0, st.tau_arm1, effort_limits)
    eff = lim.min(axis=1) if lim.shape[1] else np.full(lim.shape[0], np.inf)
    joint = np.where(eff < np.inf, lim.argmin(axis=1), -1) if lim.shape[1] else np.full(lim.shape[0], -1)
    collective = Wr.force_max() / g - st.mass
    return PayloadLimits(rot, eff, joint, float(collective), lim)


def effort_payload_limits(tau0: np.ndarray, tau1: np.ndarray, effort_limits) -> np.ndarray:
    """Largest payload m >= 0 [kg] each arm joint holds, |tau0 + m tau1| <= L (n, n_arm) [kg].

    Holding efforts are affine in m (:class:`~qprr.analysis.chain.Statics`), so the bound is
    (L - tau0 sgn(tau1)) / |tau1|; +inf where the payload does not load the joint and it holds,
    -inf where even the empty arm exceeds L.
    """
    a, b = tau0, tau1
    L = np.broadcast_to(effort_limits, a.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        lim = np.where(np.abs(b) > 1e-15, (L - a * np.sign(b)) / np.abs(b), np.where(np.abs(a) <= L, np.inf, -np.inf))
    return np.where(np.abs(a) > L * (1 + 1e-12), -np.inf, lim)


@dataclass(frozen=True)
class HoverResult:
    """Hover feasibility over the joint ``grid`` for each payload mass (see the module docstring).

    Per configuration (n = grid.size): ``ee_body`` (n, 3) [m]; for ``masses[0]``: ``thrusts``
    (n, n_rotors) [N] of the exact allocation and ``rotor_margin`` (n, n_rotors) [N] (min of
    f - f_min and f_max - f; negative = out of bounds), ``tau_arm`` (n, n_arm).  Per mass and
    configuration: ``thrust_margin`` (n_m, n) [N], ``authority`` (n_m, n, 3) [N m] about x, y, z
    of B (``force_authority`` (n_m, n, 3) [N] for fully actuated platforms, else None),
    ``rotor_ok``, ``effort_ok``, ``feasible`` (n_m, n).  ``payload``: :class:`PayloadLimits`
    (the envelope).  ``feasible_fraction`` (n_m,) of the configurations; ``min_thrust_margin``
    (n_m,) [N] over every configuration and ``worst_q`` (n_m, n_arm) where it occurs.
    ``collision_free`` (n,) bool (None: collisions not checked); ``collision_note``: why not, or how the mask was
    obtained (:meth:`qprr.analysis._common.CollisionMask.describe`);
    ``feasible_free_fraction`` (n_m,): the configurations both collision-free and hover-feasible, as a fraction
    of all configurations (None without a collision check).
    """

    platform_name: str
    grid: JointGrid
    masses: np.ndarray
    ee_body: np.ndarray
    thrusts: np.ndarray
    rotor_margin: np.ndarray
    tau_arm: np.ndarray
    thrust_margin: np.ndarray
    authority: np.ndarray
    force_authority: np.ndarray | None
    rotor_ok: np.ndarray
    effort_ok: np.ndarray
    feasible: np.ndarray
    payload: PayloadLimits
    wrench_set: WrenchSet
    hover_wrench: np.ndarray
    feasible_fraction: np.ndarray
    min_thrust_margin: np.ndarray
    worst_q: np.ndarray
    status: MapStatus
    reason: str
    collision_free: np.ndarray | None = None
    feasible_free_fraction: np.ndarray | None = None
    collision_note: str = ""
    sampling: SampleChoice | None = None

    def summary(self) -> str:
        lines = [
            f"hover feasibility of {self.platform_name}: {self.grid.size} arm configurations, wrench set of rank "
            f"{self.wrench_set.rank} ({self.wrench_set.normals.shape[0]} facets)"
        ]
        for k, m in enumerate(self.masses):
            err = 100 * fraction_error(self.feasible[k], self.grid.shape)
            lines.append(
                f"  payload {m:g} kg: hover-feasible at {100 * self.feasible_fraction[k]:.2f} +- {err:.2g}% of the configurations "
                f"(rotors {100 * self.rotor_ok[k].mean():.2f}%, efforts {100 * self.effort_ok[k].mean():.2f}%); "
                f"min thrust margin {self.min_thrust_margin[k]:.4g} N at q_arm = {np.round(self.worst_q[k], 4).tolist()}; "
                f"min roll/pitch/yaw authority {np.round(self.authority[k].min(axis=0), 4).tolist()} N m"
            )
            if self.collision_free is not None:
                lines.append(
                    f"    collision-free and hover-feasible: {100 * self.feasible_free_fraction[k]:.2f}% of the "
                    f"configurations ({100 * self.collision_free.mean():.2f}% are collision-free)"
                )
        if self.collision_note:
            lines.append(f"  {self.collision_note}")
        pl = self.payload.total
        ok = np.isfinite(pl)
        lines.append(
            f"  payload envelope (zero reserve): {np.nanmax(np.where(ok, pl, np.nan)):.4g} kg at best, "
            f"{np.nanmin(np.where(ok, pl, np.nan)):.4g} kg at worst; collective-thrust limit {self.payload.collective:.4g} kg"
        )
        lines.append("  error bars: |share on the grid - share on the grid with twice the step|")
        if self.reason:
            lines.append(f"  status {self.status.value}: {self.reason}")
        if self.sampling is not None:
            lines.append(f"  {self.sampling.describe()}")
        return "\n".join(lines)


@dataclass(frozen=True)
class HoverOptions:
    """Settings of :func:`hover` (each can also be given to it as a keyword); see its parameters."""

    n_samples: int = 100_000
    payload_masses: object = (0.0,)
    payload_offset: object = (0.0, 0.0, 0.0)
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    torque_reserve: object = 0.0
    collision: bool | None = None
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings are checked however the options are built
        object.__setattr__(self, "n_samples", check_int("n_samples", self.n_samples, 2))
        object.__setattr__(self, "budget", check_budget(self.budget))
        check_clock(self.clock)
        object.__setattr__(self, "payload_masses", tuple(float(m) for m in check_masses(self.payload_masses)))
        object.__setattr__(self, "payload_offset", tuple(float(x) for x in as_vector(self.payload_offset, 3, "payload_offset")))
        check_reserve(self.torque_reserve)
        if self.collision is not None and not isinstance(self.collision, (bool, np.bool_)):
            raise InputError(f"collision must be None (when a collision model exists), True or False, got {self.collision!r}")


def hover(platform: Platform, options: HoverOptions | None = None, *, progress=None, **settings) -> HoverResult:
    """Hover feasibility, thrusts, margins and attitude authority over the arm's joint grid.

    ``options``: :class:`HoverOptions`, and/or its fields as keywords (``hover(p, n_samples=2000)``; an unknown
    keyword is a TypeError).

    Parameters
    ----------
    platform : any platform whose rotors have finite thrust bounds.
    n_samples : joint-grid size (balanced grid).
    payload_masses : payload masses [kg] (>= 0), a point mass at ``payload_offset`` [m] in the
        end-effector frame.
    locked, ranges : joints held fixed / narrower ranges (as in :func:`qprr.analysis.workspace`).
    torque_reserve : torque [N m] to keep available about x, y, z of B in the payload envelope
        (one value or three; 0: the rotors may saturate exactly).
    progress : None, True (stderr) or a callable (fraction, message).
    collision : flag the self-colliding configurations (None: when the platform has a collision model,
        :func:`qprr.analysis._common.resolve_collision`; True: required; False: off).
    budget, clock : wall time [s] the map may take: ``n_samples`` is then chosen from pilot runs timed with
        ``clock`` (default :func:`time.perf_counter`), :mod:`qprr.analysis.budget`; None: ``n_samples`` is used.
    """
    o = replace(options or HoverOptions(), **settings) if settings else (options or HoverOptions())
    if not isinstance(o, HoverOptions):
        raise InputError(f"options must be a HoverOptions, got {type(o).__name__}")
    check_arm_platform(platform)
    work = grid_work(platform, [check_locked(platform, o.locked)], o.ranges)
    collisions = resolve_collision(platform, o.collision)  # built once, not per pilot (seconds for a 5-joint arm)
    return within_budget(o, lambda oo, pr: _hover(platform, oo, collisions, pr), work, check_progress(progress))


def _hover(platform: Platform, o: HoverOptions, collisions: tuple, progress) -> HoverResult:
    """:func:`hover` at ``o.n_samples``; ``collisions``: (collision model or None, note) of
    :func:`qprr.analysis._common.resolve_collision`."""
    cmodel, note = collisions
    setup = _Setup(
        platform,
        np.array(o.payload_masses),
        wrench_set(platform),
        Allocator(platform),
        ArmChain(platform),
        make_payload_mount(platform, o.payload_offset),
        np.array(platform.arm_effort_limits),
        check_reserve(o.torque_reserve),
    )
    grid = make_grid(platform, o.n_samples, o.locked, o.ranges)
    n, masses, W = grid.size, setup.masses, setup.W
    arr = _Arrays.empty(n, len(masses), platform.n_rotors, platform.n_arm, W.rank == 6)
    for start, q in grid.chunks():
        _fill(setup, arr, start, q)
        if progress:
            progress((start + len(q)) / n, "hover map")
    rmargin = np.minimum(arr.thrusts - W.thrust_min, W.thrust_max - arr.thrusts)
    feasible = arr.rot_ok & arr.eff_ok
    worst = arr.margin.argmin(axis=1)
    status, reason = MapStatus.OK, ""
    if not feasible.any():
        status, reason = MapStatus.EMPTY, "no configuration hovers at any payload mass asked"
    limits = PayloadLimits(arr.lim_rot, arr.lim_eff, arr.lim_joint, float(arr.collective), arr.lim_per)
    result = HoverResult(
        platform.name,
        grid,
        masses,
        arr.ee,
        arr.thrusts,
        rmargin,
        arr.tau_arm,
        arr.margin,
        arr.auth,
        arr.fauth,
        arr.rot_ok,
        arr.eff_ok,
        feasible,
        limits,
        W,
        arr.w_hover,
        feasible.mean(axis=1),
        arr.margin[np.arange(len(masses)), worst],
        grid.configurations(0, n)[worst],
        status,
        reason,
        collision_note=note,
    )
    return _with_collisions(result, cmodel, progress)


@dataclass(frozen=True)
class _Setup:
    """What every chunk of the hover map uses: the platform, payload masses [kg], rotor wrench set, allocator, arm
    chain, payload point, joint effort limits and the torque reserve."""

    platform: Platform
    masses: np.ndarray
    W: WrenchSet
    alloc: Allocator
    chain: ArmChain
    payload: object
    eff_lim: np.ndarray
    torque_reserve: object


@dataclass
class _Arrays:
    """The hover map's per-configuration arrays (filled chunk by chunk, :func:`_fill`)."""

    ee: np.ndarray
    thrusts: np.ndarray
    tau_arm: np.ndarray
    margin: np.ndarray
    auth: np.ndarray
    fauth: np.ndarray | None
    rot_ok: np.ndarray
    eff_ok: np.ndarray
    w_hover: np.ndarray
    lim_rot: np.ndarray
    lim_eff: np.ndarray
    lim_joint: np.ndarray
    lim_per: np.ndarray
    collective: float | None = None

    @classmethod
    def empty(cls, n: int, nm: int, nr: int, na: int, full: bool) -> _Arrays:
        """Arrays for n configurations, nm payload masses, nr rotors, na arm joints (``full``: force authority too)."""
        return cls(
            np.empty((n, 3)),
            np.empty((n, nr)),
            np.empty((n, na)),
            np.empty((nm, n)),
            np.empty((nm, n, 3)),
            np.empty((nm, n, 3)) if full else None,
            np.empty((nm, n), dtype=bool),
            np.empty((nm, n), dtype=bool),
            np.empty((n, 6)),
            np.empty(n),
            np.empty(n),
            np.empty(n, dtype=np.int64),
            np.empty((n, na)),
        )


def _fill(setup: _Setup, arr: _Arrays, start: int, q: np.ndarray) -> None:
    """The hover map's values at the configurations ``q`` (rows ``start`` onwards)."""
    platform, masses, W, alloc = setup.platform, setup.masses, setup.W, setup.alloc
    sl = slice(start, start + len(q))
    pose = setup.chain.pose(q)
    st = setup.chain.statics(pose, setup.payload.frame, setup.payload.offset_frame)
    arr.ee[sl] = setup.chain.frame_position(pose, platform.ee_frame)
    w0 = st.wrench(masses[0])
    arr.w_hover[sl] = w0
    arr.thrusts[sl] = w0[:, alloc.rows] @ alloc.Omega_P_inv.T
    arr.tau_arm[sl] = st.tau_arm(masses[0])
    for k, m in enumerate(masses):
        w = st.wrench(m)
        arr.rot_ok[k, sl] = W.contains(w)
        arr.eff_ok[k, sl] = np.all(np.abs(st.tau_arm(m)) <= setup.eff_lim * (1 + 1e-12), axis=1)
        arr.margin[k, sl] = W.thrust_margin(w) if W.equal_bounds else np.where(arr.rot_ok[k, sl], _alloc_margin(w, alloc, W), -np.inf)
        arr.auth[k, sl] = W.authority(w, (3, 4, 5)).min(axis=2)
        if arr.fauth is not None:
            arr.fauth[k, sl] = W.authority(w, (0, 1, 2)).min(axis=2)
    pl = payload_limits(st, W, setup.eff_lim, platform.g, setup.torque_reserve)
    arr.lim_rot[sl], arr.lim_eff[sl], arr.lim_joint[sl], arr.lim_per[sl] = pl.rotors, pl.effort, pl.effort_joint, pl.effort_per_joint
    arr.collective = pl.collective


def _with_collisions(result: HoverResult, cmodel, progress) -> HoverResult:
    """``result`` with its collision-free mask and fractions (unchanged when ``cmodel`` is None)."""
    if cmodel is None:
        return result
    mask = collision_mask(cmodel, result.grid, progress, "hover map: collisions")
    return replace(
        result,
        collision_free=mask.free,
        feasible_free_fraction=(result.feasible & mask.free).mean(axis=1),
        collision_note=f"collision check: {mask.describe()}",
    )


def _alloc_margin(w: np.ndarray, alloc: Allocator, W: WrenchSet) -> np.ndarray:
    """Smallest rotor margin of the Allocator's answer (rotor sets with unequal bounds)."""
    out = np.empty(w.shape[0])
    tau = np.zeros(alloc.platform.nv)
    for i in range(w.shape[0]):
        tau[0:6] = w[i]
        f = alloc.allocate(tau).f[: alloc.n_rotors]
        out[i] = np.min(np.minimum(f - W.thrust_min, W.thrust_max - f))
    return out
