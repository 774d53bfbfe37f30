"""Shared by the flight-log tests: the shared logs' folder and a copy of a log with changes, written by pyulog."""

from __future__ import annotations

from pathlib import Path

import pytest

LOGS = Path(__file__).resolve().parents[2] / "shared/data/flightlogs"
EVENTS = LOGS / "sample_px4_events.ulg"
TAGGED = LOGS / "sample_logging_tagged_and_default_params.ulg"


def shared_log(path: Path) -> Path:
    if not path.is_file():
        pytest.skip(f"the shared flight log {path} is absent (the project's ../shared/data/flightlogs folder)")
    return path


def rewritten(src: Path, dst: Path, *, drop=(), until_s: float | None = None) -> Path:
    """A copy of ``src`` without the topics ``drop`` and, with ``until_s``, without any sample after that time."""
    from pyulog import ULog

    ulog = ULog(str(src))
    data = ulog.data_list
    data[:] = [d for d in data if d.name not in drop]
    if until_s is not None:
        cut = ulog.start_timestamp + int(until_s * 1e6)
        for d in data:
            keep = d.data["timestamp"] < cut
            d.data = {k: v[keep] for k, v in d.data.items()}
    ulog.write_ulog(str(dst))
    return dst
