"""Self-collision of a platform: the arm against the body, the propeller discs and itself (Pinocchio + coal).

:func:`collision_model` builds a :class:`CollisionModel` from the platform's URDF:

* the URDF's ``<collision>`` geometry, read by Pinocchio (``pin.buildGeomFromUrdfString``, meshes through coal;
  ``package://`` paths resolved in example-robot-data's share folder and in the folder of the URDF file);
* one disc per rotor whose ``name`` is not a URDF link carrying collision geometry of its own: a cylinder of
  :data:`DISC_THICKNESS` centred on the rotor, its axis the thrust axis, its radius the rotor's ``radius`` (the
  rotor file's ``radius`` key) or, when not given, :func:`default_disc_radius` (the largest common radius at which
  no two discs overlap).

Collision pairs: every two geometries on different bodies, except those on adjacent bodies (one joint the parent
of the other: they touch at the joint by construction) and those already in contact at the neutral configuration
(:meth:`qprr.model.Platform.neutral_q`: a contact the design accepts, e.g. a link resting in its housing).  The
excluded pairs are kept on the model (``adjacent``, ``neutral_contacts``) so that a report can list them.

The pairs are checked the most often colliding first (counted over a few random arm configurations), so that a
colliding configuration is found early.  Collisions do not depend on the base pose (every geometry moves with the vehicle), so the arm configuration
``q_arm`` decides: :meth:`CollisionModel.colliding_arm` evaluates a batch of them (``pin.computeCollisions``
per configuration, stopping at the first colliding pair).  Near contact a pair of two convex shapes is decided by
its signed distance, not by coal's collision test alone, which can miss a penetration (:data:`CONTACT_MARGIN`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError, MissingDependencyError, QprrError
from ..model import Platform, check_platform
from ..rotors import Rotor

DISC_THICKNESS = 0.01
"""Thickness [m] of the propeller disc cylinder qprr adds for a rotor (blades and their flapping, ~1 cm)."""

CONTACT_MARGIN = 0.01
"""[m] Pairs that coal's collision test finds closer than this are decided by their signed distance instead.

coal's GJK in collision mode can call two penetrating convex shapes apart: a 14 mm-radius arm link reaching up to
3.7 mm into a 4 mm-thick propeller disc of the Q-PRR was reported free, in 3 of 2e4 random arm configurations
checked each on its own (a volume sampling of the link confirms the penetration; tests/test_collision.py keeps
such cases).  Its answer "in collision" was never wrong.  So every pair within this margin (coal's
``security_margin``) is decided by ``pin.computeDistance`` (GJK run to convergence, then EPA): in contact when its
signed distance is < 0.  The answers then depend on the configuration alone, not on what was checked before."""


def default_disc_radius(rotors: Sequence[Rotor]) -> float:
    """The propeller radius [m] assumed for rotors whose ``radius`` is not given: the largest common radius at which
    no two discs overlap, half the smallest distance between two rotor centres measured in the plane normal to the
    first rotor's thrust axis (coaxial pairs, at distance 0 in that plane, are skipped: they share one disc).

    Raises :class:`~qprr.errors.InputError` when no pair of rotors is side by side (a single rotor, all coaxial):
    then give ``radius`` in the rotor file."""
    if isinstance(rotors, (str, bytes)) or not isinstance(rotors, Sequence) or not all(isinstance(r, Rotor) for r in rotors):
        raise InputError(f"rotors must be a sequence of qprr.rotors.Rotor (e.g. platform.rotors), got {rotors!r}")
    best = math.inf
    for a, b in itertools.combinations(rotors, 2):
        d = np.subtract(b.position_body, a.position_body)
        n = np.asarray(a.axis_body)
        planar = float(np.linalg.norm(d - (d @ n) * n))
        if planar > 1e-6:
            best = min(best, 0.5 * planar)
    if not math.isfinite(best):
        raise InputError(
            "no two rotors sit side by side, so no propeller radius can be derived from their spacing: give "
            "'radius' [m] for each rotor in the rotor file (or in its [defaults])"
        )
    return best


def _rotation_of_axis(axis) -> np.ndarray:
    """A rotation whose third column is the unit vector ``axis``."""
    z = np.asarray(axis, dtype=float)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _package_dirs(platform: Platform) -> list[str]:
    """Folders where ``package://`` mesh paths are looked up: example-robot-data's share folder, the URDF's folder."""
    from ..platforms import robots_dir

    dirs = []
    try:
        dirs.append(str(robots_dir().parent.parent))
    except QprrError:  # example-robot-data absent: a user's URDF may still name its meshes by path
        pass
    source = platform.provenance.get("model", "")
    if source and Path(source).is_file():
        dirs += [str(Path(source).resolve().parent), str(Path(source).resolve().parent.parent)]
    return dirs


