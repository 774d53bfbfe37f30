"""Mass model of a generated arm: links from their lengths and a material, actuators per joint.

A link's mass is the actuator of the joint at its base plus the tube's linear density times its
length; a prismatic joint adds its rail (linear density times the stroke).  The numbers of
:data:`MATERIALS` and the actuator defaults are *chosen* (typical catalogue values of the parts
named), not measured; a study overrides any of them in its ``[mass]`` table.
"""

from __future__ import annotations

from dataclasses import dataclass

from ._check import number, spec_error, table_keys

MATERIALS = {"carbon": 0.10, "aluminium": 0.25, "pla": 0.18}
"""Linear density [kg/m] of an arm link of each material (a 20 mm tube with its end fittings; chosen)."""

MODES = ("equal-total", "fixed-body")
"""``equal-total``: every design has the take-off mass ``total_mass``, the body gets what the arm leaves;
``fixed-body``: the body has ``body`` kg, the arm adds to it (the total is then an objective/constraint)."""


@dataclass(frozen=True)
class MassModel:
    """Masses [kg] and linear densities [kg/m] of the generated arms (module docstring)."""

    mode: str = "equal-total"
    body: float = 2.0
    link_density: float = MATERIALS["carbon"]
    revolute_actuator: float = 0.082  # a Dynamixel XM430-class servo (82 g)
    prismatic_actuator: float = 0.10  # a servo with its lead-screw carriage
    rail_density: float = 0.40  # a linear guide rail with its screw, per metre of stroke

    def __post_init__(self) -> None:  # checked however it is built (from_mapping or directly)
        if self.mode not in MODES:
            spec_error("mass.mode", self.mode, f"one of {', '.join(MODES)}")
        for k in ("body", "link_density", "revolute_actuator", "prismatic_actuator", "rail_density"):
            object.__setattr__(self, k, number(getattr(self, k), f"mass.{k}", lo=0.0, positive=(k == "body")))

    def link_mass(self, kind: str, length: float, stroke: float = 0.0) -> float:
        """Mass [kg] of the link after a joint of ``kind`` ("R" or "P") of ``length`` [m] (``stroke`` [m] for P)."""
        if kind == "P":
            return self.prismatic_actuator + self.link_density * length + self.rail_density * stroke
        return self.revolute_actuator + self.link_density * length

    @classmethod
    def from_mapping(cls, d) -> MassModel:
        """The ``[mass]`` table: ``mode``, ``body``, ``material`` or ``link_density``, the actuators, ``rail_density``."""
        keys = ("mode", "body", "material", "link_density", "revolute_actuator", "prismatic_actuator", "rail_density")
        d = table_keys(d, "mass", keys)
        out = {}
        mode = d.get("mode", "equal-total")
        if mode not in MODES:
            spec_error("mass.mode", mode, f"one of {', '.join(MODES)}")
        out["mode"] = mode
        if "material" in d and "link_density" in d:
            spec_error("mass.material", d["material"], "give material or link_density, not both")
        if "material" in d:
            if d["material"] not in MATERIALS:
                spec_error("mass.material", d["material"], f"one of {', '.join(MATERIALS)} (or link_density in kg/m)")
            out["link_density"] = MATERIALS[d["material"]]
        for k in ("body", "link_density", "revolute_actuator", "prismatic_actuator", "rail_density"):
            if k in d:
                out[k] = number(d[k], f"mass.{k}", lo=0.0, positive=(k == "body"))
        return cls(**out)

    def to_dict(self) -> dict:
        return {
            "mode": self.mode,
            "body": self.body,
            "link_density": self.link_density,
            "revolute_actuator": self.revolute_actuator,
            "prismatic_actuator": self.prismatic_actuator,
            "rail_density": self.rail_density,
        }
