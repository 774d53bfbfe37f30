"""A new user's whole command-line workflow on their own robot (docs/platforms.md, sections 7-9), from the files of
examples/my_platform alone: the gains printed, the multi-phase mission with a payload grasped and released (the sag
it causes is the payload's weight over m k_P, with the printed k_P), a gains file, the animation, a small robustness
campaign with model errors (show, run, report) whose columns carry the URDF's joint names, and no Q-PRR name in
anything printed or written.  Also ee-impedance on the three platforms of the generic missions' tests where it was not run.
"""

from __future__ import annotations

import csv
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr import scenarios
from qprr.cli import main
from qprr.scenarios.impedance import steady_state

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
MY = ROOT / "examples" / "my_platform"
OWN = ["--urdf", str(MY / "quad_rrr.urdf"), "--rotors", str(MY / "quad_rrr.rotors.toml"), "--ee-frame", "gripper"]
MISSION = ["--set", f"mission={MY / 'mission.toml'}", "--duration", "8", "-q"]
JOINTS = ("yaw", "shoulder", "elbow")
QPRR = re.compile(r"\br_?0\b|theta_?[23]|q-prr|qprr\.thesis|\bprr\b", re.IGNORECASE)
"""The Q-PRR's names: its platform name, its arm coordinates r0, theta2, theta3 (also as mathtext), its plug-in."""

TOTAL_MASS = 1.5  # kg, the sum of quad_rrr.urdf's link masses (tests/test_own_platform.py checks it)
G = 9.81  # m/s^2, qprr.from_urdf's default


def cli(capsys, *argv: str, code: int = 0) -> str:
    """Run ``qprr ARGV`` in this process; its stdout and stderr, after checking the exit code and that no Q-PRR name
    appears in them."""
    assert main([*argv]) == code, capsys.readouterr()
    out = capsys.readouterr()
    text = out.out + out.err
    assert not QPRR.search(text), text
    return text


def metric(text: str, name: str) -> float:
    """A number printed as ``NAME 12.3 mm`` by the mission's summary line, in metres."""
    m = re.search(rf"{name} ([0-9.]+) mm", text)
    assert m, text
    return float(m.group(1)) * 1e-3


def kp_z(text: str) -> float:
    """k_P of z from ``--print-gains``'s table (columns coordinate, kp, kd, ki)."""
    m = re.search(r"^\s+z\s+([0-9.eE+-]+)\s", text, re.MULTILINE)
    assert m, text
    return float(m.group(1))


def test_mission_with_grasp_and_release_sags_by_the_payload_weight_over_m_kp(tmp_path, capsys):
    """mission.toml grasps 0.15 kg at 3.2 s and releases it at 6 s.  With the PD gains (``[targets] integral = false``)
    the vehicle sinks towards the static sag m_p g / (m k_P) (a critically damped loop reaches 97 % of it in the 2.8 s of
    carrying), then returns once released; the same with gains.toml's cascade ratio: the sag scales as 1 / k_P.  With the
    default gains (integral action) the position integral takes the sag out while carrying: the largest error is below
    half of the PD's sag."""
    pd_file, pd_ratio_file = tmp_path / "pd.toml", tmp_path / "pd_ratio.toml"
    pd_file.write_text("[targets]\nintegral = false\n")
    pd_ratio_file.write_text("[targets]\nintegral = false\nratio = 3.0\n")
    pd = ["--gains", str(pd_file)]
    printed = cli(capsys, "simulate", "mission", *OWN, *pd, "--print-gains")
    assert "on quad_rrr" in printed and all(re.search(rf"^\s+{j}\s", printed, re.MULTILINE) for j in JOINTS)
    run = tmp_path / "mission.npz"
    out = cli(capsys, "simulate", "mission", *OWN, *MISSION, "--save", str(run), "--plot", str(tmp_path / "mission.png"))
    assert "scenario mission, platform quad_rrr, controller idc: ok" in out
    rmse = re.search(r"RMSE \(6\.26\): (.*)", out).group(1)
    assert [w.split()[0] for w in rmse.split(", ")] == ["x", "y", "z", "phi", "theta", "psi", *JOINTS]
    ratio = ["--gains", str(pd_ratio_file)]  # re-derived with a cascade ratio of 3: a stiffer position loop
    kp_file = kp_z(cli(capsys, "simulate", "mission", *OWN, *ratio, "--print-gains"))
    assert kp_file > 2.0 * kp_z(printed)
    for kp, gains in ((kp_z(printed), pd), (kp_file, ratio)):
        text = cli(capsys, "simulate", "mission", *OWN, *MISSION, *gains)
        sag = 0.15 * G / (TOTAL_MASS * kp)
        assert 0.9 * sag < metric(text, "max position error") < 1.05 * sag, (sag, text)
        assert metric(text, "final position error") < 0.12 * sag  # released at 6 s: it climbs back
    assert metric(out, "max position error") < 0.5 * 0.15 * G / (TOTAL_MASS * kp_z(printed))
    assert (tmp_path / "mission.png").stat().st_size > 10_000
    gif = tmp_path / "mission.gif"
    anim = cli(capsys, "animate", str(run), *OWN, "-o", str(gif), "--fps", "2", "-q")
    assert gif.read_bytes()[:6] == b"GIF89a" and anim.count("\n") == 1 and "16 frames at 2 fps" in anim


