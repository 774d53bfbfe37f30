"""benchmarks/ik_benchmark.py in its quick mode: it runs, every qprr method's success flag agrees with the independent
check (exit code 0) and it prints the ratio to pink for both starts (pink from the `peers` extra)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "ik_benchmark.py"


def test_ik_benchmark_quick(tmp_path, capsys):
    sys.path.insert(0, str(BENCH.parent))
    try:
        spec = importlib.util.spec_from_file_location("ik_benchmark_quick", BENCH)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod  # (its dataclasses look their module up)
        spec.loader.exec_module(mod)
        has_pink = importlib.util.find_spec("pink") is not None
        argv = ["--quick", "--png", str(tmp_path / "ik.png")] + ([] if has_pink else ["--no-peers"])
        assert mod.main(argv) == 0
    finally:
        sys.path.remove(str(BENCH.parent))
        sys.modules.pop("ik_benchmark_quick", None)
    out = capsys.readouterr().out
    assert "disagreements between a qprr method's success flag and the check: 0" in out
    assert (tmp_path / "ik.png").is_file()
    if not has_pink:
        pytest.skip("pink not installed: pip install 'qprr[peers]' to check the ratio lines")
    assert "ratio to pink, qp (IGM start)" in out and "ratio to pink, qp (cold start)" in out
