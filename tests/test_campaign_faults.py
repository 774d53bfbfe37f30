"""Campaign faults: a cut at any byte, kills, full disks, read-only folders, edited rows, lost workers and schedulers.

The target is a cheap callable (a 0.02 s flight, or an error with a multi-line reason full of
quotes and commas, the record that a cut used to corrupt); QPRR_TEST_DELAY slows its runs in the
subprocesses that are killed midway (the table does not depend on it).
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from qprr.campaign import CampaignSpec, run_campaign
from qprr.campaign.runner import columns_of, kinds_of
from qprr.campaign.store import ResultsFileError, ResultStore, ResultsWriteError, read_results
from qprr.campaign.worker import make_task_payload, run_one, xi_names_of
from qprr.errors import InputError, UnknownNameError
from tests.polling import poll

TARGET = """
import os
import signal
import time

from qprr.sim import simulate
from qprr.thesis.missions import static_mission
from qprr.thesis.scenarios import flight_controller


def target(params, seed, platform):
    if str(params["k"]) == os.environ.get("QPRR_TEST_CRASH"):  # this run kills its worker (as running out of memory would)
        os.kill(os.getpid(), signal.SIGKILL)
    if os.environ.get("QPRR_TEST_LOG"):
        with open(os.environ["QPRR_TEST_LOG"], "a") as fh:
            fh.write(f"{params['k']}\\n")
    time.sleep(float(os.environ.get("QPRR_TEST_DELAY", "0")))
    if params["k"] % 3 == 2:
        raise ValueError(f'run {params["k"]} failed,\\n  File "x.py", line 3, in "target"\\n    a, b = "1,2"\\\\n\\nValueError: end')
    return simulate(platform, flight_controller("idc", platform), static_mission(), 0.02, seed=seed)
"""

ROOT = Path(__file__).resolve().parent.parent


def _spec(tmp_path: Path, n: int = 9) -> CampaignSpec:
    (tmp_path / "target.py").write_text(TARGET)
    return CampaignSpec.from_mapping(
        {
            "name": "faults",
            "callable": "target.py:target",
            "seed": 3,
            "grid": {"k": list(range(n))},
            "random": {"x": {"dist": "uniform", "low": 0.0, "high": 1.0}},
            "metrics": ["rmse"],
        },
        base_dir=tmp_path,
    )


def _same(a, b) -> None:
    assert a.dtype.names == b.dtype.names
    for n in a.dtype.names:
        if n == "wall_time":
            continue
        if a[n].dtype.kind == "f":
            np.testing.assert_array_equal(a[n], b[n], err_msg=n)
        else:
            assert a[n].tolist() == b[n].tolist(), n


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted campaign: its spec, file bytes, table and the row of every run."""
    tmp = tmp_path_factory.mktemp("reference")
    spec = _spec(tmp)
    done = run_campaign(spec, tmp / "full.csv", backend="inline", progress=False)
    payload = make_task_payload(spec)
    rows = {i: run_one(payload, spec.run(i)) for i in range(spec.n_runs)}
    names = xi_names_of(spec)
    return spec, (tmp / "full.csv").read_bytes(), done.results.table, rows, names, tmp


def _copy_meta(src_dir: Path, dst: Path) -> None:
    shutil.copy(src_dir / "full.meta.json", dst.with_name(dst.stem + ".meta.json"))


# ---------------------------------------------------------------------------- a cut at any byte
def test_error_records_stay_on_one_line(reference):
    spec, data, table, rows, names, _ = reference
    lines = data.split(b"\n")
    assert len(lines) == spec.n_runs + 2 and lines[-1] == b""  # header, one line per run, nothing after the last newline
    errors = table["status"] == "error"
    assert errors.sum() == 3 and all("\n" in r and '"' in r and "," in r for r in table["reason"][errors])
    assert table["reason"][errors][0] == rows[2]["reason"]  # multi-line reason read back exactly


def test_a_cut_at_every_byte_of_the_last_records_resumes_to_the_same_table(reference, tmp_path):
    """Property over every byte offset of the last two records (a flight's and an error's multi-line reason) and of the
    header (every 5th byte): the complete records are kept, exactly the incomplete one is dropped, and the runs
    appended on resume give the uninterrupted table."""
    spec, data, table, rows, names, ref_dir = reference
    columns = columns_of(spec, names)
    meta = json.loads((ref_dir / "full.meta.json").read_text())
    ends = [i + 1 for i, b in enumerate(data) if b == ord("\n")]  # byte offset after each line
    offsets = [*range(0, ends[0] + 2, 5), ends[0] - 1, ends[0], ends[0] + 1, *range(ends[-3], len(data) + 1)]
    for k in offsets:
        out = tmp_path / f"cut{k}.csv"
        out.write_bytes(data[:k])
        _copy_meta(ref_dir, out)
        complete = [e for e in ends if e <= k]
        kept = max(len(complete) - 1, 0)  # records (runs 0..kept-1) whose newline made it to disk
        with ResultStore(out, columns, meta) as store:
            assert store.dropped == k - (complete[-1] if complete else 0), k
            assert store.done == {i for i in range(kept) if rows[i]["status"] != "error"}, k
            for i in range(spec.n_runs):
                if i not in store.done:
                    store.append(rows[i])
        got = read_results(out)
        _same(got.table, table)
        assert sorted(got.table["run"].tolist()) == list(range(spec.n_runs))  # none lost, none twice
        out.unlink()


