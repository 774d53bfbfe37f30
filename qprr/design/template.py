"""The user's own robot as a design space: a URDF and a rotor file with ``${name}`` placeholders.

A study's ``[robot]`` table names a URDF and a rotor file (TOML) written with placeholders of
Python's :class:`string.Template` (``<origin xyz="0 0 -${upper_arm}"/>``); its ``[parameters]``
give each name's values (a number, a list, a range, or words such as joint types and axes).  A
candidate is the files with every placeholder replaced, loaded by :func:`qprr.model.from_urdf` with
every check of a user's robot: what the instantiated files say is what is evaluated, or the design
is a failed row with the loader's reason.

Values that follow from the parameters (a link's centre of mass at half its length, a rod's inertia
m L^2 / 12, a rotor's x = arm / sqrt 2) are ``[robot.derived]`` expressions: numbers, names, ``+ - *
/ **``, parentheses, ``sqrt``, ``sin``, ``cos``, ``tan``, ``pi`` (parsed into a tree and evaluated
node by node by :func:`evaluate_expression`; no Python code is run).  Instead of a rotor file, a
``[robot.rotor_ring]`` table generates ``count`` rotors on a circle (:func:`qprr.rotors.ring`), so
that the rotor count can be a design variable; each of its fields is a number or an expression.

A parameter may apply only to some candidates: ``when = {elbow_type = "prismatic"}`` (the values of
earlier parameters for which it applies) and ``otherwise`` (what its placeholders get elsewhere).
Where it does not apply it is not varied, and the results table leaves its cell empty.
"""

from __future__ import annotations

import ast
import math
import string
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError
from ..model import from_urdf
from ..rotors import RingSpec, ring

FUNCTIONS = {"sqrt": math.sqrt, "sin": math.sin, "cos": math.cos, "tan": math.tan}
"""The functions an expression may call (one argument each, radians for the angles)."""

CONSTANTS = {"pi": math.pi}
"""The names an expression may use besides the study's parameters and derived values."""

ROBOT_KEYS = ("urdf", "urdf_text", "rotors", "rotors_text", "rotor_ring", "name", "ee_frame", "derived")
"""Keys of a study's ``[robot]`` table (``*_text``: the files' contents, written by a saved study so that it is complete)."""

RING_FIELDS = ("count", "radius", "height", "start_angle", "kappa", "f_min", "f_max", "tilt")
"""Fields of ``[robot.rotor_ring]`` (:class:`qprr.rotors.RingSpec` and the ring's size; SI units, radians)."""


def _refuse(key: str, value, fix: str):
    raise InputError(f"design specification: {key} = {value!r} is not valid; fix: {fix}")


def placeholders(text: str, source: str) -> tuple[str, ...]:
    """The names of the ``${name}`` / ``$name`` placeholders of ``text``, in order of first use; a ``$`` that starts
    none (``$$`` is a literal dollar) is refused with its line."""
    names: list[str] = []
    for m in string.Template.pattern.finditer(text):
        name = m.group("named") or m.group("braced")
        if m.group("invalid") is not None:
            line = text.count("\n", 0, m.start()) + 1
            _refuse(
                source,
                f"line {line}: {text.splitlines()[line - 1].strip()}",
                "a placeholder ${name} (a letter or _ then letters, digits, _) or $$ for a dollar",
            )
        if name and name not in names:
            names.append(name)
    return tuple(names)


def substitute(text: str, values: Mapping[str, float | str]) -> str:
    """``text`` with every placeholder replaced by its value (a float by its shortest exact decimal form)."""
    return string.Template(text).substitute({k: repr(float(v)) if isinstance(v, (int, float)) else str(v) for k, v in values.items()})


def expression_names(expr: str, key: str) -> tuple[str, ...]:
    """The names an expression uses (its syntax checked: :func:`evaluate_expression`)."""
    tree = _parse(expr, key)
    return tuple(dict.fromkeys(n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and n.id not in FUNCTIONS and n.id not in CONSTANTS))


def _parse(expr: str, key: str) -> ast.Expression:
    if not isinstance(expr, str):
        _refuse(key, expr, 'an arithmetic expression in a string, e.g. "upper_arm / 2"')
    try:
        tree = ast.parse(expr, mode="eval")
    except SyntaxError:
        _refuse(key, expr, "an arithmetic expression of numbers, names, + - * / **, parentheses, sqrt, sin, cos, tan, pi")
    for node in ast.walk(tree):
        if not _allowed(node):
            _refuse(key, expr, f"only numbers, names, + - * / **, parentheses and {', '.join(FUNCTIONS)} of one argument")
    return tree


ALLOWED = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Constant, ast.Name, ast.Call, ast.Load)
ALLOWED += (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)
"""The nodes of an expression's syntax tree: numbers, names, the arithmetic operators, calls of :data:`FUNCTIONS`."""


