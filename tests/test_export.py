"""A run as a long table (qprr.sim.export, issue 35 item 7): CSV and Parquet that hold exactly the logged arrays."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from qprr.cli import main
from qprr.errors import InputError
from qprr.sim import SimResult
from qprr.sim.export import long_table, save_table


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    path = tmp_path_factory.mktemp("run") / "run.npz"
    assert main(["simulate", "static-idc", "--duration", "0.2", "-q", "--save", str(path)]) == 0
    return SimResult.load(path)


def _series(rows, name):
    return np.array([float(r["value"]) for r in rows if r["series"] == name])


def test_csv_holds_every_logged_array(run, tmp_path):
    path = save_table(run, tmp_path / "run.csv")
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == long_table(run).time.shape[0]
    np.testing.assert_array_equal(_series(rows, "xi.z"), run.xi[:, 2])  # repr round trip: exact
    np.testing.assert_array_equal(_series(rows, "xi_d.theta2"), run.xi_d[:, 7])
    np.testing.assert_array_equal(_series(rows, "f.3"), run.f[:, 2])
    np.testing.assert_array_equal(_series(rows, "arm_effort.r0"), run.arm_effort[:, 0])
    units = {r["series"]: r["unit"] for r in rows}
    assert units["xi.z"] == "m" and units["xi.phi"] == "rad" and units["xi_dot.r0"] == "m/s"
    assert units["u.theta2"] == "N m" and units["u.r0"] == "N" and units["f.1"] == "N"
    times = np.array([float(r["time"]) for r in rows if r["series"] == "xi.x"])
    np.testing.assert_array_equal(times, run.t)


def test_parquet_matches_the_table(run, tmp_path):
    pq = pytest.importorskip("pyarrow.parquet", reason='pyarrow not installed: pip install "qprr[parquet]"')
    table = pq.read_table(save_table(run, tmp_path / "run.parquet")).to_pydict()
    expected = long_table(run)
    np.testing.assert_array_equal(table["value"], expected.value)
    assert table["series"] == expected.series.tolist() and table["unit"] == expected.unit.tolist()


def test_cli_saves_a_table(tmp_path, capsys):
    path = tmp_path / "run.csv"
    assert main(["simulate", "static-idc", "--duration", "0.05", "-q", "--save", str(path)]) == 0
    assert f"saved {path}" in capsys.readouterr().out
    assert path.read_text().splitlines()[0] == "time,series,value,unit"


def test_bad_paths_are_refused(run, tmp_path):
    with pytest.raises(InputError, match=r"table files end in \.csv or \.parquet"):
        save_table(run, tmp_path / "run.xlsx")
    with pytest.raises(InputError, match="does not exist"):
        save_table(run, tmp_path / "missing" / "run.csv")
    with pytest.raises(InputError, match="must be a qprr.sim.SimResult"):
        long_table({"xi": []})