def test_a_cut_inside_a_multiline_error_record_resumes_through_the_runner(reference, tmp_path):
    spec, data, table, rows, names, ref_dir = reference
    start = data.index(b"run 2 failed")
    cut = data.index(b"\\n", start) + 2  # just after an escaped newline of the traceback: once the fatal offset
    out = tmp_path / "r.csv"
    out.write_bytes(data[:cut])
    _copy_meta(ref_dir, out)
    again = run_campaign(spec, out, backend="inline", progress=False)
    assert (again.skipped, again.executed, again.remaining, again.lost) == (2, spec.n_runs - 2, 0, 0)
    _same(again.results.table, table)
    assert run_campaign(spec, out, backend="inline", progress=False).executed == 3  # only the error rows are done again


# ---------------------------------------------------------------------------- rows edited or damaged
def _edit(line: bytes, column: int, value: bytes, columns) -> bytes:
    import csv

    fields = next(csv.reader([line.decode()]))
    fields[column] = value.decode()
    return ",".join(fields).encode()


@pytest.mark.parametrize(
    "case, column, match",
    [
        ("garbage", None, "2 fields where the header has 20"),
        ("run=999", "run", "run 999 is outside the campaign's runs 0..8"),
        ("run=abc", "run", "'abc' is not a run index"),
        ("rmse_x=oops", "rmse_x", "'oops' is not a number"),
        ("status=great", "status", "'great' is not a status"),
        ("success=2", "success", "'2' is not 0 or 1"),
        ("rmse_x=0.5", "crc32", "checksum does not match"),
        ("seed=1 with its checksum", "seed", "is not what the specification gives run 1"),
    ],
)
def test_a_bad_row_is_named_with_file_line_and_column_and_refused(reference, tmp_path, case, column, match, capsys):
    import zlib

    from qprr.cli import main

    spec, data, table, rows, names, ref_dir = reference
    columns = columns_of(spec, names)
    lines = data.split(b"\n")
    if case == "garbage":
        lines.insert(2, b"garbage,row")
    else:
        name, value = case.split(" ")[0].split("=")
        body = _edit(lines[2], columns.index(name), value.encode(), columns)  # line 3 of the file: run 1
        if "checksum" in case:
            body = body[: body.rfind(b",") + 1]
            body += b"%08x" % zlib.crc32(body, zlib.crc32(spec.fingerprint.encode()))  # format 3: fingerprint + line
        lines[2] = body
    out = tmp_path / "bad.csv"
    out.write_bytes(b"\n".join(lines))
    _copy_meta(ref_dir, out)
    where = f"'{out}', line 3" + (f", column {column!r}" if column else "")
    with pytest.raises(ResultsFileError, match=match) as err:
        read_results(out)
    assert where in str(err.value)
    with pytest.raises(ResultsFileError, match=match):  # the resume refuses rather than counting the row
        run_campaign(spec, out, backend="inline", progress=False)
    assert main(["campaign", "report", str(out)]) == 2
    assert where in capsys.readouterr().err


@pytest.mark.parametrize(
    "meta, match",
    [
        ([1, 2], "JSON object, this file holds a list"),
        ({"fingerprint": "x", "format_version": 2}, "key 'columns' is missing"),
        ("drop:fingerprint", "key 'fingerprint' is missing"),
        ("spec:seed=4", "its 'spec' has fingerprint"),
        ("columns:7", "key 'columns' must be a JSON list"),
        ("kinds:status=real", "'kinds' gives column 'status' the kind 'real'"),
    ],
)
def test_bad_metadata_is_named_with_its_file_and_key(reference, tmp_path, meta, match):
    spec, data, table, rows, names, ref_dir = reference
    good = json.loads((ref_dir / "full.meta.json").read_text())
    if isinstance(meta, str):
        what, change = meta.split(":")
        if what == "drop":
            del good[change]
        elif what == "spec":
            good["spec"]["seed"] = 4
        elif what == "columns":
            good["columns"] = 7
        else:
            good["kinds"]["status"] = "real"
        meta = good
    out = tmp_path / "m.csv"
    out.write_bytes(data)
    (tmp_path / "m.meta.json").write_text(json.dumps(meta))
    with pytest.raises(ResultsFileError, match=match) as err:
        read_results(out)
    assert str(tmp_path / "m.meta.json") in str(err.value)


