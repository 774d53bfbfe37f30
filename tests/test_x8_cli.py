"""The X8 test robot of issue 35 (tests/x8_robot.py: a coaxial octocopter with a yaw / pitch / telescope / pitch arm)
through the command line, as a new user would fly it: ``qprr inspect``, ``qprr ik`` (a target it reaches and a rolled
one it cannot hold in hover), a mission file with a payload grasped and released (``qprr simulate`` saving the run,
its figure and ``qprr animate``'s GIF), and a robustness campaign whose success rate follows from the thrust it has.
"""

from __future__ import annotations

import csv
import json
import shutil

import numpy as np
import pinocchio as pin
import pytest

from qprr import charts
from qprr.cli import main
from qprr.payload import with_payload
from qprr.sim import SimResult
from qprr.trajectory import transition
from tests import x8_robot
from tests.x8_robot import CLI, JOINTS, ROTOR_NAMES, TELESCOPE_STROKE, TOTAL_MASS

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

G = 9.81  # [m/s^2] qprr.from_urdf's default
PAYLOAD_COLOUR = np.array([0x16, 0xA0, 0x85])  # qprr.viz.animation's payload ball


@pytest.fixture(scope="module")
def x8():
    return x8_robot.load()


def cli(capsys, *argv: str, code: int = 0) -> str:
    """``qprr ARGV`` run in this process: its stdout and stderr, after checking the exit code."""
    assert main([*argv]) == code, capsys.readouterr()
    out = capsys.readouterr()
    return out.out + out.err


def test_x8_files_say_what_is_built(x8):
    """Mass, joint types and limits, rotor names and the hover thrust m g / 8 per rotor, from the files."""
    assert sum(x8.model.inertias[i].mass for i in range(1, x8.model.njoints)) == TOTAL_MASS
    assert tuple(x8.model.names[2:]) == JOINTS
    assert tuple(r.name for r in x8.rotors) == ROTOR_NAMES and len(ROTOR_NAMES) == 8
    telescope = x8.model.joints[x8.model.getJointId("telescope")]
    assert telescope.nq == 1 and x8.model.lowerPositionLimit[telescope.idx_q] == 0.0
    assert x8.model.upperPositionLimit[telescope.idx_q] == TELESCOPE_STROKE
    for i in range(1, x8.model.njoints):  # physically plausible: the principal moments satisfy the triangle inequality
        moments = np.linalg.eigvalsh(x8.model.inertias[i].inertia)
        assert moments.sum() >= 2.0 * moments.max()
    summary = x8.actuation_summary()  # the CoG is on the thrust axis at the neutral pose: equal thrusts m g / 8
    assert summary.rank == 4 and summary.can_hover and summary.can_control_attitude
    np.testing.assert_allclose(summary.hover_thrusts, TOTAL_MASS * G / 8, rtol=1e-12)
    com = pin.centerOfMass(x8.model, x8.model.createData(), x8.neutral_q())
    np.testing.assert_allclose(com[:2], 0.0, atol=1e-15)


def test_inspect_prints_the_files_names_and_numbers(capsys, x8):
    out = cli(capsys, "inspect", *CLI)
    assert out.startswith("platform x8_arm4")
    for joint in x8.arm:
        assert f"  {joint.name} ({joint.kind}): [{joint.lower:.4g}, {joint.upper:.4g}]" in out
    assert "telescope (prismatic): [0, 0.25] m, 20 N, 0.5 m/s, damping 0.5 N s/m, friction 0.2 N" in out
    assert all(f"  {name}: [" in out for name in ROTOR_NAMES)
    hover = TOTAL_MASS * G / 8
    assert f"hover thrusts [{', '.join([f'{hover:.4g}'] * 8)}] N" in out
    assert "total mass 3 kg" in out and "wrench rank 4/6 (under-actuated)" in out


def test_ik_reaches_a_target_and_explains_a_rolled_one(capsys, x8):
    """A target below and ahead: reached in hover (FK of the printed configuration puts the gripper there).  The same
    target rolled 0.5 rad: not reachable in hover by a platform whose thrust is along z_B (the arm's axes are z, y, the
    telescope and y: no roll), and the reason says so instead of suggesting another start."""
    target = np.array([0.25, 0.1, 0.9])
    report = json.loads(cli(capsys, "ik", *CLI, "--target", *map(str, target), "--json"))
    assert report["success"] and report["status"] == "converged" and report["reason"] == ""
    xi = np.array([report["xi"][name] for name in x8.xi_names])
    data = x8.data()
    pin.framesForwardKinematics(x8.model, data, charts.xi_to_q(xi))
    assert np.linalg.norm(data.oMf[x8.ee_frame].translation - target) < 1e-9
    assert abs(xi[3]) < 1e-9 and abs(xi[4]) < 1e-9  # level base: hovering
    out = cli(capsys, "ik", *CLI, "--target", *map(str, target), "--rpy", "0.5", "0", "0", code=1)
    reason = next(line for line in out.splitlines() if line.startswith("reason:"))
    assert "another xi0" not in reason
    assert "needs the base at roll = 0.5 rad" in reason and "under-actuated" in reason and "thrust along z_B" in reason


@pytest.fixture(scope="module")
def mission_run(tmp_path_factory):
    """tests/robots/x8_arm4/mission.toml flown from the command line (4.5 s at 2 ms): its printed summary, the saved
    result and figure."""
    out_dir = tmp_path_factory.mktemp("x8_mission")
    npz, png = out_dir / "mission.npz", out_dir / "mission.png"
    argv = ["simulate", "mission", *CLI, "--set", f"mission={x8_robot.DIR / 'mission.toml'}", "--duration", "4.5", "--dt", "0.002"]
    assert main([*argv, "-q", "--save", str(npz), "--plot", str(png)]) == 0
    return npz, png


