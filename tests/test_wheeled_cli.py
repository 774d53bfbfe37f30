"""``qprr wheeled``: the catalogue in --help, one-line errors with exit code 2, a figure written."""

from __future__ import annotations

import pytest

from qprr.cli import build_parser, main
from qprr.wheeled.demos import EXERCISES, catalogue, run_demo
from qprr.wheeled.robots import ROBOTS


def test_help_lists_every_robot_and_exercise(capsys):
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["wheeled", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for name in list(ROBOTS) + list(EXERCISES):
        assert f"  {name} " in out
    assert set(catalogue()) == set(ROBOTS) | set(EXERCISES)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["wheeled", "hovercraft"], "unknown robot or exercise 'hovercraft'; valid: fixed-wheel"),
        (["wheeled", "types", "--plot", "out.jpg"], "--plot 'out.jpg': the file must end in .png or .pdf or .svg"),
        (["wheeled", "types", "--plot", "no-such-folder/t.png"], "folder 'no-such-folder' does not exist"),
    ],
)
def test_bad_arguments_give_one_line_and_exit_code_2(capsys, argv, message):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert message in err and err.count("\n") == 1
    assert out == ""  # refused before the run


def test_a_directory_as_plot_path_is_refused(capsys, tmp_path):
    d = tmp_path / "fig.png"
    d.mkdir()
    assert main(["wheeled", "types", "--plot", str(d)]) == 2
    assert "is a folder, not a file" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["types", "ackermann", "bicycle-exercise"])
def test_runs_print_checks_and_save_a_png(capsys, tmp_path, name):
    path = tmp_path / f"{name}.png"
    assert main(["wheeled", name, "--plot", str(path)]) == 0
    out = capsys.readouterr().out
    assert f"figure {path}" in out
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_types_output_is_computed():
    lines = run_demo("types").lines
    assert "[(3, 0), (2, 0), (2, 1), (1, 1), (1, 2)]" in lines[0]
    assert all("computed type (" in ln for ln in lines[1:])
    for ln in lines[1:]:
        computed, lecture = ln.split("computed type ")[1].split(" (lecture: ")
        assert computed == lecture.split(")")[0] + ")"