# ---------------------------------------------------------------------------- rows and metadata of another campaign, damaged metadata
def _other(reference, tmp_path: Path, **changes):
    """The reference campaign's results in ``tmp_path`` (a.csv) and those of a specification that differs by ``changes``
    (b.csv, run here), side by side."""
    spec, data, table, rows, names, ref_dir = reference
    shutil.copy(ref_dir / "target.py", tmp_path / "target.py")
    (tmp_path / "a.csv").write_bytes(data)
    _copy_meta(ref_dir, tmp_path / "a.csv")
    other = CampaignSpec.from_mapping({**spec.to_dict(), **changes}, base_dir=tmp_path)
    run_campaign(other, tmp_path / "b.csv", backend="inline", progress=False)
    return other


def test_a_row_of_a_campaign_that_differs_only_in_duration_is_refused_with_what_differs(reference, tmp_path, capsys):
    """Its fields are those of the real row (the duration is no column, the seed is the same): only the fingerprint in
    its checksum tells it apart.  Resume and report refuse it, naming the file, the line, the other campaign and what
    differs; they used to count it as done (or let it replace the real row)."""
    from qprr.cli import main

    spec = reference[0]
    _other(reference, tmp_path, options={"duration": 5.0})
    a, b = (tmp_path / "a.csv").read_bytes().split(b"\n"), (tmp_path / "b.csv").read_bytes().split(b"\n")
    assert a[2].split(b",")[:2] == b[2].split(b",")[:2]  # run 1, its seed: the same (and its parameters, its metrics)
    a[2] = b[2]
    (tmp_path / "a.csv").write_bytes(b"\n".join(a))
    where = f"'{tmp_path / 'a.csv'}', line 3: it is a record of another campaign"
    for attempt in (lambda: read_results(tmp_path / "a.csv"), lambda: run_campaign(spec, tmp_path / "a.csv", backend="inline", progress=False)):
        with pytest.raises(ResultsFileError) as err:
            attempt()
        assert where in str(err.value) and f"'{tmp_path / 'b.meta.json'}'" in str(err.value), err.value
        assert "options.duration (5.0 -> None)" in str(err.value) and "delete the line" in str(err.value), err.value
    assert main(["campaign", "report", str(tmp_path / "a.csv")]) == 2
    assert where in capsys.readouterr().err


def test_a_row_without_the_fingerprint_in_its_check_is_refused_and_format_2_files_stay_usable(reference, tmp_path):
    """A record checksummed over its line alone (format 2) in a file of format 3 is refused with the reason; a whole file
    of format 2 (written by qprr before) is read, and resumed in its own format."""
    import zlib

    spec, data, table, rows, names, ref_dir = reference
    lines = data.split(b"\n")
    old = [lines[0]] + [line[: line.rfind(b",") + 1] + b"%08x" % zlib.crc32(line[: line.rfind(b",") + 1]) for line in lines[1:-1]] + [b""]
    mixed = tmp_path / "mixed.csv"
    mixed.write_bytes(b"\n".join([*lines[:4], old[4], *lines[5:]]))
    _copy_meta(ref_dir, mixed)
    with pytest.raises(ResultsFileError, match="line 5: its checksum covers the line without this campaign's fingerprint"):
        read_results(mixed)
    v2 = tmp_path / "v2.csv"
    v2.write_bytes(b"\n".join(old[:5]) + b"\n" + old[5][:20])  # format 2, four runs and a cut record
    meta = json.loads((ref_dir / "full.meta.json").read_text())
    (tmp_path / "v2.meta.json").write_text(json.dumps({**meta, "format_version": 2}))
    assert len(read_results(v2)) == 4
    again = run_campaign(spec, v2, backend="inline", progress=False)
    assert again.remaining == 0 and json.loads((tmp_path / "v2.meta.json").read_text())["format_version"] == 2
    _same(again.results.table, table)
    last = v2.read_bytes().split(b"\n")[-2]
    assert int(last[-8:], 16) == zlib.crc32(last[:-8])  # the records appended on resume are of format 2 too


def test_a_damaged_fingerprint_in_the_metadata_is_named_as_damage_and_the_advice_keeps_the_saved_runs(reference, tmp_path):
    spec, data, table, rows, names, ref_dir = reference
    out = tmp_path / "r.csv"
    out.write_bytes(data)
    meta = json.loads((ref_dir / "full.meta.json").read_text())
    flipped = spec.fingerprint[:5] + ("0" if spec.fingerprint[5] != "0" else "1") + spec.fingerprint[6:]  # one character
    (tmp_path / "r.meta.json").write_text(json.dumps({**meta, "fingerprint": flipped}))
    with pytest.raises(ResultsFileError) as err:
        run_campaign(spec, out, backend="inline", progress=False)
    text = str(err.value)
    assert str(tmp_path / "r.meta.json") in text and f"'fingerprint' {flipped!r} was damaged" in text, text
    assert f'set "fingerprint": "{spec.fingerprint}"' in text and "another specification" not in text and "(--fresh)" not in text
    (tmp_path / "r.meta.json").write_text(json.dumps(meta))  # the advice followed: every saved run is kept
    again = run_campaign(spec, out, backend="inline", progress=False)
    assert (again.skipped, again.executed, again.remaining) == (spec.n_runs - 3, 3, 0)  # only the error rows run again
    _same(again.results.table, table)


