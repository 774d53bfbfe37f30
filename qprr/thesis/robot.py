"""The Q-PRR as a :class:`qprr.model.Platform`: its rotors, its loader and the check that URDF and parameters agree.

Re-exported by :mod:`qprr.thesis`; the thesis's modules import from here (not from the package's ``__init__``).
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError, UnknownNameError
from ..model import Platform, from_urdf
from ..rotors import Rotor
from .params import LAYOUTS, VARIANTS, QPRRParams, thesis_params
from .urdf import URDF_PATH, build_urdf

ARM_JOINTS = ("r0", "theta2", "theta3")
"""The Q-PRR's arm joints (URDF names), Thesis Sec. 3.2.1."""
EE_FRAME = "end_effector"


def rotor_set(params: QPRRParams, layout: str = "plus") -> tuple[Rotor, ...]:
    """The Q-PRR's four rotors in ``layout`` ("plus": Thesis (3.34)-(3.36); "x"), thrust along z_B.

    kappa = c/b, bounds [thrust_min, thrust_max] from the parameters; names ``rotor_<layout>_<i>``
    as the URDF frames.
    """
    if not isinstance(params, QPRRParams):
        raise InputError(f"params must be a QPRRParams, got {type(params).__name__}")
    return tuple(
        Rotor(r.position, (0.0, 0.0, 1.0), r.spin, params.kappa, params.thrust_min, params.thrust_max, f"rotor_{layout}_{i}")
        for i, r in enumerate(params.rotors(layout), start=1)
    )


def load_qprr(params: QPRRParams | str | None = None, *, layout: str = "plus", urdf_path: Path | str | None = None) -> Platform:
    """The Q-PRR as a :class:`~qprr.model.Platform` (free flyer, nq = 10, nv = 9).

    ``params``: a :class:`QPRRParams`, a variant name (``"thesis"`` default: Hypothesis 1;
    ``"cad"``: Table 3.1 CoMs and the arm base as a body), or None.  ``layout``: ``"plus"``
    (Thesis (3.36)) or ``"x"``.  With default parameters the committed ``urdf/qprr.urdf`` is
    read for the "plus" layout, otherwise the URDF is generated from ``params`` (its rotor
    visuals on the ``layout``'s frames); ``urdf_path`` reads another file,
    which must describe the same robot (its masses are checked against ``params``).
    """
    if params is None:
        params = thesis_params()
    elif isinstance(params, str):
        if params not in VARIANTS:
            raise UnknownNameError("parameter variant", params, tuple(VARIANTS))
        params = VARIANTS[params]()
    elif not isinstance(params, QPRRParams):
        raise InputError(f"params must be a QPRRParams, a variant name or None, got {type(params).__name__}")
    if layout not in LAYOUTS:
        raise UnknownNameError("layout", layout, LAYOUTS)
    if urdf_path is not None:
        urdf = Path(urdf_path)
    elif params == thesis_params() and layout == "plus" and URDF_PATH.exists():
        urdf = URDF_PATH
    else:
        urdf = build_urdf(params, layout=layout)
    platform = from_urdf(
        urdf,
        rotor_set(params, layout),
        ee_frame=EE_FRAME,
        g=params.g,
        name=f"Q-PRR ({params.variant}, {layout})",
        params=params,
        provenance={"parameters": "qprr.thesis.params (Tables 3.1-3.3 and chosen values, each with its provenance)"},
        allow_nonphysical=bool(params.nonphysical),
    )
    _check_agrees(platform, params)
    return platform


def _check_agrees(platform: Platform, params: QPRRParams) -> None:
    """The URDF and the parameters must describe the same robot: raise :class:`InputError` naming the first parameter
    the URDF contradicts, with both values (arm joints, lengths d0..d3, masses, joint limits, rotor positions)."""
    source = platform.provenance.get("model", "the URDF")
    if platform.arm_names != ARM_JOINTS:
        raise InputError(f"{source}: the arm joints {platform.arm_names} are not the Q-PRR's {ARM_JOINTS} (is it the Q-PRR's URDF?)")
    model = platform.model
    j = {name: model.getJointId(name) for name in ARM_JOINTS}
    ee = model.frames[platform.ee_frame]
    rail = params.rail.mass if params.rail is not None else 0.0
    lengths = {
        "d0": float(model.jointPlacements[j["r0"]].translation[2]),
        "d1": float(model.jointPlacements[j["theta2"]].translation[2]),
        "d2": float(model.jointPlacements[j["theta3"]].translation[2]),
        "d3": float(ee.placement.translation[2]) if ee.parentJoint == j["theta3"] else float("nan"),
    }
    quantities = [(name, getattr(params, name), lengths[name], "m") for name in ("d0", "d1", "d2", "d3")]
    quantities += [
        ("multirotor_mass" + (" + rail mass" if rail else ""), params.multirotor_mass + rail, float(model.inertias[1].mass), "kg"),
        ("links[0].mass (link1)", params.links[0].mass, float(model.inertias[j["r0"]].mass), "kg"),
        ("links[1].mass (link2)", params.links[1].mass, float(model.inertias[j["theta2"]].mass), "kg"),
        ("links[2].mass (link3)", params.links[2].mass, float(model.inertias[j["theta3"]].mass), "kg"),
    ]
    for k, (name, lim) in enumerate(
        (("r0_limits", params.r0_limits), ("theta2_limits", params.theta2_limits), ("theta3_limits", params.theta3_limits))
    ):
        joint = platform.arm[k]
        quantities += [(f"{name}[0]", lim[0], joint.lower, ""), (f"{name}[1]", lim[1], joint.upper, "")]
        quantities += [
            (f"effort_limits[{k}]", params.effort_limits[k], joint.effort, ""),
            (f"velocity_limits[{k}]", params.velocity_limits[k], joint.velocity, ""),
        ]
    for layout in LAYOUTS:
        for i, rotor in enumerate(params.rotors(layout), start=1):
            frame = f"rotor_{layout}_{i}"
            if model.existFrame(frame):
                f = model.frames[model.getFrameId(frame)]
                if f.parentJoint == 1:
                    p = f.placement.translation
                    quantities += [(f"arm_length (rotor {frame} at x, y)", math.hypot(*rotor.position[:2]), math.hypot(p[0], p[1]), "m")]
    for name, value, in_urdf, unit in quantities:
        if not abs(value - in_urdf) <= 1e-9 * max(1.0, abs(value)):
            raise InputError(
                f"params.{name} = {value!r}{' ' + unit if unit else ''} contradicts {source}, which has {in_urdf!r}: "
                "give parameters that describe this URDF (or no urdf_path: the URDF is then generated from them)"
            )
    if abs(platform.total_mass - params.total_mass) > 1e-9 * params.total_mass:
        raise InputError(f"{source}: total mass {platform.total_mass!r} kg differs from the parameters' {params.total_mass!r} kg")


def params_of(platform: Platform) -> QPRRParams:
    """The thesis parameters of a Q-PRR platform; InputError for any other platform."""
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    if not isinstance(platform.params, QPRRParams):
        raise InputError(f"platform {platform.name!r} is not the thesis's Q-PRR (its params are {type(platform.params).__name__})")
    return platform.params
