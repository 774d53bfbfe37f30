"""The example plug-in (examples/plugin/) installed as a package and run end to end from the command line.

It is installed with ``pip install --no-deps --no-build-isolation --target TMP`` (a ``.dist-info`` with its entry point
in the ``qprr.plugins`` group, as any installed distribution has), and the commands run with ``PYTHONPATH`` = this
repository and TMP: qprr finds it through ``importlib.metadata`` exactly as it finds the thesis.  Nothing is imported
from the plug-in in this process (its registrations would stay in the core's registries for the other tests).
"""

from __future__ import annotations

import csv
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = ROOT / "examples" / "plugin"


def _qprr(args: list[str], env: dict, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "qprr", *args], env=env, cwd=cwd, capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[dict, Path]:
    """(environment with the plug-in installed, a work folder)."""
    tmp = tmp_path_factory.mktemp("plugin")
    source = tmp / "src"
    shutil.copytree(PLUGIN, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))  # builds leave files
    target = tmp / "site"
    pip = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation", "--no-index", "--target", str(target), str(source)]
    proc = subprocess.run(pip, capture_output=True, text=True, timeout=300)
    if proc.returncode != 0 and "No module named" in proc.stderr and "setuptools" in proc.stderr:
        pytest.skip("the example plug-in builds with setuptools, which is not installed: pip install setuptools")
    assert proc.returncode == 0, proc.stderr
    assert (target / "qprr_example_plugin").is_dir() and list(target.glob("qprr_example_plugin-*.dist-info"))
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
