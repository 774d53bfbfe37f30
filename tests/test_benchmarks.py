"""Every script of benchmarks/ runs in its quick mode: exit 0 and at least one ratio line.

Each ``benchmarks/*.py`` (but the helper modules of :data:`HELPERS`) is run as
``python benchmarks/NAME.py --quick`` in a child process, from a temporary folder, with this
checkout first on ``PYTHONPATH``.  It must exit 0 and print a line with the word "ratio" and a
number: the benchmarks report ratios measured side by side in the same run (README, section
Benchmarks).  A benchmark needing an optional package or tool that is absent (peers, crocoddyl,
Dask, valgrind) exits 0 with a message naming its install command; the ratio line is then not
required, the message is.

:data:`NOT_YET_QUICK` lists the benchmarks of other branches that do not accept ``--quick`` yet;
they are skipped, and an entry whose script already accepts ``--quick`` fails: the list is meant to
be emptied as those branches are merged.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
HELPERS = {"machine.py", "placo_worker.py"}
"""Scripts the benchmarks import or run, not benchmarks: the machine report, and the IK benchmark's PlaCo worker (it runs
inside PlaCo's own venv, ``ik_benchmark.py --make-placo-venv``)."""
NOT_YET_QUICK: dict[str, str] = {}
"""Benchmarks skipped until their branch gives them ``--quick``; the lead empties this list after merging."""
RATIO = re.compile(r"\bratios?\b.*\d", re.IGNORECASE)
MISSING = re.compile(r"\bnot installed\b.*\b(pip|apt-get) install \S+")
"""A benchmark's message when an optional package or tool is absent: what is missing and its install command."""
TIMEOUT = 240.0
"""Seconds per benchmark: each takes a few seconds on an idle machine, far longer beside other work."""

SCRIPTS = sorted(p.name for p in BENCH.glob("*.py") if p.name not in HELPERS)


def test_every_benchmark_is_listed():
    assert SCRIPTS, "no benchmark found"
    assert all((BENCH / h).is_file() for h in HELPERS)


@pytest.mark.slow
@pytest.mark.parametrize("name", SCRIPTS)
def test_benchmark_quick_mode_exits_0_and_prints_a_ratio(name, tmp_path):
    source = (BENCH / name).read_text()
    if name in NOT_YET_QUICK:
        assert "--quick" not in source, f"{name} accepts --quick now: remove it from NOT_YET_QUICK"
        pytest.skip(f"{name} has no --quick yet: {NOT_YET_QUICK[name]}")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])), "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, str(BENCH / name), "--quick"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"{name} --quick exited {proc.returncode}:\n{out[-3000:]}"
    assert "\r" not in proc.stdout, f"{name} wrote a carriage return to a pipe"
    ratios = [line for line in out.splitlines() if RATIO.search(line)]
    assert ratios or MISSING.search(out), f"{name} --quick printed no ratio line and no missing-package message:\n{out[-3000:]}"