def _allowed(node: ast.AST) -> bool:
    if not isinstance(node, ALLOWED):
        return False
    if isinstance(node, ast.Constant):
        return not isinstance(node.value, bool) and isinstance(node.value, (int, float))
    if isinstance(node, ast.Call):
        return isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS and len(node.args) == 1 and not node.keywords
    return True


def evaluate_expression(expr: str, values: Mapping[str, float | str], key: str) -> float:
    """The value of arithmetic expression ``expr`` with the names of ``values`` (and :data:`CONSTANTS`)."""
    return float(_value(_parse(expr, key).body, values, key, expr))


def _value(node: ast.AST, values: Mapping, key: str, expr: str) -> float:
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        if node.id not in values:
            _refuse(key, expr, f"names among the parameters and derived values defined before it ({', '.join(values) or 'none'}): {node.id!r} is not")
        v = values[node.id]
        if isinstance(v, str):
            _refuse(key, expr, f"{node.id!r} is a word ({v!r}), not a number: arithmetic takes numeric parameters only")
        return float(v)
    if isinstance(node, ast.UnaryOp):
        x = _value(node.operand, values, key, expr)
        return -x if isinstance(node.op, ast.USub) else x
    if isinstance(node, ast.Call):
        x = _value(node.args[0], values, key, expr)
        try:
            return FUNCTIONS[node.func.id](x)
        except ValueError:
            _refuse(key, expr, f"{node.func.id}({x!r}) is undefined for these parameter values")
    a, b = _value(node.left, values, key, expr), _value(node.right, values, key, expr)
    ops = {ast.Add: lambda: a + b, ast.Sub: lambda: a - b, ast.Mult: lambda: a * b, ast.Div: lambda: a / b, ast.Pow: lambda: a**b}
    try:
        out = ops[type(node.op)]()
    except (ZeroDivisionError, OverflowError):
        _refuse(key, expr, f"an expression defined for these parameter values ({dict(values)})")
    if not isinstance(out, float) or not math.isfinite(out):
        _refuse(key, expr, f"an expression with a finite real value for these parameter values ({dict(values)})")
    return out


@dataclass(frozen=True)
class RotorRing:
    """``count`` rotors on a circle (:func:`qprr.rotors.ring`); each field a number or an expression string."""

    fields: Mapping[str, float | str]

    @classmethod
    def from_mapping(cls, d) -> RotorRing:
        if not isinstance(d, Mapping):
            _refuse("robot.rotor_ring", d, f"a table with keys among {', '.join(RING_FIELDS)}")
        for k, v in d.items():
            if k not in RING_FIELDS:
                _refuse(f"robot.rotor_ring.{k}", v, f"remove it or use one of {', '.join(RING_FIELDS)}")
            if isinstance(v, bool) or not isinstance(v, (int, float, str)) or (not isinstance(v, str) and not math.isfinite(v)):
                _refuse(f"robot.rotor_ring.{k}", v, "a number or an expression string")
            if isinstance(v, str):
                expression_names(v, f"robot.rotor_ring.{k}")
        for k in ("count", "radius"):
            if k not in d:
                _refuse("robot.rotor_ring", dict(d), f"give {k} (a number or an expression)")
        return cls(dict(d))

    def names(self) -> tuple[str, ...]:
        used = [n for k, v in self.fields.items() if isinstance(v, str) for n in expression_names(v, f"robot.rotor_ring.{k}")]
        return tuple(dict.fromkeys(used))

    def rotors(self, values: Mapping[str, float | str]):
        """The rotor set at ``values`` (the parameters and derived values)."""
        v = {k: evaluate_expression(x, values, f"robot.rotor_ring.{k}") if isinstance(x, str) else float(x) for k, x in self.fields.items()}
        count = v.pop("count")
        if count != round(count) or count < 1:
            raise InputError(f"robot.rotor_ring.count = {self.fields['count']!r} gives {count!r} rotors: a whole number >= 1")
        radius = v.pop("radius")
        return ring(int(count), radius, RingSpec(**v))


