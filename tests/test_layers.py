"""Issue 9: the library never imports the thesis's printed forms; only named front ends reach qprr.thesis.

A static audit of every module outside qprr/thesis/ (its import statements, parsed): no import of
``qprr.thesis.printed`` (nor of any thesis module other than the ones the front ends below use),
and each import of ``qprr.thesis`` sits in a command-line or by-name registry entry point.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

FRONT_ENDS = {
    ("qprr/cli.py", "qprr.thesis.comparisons"),  # qprr compare (the Chapter 6 comparisons)
    ("qprr/cli.py", "qprr.thesis.checks"),  # qprr check (every printed equation against the model)
    ("qprr/cli.py", "qprr.thesis.urdf"),  # qprr urdf (regenerates the Q-PRR's URDF)
    ("qprr/platforms.py", "qprr.thesis"),  # qprr.load("q-prr")
    ("qprr/platforms.py", "qprr.thesis.realistic"),  # rotor_dynamics("q-prr")
    ("qprr/scenarios.py", "qprr.thesis.control_scenarios"),  # the scenario registry, by name
    ("qprr/scenarios.py", "qprr.thesis.scenarios"),
}
"""(module, thesis module it imports): each a front end choosing the thesis instance by name."""


def thesis_imports(path: Path) -> dict[str, set[str]]:
    """{qprr.thesis module: names imported from it} of ``path``'s import statements (absolute module names)."""
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    out: dict[str, set[str]] = {}
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            pairs = [(a.name, "") for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level else ""
            pairs = [(".".join(p for p in (base, node.module) if p), a.name) for a in node.names]
        else:
            continue
        for mod, name in pairs:
            if mod == "qprr.thesis" or mod.startswith("qprr.thesis."):
                out.setdefault(mod, set()).add(name)
    return out


def test_library_never_imports_printed_forms():
    found = set()
    for path in sorted((ROOT / "qprr").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("qprr/thesis/"):
            continue
        for mod, names in thesis_imports(path).items():
            assert "printed" not in mod and "printed" not in names, f"{rel} imports the printed forms ({mod}: {sorted(names)})"
            found.add((rel, mod))
    assert found == FRONT_ENDS, sorted(found ^ FRONT_ENDS)
