"""A run as a long table other tools read: one row per (time, series, value, unit), as CSV or Parquet.

``.npz`` (:meth:`qprr.sim.result.SimResult.save`) keeps everything for qprr; the long format is what a spreadsheet,
pandas, R or Julia take without qprr: every logged array of :class:`~qprr.sim.result.SimResult` becomes series named
``<array>.<column>`` (``xi.x``, ``xi_d.theta2``, ``u.phi``, ``f.2``, ``arm_effort.r0``, ``x_cm.y``; rotors numbered from 1
in the platform's order), each with its SI unit, plus the run's extra time series (``series.<name>``, unit as logged:
empty when the run did not say).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib.util import find_spec
from pathlib import Path

import numpy as np

from ..errors import InputError, MissingDependencyError
from .result import SimResult

FORMATS = (".csv", ".parquet")
PARQUET_INSTALL = 'pip install "qprr[parquet]"'


@dataclass(frozen=True)
class LongTable:
    """Columns of equal length: ``time`` [s], ``series`` (names), ``value``, ``unit``."""

    time: np.ndarray
    series: np.ndarray
    value: np.ndarray
    unit: np.ndarray


def _coordinate_units(result: SimResult) -> tuple[list[str], list[str], list[str]]:
    """(position, rate, force) units of the thesis coordinates: base position, ZYX angles, then each arm joint."""
    prismatic = [kind == "prismatic" for kind in (result.arm_kinds or ("revolute",) * result.n_arm)]
    position = ["m"] * 3 + ["rad"] * 3 + ["m" if p else "rad" for p in prismatic]
    rate = ["m/s"] * 3 + ["rad/s"] * 3 + ["m/s" if p else "rad/s" for p in prismatic]
    force = ["N"] * 3 + ["N m"] * 3 + ["N" if p else "N m" for p in prismatic]
    return position, rate, force


def _blocks(result: SimResult) -> list[tuple[str, np.ndarray, list[str], list[str]]]:
    """(array name, (m, k) values, k column names, k units) of every logged array."""
    names = list(result.names)
    position, rate, force = _coordinate_units(result)
    arm = names[6:]
    blocks = [
        ("xi", result.xi, names, position),
        ("xi_dot", result.xi_dot, names, rate),
        ("xi_d", result.xi_d, names, position),
        ("xi_dot_d", result.xi_dot_d, names, rate),
        ("u", result.u, names, force),
        ("u_ext", result.u_ext, names, force),
        ("f", result.f, [str(i + 1) for i in range(result.f.shape[1])], ["N"] * result.f.shape[1]),
        ("arm_effort", result.arm_effort, arm, force[6:]),
        ("x_cm", result.x_cm, ["x", "y", "z"], ["m"] * 3),
    ]
    for key, values in sorted(result.series.items()):
        values = np.asarray(values, dtype=float)
        if values.ndim in (1, 2) and values.shape[0] == result.n:
            columns = values.reshape(result.n, -1)
            labels = [""] if columns.shape[1] == 1 else [str(i) for i in range(columns.shape[1])]
            blocks.append(("series." + key, columns, labels, [""] * columns.shape[1]))
    return blocks


def long_table(result: SimResult) -> LongTable:
    """The run as a :class:`LongTable`, series after series (each over every tick)."""
    if not isinstance(result, SimResult):
        raise InputError(f"result must be a qprr.sim.SimResult, got {type(result).__name__}")
    times, series, values, units = [], [], [], []
    for array, block, labels, block_units in _blocks(result):
        for j, (label, unit) in enumerate(zip(labels, block_units)):
            times.append(result.t)
            values.append(np.asarray(block[:, j], dtype=float))
            name = f"{array}.{label}" if label else array
            series.append(np.full(result.n, name, dtype=object))
            units.append(np.full(result.n, unit, dtype=object))
    return LongTable(np.concatenate(times), np.concatenate(series), np.concatenate(values), np.concatenate(units))


def save_table(result: SimResult, path: str | Path) -> Path:
    """Write :func:`long_table` to ``path`` (``.csv``, or ``.parquet`` with the ``parquet`` extra); returns the path.

    The parent folder must exist, as for :meth:`~qprr.sim.result.SimResult.save`."""
    path = Path(path)
    if path.suffix not in FORMATS:
        raise InputError(f"table files end in {' or '.join(FORMATS)}, got {str(path)!r} (.npz: SimResult.save)")
    if not path.parent.is_dir():
        raise InputError(f"cannot save {str(path)!r}: folder {str(path.parent)!r} does not exist")
    table = long_table(result)
    if path.suffix == ".csv":
        with path.open("w", newline="", encoding="utf-8") as f:
            writer = csv.writer(f)
            writer.writerow(("time", "series", "value", "unit"))
            writer.writerows(zip(table.time.tolist(), table.series.tolist(), table.value.tolist(), table.unit.tolist()))
        return path
    if find_spec("pyarrow") is None:
        raise MissingDependencyError("pyarrow", f"writing {str(path)!r} (Parquet)", PARQUET_INSTALL)
    import pyarrow as pa
    import pyarrow.parquet as pq

    columns = {"time": table.time, "series": table.series.astype(str), "value": table.value, "unit": table.unit.astype(str)}
    pq.write_table(pa.table(columns), path)
    return path
