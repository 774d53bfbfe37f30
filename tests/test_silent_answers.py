"""Issue 34, items 2 and 3: the answers that were silently wrong and are now said (where tests/catalogue.py's cases,
which expect an error or a warning, do not fit: a report's numbers, a terminal's lines)."""

from __future__ import annotations

import pytest

from qprr.campaign.report import report
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
    head = report(cut)[0].splitlines()[0]
    assert "3 of 4 runs" in head and "1 missing" in head, head
    assert "3 completed (75.0 % of 4)" in head and "100.0 %" not in head, head
    assert "4 of 4 runs" in report(four_runs)[0].splitlines()[0]


def test_the_reasons_of_failed_runs_are_on_the_terminal(tmp_path, capsys):
    from qprr.cli import main

    spec = tmp_path / "typo.toml"
    spec.write_text('name = "typo"\nscenario = "hover-reach"\n[options]\nduration = 0.02\nintegrator = "rk5"\n')
    main(["campaign", "run", str(spec), "-o", str(tmp_path / "typo.csv"), "--backend", "inline"])
    out = capsys.readouterr().out
    assert "not completed (1 run(s))" in out and "unknown integrator 'rk5'" in out, out
