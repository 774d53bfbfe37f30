"""qprr.progress: plain rate-limited lines to a non-terminal, a bar to a terminal, nothing when quiet."""

from __future__ import annotations

import io
import re
import sys

import pytest

from qprr.errors import InputError
from qprr.progress import FractionProgress, Progress, is_terminal

LINE = re.compile(r"^work: (\d+)/(\d+) \((\d+)%\), elapsed \d\d:\d\d, ETA (\?|\d\d:\d\d), (\?|[\d.]+)step/s(, .*)?$")


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


class FakeClock:
    """A clock the test advances by hand (tqdm reads ``tqdm.std.time``): the tests depend on no machine's speed."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch):
    import tqdm.std

    fake = FakeClock()
    monkeypatch.setattr(tqdm.std, "time", fake)
    return fake


def test_a_log_gets_whole_lines_without_carriage_returns(clock):
    log = io.StringIO()
    with Progress(50, "work", stream=log, unit="step", interval=0.02) as bar:
        for _ in range(50):
            clock.now += 0.002
            bar.update()
    text = log.getvalue()
    assert "\r" not in text and text.endswith("\n")
    lines = text.splitlines()
    counts = []
    for line in lines:
        m = LINE.match(line)
        assert m, line
        assert m.group(2) == "50" and int(m.group(3)) == 100 * int(m.group(1)) // 50
        counts.append(int(m.group(1)))
    assert counts[0] == 0 and counts[-1] == 50 and counts == sorted(counts)
    assert len(lines) >= 3  # 50 x 2 ms = 0.1 s at one line per 20 ms: lines while it runs, not only at the ends


def test_lines_are_rate_limited():
    log = io.StringIO()
    with Progress(10_000, "work", stream=log, unit="step", interval=60.0) as bar:
        for _ in range(10_000):
            bar.update()
    lines = log.getvalue().splitlines()
    assert [LINE.match(s).group(1) for s in lines] == ["0", "10000"]  # the start and the end, nothing between


def test_a_line_at_least_every_interval_while_it_runs(clock):
    log = io.StringIO()
    interval = 0.05
    stamps, late_without_line = [], []
    with Progress(40, "work", stream=log, unit="step", interval=interval) as bar:
        for k in range(40):
            clock.now += 0.01 if k % 7 else 0.083  # uneven work: some steps longer than the interval
            before = log.getvalue().count("\n")
            bar.update()
            if log.getvalue().count("\n") > before:
                stamps.append(clock.now)
            elif stamps and clock.now - stamps[-1] >= interval:
                late_without_line.append(clock.now - stamps[-1])
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    assert len(stamps) >= 5
    assert min(gaps) >= interval - 1e-9  # never more often than the interval
    # and every update that comes an interval or more after the last line writes one
    assert not late_without_line, late_without_line


def test_quiet_writes_nothing_and_still_counts():
    log = io.StringIO()
    bar = Progress(5, "work", stream=log, quiet=True)
    for _ in range(5):
        bar.update()
    bar.write("a message")
    bar.close()
    assert log.getvalue() == "" and bar.n == 5


def test_update_to_postfix_initial_and_write():
    log = io.StringIO()
    bar = Progress(10, "work", stream=log, unit="step", initial=4, interval=1e-9)
    assert LINE.match(log.getvalue().splitlines()[0]).group(1) == "4"  # a resumed count starts where it was
    bar.set_postfix("1 failed")
    bar.update_to(7)
    bar.write("note")
    bar.close()
    lines = log.getvalue().splitlines()
    assert lines[1].startswith("work: 7/10 (70%)") and lines[1].endswith(", 1 failed")
    assert "note" in lines and lines[-1].startswith("work: 7/10 (70%)")  # closed at 7: the last state shown
    assert bar.n == 7 and bar.total == 10


def test_a_terminal_gets_a_bar_redrawn_in_place():
    tty = FakeTerminal()
    assert is_terminal(tty) and not is_terminal(io.StringIO())
    with Progress(20, "work", stream=tty, interval=1e-9) as bar:
        for _ in range(20):
            bar.update()
    text = tty.getvalue()
    assert text.count("\r") >= 2 and text.count("\n") == 1 and "20/20" in text


def test_fraction_progress_one_display_per_message():
    log = io.StringIO()
    hook = FractionProgress(stream=log, interval=60.0)
    for k in range(11):
        hook(k / 10, "workspace map")
    hook(0.5, "CoG balance")
    hook(1.0, "CoG balance")  # a fraction of 1 closes the bar: close() after it adds nothing
    text = log.getvalue()
    hook.close()
    assert log.getvalue() == text
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert [s.split(":")[0] for s in lines] == ["workspace map"] * 2 + ["CoG balance"] * 2
    # a fraction: the percentage with elapsed time and ETA, no unit counts and no rate
    assert lines[1].startswith("workspace map: 100%, elapsed ") and lines[3].startswith("CoG balance: 100%, elapsed ")
    assert all("/100" not in s and "/s" not in s for s in lines)


@pytest.mark.parametrize("kwargs", [{"total": -1}, {"total": 2.5}, {"total": True}, {"total": 3, "interval": 0.0}])
def test_bad_arguments_are_named(kwargs):
    with pytest.raises(InputError, match="total|interval"):
        Progress(**kwargs, stream=io.StringIO())


@pytest.mark.parametrize("quiet", [False, True])
def test_analyze_shows_progress_in_a_log_by_default_and_quiet_silences_it(quiet, capsys):
    from qprr.cli import main

    assert main(["analyze", "hover", "--samples", "2000", "--payload", "0", *(["--quiet"] if quiet else [])]) == 0
    captured = capsys.readouterr()
    assert "hover map of" in captured.out  # the map ran
    lines = [s for s in captured.err.splitlines() if s.startswith("hover map: ")]
    if quiet:
        assert captured.err == ""
    else:
        assert "\r" not in captured.err  # capsys's stderr is no terminal: plain lines
        # the label carries the map's current stage (e.g. "hover map: collisions: ..."), the count runs to 100 %
        assert lines[0].startswith("hover map: 0%,") and ": 100%, elapsed " in lines[-1]


def test_wheeled_simulate_reports_its_steps_only_when_asked(capsys):
    from qprr.wheeled.robots import Unicycle
    from qprr.wheeled.sim import simulate_wheeled

    res = simulate_wheeled(Unicycle(), [0.0, 0.0, 0.0], [1.0, 0.5], 1.0, 0.01, progress=True)
    err = capsys.readouterr().err
    assert str(res.status.value) == "ok" and "\r" not in err
    assert err.splitlines()[-1].startswith("unicycle: 100/100 (100%)")
    simulate_wheeled(Unicycle(), [0.0, 0.0, 0.0], [1.0, 0.5], 1.0, 0.01)
    assert capsys.readouterr().err == ""


def test_status_progress_counts_failures_and_prints_messages():
    from qprr.progress import StatusProgress

    log = io.StringIO()
    bar = StatusProgress("campaign c", 4, 1, stream=log, unit="run", interval=1e-9)  # one run saved before: resumed
    bar.message("3 runs to do")
    for status in ("ok", "error", "ok"):
        bar.update(status)
    bar.close()
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and "campaign c: 3 runs to do" in lines
    assert lines[0].startswith("campaign c: 1/4 (25%)") and lines[-1].startswith("campaign c: 4/4 (100%)")
    assert lines[-1].endswith(", 1 failed") and (bar.done, bar.total, bar.failed) == (4, 4, 1)
    quiet = io.StringIO()
    StatusProgress("c", 2, quiet=True, stream=quiet).message("nothing")
    assert quiet.getvalue() == ""


class _Stream(io.StringIO):
    def __init__(self, tty: bool) -> None:
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.mark.parametrize("err_tty, out_tty, expected", [(True, False, "out"), (True, True, "err"), (False, False, "err"), (False, True, "err")])
def test_progress_follows_the_output_into_a_log(monkeypatch, err_tty, out_tty, expected):
    """``qprr simulate ... > log`` from a terminal: the lines go to the log with the output; otherwise to stderr."""
    from qprr.progress import Progress, default_stream

    out, err = _Stream(out_tty), _Stream(err_tty)
    monkeypatch.setattr(sys, "stdout", out)
    monkeypatch.setattr(sys, "stderr", err)
    assert default_stream() is (out if expected == "out" else err)
    if expected == "out":  # a log: plain lines, no carriage return
        with Progress(10, "run", unit="tick") as bar:
            bar.update_to(10)
        assert "run: 10/10 (100%)" in out.getvalue() and "\r" not in out.getvalue() and err.getvalue() == ""
