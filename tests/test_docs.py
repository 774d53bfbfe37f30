"""The documentation describes the code as it is: every page's Python blocks run, every name resolves.

* Each page's ```python blocks run in order in one fresh interpreter (as a reader pastes them
  into one session), headless (MPLBACKEND=Agg), in a temporary folder that sees the
  repository's examples/ (docs/platforms.md loads examples/my_platform/ as a reader in the
  repository root would).  Every ``qprr`` module the blocks imported must come from this
  repository.  A block that cannot run here is marked on the line above its fence with
  ``<!-- not run: REASON -->``; a page whose blocks need an optional extra names it in REQUIRES.
* Every dotted name ``qprr.xxx.yyy`` of every page resolves (in this repository's ``qprr``), every
  repository path exists, every test a page cites exists, and every ``qprr ...`` /
  ``python -m qprr ...`` command parses with the real command line, with known scenario,
  controller, option, comparison, robot and platform names.
"""

from __future__ import annotations

import ast
import contextlib
import importlib
import io
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from qprr.errors import MissingDependencyError

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").glob("*.md")) + ["README.md"]
REQUIRES = {
    "docs/mpc.md": ("crocoddyl", "mpc"),
    "docs/wheeled.md": ("sympy", "symbolic"),
    "docs/flightstack.md": ("pyulog", "flightlog"),
    "docs/rl.md": ("gymnasium", "rl"),
}
"""Optional extras a page's blocks need: page -> (module, extra); the test is skipped with the install command where the
extra is missing."""

NOT_RUN = re.compile(r"<!--\s*not run:\s*(.*?)\s*-->\s*$")


def read(page: str) -> str:
    return (ROOT / page).read_text()


def python_blocks(text: str) -> list[tuple[str, str]]:
    """(code, reason) of every ```python block; reason is "" for a block that runs, else its not-run marker's reason."""
    out = []
    for m in re.finditer(r"```python\n(.*?)```", text, flags=re.S):
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        marker = NOT_RUN.search(before)
        out.append((m.group(1), marker.group(1) if marker else ""))
    return out


GUARD = """
import pathlib as _pathlib, sys as _sys
_root = _pathlib.Path({root!r})
_outside = sorted(n for n, m in list(_sys.modules.items()) if n.split(".")[0] == "qprr" and getattr(m, "__file__", None)
                  and not _pathlib.Path(m.__file__).resolve().is_relative_to(_root))
if _outside:
    raise SystemExit(f"qprr modules imported from outside {{_root}} (stale names?): {{_outside}}")
"""


