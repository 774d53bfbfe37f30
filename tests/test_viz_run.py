"""Saved runs: the .npz round trip, SimResult-like objects, and clear errors for bad files."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import qprr
from qprr.viz import RunLog, load_run, save_run
from qprr.viz.run import as_run


def _run(n=50, with_all=True):
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(0.0, 0.01, n))
    kw = dict(f=rng.uniform(0, 20, (n, 4)), arm_effort=rng.normal(size=(n, 3)), x_cm=rng.normal(size=(n, 2)) * 1e-3,
              contact_wrench_world=rng.normal(size=(n, 6))) if with_all else {}
    return RunLog(t, rng.normal(size=(n, 9)), platform="Q-PRR (thesis, plus)", **kw)


def test_round_trip_is_exact(tmp_path):
    run = _run()
    back = load_run(save_run(run, tmp_path / "a" / "run.npz"))
    for name in ("t", "xi", "f", "arm_effort", "x_cm", "contact_wrench_world"):
        np.testing.assert_array_equal(getattr(back, name), getattr(run, name))
    assert back.platform == run.platform and back.n == 50


def test_optional_arrays_stay_absent(tmp_path):
    back = load_run(save_run(_run(with_all=False), tmp_path / "run.npz"))
    assert back.f is None and back.contact_wrench_world is None and back.xi.shape == (50, 9)


def test_a_simresult_like_object_is_saved(tmp_path):
    run = _run()
    sim = SimpleNamespace(t=run.t, xi=run.xi, f=run.f, arm_effort=run.arm_effort, x_cm=run.x_cm, platform="Q-PRR", u=np.zeros(3))
    back = load_run(save_run(sim, tmp_path / "sim.npz"))
    np.testing.assert_array_equal(back.f, run.f)
    assert back.contact_wrench_world is None and back.platform == "Q-PRR"
    with pytest.raises(qprr.InputError, match="lacks xi"):
        as_run(SimpleNamespace(t=run.t))


def test_missing_file_is_a_clear_error(tmp_path):
    with pytest.raises(qprr.InputError, match=r"run file .*nope\.npz.* does not exist"):
        load_run(tmp_path / "nope.npz")


def test_not_an_archive_and_missing_arrays(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_text("not a zip")
    with pytest.raises(qprr.InputError, match="not a .npz archive"):
        load_run(bad)
    np.savez(tmp_path / "t_only.npz", t=np.arange(3.0))
    with pytest.raises(qprr.InputError, match=r"lacks the array\(s\) xi; it holds \['t'\]"):
        load_run(tmp_path / "t_only.npz")
    with pytest.raises(qprr.InputError, match="end in .npz"):
        save_run(_run(), tmp_path / "run.txt")


def test_runlog_validates_shapes_and_values():
    t, xi = np.arange(4.0), np.zeros((4, 9))
    with pytest.raises(qprr.ShapeError, match=r"xi must have shape \(4, 6 \+ n_arm\)"):
        RunLog(t, np.zeros((3, 9)))
    with pytest.raises(qprr.ShapeError, match=r"x_cm must have shape \(4, 2\)"):
        RunLog(t, xi, x_cm=np.zeros((4, 3)))
    with pytest.raises(qprr.InputError, match="non-decreasing"):
        RunLog(t[::-1], xi)
    xi_bad = xi.copy()
    xi_bad[2, 4] = np.nan
    with pytest.raises(qprr.NonFiniteError, match="first bad row 2"):
        RunLog(t, xi_bad)
    run = RunLog(t, xi)
    with pytest.raises(ValueError):
        run.xi[0, 0] = 1.0  # read-only
