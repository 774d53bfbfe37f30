"""Issue 31 item 4: PX4's mix rebuilt from the log's CA_* reproduces actuator_motors to float32 round-off, and the
IMU predicted through a platform from the motor commands."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")

from qprr import cli
from qprr.flightlog.phases import find_phases
from qprr.flightlog.replay import replay
from qprr.flightlog.ulog import FlightLog

from .flightlog_common import EVENTS, shared_log


@pytest.fixture(scope="module")
def result():
    log = FlightLog.read(shared_log(EVENTS))
    return replay(log, find_phases(log))


def test_the_mix_reproduces_actuator_motors_to_float32_round_off(result):
    mix = result.mix
    assert len(mix.t_s) == 313 and mix.unsaturated.sum() > 100
    assert mix.max_residual <= 1e-5
    # the saturated samples (on the ground, motors at idle) are where PX4's desaturation acts: not compared
    assert np.max(np.abs(mix.predicted - mix.logged)) > 1e-3


def test_the_imu_is_predicted_from_the_motor_commands(result):
    force_rms, alpha_rms = result.imu.rms()
    assert len(result.imu.t_s) > 50
    # the mass comes from the hover balance, so the vertical specific force follows the thrust's variations
    assert force_rms[2] < 0.2 and np.all(force_rms[:2] < 0.2)
    z = result.imu.force_measured[:, 2]
    assert np.ptp(z) > 2.0  # the climb and the descent excite it by more than ten times the error
    assert np.all(alpha_rms < 2.0)


def test_the_cli_prints_the_max_residual(capsys, tmp_path):
    code = cli.main(["log", "replay", str(shared_log(EVENTS)), "--plot", str(tmp_path / "replay.png")])
    out = capsys.readouterr().out
    assert code == 0
    line = next(ln for ln in out.splitlines() if ln.startswith("max residual "))
    assert float(line.split()[-1]) <= 1e-5
    assert "m/s^2" in out and "rad/s^2" in out and (tmp_path / "replay.png").is_file()
