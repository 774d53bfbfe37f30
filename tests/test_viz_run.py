"""Runs for the viewers: result files of the simulator read as RunLogs, SimResult-like objects, clear errors."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

import qprr
from qprr.scenarios import run as run_scenario
from qprr.viz import RunLog, load_run
from qprr.viz.run import as_run


@pytest.fixture(scope="module")
def result():
    """A real run: hover-reach of the Q-PRR, 0.3 s, with a contact wrench series (n, 6)."""
    res = run_scenario("hover-reach", duration=0.3)
    res.series["contact_wrench_world"] = np.random.default_rng(7).normal(size=(res.n, 6))
    return res


def test_a_result_file_is_read_as_the_run_it_logged(result, tmp_path):
    run = load_run(result.save(tmp_path / "run.npz"))
    for name in ("t", "xi", "f", "arm_effort"):
        np.testing.assert_array_equal(getattr(run, name), getattr(result, name))
    np.testing.assert_array_equal(run.contact_wrench_world, result.series["contact_wrench_world"])
    assert run.platform == result.platform and run.n == result.n and run.xi.shape[1] == 9


def test_a_result_without_contact_series(result):
    res = dataclasses.replace(result, series={})
    run = as_run(res)
    assert run.contact_wrench_world is None and run.platform == result.platform
    np.testing.assert_array_equal(run.arm_effort, result.arm_effort)
    assert as_run(run) is run
    with pytest.raises(qprr.errors.InputError, match="must be a run: a qprr.sim.SimResult or a qprr.viz.RunLog.*SimpleNamespace"):
        as_run(SimpleNamespace(t=result.t, xi=result.xi))


def test_missing_foreign_and_truncated_files_are_clear_errors(result, tmp_path):
    with pytest.raises(qprr.errors.InputError, match=r"result file .*nope\.npz.* does not exist"):
        load_run(tmp_path / "nope.npz")
    bad = tmp_path / "bad.npz"
    bad.write_text("not a zip")
    with pytest.raises(qprr.errors.InputError, match="not a qprr result file"):
        load_run(bad)
    np.savez(tmp_path / "t_only.npz", t=np.arange(3.0))
    with pytest.raises(qprr.errors.InputError, match="no qprr metadata"):
        load_run(tmp_path / "t_only.npz")
    good = result.save(tmp_path / "good.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(good[: len(good) // 2])
    with pytest.raises(qprr.errors.InputError, match="cut.npz"):
        load_run(tmp_path / "cut.npz")


def test_runlog_validates_shapes_and_values():
    t, xi = np.arange(4.0), np.zeros((4, 9))
    with pytest.raises(qprr.errors.ShapeError, match=r"xi must have shape \(4, 6 \+ n_arm\)"):
        RunLog(t, np.zeros((3, 9)))
    with pytest.raises(qprr.errors.ShapeError, match=r"contact_wrench_world must have shape \(4, 6\)"):
        RunLog(t, xi, contact_wrench_world=np.zeros((4, 3)))
    with pytest.raises(qprr.errors.InputError, match="non-decreasing"):
        RunLog(t[::-1], xi)
    xi_bad = xi.copy()
    xi_bad[2, 4] = np.nan
    with pytest.raises(qprr.errors.NonFiniteError, match="first bad row 2"):
        RunLog(t, xi_bad)
    run = RunLog(t, xi)
    with pytest.raises(ValueError):
        run.xi[0, 0] = 1.0  # read-only