@pytest.mark.parametrize("damage", ["truncated", "spec", "no records: spec"])
def test_damaged_metadata_is_never_blamed_on_another_specification(reference, tmp_path, damage):
    """Metadata that is no JSON, or whose 'spec' was damaged too: the message says so and how to write it again; it never
    advises --fresh (which discards every saved run)."""
    spec, data, table, rows, names, ref_dir = reference
    out = tmp_path / "r.csv"
    out.write_bytes(data if "no records" not in damage else data.split(b"\n")[0] + b"\n")
    text = (ref_dir / "full.meta.json").read_text()
    meta = json.loads(text)
    if damage == "truncated":
        text = text[: len(text) // 2]
    else:
        meta["spec"]["seed"] += 1
        text = json.dumps({**meta, "fingerprint": "f" * 16})
    (tmp_path / "r.meta.json").write_text(text)
    with pytest.raises(ResultsFileError) as err:
        run_campaign(spec, out, backend="inline", progress=False)
    message = str(err.value)
    assert str(tmp_path / "r.meta.json") in message and "damaged" in message or "corrupted" in message, message
    assert "the saved runs are kept" in message and "qprr campaign run SPEC -o NEW.csv --limit 0" in message, message
    assert "another specification" not in message and "(--fresh)" not in message and "delete the line (file)" not in message


def test_results_of_a_genuinely_other_specification_are_refused_with_what_differs(reference, tmp_path):
    other = _other(reference, tmp_path, options={"duration": 5.0})
    with pytest.raises(InputError, match=r"holds results of another specification .*options\.duration \(5\.0 -> None\)") as err:
        run_campaign(reference[0], tmp_path / "b.csv", backend="inline", progress=False)
    assert not isinstance(err.value, ResultsFileError) and other.fingerprint in str(err.value)


@pytest.mark.parametrize("metric", ["rmse_x", "rmse_position", "x_cm_max", "saturation", "recovery_time", "t_end"])
def test_a_success_bound_no_run_can_meet_is_refused(reference, tmp_path, metric):
    with pytest.raises(InputError, match=rf"{metric} = -0.1: no run can meet it \({metric} is >= 0"):
        CampaignSpec.from_mapping({**reference[0].to_dict(), "success": {metric: -0.1}}, base_dir=reference[5])
    CampaignSpec.from_mapping({**reference[0].to_dict(), "success": {metric: 0.0}}, base_dir=reference[5])  # met by a 0


def test_a_success_bound_on_no_metric_is_refused(reference, tmp_path):
    spec = CampaignSpec.from_mapping({**reference[0].to_dict(), "success": {"seed": 3.0}}, base_dir=reference[5])
    with pytest.raises(UnknownNameError, match="metric of \\[success\\]"):  # a parameter is no success criterion
        run_campaign(spec, tmp_path / "s.csv", backend="inline", progress=False)


def test_quiet_still_says_that_an_incomplete_last_record_was_dropped(reference, tmp_path, capsys):
    from qprr.cli import main

    spec, data, table, rows, names, ref_dir = reference
    shutil.copy(ref_dir / "target.py", tmp_path / "target.py")
    (tmp_path / "s.json").write_text(json.dumps(spec.to_dict()))
    out = tmp_path / "q.csv"
    out.write_bytes(data[: data.index(b"\n", data.index(b"\n") + 1) + 1 + 30])  # the header, one record, 30 bytes of the next
    _copy_meta(ref_dir, out)
    assert main(["campaign", "run", str(tmp_path / "s.json"), "-o", str(out), "--backend", "inline", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert f"campaign faults: dropped an incomplete last record (30 bytes, a cut write) of {out}: its run is done again" in err
    _same(read_results(out).table, table)


def test_show_into_a_reader_that_stops_early_ends_without_a_traceback(reference, tmp_path):
    """``qprr campaign show SPEC | head -1``: more lines than a pipe holds, the reader gone after the first one."""
    spec, data, table, rows, names, ref_dir = reference
    shutil.copy(ref_dir / "target.py", tmp_path / "target.py")
    (tmp_path / "s.json").write_text(json.dumps({**spec.to_dict(), "samples": 4000}))
    proc = subprocess.Popen(
        [sys.executable, "-m", "qprr", "campaign", "show", str(tmp_path / "s.json"), "--first", "30000"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    first = proc.stdout.readline()
    proc.stdout.close()  # what head does after its line
    stderr = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0, stderr
    assert first.startswith(b"faults: callable") and stderr == "", stderr


def test_a_report_of_a_cut_campaign_counts_the_missing_runs(reference, tmp_path):
    """3 records saved and a fourth cut: "3 of 9 runs ... (6 missing ...)", the rates over the 9 runs (it said "3 runs",
    "100 %" of what was there)."""
    from qprr.campaign.report import campaign_report

    spec, data, table, rows, names, ref_dir = reference
    ends = [i + 1 for i, b in enumerate(data) if b == ord("\n")]
    out = tmp_path / "cut.csv"
    out.write_bytes(data[: ends[3] + 25])
    _copy_meta(ref_dir, out)
    head = campaign_report(out)[0].splitlines()[0]
    ok = int((table["status"][:3] == "ok").sum())
    assert (
        head.startswith("faults: 3 of 9 runs of target.py:target") and "(6 missing" in head and f"{ok} completed ({100 * ok / 9:.1f} % of 9)" in head
    ), head


# ---------------------------------------------------------------------------- full disk, read-only folder
def _tmpfs(path: Path, size: str, ro: bool = False) -> bool:
    path.mkdir()
    opts = f"size={size}" + (",ro" if ro else "")
    return subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(path)], capture_output=True).returncode == 0


def test_a_full_disk_stops_the_campaign_at_once_and_resume_completes_it(reference, tmp_path, monkeypatch):
    """A write that fails (ENOSPC, injected in the middle of the 4th record) ends the campaign with the file and the
    error; the worker is stopped and no run starts after it; once space returns the same command completes the table."""
    import qprr.campaign.store as store_mod

    spec, data, table, rows, names, ref_dir = reference
    out = tmp_path / "full-disk.csv"
    calls = {"n": 0}
    real = store_mod._write_all

    def failing(fd, chunk):
        calls["n"] += 1
        if calls["n"] == 5:  # header, three records, then the disk is full in the middle of the fourth
            os.write(fd, chunk[:17])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd, chunk)

    monkeypatch.setattr(store_mod, "_write_all", failing)
    monkeypatch.setenv("QPRR_TEST_LOG", str(tmp_path / "started.log"))
    monkeypatch.setenv("QPRR_TEST_DELAY", "0.5")
    with pytest.raises(ResultsWriteError, match=rf"cannot write campaign results '{out}': \[Errno 28\] No space left"):
        run_campaign(spec, out, backend="local", workers=1, progress=False)
    starts = (tmp_path / "started.log").read_text().splitlines()
    # the 4 runs that reached the store and at most the next one, which the worker took as it handed over the 4th:
    # no run is started after the failure (counted, not timed: the machine's load cannot move it)
    assert len(starts) <= 5
    assert len(read_results(out)) == 3  # what was saved is kept; the cut fourth record is not read
    monkeypatch.setattr(store_mod, "_write_all", real)  # space returns
    monkeypatch.setenv("QPRR_TEST_DELAY", "0")
    again = run_campaign(spec, out, backend="inline", progress=False)
    assert again.executed == spec.n_runs - 3 + 1 and again.remaining == 0  # the 3 saved (one an error, done again)
    _same(again.results.table, table)


@pytest.mark.parametrize("backend", [["--backend", "inline"], ["--backend", "local", "--workers", "2"]])
def test_a_full_tmpfs_gives_one_line_and_exit_3_then_resumes(reference, tmp_path, backend):
    """One line on stderr and nothing after it: with workers stopped midway too (their resource tracker used to warn
    of leaked semaphores after the runner's last line)."""
    spec, data, table, rows, names, ref_dir = reference
    mnt = tmp_path / "small"
    if not _tmpfs(mnt, "8k"):
        pytest.skip("cannot mount a tmpfs here (needs root): the injected write error above covers the same path")
    try:
        shutil.copy(ref_dir / "target.py", mnt.parent / "target.py")
        (tmp_path / "s.json").write_text(json.dumps(spec.to_dict()))
        out = mnt / "r.csv"
        with open(mnt / "filler", "wb") as fh:  # leave room for the metadata, the header and about two records
            try:
                fh.write(b"\0" * (8192 - 1024 - 4096 + 900))
            except OSError:
                pass
        proc = subprocess.run(
            [sys.executable, "-m", "qprr", "campaign", "run", str(tmp_path / "s.json"), "-o", str(out), *backend, "--quiet"],
            capture_output=True,
            text=True,
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT), "QPRR_TEST_DELAY": "0.3" if "local" in backend else "0"},
        )
        assert proc.returncode == 3, proc.stderr
        err = proc.stderr.strip().splitlines()
        assert len(err) == 1 and f"'{out}'" in err[0] and "No space left on device" in err[0], proc.stderr
        saved = len(read_results(out))
        assert 0 <= saved < spec.n_runs
        (mnt / "filler").unlink()  # space returns
        again = run_campaign(spec, out, backend="inline", progress=False)
        assert again.remaining == 0
        _same(again.results.table, table)
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True)


