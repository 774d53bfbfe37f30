"""Named platforms: a registry (:data:`PLATFORMS`) of loaders, filled by the core and by plug-ins.

=========================  ==========================================================================
name                       what
=========================  ==========================================================================
``q-prr``                  the thesis's Q-PRR ("+" layout; ``layout="x"`` for "X"), registered by the
                           thesis plug-in (:mod:`qprr.thesis`, :func:`qprr.thesis.register`)
``borinot_flying_arm_2``   example-robot-data: a coplanar hexarotor (2.9 kg) with a 2-DOF arm (HEX-RR)
``hextilt_flying_arm_5``   example-robot-data: a tilted, fully actuated hexarotor with a 5-DOF arm
=========================  ==========================================================================

The core never imports the thesis: ``load("q-prr")`` finds the Q-PRR in :data:`PLATFORMS`, where the
thesis plug-in puts it when the registry first misses a name (:mod:`qprr.registry`).

The URDFs of the last two carry no rotors: their rotor descriptions (``qprr/data/*.rotors.toml``)
come from the upstream models the URDFs were made from, cited in each file.  Note that
borinot_flying_arm_2 is a hexarotor (six rotors in its upstream Gazebo model), not a quadrotor.
"""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

import pinocchio as pin

from .errors import InputError, QprrError, UnknownNameError
from .model import Platform, apply_inertials, check_flight, from_urdf
from .registry import Registry
from .rotors import read_rotor_file
from .urdf.inertia import read_inertials

DATA_DIR = Path(__file__).resolve().parent / "data"

_EXAMPLE_ROBOTS = {
    "borinot_flying_arm_2": ("borinot_description/urdf/borinot_flying_arm_2.urdf", "flying_arm_2__ee"),
    "hextilt_flying_arm_5": ("hextilt_description/urdf/hextilt_flying_arm_5.urdf", "flying_arm_5__gripper"),
}
_BARE_MULTIROTORS = {
    "hector": "hector_description/robots/quadrotor_base.urdf",
    "iris": "iris_description/robots/iris_simple.urdf",
}
DEFAULT_PLATFORM = "q-prr"
"""The platform :func:`load`, :func:`resolve`, the command line and the campaigns give without a name: the thesis's
Q-PRR, by name, through :data:`PLATFORMS` (its documented default, ``PLATFORMS.default``).  The one place the core
names the thesis's platform: every other module reads this constant or the registry's default."""
PLATFORMS: Registry = Registry("platform", default=DEFAULT_PLATFORM)
"""Platform name -> loader ``(**options) -> Platform``; the core registers the example-robot-data ones below."""
ROTOR_DYNAMICS: Registry = Registry("rotor-dynamics set", default=DEFAULT_PLATFORM)
"""Platform name -> ``(**overrides) -> RotorDynamics`` (:class:`qprr.sim.actuators.RotorDynamics`)."""
NAMES = PLATFORMS
"""Names accepted by :func:`load`: the keys of :data:`PLATFORMS` (``name in NAMES``, ``", ".join(NAMES)``)."""


def robots_dir() -> Path:
    """Folder of example-robot-data's robot descriptions (installed by the ``example-robot-data`` wheel)."""
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError as exc:  # pragma: no cover - runtime dependency
        raise QprrError("example-robot-data is not installed: pip install example-robot-data") from exc
    path = Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))
    if not path.is_dir():  # pragma: no cover - layout of a future wheel
        raise QprrError(f"example-robot-data robots folder not found at {path}")
    return path


def load(name: str = DEFAULT_PLATFORM, **kwargs) -> Platform:
    """The platform called ``name`` (see the module table; :data:`PLATFORMS`); keyword arguments go to its loader.

    ``load()`` is ``load("q-prr")`` (:data:`DEFAULT_PLATFORM`), looked up in the registry like any
    name: the Q-PRR comes from the thesis plug-in.  ``q-prr`` takes the options of
    :func:`qprr.thesis.load_qprr` (``params``, ``layout``, ``urdf_path``); the example-robot-data
    platforms take ``g`` (default 9.81 m/s^2).
    """
    return PLATFORMS[name](**kwargs)


def _example_robot(name: str):
    """The loader of the example-robot-data platform ``name`` (its URDF and the rotor file of qprr/data)."""

    def loader(**kwargs) -> Platform:
        unknown = set(kwargs) - {"g"}
        if unknown:
            raise UnknownNameError(f"option of platform {name!r}", sorted(unknown)[0], ("g",))
        rel, ee = _EXAMPLE_ROBOTS[name]
        urdf = robots_dir() / rel
        rotors = read_rotor_file(DATA_DIR / f"{name}.rotors.toml")
        prov = {"model": f"example-robot-data {rel}", "rotors": f"qprr/data/{name}.rotors.toml (sources cited in the file)"}
        return from_urdf(urdf, rotors, ee_frame=ee, g=kwargs.get("g", 9.81), name=name, provenance=prov)

    return loader


