"""What only the thesis has: the Q-PRR's parameters, its printed equations, algorithms and scenarios.

K. Bouzgou, *Contribution a l'architecture, la modelisation et la commande d'un bras
manipulateur aerien*, Universite Paris-Saclay, 2021.  Equation numbers refer to it.

* :func:`load` - the Q-PRR as a :class:`qprr.platform.Platform` (the flagship instance of the
  generic core), from :mod:`qprr.thesis.params` (Tables 3.1-3.3 and the values the thesis does
  not print, each with its provenance) and the URDF of :mod:`qprr.thesis.urdf`;
* :mod:`qprr.thesis.printed` - closed forms as printed and corrected; :mod:`qprr.thesis.checks`
  (``qprr check``) tests every one against the model; :mod:`qprr.thesis.symbolic` is the
  independent sympy Lagrangian;
* the thesis's own algorithms: the analytic IGM (Alg. 3-5, :mod:`qprr.thesis.igm`), the CoG
  stabiliser BSG (:mod:`qprr.thesis.bsg`), the chapter-6 missions, gain tables and scenarios;
* beyond the thesis, on the Q-PRR: :mod:`qprr.thesis.control_scenarios` (point-to-point, Annex A,
  aggressive reach, realistic), :mod:`qprr.thesis.realistic` (its motor, drag, friction and wind
  values), :mod:`qprr.thesis.comparisons` (``qprr compare``).

The library (everything outside this package) never imports from here, except the registry of
named platforms (``qprr.load("q-prr")``) which calls :func:`load`.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError, UnknownNameError
from ..platform import Platform, from_urdf
from ..rotors import Rotor
from .params import LAYOUTS, VARIANTS, QPRRParams, cad_params, thesis_params
from .urdf import URDF_PATH, build_urdf

ARM_JOINTS = ("r0", "theta2", "theta3")
"""The Q-PRR's arm joints (URDF names), Thesis Sec. 3.2.1."""
EE_FRAME = "end_effector"


def rotor_set(params: QPRRParams, layout: str = "plus") -> tuple[Rotor, ...]:
    """The Q-PRR's four rotors in ``layout`` ("plus": Thesis (3.34)-(3.36); "x"), thrust along z_B.

    kappa = c/b, bounds [thrust_min, thrust_max] from the parameters; names ``rotor_<layout>_<i>``
    as the URDF frames.
    """
    return tuple(
        Rotor(r.position, (0.0, 0.0, 1.0), r.spin, params.kappa, params.thrust_min, params.thrust_max, f"rotor_{layout}_{i}")
        for i, r in enumerate(params.rotors(layout), start=1)
    )


def load(params: QPRRParams | str | None = None, *, layout: str = "plus", urdf_path: Path | str | None = None) -> Platform:
    """The Q-PRR as a :class:`~qprr.platform.Platform` (free flyer, nq = 10, nv = 9).

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
    platform = from_urdf(urdf, rotor_set(params, layout), ee_frame=EE_FRAME, g=params.g,
                         name=f"Q-PRR ({params.variant}, {layout})", params=params,
                         provenance={"parameters": "qprr.thesis.params (Tables 3.1-3.3 and chosen values, each with its provenance)"},
                         allow_nonphysical=bool(params.nonphysical))
    _check_agrees(platform, params)
    return platform


def _check_agrees(platform: Platform, params: QPRRParams) -> None:
    """The URDF and the parameters must describe the same robot (arm joints, total mass, lengths)."""
    if platform.arm_names != ARM_JOINTS:
        raise InputError(f"the URDF's arm joints {platform.arm_names} are not the Q-PRR's {ARM_JOINTS}")
    if abs(platform.total_mass - params.total_mass) > 1e-9 * params.total_mass:
        raise InputError(f"the URDF's total mass {platform.total_mass!r} kg differs from the parameters' {params.total_mass!r} kg")
    import pinocchio as pin

    data = platform.data()
    q = platform.neutral_q()
    pin.framesForwardKinematics(platform.model, data, q)
    p_ee = data.oMf[platform.ee_frame].translation
    height = params.d0 + params.d1 + params.d2 + params.d3
    if abs(p_ee[2] - height) > 1e-9 or abs(p_ee[0]) > 1e-9:
        raise InputError(f"the URDF's end effector sits at {p_ee.tolist()} m with the arm straight; the parameters put it at "
                         f"[0, 0, d0 + d1 + d2 + d3 = {height!r}] m")


def params_of(platform: Platform) -> QPRRParams:
    """The thesis parameters of a Q-PRR platform; InputError for any other platform."""
    if not isinstance(platform.params, QPRRParams):
        raise InputError(f"platform {platform.name!r} is not the thesis's Q-PRR (its params are {type(platform.params).__name__})")
    return platform.params


__all__ = ["ARM_JOINTS", "EE_FRAME", "LAYOUTS", "QPRRParams", "cad_params", "load", "params_of", "rotor_set", "thesis_params"]
