"""The numbers a design is judged on: which design map gives each, its unit and its better direction.

==========================  ======  =========  ==================================================================
name                        unit    better     map (qprr.analysis) and what is taken
==========================  ======  =========  ==================================================================
``hover_volume``            m^3     max        :func:`~qprr.analysis.workspace`: volume swept under hover, yaw
                                               free (W_eb of Thesis (3.3))
``free_hover_volume``       m^3     max        the same over the configurations free of self-collision (the arm
                                               against the body, the propeller discs and itself:
                                               :mod:`qprr.analysis.collision`); computed only for a study that names it
                                               (an objective or a constraint: the check costs time), else NaN
``balance_fraction``        --      max        :func:`~qprr.analysis.balance`: share of the workspace cells (in
                                               B) reached by a configuration with the CoG within ``balance_tol``
                                               of the thrust axis (Thesis (3.79); with a slider, at the slider
                                               position r* of (6.33));
                                               :func:`~qprr.design.evaluate.balanced_share`
``thrust_margin``           N       max        :func:`~qprr.analysis.hover`: smallest thrust margin over the
                                               joint grid, no payload
``payload_at_reach``        kg      max        :func:`~qprr.analysis.capacity`: largest payload held with the
                                               end effector at least ``payload_reach`` from the thrust axis
``manipulability``          m^2     max        :func:`~qprr.analysis.singularity` (position task): median over
                                               the joint grid
``arm_mass``                kg      min        the arm's links
``mass``                    kg      min        the whole platform (the take-off mass)
==========================  ======  =========  ==================================================================

The registry :data:`DESIGN_METRICS` holds them as :class:`DesignMetric` entries; a plug-in adds its own (a function
of the design's maps, docs/extending.md), which every study then measures and may name as an objective or a
constraint.  (The campaign metrics, numbers of a simulated run, are the other registry, :data:`qprr.campaign.METRICS`.)
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..registry import Registry

BETTER = ("max", "min")
"""The directions a design metric improves in."""


@dataclass(frozen=True)
class DesignMetric:
    """A number a design is judged on: ``compute(maps) -> float`` from the design's maps
    (:class:`qprr.design.evaluate.DesignMaps`: the platform, the effort, and the maps of :mod:`qprr.analysis`,
    each computed once on first use and shared by the metrics), its ``unit``, ``better`` ("max" or "min"), a short
    ``label`` and the range it can take (``low``, ``high``; None: unbounded; a constraint outside it is refused).
    ``collision``: it needs the workspace's self-collision check (:mod:`qprr.analysis.collision`), which costs time: measured
    only for a study that names it (an objective or a constraint), else NaN."""

    compute: Callable[[object], float]
    unit: str
    better: str
    label: str
    low: float | None = None
    high: float | None = None
    collision: bool = False

    def __post_init__(self) -> None:
        if not callable(self.compute):
            raise InputError(f"DesignMetric.compute must be a function (maps) -> float, got {self.compute!r}")
        if self.better not in BETTER:
            raise InputError(f"DesignMetric.better must be 'max' or 'min', got {self.better!r}")
        for what in ("unit", "label"):
            if not isinstance(getattr(self, what), str):
                raise InputError(f"DesignMetric.{what} must be a string, got {getattr(self, what)!r}")
        if self.low is not None and self.high is not None and not self.low <= self.high:
            raise InputError(f"DesignMetric range: low must be <= high, got {self.low!r}, {self.high!r}")


def _hover_volume(maps) -> float:
    hv = maps.workspace.regions[0].hover_volume
    return float(hv.measure) if hv is not None else 0.0


def _free_hover_volume(maps) -> float:
    free = maps.workspace.regions[0].free_hover_volume
    return float(free.measure) if free is not None else 0.0


def _balance_fraction(maps) -> float:
    return maps.balanced_share()


def _thrust_margin(maps) -> float:
    return float(maps.hover.min_thrust_margin[0])


def _payload_at_reach(maps) -> float:
    return maps.payload_at_reach()


def _manipulability(maps) -> float:
    return float(np.median(maps.singularity.manipulability))


def _arm_mass(maps) -> float:
    return maps.arm_mass


def _mass(maps) -> float:
    return maps.mass


def _check(name: str, entry: object) -> None:
    if not isinstance(entry, DesignMetric):
        raise InputError(f"design metric {name!r}: register a qprr.design.DesignMetric(compute, unit, better, label), got {type(entry).__name__}")


DESIGN_METRICS: Registry[DesignMetric] = Registry("design metric", default="hover_volume", check=_check)
"""Design metric name -> :class:`DesignMetric`: the module table's, then the plug-ins' (the default: listed first)."""
for _name, _metric in {
    "hover_volume": DesignMetric(_hover_volume, "m^3", "max", "hover workspace volume", 0.0),
    "free_hover_volume": DesignMetric(_free_hover_volume, "m^3", "max", "collision-free hover workspace volume", 0.0, collision=True),
    "balance_fraction": DesignMetric(_balance_fraction, "", "max", "workspace share with the CoG balanced", 0.0, 1.0),
    "thrust_margin": DesignMetric(_thrust_margin, "N", "max", "minimum thrust margin"),
    "payload_at_reach": DesignMetric(_payload_at_reach, "kg", "max", "payload at reach", 0.0),
    "manipulability": DesignMetric(_manipulability, "m^2", "max", "median manipulability", 0.0),
    "arm_mass": DesignMetric(_arm_mass, "kg", "min", "arm mass", 0.0),
    "mass": DesignMetric(_mass, "kg", "min", "take-off mass", 0.0),
}.items():
    DESIGN_METRICS.register(_name, _metric)
del _name, _metric

RANGES = DESIGN_METRICS.derived(lambda m: (m.low, m.high))
"""name -> (lowest, highest) value the metric can take (None: unbounded); a constraint outside it excludes every design."""


def sign(name: str) -> float:
    """+1 for a metric to minimise, -1 for one to maximise (objectives in minimisation form)."""
    return 1.0 if DESIGN_METRICS[name].better == "min" else -1.0


def unit_text(unit: str) -> str:
    """A unit as matplotlib's mathtext draws it: ``m^3`` -> m with a superscript 3, ``m/s^2`` likewise; the rest as is."""
    return re.sub(r"([A-Za-z]+)\^(-?\d+)", lambda m: rf"$\mathrm{{{m.group(1)}}}^{{{m.group(2)}}}$", unit)


def label(name: str) -> str:
    """The axis label of a metric on a figure: its label, its unit (mathtext) and its better direction."""
    m = DESIGN_METRICS[name]
    return f"{m.label} [{unit_text(m.unit)}] ({m.better})" if m.unit else f"{m.label} ({m.better})"
