"""``qprr analyze``: every map from the command line, on a named platform and a (2.1) design, with its figure."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest

from qprr.analysis.cli import MAPS, resolve_platform
from qprr.cli import main
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
    out = capsys.readouterr().out
    assert "HEX-RRR" in out
    assert "worst configuration" in out and "±" in out and "configurations limited by thrust" in out  # the error bars
    with pytest.raises(UnknownNameError, match="q-prr"):
        resolve_platform("ZZ-TOP")


@pytest.mark.parametrize("what", ["workspace", "hover"])
def test_collision_option(what, capsys):
    """--collision off leaves the collision-free part out, auto (default) and on report it for the Q-PRR (its URDF has
    collision geometry); the numbers over every configuration are the same either way."""
    lines = {}
    for choice in ("off", "auto", "on"):
        assert main(["analyze", what, "--samples", "3000", "-q", "--collision", choice]) == 0
        lines[choice] = capsys.readouterr().out.splitlines()[:-1]  # the last line is the time taken
    assert not any("collision-free" in ln for ln in lines["off"])
    assert lines["auto"] == lines["on"]
    assert any("collision-free" in ln for ln in lines["on"])
    if what == "workspace":
        assert [ln for ln in lines["on"] if "in B" in ln and "collision-free" not in ln][:2] == [ln for ln in lines["off"] if "in B" in ln][:2]


def test_registered_in_the_qprr_command():
    """``python -m qprr analyze`` (the qprr command line) reaches the maps; run in a child process, whose imports
    (qprr.cli also tries the simulator's commands) stay out of this test session."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = subprocess.run(
        [sys.executable, "-m", "qprr", "analyze", "capacity", "--samples", "500"],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": str(root)},
    )
    assert out.returncode == 0, out.stderr
    assert "payload capacity of Q-PRR" in out.stdout


def _thesis_gaps(text: str) -> list[float]:
    import re

    return [float(g) for g in re.findall(r"thesis \(4\.4[678]\), det\(J J\^T\) printed for r0 = \S+ m: max \|printed - model\| (\S+)", text)]


def test_printed_singularity_curves_only_for_the_q_prr(capsys):
    """The thesis's (4.46)-(4.48) lines come from qprr.thesis.maps through the provider hook: on the Q-PRR
    (either layout) within their 4-digit rounding of (4.44); on any other platform no thesis line at all."""
    for argv in (["--samples", "3000"], ["--samples", "3000", "--layout", "x"]):
        assert main(["analyze", "singularity", *argv]) == 0
        gaps = _thesis_gaps(capsys.readouterr().out)
        assert len(gaps) == 3 and max(gaps) < 2e-4, gaps
    for name in ("HEX-RRR", "borinot_flying_arm_2", "QX-PRR"):
        assert main(["analyze", "singularity", "--platform", name, "--samples", "2000"]) == 0
        assert "thesis" not in capsys.readouterr().out


def test_map_reference_hook():
    import qprr
    from qprr.analysis import singularity, workspace
    from qprr.analysis.cli import map_reference
    from qprr.registry import MAP_REFERENCES

    assert list(MAP_REFERENCES) == ["thesis"]  # the thesis plug-in's provider (qprr.thesis.maps), by registration
    qp = qprr.load("q-prr")
    sing = singularity(qp, n_samples=2000)
    ref = map_reference("singularity", qp, sing)
    assert sorted(ref.curves) == ["(4.46) printed, r0 = -0.04", "(4.47) printed, r0 = 0", "(4.48) printed, r0 = 0.04"]
    for x, y in ref.curves.values():  # against theta2, never singular (>= 6.02, Sec. 4.4.3)
        assert x.shape == y.shape and y.min() > 6.0
    assert map_reference("workspace", qp, workspace(qp, n_samples=2000)) is None
    hexa = qprr.build("HEX-RRR")
    assert map_reference("singularity", hexa, singularity(hexa, n_samples=2000)) is None


def test_workspace_figure_draws_only_meaningful_panels():
    """Two regions (the Q-PRR's slider free and locked): 2 x 3 panels; one region (no prismatic joint): 1 x 3;
    every cell of the grid holds a panel with data (no blank slot)."""
    import qprr
    from qprr.analysis import plots, workspace

    for platform, grid in ((qprr.load("q-prr"), (2, 3)), (qprr.build("HEX-RRR"), (1, 3))):
        fig = plots.workspace_figure(workspace(platform, n_samples=3000))
        assert {ax.get_subplotspec().get_geometry()[:2] for ax in fig.axes} == {grid}
        assert len(fig.axes) == grid[0] * grid[1]
        for ax in fig.axes:
            assert ax.has_data(), (platform.name, ax.get_title())
