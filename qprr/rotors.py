"""Rotors as data: where each one sits on the base, which way it pushes, how hard it may push.

A :class:`Rotor` is described in the base frame B of its platform (the frame of the free-flyer
joint): position ``p`` [m], unit thrust axis ``a``, spin sign ``s`` and drag-to-thrust ratio
``kappa`` [m].  A thrust f >= 0 [N] along ``a`` applies to the base the wrench, at B in B axes,

    [f_B; tau_B] = f [a; p x a + s kappa a]                       (Thesis (3.31)-(3.36))

``s = +1``: the reaction (drag) torque points along +a (a propeller turning clockwise seen from
the tip of ``a``); ``s = -1``: along -a.  Stacking the columns gives the rotor matrix
Omega (6 x n) of :func:`rotor_matrix`; Pinocchio's generalised force of the base is Omega f.

Layouts: :func:`ring` places n rotors on a circle ("+" and "X" quadrotors, hexa-, octorotors,
tilted rotors); :func:`rotors_from_mapping` reads a rotor description (a TOML file, or the
same structure in Python) so a user can describe any vehicle.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ActuationError, ActuationWarning, InputError, UnknownNameError
from .validation import as_file, as_int, as_real, as_settings, as_vector


def _finite3(value, name: str) -> tuple[float, float, float]:
    x, y, z = as_vector(value, 3, name).tolist()
    return (x, y, z)


@dataclass(frozen=True)
class Rotor:
    """One rotor of a multirotor (see the module docstring for the wrench it applies).

    Parameters
    ----------
    position_body : (3,) position of the rotor centre in B [m].
    axis_body : (3,) thrust direction in B (normalised on construction; must be non-zero).
    spin : +1 or -1, sign of the reaction torque along ``axis_body``.
    kappa : drag torque per newton of thrust, c/b [m] (>= 0).
    f_min, f_max : thrust bounds [N], 0 <= f_min < f_max.
    name : a label (e.g. the URDF frame of the rotor).
    radius : propeller radius [m] (the disc the blades sweep, used by :mod:`qprr.analysis.collision`); None: not given
        (:func:`qprr.analysis.collision.default_disc_radius` derives one from the rotor spacing).
    """

    position_body: tuple[float, float, float]
    axis_body: tuple[float, float, float] = (0.0, 0.0, 1.0)
    spin: int = 1
    kappa: float = 0.0
    f_min: float = 0.0
    f_max: float = math.inf
    name: str = ""
    radius: float | None = None

    def __post_init__(self) -> None:
        label = f"rotor {self.name!r}" if self.name else "rotor"
        p = _finite3(self.position_body, f"{label} position_body")
        a = np.asarray(_finite3(self.axis_body, f"{label} axis_body"))
        norm = float(np.linalg.norm(a))
        if not norm > 1e-9:
            raise InputError(f"{label} axis_body must be a non-zero vector, got {self.axis_body!r}")
        object.__setattr__(self, "position_body", p)
        object.__setattr__(self, "axis_body", tuple(float(x) for x in a / norm) if abs(norm - 1.0) > 1e-15 else tuple(float(x) for x in a))
        if self.spin not in (1, -1):
            raise InputError(f"{label} spin must be +1 or -1, got {self.spin!r}")
        object.__setattr__(self, "spin", int(self.spin))
        object.__setattr__(self, "kappa", as_real(self.kappa, f"{label} kappa", nonnegative=True, unit="m"))
        object.__setattr__(self, "f_min", as_real(self.f_min, f"{label} f_min", nonnegative=True, unit="N"))
        object.__setattr__(self, "f_max", as_real(self.f_max, f"{label} f_max", positive=True, allow_inf=True, unit="N"))
        if not isinstance(self.name, str):
            raise InputError(f"{label} name must be a string, got {self.name!r}")
        if self.radius is not None:
            object.__setattr__(self, "radius", as_real(self.radius, f"{label} radius", positive=True, unit="m"))
        if not (math.isfinite(self.f_min) and 0.0 <= self.f_min < self.f_max):
            raise InputError(f"{label} thrust bounds must satisfy 0 <= f_min < f_max, got f_min = {self.f_min!r}, f_max = {self.f_max!r}")

    def wrench_column(self) -> np.ndarray:
        """[a; p x a + spin kappa a] (6,): the base wrench at B, in B axes, per newton of thrust."""
        a = np.array(self.axis_body)
        p = np.array(self.position_body)
        return np.concatenate([a, np.cross(p, a) + self.spin * self.kappa * a])


def rotor_matrix(rotors: Sequence[Rotor]) -> np.ndarray:
    """Omega (6 x n): [f_B; tau_B] = Omega f for the thrusts f of ``rotors`` (Thesis (3.31), (3.36))."""
    if not isinstance(rotors, (tuple, list)) or not all(isinstance(r, Rotor) for r in rotors):
        raise InputError(f"rotors must be a sequence of qprr.rotors.Rotor, got {rotors!r:.80}")
    if len(rotors) == 0:
        raise InputError("a multirotor needs at least one rotor, got none")
    return np.column_stack([r.wrench_column() for r in rotors])


def _snap(x: float) -> float:
    """Round trigonometric values of multiples of pi/2 to their exact 0, +-1."""
    r = round(x)
    return float(r) if abs(x - r) < 1e-15 else float(x)


@dataclass(frozen=True)
class RingSpec:
    """The layout of a :func:`ring` beyond its size: ``start_angle`` [rad] of rotor 1, ``spins``, the plane's
    ``height`` [m], the ``tilt`` [rad] and its ``tilt_signs``; and every rotor's ``kappa`` [m], ``f_min`` and ``f_max``
    [N], named ``name_1``, ``name_2``, ... (see :func:`ring`)."""

    start_angle: float = 0.0
    spins: Sequence[int] | None = None
    kappa: float = 0.0
    f_min: float = 0.0
    f_max: float = math.inf
    height: float = 0.0
    tilt: float = 0.0
    tilt_signs: Sequence[int] | None = None
    name: str = "rotor"

    def __post_init__(self) -> None:  # the numbers, checked however the spec is built (the rotors check the rest)
        for key, unit in (("start_angle", "rad"), ("height", "m"), ("tilt", "rad")):
            object.__setattr__(self, key, as_real(self.__dict__[key], key, unit=unit))
        object.__setattr__(self, "kappa", as_real(self.kappa, "kappa", nonnegative=True, unit="m"))
        object.__setattr__(self, "f_min", as_real(self.f_min, "f_min", nonnegative=True, unit="N"))
        object.__setattr__(self, "f_max", as_real(self.f_max, "f_max", positive=True, allow_inf=True, unit="N"))


def ring(n: int, radius: float, spec: RingSpec | None = None, **settings) -> tuple[Rotor, ...]:
    """``n`` rotors on a circle of ``radius`` [m] in the plane z = ``height`` of B (``spec``: a :class:`RingSpec`,
    and/or its fields as keywords, which replace the spec's: ``ring(6, 0.3, tilt=0.3, f_max=10.0)``).

    Rotor i (from 1) sits at the angle ``start_angle + 2 pi (i - 1) / n`` from x_B, counter-
    clockwise about z_B.  ``spins`` default to alternating +1, -1 (rotor 1: +1).  ``tilt`` [rad]
    turns each thrust axis away from z_B about the rotor's radial arm, by ``tilt_signs[i] *
    tilt`` (default alternating +1, -1: the usual fully actuated hexarotor).  With ``tilt = 0``
    the base produces a 4-D wrench set (thrust along z_B and three torques); with alternating
    tilts and n >= 6 a 6-D one.
    """
    o = as_settings(spec, RingSpec, "spec", **settings)
    n = as_int(n, "number of rotors n", lo=1)
    radius = as_real(radius, "radius", nonnegative=True, unit="m")
    start_angle = as_real(o.start_angle, "start_angle", unit="rad")
    height = as_real(o.height, "height", unit="m")
    tilt = as_real(o.tilt, "tilt", unit="rad")
    spins = tuple((1, -1)[i % 2] for i in range(n)) if o.spins is None else tuple(o.spins)
    tilt_signs = tuple((1, -1)[i % 2] for i in range(n)) if o.tilt_signs is None else tuple(o.tilt_signs)
    if len(spins) != n or len(tilt_signs) != n:
        raise InputError(f"spins and tilt_signs need {n} entries, got {len(spins)} and {len(tilt_signs)}")
    out = []
    for i in range(n):
        ang = start_angle + 2.0 * math.pi * i / n
        c, s = _snap(math.cos(ang)), _snap(math.sin(ang))
        t = tilt_signs[i] * tilt
        # axis z_B turned by t about the radial unit vector (c, s, 0)
        ct, st = _snap(math.cos(t)), _snap(math.sin(t))
        axis = (st * s, -st * c, ct)
        out.append(Rotor((radius * c, radius * s, float(height)), axis, spins[i], o.kappa, o.f_min, o.f_max, f"{o.name}_{i + 1}"))
    return tuple(out)


def quadrotor(arm_length: float, layout: str = "plus", **kwargs) -> tuple[Rotor, ...]:
    """A quadrotor ring with the thesis numbering: "+" puts rotor 1 on -x_B, 2 on -y_B, 3 on +x_B,
    4 on +y_B (Thesis (3.34)-(3.36)); "x" turns them by +45 deg about z_B (Lecture: "+" vs "X")."""
    starts = {"plus": math.pi, "x": 1.25 * math.pi}
    if layout not in starts:
        raise UnknownNameError("quadrotor layout", layout, tuple(starts))
    return ring(4, as_real(arm_length, "arm_length", positive=True, unit="m"), start_angle=starts[layout], **kwargs)


def ideal_wrench_set(force_max: float, torque_max: float, *, name: str = "ideal") -> tuple[Rotor, ...]:
    """Eighteen virtual thrusters at B that produce any base wrench with |F_e| <= ``force_max`` [N] and |M_e| <=
    ``torque_max`` [N m] on each axis e: an idealised, fully actuated vehicle (the thesis's point-to-point test
    applies u as is, Sec. 6.3.1.1; :class:`qprr.actuation.IdealAllocator` allocates it exactly).

    Per axis e, in this order: a force pair along +e and -e (kappa = 0; columns [e; 0], [-e; 0]); a positive
    couple, thrusters along +e (spin +1) and -e (spin -1) with kappa = 1 m (columns [e; e], [-e; e]: equal thrusts
    f give the couple 2 f e); a negative couple, along +e (spin -1) and -e (spin +1) (columns [e; -e], [-e; -e]).
    """
    force_max = as_real(force_max, "force_max", positive=True, unit="N")
    torque_max = as_real(torque_max, "torque_max", positive=True, unit="N m")
    out = []
    o = (0.0, 0.0, 0.0)
    for k, e in enumerate(((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))):
        ax = "xyz"[k]
        neg = tuple(-c for c in e)
        half = 0.5 * torque_max
        out += [
            Rotor(o, e, 1, 0.0, 0.0, force_max, f"{name}_f{ax}+"),
            Rotor(o, neg, 1, 0.0, 0.0, force_max, f"{name}_f{ax}-"),
            Rotor(o, e, 1, 1.0, 0.0, half, f"{name}_m{ax}+a"),
            Rotor(o, neg, -1, 1.0, 0.0, half, f"{name}_m{ax}+b"),
            Rotor(o, e, -1, 1.0, 0.0, half, f"{name}_m{ax}-a"),
            Rotor(o, neg, 1, 1.0, 0.0, half, f"{name}_m{ax}-b"),
        ]
    return tuple(out)


LAYOUTS = ("plus", "x")
"""Ring layouts of :func:`layout_rotors`: rotor 1 on an axis of B ("plus") or between two ("x")."""


def layout_rotors(n: int, arm_length: float, layout: str = "plus", **kwargs) -> tuple[Rotor, ...]:
    """Rotors of an n-rotor ring in the "plus" or "x" layout (quadrotors: :func:`quadrotor`)."""
    if layout not in LAYOUTS:
        raise UnknownNameError("rotor layout", layout, LAYOUTS)
    n = as_int(n, "number of rotors n", lo=1)
    arm_length = as_real(arm_length, "arm_length", positive=True, unit="m")
    if n == 4:
        return quadrotor(arm_length, layout, **kwargs)
    start = 0.0 if layout == "plus" else math.pi / n
    return ring(n, arm_length, start_angle=start, **kwargs)


# ------------------------------------------------------------------ rotor descriptions (files)
_ROTOR_KEYS = {"position", "axis", "quaternion_xyzw", "spin", "kappa", "f_min", "f_max", "name", "frame", "radius"}
_DEFAULT_KEYS = {"kappa", "f_min", "f_max", "radius"}
_MAX_ROTOR_DISTANCE = 10.0  # [m] from B: the largest multirotors span a few metres; beyond, positions are not in metres
_AXIS_NORM_TOL = 1e-3  # a written axis is unit to this (rounded decimals), then normalised


def _listed3(value, what: str) -> tuple[float, float, float]:
    """A description's 3-vector: a list of 3 finite numbers (not a string, not a table)."""
    if (
        isinstance(value, (str, bytes, Mapping))
        or not isinstance(value, Sequence)
        or len(value) != 3
        or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value)
    ):
        raise InputError(f"{what} must be a list of 3 finite numbers, e.g. [0.2, 0.0, 0.05], got {value!r}")
    return (float(value[0]), float(value[1]), float(value[2]))


