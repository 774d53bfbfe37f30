"""Campaign result store: write cost per run of the line store, the plain CSV it replaced, and SQLite.

    python benchmarks/store_benchmark.py [--rows 10000] [--repeat 3] [--quick]

Rows of the robustness study's shape (``examples/campaigns/robustness.toml``: run, seed,
controller, model.payload, 4 model-error factors, status, reason, t_end, wall_time, 9 RMSE
columns, rmse_position, x_cm_max, saturation, recovery_time, success; 26 columns, ~420 bytes a
line), with the study's samples raised so that it has ``--rows`` runs, written through

* ``csv+flush`` (before, format 1): ``csv.writer.writerow`` and ``flush`` per row, what
  ``ResultStore.append`` did; a cut inside a quoted multi-line field corrupted the file;
* ``line store`` (now, format 2): ``ResultStore.append``: escaped fields, a CRC-32 per line, one
  ``os.write`` per row;
* ``sqlite WAL``: the standard library's sqlite3, WAL mode, ``synchronous=NORMAL``, one
  ``INSERT`` and ``COMMIT`` per row (the transactional alternative of issue 26); and with
  ``synchronous=FULL`` (an fsync per row).

Each configuration writes the same rows to a fresh file in a temporary folder; ``--repeat``
interleaved rounds, best kept (the machine is shared; the load average is printed).  Then the
read of the whole table back, every row validated (``read_results``), per row.  Ratios are
measured side by side in this one run.  Exits 0.  ``--quick``: 300 rows, one round (a smoke run).
"""

from __future__ import annotations

import argparse
import csv
import os
import sqlite3
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np

from qprr.campaign import CampaignSpec
from qprr.campaign.runner import columns_of, kinds_of
from qprr.campaign.store import ResultStore, read_results
from qprr.campaign.worker import params_row, xi_names_of

ROOT = Path(__file__).resolve().parent.parent


def rows_of(n: int):
    """A spec of the robustness study's shape with >= n runs, its columns and meta, and n synthetic rows."""
    spec = CampaignSpec.load(ROOT / "examples" / "campaigns" / "robustness.toml")
    d = spec.to_dict()
    d["samples"] = -(-n // spec.n_points)
    spec = CampaignSpec.from_mapping(d)
    names = xi_names_of(spec)
    columns = columns_of(spec, names)
    meta = {
        "name": spec.name,
        "fingerprint": spec.fingerprint,
        "spec": spec.to_dict(),
        "n_runs": spec.n_runs,
        "kinds": kinds_of(spec, names),
        "metrics": list(columns[columns.index("status") :]),
    }
    rng = np.random.default_rng(0)
    rows = []
    for i in range(n):
        r = spec.run(i)
        row = {"run": i, "seed": r.seed, **params_row(spec, r.params)}
        for c in columns[len(row) :]:
            row[c] = float(rng.lognormal(-3, 1))
        row.update(status="ok", reason="completed", success=int(rng.integers(2)))
        rows.append(row)
    return columns, meta, rows


def _fmt(v) -> str:
    return repr(v) if isinstance(v, float) else str(v)


def write_csv_flush(path: Path, columns, meta, rows) -> None:
    """The store before (format 1): csv.writer + flush per row."""
    with path.open("a", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        fh.flush()
        for row in rows:
            w.writerow([_fmt(row[c]) for c in columns])
            fh.flush()


def write_line_store(path: Path, columns, meta, rows) -> None:
    with ResultStore(path, columns, meta) as store:
        for row in rows:
            store.append(row)


def _sqlite(sync: str):
    def write(path: Path, columns, meta, rows) -> None:
        db = sqlite3.connect(path.with_suffix(".sqlite"), isolation_level=None)
        db.execute("PRAGMA journal_mode=WAL")
        db.execute(f"PRAGMA synchronous={sync}")
        cols = ", ".join(f'"{c}"' for c in columns)
        db.execute(f'CREATE TABLE results ({cols}, PRIMARY KEY ("run"))')
        sql = f"INSERT OR REPLACE INTO results ({cols}) VALUES ({', '.join('?' * len(columns))})"
        for row in rows:
            db.execute("BEGIN")
            db.execute(sql, [row[c] for c in columns])
            db.execute("COMMIT")
        db.close()

    return write


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=10000, help="rows written (default 10000)")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved rounds, best kept (default 3)")
    ap.add_argument("--quick", action="store_true", help="300 rows, one round (a smoke run)")
    args = ap.parse_args(argv)
    if args.quick:
        args.rows, args.repeat = 300, 1
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    columns, meta, rows = rows_of(args.rows)
    configs = {
        "csv+flush (before)": write_csv_flush,
        "line store (now)": write_line_store,
        "sqlite WAL, NORMAL": _sqlite("NORMAL"),
        "sqlite WAL, FULL": _sqlite("FULL"),
    }
    best: dict[str, float] = {}
    size: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for rnd in range(args.repeat):
            for k, (name, fn) in enumerate(configs.items()):
                path = Path(tmp) / f"r{rnd}-{k}.csv"
                t0 = time.perf_counter()
                fn(path, columns, meta, rows)
                dt = time.perf_counter() - t0
                best[name] = min(best.get(name, float("inf")), dt)
                written = [p for p in Path(tmp).glob(f"r{rnd}-{k}.*") if not p.name.endswith(".json") and not p.name.endswith(".lock")]
                size[name] = sum(p.stat().st_size for p in written)
        line = Path(tmp) / "r0-1.csv"
        t0 = time.perf_counter()
        table = read_results(line).table
        t_read = time.perf_counter() - t0
    assert len(table) == args.rows
    print(f"\n{args.rows} rows of {len(columns)} columns (robustness study shape), best of {args.repeat} rounds\n")
    print(f"{'store':<22} {'us/row':>8} {'x before':>9} {'bytes/row':>10}")
    print("-" * 52)
    ref = best["csv+flush (before)"]
    for name, dt in best.items():
        print(f"{name:<22} {1e6 * dt / args.rows:>8.1f} {dt / ref:>9.2f} {size[name] / args.rows:>10.0f}")
    print("-" * 52)
    print(f"ratio line store / csv+flush (write time): {best['line store (now)'] / ref:.2f}")
    print(f"read back with every row validated (read_results): {1e6 * t_read / args.rows:.1f} us/row, {t_read:.2f} s in all")
    print(f"a robustness run takes 0.7 s: the line store's write is {1e2 * best['line store (now)'] / args.rows / 0.7:.4f} % of it")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