def _example_rotor_dynamics(name: str):
    """The actuator stage of ``name`` from the ``[motor]`` table of its rotor description."""

    def rotor_dynamics(**overrides):
        from .sim.actuators import rotor_dynamics_from_mapping

        desc = read_rotor_file(DATA_DIR / f"{name}.rotors.toml")
        return rotor_dynamics_from_mapping(desc, load(name).rotors, **overrides)

    return rotor_dynamics


for _name in _EXAMPLE_ROBOTS:
    PLATFORMS.register(_name, _example_robot(_name))
    ROTOR_DYNAMICS.register(_name, _example_rotor_dynamics(_name))
del _name


def rotor_dynamics(name: str = DEFAULT_PLATFORM, **overrides):
    """The actuator stage (:class:`qprr.sim.actuators.RotorDynamics`) of the platform called ``name`` (:data:`ROTOR_DYNAMICS`).

    ``q-prr``: :func:`qprr.thesis.realistic.qprr_rotor_dynamics` (b of the thesis parameters, a chosen
    time constant); the others: the ``[motor]`` table of their rotor description, where it exists
    (borinot_flying_arm_2; hextilt_flying_arm_5 has none: pass ``thrust_factor`` and ``time_constant``).
    ``overrides``: thrust_factor, time_constant, w_min, w_max, initial.
    """
    return ROTOR_DYNAMICS[name](**overrides)


def resolve(
    name: str | None = None,
    *,
    layout: str | None = None,
    urdf: str | Path | None = None,
    rotors: str | Path | None = None,
    ee_frame: str | None = None,
    inertials: str | Path | None = None,
) -> Platform:
    """The platform a command line names: one of :data:`NAMES`, a (2.1) name, or a user's URDF.

    ``urdf`` with ``rotors`` (a TOML rotor file) and an optional ``ee_frame``: :func:`qprr.from_urdf`
    (then ``name`` and ``layout`` must be None).  Otherwise ``name`` (default ``"q-prr"``):
    :func:`load` for a name of :data:`NAMES`, :func:`qprr.build` for a name of formula (2.1) such
    as ``"HEX-RRR"``; ``layout`` ("plus" or "x") for the Q-PRR or a built platform.  An unknown
    name raises :class:`UnknownNameError` listing the valid ones.  ``inertials``: a TOML file of inertial overrides
    (:func:`qprr.urdf.inertia.read_inertials`) applied to the platform's model, its physics checked again.
    """
    if urdf is not None:
        if name is not None or layout is not None:
            raise InputError(
                f"give a platform name ({name!r}) or a URDF ({str(urdf)!r}), not both"
                if name is not None
                else f"layout {layout!r} applies to named platforms, not to a URDF"
            )
        if rotors is None:
            raise InputError(f"the URDF {str(urdf)!r} needs its rotor description: a TOML file (docs/platforms.md)")
        return from_urdf(urdf, rotors if isinstance(rotors, Path) else Path(rotors), ee_frame=ee_frame, inertials=inertials)
    platform = _named(name, layout, rotors, ee_frame)
    if inertials is None:
        return platform
    platform = platform.with_model(apply_inertials(platform.model, read_inertials(inertials), f"inertials {Path(inertials).name}"))
    check_flight(platform, f"platform {platform.name!r} with the inertials of {str(inertials)!r}")
    return platform


def _named(name: str | None, layout: str | None, rotors, ee_frame) -> Platform:
    """The named platform of :func:`resolve`."""
    from .nomenclature import build, parse

    if rotors is not None or ee_frame is not None:
        given = ", ".join(f"{k} = {v!r}" for k, v in (("rotors", rotors), ("ee_frame", ee_frame)) if v is not None)
        raise InputError(
            f"a rotor file (rotors) and an end-effector frame (ee_frame) go with a URDF (urdf=...); named platforms have their own: got {given}"
        )
    name = DEFAULT_PLATFORM if name is None else name
    if name in NAMES:  # a registered platform; a layout goes to its loader, which refuses it if it has none
        return load(name) if layout is None else load(name, layout=layout)
    try:
        parse(name)
    except InputError:
        raise UnknownNameError(
            "platform", name, (*NAMES, "or a (2.1) name such as 'HEX-RRR'", "or a URDF with its rotor file (--urdf FILE --rotors FILE.toml)")
        ) from None
    return build(name, layout=layout)


def multirotor_model(name: str = "hector") -> pin.Model:
    """A free-flyer Pinocchio model of an example-robot-data multirotor without arm (``"hector"`` or ``"iris"``)."""
    if name not in _BARE_MULTIROTORS:
        raise UnknownNameError("multirotor model", name, tuple(_BARE_MULTIROTORS))
    return pin.buildModelFromUrdf(str(robots_dir() / _BARE_MULTIROTORS[name]), pin.JointModelFreeFlyer())
