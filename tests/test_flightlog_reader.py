"""Issue 31 item 3: the one ULog reader (series, timestamps, motor commands from either vintage, missing topics) and
the phases found from the data."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")

from qprr.errors import InputError, MissingTopicError, NoFlightError
from qprr.flightlog.phases import FlightStatus, find_phases
from qprr.flightlog.ulog import FlightLog, motor_commands

from .flightlog_common import EVENTS, TAGGED, rewritten, shared_log


@pytest.fixture(scope="module")
def events() -> FlightLog:
    return FlightLog.read(shared_log(EVENTS))


@pytest.fixture(scope="module")
def tagged() -> FlightLog:
    return FlightLog.read(shared_log(TAGGED))


def test_the_vehicle_and_the_parameters(events, tagged):
    assert events.info["sys_name"] == "PX4" and events.info["ver_hw"] == "PX4_SITL"
    assert events.airframe == 10017 and tagged.airframe == 10016
    assert events.parameters["CA_ROTOR_COUNT"] == 4 and isinstance(events.parameters["CA_ROTOR_COUNT"], int)
    assert events.parameters["CA_ROTOR0_CT"] == pytest.approx(6.5)
    assert 31.0 < events.duration_s < 31.2 and 10.5 < tagged.duration_s < 11.0


def test_series_times_are_seconds_since_the_start_without_the_zero_timestamps(events):
    # manual_control_setpoint holds a single sample with timestamp 0: nothing is left, and no uint64 wrap-around
    assert len(events.series("manual_control_setpoint", "roll")) == 0
    acc = events.vector("sensor_combined", "accelerometer_m_s2", 3)
    assert acc.values.shape == (len(acc.t_s), 3) and np.all(np.diff(acc.t_s) > 0)
    assert -1.0 < acc.t_s[0] < 0.1 and acc.t_s[-1] <= events.duration_s + 1e-9
    np.testing.assert_array_equal(acc.t_us, np.round(acc.t_s * 1e6).astype(np.int64))
    np.testing.assert_array_equal(acc.column("accelerometer_m_s2[2]"), acc.values[:, 2])
    # at rest before the arming the accelerometer reads minus gravity along FRD z
    still = acc.t_s < 14.0
    assert np.mean(acc.values[still, 2]) == pytest.approx(-9.81, abs=0.05)
    rates = {(t.name, t.multi_id): t.rate_hz for t in events.topics()}
    assert rates[("sensor_combined", 0)] == pytest.approx(250, rel=0.02)
    assert rates[("vehicle_torque_setpoint", 0)] == pytest.approx(50, rel=0.02)
    assert rates[("actuator_motors", 0)] == pytest.approx(10, rel=0.02)
    assert events.has("sensor_baro", 1) and not events.has("sensor_baro", 2)


def test_bad_files_are_named(tmp_path):
    with pytest.raises(InputError, match="nope.ulg"):
        FlightLog.read(tmp_path / "nope.ulg")
    text = tmp_path / "text.ulg"
    text.write_text("not a log")
    with pytest.raises(InputError, match="text.ulg.*not a ULog"):
        FlightLog.read(text)


def test_a_missing_topic_names_itself_what_needs_it_and_the_logging_profile(tagged):
    with pytest.raises(MissingTopicError, match=r"vehicle_torque_setpoint.*the replay needs it.*SDLOG_PROFILE bit 0"):
        tagged.series("vehicle_torque_setpoint", "xyz[0]", needed_for="the replay")
    with pytest.raises(MissingTopicError, match="no field 'nope'"):
        tagged.series("sensor_combined", "nope")


def test_pwm_outputs_give_the_same_commands_as_actuator_motors(events, tmp_path):
    """Without actuator_motors the reader normalises actuator_outputs (PWM, default range 1000-2000 us here): the same
    commands to PWM's 1 us resolution (1e-3 of the range)."""
    direct = motor_commands(events)
    assert direct.values.shape[1] == 4 and "CA_ROTOR_COUNT" in direct.source
    older = FlightLog.read(rewritten(EVENTS, tmp_path / "no_motors.ulg", drop=("actuator_motors",)))
    pwm = motor_commands(older)
    assert "actuator_outputs" in pwm.source and "1000-2000" in pwm.source
    np.testing.assert_array_equal(pwm.t_us, direct.t_us)
    running = np.all(direct.values > 0.01, axis=1)
    assert running.sum() > 50
    np.testing.assert_allclose(pwm.values[running], direct.values[running], atol=1.01e-3)


def test_an_older_log_reads_its_pwm_with_its_own_range(tagged):
    m = motor_commands(tagged)
    assert "PWM_MAIN_MIN/MAX" in m.source and "1075-1950" in m.source and m.values.shape[1] == 6
    assert np.all(np.isnan(m.values))  # never armed: every motor at the disarmed value


def test_phases_of_the_flight_agree_with_the_motor_commands_and_the_imu(events):
    ph = find_phases(events)
    assert ph.status is FlightStatus.FLEW and len(ph.armed) == 1 and len(ph.airborne) == 1
    arm, disarm = ph.armed[0]
    assert arm == pytest.approx(14.94, abs=0.01) and disarm == pytest.approx(30.14, abs=0.01)
    # the motor commands (10 Hz, a topic the phases did not use) reach the hover level within a sample of the lift-off
    m = motor_commands(events)
    mean = np.nanmean(m.values, axis=1)
    carrying = np.flatnonzero((m.t_s > arm) & (mean >= 0.97 * ph.hover_command))
    assert abs(m.t_s[carrying[0]] - ph.takeoff_s) < 0.2
    assert abs(m.t_s[carrying[-1]] - ph.landing_s) < 0.3
    # the hover command carries the weight: near PX4's hover-thrust estimate
    hte = events.series("hover_thrust_estimate", "hover_thrust")
    assert ph.hover_command == pytest.approx(np.nanmedian(hte.values), abs=0.02)
    # the IMU feels the lift-off within half a second after the thrust reaches the weight
    assert 0.0 <= ph.specific_force_liftoff_s - ph.takeoff_s < 0.5
    # PX4's land detector declares the take-off during the spool-up and the landing well after the touchdown
    assert ph.land_detector_takeoff_lag_s < -1.0
    assert ph.land_detector_landing_lag_s > 1.0


def test_a_log_that_never_armed(tagged):
    ph = find_phases(tagged)
    assert ph.status is FlightStatus.NEVER_ARMED and ph.armed == () and ph.takeoff_s is None
    with pytest.raises(NoFlightError, match="never armed"):
        ph.require_flight("the replay")


def test_a_log_armed_but_never_airborne(tmp_path):
    log = FlightLog.read(rewritten(shared_log(EVENTS), tmp_path / "ground.ulg", until_s=17.0))
    ph = find_phases(log)
    assert ph.status is FlightStatus.ARMED_NOT_AIRBORNE and len(ph.armed) == 1 and ph.airborne == ()
    with pytest.raises(NoFlightError, match="never left the ground"):
        ph.require_flight("the replay")