def _quat_axis(qxyzw) -> tuple[float, float, float]:
    x, y, z, w = (float(v) for v in qxyzw)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not n > 1e-9:
        raise InputError(f"rotor quaternion_xyzw must be non-zero, got {qxyzw!r}")
    x, y, z, w = x / n, y / n, z / n, w / n
    # third column of the rotation matrix of the unit quaternion: R e3
    return (2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y))


def rotors_from_mapping(desc: Mapping, frame_positions: Mapping[str, tuple] | None = None) -> tuple[Rotor, ...]:
    """Rotors from a description: ``{"base_link": name, "defaults": {kappa, f_min, f_max}, "rotor": [{...}, ...]}``.

    Each rotor entry has ``spin`` (+1/-1 or "cw"/"ccw", cw = +1), either ``position`` [m] with
    ``axis`` (a unit vector, default [0, 0, 1]) or ``quaternion_xyzw`` (the rotor frame's orientation in B, the
    thrust along its z), or ``frame``: the name of a frame of the platform's URDF whose placement
    gives the position and the axis (its z) - resolved by the caller through ``frame_positions``
    (name -> (position, axis)).  ``kappa``, ``f_min``, ``f_max`` (and the propeller ``radius`` [m], optional) per rotor or in ``defaults``.
    The optional ``base_link`` (a string) names the link the positions are written in; the caller
    (:func:`qprr.model.from_model`) checks that it is the platform's base B.
    Unknown keys raise :class:`~qprr.errors.UnknownNameError`; a position farther than 10 m from B
    or an axis whose norm is not 1 (to 1e-3) raises :class:`~qprr.errors.InputError` (units, typos).
    """
    defaults, entries = _checked_description(desc)
    out = []
    for i, entry in enumerate(entries):
        if not isinstance(entry, Mapping):
            raise InputError(f"rotor {i + 1} of the description must be a table (mapping), got {entry!r}")
        bad = set(entry) - _ROTOR_KEYS
        if bad:
            raise UnknownNameError(f"key of rotor {i + 1}", sorted(bad)[0], tuple(sorted(_ROTOR_KEYS)))
        e = {**defaults, **entry}
        spin = _entry_spin(e, i)
        pos, axis = _entry_placement(e, i, frame_positions)
        name = str(e.get("name", e.get("frame", f"rotor_{i + 1}")))
        out.append(Rotor(tuple(pos), tuple(axis), spin, e.get("kappa", 0.0), e.get("f_min", 0.0), e.get("f_max", math.inf), name, e.get("radius")))
    return tuple(out)


