"""Issue 31 item 3: ``qprr log show`` (the vehicle, phases, topics, parameters; the summary figure) and the one-line
messages and exit codes of the log commands."""

from __future__ import annotations

import pytest

pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")

from qprr import cli
from qprr.flightlog.phases import find_phases
from qprr.flightlog.plots import euler_zyx_deg, summary_figure
from qprr.flightlog.show import software_version
from qprr.flightlog.ulog import FlightLog

from .flightlog_common import EVENTS, TAGGED, rewritten, shared_log


def _run(argv, capsys):
    try:
        code = cli.main(argv)
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, [ln for ln in out.err.splitlines() if ln.strip()]


def test_show_prints_the_vehicle_the_phases_and_the_rates(capsys, tmp_path):
    code, out, err = _run(["log", "show", str(shared_log(EVENTS)), "--plot", str(tmp_path / "log.png")], capsys)
    assert code == 0 and err == []
    assert "PX4 on PX4_SITL, software v1.15.0 dev" in out and "airframe 10017" in out
    assert "status: flew" in out and "take-off 18." in out and "PX4 land detector landing at 28.13 s" in out
    assert "CA_ROTOR_COUNT 4" in out and "MPC_THR_HOVER 0.5" in out
    assert "sensor_combined 250 Hz" in out and "telemetry_status[0,1,2,3]" in out
    assert (tmp_path / "log.png").stat().st_size > 10_000


def test_a_log_without_a_flight_is_shown_normally(capsys, tmp_path):
    code, out, err = _run(["log", "show", str(shared_log(TAGGED))], capsys)
    assert code == 0 and err == [] and "status: never armed" in out and "v1.13.0" in out
    ground = rewritten(EVENTS, tmp_path / "ground.ulg", until_s=17.0)
    code, out, err = _run(["log", "show", str(ground)], capsys)
    assert code == 0 and "status: armed but never airborne" in out


def test_commands_that_need_a_flight_say_so_in_one_line(capsys, tmp_path):
    code, _, err = _run(["log", "replay", str(shared_log(TAGGED))], capsys)
    assert code == 1 and len(err) == 1 and "needs a flight: this log never armed" in err[0]
    ground = rewritten(EVENTS, tmp_path / "ground.ulg", until_s=17.0)
    code, _, err = _run(["log", "replay", str(ground)], capsys)
    assert code == 1 and len(err) == 1 and "never left the ground" in err[0]


def test_a_missing_topic_is_one_line_with_the_profile(capsys, tmp_path):
    stripped = rewritten(shared_log(EVENTS), tmp_path / "no_torque.ulg", drop=("vehicle_torque_setpoint",))
    code, _, err = _run(["log", "replay", str(stripped)], capsys)
    assert code == 1 and len(err) == 1
    assert "'vehicle_torque_setpoint' is not in the log" in err[0] and "SDLOG_PROFILE" in err[0]


def test_bad_arguments_exit_2_in_one_line(capsys, tmp_path):
    for argv in (
        ["log", "show", str(tmp_path / "missing.ulg")],
        ["log", "show", str(shared_log(EVENTS)), "--plot", str(tmp_path / "fig.jpg")],
        ["log", "replay", str(EVENTS), "--platform", "no-such-robot"],
        ["log", "show"],
    ):
        code, _, err = _run(argv, capsys)
        assert code == 2 and len(err) == 1 and "error" in err[0], (argv, err)


def test_the_figure_notes_missing_topics_on_its_axes(tmp_path):
    log = FlightLog.read(rewritten(shared_log(EVENTS), tmp_path / "no_battery.ulg", drop=("battery_status",)))
    fig = summary_figure(log, find_phases(log))
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert "not in this log: battery_status" in texts
    assert [ax.get_ylabel() for ax in fig.axes] == ["position [m]", "angle [deg]", "command [0-1]", "voltage [V]"]


def test_attitude_angles_and_the_version_word():
    import numpy as np

    half = np.radians(30.0) / 2  # a 30 degree roll about FRD x
    np.testing.assert_allclose(euler_zyx_deg(np.array([[np.cos(half), np.sin(half), 0.0, 0.0]])), [[30.0, 0.0, 0.0]], atol=1e-12)
    assert software_version({"ver_sw_release": str(0x010D03FF), "ver_sw": "abcdef0123"}) == "v1.13.3 release (abcdef01)"