@dataclass(frozen=True)
class RobotTemplate:
    """A study's ``[robot]``: the URDF text with placeholders, the rotor file's text or a :class:`RotorRing`, the derived
    values (name -> expression, in order), the robot's ``name`` and ``ee_frame`` (None: the loader's default); ``urdf``
    and ``rotors``: where the texts were read (for messages)."""

    name: str
    urdf: str
    urdf_text: str
    rotors: str = ""
    rotors_text: str = ""
    ring: RotorRing | None = None
    ee_frame: str | None = None
    derived: Mapping[str, str] = field(default_factory=dict)

    @classmethod
    def from_mapping(cls, d, base: Path | None = None) -> RobotTemplate:
        """The ``[robot]`` table; paths relative to ``base`` (the study file's folder), else to the working folder."""
        if not isinstance(d, Mapping):
            _refuse("robot", d, f"a table with keys among {', '.join(ROBOT_KEYS)}")
        for k in d:
            if k not in ROBOT_KEYS:
                _refuse(f"robot.{k}", d[k], f"remove it or use one of {', '.join(ROBOT_KEYS)}")
        urdf, urdf_text = _file(d, "urdf", base)
        if not ("rotors" in d or "rotors_text" in d) ^ ("rotor_ring" in d):
            _refuse("robot", sorted(d), "give the rotors as a file (rotors = PATH) or as a ring (a [robot.rotor_ring] table), one of them")
        rotors, rotors_text = _file(d, "rotors", base) if "rotor_ring" not in d else ("", "")
        ring = RotorRing.from_mapping(d["rotor_ring"]) if "rotor_ring" in d else None
        name = d.get("name", Path(urdf).name.split(".")[0] if urdf else "robot")
        if not isinstance(name, str) or not name.strip():
            _refuse("robot.name", name, "a non-empty name")
        ee = d.get("ee_frame")
        if ee is not None and (not isinstance(ee, str) or not ee):
            _refuse("robot.ee_frame", ee, "the name of a frame of the URDF")
        derived = d.get("derived", {})
        if not isinstance(derived, Mapping) or not all(isinstance(v, str) for v in derived.values()):
            _refuse("robot.derived", derived, 'a table of name = "expression" (e.g. upper_arm_com = "-upper_arm / 2")')
        for k, v in derived.items():
            expression_names(v, f"robot.derived.{k}")
        placeholders(urdf_text, f"robot.urdf ({urdf})")
        placeholders(rotors_text, f"robot.rotors ({rotors})")
        return cls(name.strip(), urdf, urdf_text, rotors, rotors_text, ring, ee, dict(derived))

    def to_dict(self) -> dict:
        out = {"name": self.name, "urdf": self.urdf, "urdf_text": self.urdf_text}
        if self.ring is None:
            out.update(rotors=self.rotors, rotors_text=self.rotors_text)
        else:
            out["rotor_ring"] = dict(self.ring.fields)
        if self.ee_frame is not None:
            out["ee_frame"] = self.ee_frame
        if self.derived:
            out["derived"] = dict(self.derived)
        return out

    def used(self) -> dict[str, str]:
        """Every name the templates, the derived expressions and the ring use -> where (for the checks of the study)."""
        out: dict[str, str] = {}
        for where, names in (
            (f"the URDF {self.urdf}", placeholders(self.urdf_text, "robot.urdf")),
            (f"the rotor file {self.rotors}", placeholders(self.rotors_text, "robot.rotors")),
            ("robot.rotor_ring", self.ring.names() if self.ring else ()),
            *((f"robot.derived.{k}", expression_names(v, f"robot.derived.{k}")) for k, v in self.derived.items()),
        ):
            for n in names:
                out.setdefault(n, where)
        return out

    def values(self, params: Mapping[str, float | str]) -> dict[str, float | str]:
        """The parameters with the derived values added, each derived expression evaluated on those before it."""
        out = dict(params)
        for k, expr in self.derived.items():
            out[k] = evaluate_expression(expr, out, f"robot.derived.{k}")
        return out

    def platform(self, params: Mapping[str, float | str]):
        """The candidate of ``params`` (every parameter's value, ``otherwise`` ones included): the files instantiated and
        loaded by :func:`qprr.model.from_urdf` (its checks refuse what cannot fly, naming the value)."""
        values = self.values(params)
        urdf = substitute(self.urdf_text, values)
        if self.ring is not None:
            rotors = self.ring.rotors(values)
        else:
            rotors = _toml(substitute(self.rotors_text, values), self.rotors)
        return from_urdf(urdf, rotors, ee_frame=self.ee_frame, name=self.name, provenance={"model": f"{self.urdf} (instantiated)"})


def _file(d: Mapping, key: str, base: Path | None) -> tuple[str, str]:
    """(path as given, text) of the ``[robot]`` file ``key``: its ``key_text`` when given (a saved study), else read."""
    if f"{key}_text" in d:
        text = d[f"{key}_text"]
        if not isinstance(text, str) or not text.strip():
            _refuse(f"robot.{key}_text", text, "the file's text")
        return str(d.get(key, "")), text
    if key not in d or not isinstance(d[key], str):
        _refuse(f"robot.{key}", d.get(key), f"the path of the {key} template (relative to the study file)")
    p = Path(d[key])
    path = p if p.is_absolute() or base is None else base / p
    if not path.is_file():
        _refuse(f"robot.{key}", d[key], f"an existing file ({str(path)!r} is not one)")
    return d[key], path.read_text(encoding="utf-8")


def _toml(text: str, source: str) -> dict:
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(
            f"rotor file {source} with the parameters substituted is not valid TOML ({exc}): quote word values, check the placeholders"
        ) from exc
