"""Design search over the thesis nomenclature (2.1): which aerial manipulator should I build?

A study (:class:`DesignSpec`, TOML) names candidate architectures (``Q-PRR``, ``HEX-RRR``...),
their continuous parameters (reach, taper, slider stroke, masses from a material...), the
objectives and constraints taken from the design maps of :mod:`qprr.analysis`, and the effort.
:func:`run_design` evaluates the grid or runs NSGA-II (pymoo or Optuna, extra ``qprr[design]``)
on the campaign backends (local processes, Dask), resumably; :func:`design_report` ranks the designs,
draws the Pareto front and flies the best ones.

=================================  ==================================================================
package                            what
=================================  ==================================================================
:mod:`qprr.design.spec`            :class:`DesignSpec`, :data:`PARAMETERS`, :data:`DESIGN_METRICS`,
                                   :class:`MassModel`
:mod:`qprr.design.model`           :func:`build_candidate`: a design point as a platform
:mod:`qprr.design.evaluate`        the maps of a design, the backend tasks, the closed-loop flight
:mod:`qprr.design.search`          grid and run indices, NSGA-II engines, Pareto dominance
:mod:`qprr.design.engine`          :func:`run_design` (the campaign integration: ``campaign_io``)
:mod:`qprr.design.report`          ranking, figures, :func:`design_report`
:mod:`qprr.design.cli`             ``qprr design run | report | show``
=================================  ==================================================================

Quick start::

    python -m qprr design run examples/design/thesis_architectures.toml --report thesis-report
"""

from .engine import DesignRun, run_design
from .evaluate import evaluate_platform
from .model import Candidate, build_candidate
from .report import design_report, front, ranked
from .search import dominated, front_levels, make_optimiser
from .spec import DESIGN_METRICS, PARAMETERS, DesignSpec, MassModel

__all__ = [
    "DESIGN_METRICS",
    "PARAMETERS",
    "Candidate",
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
