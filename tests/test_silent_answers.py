"""Issue 34, items 2 and 3: the answers that were silently wrong and are now said (where tests/catalogue.py's cases,
which expect an error or a warning, do not fit: a report's numbers, a terminal's lines)."""

from __future__ import annotations

import pytest

from qprr.campaign.report import campaign_report
from qprr.campaign.runner import run_campaign
from qprr.campaign.spec import CampaignSpec


@pytest.fixture(scope="module")
def four_runs(tmp_path_factory):
    spec = CampaignSpec(name="four", scenario="hover-reach", samples=4, options={"duration": 0.02})
    return run_campaign(spec, tmp_path_factory.mktemp("c") / "four.csv", backend="inline", progress=False).path


def test_a_campaign_whose_last_record_is_cut_reports_the_run_missing(four_runs, tmp_path):
    cut = tmp_path / "cut.csv"
    cut.write_bytes(four_runs.read_bytes()[:-20])  # the last record cut mid-line
    (tmp_path / "cut.meta.json").write_bytes(four_runs.with_name("four.meta.json").read_bytes())
    head = campaign_report(cut)[0].splitlines()[0]
    assert "3 of 4 runs" in head and "1 missing" in head, head
    assert "3 completed (75.0 % of 4)" in head and "100.0 %" not in head, head
    assert "4 of 4 runs" in campaign_report(four_runs)[0].splitlines()[0]


def test_the_reasons_of_failed_runs_are_on_the_terminal(tmp_path, capsys):
    from qprr.cli import main

    spec = tmp_path / "typo.toml"
    spec.write_text('name = "typo"\nscenario = "hover-reach"\n[options]\nduration = 0.02\nintegrator = "rk5"\n')
    main(["campaign", "run", str(spec), "-o", str(tmp_path / "typo.csv"), "--backend", "inline"])
    out = capsys.readouterr().out
    assert "not completed (1 run(s))" in out and "unknown integrator 'rk5'" in out, out


def test_the_actuation_summary_never_prints_a_thrust_outside_the_bounds_beside_a_positive_margin():
    """A coaxial set with the last rotor's axis down: the least-norm hover needs -1.84 N there (refused at load); the
    summary of the set reports thrusts inside the bounds with its positive margin."""
    from qprr.rotors import Rotor, actuation_summary, ring

    low = ring(4, 0.2, kappa=0.016, f_max=8.0, start_angle=0.785)
    high = tuple(
        Rotor((r.position_body[0], r.position_body[1], 0.08), (0.0, 0.0, -1.0 if k == 3 else 1.0), -r.spin, 0.016, 0.0, 8.0, f"up_{k + 1}")
        for k, r in enumerate(low)
    )
    s = actuation_summary(low + high, 14.715)
    assert s.hover_margin > 0.0
    assert s.hover_thrusts.min() >= -1e-9 and s.hover_thrusts.max() <= 8.0 + 1e-9, str(s)
    assert "-" not in str(s).split("hover thrusts")[1].split("]")[0], str(s)


def test_motor_lag_flies_the_rotor_file_s_motor_table():
    """borinot's rotor file gives b = 4.511e-6 N s^2, T = 5 ms, w_max = 2236 rad/s: motor-lag's stage is that one (it
    flew b = 1e-5 and w_max from the thrust bounds); a tau given replaces the table's time constant only."""
    import qprr
    from qprr.scenarios.missions import motor_stage

    borinot = qprr.load("borinot_flying_arm_2")
    assert borinot.motor["thrust_factor"] == 4.511e-6
    stage = motor_stage(borinot)
    assert set(stage.thrust_factor) == {4.511e-6} and set(stage.time_constant) == {0.005} and set(stage.w_max) == {2236.0}
    slower = motor_stage(borinot, tau=0.02)
    assert set(slower.time_constant) == {0.02} and set(slower.thrust_factor) == {4.511e-6}
    assert set(motor_stage(qprr.load()).time_constant) == {0.005}  # no table: motor-lag's defaults


def test_a_study_with_no_feasible_design_says_which_constraint_excluded_how_many(tmp_path, capsys):
    from qprr.cli import main
    from qprr.design.report import design_report

    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "none"\narchitectures = ["Q-RR", "Q-RRR"]\nobjectives = ["hover_volume", "arm_mass"]\n'
        "[constraints]\narm_mass = { max = 1e-6 }\n[effort]\nsamples = 300\n"
    )
    assert main(["design", "run", str(spec), "-o", str(tmp_path / "r.csv"), "--backend", "inline"]) == 3  # nothing feasible
    out = capsys.readouterr().out
    assert "design 0 Q-RR: infeasible: arm_mass = 0.192 kg, above its max 1e-06" in out, out
    assert "not feasible: 2 of 2 design(s)" in out and "constraint arm_mass <= 1e-06 excludes 2 of the 2 evaluated design(s)" in out, out
    text, _ = design_report(tmp_path / "r.csv", fly=False)
    assert "0 feasible" in text and "arm_mass <= 1e-06 excludes 2" in text, text
