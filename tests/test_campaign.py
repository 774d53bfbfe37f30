"""Campaigns: specification, reproducible seeds, identical tables on every backend, resume, failures kept, reports."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from qprr.campaign import CampaignSpec, Distribution, make_backend, run_campaign
from qprr.campaign.metrics import metrics_of
from qprr.campaign.report import campaign_report, summarize
from qprr.campaign.targets import scale_bandwidth
from qprr.errors import InputError, MissingDependencyError, UnknownNameError
from qprr.scenarios import run
from qprr.thesis import gains
from qprr.thesis.flight import flight

SMALL = {
    "name": "small",
    "scenario": "static-idc",
    "seed": 11,
    "samples": 2,
    "options": {"duration": 0.3},
    "grid": {"controller": ["idc", "mfc"], "model.payload": [0.0, 0.2]},
    "random": {"model.mass": {"dist": "uniform", "low": 0.9, "high": 1.1}},
    "success": {"rmse_position": 0.05},
}

USER_FILE = '''
import numpy as np

from qprr.control.base import Controller
from qprr.sim import simulate
from qprr.thesis import load_qprr
from qprr.thesis.missions import static_mission
from qprr.thesis.scenarios import flight_controller


class Spin(Controller):
    """Weight plus a yaw torque: the yaw rate grows until the runaway bound (100 rad/s)."""

    def step(self, t, state, ref):
        return np.array([0, 0, 25.0, 0, 0, 1.0, 0, 0, 0])


def target(params, seed, platform):
    kind = params["kind"]
    if kind == "raise":
        raise ValueError("a bug in the target")
    if kind == "none":
        return 42
    ctrl = Spin() if params["spin"] else flight_controller("idc", platform)
    return simulate(platform, ctrl, static_mission(), 2.0, seed=seed)
'''


def _same_tables(a, b):
    assert a.dtype.names == b.dtype.names
    for n in a.dtype.names:
        if n == "wall_time":
            continue
        if a[n].dtype.kind == "f":
            np.testing.assert_array_equal(a[n], b[n], err_msg=n)  # NaN == NaN here
        else:
            assert a[n].tolist() == b[n].tolist(), n


# ---------------------------------------------------------------------------- specification
def test_runs_enumerate_the_grid_last_name_fastest_with_seeded_draws():
    spec = CampaignSpec.from_mapping(SMALL)
    assert spec.n_runs == 8 and spec.varying == ("controller", "model.payload", "model.mass")
    runs = list(spec.runs())
    assert [(r.params["controller"], r.params["model.payload"]) for r in runs[::2]] == [("idc", 0.0), ("idc", 0.2), ("mfc", 0.0), ("mfc", 0.2)]
    assert all(0.9 <= r.params["model.mass"] <= 1.1 for r in runs)
    assert len({r.seed for r in runs}) == 8 and len({r.params["model.mass"] for r in runs}) == 8
    again = CampaignSpec.from_mapping(SMALL)
    assert [spec.run(i) for i in (5, 0, 3)] == [again.run(i) for i in (5, 0, 3)]  # any order, any instance
    bigger = CampaignSpec.from_mapping({**SMALL, "grid": {**SMALL["grid"], "controller": ["idc", "mfc", "dsid"]}})
    assert [bigger.run(i) for i in range(8)] == runs  # adding runs leaves the earlier ones as they were


def test_paired_samples_share_draws_and_seeds_across_grid_points():
    spec = CampaignSpec.from_mapping({**SMALL, "paired": True})
    runs = list(spec.runs())
    for k in range(2):
        same = [r for r in runs if r.index % 2 == k]
        assert len({r.seed for r in same}) == 1 and len({r.params["model.mass"] for r in same}) == 1
    assert runs[0].seed != runs[1].seed
    assert spec.fingerprint != CampaignSpec.from_mapping(SMALL).fingerprint


def test_an_explicit_seed_parameter_is_the_run_seed():
    spec = CampaignSpec.from_mapping({**SMALL, "grid": {"seed": [4, 5]}, "random": {}})
    assert [r.seed for r in spec.runs()] == [4, 4, 5, 5]


@pytest.mark.parametrize(
    "change, error, match",
    [
        ({"wind": 1}, UnknownNameError, "campaign specification key"),
        ({"options": {"duraton": 1.0}}, UnknownNameError, "duration"),
        ({"grid": {"controller": ["pid"]}}, UnknownNameError, "idc"),
        ({"grid": {"model.masss": [1.0]}}, UnknownNameError, "model.mass"),
        ({"grid": {"model.mass": [0.0]}}, InputError, "mass"),
        ({"grid": {"controller": "idc"}}, InputError, "list"),
        ({"options": {"controller": "idc", "duration": 0.3}}, InputError, "twice"),
        ({"scenario": "push-thrust", "grid": {"model.mass": [1.0]}, "random": {}, "options": {}}, InputError, "perturbed plant"),
        ({"random": {"model.mass": {"dist": "uniform", "low": 2, "high": 1}}}, InputError, "low must be <= high"),
        ({"random": {"model.mass": {"dist": "gauss"}}}, UnknownNameError, "normal"),
        ({"samples": 0}, InputError, "samples"),
        ({"callable": "x:y"}, InputError, "exactly one target"),
    ],
)
def test_bad_specifications_fail_at_load_naming_the_culprit(change, error, match):
    with pytest.raises(error, match=match):
        CampaignSpec.from_mapping({**SMALL, **change})


def test_distributions_draw_within_their_support():
    rng = np.random.default_rng(0)
    d = Distribution("integers", low=2, high=4)
    assert {d.sample(rng) for _ in range(200)} == {2, 3, 4}
    d = Distribution("normal", mean=1.0, std=1.0, low=0.5, high=1.5)
    x = np.array([d.sample(rng) for _ in range(500)])
    assert x.min() == 0.5 and x.max() == 1.5 and abs(np.median(x) - 1.0) < 0.15
    d = Distribution("loguniform", low=1e-3, high=1e-1)
    x = np.log10([d.sample(rng) for _ in range(2000)])
    assert -3 <= x.min() and x.max() <= -1 and abs(x.mean() + 2) < 0.05  # uniform in the exponent
    assert Distribution("choice", values=("a", "b")).sample(rng) in ("a", "b")


def test_toml_and_json_give_the_same_specification(tmp_path):
    import json

    (tmp_path / "s.json").write_text(json.dumps(SMALL))
    toml = """name = "small"\nscenario = "static-idc"\nseed = 11\nsamples = 2\n[options]\nduration = 0.3\n[grid]
