"""Plausibility ranges of the physical inputs of an aerial manipulator, and the unit slips they catch.

A value can be valid for the type checks (finite, positive) and still be in the wrong unit: a
drag/thrust ratio of 16 (millimetres), an arm offset of 300 (millimetres), revolute limits of +-150
(degrees), a link of 1500 (grams).  :class:`Plausibility` holds one range per physical input of a
rotor file, a URDF and a payload (the table of docs/platforms.md); the checks raise
:class:`~qprr.errors.PlausibilityError` naming the input, the value, the likely slip and the way to
accept the value on purpose: ``plausibility=Plausibility(...)`` (``dataclasses.replace`` of
:data:`DEFAULT`) passed to :func:`qprr.from_urdf`, :func:`qprr.model.from_model` or
:func:`qprr.payload.with_payload`.  ``plausibility=None`` keeps the type and physics checks only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

from ..errors import InputError, PlausibilityError


@dataclass(frozen=True)
class Plausibility:
    """Upper bounds of the physical inputs of an aerial manipulator (all SI; docs/platforms.md, "Plausibility ranges").

    rotor_distance_max : rotor centre to B [m] (the largest multirotors span a few metres).
    kappa_max : drag/thrust ratio c/b of a rotor [m] (propellers: 0.005-0.06 m).
    kappa_min : the smallest non-zero drag/thrust ratio [m] (a lower bound: a raw drag coefficient c [N m s^2], ~1e-7,
        written for c/b gives a yaw torque a thousand times too weak; kappa = 0 stays allowed: no drag model).
    rotor_radius_max : propeller radius [m] (the largest multirotor propellers reach about 1 m).
    rotor_time_constant_max : first-order motor time constant [s] (electric motors: 5-100 ms; milliseconds written as
        seconds give 1000x).
    rotor_thrust_max : f_max of one rotor [N] (heavy-lift rotors give a few hundred N).
    thrust_to_weight_max : sum of the rotors' f_max along z_B over the weight m g (racing drones reach 10-15).
    length_max : joint origin offsets and inertial origins of a URDF [m].
    link_mass_max : mass of one URDF link [kg].
    gyration_radius_max : sqrt(I_max / m) of a link or payload [m] (its size; kg mm^2 gives 1000x).
    revolute_limit_max : |lower|, |upper| of a revolute joint [rad] (one turn and a bit: degrees give > 7).
    prismatic_limit_max : |lower|, |upper| of a prismatic joint [m].
    revolute_effort_max : effort bound of a revolute joint [N m].
    prismatic_effort_max : effort bound of a prismatic joint [N].
    joint_damping_max : <dynamics damping> [N m s/rad or N s/m].
    joint_friction_max : <dynamics friction> [N m or N].
    """

    rotor_distance_max: float = 10.0
    kappa_max: float = 0.1
    kappa_min: float = 1e-4
    rotor_radius_max: float = 2.0
    rotor_time_constant_max: float = 0.5
    rotor_thrust_max: float = 1000.0
    thrust_to_weight_max: float = 20.0
    length_max: float = 10.0
    link_mass_max: float = 200.0
    gyration_radius_max: float = 5.0
    revolute_limit_max: float = 7.0
    prismatic_limit_max: float = 10.0
    revolute_effort_max: float = 1000.0
    prismatic_effort_max: float = 10000.0
    joint_damping_max: float = 100.0
    joint_friction_max: float = 1000.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0.0:
                raise InputError(f"Plausibility.{f.name} must be a number > 0 (math.inf: no bound), got {v!r}")


DEFAULT = Plausibility()
"""The ranges of the table in docs/platforms.md."""


def check_plausibility_setting(plausibility) -> Plausibility | None:
    """``plausibility`` if it is a :class:`Plausibility` or None (checks off), else an :class:`InputError`."""
    if plausibility is not None and not isinstance(plausibility, Plausibility):
        raise InputError(
            f"plausibility must be a qprr.urdf.plausibility.Plausibility (or None: no range checks), got "
            f"{type(plausibility).__name__} {plausibility!r:.60}"
        )
    return plausibility


def _refuse(what: str, value: float, field_name: str, bound: float, slip: str) -> None:
    raise PlausibilityError(
        f"{what} = {value!r} is outside the plausible range for an aerial robot (<= {bound:g}): {slip}. "
        f"If you mean it, pass plausibility=dataclasses.replace(qprr.urdf.plausibility.DEFAULT, "
        f"{field_name}=...) "
    )


def check_rotors(rotors: Sequence, plausibility: Plausibility | None, source: str = "the rotor set") -> None:
    """Rotor positions, drag/thrust ratios, propeller radii and thrust bounds within ``plausibility`` (None: no check)."""
    if plausibility is None:
        return
    P = plausibility
    for k, r in enumerate(rotors):
        label = f"{source}: rotor {k + 1} ({r.name!r})"
        d = math.hypot(*r.position_body)
        if d > P.rotor_distance_max:
            _refuse(
                f"{label} distance to B [m]", d, "rotor_distance_max", P.rotor_distance_max, f"positions in millimetres? {d:g} mm = {d / 1000:g} m"
            )
        if r.kappa > P.kappa_max:
            _refuse(
                f"{label} kappa [m]",
                r.kappa,
                "kappa_max",
                P.kappa_max,
                f"a drag/thrust ratio in millimetres? {r.kappa:g} mm = {r.kappa / 1000:g} m (propellers: 0.005-0.06 m)",
            )
        if 0.0 < r.kappa < P.kappa_min:
            raise PlausibilityError(
                f"{label} kappa [m] = {r.kappa!r} is below the plausible range for an aerial robot (>= {P.kappa_min:g}, "
                f"propellers: 0.005-0.06 m): kappa is the drag/thrust ratio c/b that gives the rotors' yaw torque; a raw "
                f"drag coefficient c [N m s^2]? kappa = c / b with b the thrust coefficient [N s^2] (e.g. 1.4e-7 / 8.5e-6 "
                f"= 0.016 m). With it the yaw torque is {P.kappa_min / r.kappa:.3g}x weaker than it should be. If you mean "
                f"it, pass plausibility=dataclasses.replace(qprr.urdf.plausibility.DEFAULT, kappa_min=...)"
            )
        if r.radius is not None and r.radius > P.rotor_radius_max:
            _refuse(
                f"{label} radius [m]",
                r.radius,
                "rotor_radius_max",
                P.rotor_radius_max,
                f"a propeller radius in millimetres? {r.radius:g} mm = {r.radius / 1000:g} m",
            )
        if math.isfinite(r.f_max) and r.f_max > P.rotor_thrust_max:
            _refuse(
                f"{label} f_max [N]",
                r.f_max,
                "rotor_thrust_max",
                P.rotor_thrust_max,
                f"a thrust in grams-force? {r.f_max:g} gf = {r.f_max * 9.80665e-3:.4g} N",
            )


# ------------------------------------------------------------------------- URDF
def _check_joint(joint, P: Plausibility, source: str) -> None:
    """One :class:`qprr.urdf.reader.UrdfJoint`: its origin length, its limits and effort, its dynamics."""
    name, kind = joint.name, joint.kind
    if joint.origin.xyz is not None:
        d = math.hypot(*joint.origin.xyz)
        if d > P.length_max:
            _refuse(
                f"{source}: joint {name!r} <origin xyz> length [m]",
                d,
                "length_max",
                P.length_max,
                f"lengths in millimetres? {d:g} mm = {d / 1000:g} m",
            )
    if joint.limit is not None and kind in ("revolute", "prismatic"):
        _check_limit(joint, P, source)
    for attr, v, bound, field_name in (
        ("damping", joint.damping, P.joint_damping_max, "joint_damping_max"),
        ("friction", joint.friction, P.joint_friction_max, "joint_friction_max"),
    ):
        if v is not None and abs(v) > bound:
            _refuse(
                f"{source}: joint {name!r} <dynamics {attr}>",
                v,
                field_name,
                bound,
                "per-millimetre or per-degree units? URDF dynamics are in SI per radian or per metre",
            )


def _check_limit(joint, P: Plausibility, source: str) -> None:
    """The position limits [rad or m] and the effort [N m or N] of a revolute or prismatic joint."""
    name, kind, limit = joint.name, joint.kind, joint.limit
    for attr, v in (("lower", limit.lower), ("upper", limit.upper)):
        if v is None:
            continue
        if kind == "revolute" and abs(v) > P.revolute_limit_max:
            _refuse(
                f"{source}: revolute joint {name!r} <limit {attr}> [rad]",
                v,
                "revolute_limit_max",
                P.revolute_limit_max,
                f"degrees? {v:g} deg = {math.radians(v):.6g} rad",
            )
        if kind == "prismatic" and abs(v) > P.prismatic_limit_max:
            _refuse(
                f"{source}: prismatic joint {name!r} <limit {attr}> [m]",
                v,
                "prismatic_limit_max",
                P.prismatic_limit_max,
                f"millimetres? {v:g} mm = {v / 1000:g} m",
            )
    eff = limit.effort
    bound, field_name = (P.revolute_effort_max, "revolute_effort_max") if kind == "revolute" else (P.prismatic_effort_max, "prismatic_effort_max")
    if eff is not None and eff > bound:
        unit = "N m" if kind == "revolute" else "N"
        _refuse(
            f"{source}: joint {name!r} <limit effort> [{unit}]",
            eff,
            field_name,
            bound,
            f"N mm or kg cm? {eff:g} N mm = {eff / 1000:g} N m" if kind == "revolute" else f"grams-force? {eff:g} gf = {eff * 9.80665e-3:.4g} N",
        )


def _check_link(link, P: Plausibility, source: str) -> None:
    """One :class:`qprr.urdf.reader.UrdfLink`: its mass, its CoM offset and its radius of gyration."""
    inertial = link.inertial
    if inertial is None:
        return
    name = link.name
    m = inertial.mass if inertial.mass is not None else 0.0  # not a number: refused by the inertial check
    if m > P.link_mass_max:
        _refuse(f"{source}: link {name!r} <mass value> [kg]", m, "link_mass_max", P.link_mass_max, f"grams? {m:g} g = {m / 1000:g} kg")
    d = math.hypot(*inertial.origin.xyz) if inertial.origin.xyz is not None else 0.0
    if d > P.length_max:
        _refuse(
            f"{source}: link {name!r} <inertial><origin xyz> length [m]", d, "length_max", P.length_max, f"millimetres? {d:g} mm = {d / 1000:g} m"
        )
    xx, _, _, yy, _, zz = inertial.inertia
    moments = [v for v in (xx, yy, zz) if v is not None]
    if inertial.has_inertia and m > 0.0 and moments and max(moments) > 0.0:
        radius = math.sqrt(max(moments) / m)
        if radius > P.gyration_radius_max:
            _refuse(
                f"{source}: link {name!r} radius of gyration sqrt(I_max / m) [m]",
                radius,
                "gyration_radius_max",
                P.gyration_radius_max,
                f"an inertia in kg mm^2 or g mm^2? (I_max = {max(moments):g}, m = {m:g}: in kg mm^2 the radius would be {radius / 1000:g} m)",
            )


def check_urdf(urdf, plausibility: Plausibility | None) -> None:
    """Every joint origin, limit, effort, dynamics and every link mass, CoM and inertia of a URDF read by
    :func:`qprr.urdf.reader.parse_urdf` (a :class:`qprr.urdf.reader.UrdfFile`) within ``plausibility`` (None: no
    check); the messages name ``urdf.source``."""
    if plausibility is None:
        return
    for joint in urdf.joints:
        _check_joint(joint, plausibility, urdf.source)
    for link in urdf.links:
        _check_link(link, plausibility, urdf.source)


def check_time_constant(time_constant, plausibility: Plausibility | None, source: str = "motor time constant") -> None:
    """Every motor time constant [s] (one value or one per rotor) within ``plausibility.rotor_time_constant_max``."""
    if plausibility is None:
        return
    values = [float(time_constant)] if isinstance(time_constant, (int, float)) else [float(v) for v in time_constant]
    values = values[:1] if len(set(values)) == 1 else values  # one value for every rotor: named once
    for k, tau in enumerate(values):
        if tau > plausibility.rotor_time_constant_max:
            which = f"{source}" if len(values) == 1 else f"{source} of rotor {k + 1}"
            _refuse(
                f"{which} [s]",
                tau,
                "rotor_time_constant_max",
                plausibility.rotor_time_constant_max,
                f"milliseconds written as seconds? {tau:g} ms = {tau / 1000:g} s (electric motors: 0.005-0.1 s)",
            )


__all__ = ["DEFAULT", "Plausibility", "check_plausibility_setting", "check_rotors", "check_time_constant", "check_urdf"]
