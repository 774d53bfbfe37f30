"""The ULog files qprr writes from simulated flights (qprr.flightlog.synth), read back by pyulog and by FlightLog."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")

from pyulog import ULog

import qprr
from qprr.flightlog.synth import SynthOptions, synth_log
from qprr.flightlog.ulog import FlightLog
from qprr.flightstack.px4 import geometry_from_platform

OPTIONS = SynthOptions(duration_s=6.0, accel_noise=0.05, gyro_noise=0.01, arm_sweep=0.3, steps=0.3, seed=7)


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    platform = qprr.load("q-prr")
    return platform, synth_log(platform, tmp_path_factory.mktemp("synth") / "qprr.ulg", OPTIONS)


def test_pyulog_reads_the_topics_and_the_parameters(flight):
    platform, s = flight
    ulog = ULog(str(s.path))
    names = {d.name for d in ulog.data_list}
    assert names >= {"vehicle_status", "sensor_combined", "actuator_motors", "vehicle_attitude", "vehicle_local_position"}
    expected = geometry_from_platform(platform).parameters()
    for key, value in expected.items():
        assert np.float32(ulog.initial_parameters[key]) == np.float32(value), key  # float32-exact, as PX4 stores them
    assert ulog.initial_parameters["THR_MDL_FAC"] == 0.0


def test_flightlog_rates_and_imu_noise_at_rest(flight):
    platform, s = flight
    log = FlightLog.read(s.path)
    rates = {t.name: t.rate_hz for t in log.topics()}
    assert rates["actuator_motors"] == pytest.approx(OPTIONS.command_rate_hz, rel=0.02)
    assert rates["sensor_combined"] == pytest.approx(OPTIONS.imu_rate_hz, rel=0.02)
    imu = log.series("sensor_combined", [f"accelerometer_m_s2[{i}]" for i in range(3)] + [f"gyro_rad[{i}]" for i in range(3)])
    rest = imu.values[imu.t_s < 1.9]  # two seconds armed on the ground before the flight
    n = rest.shape[0]
    assert n > 400
    # the mean: 1 g up (FRD: -g along z, the plant's g), the std: the noise given; bounds at 5 standard errors
    np.testing.assert_allclose(rest[:, 0:3].mean(axis=0), [0.0, 0.0, -platform.g], atol=5 * OPTIONS.accel_noise / np.sqrt(n))
    np.testing.assert_allclose(rest[:, 3:6].mean(axis=0), 0.0, atol=5 * OPTIONS.gyro_noise / np.sqrt(n))
    rel = 5 / np.sqrt(2 * n)  # the standard error of a sample std, relative
    np.testing.assert_allclose(rest[:, 0:3].std(axis=0, ddof=1), OPTIONS.accel_noise, rtol=rel)
    np.testing.assert_allclose(rest[:, 3:6].std(axis=0, ddof=1), OPTIONS.gyro_noise, rtol=rel)


def test_the_truth_beside_the_file(flight):
    platform, s = flight
    truth = s.truth
    assert truth["ct"] == platform.rotors[0].f_max and truth["mass"] == pytest.approx(platform.total_mass)
    assert truth["motor_time_constant"] == OPTIONS.motor_time_constant and truth["gravity"] == platform.g
    f_max_z = sum(r.f_max * r.axis_body[2] for r in platform.rotors)
    assert truth["hover_command"] == pytest.approx(platform.total_mass * platform.g / f_max_z)
    assert {"base", "rigid", "parameters"} <= set(truth)
    assert truth["parameters"]["base.m"] == pytest.approx(platform.model.inertias[1].mass)
    assert s.joints_csv is not None and s.joints_csv.exists()
