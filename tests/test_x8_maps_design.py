"""Issue 35's "Done when" on the X8 test robot (tests/robots/x8_arm4: 8 rotors, a 4-joint arm with a telescope), from
the command line: the design maps chosen by their time budget with no empty panel, and a design study over two of its
URDF's parameters."""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

import matplotlib.image as mpimg
import pytest
from matplotlib.figure import Figure

from qprr.campaign import read_results
from qprr.cli import main
from qprr.design.report import rows_of
from tests import x8_robot


@pytest.mark.parametrize("map_name", ["workspace", "hover", "capacity", "cog"])
def test_each_map_fits_a_budget_and_draws_no_empty_panel(map_name, tmp_path, capsys, monkeypatch):
    """``--budget 2``: the command times pilot batches and picks the sample count for the rest of the budget (the
    summary says how many and why; no clock is read here); every panel of the figure it saves holds data."""
    saved = []
    savefig = Figure.savefig

    def keep(fig, *args, **kwargs):
        saved.append(fig)
        return savefig(fig, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep)
    figure = tmp_path / f"{map_name}.png"
    assert main(["analyze", map_name, *x8_robot.CLI, "--budget", "2", "--plot", str(figure), "-q"]) == 0
    text = capsys.readouterr().out
    assert f"{map_name} map of x8_arm4: " in text and "(budget 2 s: pilots and map" in text, text
    assert "requested" in text and "for a budget of " in text, text  # the sampling line(s): cog splits its budget in two
    assert len(saved) == 1 and mpimg.imread(figure).shape[2] in (3, 4)
    axes = [a for a in saved[0].axes if a.get_label() != "<colorbar>"]
    assert axes and all(a.has_data() for a in axes), [a.get_title() for a in axes if not a.has_data()]


def _templates(tmp_path: Path) -> None:
    """The X8's URDF with the telescope's stroke and the tool length (wrist to gripper) as ``${stroke}`` and ``${tool}``;
    its rotor file as it is."""
    urdf = x8_robot.URDF.read_text()
    stroke = '<limit lower="0.0" upper="0.25" effort="20.0" velocity="0.5"/>'
    tool = '<origin xyz="0 0 -0.08"/>'
    assert urdf.count(stroke) == 1 and urdf.count(tool) == 1
    urdf = urdf.replace(stroke, '<limit lower="0.0" upper="${stroke}" effort="20.0" velocity="0.5"/>')
    (tmp_path / "x8.urdf.template").write_text(urdf.replace(tool, '<origin xyz="0 0 -${tool}"/>'))
    (tmp_path / "x8.rotors.toml").write_text(x8_robot.ROTORS.read_text())


STUDY = """
name = "x8-reach"
seed = 35
objectives = ["hover_volume", "thrust_margin"]

[robot]
urdf = "x8.urdf.template"
rotors = "x8.rotors.toml"
name = "x8_arm4"
ee_frame = "gripper"

[parameters]
stroke = [0.10, 0.25]       # the telescope's travel [m]
tool = [0.04, 0.12]         # wrist joint to gripper [m]

[effort]
samples = 1500
"""


def test_a_design_study_over_two_urdf_parameters(tmp_path, capsys):
    """Four X8 candidates (stroke x tool length) built from the templates and measured: a longer stroke or a longer
    tool reaches a larger hover workspace; a longer tool carries the 0.05 kg gripper further from the thrust axis at
    the arm's worst pose, so the rotors keep less thrust margin."""
    _templates(tmp_path)
    (tmp_path / "x8.toml").write_text(STUDY)
    out = tmp_path / "x8.csv"
    assert main(["design", "run", str(tmp_path / "x8.toml"), "-o", str(out), "--backend", "inline"]) == 0
    text = capsys.readouterr().out
    rows = rows_of(read_results(out).table)
    assert len(rows) == 4 and all(r["status"] == "ok" for r in rows), rows
    by = {(r["stroke"], r["tool"]): r for r in rows}
    for tool in (0.04, 0.12):
        assert by[(0.10, tool)]["hover_volume"] < by[(0.25, tool)]["hover_volume"]
    for stroke in (0.10, 0.25):
        assert by[(stroke, 0.04)]["hover_volume"] < by[(stroke, 0.12)]["hover_volume"]
        assert by[(stroke, 0.04)]["thrust_margin"] > by[(stroke, 0.12)]["thrust_margin"]
    assert "x8-reach" in text and "4 designs evaluated" in text, text
