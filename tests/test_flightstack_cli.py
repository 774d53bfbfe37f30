"""``qprr export px4 | ardupilot`` and ``qprr import px4`` (qprr.flightstack.cli): the round trip through the files,
the .ulg hook, and one-line errors with exit code 2 before anything runs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr import cli
from qprr.flightstack import px4
from qprr.rotors import read_rotor_file, rotors_from_mapping

LOG = Path(__file__).resolve().parents[2] / "shared" / "data" / "flightlogs" / "sample_px4_events.ulg"


def _run(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


def test_export_import_round_trip(tmp_path, capsys):
    params = tmp_path / "hex.params"
    code, out, err = _run(["export", "px4", "--platform", "HEX-RRR", "--pose", "0.3,0.5,-0.2", "-o", str(params), "--resolution", "9"], capsys)
    assert code == 0, err
    assert "CA_AIRFRAME 0, 6 rotors" in out and "worst wrench error" in out and "best export pose" in out
    text = params.read_text()
    assert "# platform HEX-RRR" in text and "arm pose [0.3, 0.5, -0.2]" in text
    toml = tmp_path / "hex.toml"
    code, out, err = _run(["import", "px4", str(params), "-o", str(toml), "--mass", "2.8"], capsys)
    assert code == 0, err
    assert "hover check passed" in out
    rotors = rotors_from_mapping(read_rotor_file(toml))
    again = px4.geometry_from_rotors(rotors).parameters()
    original = px4.read_params(params)
    assert again.keys() == original.keys()
    for k, v in original.items():
        assert np.float32(again[k]).tobytes() == np.float32(v).tobytes(), k
    # the imported rotors fly the platform: same positions relative to the CoG at the pose
    c = px4.com_body_at(qprr.build("HEX-RRR"), [0.3, 0.5, -0.2])
    np.testing.assert_allclose([r.position_body for r in rotors], [np.subtract(r.position_body, c) for r in qprr.build("HEX-RRR").rotors], atol=1e-7)


def test_import_without_mass_says_hover_skipped(tmp_path, capsys):
    params = px4.write_params(px4.geometry_from_platform(qprr.load("q-prr")), tmp_path / "q.params")
    code, out, err = _run(["import", "px4", str(params), "-o", str(tmp_path / "q.toml")], capsys)
    assert code == 0, err
    assert "hover check skipped: no --mass given" in out


def test_import_refuses_a_vehicle_too_heavy(tmp_path, capsys):
    params = px4.write_params(px4.geometry_from_platform(qprr.load("q-prr")), tmp_path / "q.params")
    code, out, err = _run(["import", "px4", str(params), "-o", str(tmp_path / "q.toml"), "--mass", "50"], capsys)
    assert code == 2 and "cannot hover" in err and len(err.strip().splitlines()) == 1


def test_import_ulog_parameters(tmp_path, capsys):
    pyulog = pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")
    if not LOG.exists():
        pytest.skip("the SITL log is not in ../shared/data/flightlogs")
    toml = tmp_path / "iris.toml"
    code, out, err = _run(["import", "px4", str(LOG), "-o", str(toml), "--mass", "1.5"], capsys)
    assert code == 0, err
    rotors = rotors_from_mapping(read_rotor_file(toml))
    params = pyulog.ULog(str(LOG), message_name_filter_list=[]).initial_parameters
    for k, v in px4.geometry_from_rotors(rotors).parameters().items():
        assert params[k] == v, k


def test_export_ardupilot(tmp_path, capsys):
    lua = tmp_path / "q.lua"
    code, out, err = _run(["export", "ardupilot", "-o", str(lua)], capsys)
    assert code == 0, err
    assert "MotorsMatrix frame" in out
    assert "MotorsMatrix:add_motor_raw(0," in lua.read_text()
    code, out, err = _run(["export", "ardupilot", "--dynamic", "--joints", "r0", "-o", str(lua)], capsys)
    assert code == 0, err
    assert "Motors_dynamic:load_factors" in lua.read_text()


def test_export_with_mixer_map(tmp_path, capsys):
    png = tmp_path / "map.png"
    code, out, err = _run(["export", "px4", "-o", str(tmp_path / "q.params"), "--mixer-map", str(png), "--resolution", "9"], capsys)
    assert code == 0, err
    assert png.stat().st_size > 10_000 and f"saved {png}" in out


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["export", "px4", "-o", "x.txt"], "--output"),
        (["export", "px4", "-o", "/no/such/folder/x.params"], "does not exist"),
        (["export", "px4", "-o", "OUT.params", "--pose", "0,0"], "--pose"),
        (["export", "px4", "-o", "OUT.params", "--pose", "0,9,0"], "--pose"),
        (["export", "px4", "-o", "OUT.params", "--mixer-map", "m.gif"], "--mixer-map"),
        (["export", "px4", "-o", "OUT.params", "--pose", "a,b"], "--pose"),
        (["export", "px4", "-o", "OUT.params", "--joints", "elbow"], "elbow"),
        (["export", "ardupilot", "-o", "x.params"], "--output"),
        (["import", "px4", "nothing.params", "-o", "x.toml"], "does not exist"),
        (["import", "px4", "file.csv", "-o", "x.toml"], ".params"),
        (["import", "px4", "PARAMS", "-o", "x.json"], "--output"),
        (["import", "px4", "PARAMS", "-o", "x.toml", "--mass", "-1"], "--mass"),
    ],
)
def test_bad_arguments_one_line_exit_2(tmp_path, capsys, argv, needle):
    params = tmp_path / "p.params"
    params.write_text("1\t1\tCA_ROTOR_COUNT\t4\t6\n")
    argv = [str(tmp_path / "out.params") if a == "OUT.params" else str(params) if a == "PARAMS" else a for a in argv]
    code, out, err = _run(argv, capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, (argv, err)
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in err, (argv, err)


def test_import_names_the_missing_parameter(tmp_path, capsys):
    params = tmp_path / "p.params"
    params.write_text("1\t1\tCA_AIRFRAME\t0\t6\n1\t1\tCA_ROTOR_COUNT\t4\t6\n")
    code, out, err = _run(["import", "px4", str(params), "-o", str(tmp_path / "x.toml")], capsys)
    assert code == 2 and "CA_ROTOR0_PX is missing" in err
