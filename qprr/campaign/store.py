"""Results on disk, appended as runs finish, keyed by run index; read back as a validated table.

* ``RESULTS.csv``: one header line, then one *record* per line per finished run, written with
  one ``write`` call the moment the run ends.  A record never spans lines: in text fields a
  backslash, a newline, a carriage return and a NUL are written ``\\\\``, ``\\n``, ``\\r``,
  ``\\0`` (a traceback stays on its line), commas and quotes are CSV-quoted, floats are written
  with ``repr`` (exact round trip).  The last column, ``crc32``, is the CRC-32 (8 hex digits)
  of the line's bytes before it.  A cut at any byte (a crash, a full disk, a power loss) leaves
  complete records and at most one incomplete last line without its newline: resuming drops
  exactly that line and its run is done again.  A complete line whose checksum or values are
  wrong (edited by hand, damaged) is refused with the file, the line and the column.
* ``RESULTS.parquet`` (needs pyarrow, extra ``qprr[parquet]``): a folder of part files, one per
  batch of rows (every 50 rows or 10 s, and at the end); each part is written to a temporary
  name and renamed, so it appears complete or not at all: a crash loses at most the rows of the
  batch in progress.  ``pyarrow.parquet.read_table`` and pandas read the folder as one table.
* ``RESULTS.meta.json`` beside it (replaced atomically): the specification, its fingerprint,
  the columns and their kinds (:data:`KINDS`).  Resuming checks the fingerprint: results of
  another specification are never mixed.  ``RESULTS.lock``: a second campaign writing to the
  same file is refused while the first runs.

Reading (:func:`read_results`, and the store when it resumes) validates every row: the run
index is an integer within the campaign's runs, every column has its kind (integers, floats,
flags 0/1, statuses of :data:`qprr.campaign.metrics.STATUSES`), the checksum matches and, for
a campaign, the seed and parameters are the ones its specification gives that run.  A bad row
raises :class:`ResultsFileError` naming the file, the line and the column; nothing is counted
from a file that fails.  A failed write raises :class:`ResultsWriteError` naming the file and
the operating system's error.

Rows are keyed by ``run``: when a run appears twice (a row of status ``error`` is re-run on
resume), the last row wins.  :func:`read_results` returns a :class:`Results` (a numpy
structured array sorted by run, and the metadata).

Why lines and not SQLite: ``benchmarks/store_benchmark.py`` writes 10,000 rows of the
robustness study's shape through each.  Side by side (a shared 2-core machine, load 16): 60 us
per row for this store, 75 us for the plain CSV with a flush per row it replaced, 104 us for
SQLite in WAL mode with a transaction per row (``synchronous=NORMAL``), 6.8 ms with an fsync
per row (``FULL``) - all negligible against a run (0.3 to 30 s) but the last.  The line store
keeps the file users open (pandas, a spreadsheet) as the one copy, with no export step, and its
recovery is a property the tests check at every byte offset.
"""

from __future__ import annotations

import csv
import errno
import functools
import json
import os
import re
import time
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, MissingDependencyError, QprrError
from ..validation import as_file, as_output_path

FORMATS = (".csv", ".parquet")
PART_KEY = b"qprr.fingerprint"
"""Key of a Parquet part's schema metadata (format 3): the fingerprint of the campaign that wrote it."""
META_VERSION = 3
"""Format of the results files written now: 3 = one record per line whose checksum covers the campaign's fingerprint and
the line (a row of another campaign is refused); 2 = the same records, checksummed over the line alone (still read, and
resumed in format 2); 1 = plain CSV (read only)."""
VERSIONS = (1, 2, META_VERSION)
"""The formats qprr reads."""
CHECK = "crc32"
"""The last column of a CSV results file: CRC-32 of the campaign's fingerprint followed by the line's bytes before it
(8 hex digits; format 2: of the line's bytes alone)."""
KINDS = ("run", "int", "float", "flag", "status", "text")
"""Kinds of column: ``run`` (integer index within the campaign), ``int``, ``float`` (NaN and inf
allowed), ``flag`` (0 or 1), ``status`` (one of :data:`~qprr.campaign.metrics.STATUSES`), ``text``."""
META_KEYS = {"columns": list, "fingerprint": str, "format_version": int}
"""Keys every ``.meta.json`` has, with their JSON types."""


class ResultsWriteError(QprrError, OSError):
    """The results could not be written (full disk, read-only folder...): names the file and the OS error."""

    def __init__(self, path, exc: OSError) -> None:
        self.path = str(path)
        self.os_error = exc
        reason = exc.strerror or str(exc)
        super().__init__(exc.errno, f"cannot write campaign results {self.path!r}: [Errno {exc.errno}] {reason}")

    def __str__(self) -> str:
        return self.args[1]


