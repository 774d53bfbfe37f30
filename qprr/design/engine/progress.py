"""A progress line for design studies: rewritten in place on a terminal, plain lines otherwise."""

from __future__ import annotations

import sys
import time


class Progress:
    """``design NAME: done/total designs, failed, designs/s, ETA`` on ``stream`` (default stderr).

    On a terminal the line is rewritten in place; otherwise (a log file, a pipe) a line is printed
    every 10 % of the designs or every 30 s, whichever comes first.
    """

    def __init__(self, name: str, total: int, done: int = 0, enabled: bool = True, stream=None) -> None:
        self.name, self.total, self.start, self.done, self.failed = name, total, done, done, 0
        self.enabled = enabled
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(self.stream.isatty())  # every io stream has isatty (a StringIO: False)
        self.t0 = self._last = time.perf_counter()
        self._last_frac = done / total if total else 1.0

    def line(self) -> str:
        el = time.perf_counter() - self.t0
        rate = (self.done - self.start) / el if el > 0 else 0.0
        eta = f"{(self.total - self.done) / rate:.0f} s" if rate > 0 else "--"
        return (f"design {self.name}: {self.done}/{self.total} designs, {self.failed} failed, {rate:.2f} designs/s, "
                f"elapsed {el:.0f} s, ETA {eta}")

    def message(self, text: str) -> None:
        if self.enabled:
            if self.tty:
                self.stream.write("\r\033[K")
            self.stream.write(f"design {self.name}: {text}\n")
            self.stream.flush()

    def update(self, status: str) -> None:
        self.done += 1
        self.failed += status != "ok"
        if not self.enabled:
            return
        now = time.perf_counter()
        if self.tty:
            self.stream.write("\r" + self.line() + "\033[K")
            self.stream.flush()
        elif self.done == self.total or now - self._last > 30.0 or self.done / self.total - self._last_frac >= 0.1:
            self.stream.write(self.line() + "\n")
            self.stream.flush()
            self._last, self._last_frac = now, self.done / self.total

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()