@dataclass(frozen=True, eq=False)
class CollisionModel:
    """The collision geometry of a platform and the pairs checked (see the module docstring).

    ``geometry``: the ``pin.GeometryModel`` (its ``collisionPairs`` are the pairs checked); ``model``: the platform's
    Pinocchio model; ``pairs``, ``adjacent``, ``neutral_contacts``: (name, name) of the pairs checked, of those
    skipped because their bodies are adjacent, and of those skipped because they touch at the neutral configuration;
    ``discs``: (rotor name, radius [m], "rotor file" or "default") of every disc qprr added; ``screen``: the
    :class:`PairScreen` of these pairs (which pairs :meth:`colliding_batch` may skip).
    """

    platform_name: str
    model: pin.Model
    geometry: pin.GeometryModel
    neutral_q: np.ndarray
    pairs: tuple[tuple[str, str], ...]
    adjacent: tuple[tuple[str, str], ...]
    neutral_contacts: tuple[tuple[str, str], ...]
    discs: tuple[tuple[str, float, str], ...]
    screen: PairScreen

    def new_data(self) -> tuple[pin.Data, pin.GeometryData]:
        """Fresh (pin.Data, pin.GeometryData) for the calls below (one pair per thread; :data:`CONTACT_MARGIN` set)."""
        return self.model.createData(), margin_data(self.geometry)

    def _q(self, q) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape == (self.model.nq,):
            return q
        if q.shape == (self.model.nq - 7,):
            full = self.neutral_q.copy()
            full[7:] = q
            return full
        raise InputError(f"q must be a configuration ({self.model.nq},) or an arm configuration ({self.model.nq - 7},), got shape {q.shape}")

    def colliding(self, q, data: tuple | None = None) -> bool:
        """Whether configuration ``q`` (nq,) or arm configuration (n_arm,) puts some checked pair in contact
        (``data``: a pair from :meth:`new_data`)."""
        d, gd = self.new_data() if data is None else data
        return bool(contacts(self.model, self.geometry, (d, gd), self._q(q), first=True))

    def colliding_pairs(self, q, data: tuple | None = None) -> list[tuple[str, str]]:
        """The checked pairs in contact at ``q`` (every pair evaluated)."""
        d, gd = self.new_data() if data is None else data
        return [self.pairs[k] for k in contacts(self.model, self.geometry, (d, gd), self._q(q), first=False)]

    def min_distance(self, q, data: tuple | None = None) -> tuple[float, tuple[str, str]]:
        """(smallest distance [m] over the checked pairs (<= 0 in contact), the pair) at ``q``."""
        d, gd = self.new_data() if data is None else data
        pin.computeDistances(self.model, d, self.geometry, gd, self._q(q))
        dist = [r.min_distance for r in gd.distanceResults]
        k = int(np.argmin(dist))
        return float(dist[k]), self.pairs[k]

    def colliding_arm(self, q_arm, progress=None) -> np.ndarray:
        """(m,) bool: which rows of ``q_arm`` (m, n_arm) collide; ``progress(done, total)`` called every 4096 rows."""
        Q = np.atleast_2d(np.asarray(q_arm, dtype=float))
        if Q.ndim != 2 or Q.shape[1] != self.model.nq - 7:
            raise InputError(f"q_arm must be (m, {self.model.nq - 7}), got shape {Q.shape}")
        out = np.empty(Q.shape[0], dtype=bool)
        data = self.new_data()
        q = self.neutral_q.copy()
        for i in range(Q.shape[0]):
            q[7:] = Q[i]
            out[i] = bool(contacts(self.model, self.geometry, data, q, first=True))
            if progress is not None and (i + 1) % 4096 == 0:
                progress(i + 1, Q.shape[0])
        return out

    def colliding_batch(self, q_arm, screen: bool = True) -> np.ndarray:
        """:meth:`colliding_arm` without the progress callback, the same answers, faster: the pairs that
        :attr:`screen` proves farther than :data:`CONTACT_MARGIN` are skipped (a configuration with none left is
        free; ``screen=False``: no pair skipped, the reference), the others are screened in C++
        (``pin.computeCollisionsInParallel`` with one thread over a one-element ``pin.GeometryPool``, only those
        pairs active; configurations grouped by their set of pairs) and the configurations with a pair within the
        margin are decided pair by pair as :meth:`colliding` (:func:`decide`)."""
        Q = np.atleast_2d(np.asarray(q_arm, dtype=float))
        if Q.ndim != 2 or Q.shape[1] != self.model.nq - 7:
            raise InputError(f"q_arm must be (m, {self.model.nq - 7}), got shape {Q.shape}")
        if screen not in (True, False):
            raise InputError(f"screen must be True (skip the pairs proved far) or False (check every pair), got {screen!r}")
        if not np.all(np.isfinite(Q)):
            raise InputError(f"q_arm must be finite: rows {np.flatnonzero(~np.isfinite(Q).all(axis=1))[:5].tolist()} are not")
        out = np.zeros(Q.shape[0], dtype=bool)
        if screen:
            rows, near = self.screen.near_pairs(Q)
        else:
            rows, near = np.arange(Q.shape[0]), np.ones((Q.shape[0], len(self.pairs)), dtype=bool)
        if rows.size == 0 or not self.pairs:
            return out
        full = np.empty((self.model.nq, rows.size), order="F")
        full[:7] = self.neutral_q[:7, None]
        full[7:] = Q[rows].T
        pool = pin.GeometryPool(self.model, self.geometry, 1)
        gdata = set_margin(self.geometry, pool.getGeometryData(0))
        final = not any(r.security_margin > 0.0 for r in gdata.collisionRequests)  # no convex pair: coal decides
        data = self.new_data()
        rows_q = np.ascontiguousarray(full.T)  # row i: the configuration of rows[i], contiguous for Pinocchio
        packed = np.packbits(near, axis=1)
        keys = np.ascontiguousarray(packed).view(np.dtype((np.void, packed.shape[1]))).reshape(-1)
        _, first, group = np.unique(keys, return_index=True, return_inverse=True)
        order = np.argsort(group.reshape(-1), kind="stable")
        bounds = np.searchsorted(group.reshape(-1)[order], np.arange(first.size + 1))
        for s, row in enumerate(first):
            members = order[bounds[s] : bounds[s + 1]]
            active = np.flatnonzero(near[row])
            gdata.deactivateAllCollisionPairs()
            for k in active:
                gdata.activateCollisionPair(int(k))
            flagged = members[np.asarray(pin.computeCollisionsInParallel(1, pool, np.asfortranarray(full[:, members]), True), dtype=bool)]
            for i in flagged:
                out[rows[i]] = final or decide(self.model, self.geometry, data, rows_q[i], active)
        return out

    def summary(self) -> str:
        """The geometries, the pairs checked and the pairs excluded, in a few lines."""
        names = [g.name for g in self.geometry.geometryObjects]
        lines = [f"collision model of {self.platform_name}: {len(names)} geometries, {len(self.pairs)} pairs checked"]
        if self.discs:
            lines.append("  rotor discs added: " + ", ".join(f"{n} r = {r:.4g} m ({src})" for n, r, src in self.discs))
        lines.append(f"  pairs skipped as adjacent bodies: {len(self.adjacent)}")
        if self.neutral_contacts:
            lines.append("  pairs skipped as in contact at the neutral configuration: " + ", ".join(f"{a} / {b}" for a, b in self.neutral_contacts))
        return "\n".join(lines)


