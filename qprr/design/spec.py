"""Design study specifications: :class:`DesignSpec` (TOML/JSON), the parameters, the mass model.

A study is of one of two kinds (:class:`StudyKind`): architectures of the nomenclature (2.1) with the parameters of
:data:`PARAMETERS` and a :class:`MassModel`, or a ``[robot]`` (:class:`~qprr.design.template.RobotTemplate`) whose
parameters are the names its files' placeholders use (:func:`parse_robot_parameter`).

**Checks.** Validation helpers of design specifications: every error names the key, the value and the fix.

**Mass model.** Mass model of a generated arm: links from their lengths and a material, actuators per joint.

A link's mass is the actuator of the joint at its base plus the tube's linear density times its
length; a prismatic joint adds its rail (linear density times the stroke).  The numbers of
:data:`MATERIALS` and the actuator defaults are *chosen* (typical catalogue values of the parts
named), not measured; a study overrides any of them in its ``[mass]`` table.

**Parameters.** The continuous parameters of a candidate and how a study gives them: fixed, a grid, or a range to optimise.

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

**The study.** A design study: candidate space, objectives, constraints, effort, search (TOML / JSON / dict).

Example (``examples/design/thesis_architectures.toml``)::

    name = "thesis-architectures"
    seed = 2026
    architectures = ["Q-PRR", "Q-RR", "Q-RRR", "HEX-RRR"]   # (2.1) names qprr.build makes
    references = ["q-prr"]                                  # registered platforms evaluated as they are
    objectives = ["hover_volume", "balance_fraction", "thrust_margin", "arm_mass"]
    [parameters]            # a number, a list (grid) or {low, high} (optimised); see PARAMETERS
    reach = 0.28
    [mass]                  # MassModel: mode, body, material / link_density, actuators, rail
    mode = "equal-total"
    [constraints]           # {min = a} / {max = b} on any metric
    thrust_margin = { min = 0.5 }
    [effort]                # samples per map, counting-grid shifts, balance tolerance, payload reach
    samples = 10000
    [search]                # method = "grid" | "nsga2"; optimiser, population, generations
    method = "grid"
    [closed_loop]           # the flight check of the top designs in the report
    top = 3

Every key is checked when the file is read: an error names the key, the value and the fix.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path

from ..errors import InputError, QprrError
from ..platforms import PLATFORMS
from ..validation import as_file
from .metrics import DESIGN_METRICS, RANGES
from .template import RobotTemplate


# ----------------------------------------------------------------------------------------------------- Checks
def spec_error(key: str, value, fix: str):
    """Raise an :class:`InputError` ``key = value: fix``."""
    raise InputError(f"design specification: {key} = {value!r} is not valid; fix: {fix}")


def number(x, key: str, *, lo: float | None = None, hi: float | None = None, positive: bool = False) -> float:
    """``x`` as a finite float in [lo, hi] (> 0 if ``positive``), else :func:`spec_error`."""
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        spec_error(key, x, "a finite number")
    v = float(x)
    if positive and not v > 0.0:
        spec_error(key, x, "a number > 0")
    if lo is not None and v < lo:
        spec_error(key, x, f"a number >= {lo!r}")
    if hi is not None and v > hi:
        spec_error(key, x, f"a number <= {hi!r}")
    return v


def spec_integer(x, key: str, lo: int = 1) -> int:
    if isinstance(x, bool) or not isinstance(x, int) or x < lo:
        spec_error(key, x, f"an spec_integer >= {lo}")
    return int(x)


def table_keys(d, name: str, allowed) -> dict:
    """``d`` as a dict whose keys are all in ``allowed`` (an unknown one fails with the list)."""
    if not isinstance(d, Mapping):
        spec_error(name, d, f"a table with keys among {', '.join(allowed)}")
    for k in d:
        if k not in allowed:
            spec_error(f"{name}.{k}" if name else k, d[k], f"remove it or use one of {', '.join(allowed)}")
    return dict(d)


# ------------------------------------------------------------------------------------------------- Mass model
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


# ------------------------------------------------------------------------------------------------- Parameters
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
    """One parameter of a study: ``values`` (one: fixed; several: a grid; numbers, or words in a URDF study) or
    ``low``/``high`` (optimised); in a URDF study, ``when`` (earlier parameter -> the values for which this one applies;
    empty: always) and ``otherwise`` (what its placeholders get where it does not apply)."""

    name: str
    values: tuple[float | str, ...] = ()
    low: float | None = None
    high: float | None = None
    when: Mapping[str, tuple[float | str, ...]] = field(default_factory=dict)
    otherwise: float | str | None = None

    @property
    def optimised(self) -> bool:
        return self.low is not None

    @property
    def words(self) -> bool:
        """The values are words (a joint type, an axis), not numbers: a table cell of text, never optimised."""
        return any(isinstance(v, str) for v in self.values)

    def applies(self, chosen: Mapping[str, float | str]) -> bool:
        """Whether this parameter applies to a candidate whose earlier parameters have the values ``chosen``."""
        return all(k in chosen and chosen[k] in allowed for k, allowed in self.when.items())

    def to_dict(self):
        if self.optimised:
            short = {"low": self.low, "high": self.high}
        else:
            short = list(self.values) if len(self.values) > 1 else self.values[0]
        if not self.when:
            return short
        out = short if isinstance(short, dict) else {"values": list(self.values)}
        return {**out, "when": {k: list(v) for k, v in self.when.items()}, "otherwise": self.otherwise}


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


RESERVED = ("run", "seed", "kind", "architecture", "name", "generation", "status", "reason", "feasible", "wall_time", "level", "score")
"""Column names of a design table that a URDF study's parameter may not take (nor a design metric's)."""


def _value(v, key: str) -> float | str:
    """A parameter value of a URDF study: a finite number or a word (a joint type, an axis "0 1 0")."""
    if isinstance(v, str):
        if not v.strip() or "\n" in v:
            spec_error(key, v, 'a word on one line (a joint type, an axis such as "0 1 0")')
        return v
    return number(v, key)


def parse_robot_parameter(name: str, value, earlier: Mapping[str, Parameter]) -> Parameter:
    """A ``[parameters]`` entry of a URDF study (module docstring of :mod:`qprr.design.template`): a number, a list of
    numbers or of words, ``{low, high}``, or a table ``{values | low, high, when, otherwise}``; ``when`` names earlier
    parameters and their values."""
    key = f"parameters.{name}"
    if not name.isidentifier() or name in RESERVED or name in DESIGN_METRICS:
        spec_error(key, value, "a placeholder name (letters, digits, _) that is not a column of the table (" + ", ".join(RESERVED) + ", the metrics)")
    d = dict(value) if isinstance(value, Mapping) else {"values": value}
    table_keys(d, key, ("values", "low", "high", "when", "otherwise"))
    if ("values" in d) == ("low" in d or "high" in d):
        spec_error(key, value, "values (a number or a list) or a range low, high; one of them")
    if "values" in d:
        raw = d["values"] if isinstance(d["values"], (list, tuple)) else [d["values"]]
        vals = tuple(_value(v, key) for v in raw)
        if not vals or len(set(vals)) != len(vals) or len({type(v) is str for v in vals}) > 1:
            spec_error(key, d["values"], "at least one value, distinct, all numbers or all words")
        low = high = None
    else:
        low, high, vals = number(d.get("low"), f"{key}.low"), number(d.get("high"), f"{key}.high"), ()
        if not low < high:
            spec_error(key, value, "low < high")
    when = {}
    for k, allowed in table_keys(d.get("when", {}), f"{key}.when", tuple(earlier)).items():
        allowed = tuple(allowed) if isinstance(allowed, (list, tuple)) else (allowed,)
        if earlier[k].optimised or not set(allowed) <= set(earlier[k].values):
            spec_error(f"{key}.when.{k}", allowed, f"values among those of parameters.{k} ({', '.join(map(str, earlier[k].values))})")
        when[k] = allowed
    if when and low is not None:
        spec_error(f"{key}.when", d["when"], "a condition on a listed parameter only (an optimised range applies to every candidate)")
    if bool(when) != ("otherwise" in d):
        spec_error(f"{key}.otherwise", d.get("otherwise"), "the value its placeholders get where it does not apply (with when, and only with it)")
    otherwise = _value(d["otherwise"], f"{key}.otherwise") if when else None
    return Parameter(name, vals, low, high, when, otherwise)


def default_parameters() -> dict[str, Parameter]:
    return {k: Parameter(k, (d,)) for k, (_, d, _) in PARAMETERS.items()}


# -------------------------------------------------------------------------------------------------- The study
OPTIMISERS = ("pymoo", "optuna")
"""Multi-objective optimisers (NSGA-II) a study may use; the first is the default (docs/design.md says why)."""

SEARCH_METHODS = ("grid", "nsga2")
_KEYS = (
    "name",
    "description",
    "seed",
    "architectures",
    "references",
    "objectives",
    "parameters",
    "mass",
    "constraints",
    "effort",
    "search",
    "closed_loop",
    "robot",
)


@dataclass(frozen=True)
class Effort:
    """Evaluation effort: joint-grid ``samples`` per map, ``shifts`` of the measure's counting grid,
    ``balance_tol`` [m] (the thesis's epsilon of (3.79)), ``payload_reach`` [m] of ``payload_at_reach``."""

    samples: int = 10_000
    shifts: int = 4
    balance_tol: float = 1e-3
    payload_reach: float = 0.15

    def __post_init__(self) -> None:  # checked however it is built (the [effort] table or directly)
        object.__setattr__(self, "samples", spec_integer(self.samples, "effort.samples", lo=64))
        object.__setattr__(self, "shifts", spec_integer(self.shifts, "effort.shifts", lo=2))
        object.__setattr__(self, "balance_tol", number(self.balance_tol, "effort.balance_tol", positive=True))
        object.__setattr__(self, "payload_reach", number(self.payload_reach, "effort.payload_reach", lo=0.0))


@dataclass(frozen=True)
class Search:
    """``method``: "grid" (every architecture x every listed value) or "nsga2" (per architecture, the
    ranged parameters optimised by ``optimiser`` over ``generations`` of ``population`` designs)."""

    method: str = "grid"
    optimiser: str = OPTIMISERS[0]
    population: int = 12
    generations: int = 5

    def __post_init__(self) -> None:  # checked however it is built (the [search] table or directly)
        if self.method not in SEARCH_METHODS:
            spec_error("search.method", self.method, f"one of {', '.join(SEARCH_METHODS)}")
        if self.optimiser not in OPTIMISERS:
            spec_error("search.optimiser", self.optimiser, f"one of {', '.join(OPTIMISERS)}")
        object.__setattr__(self, "population", spec_integer(self.population, "search.population", lo=4))
        object.__setattr__(self, "generations", spec_integer(self.generations, "search.generations", lo=1))


@dataclass(frozen=True)
class ClosedLoop:
    """The report's flight check: ``top`` designs fly ``scenario`` with ``controller`` for ``duration`` [s]."""

    top: int = 3
    scenario: str = "hover-reach"
    controller: str = "idc"
    duration: float = 8.0

    def __post_init__(self) -> None:  # checked however it is built (the [closed_loop] table or directly)
        from ..scenarios import SCENARIOS

        object.__setattr__(self, "top", spec_integer(self.top, "closed_loop.top", lo=0))
        if not isinstance(self.scenario, str) or self.scenario not in SCENARIOS or SCENARIOS[self.scenario].platforms is not None:
            spec_error("closed_loop.scenario", self.scenario, "a generic scenario (any platform), e.g. hover-reach")
        if self.controller not in SCENARIOS[self.scenario].controller_names():
            spec_error("closed_loop.controller", self.controller, f"one of {', '.join(SCENARIOS[self.scenario].controller_names())}")
        object.__setattr__(self, "duration", number(self.duration, "closed_loop.duration", positive=True))


class StudyKind(Enum):
    """What a study's candidates are: architectures of the nomenclature (2.1) built by :func:`qprr.nomenclature.build`,
    or the user's own robot, a URDF and rotor file with placeholders (:mod:`qprr.design.template`)."""

    NOMENCLATURE = "nomenclature"
    URDF = "urdf"


@dataclass(frozen=True)
class DesignSpec:
    """A validated design study (module docstring).  :meth:`load` reads TOML/JSON, :meth:`from_mapping` a dict."""

    name: str
    architectures: tuple[str, ...]
    objectives: tuple[str, ...]
    parameters: dict[str, Parameter]
    seed: int = 0
    references: tuple[str, ...] = ()
    mass: MassModel = field(default_factory=MassModel)
    constraints: dict[str, tuple[float | None, float | None]] = field(default_factory=dict)
    effort: Effort = field(default_factory=Effort)
    search: Search = field(default_factory=Search)
    closed_loop: ClosedLoop = field(default_factory=ClosedLoop)
    description: str = ""
    robot: RobotTemplate | None = None

    @property
    def kind(self) -> StudyKind:
        return StudyKind.NOMENCLATURE if self.robot is None else StudyKind.URDF

    @property
    def families(self) -> tuple[str, ...]:
        """What the search runs over, one family at a time: the architectures, or the robot's name (a URDF study)."""
        return self.architectures if self.robot is None else (self.robot.name,)

    @property
    def optimised(self) -> tuple[str, ...]:
        """The parameters given as ranges."""
        return tuple(k for k, p in self.parameters.items() if p.optimised)

    @property
    def swept(self) -> tuple[str, ...]:
        """The parameters given as lists of several values."""
        return tuple(k for k, p in self.parameters.items() if len(p.values) > 1)

    @property
    def fingerprint(self) -> str:
        """A hash of everything that changes the results (not the description or the closed-loop check)."""
        d = self.to_dict()
        d.pop("description")
        d.pop("closed_loop")
        return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()[:16]

    def to_dict(self) -> dict:
        out = {
            "name": self.name,
            "description": self.description,
            "seed": self.seed,
            "architectures": list(self.architectures),
            "references": list(self.references),
            "objectives": list(self.objectives),
            "parameters": {k: p.to_dict() for k, p in self.parameters.items()},
            "mass": self.mass.to_dict(),
            "constraints": {k: {n: v for n, v in zip(("min", "max"), b) if v is not None} for k, b in self.constraints.items()},
            "effort": vars(self.effort).copy(),
            "search": vars(self.search).copy(),
            "closed_loop": vars(self.closed_loop).copy(),
        }
        if self.robot is not None:  # a URDF study: the robot (its files' texts included) instead of the nomenclature's
            del out["architectures"], out["mass"]
            out["robot"] = self.robot.to_dict()
        return out

    @classmethod
    def load(cls, path) -> DesignSpec:
        """Read a ``.toml`` or ``.json`` study (a ``[robot]``'s files are found relative to it)."""
        p = as_file(path, "spec", what="design specification")
        if p.suffix == ".toml":
            try:
                import tomllib
            except ImportError:  # Python 3.10
                import tomli as tomllib
            try:
                data = tomllib.loads(p.read_text())
            except tomllib.TOMLDecodeError as exc:
                spec_error("spec", str(p), f"valid TOML ({exc})")
        elif p.suffix == ".json":
            try:
                data = json.loads(p.read_text())
            except json.JSONDecodeError as exc:
                spec_error("spec", str(p), f"valid JSON ({exc})")
        else:
            spec_error("spec", str(p), "a .toml or .json file")
        return cls.from_mapping(data, base=p.parent)

    @classmethod
    def from_mapping(cls, data: Mapping, base: Path | None = None) -> DesignSpec:
        """Validate a study given as a dict (the TOML tables as nested dicts); ``base``: the folder a ``[robot]``'s
        relative paths start from (default: the working folder)."""
        d = table_keys(data, "", _KEYS)
        name = d.get("name")
        if not isinstance(name, str) or not name.strip() or any(c in name for c in "/\\"):
            spec_error("name", name, "a non-empty study name without slashes")
        seed = spec_integer(d.get("seed", 0), "seed", lo=0)
        refs = _names(d.get("references", []), "references", tuple(PLATFORMS))  # any registered platform, as it is
        objectives = _names(d.get("objectives"), "objectives", tuple(DESIGN_METRICS), need=2)
        if "robot" in d:
            robot, archs, params, mass = _robot_study(d, base)
        else:
            robot, archs, mass = None, _architectures(d.get("architectures")), MassModel.from_mapping(d.get("mass", {}))
            params = default_parameters()
            for k, v in table_keys(d.get("parameters", {}), "parameters", tuple(params)).items():
                params[k] = parse_parameter(k, v)
        constraints = _constraints(d.get("constraints", {}))
        search = _search(d.get("search", {}))
        _check_search(search, params)
        desc = d.get("description", "")
        if not isinstance(desc, str):
            spec_error("description", desc, "a string")
        effort, closed = _effort(d.get("effort", {})), _closed_loop(d.get("closed_loop", {}))
        return cls(name.strip(), archs, objectives, params, seed, refs, mass, constraints, effort, search, closed, desc, robot)


def _check_search(search: Search, params: dict[str, Parameter]) -> None:
    """Ranges need NSGA-II, NSGA-II needs a range and takes no list of several values (it varies the ranges only)."""
    ranged = [k for k, p in params.items() if p.optimised]
    listed = [k for k, p in params.items() if len(p.values) > 1]
    if search.method == "grid" and ranged:
        spec_error(
            f"parameters.{ranged[0]}",
            params[ranged[0]].to_dict(),
            'a number or a list for search.method = "grid" (ranges need search.method = "nsga2")',
        )
    if search.method == "nsga2" and not ranged:
        spec_error("search.method", "nsga2", 'give at least one parameter as a range {low, high}, or use method = "grid"')
    if search.method == "nsga2" and listed:
        spec_error(
            f"parameters.{listed[0]}",
            params[listed[0]].to_dict(),
            'one value or a range {low, high} for search.method = "nsga2" (a list needs "grid")',
        )


def _robot_study(d: Mapping, base: Path | None) -> tuple[RobotTemplate, tuple, dict[str, Parameter], MassModel]:
    """The robot, (no architectures), the parameters and (the default mass model, unused) of a URDF study."""
    for k in ("architectures", "mass"):
        if k in d:
            spec_error(
                k,
                d[k],
                "remove it: a study with a [robot] evaluates that robot (the nomenclature's architectures and mass model are for generated arms)",
            )
    robot = RobotTemplate.from_mapping(d["robot"], base)
    raw = d.get("parameters", {})
    if not isinstance(raw, Mapping) or not raw:
        spec_error("parameters", raw, "a table giving each placeholder of the robot's files its values")
    params: dict[str, Parameter] = {}
    for k, v in raw.items():
        params[k] = parse_robot_parameter(k, v, params)
    used = robot.used()
    for k in params:
        if k not in used:
            spec_error(f"parameters.{k}", params[k].to_dict(), f"remove it, or use ${{{k}}} in the robot's files (it appears in none)")
    for k in robot.derived:
        if k in params:
            spec_error(f"robot.derived.{k}", robot.derived[k], f"another name: {k} is a parameter")
    for k, where in used.items():
        if k not in params and k not in robot.derived:
            spec_error("parameters", sorted(params), f"give {k} a value: {where} uses it")
    return robot, (), params, MassModel()


def _names(value, key: str, valid: tuple[str, ...], need: int = 0) -> tuple[str, ...]:
    if not isinstance(value, (list, tuple)) or len(value) < need:
        spec_error(key, value, f"a list of at least {need} names among {', '.join(valid)}" if need else f"a list of names among {', '.join(valid)}")
    for v in value:
        if v not in valid:
            spec_error(key, v, f"names among {', '.join(valid)}")
    if len(set(value)) != len(value):
        spec_error(key, list(value), "each name once")
    return tuple(value)


def _architectures(value) -> tuple[str, ...]:
    from ..nomenclature import UAV_ROTORS, parse

    if not isinstance(value, (list, tuple)) or not value:
        spec_error("architectures", value, 'a non-empty list of (2.1) names such as ["Q-PRR", "HEX-RRR"]')
    out = []
    for a in value:
        try:
            d = parse(a)
        except QprrError as exc:
            spec_error("architectures", a, f"a (2.1) name ({exc})")
        if d.n_uav != 1 or d.n_arms != 1 or d.uav not in UAV_ROTORS or set(d.joints) - set("RP") or "R" not in d.joints:
            spec_error(
                "architectures",
                a,
                "one multirotor (Q, HEX, OCT) and one arm of R and P joints with at least one R "
                "(qprr.build makes no other; several vehicles or arms, cables and helicopters are not built)",
            )
        if d.joints.count("P") > 1:
            spec_error("architectures", a, "at most one P joint (the slider parameters describe one)")
        out.append(d.name.strip().upper())
    if len(set(out)) != len(out):
        spec_error("architectures", list(value), "each architecture once")
    return tuple(out)


def _constraints(value) -> dict:
    out = {}
    for k, v in table_keys(value, "constraints", tuple(DESIGN_METRICS)).items():
        b = table_keys(v, f"constraints.{k}", ("min", "max"))
        if not b:
            spec_error(f"constraints.{k}", v, "{min = a} and/or {max = b}")
        lo = number(b["min"], f"constraints.{k}.min") if "min" in b else None
        hi = number(b["max"], f"constraints.{k}.max") if "max" in b else None
        if lo is not None and hi is not None and not lo <= hi:
            spec_error(f"constraints.{k}", v, "min <= max")
        low, high = RANGES[k]
        unit = DESIGN_METRICS[k].unit
        if hi is not None and low is not None and hi < low:
            spec_error(f"constraints.{k}.max", hi, f"a bound >= {low:g} {unit}: {k} is never below {low:g}, so max = {hi:g} excludes every design")
        if lo is not None and high is not None and lo > high:
            spec_error(f"constraints.{k}.min", lo, f"a bound <= {high:g}: {k} is never above {high:g}, so min = {lo:g} excludes every design")
        out[k] = (lo, hi)
    return out


def _effort(value) -> Effort:
    return Effort(**table_keys(value, "effort", ("samples", "shifts", "balance_tol", "payload_reach")))


def _search(value) -> Search:
    return Search(**table_keys(value, "search", ("method", "optimiser", "population", "generations")))


def _closed_loop(value) -> ClosedLoop:
    return ClosedLoop(**table_keys(value, "closed_loop", ("top", "scenario", "controller", "duration")))