class ResultsFileError(InputError):
    """A results file or its metadata that does not hold what a campaign writes: names the file, line and column."""


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
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, np.integer):
        return str(int(v))
    return str(v)


_ESCAPES = {"\\": "\\\\", "\n": "\\n", "\r": "\\r", "\x00": "\\0"}
_ESCAPED = re.compile(r"[\\\n\r\x00]")
_UNESCAPES = {"\\": "\\", "n": "\n", "r": "\r", "0": "\x00"}
_UNESCAPED = re.compile(r"\\(.)")


def _escape(s: str) -> str:
    return _ESCAPED.sub(lambda m: _ESCAPES[m.group()], s) if _ESCAPED.search(s) else s


def _unescape(s: str) -> str:
    return _UNESCAPED.sub(lambda m: _UNESCAPES.get(m.group(1), m.group(1)), s) if "\\" in s else s


def _field(s: str) -> str:
    s = _escape(s)
    return '"' + s.replace('"', '""') + '"' if ("," in s or '"' in s) else s


@functools.lru_cache(maxsize=64)
def _salt(fingerprint: str) -> int:
    """CRC-32 of ``fingerprint``: the start value of a record's checksum, which then covers fingerprint + line (0 for "")."""
    return zlib.crc32(fingerprint.encode())


def record(values, fingerprint: str = "") -> bytes:
    """One line of a CSV results file: the escaped fields, then the CRC-32 of the campaign's ``fingerprint`` followed by
    the bytes before it (format 3; ``""``: of those bytes alone, format 2), then a newline."""
    parts = []
    for v in values:
        t = type(v)
        parts.append(repr(v) if t is float else str(v) if t is int else _field(_fmt(v)))  # numbers need no quoting
    body = (",".join(parts) + ",").encode()
    return body + b"%08x\n" % zlib.crc32(body, _salt(fingerprint))


def _writes(path: Path, fn, *args):
    """``fn(*args)``, an ``OSError`` raised as :class:`ResultsWriteError` naming ``path``."""
    try:
        return fn(*args)
    except ResultsWriteError:
        raise
    except OSError as exc:
        raise ResultsWriteError(exc.filename or path, exc) from exc


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        if n <= 0:  # pragma: no cover - a write that makes no progress
            raise OSError(errno.EIO, "write made no progress")
        view = view[n:]


def _write_meta(path: Path, meta: dict) -> None:
    """The ``.meta.json`` of ``path``, replaced atomically (a crash leaves the old or the new one)."""
    mp = _meta_path(path)
    tmp = mp.with_name(mp.name + ".tmp")
    tmp.write_text(json.dumps(meta, indent=1, default=str))
    os.replace(tmp, mp)


def default_kinds(columns) -> dict[str, str]:
    """Kinds of a store's columns when none are given: ``run`` and ``status`` known, the rest text."""
    return {c: "run" if c == "run" else "status" if c == "status" else "text" for c in columns}


