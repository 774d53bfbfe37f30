"""Design search over the (2.1) nomenclature (qprr.design): specification, evaluation, search, Pareto front, resume."""

from __future__ import annotations

import csv
import io
import math
import sys

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr.analysis import balance, capacity, hover, singularity, workspace
from qprr.campaign import read_results
from qprr.design import DesignSpec, dominated, front, front_levels, ranked, run_design
from qprr.design.report import rows_of
from qprr.design.search import INSTALL, make_optimiser
from qprr.errors import InputError, MissingDependencyError
from qprr.nomenclature import LinkSpec

SAMPLES = 400


def tiny(**over) -> dict:
    d = {
        "name": "tiny",
        "seed": 3,
        "architectures": ["Q-PRR", "Q-RR", "HEX-RRR"],
        "objectives": ["hover_volume", "balance_fraction", "thrust_margin", "arm_mass"],
        "parameters": {"reach": 0.3, "taper": 0.6, "slider_stroke": 0.08, "slider_link": 0.05, "total_mass": 3.0, "thrust_to_weight": 2.0},
        "effort": {"samples": SAMPLES},
        "constraints": {"thrust_margin": {"min": 0.0}},
    }
    d.update(over)
    return d


def same_table(a, b) -> None:
    """Two results files hold the same rows, bit for bit in every column but the wall time (NaN equal to NaN)."""
    ta, tb = read_results(a).table, read_results(b).table
    assert ta.dtype.names == tb.dtype.names and len(ta) == len(tb)
    for k in ta.dtype.names:
        if k != "wall_time":
            np.testing.assert_array_equal(ta[k], tb[k], err_msg=k, strict=True)


# ------------------------------------------------------------------------------ specification
@pytest.mark.parametrize(
    "change, key, fix",
    [
        ({"architectures": ["Q-PRRX"]}, "architectures", "(2.1) name"),
        ({"architectures": ["3Q-RR"]}, "architectures", "one multirotor"),
        ({"architectures": ["Q-PPR"]}, "architectures", "at most one P joint"),
        ({"objectives": ["hover_volume"]}, "objectives", "at least 2"),
        ({"objectives": ["hover_volume", "speed"]}, "objectives", "names among"),
        ({"parameters": {"reach": -0.1}}, "parameters.reach", ">= 0.05"),
        ({"parameters": {"length": 0.2}}, "parameters.length", "use one of reach"),
        ({"parameters": {"reach": {"low": 0.3, "high": 0.2}}}, "parameters.reach", "low < high"),
        ({"parameters": {"reach": {"low": 0.2, "high": 0.3}}}, "parameters.reach", "nsga2"),
        ({"search": {"method": "nsga2"}}, "search.method", "range"),
        ({"search": {"method": "grid", "optimiser": "deap"}}, "search.optimiser", "pymoo, optuna"),
        ({"mass": {"material": "steel"}}, "mass.material", "carbon"),
        ({"constraints": {"thrust_margin": {"least": 1}}}, "constraints.thrust_margin.least", "min, max"),
        ({"effort": {"samples": 3}}, "effort.samples", ">= 64"),
        ({"closed_loop": {"scenario": "static-idc"}}, "closed_loop.scenario", "generic scenario"),
        ({"colour": "red"}, "colour", "remove it"),
    ],
)
def test_spec_errors_name_key_value_and_fix(change, key, fix):
    with pytest.raises(InputError) as err:
        DesignSpec.from_mapping(tiny(**change))
    msg = str(err.value)
    assert f"{key} = " in msg and "fix:" in msg and fix in msg, msg


def test_spec_round_trips_and_loads_the_examples():
    s = DesignSpec.from_mapping(tiny())
    assert DesignSpec.from_mapping(s.to_dict()) == s and DesignSpec.from_mapping(s.to_dict()).fingerprint == s.fingerprint
    for f in ("thesis_architectures.toml", "thesis_architectures_free.toml"):
        spec = DesignSpec.load(f"examples/design/{f}")
        assert "Q-PRR" in spec.architectures and spec.references == ("q-prr",)


# ------------------------------------------------------------------------------ evaluation = the maps
def hit_share(region, balanced_body, across=40) -> float:
    """Cells of the workspace's plane (its origin and basis) hit by a balanced point over cells hit by any."""
    ws, bal = (region.points_body - region.origin) @ region.basis.T, (balanced_body - region.origin) @ region.basis.T
    lo = ws.min(axis=0)
    h = np.max(ws.max(axis=0) - lo) / across
    cells = np.unique(np.floor((ws - lo) / h), axis=0)
    hit = np.unique(np.floor((bal - lo) / h), axis=0)
    both = (hit[:, None, :] == cells[None, :, :]).all(axis=2).any(axis=1)
    return both.sum() / len(cells)