def collision_model(platform: Platform, *, package_dirs: Sequence[str] | None = None) -> CollisionModel:
    """The :class:`CollisionModel` of ``platform`` (see the module docstring).

    ``package_dirs``: folders for ``package://`` mesh paths (default: example-robot-data's share folder and the
    URDF file's folder).  Raises :class:`~qprr.errors.InputError` when the platform has no URDF text (made with
    :func:`qprr.model.from_model`) or its arm links carry no ``<collision>`` geometry (say what to add).
    """
    check_platform(platform)
    if platform.urdf is None:
        raise InputError(
            f"platform {platform.name!r} has no URDF (made with from_model): no collision geometry to read; "
            "build it with qprr.from_urdf from a URDF whose links have <collision> elements"
        )
    dirs = list(package_dirs) if package_dirs is not None else _package_dirs(platform)
    model = platform.model
    try:
        geom = pin.buildGeomFromUrdfString(model, platform.urdf, pin.GeometryType.COLLISION, package_dirs=dirs)
    except ValueError as exc:
        raise InputError(
            f"platform {platform.name!r}: Pinocchio could not read the URDF's collision geometry ({exc}); "
            f"mesh folders searched: {dirs} (package_dirs=...)"
        ) from exc
    on_arm = [g.name for g in geom.geometryObjects if g.parentJoint > 1]
    if not on_arm:
        raise InputError(
            f"platform {platform.name!r}: no arm link of its URDF has a <collision> element: add the links' "
            "shapes (qprr.urdf.writer writes them with every primitive visual)"
        )
    discs = _add_discs(platform, geom)
    pairs, adjacent, contacts = _select_pairs(platform, geom)
    screen = PairScreen(platform, geom)
    return CollisionModel(platform.name, model, geom, platform.neutral_q(), pairs, adjacent, contacts, discs, screen)


