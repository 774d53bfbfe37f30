"""The example plug-in (examples/plugin/) installed as a package and run end to end from the command line.

The fixture lays the plug-in out as pip installs it, without a build backend (a fresh venv on Python 3.11 has an old
setuptools and no ``wheel``, and CI has no index to fetch them): the package folder, and a ``.dist-info`` whose
``entry_points.txt`` is written from the plug-in's own ``pyproject.toml`` (``[project.entry-points]``), so a wrong entry
point there fails here.  The commands run with ``PYTHONPATH`` = this repository and that folder: qprr finds the plug-in
through ``importlib.metadata`` exactly as it finds the thesis.  Nothing is imported from the plug-in in this process
(its registrations would stay in the core's registries for the other tests).  A last test builds it with pip where the
build backend can (setuptools >= 70.1, or ``wheel`` installed).
"""

from __future__ import annotations

import csv
import importlib.metadata
import importlib.util
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = ROOT / "examples" / "plugin"


def _qprr(args: list[str], env: dict, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "qprr", *args], env=env, cwd=cwd, capture_output=True, text=True, timeout=300)


def _install_layout(source: Path, target: Path) -> None:
    """Write the plug-in into ``target`` as an installed distribution: its package and a ``.dist-info`` from pyproject."""
    pyproject = tomllib.loads((source / "pyproject.toml").read_text())
    project = pyproject["project"]
    for package in pyproject["tool"]["setuptools"]["packages"]:
        shutil.copytree(source / package, target / package, ignore=shutil.ignore_patterns("__pycache__"))
    info = target / f"{project['name'].replace('-', '_')}-{project['version']}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {project['name']}\nVersion: {project['version']}\n")
    lines = []
    for group, entries in project["entry-points"].items():
        lines += [f"[{group}]", *(f"{name} = {value}" for name, value in entries.items()), ""]
    (info / "entry_points.txt").write_text("\n".join(lines))


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[dict, Path]:
    """(environment with the plug-in installed, a work folder)."""
    tmp = tmp_path_factory.mktemp("plugin")
    target = tmp / "site"
    _install_layout(PLUGIN, target)
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join([str(ROOT), str(target)]))
    work = tmp / "work"
    work.mkdir()
    return env, work


def test_the_entry_point_is_found_and_fills_every_registry(installed):
    env, work = installed
    code = (
        "from qprr.registry import load_plugins, SCENARIOS\n"
        "from qprr.platforms import PLATFORMS\n"
        "from qprr.control import CONTROLLERS\n"
        "from qprr.campaign import METRICS\n"
        "print(sorted(load_plugins()))\n"
        "print('example-quad' in PLATFORMS, 'pd-gravity' in CONTROLLERS, 'square-tour' in SCENARIOS, 'max_tilt' in METRICS)\n"
        "print(SCENARIOS['hover-reach'].controller_names()[-1])\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=work, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split("\n")[:3] == ["['example', 'thesis']", "True True True True", "pd-gravity"], proc.stdout


def test_simulate_the_plugins_scenario_with_its_controller_on_its_platform(installed):
    env, work = installed
    proc = _qprr(["simulate", "square-tour", "--controller", "pd-gravity", "--duration", "4", "-q", "--save", "tour.npz"], env, work)
    assert proc.returncode == 0, proc.stderr
    assert "scenario square-tour, platform example-quad, controller pd-gravity: ok (completed)" in proc.stdout, proc.stdout
    assert (work / "tour.npz").is_file()
    listed = _qprr(["simulate", "--help"], env, work).stdout
    assert "square-tour" in listed and "controllers: pd-gravity, idc" in listed, listed


def test_a_core_scenario_flies_the_plugins_controller(installed):
    """hover-reach names no plug-in controller: the controller's entry names hover-reach (ControllerEntry.scenarios)."""
    env, work = installed
    proc = _qprr(["simulate", "hover-reach", "--controller", "pd-gravity", "--platform", "example-quad", "--duration", "3", "-q"], env, work)
    assert proc.returncode == 0, proc.stderr
    assert "controller pd-gravity: ok (completed)" in proc.stdout, proc.stdout
    gains = _qprr(["simulate", "hover-reach", "--controller", "pd-gravity", "--platform", "example-quad", "--print-gains"], env, work)
    assert gains.returncode == 0 and "gains of pd-gravity in hover-reach on" in gains.stdout and "PDGains" in gains.stdout, gains.stdout


def test_campaign_run_with_the_plugins_metric(installed):
    env, work = installed
    spec = work / "tour.toml"
    spec.write_text(
        'name = "tour"\nscenario = "square-tour"\nplatform = "example-quad"\nseed = 3\nmetrics = ["rmse", "max_tilt"]\n'
        '[options]\nduration = 4.0\nside = 0.3\n[grid]\ncontroller = ["pd-gravity", "idc"]\n[success]\nmax_tilt = 0.6\n'
    )
    proc = _qprr(["campaign", "run", str(spec), "-o", "tour.csv", "--backend", "local", "--workers", "2", "--report", "report", "--quiet"], env, work)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    with open(work / "tour.csv", newline="") as f:  # read as text: this process has no plug-in to validate the spec with
        header, *rows = list(csv.reader(f))
    assert "max_tilt" in header and "rmse_position" in header, header
    tilt = [float(r[header.index("max_tilt")]) for r in rows]
    assert sorted(r[header.index("controller")] for r in rows) == ["idc", "pd-gravity"], rows
    assert all(0.0 < t < 0.6 and math.isfinite(t) for t in tilt), tilt  # roll and pitch of a 0.3 m square in 4 s
    assert "max_tilt median [rad]" in (work / "report" / "summary.md").read_text()


def test_without_the_plugin_its_names_are_unknown(installed):
    """The same command line without the package: the plug-in's names are refused, listing the registered ones."""
    env, work = installed
    bare = dict(env, PYTHONPATH=str(ROOT))
    proc = _qprr(["simulate", "square-tour"], bare, work)
    assert proc.returncode == 2 and "unknown scenario 'square-tour'" in proc.stderr, proc.stderr


def _backend_builds_wheels() -> bool:
    """setuptools >= 70.1 builds wheels itself; older ones need the ``wheel`` package."""
    try:
        major, minor = (int(part) for part in importlib.metadata.version("setuptools").split(".")[:2])
    except importlib.metadata.PackageNotFoundError:
        return False
    return (major, minor) >= (70, 1) or importlib.util.find_spec("wheel") is not None


@pytest.mark.skipif(not _backend_builds_wheels(), reason="building the example plug-in needs setuptools>=70.1: pip install -U setuptools")
def test_pip_installs_the_plugin_as_the_layout_above(tmp_path):
    """``pip install`` of examples/plugin gives the same package and entry point as the fixture's layout."""
    source = tmp_path / "src"
    shutil.copytree(PLUGIN, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))  # builds leave files
    target = tmp_path / "site"
    pip = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation", "--no-index", "--target", str(target), str(source)]
    proc = subprocess.run(pip, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    layout = tmp_path / "layout"
    _install_layout(PLUGIN, layout)
    (built,) = target.glob("qprr_example_plugin-*.dist-info")
    (laid,) = layout.glob("qprr_example_plugin-*.dist-info")
    assert built.name == laid.name
    assert _entry_points(built) == _entry_points(laid)
    modules = [sorted(p.name for p in (root / "qprr_example_plugin").glob("*.py")) for root in (target, layout)]
    assert modules[0] == modules[1]


def _entry_points(info: Path) -> set[tuple[str, str, str]]:
    return {(ep.group, ep.name, ep.value) for ep in importlib.metadata.PathDistribution(info).entry_points}