@pytest.mark.parametrize("page", [p for p in PAGES if "```python" in read(p)])
def test_blocks_run(page, tmp_path):
    if page in REQUIRES:
        module, extra = REQUIRES[page]
        pytest.importorskip(module, reason=f"{page} needs {module}: pip install -e '.[{extra}]'")
    blocks = python_blocks(read(page))
    for code, reason in blocks:
        assert reason or not code.lstrip().startswith("<!--"), page
    run = [code for code, reason in blocks if not reason]
    assert run, f"{page}: every block is marked not run"
    (tmp_path / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    script = tmp_path / "blocks.py"
    script.write_text("\n\n".join(run) + GUARD.format(root=str(ROOT)))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{page}:\n{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}"
    assert "Warning" not in proc.stderr, proc.stderr


def test_pages_with_blocks():
    """The pages a reader runs code from (a page losing its blocks by accident fails here)."""
    counts = {p: len(python_blocks(read(p))) for p in PAGES}
    for page, least in {
        "docs/guide.md": 9,
        "docs/platforms.md": 4,
        "README.md": 3,
        "docs/ik.md": 2,
        "docs/interaction.md": 1,
        "docs/mpc.md": 1,
        "docs/wheeled.md": 1,
    }.items():
        assert counts[page] >= least, (page, counts[page])


# ------------------------------------------------------------------------------------- names
def resolve(dotted: str) -> str:
    """ "" if ``dotted`` (qprr.a.b.c) is a module of this repository or an attribute of one, else why not."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        name = ".".join(parts[:i])
        try:
            obj = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and (name == exc.name or name.startswith(exc.name + ".")):
                continue
            raise
        except MissingDependencyError as exc:  # an optional dependency is absent: read the module's source instead
            for j in range(i, 0, -1):
                base = ROOT / Path(*parts[:j])
                for path in (base.with_suffix(".py"), base / "__init__.py"):  # a module or a package (qprr.envs)
                    if path.is_file():
                        return defined_in_source(path, parts[j:], ".".join(parts[:j]))
            return f"{name}: {exc}"
        path = Path(getattr(obj, "__file__", "") or "").resolve()
        if not path.is_relative_to(ROOT):
            return f"{name} is not in this repository ({path})"
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return f"{'.'.join(parts[: parts.index(attr)])} has no {attr!r}"
            obj = getattr(obj, attr)
        return ""
    return f"no module {parts[0]!r}"


def defined_in_source(path: Path, attrs: list[str], module: str) -> str:
    """ "" if the attribute chain ``attrs`` (a class, then a method...) is defined in the source file ``path``, else why
    not: the check of a module that cannot be imported here because an optional dependency is absent."""
    body = ast.parse(path.read_text()).body
    for k, attr in enumerate(attrs):
        found = None
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.name == attr:
                found = node
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                if any(isinstance(t, ast.Name) and t.id == attr for t in targets):
                    found = node
            elif isinstance(node, ast.ImportFrom) and any((a.asname or a.name) == attr for a in node.names):
                found = node  # a name a package's __init__ imports from its modules
        if found is None:
            return f"{'.'.join([module, *attrs[:k]])} defines no {attr!r} (read from {path.relative_to(ROOT)})"
        body = getattr(found, "body", [])
    return ""


def dotted_names(text: str) -> set[str]:
    return {m.group(0).rstrip(".") for m in re.finditer(r"(?<![\w/.\-])qprr(?:\.[A-Za-z_]\w*)+", text)}


def test_dotted_names_resolve():
    """In a child process: importing every module the pages name (viser, crocoddyl...) stays out of this session."""
    import json

    from qprr.registry import COMMAND_GROUP, PLUGIN_GROUP

    groups = {PLUGIN_GROUP, COMMAND_GROUP}  # entry-point group names (a pyproject.toml's tables), not modules
    names = sorted({(page, name) for page in PAGES for name in dotted_names(read(page)) if name not in groups})
    code = (
        "import json, sys; sys.path.insert(0, sys.argv[1]); from tests.test_docs import resolve; "
        "print(json.dumps([resolve(n) for n in json.loads(sys.stdin.read())]))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, str(ROOT)],
        input=json.dumps([n for _, n in names]),
        cwd=ROOT,
        env=dict(os.environ, MPLBACKEND="Agg"),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    why = json.loads(proc.stdout.strip().splitlines()[-1])
    bad = [f"{page}: {name}: {w}" for (page, name), w in zip(names, why) if w]
    assert len(names) > 100 and not bad, "\n".join(bad)


def test_paths_and_links_exist():
    bad = []
    for page in PAGES:
        text = read(page)
        for m in re.finditer(r"(?<![\w/.])((?:qprr|tests|benchmarks|examples|urdf|docs)/[\w/.\-*]+)", text):
            path = m.group(1).rstrip(".,")
            if re.search(r"/[A-Z]+\.\w+$", path):
                continue  # a placeholder (examples/NAME.py)
            if re.fullmatch(r"qprr/[A-Z]\w*-v\d+", path):
                continue  # a Gymnasium environment id (qprr/Reach-v0, docs/rl.md), not a path
            if not (any(ROOT.glob(path)) if "*" in path else (ROOT / path).exists()):
                bad.append(f"{page}: {path}")
        for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", text):  # relative links
            if not (ROOT / page).parent.joinpath(target).exists():
                bad.append(f"{page}: link {target}")
    assert not bad, "\n".join(bad)


def test_cited_tests_exist():
    defined = set()
    for f in (ROOT / "tests").glob("*.py"):
        src = f.read_text()
        defined |= set(re.findall(r"def (test_\w+)", src)) | set(re.findall(r"^(\w+)\s*[:=]", src, flags=re.M))
    bad = []
    for page in PAGES:
        text = read(page)
        cited = set(re.findall(r"(?<![\w.])(test_\w+)(?!\w|\.py|\*)", text)) | set(re.findall(r"tests/\w+\.py::(\w+)", text))
        bad += [f"{page}: {name}" for name in sorted(cited) if not name.endswith("_") and name not in defined]
    assert not bad, "\n".join(bad)


# ---------------------------------------------------------------------------------- commands
PLACEHOLDER = re.compile(r"^(?:\.\.\.|[A-Z][A-Z0-9_\-]*(?:\.\w+)?)$")


def commands(text: str) -> list[str]:
    """The ``qprr ...`` command lines of a page (indented code lines, continuation lines joined, and inline code),
    without the leading ``pip install ... &&`` and the trailing comment."""
    lines, joined = text.splitlines(), []
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("    ") and not line.lstrip().startswith("|"):
            while line.rstrip().endswith("\\") and i + 1 < len(lines):
                i += 1
                line = line.rstrip()[:-1] + " " + lines[i].strip()
            joined.append(line.strip())
        joined += re.findall(r"`((?:python -m )?qprr [^`]+)`", line)
        i += 1
    out = []
    for c in joined:
        c = re.sub(r"^pip install [^&]*&&\s*", "", c).split("#")[0].strip()
        m = re.match(r"(?:python -m qprr|qprr)\s+(.*)$", c)
        if m:
            out.append(m.group(1))
    return out


def check_command(parser, argv: list[str]) -> str:
    """ "" if ``qprr ARGV`` parses and names things that exist, else why not."""
    from qprr.platforms import NAMES
    from qprr.scenarios import SCENARIOS
    from qprr.thesis.comparisons import COMPARISONS
    from qprr.wheeled.demos import catalogue

    err = io.StringIO()
    exits = {"--help", "--version"} & set(argv)  # argparse prints and exits 0
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            args = parser.parse_args(argv)
    except SystemExit as exc:
        return "" if exc.code == 0 and exits else f"does not parse: {err.getvalue().strip()}"
    if args.command == "simulate":
        if args.scenario not in SCENARIOS:
            return f"unknown scenario {args.scenario!r}"
        sc = SCENARIOS[args.scenario]
        if args.controller is not None and args.controller not in sc.controller_names():
            return f"{args.scenario} has no controller {args.controller!r}"
        for item in args.set or ():
            if item.split("=", 1)[0] not in sc.options:
                return f"{args.scenario} has no option {item!r}"
    if args.command == "compare":
        bad = [n for n in args.names if n not in COMPARISONS and n != "all"]
        if bad:
            return f"unknown comparison {bad[0]!r}"
    if args.command == "wheeled" and args.name not in catalogue():
        return f"unknown robot or exercise {args.name!r}"
    name = getattr(args, "platform", None)
    if name is not None and name not in NAMES:
        from qprr.errors import QprrError
        from qprr.nomenclature import parse

        try:
            parse(name)  # a (2.1) designation
        except QprrError as exc:
            return f"--platform {name!r}: {exc}"
    return ""


def test_commands_parse():
    from qprr.cli import build_parser

    parser = build_parser()
    bad, seen = [], 0
    for page in PAGES:
        for cmd in commands(read(page)):
            if "[" in cmd or "|" in cmd:
                continue  # a synopsis: qprr simulate SCENARIO [--controller C] ...
            argv = shlex.split(cmd)
            positional = [a for a in argv[1:] if not a.startswith("-")]
            if positional and PLACEHOLDER.match(positional[0]):
                continue  # qprr simulate MISSION --controller mpc
            seen += 1
            why = check_command(parser, argv)
            if why:
                bad.append(f"{page}: qprr {cmd}: {why}")
    assert not bad, "\n".join(bad)
    assert seen > 50, seen