def _add_discs(platform: Platform, geom: pin.GeometryModel) -> tuple[tuple[str, float, str], ...]:
    """Add a disc cylinder for each rotor without collision geometry of its own in the URDF."""
    try:
        import coal
    except ImportError as exc:  # pragma: no cover - shipped with Pinocchio's wheels
        raise MissingDependencyError("coal", "the rotor discs of the collision model", "pip install pin") from exc
    model = platform.model
    with_geometry = {model.frames[g.parentFrame].name for g in geom.geometryObjects}
    missing = [r for r in platform.rotors if r.name not in with_geometry]
    fallback = default_disc_radius(platform.rotors) if any(r.radius is None for r in missing) else None
    out = []
    for r in missing:
        radius, source = (r.radius, "rotor file") if r.radius is not None else (fallback, "default")
        placement = pin.SE3(_rotation_of_axis(r.axis_body), np.array(r.position_body))
        obj = pin.GeometryObject(f"disc_{r.name}", 1, platform.base_frame, placement, coal.Cylinder(radius, DISC_THICKNESS))
        geom.addGeometryObject(obj)
        out.append((r.name, float(radius), source))
    return tuple(out)


def set_margin(geom: pin.GeometryModel, gdata: pin.GeometryData) -> pin.GeometryData:
    """``gdata`` (of ``geom``) with the collision request of every pair of two convex shapes asking for contact within
    :data:`CONTACT_MARGIN` (returned).  A pair with a triangle mesh keeps coal's exact test (margin 0): a mesh has
    no signed distance (its distance stays >= 0 through an intersection), and the mesh test is not GJK's."""
    import coal

    objs = geom.geometryObjects
    for cp, request in zip(geom.collisionPairs, gdata.collisionRequests):
        convex = isinstance(objs[cp.first].geometry, coal.ShapeBase) and isinstance(objs[cp.second].geometry, coal.ShapeBase)
        request.security_margin = CONTACT_MARGIN if convex else 0.0
    return gdata


def margin_data(geom: pin.GeometryModel) -> pin.GeometryData:
    """A fresh ``pin.GeometryData`` of ``geom`` for :func:`contacts` (:func:`set_margin`)."""
    return set_margin(geom, pin.GeometryData(geom))


def contacts(model: pin.Model, geom: pin.GeometryModel, data: tuple, q: np.ndarray, first: bool) -> list[int]:
    """Indices of the collision pairs of ``geom`` in contact at ``q`` (all of them, or the first found when ``first``).

    ``data``: (pin.Data, pin.GeometryData from :func:`margin_data`).  coal screens every pair (one pass, stopping at
    the first pair reported, when none is); a pair of convex shapes reported within :data:`CONTACT_MARGIN` is then in
    contact when its signed distance (``pin.computeDistance``) is < 0, a pair with a mesh when coal reports it."""
    d, gd = data
    if not pin.computeCollisions(model, d, geom, gd, q, True):
        return []
    # the pass stopped at the first pair reported (the pairs before it were found clear); the placements are set
    results = gd.collisionResults
    k0 = next(k for k, res in enumerate(results) if res.isCollision())
    out = []
    for k in range(k0, len(results)):
        if k > k0 and not pin.computeCollision(geom, gd, k):
            continue
        if _reported_in_contact(geom, gd, k):
            out.append(k)
            if first:
                break
    return out


