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

from .errors import InputError, MissingDependencyError, QprrError
from .model import Platform, check_platform
from .rotors import Rotor

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
        raise InputError(f"rotors must be a sequence of qprr.Rotor (e.g. platform.rotors), got {rotors!r}")
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
    from .platforms import robots_dir

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
    ``discs``: (rotor name, radius [m], "rotor file" or "default") of every disc qprr added.
    """

    platform_name: str
    model: pin.Model
    geometry: pin.GeometryModel
    neutral_q: np.ndarray
    pairs: tuple[tuple[str, str], ...]
    adjacent: tuple[tuple[str, str], ...]
    neutral_contacts: tuple[tuple[str, str], ...]
    discs: tuple[tuple[str, float, str], ...]

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

    def colliding_batch(self, q_arm) -> np.ndarray:
        """:meth:`colliding_arm` without the progress callback, the same answers: the screening loop in C++ (which
        configurations have some pair within :data:`CONTACT_MARGIN`: ``pin.computeCollisionsInParallel`` with one
        thread over a one-element ``pin.GeometryPool``), then those few decided pair by pair as :meth:`colliding`."""
        Q = np.atleast_2d(np.asarray(q_arm, dtype=float))
        if Q.ndim != 2 or Q.shape[1] != self.model.nq - 7:
            raise InputError(f"q_arm must be (m, {self.model.nq - 7}), got shape {Q.shape}")
        full = np.empty((self.model.nq, Q.shape[0]), order="F")
        full[:7] = self.neutral_q[:7, None]
        full[7:] = Q.T
        pool = pin.GeometryPool(self.model, self.geometry, 1)
        set_margin(self.geometry, pool.getGeometryData(0))
        near = np.asarray(pin.computeCollisionsInParallel(1, pool, full, True), dtype=bool)
        if not any(r.security_margin > 0.0 for r in pool.getGeometryData(0).collisionRequests):
            return near  # no pair of two convex shapes: coal's answers are final
        data = self.new_data()
        out = np.zeros(Q.shape[0], dtype=bool)
        for i in np.flatnonzero(near):
            out[i] = bool(contacts(self.model, self.geometry, data, np.ascontiguousarray(full[:, i]), first=True))
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
            "shapes (qprr.urdfgen writes them with every primitive visual)"
        )
    discs = _add_discs(platform, geom)
    pairs, adjacent, contacts = _select_pairs(platform, geom)
    return CollisionModel(platform.name, model, geom, platform.neutral_q(), pairs, adjacent, contacts, discs)


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
    results, requests = gd.collisionResults, gd.collisionRequests
    k0 = next(k for k, res in enumerate(results) if res.isCollision())
    out = []
    for k in range(k0, len(results)):
        if k > k0 and not pin.computeCollision(geom, gd, k):
            continue
        if requests[k].security_margin == 0.0 or pin.computeDistance(geom, gd, k).min_distance < 0.0:
            out.append(k)
            if first:
                break
    return out


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
