"""The user guide's examples (examples/*.py, docs/guide.md) run headless and print physically right numbers.

Each script runs in a fresh interpreter (as a reader would run it), with MPLBACKEND=Agg, the
worktree's qprr first on the path, and its figures written into a temporary folder.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def run_example(name: str, tmp_path: Path) -> str:
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, str(EXAMPLES / name), str(tmp_path)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{name} failed:\n{proc.stdout}\n{proc.stderr}"
    assert "Traceback" not in proc.stderr and "Warning" not in proc.stderr, proc.stderr
    return proc.stdout


def number(pattern: str, text: str) -> float:
    m = re.search(pattern, text)
    assert m is not None, f"{pattern!r} not in the output:\n{text}"
    return float(m.group(1))


def figure(tmp_path: Path, name: str) -> None:
    p = tmp_path / name
    assert p.is_file() and p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000, name


def test_every_example_is_tested():
    tested = {
        "pose_and_cog.py",
        "ik_hover.py",
        "custom_mission.py",
        "allocation.py",
        "hover_analysis.py",
        "other_platforms.py",
        "platforms_tour.py",
        "own_platform.py",
    }
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested


def test_pose_and_cog(tmp_path):
    out = run_example("pose_and_cog.py", tmp_path)
    # the CoG offset printed equals the CoG in B minus the thrust axis (z_B): x_cm of the CoG line
    x_b = number(r"CoG in B \[m\]: \[\s*([-\d.e]+)", out)
    x_cm = number(r"x_cm = ([-\d.]+) mm", out)
    assert abs(1e3 * x_b - x_cm) < 2e-3
    assert "(6, 9)" in out


def test_ik_hover(tmp_path):
    out = run_example("ik_hover.py", tmp_path)
    assert "success True" in out and "hover-feasible: True" in out
    assert number(r"\|p_e - target\| = ([-\d.e+]+) m", out) < 1e-6  # independent forward kinematics
    assert abs(number(r"CoG offset x_cm ([-\d.e+]+) m", out)) < 1e-8
    assert number(r"offset left ([-\d.e+]+) mm", out) < 1e-9
    assert "(limited: joint 'r0' would need" in out


def test_custom_mission(tmp_path):
    out = run_example("custom_mission.py", tmp_path)
    assert out.startswith("ok:")
    assert number(r"final CoG offset x_cm = ([-\d.]+) mm", out) > 3.0  # the arm swing moves the CoG off the axis
    assert "(balanced)" in out
    assert abs(number(r"with the slider: final x_cm = ([-\d.]+) mm", out)) < 1e-3  # and the slider brings it back
    figure(tmp_path, "custom_x_cm.png")
    figure(tmp_path, "custom_run.png")
    assert (tmp_path / "custom_run.npz").is_file()


def test_allocation(tmp_path):
    out = run_example("allocation.py", tmp_path)
    assert out.count("hover thrusts [N]: [8.623 8.623 8.623 8.623]") == 2  # m g / 4 on both layouts
    assert out.count("check: Omega f = [ 0.    0.   40.    0.3  -0.2   0.05]") == 2  # exact allocations
    assert out.count("allocate: saturated") == 2


def test_hover_analysis(tmp_path):
    out = run_example("hover_analysis.py", tmp_path)
    assert number(r"([\d.]+) N with the slider at 0", out) > number(r", ([\d.]+) N balancing", out)
    figure(tmp_path, "hover_analysis.png")


def test_other_platforms(tmp_path):
    out = run_example("other_platforms.py", tmp_path)
    for name in ("Q-PRR (thesis, x)", "HEX-RRR", "borinot_flying_arm_2"):
        assert re.search(re.escape(name) + r": \d rotors, arm .*: ok, RMSE x ([\d.e-]+) m", out), out
    for m in re.finditer(r"RMSE x ([\d.e+-]+) m, z ([\d.e+-]+) m", out):
        assert float(m.group(1)) < 1e-2 and float(m.group(2)) < 1e-2
    figure(tmp_path, "x_cm_three_platforms.png")


def test_platforms_tour(tmp_path):
    """Five platforms: the QP IK reaches a reachable pose (the pose of a level configuration), the allocator holds the
    IK configuration, a hover-and-reach flight tracks its reference."""
    out = run_example("platforms_tour.py", tmp_path)
    labels = ("Q-PRR +", "Q-PRR X", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")
    errors = [float(e) for e in re.findall(r"IK converged: position error ([\d.e+-]+) m", out)]
    assert len(errors) == len(labels) and max(errors) < 1e-6, out
    rmse = [float(e) for e in re.findall(r"hover-and-reach: ok, position RMSE ([\d.e+-]+) m", out)]
    assert len(rmse) == len(labels) and max(rmse) < 1e-3, out
    for label in labels:
        assert re.search(rf"^{re.escape(label)} +Platform\(", out, re.M), label
        figure(tmp_path, f"tour-{label.replace(' ', '').replace('+', 'plus').lower()}.png")


def test_own_platform(tmp_path):
    """A user's own URDF and rotor file (examples/my_platform): the mass is the sum of the URDF's link masses, the IK
    reaches the pose (checked by an independent forward kinematics), the hover thrusts carry m g, the flight reaches
    the IK target."""
    out = run_example("own_platform.py", tmp_path)
    assert "Platform('quad_rrr', 4 rotors, arm RRR, 1.500 kg, under-actuated)" in out  # 1.20 + 0.08 + 0.10 + 0.07 + 0.05 kg
    assert "IK converged" in out
    assert number(r"IK position error ([\d.e+-]+) m", out) < 1e-6
    assert number(r"orientation error ([\d.e+-]+) rad", out) < 1e-6
    assert abs(number(r"sum ([\d.]+) N = m g", out) - 1.5 * 9.81) < 1e-9 * 1.5 * 9.81
    assert number(r"relative difference ([\d.e+-]+)\)", out) < 1e-9
    assert re.search(r"^flight ok:", out, re.M), out
    assert number(r"end effector ([\d.]+) mm from the target", out) < 1.0
    figure(tmp_path, "own_platform.png")