def decide(model: pin.Model, geom: pin.GeometryModel, data: tuple, q: np.ndarray, pairs) -> bool:
    """Whether some pair of ``pairs`` (indices into ``geom.collisionPairs``) is in contact at ``q``, by the rule of
    :func:`contacts` (coal's test within the pair's security margin, then for two convex shapes the signed
    distance < 0): the same answer as ``bool(contacts(..., first=True))`` when the other pairs are farther apart
    than :data:`CONTACT_MARGIN` (:class:`PairScreen`)."""
    d, gd = data
    pin.updateGeometryPlacements(model, d, geom, gd, q)
    return any(pin.computeCollision(geom, gd, int(k)) and _reported_in_contact(geom, gd, int(k)) for k in pairs)


def _reported_in_contact(geom: pin.GeometryModel, gd: pin.GeometryData, k: int) -> bool:
    """Whether pair ``k``, which coal reported within its security margin, is in contact: a pair with a mesh (margin
    0) as coal says, a pair of two convex shapes when its signed distance is < 0 (:func:`set_margin`)."""
    return gd.collisionRequests[k].security_margin == 0.0 or pin.computeDistance(geom, gd, k).min_distance < 0.0


ORDER_SAMPLES = 256
"""Random arm configurations (seed 0) over which the pairs are counted to check the most often colliding first."""


def _order_pairs(platform: Platform, geom: pin.GeometryModel) -> None:
    """Reorder the pairs, the most often colliding over :data:`ORDER_SAMPLES` random arm configurations first, so
    that a colliding configuration is found after few pairs (``pin.computeCollisions`` stops at the first)."""
    model = platform.model
    lo, hi = np.maximum(platform.arm_lower, -math.pi), np.minimum(platform.arm_upper, math.pi)
    rng = np.random.default_rng(0)
    data = (model.createData(), margin_data(geom))
    counts = np.zeros(len(geom.collisionPairs))
    q = platform.neutral_q()
    for _ in range(ORDER_SAMPLES):
        q[7:] = rng.uniform(lo, hi)
        counts[contacts(model, geom, data, q, first=False)] += 1.0
    ordered = [geom.collisionPairs[int(k)] for k in np.argsort(-counts, kind="stable")]
    ordered = [pin.CollisionPair(cp.first, cp.second) for cp in ordered]
    geom.removeAllCollisionPairs()
    for cp in ordered:
        geom.addCollisionPair(cp)


def _select_pairs(platform: Platform, geom: pin.GeometryModel):
    """Add the pairs of geometries on different, non-adjacent bodies; drop those in contact at the neutral q."""
    model = platform.model
    objs = geom.geometryObjects
    adjacent = []
    for i, j in itertools.combinations(range(len(objs)), 2):
        ja, jb = objs[i].parentJoint, objs[j].parentJoint
        if ja == jb or ja == 0 or jb == 0:
            continue
        if model.parents[ja] == jb or model.parents[jb] == ja:
            adjacent.append((objs[i].name, objs[j].name))
            continue
        geom.addCollisionPair(pin.CollisionPair(i, j))
    all_pairs = list(geom.collisionPairs)
    touching = [all_pairs[k] for k in contacts(model, geom, (model.createData(), margin_data(geom)), platform.neutral_q(), first=False)]
    in_contact = tuple((objs[cp.first].name, objs[cp.second].name) for cp in touching)
    for cp in touching:
        geom.removeCollisionPair(cp)
    _order_pairs(platform, geom)
    pairs = tuple((objs[cp.first].name, objs[cp.second].name) for cp in geom.collisionPairs)
    return pairs, tuple(adjacent), in_contact


# ------------------------------------------------------------------------------ screening of far pairs
SCREEN_TOLERANCE = 1e-3
"""[m] A pair is skipped by :class:`PairScreen` only when its distance is proved larger than :data:`CONTACT_MARGIN`
plus this (rounding of the numpy kinematics and of coal's GJK, both far below it)."""

SCREEN_CELL = 0.04
"""[m] How far the geometries may move inside a cell of :class:`PairScreen`'s finest level (the slack its bound
gives away): smaller cells prove more pairs far and cost more cells."""