def test_balance_share_limits():
    """A tolerance of 1 m balances everything (share 1); the share grows with the tolerance; at 1 nm only the
    postures with the arm's CoG on z_B remain (the straight-up arm), a few cells."""
    from qprr.design.evaluate import balanced_share

    p = qprr.build("Q-RR")
    region = workspace(p, n_samples=SAMPLES, variants=[]).regions[0]
    shares = [balanced_share(region, balance(p, slider=None, n_samples=SAMPLES, tol=t)) for t in (1e-9, 1e-3, 1e-2, 1.0)]
    assert shares == sorted(shares) and shares[-1] == 1.0 and 0.0 < shares[0] < 0.02


def test_grid_reproduces_the_analysis_maps(tmp_path):
    """Each row equals the maps run directly on a platform built by hand from the (2.1) name and the mass model."""
    spec = DesignSpec.from_mapping(tiny())
    run = run_design(spec, tmp_path / "t.csv", backend="inline", progress=False)
    rows = {r["name"]: r for r in rows_of(run.results.table)}
    assert set(rows) == {"Q-PRR", "Q-RR", "HEX-RRR"} and all(r["status"] == "ok" for r in rows.values())
    m = spec.mass
    d2, d3 = 0.3 / 1.6, 0.3 * 0.6 / 1.6  # reach 0.3 m shared 1 : 0.6
    lengths = {"Q-PRR": [0.05, d2, d3], "Q-RR": [d2, d3], "HEX-RRR": [0.3 / 1.96, 0.18 / 1.96, 0.108 / 1.96]}
    for name, ls in lengths.items():
        joints = name.split("-")[1]
        links = [
            LinkSpec("P", length=L, mass=m.prismatic_actuator + m.link_density * L + m.rail_density * 0.08, lower=-0.04, upper=0.04)
            if k == "P"
            else LinkSpec("R", length=L, mass=m.revolute_actuator + m.link_density * L)
            for k, L in zip(joints, ls)
        ]
        m_arm = sum(k.mass for k in links)
        p = qprr.build(name, links=links, body_mass=3.0 - m_arm, thrust_to_weight=2.0)
        assert math.isclose(pin.computeTotalMass(p.model), 3.0, rel_tol=1e-14)  # equal take-off mass
        assert math.isclose(sum(r.f_max for r in p.rotors), 2.0 * 3.0 * 9.81, rel_tol=1e-14)  # equal total thrust
        r = rows[name]
        seed = int(r["seed"])
        slider = "joint1" if joints[0] == "P" else None
        ws = workspace(p, n_samples=SAMPLES, variants=[], n_shifts=4, seed=seed)
        assert r["hover_volume"] == ws.regions[0].hover_volume.measure
        b = balance(p, slider=slider, n_samples=SAMPLES, tol=1e-3)
        assert r["balance_fraction"] == hit_share(ws.regions[0], b.ee_body[b.balanced])
        assert r["thrust_margin"] == hover(p, n_samples=SAMPLES).min_thrust_margin[0]
        c = capacity(p, n_samples=SAMPLES)
        far = np.hypot(c.ee_body[:, 0], c.ee_body[:, 1]) >= 0.15
        assert r["payload_at_reach"] == c.capacity[far].max()
        assert r["manipulability"] == np.median(singularity(p, n_samples=SAMPLES, task="position").manipulability)
        assert math.isclose(r["arm_mass"], m_arm, rel_tol=1e-12) and math.isclose(r["mass"], 3.0, rel_tol=1e-14)
    # physics: the slider costs its mass; at equal reach and mass the Q-RR hovers with the widest margin of the three
    assert rows["Q-PRR"]["arm_mass"] > rows["Q-RR"]["arm_mass"]
    assert rows["Q-RR"]["thrust_margin"] > rows["HEX-RRR"]["thrust_margin"]