def _checked_description(desc) -> tuple[dict, Sequence]:
    """(defaults, rotor entries) of a rotor description, its top-level keys checked (:func:`rotors_from_mapping`)."""
    if not isinstance(desc, Mapping):
        raise InputError(f"a rotor description must be a mapping, got {type(desc).__name__}")
    unknown = set(desc) - {"base_link", "defaults", "rotor", "motor"}  # "motor": the actuator stage's data (qprr.sim.actuators)
    if unknown:
        raise UnknownNameError("rotor description key", sorted(unknown)[0], ("base_link", "defaults", "rotor", "motor"))
    if not isinstance(desc.get("base_link", ""), str):
        raise InputError(f"base_link must be the name of a link (a string), got {desc['base_link']!r}")
    defaults = desc.get("defaults", {})
    if not isinstance(defaults, Mapping):
        raise InputError(f"'defaults' must be a table of {sorted(_DEFAULT_KEYS)}, got {defaults!r}")
    defaults = dict(defaults)
    bad = set(defaults) - _DEFAULT_KEYS
    if bad:
        raise UnknownNameError("rotor default", sorted(bad)[0], tuple(sorted(_DEFAULT_KEYS)))
    entries = desc.get("rotor")
    if not entries or isinstance(entries, Mapping) or not isinstance(entries, (list, tuple)):
        raise InputError(f"a rotor description needs a non-empty list 'rotor' of tables (in TOML: one [[rotor]] per rotor), got {entries!r}")
    return defaults, entries