controller = ["idc", "mfc"]\n"model.payload" = [0.0, 0.2]\n[random]\n"model.mass" = { dist = "uniform", low = 0.9, high = 1.1 }
[success]\nrmse_position = 0.05\n"""
    (tmp_path / "s.toml").write_text(toml)
    a, b = CampaignSpec.load(tmp_path / "s.json"), CampaignSpec.load(tmp_path / "s.toml")
    assert a.fingerprint == b.fingerprint and list(a.runs()) == list(b.runs())


# ---------------------------------------------------------------------------- metrics
def test_metrics_are_the_result_s_own_numbers():
    res = run("static-idc", duration=2.0)
    row = metrics_of(res, ("rmse", "x_cm_max", "saturation", "recovery_time"), res.names, success={"rmse_position": 1.0})
    e = res.rmse()
    for n in res.names:
        assert row[f"rmse_{n}"] == e[n]
    assert row["rmse_position"] == pytest.approx(math.sqrt(e["x"] ** 2 + e["y"] ** 2 + e["z"] ** 2), rel=1e-15)
    assert row["x_cm_max"] == float(np.max(np.hypot(res.x_cm[:, 0], res.x_cm[:, 1])))
    assert row["saturation"] == res.saturation_fraction() and math.isnan(row["recovery_time"])
    assert row["t_end"] == pytest.approx(2.0) and row["status"] == "ok" and row["success"] == 1
    assert metrics_of(res, ("rmse",), res.names, success={"rmse_position": 1e-9})["success"] == 0


# ---------------------------------------------------------------------------- execution
def test_same_table_inline_and_on_two_local_processes(tmp_path):
    spec = CampaignSpec.from_mapping(SMALL)
    a = run_campaign(spec, tmp_path / "a.csv", backend="inline", progress=False)
    b = run_campaign(spec, tmp_path / "b.csv", backend="local", workers=2, progress=False)
    assert a.executed == b.executed == 8 and len(a.results) == 8
    _same_tables(a.results.table, b.results.table)
    t = a.results.table
    assert set(t["status"]) == {"ok"} and np.all(np.isfinite(t["rmse_position"]))
    # the plant's payload and mass reach the run: different parameters, different flights
    assert len(set(t["rmse_z"].tolist())) == 8


def test_same_table_on_a_dask_local_cluster(tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed: pip install 'qprr[dask]'")
    spec = CampaignSpec.from_mapping({**SMALL, "samples": 1})
    a = run_campaign(spec, tmp_path / "a.csv", backend="inline", progress=False)
    b = run_campaign(spec, tmp_path / "b.csv", backend="dask", workers=2, progress=False)
    assert b.backend == "dask" and b.executed == 4
    _same_tables(a.results.table, b.results.table)


@pytest.mark.slow
def test_same_table_on_a_running_scheduler_and_locally_for_a_larger_campaign(tmp_path):
    """40 runs of 2 s with random model errors: local processes, and a client on a scheduler address (--scheduler)."""
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed: pip install 'qprr[dask]'")
    import logging

    spec = CampaignSpec.from_mapping(
        {
            **SMALL,
            "samples": 10,
            "options": {"duration": 2.0},
            "random": {**SMALL["random"], "model.kappa": {"dist": "normal", "mean": 1.0, "std": 0.05}},
        }
    )
    a = run_campaign(spec, tmp_path / "a.csv", backend="local", workers=2, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None, silence_logs=logging.ERROR) as cluster:
        b = run_campaign(spec, tmp_path / "b.csv", backend="dask", scheduler=cluster.scheduler_address, progress=False)
    assert a.executed == b.executed == 40
    _same_tables(a.results.table, b.results.table)


def test_interrupted_campaign_resumes_with_only_the_missing_runs(tmp_path):
    spec = CampaignSpec.from_mapping(SMALL)
    out = tmp_path / "r.csv"
    first = run_campaign(spec, out, backend="inline", limit=3, progress=False)
    assert first.executed == 3 and len(first.results) == 3
    with out.open("a") as fh:  # a crash in the middle of a line: the cut row is ignored, its run done again
        fh.write("3,123,idc,0.2,0.95,ok,compl")
    second = run_campaign(spec, out, backend="inline", progress=False)
    assert (second.skipped, second.executed) == (3, 5)
    full = run_campaign(spec, tmp_path / "full.csv", backend="inline", progress=False)
    _same_tables(second.results.table, full.results.table)
    third = run_campaign(spec, out, backend="inline", progress=False)
    assert third.executed == 0
    other = CampaignSpec.from_mapping({**SMALL, "seed": 12})
    with pytest.raises(InputError, match="another specification"):
        run_campaign(other, out, backend="inline", progress=False)
    assert run_campaign(other, out, backend="inline", fresh=True, progress=False).executed == 8


def test_one_writer_per_results_file(tmp_path):
    from qprr.campaign.store import ResultStore

    first = ResultStore(tmp_path / "r.csv", ("run", "status"), {"fingerprint": "a"})
    with pytest.raises(InputError, match="another campaign is writing"):
        ResultStore(tmp_path / "r.csv", ("run", "status"), {"fingerprint": "a"})
    first.close()
    ResultStore(tmp_path / "r.csv", ("run", "status"), {"fingerprint": "a"}).close()  # free again
    assert not (tmp_path / "r.lock").exists()  # a finished writer leaves no lock file (issue 35)


def test_failures_and_bugs_are_rows_with_their_reason(tmp_path):
    (tmp_path / "user.py").write_text(USER_FILE)
    spec = CampaignSpec.from_mapping(
        {"name": "fail", "callable": "user.py:target", "grid": {"kind": ["fly", "raise", "none"], "spin": [0, 1]}}, base_dir=tmp_path
    )
    res = run_campaign(spec, tmp_path / "f.csv", backend="local", workers=2, progress=False).results
    t = res.table
    by = {(k, f): (s, r, te) for k, f, s, r, te in zip(t["kind"], t["spin"], t["status"], t["reason"], t["t_end"])}
    assert by[("fly", 0)][0] == "ok"
    s, r, t_end = by[("fly", 1)]  # spun up to the runaway bound: the run is kept, with where it stopped
    assert s == "diverged" and r.startswith("DivergenceError") and "bound" in r and 0 < t_end < 2.0
    assert by[("raise", 0)][:2] == ("error", "ValueError: a bug in the target")
    assert by[("none", 0)][0] == "error" and "int" in by[("none", 0)][1]
    assert np.all(np.isnan(t["rmse_x"][t["status"] != "ok"]))
    # an error row (a bug in the target) is done again on resume; the others are kept
    again = run_campaign(spec, tmp_path / "f.csv", backend="inline", progress=False)
    assert again.executed == int(np.sum(t["status"] == "error"))


def test_parquet_results_read_like_csv(tmp_path):
    pytest.importorskip("pyarrow", reason="pyarrow is not installed: pip install 'qprr[parquet]'")
    spec = CampaignSpec.from_mapping({**SMALL, "samples": 1})
    a = run_campaign(spec, tmp_path / "a.csv", backend="inline", progress=False)
    b = run_campaign(spec, tmp_path / "a.parquet", backend="inline", progress=False)
    assert (tmp_path / "a.parquet").is_dir()
    _same_tables(a.results.table, b.results.table)


def test_missing_dask_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(MissingDependencyError, match="pip install"):
        make_backend("dask")


# ---------------------------------------------------------------------------- report and CLI
def test_summary_and_figures(tmp_path):
    spec = CampaignSpec.from_mapping(SMALL)
    res = run_campaign(spec, tmp_path / "a.csv", backend="inline", progress=False).results
    summ = summarize(res)
    assert summ.groups == ("controller", "model.payload") and [r["n"] for r in summ.rows] == [2, 2, 2, 2]
    for row in summ.rows:
        sel = (res.table["controller"] == row["controller"]) & (res.table["model.payload"] == row["model.payload"])
        assert row["success"] == pytest.approx(np.mean(res.table["success"][sel]))
        assert row["rmse_position"]["median"] == pytest.approx(np.median(res.table["rmse_position"][sel]))
    text, figures = campaign_report(res, tmp_path / "rep")
    assert "controller" in text and (tmp_path / "rep" / "summary.md").is_file()
    assert figures and all(f.stat().st_size > 5000 for f in figures)


def test_cli_run_then_report(tmp_path, capsys):
    import json

    from qprr.cli import main

    (tmp_path / "s.json").write_text(json.dumps({**SMALL, "samples": 1}))
    assert main(["campaign", "run", str(tmp_path / "s.json"), "-o", str(tmp_path / "o.csv"), "--backend", "inline", "--quiet"]) == 0
    assert main(["campaign", "report", str(tmp_path / "o.csv"), "--out", str(tmp_path / "rep")]) == 0
    out = capsys.readouterr().out
    assert "4 runs" in out and "figure" in out
    assert main(["campaign", "run", str(tmp_path / "missing.toml")]) == 2


# ---------------------------------------------------------------------------- flight target
def test_flight_target_with_defaults_is_the_static_idc_scenario():
    a = flight({"duration": 1.0}, 0)
    b = run("static-idc", duration=1.0, seed=0)
    np.testing.assert_array_equal(a.xi, b.xi)
    np.testing.assert_array_equal(a.u, b.u)


def test_flight_target_parameters_reach_the_run():
    base = flight({"duration": 0.5}, 3)
    noisy = flight({"duration": 0.5, "noise": 1.0}, 3)
    assert np.abs(base.u_ext).max() == 0  # (6.27) noise of the noise scenario: +-0.3 on x..r0, +-0.01 on theta2, theta3
    assert 0.29 < np.abs(noisy.u_ext[:, :7]).max() <= 0.3 and 0.0095 < np.abs(noisy.u_ext[:, 7:]).max() <= 0.01
    heavy = flight({"duration": 0.5, "model.mass": 1.1}, 3)
    assert heavy.xi[-1, 2] < base.xi[-1, 2]  # a heavier plant climbs less under the nominal model's thrust
    fast = flight({"duration": 0.5, "bandwidth.position": 2.0}, 3)
    assert not np.array_equal(fast.u, base.u)
    with pytest.raises(UnknownNameError, match="bandwidth.position"):
        flight({"bandwith.position": 2.0}, 3)


@pytest.mark.parametrize("s", [0.5, 2.0])
def test_bandwidth_factor_scales_every_loop_pole(s):
    g = gains.idc()
    h = scale_bandwidth(g, "attitude", s, 9)
    for i in range(9):
        p0 = np.sort_complex(np.roots([1.0, g.kd[i], g.kp[i], g.ki[i]]))
        p1 = np.sort_complex(np.roots([1.0, h.kd[i], h.kp[i], h.ki[i]]))
        np.testing.assert_allclose(p1, p0 * (s if i in (3, 4, 5) else 1.0), rtol=1e-6, atol=1e-9)
