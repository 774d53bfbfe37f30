"""Results on disk, appended as runs finish, keyed by run index; read back as a tidy table.

* ``RESULTS.csv``: one header line, then one line per finished run, flushed at once (an
  interrupted campaign loses nothing it was told).  Floats are written with ``repr`` (exact
  round trip), so two runs of one specification give byte-comparable values.
* ``RESULTS.parquet`` (needs pyarrow, extra ``qprr[parquet]``): a folder of part files, one per
  batch of rows (every 50 rows or 10 s, and at the end); each part is a complete Parquet file,
  so a crash loses at most the rows of the batch in progress.  ``pyarrow.parquet.read_table``
  and pandas read the folder as one table.
* ``RESULTS.meta.json`` beside it: the specification, its fingerprint, the parameter and metric
  columns.  Resuming checks the fingerprint: results of another specification are never mixed.
  ``RESULTS.lock``: a second campaign writing to the same file is refused while the first runs.

Rows are keyed by ``run``: when a run appears twice (a row of status ``error`` - a worker that
died - is re-run on resume), the last row wins.  :func:`read_results` returns a
:class:`Results` (a numpy structured array sorted by run, and the metadata).
"""

from __future__ import annotations

import csv
import json
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..charts import as_file, as_output_path
from ..errors import InputError, MissingDependencyError

FORMATS = (".csv", ".parquet")
META_VERSION = 1


def _meta_path(path: str | Path) -> Path:
    p = Path(path)
    return p.with_name(p.stem + ".meta.json")


def _require_pyarrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError as exc:
        raise MissingDependencyError("pyarrow", "Parquet campaign results", "pip install 'qprr[parquet]' (or pip install pyarrow)") from exc
    return pa, pq


def check_output(path: str | Path, name: str = "path") -> Path:
    """``path`` as the results file to write (``name`` in the errors): .csv or .parquet, in an existing folder."""
    if isinstance(path, (str, os.PathLike)) and Path(path).suffix == ".parquet" and Path(path).is_dir():
        p = Path(path)  # the folder of a Parquet table being resumed
    else:
        p = as_output_path(path, name, suffixes=FORMATS)
    if p.suffix not in FORMATS:
        raise InputError(f"{name}: campaign results end in .csv or .parquet, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"cannot write {str(p)!r}: folder {str(p.parent)!r} does not exist")
    if p.suffix == ".parquet":
        _require_pyarrow()
    return p


def _fmt(v) -> str:
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (np.floating,)):
        return repr(float(v))
    return str(v)