def _entry_spin(e: Mapping, i: int) -> int:
    """The spin of rotor entry ``e`` (number i + 1): +1/-1 or "cw"/"ccw" (cw = +1)."""
    if "spin" not in e:
        raise InputError(f'rotor {i + 1} needs \'spin\': "cw" (+1: reaction torque along +axis) or "ccw" (-1)')
    spin = e.get("spin")
    if isinstance(spin, str):
        if spin.lower() not in ("cw", "ccw"):
            raise UnknownNameError(f"spin of rotor {i + 1}", spin, ("cw", "ccw", "+1", "-1"))
        spin = 1 if spin.lower() == "cw" else -1
    return spin


def _entry_placement(e: Mapping, i: int, frame_positions: Mapping | None) -> tuple[tuple, tuple]:
    """(position [m], unit thrust axis) in B of rotor entry ``e``: from its URDF frame, or its position with an axis or
    a quaternion (:func:`rotors_from_mapping`)."""
    if "frame" in e:
        if frame_positions is None or e["frame"] not in frame_positions:
            valid = tuple(frame_positions) if frame_positions else ()
            raise UnknownNameError(f"frame of rotor {i + 1}", e["frame"], valid)
        return frame_positions[e["frame"]]
    if "position" not in e:
        raise InputError(f"rotor {i + 1} needs 'position' (or 'frame')")
    pos = _listed3(e["position"], f"rotor {i + 1} position [m]")
    distance = math.hypot(*pos)
    if distance > _MAX_ROTOR_DISTANCE:
        raise InputError(
            f"rotor {i + 1} position {list(pos)} is {distance:.4g} m from B: positions are in metres "
            "(millimetres divided by 1000), in the frame of the URDF's root link"
        )
    if "quaternion_xyzw" in e and "axis" in e:
        raise InputError(f"rotor {i + 1}: give 'axis' or 'quaternion_xyzw', not both")
    if "quaternion_xyzw" in e:
        q = e["quaternion_xyzw"]
        if isinstance(q, (str, bytes, Mapping)) or not isinstance(q, Sequence) or len(q) != 4:
            raise InputError(f"rotor {i + 1} quaternion_xyzw must be a list of 4 numbers [x, y, z, w], got {q!r}")
        return pos, _quat_axis(q)
    axis = _listed3(e.get("axis", (0.0, 0.0, 1.0)), f"rotor {i + 1} axis")
    norm = math.hypot(*axis)
    if abs(norm - 1.0) > _AXIS_NORM_TOL:
        unit = [round(x / norm, 6) for x in axis] if norm > 0 else "a non-zero vector"
        raise InputError(f"rotor {i + 1} axis {list(axis)} has norm {norm:.6g}: give the unit thrust direction in B (here {unit})")
    return pos, axis


def read_rotor_file(path: str | Path) -> dict:
    """Parse a TOML rotor description (see :func:`rotors_from_mapping`) into a dict."""
    path = as_file(path, "path", what="rotor description file")
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        try:
            import tomli as tomllib
        except ModuleNotFoundError as exc:
            from .errors import MissingDependencyError

            raise MissingDependencyError("tomli", "reading TOML rotor files on Python 3.10", "pip install tomli") from exc
    with path.open("rb") as fh:
        try:
            desc = tomllib.load(fh)
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise InputError(f"rotor description file {str(path)!r} is not valid TOML: {exc}") from exc
    if not desc:
        raise InputError(f"rotor description file {str(path)!r} is empty: it needs one [[rotor]] table per rotor")
    return desc  # its content is checked by rotors_from_mapping (errors prefixed with the file by from_urdf)


