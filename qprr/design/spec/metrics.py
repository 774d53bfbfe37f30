"""The numbers a design is judged on: which design map gives each, its unit and its better direction.

==========================  ======  =========  ==================================================================
name                        unit    better     map (qprr.analysis) and what is taken
==========================  ======  =========  ==================================================================
``hover_volume``            m^3     max        :func:`~qprr.analysis.workspace`: volume swept under hover, yaw
                                               free (W_eb of Thesis (3.3))
``free_hover_volume``       m^3     max        the same over the configurations free of self-collision (the arm
                                               against the body, the propeller discs and itself:
                                               :mod:`qprr.collision`); computed only for a study that names it
                                               (an objective or a constraint: the check costs time), else NaN
``balance_fraction``        --      max        :func:`~qprr.analysis.balance`: share of the workspace cells (in
                                               B) reached by a configuration with the CoG within ``balance_tol``
                                               of the thrust axis (Thesis (3.79); with a slider, at the slider
                                               position r* of (6.33));
                                               :func:`~qprr.design.evaluate.maps.balanced_share`
``thrust_margin``           N       max        :func:`~qprr.analysis.hover`: smallest thrust margin over the
                                               joint grid, no payload
``payload_at_reach``        kg      max        :func:`~qprr.analysis.capacity`: largest payload held with the
                                               end effector at least ``payload_reach`` from the thrust axis
``manipulability``          m^2     max        :func:`~qprr.analysis.singularity` (position task): median over
                                               the joint grid
``arm_mass``                kg      min        the arm's links
``mass``                    kg      min        the whole platform (the take-off mass)
==========================  ======  =========  ==================================================================
"""

from __future__ import annotations

METRICS = {
    "hover_volume": ("m^3", "max", "hover workspace volume"),
    "free_hover_volume": ("m^3", "max", "collision-free hover workspace volume"),
    "balance_fraction": ("", "max", "workspace share with the CoG balanced"),
    "thrust_margin": ("N", "max", "minimum thrust margin"),
    "payload_at_reach": ("kg", "max", "payload at reach"),
    "manipulability": ("m^2", "max", "median manipulability"),
    "arm_mass": ("kg", "min", "arm mass"),
    "mass": ("kg", "min", "take-off mass"),
}
"""name -> (unit, "max" or "min", label)."""

RANGES = {
    "hover_volume": (0.0, None),
    "free_hover_volume": (0.0, None),
    "balance_fraction": (0.0, 1.0),
    "thrust_margin": (None, None),
    "payload_at_reach": (0.0, None),
    "manipulability": (0.0, None),
    "arm_mass": (0.0, None),
    "mass": (0.0, None),
}
"""name -> (lowest, highest) value the metric can take (None: unbounded); a constraint outside it excludes every design."""


def sign(name: str) -> float:
    """+1 for a metric to minimise, -1 for one to maximise (objectives in minimisation form)."""
    return 1.0 if METRICS[name][1] == "min" else -1.0


def label(name: str) -> str:
    unit, better, text = METRICS[name]
    return f"{text} [{unit}] ({better})" if unit else f"{text} ({better})"
