"""The thesis's printed numbers on the design maps of :mod:`qprr.analysis`, for the Q-PRR only.

``qprr analyze`` asks each provider of :data:`qprr.registry.MAP_REFERENCES` (the thesis plug-in registers
:func:`analysis_reference`); the analysis itself never imports the printed forms.  Today one map
has printed numbers to compare with: the singularity map, whose system det(J J^T) (4.44) the
thesis evaluates at r0 = -0.04, 0, 0.04 m as (4.46)-(4.48).
"""

from __future__ import annotations

import numpy as np

from ..analysis._common import MapReference
from ..analysis.singularity import SingularityResult
from ..errors import InputError
from ..model import Platform
from . import printed
from .params import QPRRParams

SINGULARITY_CURVES = ((-0.04, "(4.46)", printed.sol_4_46), (0.0, "(4.47)", printed.sol_4_47), (0.04, "(4.48)", printed.sol_4_48))
"""(r0 [m], equation, printed det(J J^T) as a function of theta2 [rad]), Thesis (4.46)-(4.48)."""


def analysis_reference(map_name: str, platform: Platform, result) -> MapReference | None:
    """The printed numbers to draw on and print with map ``map_name`` of ``platform``, or None.

    None unless ``platform`` is the thesis's Q-PRR (its ``params`` a :class:`QPRRParams`) and the
    thesis prints numbers for that map.  Singularity map: the printed (4.46)-(4.48) against theta2
    (dashed on the figure) and, per curve, the largest |printed - model| over the map's grid at
    that r0 (all theta3): within the printed coefficients' 4-digit rounding (2e-4) for the
    thesis's lengths d0 + d1 = 0.095 m, d2 = 0.18 m.
    """
    if map_name != "singularity" or not isinstance(platform.params, QPRRParams):
        return None
    if not isinstance(result, SingularityResult):
        raise InputError(f"result must be the SingularityResult of the map, got {type(result).__name__}")
    grid = result.grid
    a_r0, a_t2 = platform.arm_names.index("r0"), platform.arm_names.index("theta2")
    r0_axis, t2 = grid.axes[a_r0], grid.axes[a_t2]
    det = result.det_system.reshape(grid.shape)
    curves, lines = {}, []
    for r0, eq, fn in SINGULARITY_CURVES:
        y = np.array([fn(t) for t in t2])
        curves[f"{eq} printed, r0 = {r0:g}"] = (t2, y)
        i = int(np.argmin(np.abs(r0_axis - r0)))
        model = np.moveaxis(np.take(det, i, axis=a_r0), a_t2 - (a_t2 > a_r0), 0)  # theta2 first
        gap = float(np.abs(model - y.reshape((-1,) + (1,) * (model.ndim - 1))).max())
        lines.append(
            f"  thesis {eq}, det(J J^T) printed for r0 = {r0:g} m: max |printed - model| {gap:.2g} "
            f"(model at r0 = {r0_axis[i]:.4g} m, every theta2, theta3 of the grid)"
        )
    return MapReference(curves=curves, lines=tuple(lines))