# ------------------------------------------------------------------ what a rotor set can do
WRENCH_NAMES = ("F_x", "F_y", "F_z", "tau_x", "tau_y", "tau_z")
"""The base wrench components [f_B; tau_B] of a column of Omega, in B."""

RANK_RTOL = 1e-9
"""A singular value of the (length-scaled) wrench map below RANK_RTOL x the largest is zero (a direction the rotors
cannot produce)."""

CONDITION_WARN = 1e3
"""Condition number of the length-scaled attitude map [thrust; tau] above which loading warns (one direction is more
than a thousand times weaker than the strongest)."""

DUPLICATE_DISTANCE = 1e-3
"""Two rotors closer than this [m] with the same axis, spin and kappa are one rotor written twice."""


@dataclass(frozen=True)
class ActuationSummary:
    """What a rotor set can do for a vehicle of weight m g with its CoG at ``com_body`` (B) (:func:`actuation_summary`).

    rank : dimension of the base wrench set Omega f (4: coplanar parallel rotors, 6: fully actuated).
    directions : the axes of B's wrench (:data:`WRENCH_NAMES`) the set can produce on their own (each e_k in the
        range of Omega); an under-actuated quadrotor: ("F_z", "tau_x", "tau_y", "tau_z").
    range_basis : (6, rank) orthonormal basis of the producible wrenches (in the length-scaled space of ``length``).
    fully_actuated : rank == 6 (any force and torque at a level attitude).
    thrust_axis_body : d, the unit direction of the collective thrust (sum of the rotor axes, z_B if they cancel).
    attitude_rank : rank of [d^T Omega_F; Omega_tau] (4 rows): 4 is what every flight controller needs
        (collective thrust plus three independent torques).
    condition : sigma_max / sigma_min of that 4-row map with the torques divided by ``length`` (inf if rank < 4).
    length : the length [m] torques are divided by (the largest rotor distance to B, or kappa if larger; 1 if both 0).
    hover_wrench : [f; tau] (6,) the rotors apply at hover with d vertical: m g [d; c x d].
    hover_thrusts : (n,) thrusts that give ``hover_wrench`` [N]: the least-norm ones, or, when those leave the bounds and
        the margin is positive, the thrusts of the largest margin (never a thrust outside the bounds beside a positive
        margin); NaN if no thrusts give it.
    hover_margin : the largest s [N] such that some thrusts give ``hover_wrench`` with f_min + s <= f <= f_max - s
        (a linear programme; <= 0: the set cannot hover with every thrust strictly inside its bounds; capped at m g).
    can_hover, can_control_attitude : hover_margin > 0; attitude_rank == 4.
    """

    rank: int
    directions: tuple[str, ...]
    range_basis: np.ndarray
    fully_actuated: bool
    thrust_axis_body: np.ndarray
    attitude_rank: int
    condition: float
    length: float
    hover_wrench: np.ndarray
    hover_thrusts: np.ndarray
    hover_margin: float

    @property
    def can_hover(self) -> bool:
        return self.hover_margin > 0.0

    @property
    def can_control_attitude(self) -> bool:
        return self.attitude_rank == 4

    def __str__(self) -> str:
        kind = "fully actuated" if self.fully_actuated else "under-actuated"
        f = ", ".join(f"{x:.4g}" for x in self.hover_thrusts)
        return (
            f"rank {self.rank} ({kind}); wrench directions {', '.join(self.directions) or 'none'}; attitude map rank "
            f"{self.attitude_rank}/4, condition {self.condition:.4g}; hover thrusts [{f}] N, margin {self.hover_margin:.4g} N"
        )


def _rank(s: np.ndarray) -> int:
    return int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0.0 else 0


def actuation_summary(rotors: Sequence[Rotor], weight: float, com_body=(0.0, 0.0, 0.0)) -> ActuationSummary:
    """:class:`ActuationSummary` of ``rotors`` carrying a weight m g = ``weight`` [N] with its CoG at ``com_body`` [m] in B.

    The hover wrench is the one the rotors must apply with the collective thrust axis d vertical (a vehicle hovers
    with d up): m g [d; c x d].  The hover margin is the optimum of the linear programme max s subject to
    Omega f = hover wrench, f_min + s <= f <= f_max - s, s <= m g (scipy's HiGHS)."""
    return _summary(rotors, weight, com_body, optimal_margin=True)


