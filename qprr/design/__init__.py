"""Design search over the thesis nomenclature (2.1) or your own robot: which aerial manipulator should I build?

A study (:class:`DesignSpec`, TOML) names candidate architectures (``Q-PRR``, ``HEX-RRR``...) and
their continuous parameters (reach, taper, slider stroke, masses from a material...), or a URDF and
rotor file with ``${name}`` placeholders and the values of each name (:mod:`qprr.design.template`),
the objectives and constraints taken from the design maps of :mod:`qprr.analysis`, and the effort.
:func:`run_design` evaluates the grid or runs NSGA-II (pymoo or Optuna, extra ``qprr[design]``)
on the campaign backends (local processes, Dask), resumably; :func:`design_report` ranks the designs,
draws the Pareto front and flies the best ones.

=================================  ==================================================================
module                             what
=================================  ==================================================================
:mod:`qprr.design.metrics`         :data:`DESIGN_METRICS` (the registry of :class:`DesignMetric`)
:mod:`qprr.design.template`        a URDF study's robot: placeholders, derived values, rotor ring
:mod:`qprr.design.spec`            :class:`DesignSpec`, :data:`PARAMETERS`, :class:`MassModel`
:mod:`qprr.design.evaluate`        :func:`build_candidate` (a design point as a platform), the maps
                                   of a design, the backend task
:mod:`qprr.design.search`          grid and run indices, Pareto dominance, NSGA-II engines,
                                   the campaign backends, :func:`run_design`
:mod:`qprr.design.report`          ranking, figures, the closed-loop flight, :func:`design_report`
:mod:`qprr.design.cli`             ``qprr design run | report | show``
=================================  ==================================================================

Quick start::

    python -m qprr design run examples/design/thesis_architectures.toml --report thesis-report
"""

from .evaluate import Candidate, build_candidate, evaluate_platform
from .metrics import DESIGN_METRICS, DesignMetric
from .report import design_report, front, ranked
from .search import DesignRun, dominated, front_levels, make_optimiser, run_design
from .spec import PARAMETERS, DesignSpec, MassModel

__all__ = [
    "DESIGN_METRICS",
    "PARAMETERS",
    "Candidate",
    "DesignMetric",
    "DesignRun",
    "DesignSpec",
    "MassModel",
    "build_candidate",
    "dominated",
    "evaluate_platform",
    "front",
    "front_levels",
    "make_optimiser",
    "ranked",
    "design_report",
    "run_design",
]