def _hull(obj: pin.GeometryObject) -> tuple[np.ndarray, float, np.ndarray, np.ndarray, np.ndarray]:
    """Enclosures of a geometry in its joint's frame: (segment ends (2, 3), radius) of a capsule containing it, and
    three slabs containing it: (normals (3, 3) as rows, centre (3,), half-thicknesses (3,); inf for no slab).  A
    cylinder's slab lies between its end caps, a box's slabs between its faces; a shape other than a sphere,
    cylinder, capsule or box is taken as its local AABB (a box; infinite for a plane: never skipped)."""
    import coal

    shape, M = obj.geometry, obj.placement
    R, t = np.array(M.rotation), np.array(M.translation)
    none = np.full(3, math.inf)
    if isinstance(shape, coal.Sphere):
        return np.array([t, t]), float(shape.radius), R.T, t, none
    if isinstance(shape, (coal.Cylinder, coal.Capsule)):
        h, axis = float(shape.halfLength), R[:, 2]
        half = np.array([math.inf, math.inf, h]) if isinstance(shape, coal.Cylinder) else none
        return np.array([t - h * axis, t + h * axis]), float(shape.radius), R.T, t, half
    if isinstance(shape, coal.Box):
        c, half = t, np.array(shape.halfSide, dtype=float)
    else:
        shape.computeLocalAABB()
        lo, hi = np.array(shape.aabb_local.min_), np.array(shape.aabb_local.max_)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            return np.array([t, t]), math.inf, R.T, t, none
        c, half = R @ (0.5 * (lo + hi)) + t, 0.5 * (hi - lo)
    k = int(np.argmax(half))  # the capsule along the box's longest side
    ends = np.array([c - half[k] * R[:, k], c + half[k] * R[:, k]])
    return ends, float(np.linalg.norm(np.delete(half, k))), R.T, c, half