def _summary(rotors: Sequence[Rotor], weight: float, com_body, optimal_margin: bool) -> ActuationSummary:
    """The summary; ``optimal_margin=False``: when the least-norm hover thrusts are strictly inside their bounds, their
    smallest distance to a bound (a lower bound of the optimum, enough to say the set hovers) instead of the LP."""
    from scipy.optimize import linprog

    Omega = rotor_matrix(rotors)
    weight = as_real(weight, "weight", nonnegative=True, unit="N")
    c = as_vector(com_body, 3, "com_body")
    n = Omega.shape[1]
    length = max([math.hypot(*r.position_body) for r in rotors] + [r.kappa for r in rotors])
    length = length if length > 0.0 else 1.0
    scaled = Omega.copy()
    scaled[3:6] /= length
    U, s, _ = np.linalg.svd(scaled)
    rank = _rank(s)
    basis = U[:, :rank]
    directions = tuple(WRENCH_NAMES[k] for k in range(6) if np.linalg.norm(basis.T[:, k]) > 1.0 - 1e-9)
    F = Omega[0:3].sum(axis=1)
    d = F / np.linalg.norm(F) if np.linalg.norm(F) > 1e-9 else np.array([0.0, 0.0, 1.0])
    att = np.vstack([d @ Omega[0:3], scaled[3:6]])
    sa = np.linalg.svd(att, compute_uv=False)
    att_rank = _rank(sa)
    condition = float(sa[0] / sa[3]) if att_rank == 4 else math.inf
    w = weight * np.concatenate([d, np.cross(c, d)])
    f_ls, *_ = np.linalg.lstsq(Omega, w, rcond=None)
    exact = np.linalg.norm(Omega @ f_ls - w) <= 1e-9 * max(weight, 1.0)
    f_ls = f_ls if exact else np.full(n, math.nan)
    margin = -math.inf
    lo = np.array([r.f_min for r in rotors])
    hi = np.array([r.f_max for r in rotors])
    fast = min(float(np.min(f_ls - lo)), float(np.min(hi - f_ls)), max(weight, 1e-9)) if exact else -math.inf
    if exact and not optimal_margin and fast > 0.0:
        margin = fast
    elif exact:
        fin = np.isfinite(hi)
        # variables [f (n), s]; maximise s
        A_ub = np.vstack([np.hstack([-np.eye(n), np.ones((n, 1))]), np.hstack([np.eye(n)[fin], np.ones((int(fin.sum()), 1))])])
        b_ub = np.concatenate([-lo, hi[fin]])
        # equality rows equilibrated to unit norm: HiGHS's feasibility tolerance is absolute, and a nearly coplanar
        # set's lateral-force rows (tilt 1e-5: entries 1e-5 f) would otherwise be met only to ~1 % of their scale;
        # all-zero rows hold for every f (the least-squares check above found w there zero) and are dropped
        row = np.linalg.norm(Omega, axis=1)
        keep = row > 1e-12 * row.max()
        res = linprog(
            np.r_[np.zeros(n), -1.0],
            A_ub=A_ub,
            b_ub=b_ub,
            A_eq=np.hstack([Omega[keep], np.zeros((int(keep.sum()), 1))]) / row[keep, None],
            b_eq=w[keep] / row[keep],
            bounds=[(None, None)] * n + [(None, max(weight, 1e-9))],
            method="highs",
        )
        margin = float(-res.fun) if res.status == 0 else -math.inf
        if margin > 0.0 and not (np.all(f_ls >= lo) and np.all(f_ls <= hi)):
            f_ls = res.x[:n]  # the least-norm thrusts leave the bounds: report thrusts that hover inside them
    return ActuationSummary(
        rank, directions, _ro(basis), rank == 6, _ro(d), att_rank, condition, float(length), _ro(w), _ro(np.asarray(f_ls, dtype=float)), margin
    )


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def duplicate_rotors(rotors: Sequence[Rotor]) -> list[tuple[int, int]]:
    """Index pairs (i, j), i < j, of rotors that are one rotor written twice: centres closer than
    :data:`DUPLICATE_DISTANCE`, the same axis, spin and kappa (virtual thrusters at one point with other axes, spins or
    kappa, as :func:`ideal_wrench_set`'s, are not duplicates)."""
    if not isinstance(rotors, (tuple, list)) or not rotors or not all(isinstance(r, Rotor) for r in rotors):
        raise InputError(f"rotors must be a non-empty sequence of qprr.rotors.Rotor, got {rotors!r:.80}")
    out = []
    for i, a in enumerate(rotors):
        for j in range(i + 1, len(rotors)):
            b = rotors[j]
            if (
                math.dist(a.position_body, b.position_body) < DUPLICATE_DISTANCE
                and np.dot(a.axis_body, b.axis_body) > 1.0 - 1e-9
                and a.spin == b.spin
                and abs(a.kappa - b.kappa) <= 1e-12
            ):
                out.append((i, j))
    return out


def _why_no_attitude(rotors: Sequence[Rotor], d: np.ndarray) -> str:
    """The likely reason a rotor set lacks an attitude direction (for the error message)."""
    parallel = all(float(np.dot(r.axis_body, d)) > 1.0 - 1e-9 for r in rotors)
    p = np.array([r.position_body for r in rotors])
    p_perp = p - np.outer(p @ d, d)
    reasons = []
    if len(rotors) < 4:
        reasons.append(f"{len(rotors)} rotor(s) produce at most {len(rotors)} independent wrench components; a multirotor needs 4")
    if parallel and len({r.spin for r in rotors}) == 1:
        reasons.append('every rotor has the same spin: the drag torques only add up, give half of them the other spin ("cw" / "ccw")')
    if parallel and all(r.kappa == 0.0 for r in rotors):
        reasons.append("every drag/thrust ratio kappa is 0: parallel rotors then give no yaw torque (propellers: 0.005-0.06 m)")
    if np.all(np.linalg.norm(p_perp, axis=1) < DUPLICATE_DISTANCE):
        reasons.append("every rotor sits on the thrust axis through B (rotors at the centre): no roll or pitch torque")
    elif np.linalg.matrix_rank(p_perp - p_perp.mean(axis=0), tol=DUPLICATE_DISTANCE) <= 1:
        reasons.append("the rotors lie on one line: no torque about that line")
    return "; ".join(reasons) if reasons else "the rotor axes and positions are degenerate"