def test_simulate_animate_prints_one_line(tmp_path, capsys):
    gif = tmp_path / "up.gif"
    out = cli(capsys, "simulate", "takeoff-hover", *OWN, "--duration", "1", "-q", "--animate", str(gif))
    assert gif.read_bytes()[:6] == b"GIF89a"
    lines = [line for line in out.splitlines() if line.startswith("animation")]
    assert len(lines) == 1 and lines[0].startswith(f"animation: {gif} (") and "AnimationInfo(" not in out


def test_a_thesis_scenario_on_your_robot_names_those_that_fly_it(capsys):
    assert main(["simulate", "static-idc", *OWN]) == 2
    err = capsys.readouterr().err
    generic = re.search(r"scenarios for any platform: (.*)$", err.strip()).group(1).split(", ")
    assert {"hover-reach", "mission", "grasp-drop", "motor-lag"} <= set(generic) and "static-idc" not in generic


def test_robustness_campaign_on_your_robot_has_its_joints_columns(tmp_path, capsys):
    """robustness.toml, cut to 2 samples of 2 s, next to copies of the robot's files as a user keeps them: show, run,
    report.  Every run completes; the columns are the URDF's joints; the paired draws are the same for both
    controllers and within the specification's bounds; no file written names the Q-PRR."""
    for name in ("quad_rrr.urdf", "quad_rrr.rotors.toml"):
        shutil.copy(MY / name, tmp_path / name)
    text = (MY / "robustness.toml").read_text()
    spec = tomllib.loads(text)
    assert spec["samples"] * len(spec["grid"]["controller"]) == 100
    assert {"model.mass", "model.inertia", "model.kappa"} <= set(spec["random"])
    text = re.sub(r"^samples = 50", "samples = 2", text, flags=re.MULTILINE)
    text = re.sub(r"^duration = 6.0", "duration = 2.0", text, flags=re.MULTILINE)
    (tmp_path / "robustness.toml").write_text(text)
    shown = cli(capsys, "campaign", "show", str(tmp_path / "robustness.toml"))
    assert "on quad_rrr" in shown and "= 4 runs" in shown and all(f"rmse_{j}" in shown for j in JOINTS)
    results, report = tmp_path / "r.csv", tmp_path / "report"
    cli(capsys, "campaign", "run", str(tmp_path / "robustness.toml"), "-o", str(results), "--backend", "inline", "--quiet")
    metrics = ["--metric", "rmse_position", *(f"rmse_{j}" for j in JOINTS)]
    summary = cli(capsys, "campaign", "report", str(results), *metrics, "--out", str(report))
    assert all(f"rmse_{j} median [rad]" in summary for j in JOINTS)
    with results.open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and {r["status"] for r in rows} == {"ok"}
    assert [c for c in rows[0] if c.startswith("rmse_")] == [f"rmse_{n}" for n in ("x", "y", "z", "phi", "theta", "psi", *JOINTS, "position")]
    for row in rows:
        assert all(float(row[f"rmse_{j}"]) >= 0.0 for j in JOINTS)
        for key, draw in spec["random"].items():
            assert draw["low"] <= float(row[key]) <= draw["high"]
    by_sample = {}
    for row in rows:
        by_sample.setdefault(int(row["run"]) % 2, []).append(tuple(row[k] for k in spec["random"]))
    assert all(len(set(draws)) == 1 for draws in by_sample.values())  # paired: same draws for idc and mfc
    for written in (results, results.with_suffix(".meta.json"), report / "summary.md"):
        assert not QPRR.search(written.read_text()), written


def test_the_page_shows_the_example_files():
    """Section 9 of docs/platforms.md shows robustness.toml as it is (the same table), and its commands name the example
    files this test flies."""
    text = (ROOT / "docs" / "platforms.md").read_text()
    section = text[text.index("### 9. A robustness campaign") :]
    block = re.search(r"\n\n((?:    .*\n|\n)+?)\n\S", section).group(1)
    shown = tomllib.loads("\n".join(line[4:] for line in block.splitlines()))
    spec = tomllib.loads((MY / "robustness.toml").read_text())
    spec.pop("description")
    assert shown == spec
    for needed in ("--gains examples/my_platform/gains.toml", "campaign run examples/my_platform/robustness.toml", "--save out/mission.npz"):
        assert needed in text, needed


# ---------------------------------------------------------------------------------- coverage of the generic scenarios
@pytest.mark.parametrize("name", ["q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5"])
def test_ee_impedance_on_the_other_platforms(name):
    """ee-impedance, tested on HEX-RRR in tests/test_opspace_impedance.py, on the three other platforms of the generic
    missions' tests: the wall stops the end effector where the impedance K e = h (two springs in series), within 0.2 %.
    Frictionless arms: hextilt_flying_arm_5's URDF joint friction holds its arm 20 % short of K^-1 h."""
    platform = qprr.load(name).without_joint_friction()
    res = scenarios.run("ee-impedance", platform=platform, t_on=0.5, t_off=3.5, duration=5.5)
    assert res.status == "ok" and tuple(res.names) == platform.xi_names
    d = steady_state(res, 3.5 - res.dt)
    assert d["h"][0] < -0.5  # in contact
    assert np.abs(d["e"] - d["predicted"]).max() < 2e-3 * np.abs(d["predicted"]).max()