def test_a_read_only_folder_gives_one_line(reference, tmp_path, capsys):
    from qprr.cli import main

    spec = reference[0]
    mnt = tmp_path / "ro"
    if not _tmpfs(mnt, "64k", ro=True):
        pytest.skip("cannot mount a read-only tmpfs here (needs root)")
    try:
        (tmp_path / "s.json").write_text(json.dumps(spec.to_dict()))
        shutil.copy(reference[5] / "target.py", tmp_path / "target.py")
        assert main(["campaign", "run", str(tmp_path / "s.json"), "-o", str(mnt / "r.csv"), "--backend", "inline", "--quiet"]) == 3
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"'{mnt / 'r.lock'}'" in err[0] and "Read-only file system" in err[0]
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True)


# ---------------------------------------------------------------------------- the runner killed
def _children(pid: int) -> list[int]:
    out = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                stat = (p / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(p.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _start(tmp_path: Path, spec: CampaignSpec, out: Path, delay: float) -> subprocess.Popen:
    (tmp_path / "s.json").write_text(json.dumps(spec.to_dict()))
    return subprocess.Popen(
        [sys.executable, "-m", "qprr", "campaign", "run", str(tmp_path / "s.json"), "-o", str(out), "--backend", "local", "--workers", "2"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT), "QPRR_TEST_DELAY": str(delay)},
    )


def _rows_reached(out: Path, n: int) -> bool:
    """``out`` holds its header and at least ``n`` rows."""
    return out.exists() and out.read_bytes().count(b"\n") >= n + 1


def _wait_rows(out: Path, n: int, proc: subprocess.Popen, tries: int = 1200) -> None:
    """Until ``out`` has ``n`` rows (checked ``tries`` times, 0.05 s apart); the runner must stay alive meanwhile."""

    def reached() -> bool:
        assert proc.poll() is None, proc.communicate()
        return _rows_reached(out, n)

    assert poll(reached, tries), f"no {n} rows in {out} after {tries} checks"


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_killing_the_runner_leaves_no_worker_and_loses_no_saved_run(reference, tmp_path, sig):
    spec, data, table, rows, names, ref_dir = reference
    shutil.copy(ref_dir / "target.py", tmp_path / "target.py")
    out = tmp_path / "k.csv"
    proc = _start(tmp_path, spec, out, delay=0.6)
    _wait_rows(out, 2, proc)
    kids = _children(proc.pid)
    assert len(kids) >= 2  # the two pool workers (and the resource tracker)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=30)
    poll(lambda: not any(_alive(k) for k in kids), tries=100, pause=0.1)
    assert not [k for k in kids if _alive(k)], "processes outlived the runner"
    if sig != signal.SIGKILL:
        assert proc.returncode == 1, stderr
        assert f"stopped by {sig.name}" in stderr and "run the same command again to resume" in stderr
        assert "Traceback" not in stderr
    saved = read_results(out)
    assert 2 <= len(saved) < spec.n_runs
    again = run_campaign(spec, out, backend="inline", progress=False)
    assert again.skipped + again.executed >= spec.n_runs and again.remaining == 0
    _same(again.results.table, table)


def _flock_free(lock: Path) -> bool:
    import fcntl

    with lock.open("a") as fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return False
        fcntl.flock(fh, fcntl.LOCK_UN)
    return True


@pytest.mark.slow
def test_sigterm_to_the_whole_process_group_ends_the_campaign_cleanly_and_the_same_command_resumes(reference, tmp_path):
    """What ``timeout 20 qprr campaign run ...`` and a job scheduler's time limit send: SIGTERM to the runner and its
    workers at once.  The runner ends (the timeout is a safety limit, not a speed requirement) with exit code 1, its
    one-line message last on stderr, the lock released, every finished run saved; the same command then completes the
    table.  (It used to wait forever on a shared event that only live workers acknowledge.)"""
    spec, data, table, rows, names, ref_dir = reference
    shutil.copy(ref_dir / "target.py", tmp_path / "target.py")
    (tmp_path / "s.json").write_text(json.dumps(spec.to_dict()))
    out = tmp_path / "g.csv"
    command = [sys.executable, "-m", "qprr", "campaign", "run", str(tmp_path / "s.json"), "-o", str(out), "--workers", "2"]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "QPRR_TEST_DELAY": "0.6"}
    proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    try:
        _wait_rows(out, 2, proc)
        kids = _children(proc.pid)
        os.killpg(proc.pid, signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:  # the old runner: still waiting; end it so that the test reports instead of hanging
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 1, stderr
    last = stderr.strip().splitlines()[-1]
    assert last.startswith("campaign faults: stopped by SIGTERM after ") and last.endswith("run the same command again to resume"), stderr
    assert "Traceback" not in stderr and "Warning" not in stderr, stderr
    assert "stopped by SIGTERM" in stdout
    assert _flock_free(tmp_path / "g.lock")
    poll(lambda: not any(_alive(k) for k in kids), tries=100, pause=0.1)
    assert not [k for k in kids if _alive(k)], "processes outlived the runner"
    saved = read_results(out).table
    assert 2 <= len(saved) < spec.n_runs
    _same(saved, table[np.isin(table["run"], saved["run"])])
    again = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, env={**env, "QPRR_TEST_DELAY": "0"}, timeout=300)
    assert again.returncode == 0, again.stderr
    _same(read_results(out).table, table)


