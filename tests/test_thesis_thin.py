"""The thesis's Chapter 6 scenarios are the generic missions of qprr.scenarios.missions called with the thesis's settings.

Each test runs a thesis scenario (registered by the plug-in) and the generic scenario with the thesis's
gains, mission (as data), disturbance amplitudes or pulses, and checks the logs agree to 1e-12; runs are
2-3 s at 1 kHz.  Each also checks the physics the settings stand for (the disturbance the plant felt).
"""

from __future__ import annotations

import numpy as np
import pytest

from qprr.control import PayloadIDC
from qprr.scenarios import SCENARIOS, missions
from qprr.sim import SimConfig
from qprr.thesis import gains, load_qprr
from qprr.thesis.missions import STATIC_MISSION, static_mission
from qprr.thesis.realistic import TIME_CONSTANT, realistic
from qprr.thesis.robot import params_of
from qprr.thesis.scenarios import NOISE_AMPLITUDE, PULSES
from qprr.trajectory import Hold

TOL = 1e-12
COMMON = {"dt": SimConfig.dt, "integrator": "midpoint", "seed": 0, "law": "septic"}


@pytest.fixture(scope="module")
def qprr():
    return load_qprr()


def same_run(a, b) -> None:
    """Both logs have the same ticks and agree to TOL in xi, u, the applied thrusts and the disturbance felt."""
    assert a.xi.shape == b.xi.shape
    np.testing.assert_array_equal(a.t, b.t)
    for field in ("xi", "xi_d", "u", "f", "u_ext"):
        assert np.max(np.abs(getattr(a, field) - getattr(b, field))) <= TOL, field


@pytest.mark.parametrize(("thesis", "controller", "table"), [("static-idc", "idc", "q-prr:idc"), ("static-dsid", "dsid", "q-prr:desired-state")])
def test_static_mission_is_the_generic_mission_with_thesis_gains(qprr, thesis, controller, table):
    """static-idc / static-dsid = the registered generic ``mission`` given Sec. 6.3.1.4 as data and the thesis's gain table."""
    ours = SCENARIOS[thesis].run(platform=qprr, duration=3.0)
    mine = SCENARIOS["mission"].run(platform=qprr, controller=controller, gains=table, mission=STATIC_MISSION, duration=3.0)
    same_run(ours, mine)
    # the climb of the static mission: z follows the (6.16) reference to 10 m within centimetres at 3 s
    assert mine.xi_d[-1, 2] > 5.0 and abs(mine.xi[-1, 2] - mine.xi_d[-1, 2]) < 0.05


def test_noise_is_hover_noise_with_the_thesis_amplitudes(qprr):
    """noise = generic ``hover-noise`` along the static mission with the amplitudes NOISE_AMPLITUDE (6.27)."""
    ours = SCENARIOS["noise"].run(platform=qprr, duration=2.0)
    settings = missions.MissionSettings(trajectory=static_mission(), name="noise")
    mine = missions.noise(qprr, "idc", False, settings, amplitude=NOISE_AMPLITUDE, gains=gains.idc(), duration=2.0, **COMMON)
    same_run(ours, mine)
    # uniform white noise in [-a, a]: every sample inside, the extremes near +-a, the mean near 0
    a = np.array(NOISE_AMPLITUDE)
    assert np.all(np.abs(mine.u_ext) <= a + 1e-15)
    assert np.all(mine.u_ext.max(axis=0) > 0.95 * a) and np.all(mine.u_ext.min(axis=0) < -0.95 * a)
    assert np.all(np.abs(mine.u_ext.mean(axis=0)) < 0.1 * a)


def test_pulses_are_hover_pulses_with_the_thesis_train(qprr):
    """pulses = generic ``hover-pulses`` along the static mission with the train PULSES (6.28): 5 N on z for 2-2.5 s."""
    ours = SCENARIOS["pulses"].run(platform=qprr, duration=3.0)
    settings = missions.MissionSettings(trajectory=static_mission(), name="pulses")
    mine = missions.pulses(qprr, "idc", False, settings, train=PULSES, gains=gains.idc(), duration=3.0, **COMMON)
    same_run(ours, mine)
    on = (mine.t >= 2.0 + 1e-9) & (mine.t < 2.5 - 1e-9)
    np.testing.assert_array_equal(mine.u_ext[on], np.tile(PULSES[0].gamma, (on.sum(), 1)))
    assert np.all(mine.u_ext[(mine.t < 2.0 - 1e-9) | (mine.t > 2.5 + 1e-9)] == 0.0)


def test_payload_drop_is_the_generic_mission_with_payload_events(qprr):
    """payload-drop (hover) = the generic ``mission`` with the payload events as data and the thesis's payload IDC."""
    ours = SCENARIOS["payload-drop"].run(platform=qprr, mission="hover", duration=2.0, release_time=1.0)
    arm = (-0.04, 0.3, 0.5)
    ctrl = PayloadIDC(qprr, gains.payload_idc(), payload="estimate")
    settings = missions.MissionSettings(trajectory=Hold((0.0, 0.0, 1.0, 0.0, 0.0, 0.0, *arm)), controller=ctrl, name="payload-drop")
    data = {"payload": [{"time": 0.0, "mass": 0.1}, {"time": 1.0, "mass": 0.0}]}
    mine = missions.mission(qprr, "payload-idc", False, settings, mission=data, duration=2.0, **COMMON)
    same_run(ours, mine)
    # the estimator finds the carried 0.1 kg before the release (within 10 %)
    m_hat = np.asarray(ctrl.mass_log)
    before = (mine.t > 0.5) & (mine.t < 1.0)
    assert np.all(np.abs(m_hat[before] - 0.1) < 0.01)


def test_realistic_is_motor_lag_with_the_qprr_rotor_stage(qprr):
    """realistic (static mission) = generic ``motor-lag`` with the Q-PRR's thrust factor and 5 ms lag, the static mission as
    the reference and the drag in wind and joint friction of qprr.thesis.realistic as the disturbance."""
    ours = SCENARIOS["realistic"].run(platform=qprr, duration=1.5)
    env = realistic(qprr)
    settings = missions.MissionSettings(trajectory=static_mission(), disturbance=env.disturbance, name="realistic")
    b = params_of(qprr).thrust_factor
    mine = missions.motor_lag(qprr, "idc", False, settings, tau=TIME_CONSTANT, thrust_factor=b, gains=gains.idc(), duration=1.5, **COMMON)
    same_run(ours, mine)
    # the actuator stage: applied thrusts are b w^2 of the lagged rotor speeds, which differ from the commanded ones
    w = mine.series["rotor_speed"]
    np.testing.assert_allclose(mine.f, b * w**2, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(mine.f - mine.series["thrust_command"])) > 1e-6