class ResultStore:
    """Append-only results file of one campaign (see the module docstring).

    ``columns``: every column in order; ``meta``: what goes to the ``.meta.json`` file
    (``fingerprint`` is checked on resume; optional ``kinds``, column -> one of :data:`KINDS`,
    and ``n_runs``, the number of runs, validate the rows; ``spec``, a specification as a dict,
    checks every row's seed and parameters).  :attr:`done` holds the run indices already saved
    with a status other than ``error``; :attr:`dropped` the bytes of an incomplete last record
    removed when resuming (its run is done again).  A failed write raises
    :class:`ResultsWriteError`; the store then refuses further rows.
    """

    def __init__(self, path: str | Path, columns: tuple[str, ...], meta: dict, *, fresh: bool = False) -> None:
        if (
            isinstance(columns, str)
            or not isinstance(columns, (list, tuple))
            or not columns
            or not all(isinstance(c, str) and c for c in columns)
            or len(set(columns)) != len(columns)
        ):
            raise InputError(f"columns must be a non-empty sequence of distinct column names, got {columns!r}")
        if CHECK in columns or "run" not in columns:
            raise InputError(f"columns must include 'run' (the key of a row) and not {CHECK!r} (the checksum), got {columns!r}")
        if not isinstance(meta, Mapping):
            raise InputError(f"meta must be a mapping (the .meta.json content), got {type(meta).__name__}")
        kinds = dict(default_kinds(columns), **dict(meta.get("kinds", {})))
        for c, k in kinds.items():
            if c not in columns or k not in KINDS:
                raise InputError(f"meta['kinds']: column {c!r} of kind {k!r}: the columns are {list(columns)}, the kinds {list(KINDS)}")
        self.path = check_output(path)
        self._fd: int | None = None
        self._failed = False
        self._lock = _writes(self.path, _lock, self.path)  # one writer per results file (released when this process ends)
        try:
            self._open(tuple(columns), dict(meta, columns=list(columns), kinds=kinds, format_version=META_VERSION), fresh)
        except BaseException:
            self._release()
            raise

    def _open(self, columns: tuple[str, ...], meta: dict, fresh: bool) -> None:
        self.columns, self.meta = columns, meta
        self.parquet = self.path.suffix == ".parquet"
        self.done: set[int] = set()
        self.rows_before = self.dropped = 0
        if self.path.exists() and not fresh:
            old = read_meta(self.path)
            _check_resume(self.path, old, meta)
            meta["format_version"] = old["format_version"]  # a file of format 2 goes on in format 2 (its records lack the fingerprint)
            if not self.parquet:
                self.dropped = _writes(self.path, _drop_incomplete, self.path)
            table = read_results(self.path).table  # every row validated: a bad one refuses the resume
            self.rows_before = len(table)
            self.done = {int(r) for r, s in zip(table["run"], table["status"]) if s != "error"}
        elif self.path.exists():
            _writes(self.path, _remove, self.path)
        self._fingerprint = str(meta.get("fingerprint", "")) if meta["format_version"] >= 3 else ""  # in every record's check
        _writes(self.path, _write_meta, self.path, meta)
        self._buffer: list[dict] = []
        self._last_flush = time.monotonic()
        if self.parquet:
            _writes(self.path, self.path.mkdir, 0o777, False, True)
            parts = [int(p.stem.split("-")[1]) for p in self.path.glob("part-*.parquet") if p.stem.split("-")[1].isdigit()]
            self._part = max(parts, default=-1) + 1
        else:
            self._fd = _writes(self.path, os.open, self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
            if os.fstat(self._fd).st_size == 0:
                self._write((",".join((*columns, CHECK)) + "\n").encode())

    def _write(self, data: bytes) -> None:
        if self._failed:
            raise InputError(f"the results store {str(self.path)!r} failed to write before: it takes no more rows")
        try:
            _writes(self.path, _write_all, self._fd, data)
        except ResultsWriteError:
            self._failed = True
            raise

    def append(self, row: Mapping) -> None:
        """Save one finished run (CSV: one line written now; Parquet: with its batch); :class:`ResultsWriteError` if it cannot."""
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
            self._write(record((row[c] for c in self.columns), self._fingerprint))

    def flush(self) -> None:
        """Write the Parquet rows of the batch in progress as one part (CSV rows are written by :meth:`append`)."""
        if self.parquet and self._buffer and not self._failed:
            pa, pq = _require_pyarrow()
            table = pa.table({c: pa.array([_plain(r[c]) for r in self._buffer]) for c in self.columns})
            if self._fingerprint:  # a part knows its campaign: one copied from another campaign's folder is refused
                table = table.replace_schema_metadata({PART_KEY: self._fingerprint})
            tmp = self.path / f".part-{self._part:05d}.tmp"
            try:
                _writes(tmp, pq.write_table, table, tmp)
                _writes(tmp, os.replace, tmp, self.path / f"part-{self._part:05d}.parquet")  # complete or absent
            except ResultsWriteError:
                self._failed = True
                tmp.unlink(missing_ok=True)
                raise
            self._part += 1
            self._buffer.clear()
        self._last_flush = time.monotonic()

    def close(self) -> None:
        """Write what is buffered (Parquet), close the file and release the lock (the lock is released even if the write fails)."""
        try:
            self.flush()
        finally:
            self._release()

    def _release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if self._lock is not None:
            Path(self._lock.name).unlink(missing_ok=True)  # removed while held: no .lock is left after a finished run
            self._lock.close()
            self._lock = None

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _check_resume(path: Path, old: dict, meta: dict) -> None:
    """Refuse to resume results ``path`` (metadata ``old``) with the campaign of ``meta`` when they are another campaign's,
    when their metadata is damaged (:func:`_meta_damage`: never blamed on another specification) or of format 1."""
    fingerprint = meta.get("fingerprint")
    if old["fingerprint"] != fingerprint:
        damage = _meta_damage(path, old, fingerprint)
        if damage:
            raise ResultsFileError(f"{str(_meta_path(path))!r}: {damage}")
        raise InputError(
            f"{str(path)!r} holds results of another specification (fingerprint {old['fingerprint']!r}, "
            f"this one {fingerprint!r}{_spec_difference(old.get('spec'), meta.get('spec'))}): "
            f"choose another output (its runs stay in {str(path)!r}) or start afresh (--fresh discards them)"
        )
    if list(old["columns"]) != list(meta["columns"]):
        raise InputError(f"{str(path)!r} has other columns than this campaign's: choose another output or --fresh")
    if old["format_version"] == 1:
        raise InputError(
            f"{str(path)!r} was written in format 1 (a cut record could corrupt it); qprr reads it (qprr campaign report) "
            f"but resumes only formats 2 and {META_VERSION}: choose another output (it stays readable) or --fresh"
        )


def _meta_damage(path: Path, old: dict, fingerprint) -> str:
    """Why the metadata ``old`` of ``path``, whose fingerprint is not ``fingerprint``, is damaged rather than another
    campaign's ("" when nothing says so): its 'spec' does not give the fingerprint it records, or its records carry
    ``fingerprint``.  A 'spec' that is no specification raises :class:`ResultsFileError`."""
    spec, own = _recomputed(old, _meta_path(path))
    carried = _records_fingerprint(path, old, (fingerprint, old["fingerprint"]))
    if carried != fingerprint and (own is None or own == old["fingerprint"]):
        return ""  # consistent metadata (and records): another campaign's results
    if own == fingerprint or (own is None and carried == fingerprint):
        return (
            f"its 'fingerprint' {old['fingerprint']!r} was damaged: its {'spec' if own == fingerprint else 'records'} "
            f"{'is' if own == fingerprint else 'carry'} this specification's ({fingerprint!r}); the saved runs are this "
            f'campaign\'s: set "fingerprint": "{fingerprint}" in it (or restore it from a copy) and run the same command '
            f"again (not --fresh, which would discard them)"
        )
    why = f"its 'spec' has fingerprint {own!r}, not the {old['fingerprint']!r} it records" if own is not None else "it does not match its records"
    mine = "; its records carry this specification's fingerprint" if carried == fingerprint else ""
    return f"the campaign metadata was damaged ({why}{mine}): {_META_FIX}"


def _records_fingerprint(path: Path, meta: dict, candidates) -> str | None:
    """Which of the fingerprints ``candidates`` the first record of ``path`` carries in its check (format 3 only; None:
    none, or nothing to tell by)."""
    if meta["format_version"] < 3 or not path.exists():
        return None
    if path.is_dir():
        parts = sorted(path.glob("part-*.parquet"))
        if not parts:
            return None
        pa, pq = _require_pyarrow()
        try:
            carried = (pq.read_schema(parts[0]).metadata or {}).get(PART_KEY, b"").decode()
        except (OSError, pa.ArrowException, UnicodeDecodeError):
            return None
        return next((c for c in candidates if isinstance(c, str) and c == carried), None)
    lines = path.read_bytes().split(b"\n")
    if len(lines) < 3:
        return None
    body, crc = _split_check(lines[1])
    return next((c for c in candidates if isinstance(c, str) and crc is not None and zlib.crc32(body, _salt(c)) == crc), None)


def _lock(path: Path):
    """An exclusive advisory lock on ``<stem>.lock`` beside the results (POSIX; elsewhere no lock)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return None
    fh = path.with_name(path.stem + ".lock").open("a")
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        lock_file = Path(fh.name)
        if not lock_file.exists() or os.fstat(fh.fileno()).st_ino != lock_file.stat().st_ino:  # removed by a writer that just ended
            raise OSError("the lock file was replaced")
    except OSError as exc:
        fh.close()
        raise InputError(f"another campaign is writing to {str(path)!r} (lock {fh.name!r}): wait for it or choose another output") from exc
    return fh


def _plain(v):
    return v.item() if isinstance(v, np.generic) else v


def _drop_incomplete(path: Path) -> int:
    """Remove an incomplete last record (no final newline: a cut write); returns the bytes removed."""
    with path.open("rb+") as fh:
        data = fh.read()
        if not data or data.endswith(b"\n"):
            return 0
        keep = data.rfind(b"\n") + 1
        fh.truncate(keep)
        return len(data) - keep


def _remove(path: Path) -> None:
    if path.is_dir():
        for p in path.glob("*"):
            p.unlink()
        path.rmdir()
    else:
        path.unlink()


_FIX = "restore it, or delete the line (file) to run its runs again on resume"
_FOREIGN_FIX = "delete the line (part) to run its run again on resume, or move it to the results of its own campaign"
_META_FIX = (
    "the saved runs are kept: restore it from a copy, or write it again from the campaign's specification "
    "(qprr campaign run SPEC -o NEW.csv --limit 0 writes NEW.meta.json and runs nothing: copy it over this file; "
    "set its format_version to 2 for results written before format 3); not --fresh, which would discard them"
)


def read_meta(path: str | Path) -> dict:
    """The ``.meta.json`` beside results ``path``, checked: a JSON object with ``columns``, ``fingerprint``, ``format_version``."""
    mp = _meta_path(path)
    if not mp.is_file():
        raise ResultsFileError(f"{str(path)!r} has no {mp.name} beside it: not campaign results of qprr (or the file was moved alone)")
    try:
        meta = json.loads(mp.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ResultsFileError(f"{str(mp)!r}: corrupted campaign metadata ({exc}): {_META_FIX}") from exc
    if not isinstance(meta, dict):
        raise ResultsFileError(f"{str(mp)!r}: campaign metadata is a JSON object, this file holds a {type(meta).__name__}: {_META_FIX}")
    for key, typ in META_KEYS.items():
        if key not in meta:
            raise ResultsFileError(f"{str(mp)!r}: key {key!r} is missing (campaign metadata has {', '.join(META_KEYS)}): {_META_FIX}")
        if not isinstance(meta[key], typ) or isinstance(meta[key], bool):
            raise ResultsFileError(f"{str(mp)!r}: key {key!r} must be a JSON {typ.__name__}, got {meta[key]!r}: {_META_FIX}")
    cols = meta["columns"]
    if not cols or not all(isinstance(c, str) and c for c in cols) or len(set(cols)) != len(cols) or "run" not in cols:
        raise ResultsFileError(f"{str(mp)!r}: 'columns' must be distinct names including 'run', got {cols!r}: {_META_FIX}")
    if meta["format_version"] not in VERSIONS:
        raise ResultsFileError(
            f"{str(mp)!r}: format_version {meta['format_version']!r} is not one qprr knows {VERSIONS}: results of a newer qprr? read them with it"
        )
    for key, typ in (("params", list), ("metrics", list), ("names", list), ("spec", dict), ("kinds", dict), ("n_runs", int)):
        if key in meta and (not isinstance(meta[key], typ) or isinstance(meta[key], bool)):
            raise ResultsFileError(f"{str(mp)!r}: key {key!r} must be a JSON {typ.__name__}, got {meta[key]!r}: {_META_FIX}")
    for c, k in meta.get("kinds", {}).items():
        if c not in cols or k not in KINDS:
            raise ResultsFileError(f"{str(mp)!r}: 'kinds' gives column {c!r} the kind {k!r} (columns {cols}, kinds {list(KINDS)}): {_META_FIX}")
    return meta


@dataclass
class _Specification:
    """A campaign specification read from metadata, and the seed and parameter columns (as written) it gives each run,
    computed once per run (a resumed or re-read file checks every row against them)."""

    spec: object
    columns: dict[int, dict[str, str]] = field(default_factory=dict)

    def expected(self, run: int) -> dict[str, str]:
        """The seed and parameter columns of ``run``."""
        if run not in self.columns:
            from .worker import params_row

            r = self.spec.run(run)
            self.columns[run] = {"seed": str(r.seed), **{k: _fmt(v) for k, v in params_row(self.spec, r.params).items()}}
        return self.columns[run]


_SPECS: dict[str, _Specification] = {}
"""Specifications read from metadata in this process, keyed by their JSON text (a report after a run reads it once)."""


def _short(value) -> str:
    """``value``'s repr, cut to 40 characters."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _spec_difference(old, new) -> str:
    """``; it differs in ...``: the keys of two specifications (as dicts) that differ, a platform file's content named."""
    if not isinstance(old, dict) or not isinstance(new, dict):
        return ""
    keys = [k for k in sorted(set(old) | set(new)) if old.get(k) != new.get(k)]
    parts = []
    for k in keys:
        o, n = old.get(k), new.get(k)
        if (
            k == "platform"
            and isinstance(o, dict)
            and isinstance(n, dict)
            and isinstance(o.get("sha256"), dict)
            and isinstance(n.get("sha256"), dict)
        ):
            changed = [f for f in ("urdf", "rotors") if o["sha256"].get(f) != n["sha256"].get(f)]
            same_paths = all(o.get(f) == n.get(f) for f in ("urdf", "rotors", "ee_frame"))
            if changed and same_paths:
                parts += [
                    f"the content of platform.{f} = {n.get(f)!r} (sha256 {str(o['sha256'].get(f))[:12]}... -> {str(n['sha256'].get(f))[:12]}...)"
                    for f in changed
                ]
                continue
        if isinstance(o or {}, dict) and isinstance(n or {}, dict):  # a table (or none): name its entries that differ, with their values
            o, n = o or {}, n or {}
            parts += [f"{k}.{f} ({_short(o.get(f))} -> {_short(n.get(f))})" for f in sorted(set(o) | set(n)) if o.get(f) != n.get(f)]
            continue
        parts.append(k)
    return f"; it differs in {', '.join(parts)}" if parts else ""


def _read_spec(meta: dict, mp: Path) -> _Specification | None:
    """The :class:`_Specification` of campaign metadata (None for a plain store); :class:`ResultsFileError` when its
    'spec' is no valid specification."""
    if "spec" not in meta:
        return None
    from .spec import CampaignSpec

    key = json.dumps(meta["spec"], sort_keys=True, default=str)
    try:
        return _SPECS.get(key) or _SPECS.setdefault(key, _Specification(CampaignSpec.from_mapping(meta["spec"])))
    except (QprrError, TypeError, ValueError) as exc:
        raise ResultsFileError(f"{str(mp)!r}: key 'spec' is not a valid campaign specification ({exc}): {_META_FIX}") from exc


def _recomputed(meta: dict, mp: Path):
    """The specification of campaign metadata and its fingerprint recomputed ((None, None) for a plain store);
    :class:`ResultsFileError` when its 'spec' is no valid specification."""
    entry = _read_spec(meta, mp)
    return (None, None) if entry is None else (entry.spec, entry.spec.fingerprint)


def _campaign_spec(meta: dict, mp: Path) -> _Specification | None:
    """The specification of campaign metadata (None for a plain store), checked against its fingerprint."""
    entry = _read_spec(meta, mp)
    if entry is None:
        return None
    fingerprint = entry.spec.fingerprint
    if fingerprint != meta["fingerprint"]:
        raise ResultsFileError(
            f"{str(mp)!r}: its 'spec' has fingerprint {fingerprint!r}, not the {meta['fingerprint']!r} it records "
            f"(the file was damaged or edited): {_META_FIX}"
        )
    return entry


class _Rows:
    """Validates rows of text fields against the metadata and keeps the last one per run."""

    def __init__(self, meta: dict, mp: Path) -> None:
        self.columns = list(meta["columns"])
        kinds = dict(default_kinds(self.columns), **meta.get("kinds", {}))
        self.kinds = [kinds[c] for c in self.columns]
        self.campaign = _campaign_spec(meta, mp)
        self.spec = self.campaign.spec if self.campaign is not None else None
        self.fingerprint = meta["fingerprint"]
        self.version = meta["format_version"]
        self.spec_dict = meta.get("spec")
        self.n_runs = self.spec.n_runs if self.spec is not None else meta.get("n_runs")
        self.i_run = self.columns.index("run")
        self.rows: dict[int, list[str]] = {}
        from .metrics import STATUSES

        self.statuses = STATUSES

    def _bad(self, where: str, column: str, problem: str):
        return ResultsFileError(f"{where}, column {column!r}: {problem}: {_FIX}")

    def _check(self, where: str, column: str, kind: str, text: str) -> None:
        if kind == "status":
            if text not in self.statuses:
                raise self._bad(where, column, f"{text!r} is not a status ({', '.join(self.statuses)})")
            return
        try:
            if kind in ("run", "int"):
                value = int(text)
                if str(value) != text:
                    raise ValueError(text)
            elif kind == "float":
                float(text)
            elif kind == "flag" and text not in ("0", "1"):
                raise ValueError(text)
        except ValueError:
            what = {"run": "a run index (an integer)", "int": "an integer", "float": "a number", "flag": "0 or 1"}[kind]
            raise self._bad(where, column, f"{text!r} is not {what}") from None
        if kind == "run" and (value < 0 or (self.n_runs is not None and value >= self.n_runs)):
            raise self._bad(where, column, f"run {value} is outside the campaign's runs 0..{(self.n_runs or 0) - 1}")

    def add(self, where: str, fields: list[str], checksum_ok: bool | None = None) -> None:
        """Validate one row (``checksum_ok``: the verdict of its checksum, None where rows have none) and keep it."""
        if len(fields) != len(self.columns):
            extra = 0 if checksum_ok is None else 1
            raise ResultsFileError(
                f"{where}: {len(fields) + extra} fields where the header has {len(self.columns) + extra} "
                f"({', '.join(self.columns)}{', ' + CHECK if extra else ''}): {_FIX}"
            )
        for c, k, f in zip(self.columns, self.kinds, fields):
            self._check(where, c, k, f)
        if checksum_ok is False:
            fp = "this campaign's fingerprint and " if self.version >= 3 else ""
            raise self._bad(where, CHECK, f"the checksum does not match {fp}the line (it was edited or damaged)")
        run = int(fields[self.i_run])
        if self.spec is not None:
            self._check_run(where, run, fields)
        self.rows[run] = fields

    def _check_run(self, where: str, run: int, fields: list[str]) -> None:
        expected = self.campaign.expected(run)
        for j, c in enumerate(self.columns):
            if c in expected and fields[j] != expected[c]:
                raise self._bad(where, c, f"{fields[j]!r} is not what the specification gives run {run} ({expected[c]!r})")


def _split_check(raw: bytes) -> tuple[bytes, int | None]:
    """The bytes a record's checksum covers (up to its last comma) and the checksum (None if it is no 8 hex digits)."""
    i = raw.rfind(b",")
    text = raw[i + 1 :]
    if i < 0 or len(text) != 8 or not all(c in b"0123456789abcdefABCDEF" for c in text):
        return raw, None
    return raw[: i + 1], int(text, 16)


def _parse(raw: bytes, fingerprint: str = "") -> tuple[list[str], bool]:
    """Fields and checksum verdict of one record (the bytes of a line without its newline) of the campaign of
    ``fingerprint`` (format 3; ``""``: format 2, a checksum of the line alone)."""
    i = raw.rfind(b",")
    covered, crc = _split_check(raw)
    ok = crc is not None and zlib.crc32(covered, _salt(fingerprint)) == crc
    body = raw[:i] if i >= 0 else raw
    try:
        text = body.decode()
        fields = next(csv.reader([text], strict=True)) if text else [""]
    except (UnicodeDecodeError, csv.Error):
        return [body.decode(errors="replace")], False
    return [_unescape(f) for f in fields], ok


def _foreign(path: Path, raw: bytes, rows: _Rows) -> str:
    """Why record ``raw`` of ``path``, whose checksum does not match its campaign's fingerprint, is no record of that
    campaign: its checksum covers the line alone, or another campaign's fingerprint (one of the results' metadata in the
    same folder: what differs is named).  "" when nothing tells (the line was edited or damaged)."""
    body, crc = _split_check(raw)
    if crc is None:
        return ""
    if zlib.crc32(body) == crc:
        return (
            "its checksum covers the line without this campaign's fingerprint (a record of format 2, or written by hand): "
            "it is not known to be this campaign's"
        )
    for mp in sorted(path.parent.glob("*.meta.json")):
        try:
            other = json.loads(mp.read_text()) if mp != _meta_path(path) else None
        except (OSError, ValueError):
            continue
        fp = other.get("fingerprint") if isinstance(other, dict) else None
        if isinstance(fp, str) and fp and zlib.crc32(body, _salt(fp)) == crc:
            return (
                f"it is a record of another campaign (fingerprint {fp!r}, of {str(mp)!r}; this one's {rows.fingerprint!r}"
                f"{_spec_difference(other.get('spec'), rows.spec_dict)})"
            )
    return ""


def _csv_rows(path: Path, rows: _Rows) -> None:
    data = path.read_bytes()
    lines = data.split(b"\n")  # the last piece: b"" after a final newline, else an incomplete record (a write in progress or cut)
    if len(lines) < 2:
        return
    header = ",".join((*rows.columns, CHECK)).encode()
    if lines[0] != header:
        raise ResultsFileError(
            f"{str(path)!r}, line 1: header {lines[0].decode(errors='replace')!r} differs from its metadata's columns ({header.decode()!r}): {_FIX}"
        )
    fingerprint = rows.fingerprint if rows.version >= 3 else ""
    for n, raw in enumerate(lines[1:-1], start=2):
        fields, ok = _parse(raw, fingerprint)
        where = f"{str(path)!r}, line {n}"
        foreign = "" if ok or not fingerprint else _foreign(path, raw, rows)
        if foreign:
            raise ResultsFileError(f"{where}: {foreign}: {_FOREIGN_FIX}")
        rows.add(where, fields, ok)


def _csv_v1_rows(path: Path, rows: _Rows) -> None:
    """Format 1 (plain CSV, read only): a last line cut short is skipped."""
    with path.open(newline="") as fh:
        reader = csv.reader(fh)
        header = next(reader, None)
        if header != rows.columns:
            raise ResultsFileError(f"{str(path)!r}, line 1: header {header} differs from its metadata's columns {rows.columns}: {_FIX}")
        lines = [(reader.line_num, line) for line in reader]
    for k, (n, line) in enumerate(lines):
        if k == len(lines) - 1 and len(line) != len(rows.columns):
            continue
        rows.add(f"{str(path)!r}, line {n}", line)


def _parquet_rows(path: Path, rows: _Rows) -> None:
    pa, pq = _require_pyarrow()
    for part in sorted(path.glob("part-*.parquet")):
        try:
            t = pq.read_table(part).to_pydict()
        except (OSError, pa.ArrowException) as exc:
            raise ResultsFileError(f"{str(part)!r}: not a readable Parquet part ({exc}): {_FIX}") from exc
        if list(t) != rows.columns:
            raise ResultsFileError(f"{str(part)!r}: columns {list(t)} differ from its metadata's {rows.columns}: {_FIX}")
        carried = (pq.read_schema(part).metadata or {}).get(PART_KEY, b"").decode(errors="replace")
        if rows.version >= 3 and carried != rows.fingerprint:
            whose = f"another campaign's (fingerprint {carried!r})" if carried else "without a campaign's fingerprint"
            raise ResultsFileError(f"{str(part)!r}: a part {whose}, not this campaign's ({rows.fingerprint!r}): {_FOREIGN_FIX}")
        for i in range(len(t["run"])):
            rows.add(f"{str(part)!r}, row {i + 1}", [_fmt(t[c][i]) for c in rows.columns])


@dataclass
class Results:
    """A campaign's table: ``table`` (numpy structured array, one row per run, sorted by ``run``) and its metadata.

    ``params``: the parameter columns; ``metrics``: the metric columns; ``spec``: the
    specification as a dict; ``names``: the xi names of the RMSE columns; ``meta``: the whole
    ``.meta.json`` (what another writer of the store, e.g. :mod:`qprr.design`, keeps beside the table).
    """

    table: np.ndarray
    params: tuple[str, ...]
    metrics: tuple[str, ...]
    spec: dict
    names: tuple[str, ...]
    path: Path
    meta: dict = field(default_factory=dict)

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


def _column_array(values: list[str]) -> np.ndarray:
    """Ints if every value is an integer literal, floats if every one parses as a float, else strings."""
    try:
        ints = [int(v) for v in values]
        if all(str(i) == v.strip() for i, v in zip(ints, values)):
            return np.array(ints, dtype=np.int64)
    except ValueError:
        pass
    try:
        return np.array([float(v) for v in values], dtype=float)
    except ValueError:
        return np.array(values, dtype=str)


def read_results(path: str | Path) -> Results:
    """Read a campaign's results (``.csv`` or ``.parquet``) with its ``.meta.json``, every row validated; last row per run wins.

    An incomplete last record (a campaign writing now, or a cut write) is not read.  A bad row
    raises :class:`ResultsFileError` naming the file, the line and the column.
    """
    if isinstance(path, (str, os.PathLike)) and Path(path).suffix == ".parquet":
        path = Path(path)  # a folder of parts
        if not path.is_dir():
            raise InputError(f"path: campaign results {str(path)!r} do not exist")
    else:
        path = as_file(path, "path", what="campaign results file")
    meta = read_meta(path)
    rows = _Rows(meta, _meta_path(path))
    if path.suffix == ".parquet":
        _parquet_rows(path, rows)
    elif meta["format_version"] == 1:
        _csv_v1_rows(path, rows)
    else:
        _csv_rows(path, rows)
    columns = rows.columns
    order = sorted(rows.rows)
    kinds = dict(zip(columns, rows.kinds))
    cols = {}
    for j, c in enumerate(columns):
        values = [rows.rows[r][j] for r in order]
        if c in ("status", "reason"):
            cols[c] = np.array(values, dtype=str)
        elif kinds[c] == "float":
            cols[c] = np.array([float(v) for v in values], dtype=float)
        else:
            cols[c] = _column_array(values)
            if c in meta.get("metrics", ()) and cols[c].dtype.kind in "iu":
                cols[c] = cols[c].astype(float)
    if order:
        table = np.empty(len(order), dtype=[(c, cols[c].dtype) for c in columns])
        for c in columns:
            table[c] = cols[c]
    else:
        table = np.empty(0, dtype=[(c, float) for c in columns])
    return Results(
        table, tuple(meta.get("params", ())), tuple(meta.get("metrics", ())), meta.get("spec", {}), tuple(meta.get("names", ())), path, meta
    )