@pytest.mark.slow
def test_a_local_worker_killed_midway_is_retried_on_a_new_pool(reference, tmp_path, monkeypatch):
    """A pool worker killed once (out of memory, kill -9): the runs the broken pool had are lost, not rows, and
    retried on a new pool: the table is complete and equal to an uninterrupted run's."""
    spec, data, table, rows, names, ref_dir = reference
    monkeypatch.setenv("QPRR_TEST_DELAY", "0.4")
    out = tmp_path / "w.csv"

    from threading import Thread

    def kill():
        poll(lambda: _rows_reached(out, 2), tries=1200)
        workers = [p for p in _children(os.getpid()) if b"spawn_main" in Path(f"/proc/{p}/cmdline").read_bytes()]
        os.kill(workers[0], signal.SIGKILL)

    th = Thread(target=kill)
    th.start()
    done = run_campaign(spec, out, backend="local", workers=2, progress=False)
    th.join()
    assert (done.lost, done.remaining, done.executed) == (0, 0, spec.n_runs)
    _same(done.results.table, table)


@pytest.mark.slow
def test_a_run_that_always_kills_its_worker_ends_lost_not_saved(reference, tmp_path, monkeypatch, capsys):
    spec, data, table, rows, names, ref_dir = reference
    monkeypatch.setenv("QPRR_TEST_CRASH", "4")
    monkeypatch.setenv("QPRR_TEST_DELAY", "0.2")
    done = run_campaign(spec, tmp_path / "c.csv", backend="local", workers=2, progress=True)
    saved = done.results.table
    assert done.lost >= 1 and done.remaining == done.lost and 4 not in saved["run"].tolist()
    _same(saved, table[np.isin(table["run"], saved["run"])])  # no placeholder rows: what is saved is what the runs gave
    err = capsys.readouterr().err
    assert f"{done.lost} runs lost with their worker or scheduler (BrokenProcessPool" in err