class ResultStore:
    """Append-only results file of one campaign (see the module docstring).

    ``columns``: every column in order; ``meta``: what goes to the ``.meta.json`` file
    (``fingerprint`` is checked on resume).  :attr:`done` holds the run indices already saved
    with a status other than ``error``.
    """

    def __init__(self, path: str | Path, columns: tuple[str, ...], meta: dict, *, fresh: bool = False) -> None:
        if isinstance(columns, str) or not isinstance(columns, (list, tuple)) or not columns or \
                not all(isinstance(c, str) and c for c in columns):
            raise InputError(f"columns must be a non-empty sequence of column names, got {columns!r}")
        if not isinstance(meta, Mapping):
            raise InputError(f"meta must be a mapping (the .meta.json content), got {type(meta).__name__}")
        self.path = check_output(path)
        self._lock = _lock(self.path)  # one writer per results file (released when this process ends, even by a crash)
        try:
            self._open(columns, meta, fresh)
        except BaseException:
            if self._lock is not None:
                self._lock.close()
            raise

    def _open(self, columns, meta: dict, fresh: bool) -> None:
        self.columns = tuple(columns)
        self.meta = dict(meta, columns=list(columns), format_version=META_VERSION)
        self.parquet = self.path.suffix == ".parquet"
        self.done: set[int] = set()
        self.rows_before = 0
        mp = _meta_path(self.path)
        exists = self.path.exists()
        if exists and not fresh:
            old = _read_meta(self.path)
            if old.get("fingerprint") != meta.get("fingerprint"):
                raise InputError(f"{str(self.path)!r} holds results of another specification (fingerprint {old.get('fingerprint')!r}, "
                                 f"this one {meta.get('fingerprint')!r}): choose another output or start afresh (--fresh)")
            if list(old.get("columns", [])) != list(columns):
                raise InputError(f"{str(self.path)!r} has other columns than this campaign's: choose another output or --fresh")
            if not self.parquet:
                _drop_cut_line(self.path)
            table = read_results(self.path).table
            self.rows_before = len(table)
            self.done = {int(r) for r, s in zip(table["run"], table["status"]) if s != "error"}
        elif exists:
            _remove(self.path)
        mp.write_text(json.dumps(self.meta, indent=1, default=str))
        self._buffer: list[dict] = []
        self._last_flush = time.monotonic()
        self._part = 0
        if self.parquet:
            self.path.mkdir(exist_ok=True)
            self._part = len(list(self.path.glob("part-*.parquet")))
            self._file = None
        else:
            new = not self.path.exists()
            self._file = self.path.open("a", newline="")
            self._writer = csv.writer(self._file)
            if new:
                self._writer.writerow(self.columns)
                self._file.flush()

    def append(self, row: dict) -> None:
        """Save one finished run (CSV: written and flushed now; Parquet: with its batch)."""
        if not isinstance(row, Mapping):
            raise InputError(f"row must be a mapping column -> value, got {type(row).__name__}")
        missing = [c for c in self.columns if c not in row]
        if missing:
            raise InputError(f"result row lacks the columns {missing}")
        if self.parquet:
            self._buffer.append(row)
            if len(self._buffer) >= 50 or time.monotonic() - self._last_flush > 10.0:
                self.flush()
        else:
            self._writer.writerow([_fmt(row[c]) for c in self.columns])
            self._file.flush()

    def flush(self) -> None:
        if self.parquet and self._buffer:
            pa, pq = _require_pyarrow()
            cols = {c: [r[c] for r in self._buffer] for c in self.columns}
            table = pa.table({c: pa.array([_plain(v) for v in vals]) for c, vals in cols.items()})
            tmp = self.path / f".part-{self._part:05d}.tmp"
            pq.write_table(table, tmp)
            tmp.rename(self.path / f"part-{self._part:05d}.parquet")  # a part appears complete or not at all
            self._part += 1
            self._buffer.clear()
        self._last_flush = time.monotonic()

    def close(self) -> None:
        self.flush()
        if self._file is not None:
            self._file.close()
            self._file = None
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _lock(path: Path):
    """An exclusive advisory lock on ``<stem>.lock`` beside the results (POSIX; elsewhere no lock)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return None
    fh = path.with_name(path.stem + ".lock").open("a")
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        fh.close()
        raise InputError(f"another campaign is writing to {str(path)!r} (lock {fh.name!r}): wait for it or choose another output") from exc
    return fh


def _plain(v):
    return v.item() if isinstance(v, np.generic) else v


def _drop_cut_line(path: Path) -> None:
    """Remove a last line cut short by a crash (no final newline): its run is done again."""
    with path.open("rb+") as fh:
        data = fh.read()
        if data and not data.endswith(b"\n"):
            fh.truncate(data.rfind(b"\n") + 1)


def _remove(path: Path) -> None:
    if path.is_dir():
        for p in path.glob("*"):
            p.unlink()
        path.rmdir()
    else:
        path.unlink()


def _read_meta(path: Path) -> dict:
    mp = _meta_path(path)
    if not mp.is_file():
        raise InputError(f"{str(path)!r} has no {mp.name} beside it: not campaign results of qprr (or the file was moved alone)")
    try:
        return json.loads(mp.read_text())
    except json.JSONDecodeError as exc:
        raise InputError(f"{str(mp)!r}: corrupted campaign metadata ({exc})") from exc


@dataclass
class Results:
    """A campaign's table: ``table`` (numpy structured array, one row per run, sorted by ``run``) and its metadata.

    ``params``: the parameter columns; ``metrics``: the metric columns; ``spec``: the
    specification as a dict; ``names``: the xi names of the RMSE columns.
    """

    table: np.ndarray
    params: tuple[str, ...]
    metrics: tuple[str, ...]
    spec: dict
    names: tuple[str, ...]
    path: Path

    def __len__(self) -> int:
        return len(self.table)

    def column(self, name: str) -> np.ndarray:
        if name not in self.table.dtype.names:
            from ..errors import UnknownNameError

            raise UnknownNameError("results column", name, self.table.dtype.names)
        return self.table[name]

    def to_pandas(self):
        """The table as a pandas DataFrame (needs pandas)."""
        try:
            import pandas as pd
        except ImportError as exc:
            raise MissingDependencyError("pandas", "campaign tables as DataFrames", "pip install pandas") from exc
        return pd.DataFrame({k: self.table[k] for k in self.table.dtype.names})


def _column_array(values: list) -> np.ndarray:
    """Ints if every value is an integer literal, floats if every one parses as a float, else strings."""
    try:
        ints = [int(v) for v in values]
        if all(str(i) == str(v).strip() for i, v in zip(ints, values)):
            return np.array(ints, dtype=np.int64)
    except (TypeError, ValueError):
        pass
    try:
        return np.array([float(v) for v in values], dtype=float)
    except (TypeError, ValueError):
        return np.array([str(v) for v in values], dtype=str)


def read_results(path: str | Path) -> Results:
    """Read a campaign's results (``.csv`` or ``.parquet``) with its ``.meta.json``; last row per run wins."""
    if isinstance(path, (str, os.PathLike)) and Path(path).suffix == ".parquet":
        path = Path(path)  # a folder of parts
        if not path.is_dir():
            raise InputError(f"path: campaign results {str(path)!r} do not exist")
    else:
        path = as_file(path, "path", what="campaign results file")
    meta = _read_meta(path)
    columns = list(meta["columns"])
    rows: dict[int, list] = {}
    if path.suffix == ".parquet":
        pa, pq = _require_pyarrow()
        parts = sorted(path.glob("part-*.parquet"))
        for part in parts:
            t = pq.read_table(part).to_pydict()
            for i in range(len(t["run"])):
                rows[int(t["run"][i])] = [t[c][i] for c in columns]
    else:
        with path.open(newline="") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            if header != columns:
                raise InputError(f"{str(path)!r}: header {header} differs from its metadata's columns {columns}")
            for line in reader:
                if len(line) != len(columns):  # a line cut by a crash: the run is re-run on resume
                    continue
                rows[int(line[0])] = line
    order = sorted(rows)
    cols = {c: _column_array([rows[r][j] for r in order]) for j, c in enumerate(columns)}
    for c in ("status", "reason"):
        if c in cols:
            cols[c] = np.array([str(v) for v in (rows[r][columns.index(c)] for r in order)], dtype=str)
    for c in cols:
        if c in meta.get("metrics", []) and c not in ("status", "reason") and cols[c].dtype.kind in "iu":
            cols[c] = cols[c].astype(float)
    if order:
        dtype = [(c, cols[c].dtype) for c in columns]
        table = np.empty(len(order), dtype=dtype)
        for c in columns:
            table[c] = cols[c]
    else:
        table = np.empty(0, dtype=[(c, float) for c in columns])
    return Results(table, tuple(meta.get("params", ())), tuple(meta.get("metrics", ())), meta.get("spec", {}),
                   tuple(meta.get("names", ())), path)
