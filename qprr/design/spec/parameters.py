"""The continuous parameters of a candidate and how a study gives them: fixed, a grid, or a range to optimise.

========================  =====  ==========================================================================
name                      unit   what
========================  =====  ==========================================================================
``reach``                 m      total length of the revolute links (the arm's reach from its first
                                 revolute joint, straight)
``taper``                 --     length of each revolute link over the previous one (1: equal links;
                                 the thesis's d3/d2 = 0.10/0.18 = 0.556)
``slider_stroke``         m      full stroke of a prismatic joint (limits -stroke/2 .. +stroke/2)
``slider_link``           m      length of the link after a prismatic joint (the thesis's d1)
``mount_height``          m      height of the first joint above B's origin (the thesis's d0)
``rotor_arm_length``      m      rotor distance from z_B (0: the vehicle's default of
                                 :func:`qprr.nomenclature.build`)
``total_mass``            kg     the take-off mass (``equal-total`` mass mode) or the budget
                                 used to size the rotors (``fixed-body``)
``thrust_to_weight``      --     total maximum rotor thrust over total_mass * g (the rotors of every
                                 design give the same total thrust, whatever their number)
========================  =====  ==========================================================================

In a study's ``[parameters]`` table each is a number (fixed), a list (every value, a grid) or
``{low = a, high = b}`` (a range the optimiser explores).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from ._check import number, spec_error

PARAMETERS = {
    "reach": ("m", 0.28, (0.05, 2.0)),
    "taper": ("", 0.556, (0.1, 10.0)),
    "slider_stroke": ("m", 0.08, (0.005, 1.0)),
    "slider_link": ("m", 0.055, (0.005, 1.0)),
    "mount_height": ("m", 0.04, (0.0, 1.0)),
    "rotor_arm_length": ("m", 0.0, (0.0, 2.0)),
    "total_mass": ("kg", 3.5196, (0.1, 100.0)),
    "thrust_to_weight": ("", 2.317, (1.0, 10.0)),
}
"""name -> (unit, default, (smallest, largest) value accepted)."""


@dataclass(frozen=True)
class Parameter:
    """One parameter of a study: ``values`` (one: fixed; several: a grid) or ``low``/``high`` (optimised)."""

    name: str
    values: tuple[float, ...] = ()
    low: float | None = None
    high: float | None = None

    @property
    def optimised(self) -> bool:
        return self.low is not None

    def to_dict(self):
        if self.optimised:
            return {"low": self.low, "high": self.high}
        return list(self.values) if len(self.values) > 1 else self.values[0]


def parse_parameter(name: str, value) -> Parameter:
    """A ``[parameters]`` entry checked against :data:`PARAMETERS` (errors name the key, the value and the fix)."""
    key = f"parameters.{name}"
    if name not in PARAMETERS:
        spec_error(key, value, f"a parameter among {', '.join(PARAMETERS)}")
    unit, _, (lo, hi) = PARAMETERS[name]
    unit = f" {unit}" if unit else ""
    if isinstance(value, Mapping):
        if set(value) != {"low", "high"}:
            spec_error(key, dict(value), "a range {low = a, high = b}")
        a = number(value["low"], f"{key}.low", lo=lo, hi=hi)
        b = number(value["high"], f"{key}.high", lo=lo, hi=hi)
        if not a < b:
            spec_error(key, dict(value), f"low < high (in{unit})")
        return Parameter(name, (), a, b)
    if isinstance(value, (list, tuple)):
        if not value:
            spec_error(key, value, "at least one value")
        vals = tuple(number(v, key, lo=lo, hi=hi) for v in value)
        if len(set(vals)) != len(vals):
            spec_error(key, list(value), "distinct values")
        return Parameter(name, vals)
    return Parameter(name, (number(value, key, lo=lo, hi=hi),))


def default_parameters() -> dict[str, Parameter]:
    return {k: Parameter(k, (d,)) for k, (_, d, _) in PARAMETERS.items()}