def _names(rotors: Sequence[Rotor], idx) -> str:
    return ", ".join(f"{rotors[k].name or f'rotor_{k + 1}'!r} (rotor {k + 1})" for k in idx)


def check_hover_solution(rotors: Sequence[Rotor], weight: float, com_body=(0.0, 0.0, 0.0), source: str = "the rotor set") -> None:
    """Refuse a rotor set whose hover solution - the least-norm thrusts that give the hover wrench m g [d; c x d], what
    an allocator starts from - needs a thrust outside a rotor's bounds (a negative one: a rotor whose axis points
    against the others', e.g. the lower rotor of a coaxial pair written [0, 0, -1]); warn when the spins do not balance
    the yaw drag at hover (equal thrusts leave a yaw torque: the hover thrusts become unequal), naming the rotors.
    An :class:`~qprr.errors.ActuationError` / :class:`~qprr.errors.ActuationWarning` naming ``source`` and the rotors."""
    Omega = rotor_matrix(rotors)
    weight = as_real(weight, "weight", nonnegative=True, unit="N")
    c = as_vector(com_body, 3, "com_body")
    F = Omega[0:3].sum(axis=1)
    d = F / np.linalg.norm(F) if np.linalg.norm(F) > 1e-9 else np.array([0.0, 0.0, 1.0])
    f, *_ = np.linalg.lstsq(Omega, weight * np.concatenate([d, np.cross(c, d)]), rcond=None)
    lo, hi = np.array([r.f_min for r in rotors]), np.array([r.f_max for r in rotors])
    tol = 1e-9 * max(weight, 1.0)
    out = [k for k in range(len(rotors)) if not lo[k] - tol <= f[k] <= hi[k] + tol]
    if out:
        against = [k for k in out if float(np.dot(rotors[k].axis_body, d)) < 0.0]
        hint = (
            f"the axis of {_names(rotors, against)} points against the collective thrust {np.round(d, 6).tolist()}: a "
            "propeller pushes along its axis, the direction the vehicle is pushed (a lower coaxial rotor blowing down "
            "still pushes up: axis [0, 0, 1])"
            if against
            else "check the axes (the direction each rotor pushes), the positions (frame B, metres) and the bounds"
        )
        thrusts = ", ".join(f"{rotors[k].name or f'rotor_{k + 1}'!r} {f[k]:.4g} N in [{lo[k]:g}, {hi[k]:g}]" for k in out)
        raise ActuationError(
            f"{source}: the hover solution (least-norm thrusts giving the weight {weight:.6g} N) needs thrusts outside "
            f"the rotors' bounds: {thrusts}; {hint}"
        )
    drag = np.array([r.spin * r.kappa * float(np.dot(r.axis_body, d)) for r in rotors])
    scale = float(np.sum(np.abs(drag)))
    if scale > 0.0 and abs(float(drag.sum())) > 1e-6 * scale:
        cw = [k for k, r in enumerate(rotors) if r.spin > 0]
        ccw = [k for k, r in enumerate(rotors) if r.spin < 0]
        warnings.warn(
            f"{source}: the spins do not balance the yaw drag at hover: at equal thrusts the drag torques leave "
            f"{float(drag.sum()) / len(rotors):+.3g} N m per newton about the thrust axis (cw, spin +1: {_names(rotors, cw) or 'none'}; "
            f"ccw, spin -1: {_names(rotors, ccw) or 'none'}), so the hover thrusts are unequal "
            f"({float(f.min()):.4g}-{float(f.max()):.4g} N) and yaw authority is lost; check the spins (coaxial pairs turn opposite ways)",
            ActuationWarning,
            stacklevel=3,
        )


