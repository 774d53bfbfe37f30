"""Issue 20 item 1: the layers only point down, with no allow-list.

Three layers, from the bottom:

* the core: every module of ``qprr/`` outside ``qprr/thesis/`` and the front ends;
* the thesis plug-in: ``qprr/thesis/`` (it registers into the core's registries, :mod:`qprr.registry`);
* the front ends: the package ``qprr/cli/``, ``qprr/__main__.py`` and every ``cli.py`` of a
  subpackage (the thesis's own ``qprr/thesis/cli.py`` included).

A module imports only from its own layer or the ones below, and the core's front ends reach the
thesis through the registries, never by import.  Checked on the import statements (parsed, anywhere
in a module, deferred imports included), on ``import_module``/``__import__`` calls with a literal
name, and at run time (importing the core loads no thesis module).  No import cycle between modules.

Inside the layers, the order of docs/architecture.md's module map: every module is named by a row of the map (a file,
or its folder), and every import, deferred ones included, points to its own row or one above.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "qprr"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PKG.rglob("*.py"))}


def is_front_end(mod: str) -> bool:
    return mod in ("qprr.cli", "qprr.__main__") or mod.startswith("qprr.cli.") or mod.endswith(".cli")


def is_thesis(mod: str) -> bool:
    return mod == "qprr.thesis" or mod.startswith("qprr.thesis.")


def layer(mod: str) -> int:
    """0 core, 1 the thesis plug-in, 2 front ends."""
    return 2 if is_front_end(mod) else 1 if is_thesis(mod) else 0


def imports(mod: str) -> list[tuple[int, str]]:
    """(line, qprr module) of every import in ``mod``: statements (a name imported from a package counts as the
    package unless it is a submodule) and ``import_module``/``__import__`` calls with a literal name."""
    path = MODULES[mod]
    is_pkg = path.name == "__init__.py"
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = mod.split(".") if is_pkg else mod.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            subs = [f"{target}.{a.name}" for a in node.names]
            out += [(node.lineno, s) for s in subs if s in MODULES]
            if any(s not in MODULES for s in subs):
                out.append((node.lineno, target))
        elif (
            isinstance(node, ast.Call)
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
            and (
                (isinstance(node.func, ast.Name) and node.func.id in ("import_module", "__import__"))
                or (isinstance(node.func, ast.Attribute) and node.func.attr == "import_module")
            )
        ):
            out.append((node.lineno, node.args[0].value))
    return [(line, t) for line, t in out if t == "qprr" or t.startswith("qprr.")]


def _where(mod: str, line: int, target: str) -> str:
    return f"{MODULES[mod].relative_to(ROOT)}:{line} imports {target}"


def test_no_module_imports_a_layer_above_its_own():
    up = [_where(mod, line, t) for mod in MODULES for line, t in imports(mod) if t in MODULES and layer(t) > layer(mod)]
    assert up == [], "\n".join(up)


def test_front_ends_reach_the_thesis_only_through_the_registries():
    """``qprr compare``, ``qprr check``, ``qprr urdf``, ``qprr analyze``'s references: the core's front ends name no thesis module."""
    bad = [_where(mod, line, t) for mod in MODULES if is_front_end(mod) and not is_thesis(mod) for line, t in imports(mod) if is_thesis(t)]
    assert bad == [], "\n".join(bad)


def test_lazy_names_of_the_package_are_core_modules():
    import qprr

    assert qprr.LAZY and all(m in MODULES and layer(m) == 0 for m in qprr.LAZY.values()), qprr.LAZY


def test_no_import_cycle():
    graph = {mod: {t for _, t in imports(mod) if t in MODULES and t != mod and not mod.startswith(t + ".")} for mod in MODULES}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    cycles: list[list[str]] = []

    def strong(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in graph:
        if v not in index:
            strong(v)
    assert cycles == [], cycles


def test_the_rules_see_what_they_forbid():
    """The audit is not blind: the thesis is imported by its own modules and the front ends import the core."""
    assert any(is_thesis(t) for line, t in imports("qprr.thesis.scenarios"))
    assert layer("qprr.viz.cli") == 2 and layer("qprr.thesis.robot") == 1 and layer("qprr.sim.loop") == 0
    assert "qprr.registry" in {t for _, t in imports("qprr.cli")}


def test_importing_the_core_loads_no_thesis_module():
    code = (
        "import sys, qprr, qprr.sim, qprr.control, qprr.ik, qprr.scenarios, qprr.viz, qprr.analysis, qprr.campaign, qprr.cli\n"
        "qprr.cli.build_parser.__name__\n"
        "print(sorted(m for m in sys.modules if m.startswith('qprr.thesis')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300, check=True)
    assert out.stdout.strip() == "[]", out.stdout


def test_the_thesis_arrives_by_registration():
    """``qprr.load("q-prr")`` with no import of the thesis: the registry loads the plug-in (entry point ``qprr.plugins``)."""
    code = (
        "import sys, qprr\n"
        "assert 'qprr.thesis' not in sys.modules\n"
        "p = qprr.load('q-prr')\n"
        "from qprr.scenarios import SCENARIOS\n"
        "print(p.name, 'qprr.thesis' in sys.modules, 'static-idc' in SCENARIOS)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["Q-PRR", "(thesis,", "plus)", "True", "True"], out.stdout


def test_the_public_face_is_the_workflow():
    """``import qprr`` gives the workflow (issue 20 item 5); the five heavier names load on first access, then are the
    objects of their modules."""
    code = (
        "import sys, qprr\n"
        "before = {m for m in ('qprr.sim', 'qprr.control', 'qprr.ik', 'qprr.actuation') if m in sys.modules}\n"
        "import qprr.sim, qprr.control, qprr.ik, qprr.actuation\n"
        "same = [qprr.simulate is qprr.sim.simulate, qprr.SimResult is qprr.sim.SimResult, qprr.IKSolver is qprr.ik.IKSolver,\n"
        "        qprr.Allocator is qprr.actuation.Allocator, qprr.make_controller is qprr.control.make_controller]\n"
        "print(sorted(before), all(same), sorted(qprr.__all__))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == (
        "[] True ['Allocator', 'Hold', 'IKSolver', 'MultiPhase', 'Phase', 'Platform', 'QprrError', 'SimConfig', 'SimInputs', "
        "'SimResult', 'Spiral', 'build', 'from_urdf', 'load', 'make_controller', 'simulate']"
    ), out.stdout
    import qprr

    with pytest.raises(AttributeError, match="no attribute 'simulat'"):
        qprr.simulat  # noqa: B018 - a typo is an AttributeError, not a lazy lookup
    assert qprr.SimConfig is qprr.sim.SimConfig and qprr.Hold is qprr.trajectory.Hold


def test_names_kept_for_existing_code_are_deprecated_with_a_removal_version():
    """``qprr.InputError``, ``qprr.xi_to_q``...: still their objects, with a DeprecationWarning naming the home and the
    version that removes them (issue 33 item 5); no deprecated name is in ``__all__``."""
    import importlib

    import qprr

    version = [tuple(int(x) for x in v.split(".")) for v in (qprr.REMOVED_IN, qprr.__version__)]
    assert version[0] > version[1] and not set(qprr.DEPRECATED) & set(qprr.__all__)
    for name, home in qprr.DEPRECATED.items():
        with pytest.warns(DeprecationWarning, match=rf"qprr\.{name} is deprecated .* removed in qprr {qprr.REMOVED_IN}: use {home}\.{name}"):
            value = getattr(qprr, name)
        assert value is getattr(importlib.import_module(home), name)


# ------------------------------------------------------------------------------------ the module map's order
ARCHITECTURE = ROOT / "docs" / "architecture.md"
MAP_COLUMN = 37
"""Width of the left column of the map's rows (the paths); the right column describes them."""


