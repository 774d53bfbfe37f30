"""Progress of long runs on a terminal and in a log alike: one small wrapper around tqdm.

:class:`Progress` is the one progress display of qprr (simulations, animations, design maps,
campaigns, the wheeled demos).  Where it goes decides how it looks:

* a terminal (``stream.isatty()``): tqdm's bar, redrawn in place at most every
  :data:`TTY_INTERVAL` seconds;
* anything else (a log file, a pipe, :class:`io.StringIO`): plain lines ending in ``\\n``, never a
  ``\\r``, one at the start, then at most one every ``interval`` seconds (default
  :data:`LOG_INTERVAL`) as the work advances, and one at the end: ``label: 120/300 (40%), 12.0
  elapsed 00:12, ETA 00:18, 10.00it/s``;
* ``quiet=True``: nothing at all (the counts are still kept).

:class:`StatusProgress` counts units that end with a status (campaign runs, design evaluations,
the failed ones shown apart); :class:`FractionProgress` is the ``progress(fraction, message)``
hook of the design maps.

A line is written only when :meth:`Progress.update` (or :meth:`Progress.update_to`) is called:
code that reports every step, or every few percent, gives a line at least every ``interval``
seconds while it runs.

```python
import io
from qprr.progress import Progress

log = io.StringIO()
with Progress(300, "simulate", stream=log, unit="step") as bar:
    for k in range(300):
        bar.update()
print(log.getvalue().splitlines()[-1])   # simulate: 300/300 (100%), ... step/s
```
"""

from __future__ import annotations

import sys
from typing import TextIO

from tqdm import tqdm

from .errors import InputError

TTY_INTERVAL = 0.1
"""Seconds between two redraws of the bar on a terminal."""
LOG_INTERVAL = 2.0
"""Seconds between two progress lines written to a non-terminal (a log file, a pipe)."""
LOG_FORMAT = "{desc}: {n_fmt}/{total_fmt} ({percentage:.0f}%), elapsed {elapsed}, ETA {remaining}, {rate_fmt}{postfix}"
"""One progress line in a log (tqdm's ``bar_format`` fields)."""
PERCENT_LOG_FORMAT = "{desc}: {percentage:.0f}%, elapsed {elapsed}, ETA {remaining}{postfix}"
"""One line in a log of work measured as a fraction (:class:`FractionProgress`): no unit counts, no rate."""
PERCENT_BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| elapsed {elapsed}, ETA {remaining}{postfix}"
"""The bar on a terminal of work measured as a fraction."""


def default_stream() -> TextIO:
    """Where progress goes when no stream is given: standard error, except when only the standard output is
    redirected (``qprr simulate ... > log`` from a terminal): then the log gets the progress lines too, since the
    run's output is being kept there.  A pipe or file on both (CI, ``2>&1``) keeps them on standard error."""
    if is_terminal(sys.stderr) and not is_terminal(sys.stdout):
        return sys.stdout
    return sys.stderr


