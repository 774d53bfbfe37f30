"""``qprr inspect`` and ``qprr ik`` (issue 35): a platform's report and one IK target, on a robot from a user's files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from qprr import load
from qprr.analysis.inspect import inspect_platform
from qprr.cli import main
from qprr.platforms import resolve

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_platform"
OWN = ["--urdf", str(EXAMPLE / "quad_rrr.urdf"), "--rotors", str(EXAMPLE / "quad_rrr.rotors.toml")]


def test_inspect_reports_the_users_files(capsys):
    """Joint, body and rotor names and the numbers come from the user's URDF and rotor file."""
    assert main(["inspect", *OWN]) == 0
    out = capsys.readouterr().out
    platform = resolve(urdf=str(EXAMPLE / "quad_rrr.urdf"), rotors=str(EXAMPLE / "quad_rrr.rotors.toml"))
    for joint in platform.arm:
        assert f"{joint.name} ({joint.kind}): [{joint.lower:.4g}, {joint.upper:.4g}]" in out
    for rotor in platform.rotors:
        assert f"  {rotor.name}: [" in out
    assert f"total mass {platform.total_mass:.4g} kg" in out
    summary = platform.actuation_summary()
    assert f"wrench rank {summary.rank}/6" in out
    assert f"margin to the bounds {summary.hover_margin:.4g} N" in out


def test_inspect_report_numbers():
    """The hextilt: fully actuated, its six rotors, the friction note with the explicit step 1 / rate."""
    report = inspect_platform(load("hextilt_flying_arm_5"))
    assert report.actuation.fully_actuated and len(report.rotors) == 6
    assert any("joint friction: stiffest rate" in note for note in report.notes)
    assert report.tree[0].startswith("  root_joint: FreeFlyer, universe -> ")
    text = report.text()
    assert "fully actuated" in text and "hover thrusts [" in text


def test_ik_solves_a_target(capsys):
    assert main(["ik", "--target", "0.3", "0", "1.0", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["success"] and report["status"] == "converged"
    assert report["position_error_m"] < 1e-9
    assert set(report["xi"]) == set(load("q-prr").xi_names)


def test_ik_failure_says_what_would_help(capsys):
    """A rolled target on the under-actuated Q-PRR: exit 1, the reason, and advice that does not say 'another xi0'."""
    assert main(["ik", "--target", "0.3", "0", "1.0", "--rpy", "0.5", "0", "0"]) == 1
    out = capsys.readouterr().out
    assert "not reached" in out
    help_line = next(line for line in out.splitlines() if line.startswith("what would help:"))
    assert "under-actuated" in help_line and "--rpy" in help_line


def test_ik_fully_actuated_platform_reaches_a_rolled_target(capsys):
    assert main(["ik", "--platform", "hextilt_flying_arm_5", "--target", "0.2", "0.1", "1", "--rpy", "0.3", "0", "0"]) == 0
    assert "converged (reached)" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv",
    [["ik", "--target", "0.3", "0"], ["ik", "--target", "a", "0", "1"], ["ik", "--target", "0", "0", "1", "--method", "newton"]],
)
def test_ik_bad_arguments_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2


def test_unknown_platform_exits_2(capsys):
    assert main(["ik", "--target", "0", "0", "1", "--platform", "nope"]) == 2
    assert "nope" in capsys.readouterr().err
    assert main(["inspect", "--platform", "nope"]) == 2
    assert "unknown platform 'nope'" in capsys.readouterr().err