def map_rows() -> list[list[str]]:
    """The paths of each row of docs/architecture.md's module map, top to bottom (a row whose left column is empty
    continues the description of the row above)."""
    block = ARCHITECTURE.read_text(encoding="utf-8").split("## The module map", 1)[1].split("```", 2)[1]
    lines = block.split("\n")[1:]
    assert lines[0].strip() == "qprr/", "the map's code block starts with qprr/"
    return [line[:MAP_COLUMN].split() for line in lines[1:] if line[:MAP_COLUMN].strip()]


def map_rank(mod: str, rows: list[list[str]]) -> int | None:
    """Row of module ``mod`` in the map: the most specific entry naming it (a file, then its innermost folder; ``*/cli.py``
    stands for every subpackage's cli module), None when no entry does."""
    path = MODULES[mod].relative_to(PKG).as_posix()
    best, depth = None, -1
    for i, row in enumerate(rows):
        for entry in row:
            if entry == path or (entry == "*/cli.py" and path.endswith("/cli.py")):
                return i
            if entry.endswith("/") and path.startswith(entry) and entry.count("/") > depth:
                best, depth = i, entry.count("/")
    return best


def test_the_module_map_names_every_module():
    rows = map_rows()
    missing = [str(MODULES[m].relative_to(ROOT)) for m in MODULES if m not in ("qprr", "qprr.__main__") and map_rank(m, rows) is None]
    assert missing == [], missing


def test_every_import_follows_the_module_maps_order():
    """docs/architecture.md: "each line uses only what is above it or beside it".  Every import counts, the ones inside
    functions too (qprr's package ``__init__`` and ``__main__`` stand outside the order)."""
    rows = map_rows()
    bad = []
    for mod in MODULES:
        if mod in ("qprr", "qprr.__main__"):
            continue
        mine = map_rank(mod, rows)
        for line, target in imports(mod):
            if target in MODULES and target != "qprr" and map_rank(target, rows) > mine:
                bad.append(f"{_where(mod, line, target)} (map row {mine + 1} uses row {map_rank(target, rows) + 1})")
    assert bad == [], "\n".join(bad)


def test_the_map_order_check_sees_an_upward_import():
    rows = map_rows()
    assert map_rank("qprr.errors", rows) < map_rank("qprr.model", rows) < map_rank("qprr.sim.loop", rows) < map_rank("qprr.cli", rows)
    assert map_rank("qprr.analysis.cli", rows) == map_rank("qprr.cli", rows)