class _Lines:
    """A text stream seen by tqdm, handing the stream under it whole lines instead of ``\\r`` redraws."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self._last = ""

    def write(self, s: str) -> None:
        for piece in str(s).replace("\n", "\r").split("\r"):
            line = piece.rstrip()
            if line and line != self._last:  # tqdm redraws the last state when it closes
                self.stream.write(line + "\n")
                self._last = line

    def flush(self) -> None:
        self.stream.flush()


def is_terminal(stream) -> bool:
    """Whether the text stream ``stream`` is an interactive terminal."""
    return bool(stream.isatty())


class Progress:
    """Progress of ``total`` units of work, shown on ``stream`` (default: :func:`default_stream` when constructed).

    ``label``: what is shown before the counts.  ``quiet``: show nothing.  ``initial``: units
    already done (a resumed campaign).  ``unit``: the name of a unit in the rate (``step/s``); ``"%"``: the work
    is a fraction (``total`` = 100), shown as a percentage without counts or rate (:data:`PERCENT_LOG_FORMAT`).
    ``interval``: seconds between two lines on a non-terminal (default :data:`LOG_INTERVAL`).
    :meth:`update` adds units, :meth:`update_to` sets the count, :meth:`set_postfix` appends a
    text (``3 failed``), :meth:`write` prints a message without breaking the bar, :meth:`close`
    (or leaving a ``with`` block) ends the display.
    """

    def __init__(
        self,
        total: int,
        label: str = "",
        *,
        quiet: bool = False,
        stream: TextIO | None = None,
        initial: int = 0,
        unit: str = "it",
        interval: float | None = None,
    ) -> None:
        if isinstance(total, bool) or not isinstance(total, int) or total < 0:
            raise InputError(f"total must be an integer >= 0, got {total!r}: the number of units of work")
        if interval is not None and not interval > 0:
            raise InputError(f"interval must be > 0 seconds, got {interval!r}: e.g. interval=2.0")
        self.stream = default_stream() if stream is None else stream
        self.quiet = bool(quiet)
        self.tty = is_terminal(self.stream)
        percent = unit == "%"
        if self.tty:
            options = {"file": self.stream, "mininterval": TTY_INTERVAL if interval is None else interval, "dynamic_ncols": True}
            if percent:
                options["bar_format"] = PERCENT_BAR_FORMAT
        else:
            options = {
                "file": _Lines(self.stream),
                "mininterval": LOG_INTERVAL if interval is None else interval,
                "miniters": 1,
                "ascii": True,
                "bar_format": PERCENT_LOG_FORMAT if percent else LOG_FORMAT,
            }
        self._done, self._total = initial, total  # kept here too: a disabled tqdm does not count
        self._bar = tqdm(total=total, desc=label, initial=initial, unit=unit, disable=self.quiet, leave=True, **options)

    @property
    def n(self) -> int:
        """Units done so far."""
        return self._done

    @property
    def total(self) -> int:
        return self._total

    def update(self, n: int = 1) -> None:
        """``n`` more units done."""
        self._done += n
        self._bar.update(n)

    def update_to(self, done: int) -> None:
        """``done`` units done in all."""
        self.update(done - self._done)

    def set_postfix(self, text: str) -> None:
        """A text after the counts (``3 failed``), shown from the next line on."""
        self._bar.set_postfix_str(text, refresh=False)

    def write(self, message: str) -> None:
        """Print ``message`` on its own line (above the bar on a terminal)."""
        if not self.quiet:
            self._bar.write(message, file=self.stream)

    def close(self) -> None:
        """End the display: the final state is shown once (nothing when quiet)."""
        self._bar.close()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class StatusProgress:
    """Units of work that each end with a status (campaign runs, design evaluations): done / total and failed.

    ``update(status)`` counts one unit; a status other than "ok" counts as failed (shown after the
    counts).  ``message(text)`` prints ``label: text`` on its own line.  The other arguments are
    those of :class:`Progress`.
    """

    def __init__(
        self,
        label: str,
        total: int,
        done: int = 0,
        *,
        quiet: bool = False,
        stream: TextIO | None = None,
        unit: str = "run",
        interval: float | None = None,
    ) -> None:
        self.label, self.failed = label, 0
        self._bar = Progress(total, label, quiet=quiet, stream=stream, initial=done, unit=unit, interval=interval)
        self.stream = self._bar.stream

    @property
    def done(self) -> int:
        return self._bar.n

    @property
    def total(self) -> int:
        return self._bar.total

    def update(self, status: str) -> None:
        if status != "ok":
            self.failed += 1
            self._bar.set_postfix(f"{self.failed} failed")
        self._bar.update()

    def message(self, text: str) -> None:
        self._bar.write(f"{self.label}: {text}")

    def close(self) -> None:
        self._bar.close()


class FractionProgress:
    """A ``progress(fraction, message)`` callable (the design maps' hook) drawing one :class:`Progress` per message.

    The fraction in [0, 1] is shown as a percentage; a fraction of 1 closes the bar, a new message
    closes the previous one and opens the next.  :meth:`close` ends a bar left open.
    """

    def __init__(self, *, quiet: bool = False, stream: TextIO | None = None, interval: float | None = None) -> None:
        self.quiet, self.stream, self.interval = quiet, stream, interval
        self._bar: Progress | None = None
        self._message = None

    def __call__(self, fraction: float, message: str) -> None:
        if message != self._message:
            self.close()
            self._bar = Progress(100, message, quiet=self.quiet, stream=self.stream, unit="%", interval=self.interval)
            self._message = message
        self._bar.update_to(min(100, max(0, int(100 * fraction))))
        if fraction >= 1.0:
            self.close()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        self._bar, self._message = None, None


__all__ = [
    "LOG_FORMAT",
    "LOG_INTERVAL",
    "PERCENT_BAR_FORMAT",
    "PERCENT_LOG_FORMAT",
    "TTY_INTERVAL",
    "FractionProgress",
    "Progress",
    "StatusProgress",
    "is_terminal",
]
