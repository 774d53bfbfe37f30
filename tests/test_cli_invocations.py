"""Issue 16 item 5: every bad command line ends in one line on stderr and exit code 2, never a traceback, and the
output targets (--save, --plot, --animate, -o) are checked before any run starts."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import qprr
from qprr import cli
from qprr.scenarios import Scenario

ROOT = Path(qprr.__file__).resolve().parent.parent


def _bad(tmp: Path) -> list[list[str]]:
    blocker = tmp / "a-file"
    blocker.write_text("")
    garbage = tmp / "garbage.npz"
    garbage.write_bytes(b"\x00not a result")
    return [
        [],
        ["fly"],
        ["simulate"],
        ["simulate", "no-such-scenario"],
        ["simulate", "hover-reach", "--controller", "pid"],
        ["simulate", "hover-reach", "--duration", "-1"],
        ["simulate", "hover-reach", "--duration", "nan"],
        ["simulate", "hover-reach", "--duration", "fast"],
        ["simulate", "hover-reach", "--dt", "0"],
        ["simulate", "hover-reach", "--dt", "inf", "--duration", "0.01"],
        ["simulate", "hover-reach", "--integrator", "rk5"],
        ["simulate", "hover-reach", "--seed", "1.5"],
        ["simulate", "hover-reach", "--set", "z"],
        ["simulate", "hover-reach", "--set", "nope=1"],
        ["simulate", "hover-reach", "--set", "z=high"],
        ["simulate", "hover-reach", "--set", "z=nan", "--duration", "0.01"],
        ["simulate", "hover-reach", "--platform", "crazyflie"],
        ["simulate", "static-idc", "--platform", "borinot_flying_arm_2"],
        ["simulate", "hover-reach", "--save", str(tmp / "missing" / "run.npz")],
        ["simulate", "hover-reach", "--save", str(tmp / "run.txt")],
        ["simulate", "hover-reach", "--plot", str(blocker / "fig.png")],
        ["simulate", "hover-reach", "--plot", str(tmp / "fig.jpg")],
        ["simulate", "hover-reach", "--animate", str(tmp / "anim.avi")],
        ["compare", "--duration", "0"],
        ["urdf", "-o", str(tmp / "robot.xml")],
        ["analyze", "warp"],
        ["analyze", "workspace", "--platform", "crazyflie"],
        ["animate", str(garbage), "-o", str(tmp / "a.gif")],
        ["wheeled", "no-such-robot"],
    ]


def test_bad_invocations_end_in_one_line_and_exit_code_2(tmp_path, capsys, monkeypatch):
    """In-process: any exception escaping ``main`` would be a traceback for the user.  No scenario may start (the
    output targets and the options are checked first): Scenario.run is replaced by a tripwire where a run would be wasted."""
    started = []
    real_run = Scenario.run

    def tripwire(self, *args, **kwargs):
        started.append(self.name)
        return real_run(self, *args, **kwargs)

    monkeypatch.setattr(Scenario, "run", tripwire)
    cases = _bad(tmp_path)
    assert len(cases) >= 20
    for argv in cases:
        try:
            code = cli.main(argv)
        except SystemExit as exc:  # argparse
            code = exc.code
        out = capsys.readouterr()
        lines = [ln for ln in out.err.splitlines() if ln.strip()]
        assert code == 2, (argv, code, out.err)
        assert len(lines) == 1 and "error" in lines[0] and "Traceback" not in out.err, (argv, out.err)
    # only the cases whose bad value lives in a scenario option reach Scenario.run (and fail at its start)
    assert set(started) <= {"hover-reach"} and len(started) <= 2, started


@pytest.mark.parametrize("argv", [["simulate", "hover-reach", "--dt", "-1"], ["simulate", "nope"], ["analyze", "workspace", "--samples", "x"]])
def test_no_traceback_from_the_console(argv):
    proc = subprocess.run([sys.executable, "-m", "qprr", *argv], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
