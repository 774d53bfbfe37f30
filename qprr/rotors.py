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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .charts import as_file, as_int, as_real, as_vector
from .errors import InputError, UnknownNameError


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
    """

    position_body: tuple[float, float, float]
    axis_body: tuple[float, float, float] = (0.0, 0.0, 1.0)
    spin: int = 1
    kappa: float = 0.0
    f_min: float = 0.0
    f_max: float = math.inf
    name: str = ""

    def __post_init__(self) -> None:
        label = f"rotor {self.name!r}" if self.name else "rotor"
        p = _finite3(self.position_body, f"{label} position_body")
        a = np.asarray(_finite3(self.axis_body, f"{label} axis_body"))
        norm = float(np.linalg.norm(a))
        if not norm > 1e-9:
            raise InputError(f"{label} axis_body must be a non-zero vector, got {self.axis_body!r}")
        object.__setattr__(self, "position_body", p)
        object.__setattr__(self, "axis_body", tuple(float(x) for x in a / norm) if abs(norm - 1.0) > 1e-15 else
                           tuple(float(x) for x in a))
        if self.spin not in (1, -1):
            raise InputError(f"{label} spin must be +1 or -1, got {self.spin!r}")
        object.__setattr__(self, "spin", int(self.spin))
        object.__setattr__(self, "kappa", as_real(self.kappa, f"{label} kappa", nonnegative=True, unit="m"))
        object.__setattr__(self, "f_min", as_real(self.f_min, f"{label} f_min", nonnegative=True, unit="N"))
        object.__setattr__(self, "f_max", as_real(self.f_max, f"{label} f_max", positive=True, allow_inf=True, unit="N"))
        if not isinstance(self.name, str):
            raise InputError(f"{label} name must be a string, got {self.name!r}")
        if not (math.isfinite(self.f_min) and 0.0 <= self.f_min < self.f_max):
            raise InputError(f"{label} thrust bounds must satisfy 0 <= f_min < f_max, got f_min = {self.f_min!r}, "
                             f"f_max = {self.f_max!r}")

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


def ring(
    n: int,
    radius: float,
    *,
    start_angle: float = 0.0,
    spins: Sequence[int] | None = None,
    kappa: float = 0.0,
    f_min: float = 0.0,
    f_max: float = math.inf,
    height: float = 0.0,
    tilt: float = 0.0,
    tilt_signs: Sequence[int] | None = None,
    name: str = "rotor",
) -> tuple[Rotor, ...]:
    """``n`` rotors on a circle of ``radius`` [m] in the plane z = ``height`` of B.

    Rotor i (from 1) sits at the angle ``start_angle + 2 pi (i - 1) / n`` from x_B, counter-
    clockwise about z_B.  ``spins`` default to alternating +1, -1 (rotor 1: +1).  ``tilt`` [rad]
    turns each thrust axis away from z_B about the rotor's radial arm, by ``tilt_signs[i] *
    tilt`` (default alternating +1, -1: the usual fully actuated hexarotor).  With ``tilt = 0``
    the base produces a 4-D wrench set (thrust along z_B and three torques); with alternating
    tilts and n >= 6 a 6-D one.
    """
    n = as_int(n, "number of rotors n", lo=1)
    radius = as_real(radius, "radius", nonnegative=True, unit="m")
    start_angle = as_real(start_angle, "start_angle", unit="rad")
    height = as_real(height, "height", unit="m")
    tilt = as_real(tilt, "tilt", unit="rad")
    spins = tuple((1, -1)[i % 2] for i in range(n)) if spins is None else tuple(spins)
    tilt_signs = tuple((1, -1)[i % 2] for i in range(n)) if tilt_signs is None else tuple(tilt_signs)
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
        out.append(Rotor((radius * c, radius * s, float(height)), axis, spins[i], kappa, f_min, f_max, f"{name}_{i + 1}"))
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
        out += [Rotor(o, e, 1, 0.0, 0.0, force_max, f"{name}_f{ax}+"), Rotor(o, neg, 1, 0.0, 0.0, force_max, f"{name}_f{ax}-"),
                Rotor(o, e, 1, 1.0, 0.0, half, f"{name}_m{ax}+a"), Rotor(o, neg, -1, 1.0, 0.0, half, f"{name}_m{ax}+b"),
                Rotor(o, e, -1, 1.0, 0.0, half, f"{name}_m{ax}-a"), Rotor(o, neg, 1, 1.0, 0.0, half, f"{name}_m{ax}-b")]
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
_ROTOR_KEYS = {"position", "axis", "quaternion_xyzw", "spin", "kappa", "f_min", "f_max", "name", "frame"}
_DEFAULT_KEYS = {"kappa", "f_min", "f_max"}
_MAX_ROTOR_DISTANCE = 10.0  # [m] from B: the largest multirotors span a few metres; beyond, positions are not in metres
_AXIS_NORM_TOL = 1e-3  # a written axis is unit to this (rounded decimals), then normalised


def _listed3(value, what: str) -> tuple[float, float, float]:
    """A description's 3-vector: a list of 3 finite numbers (not a string, not a table)."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence) or len(value) != 3 or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value):
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
    (name -> (position, axis)).  ``kappa``, ``f_min``, ``f_max`` per rotor or in ``defaults``.
    The optional ``base_link`` (a string) names the link the positions are written in; the caller
    (:func:`qprr.platform.from_model`) checks that it is the platform's base B.
    Unknown keys raise :class:`~qprr.errors.UnknownNameError`; a position farther than 10 m from B
    or an axis whose norm is not 1 (to 1e-3) raises :class:`~qprr.errors.InputError` (units, typos).
    """
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
        raise InputError("a rotor description needs a non-empty list 'rotor' of tables (in TOML: one [[rotor]] per rotor), "
                         f"got {entries!r}")
    out = []
    for i, entry in enumerate(entries):
        if not isinstance(entry, Mapping):
            raise InputError(f"rotor {i + 1} of the description must be a table (mapping), got {entry!r}")
        bad = set(entry) - _ROTOR_KEYS
        if bad:
            raise UnknownNameError(f"key of rotor {i + 1}", sorted(bad)[0], tuple(sorted(_ROTOR_KEYS)))
        e = {**defaults, **entry}
        if "spin" not in e:
            raise InputError(f"rotor {i + 1} needs 'spin': \"cw\" (+1: reaction torque along +axis) or \"ccw\" (-1)")
        spin = e.get("spin")
        if isinstance(spin, str):
            if spin.lower() not in ("cw", "ccw"):
                raise UnknownNameError(f"spin of rotor {i + 1}", spin, ("cw", "ccw", "+1", "-1"))
            spin = 1 if spin.lower() == "cw" else -1
        if "frame" in e:
            if frame_positions is None or e["frame"] not in frame_positions:
                valid = tuple(frame_positions) if frame_positions else ()
                raise UnknownNameError(f"frame of rotor {i + 1}", e["frame"], valid)
            pos, axis = frame_positions[e["frame"]]
        else:
            if "position" not in e:
                raise InputError(f"rotor {i + 1} needs 'position' (or 'frame')")
            pos = _listed3(e["position"], f"rotor {i + 1} position [m]")
            distance = math.hypot(*pos)
            if distance > _MAX_ROTOR_DISTANCE:
                raise InputError(f"rotor {i + 1} position {list(pos)} is {distance:.4g} m from B: positions are in metres "
                                 "(millimetres divided by 1000), in the frame of the URDF's root link")
            if "quaternion_xyzw" in e and "axis" in e:
                raise InputError(f"rotor {i + 1}: give 'axis' or 'quaternion_xyzw', not both")
            if "quaternion_xyzw" in e:
                q = e["quaternion_xyzw"]
                if isinstance(q, (str, bytes, Mapping)) or not isinstance(q, Sequence) or len(q) != 4:
                    raise InputError(f"rotor {i + 1} quaternion_xyzw must be a list of 4 numbers [x, y, z, w], got {q!r}")
                axis = _quat_axis(q)
            else:
                axis = _listed3(e.get("axis", (0.0, 0.0, 1.0)), f"rotor {i + 1} axis")
                norm = math.hypot(*axis)
                if abs(norm - 1.0) > _AXIS_NORM_TOL:
                    unit = [round(x / norm, 6) for x in axis] if norm > 0 else "a non-zero vector"
                    raise InputError(f"rotor {i + 1} axis {list(axis)} has norm {norm:.6g}: give the unit thrust direction "
                                     f"in B (here {unit})")
        out.append(Rotor(tuple(pos), tuple(axis), spin, e.get("kappa", 0.0), e.get("f_min", 0.0), e.get("f_max", math.inf),
                         str(e.get("name", e.get("frame", f"rotor_{i + 1}")))))
    return tuple(out)


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