def test_a_damaged_parquet_part_is_named(reference, tmp_path):
    pytest.importorskip("pyarrow", reason="pyarrow is not installed: pip install 'qprr[parquet]'")
    spec, data, table, rows, names, ref_dir = reference
    out = tmp_path / "p.parquet"
    done = run_campaign(spec, out, backend="inline", progress=False)
    _same(done.results.table, table)
    part = sorted(out.glob("part-*.parquet"))[0]
    part.write_bytes(part.read_bytes()[:-100])
    with pytest.raises(ResultsFileError, match="not a readable Parquet part") as err:
        read_results(out)
    assert str(part) in str(err.value)


# ---------------------------------------------------------------------------- Dask: a worker, the scheduler
@pytest.mark.slow
def test_a_dask_worker_killed_midway_loses_no_run(reference, tmp_path, monkeypatch):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed: pip install 'qprr[dask]'")
    import logging

    spec, data, table, rows, names, ref_dir = reference
    monkeypatch.setenv("QPRR_TEST_DELAY", "0.4")
    monkeypatch.setenv("QPRR_TEST_LOG", str(tmp_path / "started.log"))
    saved_at_kill = []
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None, silence_logs=logging.CRITICAL
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        pids = list(client.run(os.getpid).values())
        out = tmp_path / "d.csv"

        from threading import Thread

        def kill():
            poll(lambda: _rows_reached(out, 2), tries=1200)
            saved_at_kill.extend(read_results(out).table["run"].tolist())
            os.kill(pids[0], signal.SIGKILL)

        th = Thread(target=kill)
        th.start()
        done = run_campaign(spec, out, backend="dask", scheduler=cluster.scheduler_address, progress=False)
        th.join()
    assert done.lost == 0 and done.remaining == 0 and "dask (scheduler" in done.where
    _same(done.results.table, table)
    starts = [int(line.split()[0]) for line in (tmp_path / "started.log").read_text().splitlines()]
    assert len(saved_at_kill) >= 2 and all(starts.count(r) == 1 for r in saved_at_kill)  # saved runs are never recomputed