def test_mission_flies_the_payload_the_file_gives(mission_run, x8):
    """The payload events of the file (0.3 kg at 2.0 s, released at 4.0 s) are what the plant carried: the logged
    payload mass, and the simulator's CoG in B against Pinocchio's CoG of the robot with (and without) 0.3 kg at the
    gripper, at the logged configurations, to machine precision.  The figure is written beside the run."""
    npz, png = mission_run
    res = SimResult.load(npz)
    assert res.status == "ok" and res.rotor_names == ROTOR_NAMES and res.names[6:] == JOINTS
    events = tomllib.loads((x8_robot.DIR / "mission.toml").read_text())["payload"]
    (grasp, m_p), (release, m_after) = [(e["time"], e["mass"]) for e in events]
    carried = np.where((res.t >= grasp - 1e-12) & (res.t < release - 1e-12), m_p, m_after)
    np.testing.assert_array_equal(res.series["payload_mass"], carried)
    loaded = with_payload(x8, m_p)
    for t, model in ((grasp - 0.1, x8.model), (0.5 * (grasp + release), loaded.model), (release + 0.2, x8.model)):
        k = int(np.argmin(np.abs(res.t - t)))
        q = charts.xi_to_q(res.xi[k])
        com_world = pin.centerOfMass(model, model.createData(), q)
        R = charts.euler_to_rotation(res.xi[k, 3:6])
        np.testing.assert_allclose(res.x_cm[k], R.T @ (com_world - res.xi[k, 0:3]), atol=1e-12)
    assert np.max(np.abs(res.x_cm[(res.t > grasp + 0.05) & (res.t < release), 0])) > 1e-3  # the payload moved the CoG
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 50_000


def test_animation_draws_the_payload_while_carried(mission_run, tmp_path, capsys):
    """``qprr animate`` of the mission's result at 2 fps: the payload's colour is in the frames between the grasp and
    the release, and in no frame before or after."""
    from PIL import Image

    npz, _ = mission_run
    gif = tmp_path / "mission.gif"
    cli(capsys, "animate", str(npz), *CLI, "-o", str(gif), "--fps", "2", "-q")
    frames = []
    with Image.open(gif) as im:
        for k in range(im.n_frames):
            im.seek(k)
            rgb = np.asarray(im.convert("RGB"), dtype=int)
            frames.append(int(np.sum(np.all(np.abs(rgb - PAYLOAD_COLOUR) <= 2, axis=2))))
    times = 0.5 * np.arange(len(frames))  # 2 fps from t = 0
    legend_swatch = min(frames)  # the legend's entry, on every frame
    carrying = [n - legend_swatch for t, n in zip(times, frames) if 2.0 < t < 4.0]
    empty = [n - legend_swatch for t, n in zip(times, frames) if t < 2.0 or t > 4.0]
    assert carrying and min(carrying) > 20 and max(empty) == 0, frames


def test_robustness_campaign_success_follows_the_thrust(tmp_path, capsys, x8):
    """tests/robots/x8_arm4/robustness.toml: takeoff-hover with every rotor's f_max scaled by a random factor k (the
    controller's model is otherwise exact).  Physics: the rotors hold the weight only if k 8 f_max >= m g; they also
    fly the climb untouched if k f_max >= (m g / 8)(1 + a_max / g), a_max the reference's largest climb acceleration.
    A run below the first bound must fail (it sinks), one 5 % above the second (room for the feedback) must succeed;
    the campaign's success rate is the share of draws above it.  No .lock is left beside the finished results."""
    for name in ("x8_arm4.urdf", "x8_arm4.rotors.toml", "robustness.toml"):
        shutil.copy(x8_robot.DIR / name, tmp_path / name)
    spec = tomllib.loads((tmp_path / "robustness.toml").read_text())
    results = tmp_path / "r.csv"
    cli(capsys, "campaign", "run", str(tmp_path / "robustness.toml"), "-o", str(results), "--backend", "inline", "--quiet")
    with results.open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == spec["samples"] and {r["status"] for r in rows} == {"ok"}
    o = spec["options"]
    t = np.linspace(0.0, 0.4 * o["duration"], 2001)  # takeoff-hover climbs over the first 40 % of the run
    a_max = float(np.max(np.abs(transition(t, 0.0, 0.4 * o["duration"], 0.0, o["z"], order=2)[2])))
    f_max = np.array([r.f_max for r in x8.rotors])
    k_weight = TOTAL_MASS * G / f_max.sum()
    k_climb = 1.05 * k_weight * (1.0 + a_max / G)
    predicted, measured = [], []
    for r in rows:
        k = float(r["model.f_max"])
        if k_weight <= k <= k_climb:
            continue  # saturated during the climb only: either outcome
        predicted.append(k > k_climb)
        measured.append(r["success"] == "1")
        if k < k_weight:  # sinking at g (1 - k / k_weight): far below the 5 cm bound on the height RMSE
            assert float(r["rmse_z"]) > 10 * spec["success"]["rmse_z"] and float(r["saturation"]) > 0.9
    assert measured == predicted and len(predicted) >= 4 and any(predicted) and not all(predicted)
    rate = np.mean([r["success"] == "1" for r in rows])
    assert rate == np.mean([float(r["model.f_max"]) > k_climb for r in rows])
    assert not list(tmp_path.glob("*.lock"))
    report = cli(capsys, "campaign", "report", str(results), "--out", str(tmp_path / "report"))
    n_ok = sum(r["success"] == "1" for r in rows)
    assert f"{n_ok} successful ({100 * rate:.1f} %)" in report, report  # the rate stated is the one derived above