def test_collision_free_hover_volume_when_a_study_names_it(tmp_path):
    """free_hover_volume is the workspace map's collision-free hover volume (the same number as the map run directly),
    at most the hover volume; a study that does not name it leaves it NaN (no collision check)."""
    spec = DesignSpec.from_mapping(tiny(architectures=["Q-RR", "HEX-RRR"], objectives=["free_hover_volume", "arm_mass"]))
    run = run_design(spec, tmp_path / "f.csv", backend="inline", progress=False)
    rows = {r["name"]: r for r in rows_of(run.results.table)}
    for r in rows.values():
        assert r["status"] == "ok", r["reason"]
        assert 0.0 < r["free_hover_volume"] <= r["hover_volume"]
    m, d2, d3 = spec.mass, 0.3 / 1.6, 0.3 * 0.6 / 1.6  # the Q-RR of the study, built by hand (as above)
    links = [LinkSpec("R", length=L, mass=m.revolute_actuator + m.link_density * L) for L in (d2, d3)]
    p = qprr.build("Q-RR", links=links, body_mass=3.0 - sum(k.mass for k in links), thrust_to_weight=2.0)
    r = rows["Q-RR"]
    ws = workspace(p, n_samples=SAMPLES, variants=[], n_shifts=4, seed=int(r["seed"]), collision=True)
    assert r["free_hover_volume"] == ws.regions[0].free_hover_volume.measure
    plain = run_design(DesignSpec.from_mapping(tiny(architectures=["Q-RR"])), tmp_path / "p.csv", backend="inline", progress=False)
    assert all(math.isnan(r["free_hover_volume"]) for r in rows_of(plain.results.table))


def test_an_arm_heavier_than_the_budget_is_a_failed_row(tmp_path):
    spec = DesignSpec.from_mapping(tiny(architectures=["Q-RRR"], parameters={"reach": 1.9, "total_mass": 0.3}))
    row = rows_of(run_design(spec, tmp_path / "t.csv", backend="inline", progress=False).results.table)[0]
    assert row["status"] == "failed" and "total_mass" in row["reason"] and row["feasible"] == 0


# ------------------------------------------------------------------------------ backends, resume
def test_same_table_inline_and_on_local_processes(tmp_path):
    spec = DesignSpec.from_mapping(tiny(references=["q-prr"]))
    run_design(spec, tmp_path / "a.csv", backend="inline", progress=False)
    run_design(spec, tmp_path / "b.csv", backend="local", workers=2, progress=False)
    same_table(tmp_path / "a.csv", tmp_path / "b.csv")


def test_same_table_on_dask(tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed: pip install 'qprr[dask]'")
    spec = DesignSpec.from_mapping(tiny(architectures=["Q-PRR", "HEX-RRR"]))
    run_design(spec, tmp_path / "a.csv", backend="inline", progress=False)
    run_design(spec, tmp_path / "b.csv", backend="dask", workers=2, progress=False)
    same_table(tmp_path / "a.csv", tmp_path / "b.csv")


def test_resume_evaluates_only_the_missing_designs(tmp_path):
    spec = DesignSpec.from_mapping(tiny())
    run_design(spec, tmp_path / "a.csv", backend="inline", progress=False)
    lines = (tmp_path / "a.csv").read_text().splitlines(keepends=True)
    (tmp_path / "a.csv").write_text("".join(lines[:2]) + lines[2][:20])  # one row saved, one cut by a crash
    again = run_design(spec, tmp_path / "a.csv", backend="inline", progress=False)
    assert (again.skipped, again.executed) == (1, 2)
    run_design(spec, tmp_path / "b.csv", backend="inline", progress=False)
    same_table(tmp_path / "a.csv", tmp_path / "b.csv")
    other = DesignSpec.from_mapping(tiny(seed=4))
    with pytest.raises(InputError, match="another specification"):
        run_design(other, tmp_path / "a.csv", backend="inline", progress=False)


# ------------------------------------------------------------------------------ Pareto front
@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(*[st.integers(0, 5)] * 3), min_size=1, max_size=25))
def test_dominance_and_levels_match_brute_force(points):
    F = np.array(points, dtype=float)
    dom = dominated(F)
    for i in range(len(F)):
        brute = any(np.all(F[j] <= F[i]) and np.any(F[j] < F[i]) for j in range(len(F)))
        assert dom[i] == brute
    lv = front_levels(F)
    for i in range(len(F)):  # a point of level k > 1 is dominated by one of level k - 1 and by none of level >= k
        better = [j for j in range(len(F)) if np.all(F[j] <= F[i]) and np.any(F[j] < F[i])]
        assert (lv[i] == 1) == (not better)
        assert all(lv[j] < lv[i] for j in better)
        if lv[i] > 1:
            assert any(lv[j] == lv[i] - 1 for j in better)


def test_no_design_of_the_front_is_dominated_by_an_evaluated_one(tmp_path):
    spec = DesignSpec.from_mapping(
        tiny(architectures=["Q-PRR", "Q-RR", "Q-RRR", "Q-RPR", "HEX-RR"], parameters={"reach": [0.2, 0.3], "taper": 0.6, "total_mass": 3.0})
    )
    rows = rows_of(run_design(spec, tmp_path / "t.csv", backend="inline", progress=False).results.table)
    assert len(rows) == 10
    fr = front(rows, spec.objectives)
    feas = [r for r in rows if r["status"] == "ok" and r["feasible"] == 1]
    assert fr
    for a in fr:
        for b in feas:
            fa = [r * (1 if k == "arm_mass" else -1) for k, r in ((k, a[k]) for k in spec.objectives)]
            fb = [r * (1 if k == "arm_mass" else -1) for k, r in ((k, b[k]) for k in spec.objectives)]
            assert not (all(y <= x for x, y in zip(fa, fb)) and any(y < x for x, y in zip(fa, fb)))
    rk = ranked(rows, spec.objectives)
    assert [r["level"] for r in rk if r["level"] >= 1] == sorted(r["level"] for r in rk if r["level"] >= 1)


