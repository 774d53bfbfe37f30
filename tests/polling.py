"""Waiting for another process or thread without reading a clock (tests measure no time: benchmarks/ do).

:func:`poll` checks a condition up to ``tries`` times with a pause between checks: the bound is a number of checks,
so a loaded machine makes a wait longer, never a verdict different.
"""

from __future__ import annotations

import time
from collections.abc import Callable


def poll(condition: Callable[[], bool], tries: int, pause: float = 0.05) -> bool:
    """True as soon as ``condition()`` holds (checked up to ``tries`` times, ``pause`` [s] apart), else False."""
    for _ in range(tries):
        if condition():
            return True
        time.sleep(pause)
    return condition()
