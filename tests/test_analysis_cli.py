"""``qprr analyze``: every map from the command line, on a named platform and a (2.1) design, with its figure."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest

from qprr.analysis.cli import MAPS, main, resolve_platform
from qprr.errors import UnknownNameError


@pytest.mark.parametrize("what", MAPS)
def test_every_map_runs_and_saves_its_figure(what, tmp_path, capsys):
    out = tmp_path / f"{what}.png"
    assert main(["analyze", what, "--samples", "3000", "--plot", str(out)]) == 0
    assert out.stat().st_size > 10_000
    text = capsys.readouterr().out
    assert "Q-PRR" in text and f"saved {out}" in text


def test_fully_actuated_hover_also_draws_its_wrench_set(tmp_path, capsys):
    out = tmp_path / "hover.png"
    assert main(["analyze", "hover", "--platform", "hextilt_flying_arm_5", "--samples", "2000", "--plot", str(out)]) == 0
    assert (tmp_path / "hover-wrench-set.png").stat().st_size > 10_000
    assert "rank 6" in capsys.readouterr().out


def test_designations_and_unknown_names(capsys):
    assert main(["analyze", "capacity", "--platform", "HEX-RRR", "--samples", "2000"]) == 0
    assert "HEX-RRR" in capsys.readouterr().out
    with pytest.raises(UnknownNameError, match="q-prr"):
        resolve_platform("ZZ-TOP")


def test_registered_in_the_qprr_command():
    """``python -m qprr analyze`` (the qprr command line) reaches the maps; run in a child process, whose imports
    (qprr.cli also tries the simulator's commands) stay out of this test session."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-m", "qprr", "analyze", "capacity", "--samples", "500"], cwd=root, capture_output=True,
                         text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(root)})
    assert out.returncode == 0, out.stderr
    assert "payload capacity of Q-PRR" in out.stdout
