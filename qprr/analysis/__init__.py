"""Design analysis of an aerial manipulator: maps over the arm's configuration space, for any platform.

=====================================  ==================================================================
map (module)                           what
=====================================  ==================================================================
:func:`workspace` (workspace)          end-effector workspace in B and under hover, with/without chosen
                                       joints (the slider), measure with error bar, boundary, gain
                                       (Thesis (3.1)-(3.3), Fig. 3.14/3.15)
:func:`cog_regions`, :func:`balance`   CoG regions with/without payload; the slider position that puts
(cog)                                  the CoG on the thrust axis (Thesis (3.75)-(3.81), (6.29)-(6.35))
:func:`singularity` (singularity)      det(J J^T) (4.44), manipulability, condition number, singular
                                       set and the distance to it (Thesis (4.42)-(4.48))
:func:`hover` (hover)                  thrusts, thrust margin, attitude authority, hover feasibility,
                                       payload envelope; the rotors' wrench set (wrenchset)
:func:`opspace_model`, :func:`opspace_map` (opspace)
                                       Lambda, mu, p at the end effector (Thesis (5.47)-(5.52));
                                       :func:`opspace_model_xi` in thesis coordinates, some locked
:func:`capacity` (capacity)            largest payload over the workspace and its limiting factor
                                       (Thesis Fig. 6.46 generalised)
=====================================  ==================================================================

Each map takes ``(platform, ...)`` and returns a result dataclass with a ``status``, a
``reason`` and a ``summary()``; figures are in :mod:`qprr.analysis.plots`.  The maps run on
:class:`~qprr.analysis.chain.ArmChain` (batched kinematics and statics of the arm, checked
against Pinocchio to round-off) over joint grids (:mod:`qprr.analysis._common`); measures
come from :mod:`qprr.analysis.voxels`.  Every map's options take ``budget`` (seconds of wall time): the sample
count is then chosen from timed pilot runs (:mod:`qprr.analysis.budget`; the command line's default,
:data:`DEFAULT_BUDGET`).  Command line: ``python -m qprr analyze MAP``.
"""

from ._common import JointGrid, MapStatus, make_grid
from .budget import DEFAULT_BUDGET, SampleChoice
from .capacity import LIMITS, CapacityOptions, CapacityResult, capacity
from .chain import ArmChain, Statics
from .cog import BalanceOptions, CoGBalanceMap, CoGOptions, CoGResult, balance, cog_regions
from .hover import HoverOptions, HoverResult, PayloadLimits, hover
from .opspace import OpSpaceMap, OpSpaceModel, OpSpaceModelXi, OpSpaceOptions, opspace_map, opspace_model, opspace_model_xi
from .singularity import SingularityOptions, SingularityResult, singularity
from .voxels import MeasureEstimate, estimate_measure
from .workspace import WorkspaceOptions, WorkspaceResult, reachable, workspace
from .wrenchset import WrenchSet, wrench_set

__all__ = [
    "DEFAULT_BUDGET",
    "LIMITS",
    "ArmChain",
    "BalanceOptions",
    "CoGBalanceMap",
    "CapacityOptions",
    "CapacityResult",
    "CoGOptions",
    "CoGResult",
    "HoverOptions",
    "HoverResult",
    "JointGrid",
    "MeasureEstimate",
    "OpSpaceMap",
    "OpSpaceModel",
    "OpSpaceModelXi",
    "OpSpaceOptions",
    "PayloadLimits",
    "SampleChoice",
    "SingularityOptions",
    "SingularityResult",
    "Statics",
    "MapStatus",
    "WorkspaceOptions",
    "WorkspaceResult",
    "WrenchSet",
    "balance",
    "capacity",
    "cog_regions",
    "estimate_measure",
    "hover",
    "make_grid",
    "opspace_map",
    "opspace_model",
    "opspace_model_xi",
    "reachable",
    "singularity",
    "workspace",
    "wrench_set",
]
