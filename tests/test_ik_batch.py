"""Many IK targets in one call (qprr.ik.solve_many, ``qprr ik --targets``): the answers of the same solves one by one,
in the targets' order, whatever the number of worker processes; bad input refused with its name."""

from __future__ import annotations

import csv

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.cli import main
from qprr.errors import InputError
from qprr.ik import IKBatch, IKSolver, solve_many
from qprr.ik.batch import reachable_targets
from qprr.kinematics import ee_pose_xi


def _targets(platform, n: int, seed: int = 0) -> list:
    """End-effector positions of random hover configurations (reachable by construction), then one oriented target
    no level base reaches on an under-actuated platform (its y axis tilted out of the horizontal plane)."""
    out = reachable_targets(platform, n, seed)
    out.append((np.array([0.3, 0.0, 1.5]), pin.rpy.rpyToMatrix(0.4, 0.0, 0.0)))
    return out


def _same(a, b) -> bool:
    return a.status == b.status and a.iterations == b.iterations and np.array_equal(a.q, b.q) and a.reason == b.reason


@pytest.mark.parametrize("name", ["borinot_flying_arm_2", "q-prr"])
def test_a_batch_answers_as_the_same_solves_one_by_one(name):
    platform = qprr.load(name)
    solver = IKSolver(platform)
    targets = _targets(platform, 9)
    data = platform.data()
    one_by_one = [solver.solve(data, t) for t in targets]
    here = solve_many(solver, targets)
    spread = solve_many(solver, targets, workers=2)
    assert isinstance(here, IKBatch) and len(here) == len(targets) == len(spread)
    assert all(_same(a, b) for a, b in zip(one_by_one, here.results))
    assert all(_same(a, b) for a, b in zip(one_by_one, spread.results))
    np.testing.assert_array_equal(here.success, [r.success for r in one_by_one])
    assert here.success[:-1].all() and not here.success[-1]  # the random hover poses reached, the rolled one refused
    assert here.xi.shape == (len(targets), len(platform.xi_names))
    assert here.counts()["converged"] == len(targets) - 1
    assert f"{len(targets) - 1} of {len(targets)} targets reached" in here.summary()
    assert f"target {len(targets) - 1}: {one_by_one[-1].status.value}" in here.summary()


def test_a_batch_takes_one_start_for_all_or_one_per_target():
    platform = qprr.load("borinot_flying_arm_2")
    solver = IKSolver(platform)
    targets = _targets(platform, 3)[:3]
    xi0 = platform.neutral_xi().copy()
    xi0[2] = 2.0
    data = platform.data()
    common = solve_many(solver, targets, xi0=xi0)
    assert all(_same(a, solver.solve(data, t, xi0)) for a, t in zip(common.results, targets))
    each = solve_many(solver, targets, xi0=np.array([xi0] * 3))
    assert all(_same(a, b) for a, b in zip(common.results, each.results))
    as_list = solve_many(solver, targets, xi0=xi0.tolist())  # one start written as a list of numbers
    assert all(_same(a, b) for a, b in zip(common.results, as_list.results))
    mixed = solve_many(solver, targets, xi0=[None, xi0, None])
    assert _same(mixed[1], common[1]) and _same(mixed[0], solver.solve(data, targets[0]))


def test_a_batch_refuses_bad_input_with_its_name():
    platform = qprr.load("borinot_flying_arm_2")
    solver = IKSolver(platform)
    with pytest.raises(InputError, match="solver"):
        solve_many(platform, [np.zeros(3)])
    with pytest.raises(InputError, match=r"targets\[1\]"):
        solve_many(solver, [np.array([0.0, 0.0, 1.0]), np.array([0.0, np.nan, 1.0])])
    with pytest.raises(InputError, match="workers"):
        solve_many(solver, [np.array([0.0, 0.0, 1.0])], workers=0)
    with pytest.raises(InputError, match="xi0"):
        solve_many(solver, [np.array([0.0, 0.0, 1.0])] * 2, xi0=np.zeros((3, len(platform.xi_names))))
    local = IKSolver(platform, initial_guess=lambda p, d, pw, rw: (p.neutral_xi(), "lambda"))
    with pytest.raises(InputError, match="initial_guess"):
        solve_many(local, [np.array([0.0, 0.0, 1.0])] * 2, workers=2)


def test_qprr_ik_targets_solves_a_file_and_writes_its_rows(tmp_path, capsys):
    platform = qprr.load("borinot_flying_arm_2")
    positions = [t for t in _targets(platform, 4) if isinstance(t, np.ndarray)]
    path = tmp_path / "targets.csv"
    path.write_text("x,y,z\n" + "".join(",".join(f"{v:.17g}" for v in p) + "\n" for p in positions))
    out = tmp_path / "rows.csv"
    code = main(["ik", "--platform", "borinot_flying_arm_2", "--targets", str(path), "--save", str(out), "--workers", "2"])
    assert code == 0, capsys.readouterr()
    assert "4 of 4 targets reached" in capsys.readouterr().out
    rows = list(csv.DictReader(out.read_text().splitlines()))
    assert [r["status"] for r in rows] == ["converged"] * 4
    data = platform.data()
    for row, p in zip(rows, positions):  # the configuration written reaches its target
        xi = np.array([float(row[n]) for n in platform.xi_names])
        assert np.linalg.norm(ee_pose_xi(platform, data, xi)[0] - p) < 1e-6
    path.write_text("x,y,z,roll,pitch,yaw\n0.3,0,1.5,0.4,0,0\n")
    assert main(["ik", "--platform", "borinot_flying_arm_2", "--targets", str(path)]) == 1  # rolled: not reached
    path.write_text("x,y\n0.3,0\n")
    assert main(["ik", "--targets", str(path)]) == 2
    assert "no column z" in capsys.readouterr().err
    path.write_text("x,y,z,roll\n0.3,0,1,0.1\n")
    assert main(["ik", "--targets", str(path)]) == 2
    assert "roll, pitch and yaw together" in capsys.readouterr().err
    assert main(["ik", "--targets", str(path), "--rpy", "0", "0", "0"]) == 2
    assert "--rpy and --json go with one --target" in capsys.readouterr().err
    assert main(["ik", "--target", "0.3", "0", "1", "--save", str(out)]) == 2
    assert "--workers and --save go with --targets" in capsys.readouterr().err
    path.write_text("x,y,z\n0.3,0,1,7\n")
    assert main(["ik", "--targets", str(path)]) == 2
    assert "line 2: more values than the header's 3 columns" in capsys.readouterr().err
    assert main(["ik", "--targets", str(path), "--save", str(tmp_path / "no" / "rows.csv")]) == 2
    assert "no folder" in capsys.readouterr().err
    path.write_text("\ufeffx,y,z\n0.3,0,1.5\n", encoding="utf-8")  # a spreadsheet's byte-order mark
    assert main(["ik", "--platform", "borinot_flying_arm_2", "--targets", str(path)]) == 0
    capsys.readouterr()
    path.write_text("x,y,z\n\n0.3,0,1\n0.3,zero,1\n")  # a blank line: the bad row is still named by its line
    assert main(["ik", "--targets", str(path)]) == 2
    assert "line 4" in capsys.readouterr().err
    path.write_text("x,y,z\n0.3,zero,1\n")
    assert main(["ik", "--targets", str(path)]) == 2
    assert "line 2" in capsys.readouterr().err