@pytest.mark.slow
def test_a_lost_scheduler_saves_no_placeholder_and_exits_non_zero(reference, tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed: pip install 'qprr[dask]'")
    spec, data, table, rows, names, ref_dir = reference
    shutil.copy(ref_dir / "target.py", tmp_path / "target.py")
    (tmp_path / "s.json").write_text(json.dumps(spec.to_dict()))
    cluster = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import logging, time, distributed\n"
            "c = distributed.LocalCluster(n_workers=1, threads_per_worker=1, host='127.0.0.1', "
            "dashboard_address=None, silence_logs=logging.CRITICAL)\nprint(c.scheduler_address, flush=True)\n"
            "time.sleep(600)",
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
        # the runs execute on this cluster's worker: the delay must reach it, or all of them can end before the kill
        env={**os.environ, "PYTHONPATH": str(ROOT), "QPRR_TEST_DELAY": "0.5"},
        start_new_session=True,
    )
    try:
        address = cluster.stdout.readline().strip()
        out = tmp_path / "l.csv"
        proc = subprocess.Popen(
            [sys.executable, "-m", "qprr", "campaign", "run", str(tmp_path / "s.json"), "-o", str(out), "--scheduler", address],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "PYTHONPATH": str(ROOT), "QPRR_TEST_DELAY": "0.5"},
        )
        _wait_rows(out, 2, proc)
        os.killpg(cluster.pid, signal.SIGKILL)  # the scheduler and its worker
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if cluster.poll() is None:
            os.killpg(cluster.pid, signal.SIGKILL)
        cluster.wait()
    assert proc.returncode == 1, stderr
    assert "lost (not saved)" in stdout and "on dask (scheduler" in stdout, stdout
    assert "Traceback" not in stderr and "runs lost with their worker or scheduler (" in stderr, stderr
    saved = read_results(out).table
    assert 2 <= len(saved) < spec.n_runs  # no placeholder rows: what is saved is what the runs gave
    _same(saved, table[np.isin(table["run"], saved["run"])])
    again = run_campaign(spec, out, backend="inline", progress=False)
    assert again.remaining == 0
    _same(again.results.table, table)


def test_kinds_cover_every_column(reference):
    spec, data, table, rows, names, _ = reference
    kinds = kinds_of(spec, names)
    assert list(kinds) == list(columns_of(spec, names))
    assert kinds["run"] == "run" and kinds["status"] == "status" and kinds["success"] == "flag" and kinds["rmse_x"] == "float"


# ---------------------------------------------------------------------------- the record format
def test_any_text_round_trips_through_a_record_on_one_line():
    """Property: whatever a reason holds (newlines, CR, NUL, quotes, commas, backslashes, any Unicode), its record is
    one line whose checksum matches, and parsing gives the text back exactly; a changed byte fails the checksum."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from qprr.campaign import store as store_mod

    record, store_parse = store_mod.record, store_mod._parse

    @settings(max_examples=150, deadline=None)
    @given(
        st.lists(st.text(alphabet=st.characters(codec="utf-8")), min_size=1, max_size=4),
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(-(2**63), 2**63 - 1),
    )
    def check(texts, x, n):
        line = record([n, x, *texts])
        assert line.endswith(b"\n") and line.count(b"\n") == 1 and b"\r" not in line
        fields, ok = store_parse(line[:-1])
        assert ok and fields == [str(n), repr(x), *texts]
        flipped = bytearray(line[:-1])
        flipped[0] ^= 0x01
        assert store_parse(bytes(flipped))[1] is False

    check()


def test_a_session_releases_only_what_it_opened(tmp_path):
    """The session a campaign and a design study share: a backend it made is closed (or aborted after an interruption,
    its pending futures cancelled); a caller's backend is left open."""
    from qprr.campaign.backends import InlineBackend
    from qprr.campaign.session import BackendChoice, Session

    class Recording(InlineBackend):
        def __init__(self) -> None:
            self.calls = []

        def close(self) -> None:
            self.calls.append("close")

        def abort(self, futures=()) -> None:
            self.calls.append("abort")
            self.cancel(futures)

    class Future:
        cancelled = False

        def cancel(self) -> None:
            self.cancelled = True

    meta = {"fingerprint": "f"}
    theirs = Recording()
    s = Session(tmp_path / "a.csv", ("run", "x"), meta, BackendChoice(theirs))
    assert s.be is None and s.backend() is theirs and s.backend() is theirs
    s.stop(clean=False, futures=[Future()])
    s.close()
    assert theirs.calls == []  # the caller's: neither closed nor aborted
    for clean, expected in ((True, ["close"]), (False, ["abort"])):
        s = Session(tmp_path / "a.csv", ("run", "x"), meta, BackendChoice("inline"), fresh=True)
        s.progress("t", 1, 0, quiet=True, stream=None, unit="run")
        s.be = Recording()  # as if opened by backend()
        futures = [Future(), Future()]
        s.stop(clean=clean, futures=futures)
        s.close()
        assert s.be.calls == expected and all(f.cancelled for f in futures) == (not clean)
    with pytest.raises(UnknownNameError, match="campaign backend.*'lokal'"):
        Session(tmp_path / "b.csv", ("run", "x"), meta, BackendChoice("lokal"))
    with pytest.raises(InputError, match="backend must be one of .* or a Backend, got object"):
        Session(tmp_path / "b.csv", ("run", "x"), meta, BackendChoice(object()))
