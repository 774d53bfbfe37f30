"""Validation helpers of design specifications: every error names the key, the value and the fix."""

from __future__ import annotations

import math
from collections.abc import Mapping

from ...errors import InputError


def spec_error(key: str, value, fix: str):
    """Raise an :class:`InputError` ``key = value: fix``."""
    raise InputError(f"design specification: {key} = {value!r} is not valid; fix: {fix}")


def number(x, key: str, *, lo: float | None = None, hi: float | None = None, positive: bool = False) -> float:
    """``x`` as a finite float in [lo, hi] (> 0 if ``positive``), else :func:`spec_error`."""
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        spec_error(key, x, "a finite number")
    v = float(x)
    if positive and not v > 0.0:
        spec_error(key, x, "a number > 0")
    if lo is not None and v < lo:
        spec_error(key, x, f"a number >= {lo!r}")
    if hi is not None and v > hi:
        spec_error(key, x, f"a number <= {hi!r}")
    return v


def spec_integer(x, key: str, lo: int = 1) -> int:
    if isinstance(x, bool) or not isinstance(x, int) or x < lo:
        spec_error(key, x, f"an spec_integer >= {lo}")
    return int(x)


def table_keys(d, name: str, allowed) -> dict:
    """``d`` as a dict whose keys are all in ``allowed`` (an unknown one fails with the list)."""
    if not isinstance(d, Mapping):
        spec_error(name, d, f"a table with keys among {', '.join(allowed)}")
    for k in d:
        if k not in allowed:
            spec_error(f"{name}.{k}" if name else k, d[k], f"remove it or use one of {', '.join(allowed)}")
    return dict(d)