# ------------------------------------------------------------------------------ optimiser
def test_missing_optimiser_raises_with_the_install_command(monkeypatch):
    for mod, name in (("pymoo", "pymoo"), ("optuna", "optuna")):
        monkeypatch.setitem(sys.modules, mod, None)
        with pytest.raises(MissingDependencyError) as err:
            make_optimiser(name, [0.0], [1.0], 2, 1, 4, 0)
        assert INSTALL[name] in str(err.value) and "pip install" in INSTALL[name]


@pytest.mark.parametrize("engine", ["pymoo", "optuna"])
def test_nsga2_is_seeded_resumable_and_feasible(engine, tmp_path):
    pytest.importorskip(engine, reason=f"{engine} is not installed: {INSTALL[engine]}")
    spec = DesignSpec.from_mapping(
        tiny(
            architectures=["Q-PRR"],
            parameters={"reach": {"low": 0.15, "high": 0.4}, "total_mass": 3.0},
            search={"method": "nsga2", "optimiser": engine, "population": 4, "generations": 2},
            constraints={"arm_mass": {"max": 0.36}},
        )
    )
    run_design(spec, tmp_path / "a.csv", backend="inline", progress=False)
    t = read_results(tmp_path / "a.csv").table
    assert len(t) == 8 and set(t["generation"].tolist()) == {0, 1}
    assert np.all((t["reach"] >= 0.15) & (t["reach"] <= 0.4))
    assert np.array_equal(t["feasible"], (t["arm_mass"] <= 0.36).astype(int))
    lines = (tmp_path / "a.csv").read_text().splitlines(keepends=True)
    (tmp_path / "b.csv").write_text("".join(lines[:6]))  # interrupted in the second generation... then resumed
    (tmp_path / "b.meta.json").write_text((tmp_path / "a.meta.json").read_text())
    again = run_design(spec, tmp_path / "b.csv", backend="inline", progress=False)
    assert (again.skipped, again.executed) == (5, 3)
    same_table(tmp_path / "a.csv", tmp_path / "b.csv")


def test_progress_lines_in_a_log(tmp_path):
    """Not a terminal: plain lines (no carriage return), the last one at 100 %."""
    log = io.StringIO()
    spec = DesignSpec.from_mapping(tiny(architectures=["Q-RR", "Q-RRR"], effort={"samples": 100}))
    with pytest.raises(InputError):  # the output's folder does not exist: refused before any design
        run_design(spec, "/nonexistent/dir/t.csv", backend="inline", stream=log)
    run_design(spec, tmp_path / "t.csv", backend="inline", stream=log)
    text = log.getvalue()
    assert "\r" not in text and "2 designs to evaluate on inline" in text and "design tiny: 2/2 (100%)" in text.splitlines()[-1]


# ------------------------------------------------------------------------------ command line and report
def test_cli_run_report_show(tmp_path, capsys):
    from qprr.cli import main

    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "cli"\narchitectures = ["Q-PRR", "Q-RR", "Q-RRR"]\nobjectives = ["hover_volume", "arm_mass"]\n'
        "[effort]\nsamples = 300\n[closed_loop]\ntop = 1\nduration = 0.5\n"
    )
    assert main(["design", "show", str(spec)]) == 0
    assert "3 designs" in capsys.readouterr().out
    out = tmp_path / "rep"
    assert main(["design", "run", str(spec), "-o", str(tmp_path / "r.csv"), "--backend", "inline", "--report", str(out)]) == 0
    text = capsys.readouterr().out
    assert "closed-loop check" in text and "| 1 | " in text
    assert (out / "pareto.png").read_bytes()[:4] == b"\x89PNG" and (out / "parallel.png").is_file()
    with (out / "closed_loop.csv").open() as fh:
        fl = list(csv.DictReader(fh))
    assert len(fl) == 1 and fl[0]["status"] == "ok"
    assert float(fl[0]["x_cm_max"]) >= 0.0 and 0.0 <= float(fl[0]["saturation"]) <= 1.0
    assert main(["design", "run", str(tmp_path / "missing.toml")]) == 2