def _segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """(K,) distances between the segments [p1, q1] and [p2, q2] (each (K, 3)): the closest points by clamped
    parameters (Ericson, Real-Time Collision Detection, 5.1.9); nearly parallel segments (sin^2 of the angle below
    1e-12) take s = 0 first, which overestimates the distance by less than 1e-6 times the segments' length."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e = np.einsum("ij,ij->i", d1, d1), np.einsum("ij,ij->i", d2, d2)
    b, c, f = np.einsum("ij,ij->i", d1, d2), np.einsum("ij,ij->i", d1, r), np.einsum("ij,ij->i", d2, r)
    point1, point2 = a <= 1e-18, e <= 1e-18
    a1, e1 = np.where(point1, 1.0, a), np.where(point2, 1.0, e)
    denom = a * e - b * b
    general = ~(point1 | point2) & (denom > 1e-12 * a * e)
    s = np.where(general, np.clip((b * f - c * e) / np.where(general, denom, 1.0), 0.0, 1.0), 0.0)
    s = np.where(point2 & ~point1, np.clip(-c / a1, 0.0, 1.0), s)
    t = np.where(point2, 0.0, (b * s + f) / e1)
    tc = np.clip(t, 0.0, 1.0)
    s = np.where((t != tc) & ~point1, np.clip((b * tc - c) / a1, 0.0, 1.0), s)
    x = r + s[:, None] * d1 - tc[:, None] * d2
    return np.sqrt(np.einsum("ij,ij->i", x, x))


class PairScreen:
    """Which collision pairs of a batch of arm configurations may be within :data:`CONTACT_MARGIN`: a conservative
    numpy bound, so that :meth:`CollisionModel.colliding_batch` asks coal about the others only.

    Each geometry is enclosed in a capsule and up to three slabs (a cylinder's between its end caps, a box's or a
    mesh's AABB's between opposite faces): the distance of a pair is at least that of the capsules, and at least the
    gap between one's slab and the other's capsule.  The bound is evaluated at the centres of cells of joint space:
    moving joint j by dq_j moves a point x of a geometry by at most |x - o_j| |dq_j| (revolute, o_j on its axis) or
    |dq_j| (prismatic), and
    |x - o_j| is at most the lengths of the joint offsets down to the geometry, the prismatic strokes among them and
    the geometry's extent in its joint frame (a lever per pair and joint, joints that move both geometries not
    counted).  So over a cell of half-widths w_j the distance falls by at most sum_j lever_j w_j from the centre's.
    Cells come in levels (each half the size of the one above, the finest moving a geometry by about
    :data:`SCREEN_CELL`); a cell whose pairs are all proved farther than :data:`CONTACT_MARGIN` plus
    :data:`SCREEN_TOLERANCE` settles its configurations (free), the others go down a level with their near pairs.
    """

    def __init__(self, platform: Platform, geom: pin.GeometryModel) -> None:
        from .chain import ArmChain

        self.chain = ArmChain(platform)
        objs = geom.geometryObjects
        hulls = [_hull(o) for o in objs]
        self.joint = np.array([int(o.parentJoint) for o in objs])
        self.ends = np.array([h[0] for h in hulls])
        self.radius = np.array([h[1] for h in hulls])
        self.slab_half = np.array([h[4] for h in hulls])  # (G, 3)
        normals, centres = np.array([h[2] for h in hulls]), np.array([h[3] for h in hulls])
        self.first = np.array([int(cp.first) for cp in geom.collisionPairs], dtype=np.int64)
        self.second = np.array([int(cp.second) for cp in geom.collisionPairs], dtype=np.int64)
        self.unbounded = ~np.isfinite(self.radius[self.first] + self.radius[self.second])
        self.local = np.concatenate([self.ends, centres[:, None], normals], axis=1)  # (G, 6, 3): ends, centre, normals
        self.by_joint = [(int(j), np.flatnonzero(self.joint == j)) for j in np.unique(self.joint)]
        self.prismatic = np.array([j.kind == "prismatic" for j in platform.arm])
        self.lever0, self.lever_q = self._levers(platform.model, [j.joint_id for j in platform.arm])

    def _levers(self, model: pin.Model, arm_ids: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """(P, n_arm) constant part and (P, n_arm, n_arm) part per unit |q_i| of prismatic joint i of the levers."""
        extent = np.linalg.norm(self.ends, axis=2).max(axis=1) + np.where(np.isfinite(self.radius), self.radius, 0.0)
        column = {jid: k for k, jid in enumerate(arm_ids)}
        n_pairs, n = len(self.first), len(arm_ids)
        lever0, lever_q = np.zeros((n_pairs, n)), np.zeros((n_pairs, n, n))

        def ancestors(j: int) -> list[int]:  # j and the joints above it, deepest first (the universe, 0, left out)
            return [int(a) for a in reversed(model.supports[j]) if a > 0]

        for p in range(n_pairs):
            chains = [ancestors(int(self.joint[g])) for g in (self.first[p], self.second[p])]
            common = next(j for j in chains[0] if j in chains[1])
            for g, chain in zip((self.first[p], self.second[p]), chains):
                below = chain[: chain.index(common)]  # the joints that move g relative to the other, deepest first
                for i, j in enumerate(below):
                    k = column[j]
                    if self.prismatic[k]:
                        lever0[p, k] += 1.0
                        continue
                    lever0[p, k] += extent[g] + sum(float(np.linalg.norm(model.jointPlacements[jj].translation)) for jj in below[:i])
                    for jj in below[:i]:
                        lever_q[p, k, column[jj]] += 1.0 if self.prismatic[column[jj]] else 0.0
        return lever0, lever_q

    def _world(self, C: np.ndarray) -> np.ndarray:
        """(n, G, 6, 3): at arm configurations ``C`` (n, n_arm), per geometry its capsule's two ends, its slabs'
        centre and their three normals, in B (the rotation entries of :meth:`qprr.analysis.ArmChain.pose` that are
        exact zeros are skipped)."""
        pose = self.chain.pose(C)
        n = C.shape[0]
        out = np.empty((n, len(self.joint), 6, 3))
        translate = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])  # the normals are directions
        for j, g in self.by_joint:
            X = self.local[g]  # (k, 6, 3)
            coords = []
            for a in range(3):
                acc = np.multiply.outer(np.broadcast_to(pose.p[j][a], (n,)), translate)[:, None, :]
                for b in range(3):
                    e = pose.R[j][a][b]
                    if not isinstance(e, float):
                        acc = acc + e[:, None, None] * X[None, :, :, b]
                    elif e != 0.0:
                        acc = acc + e * X[None, :, :, b]
                coords.append(np.broadcast_to(acc, (n, g.size, 6)))
            out[:, g] = np.stack(coords, axis=-1)
        return out

    def lower_bounds(self, C: np.ndarray, cells: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """(K,) lower bounds [m] of the distance of pair ``pairs[k]`` at configuration ``C[cells[k]]``: the larger of
        the capsules' distance and the gaps between one's slabs and the other's capsule (-inf for a pair with an
        unbounded shape)."""
        world = self._world(C)
        a, b = self.first[pairs], self.second[pairs]
        wa, wb = world[cells, a], world[cells, b]  # (K, 6, 3)
        with np.errstate(invalid="ignore"):
            bound = _segment_distance(wa[:, 0], wa[:, 1], wb[:, 0], wb[:, 1]) - self.radius[a] - self.radius[b]
            for x, wx, wy, y in ((a, wa, wb, b), (b, wb, wa, a)):
                h1 = np.einsum("ka,ksa->ks", wy[:, 0] - wx[:, 2], wx[:, 3:])  # (K, 3): the capsule's ends over the slabs
                h2 = np.einsum("ka,ksa->ks", wy[:, 1] - wx[:, 2], wx[:, 3:])
                gap = np.where(h1 * h2 > 0.0, np.minimum(np.abs(h1), np.abs(h2)), 0.0) - self.slab_half[x]
                bound = np.maximum(bound, gap.max(axis=1) - self.radius[y])
        return np.where(self.unbounded[pairs], -math.inf, bound)

    def _cells(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, np.ndarray]:
        """(lowest q (n_arm,), finest cell widths (n_arm,), cell indices of Q (m, n_arm), number of levels above the
        finest, (P, n_arm) levers over the cells) of the batch ``Q``."""
        lo, hi = Q.min(axis=0), Q.max(axis=0)
        span = hi - lo
        moving = span > 0.0
        lever = self.lever0 + self.lever_q @ np.maximum(np.abs(lo), np.abs(hi))
        reach = lever.max(axis=0, initial=0.0) * max(int(moving.sum()), 1)
        width = np.where(moving, np.minimum(span, 2.0 * SCREEN_CELL / np.where(reach > 0.0, reach, 1.0)), 0.0)
        width = np.where(moving & (reach == 0.0), span, width)
        index = np.zeros(Q.shape, dtype=np.int64)
        index[:, moving] = np.floor((Q[:, moving] - lo[moving]) / width[moving]).astype(np.int64)
        top = int(index.max(initial=0)).bit_length()
        lever = self.lever0 + self.lever_q @ (np.maximum(np.abs(lo), np.abs(hi)) + 2.0**top * width)  # cells overhang Q
        return lo, width, index, top, lever

    def near_pairs(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rows (k,), near (k, P) bool): the rows of the arm configurations ``Q`` (m, n_arm) where some pair is not
        proved farther apart than :data:`CONTACT_MARGIN`, and those pairs; no pair is in contact at the other rows.
        The descent stops at a level whose cells would hold fewer than two configurations each on average (an arm
        of many joints on a small batch): the near pairs are then those of the level above."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        if Q.ndim != 2 or Q.shape[1] != self.chain.n_arm or not np.all(np.isfinite(Q)):
            raise InputError(f"Q must be a finite (m, {self.chain.n_arm}) array of arm configurations, got shape {Q.shape}")
        n_pairs = len(self.first)
        if Q.shape[0] == 0 or n_pairs == 0:
            return np.zeros(0, dtype=np.int64), np.zeros((0, n_pairs), dtype=bool)
        lo, width, index, top, lever = self._cells(Q)
        todo, parent, near = np.arange(Q.shape[0]), np.zeros(Q.shape[0], dtype=np.int64), np.ones((1, n_pairs), dtype=bool)
        for level in range(top, -1, -1):
            key = index[todo] >> level
            _, first, inv = np.unique(_cell_ids(key, (index.max(axis=0) >> level) + 1), return_index=True, return_inverse=True)
            inv = inv.reshape(-1)
            if 2 * first.size > todo.size:  # cells of one configuration or two: the bound costs as much as coal
                break
            centre = lo + (key[first] + 0.5) * (width * 2.0**level)
            slack = lever @ (width * 2.0 ** (level - 1))
            active = near[parent[first]]
            cells, pairs = np.nonzero(active)
            bound = self.lower_bounds(centre, cells, pairs) - slack[pairs]
            near = np.zeros_like(active)
            near[cells, pairs] = bound <= CONTACT_MARGIN + SCREEN_TOLERANCE
            keep = near.any(axis=1)[inv]
            todo, parent = todo[keep], inv[keep]
        return todo, near[parent]


def _cell_ids(key: np.ndarray, dims: np.ndarray) -> np.ndarray:
    """One integer per row of the cell indices ``key`` (m, n), equal for equal rows: the flat index in a grid of
    ``dims`` cells per axis when that grid's size fits in int64, else the rank of the row among the distinct rows
    (an arm of many joints: 8 revolute joints exceed 2^63 cells at the finest level)."""
    if float(np.prod(dims.astype(float))) < 2.0**62:
        return np.ravel_multi_index(tuple(key.T), tuple(dims))
    return np.unique(key, axis=0, return_inverse=True)[1].reshape(-1)