def check_rotor_set(rotors: Sequence[Rotor], weight: float, com_body=(0.0, 0.0, 0.0), source: str = "the rotor set", *, hover: bool = True) -> None:
    """Nothing for a rotor set that can hover and control its attitude, else an :class:`~qprr.errors.ActuationError`
    naming ``source`` (the rotor file) and the rotors (:func:`actuation_summary` reports the numbers).

    Refused: a rotor written twice (:func:`duplicate_rotors`); an attitude map [d^T Omega_F; Omega_tau] of rank < 4
    (every flight controller needs collective thrust and three independent torques: same spins, zero kappa, rotors on
    a line or at the centre, fewer than four rotors); no hover thrusts strictly inside the bounds (``hover=False``
    skips this one: a rotor set read without the vehicle's mass, e.g. ``qprr import px4`` without ``--mass``).  Warned about
    (:class:`~qprr.errors.ActuationWarning`): a condition number above :data:`CONDITION_WARN`."""
    dup = duplicate_rotors(rotors)
    names = [r.name or f"rotor_{k + 1}" for k, r in enumerate(rotors)]
    if dup:
        pairs = ", ".join(f"{names[i]!r} (rotor {i + 1}) and {names[j]!r} (rotor {j + 1})" for i, j in dup)
        raise ActuationError(
            f"{source}: {pairs} are the same rotor written twice (same position, axis, spin and kappa); "
            "was a rotor table pasted twice? Remove the copies (coaxial pairs sit at different heights)"
        )
    summary = _summary(rotors, as_real(weight, "weight", nonnegative=True, unit="N"), com_body, optimal_margin=False)
    listed = ", ".join(names)
    if not summary.can_control_attitude:
        raise ActuationError(
            f"{source}: the rotors [{listed}] span {summary.attitude_rank} of the 4 directions (collective thrust, roll, "
            f"pitch and yaw torque) every flight controller needs (wrench rank {summary.rank}, directions "
            f"{', '.join(summary.directions) or 'none'}): {_why_no_attitude(rotors, summary.thrust_axis_body)}"
        )
    if hover and not summary.can_hover:
        why = (
            "no thrusts give the hover wrench m g [d; c x d] (CoG outside what the rotors can balance)"
            if np.isnan(summary.hover_thrusts).any()
            else f"the best hover thrusts keep a margin of {summary.hover_margin:.4g} N to their bounds [f_min, f_max]"
        )
        raise ActuationError(
            f"{source}: the rotors [{listed}] cannot hover the vehicle (weight {weight:.6g} N, CoG "
            f"{np.round(np.asarray(com_body, dtype=float), 6).tolist()} m in B at the neutral configuration): "
            f"{why}; check the positions (frame B, metres), the thrust bounds and the spins"
        )
    if summary.condition > CONDITION_WARN:
        warnings.warn(
            f"{source}: the rotors' attitude map is badly conditioned (condition {summary.condition:.3g} > "
            f"{CONDITION_WARN:g}): {_weakest(rotors, summary)}",
            ActuationWarning,
            stacklevel=3,
        )


def rotors_to_toml(rotors: Sequence[Rotor], header: Sequence[str] = ()) -> str:
    """The TOML text of a rotor description of ``rotors`` (read back by :func:`read_rotor_file` and
    :func:`rotors_from_mapping` to the same float64 numbers): one ``[[rotor]]`` per rotor with ``name``, ``position``
    [m], ``axis``, ``spin`` (+1/-1), ``kappa`` [m], ``f_min`` and ``f_max`` [N] (and ``radius`` [m] when given), after
    ``#`` comment lines ``header``.  An infinite f_max is left out (the description's default)."""
    if not isinstance(rotors, (tuple, list)) or not rotors or not all(isinstance(r, Rotor) for r in rotors):
        raise InputError(f"rotors must be a non-empty sequence of qprr.rotors.Rotor, got {rotors!r:.80}")

    def vec(v) -> str:
        return "[" + ", ".join(repr(float(x)) for x in v) + "]"

    lines = [f"# {h}" if h else "#" for h in header]
    for r in rotors:
        lines += ["", "[[rotor]]"]
        if r.name:
            lines.append(f"name = {_toml_string(r.name)}")
        lines += [f"position = {vec(r.position_body)}", f"axis = {vec(r.axis_body)}", f"spin = {r.spin}", f"kappa = {float(r.kappa)!r}"]
        lines.append(f"f_min = {float(r.f_min)!r}")
        if math.isfinite(r.f_max):
            lines.append(f"f_max = {float(r.f_max)!r}")
        if r.radius is not None:
            lines.append(f"radius = {float(r.radius)!r}")
    return "\n".join(lines) + "\n"


def _toml_string(text: str) -> str:
    """A TOML basic string of ``text`` (backslash and double quote escaped, control characters refused)."""
    if any(ord(ch) < 32 for ch in text):
        raise InputError(f"rotor name {text!r} contains a control character")
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _weakest(rotors: Sequence[Rotor], summary: ActuationSummary) -> str:
    """Which of thrust, roll, pitch, yaw torque the set hardly produces, and why when it is yaw (small kappa)."""
    Omega = rotor_matrix(rotors)
    d = summary.thrust_axis_body
    att = np.vstack([d @ Omega[0:3], Omega[3:6] / summary.length])
    U, _, _ = np.linalg.svd(att)
    axis_of = np.vstack([np.r_[1.0, 0.0, 0.0, 0.0], np.hstack([np.zeros((3, 1)), np.eye(3)])])
    weak = int(np.argmax(np.abs(axis_of @ U[:, -1])))
    name = ("collective thrust", "roll torque (about x_B)", "pitch torque (about y_B)", "yaw torque (about z_B)")[weak]
    if weak == 3 or abs(float(U[3, -1])) > 0.5:
        kappas = sorted({r.kappa for r in rotors})
        return (
            f"the yaw torque is far weaker than thrust, roll and pitch: it comes from the drag/thrust ratios kappa "
            f"{', '.join(f'{k:g}' for k in kappas)} m (propellers: 0.005-0.06 m); a raw drag coefficient c [N m s^2] "
            "written for kappa = c / b? Yaw errors and saturated rotors follow"
        )
    return f"the {name} is far weaker than the others"
