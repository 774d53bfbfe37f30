"""The building blocks of qprr.scenarios.missions a plug-in instantiates (MissionSettings, noise amplitudes, a pulse train,
phases as data, gains objects), on a platform other than the Q-PRR: what they do and what they refuse."""

from __future__ import annotations

import numpy as np
import pytest

import qprr
from qprr.control import IDCGains
from qprr.errors import InputError
from qprr.scenarios import SCENARIOS, missions
from qprr.sim import Pulse, WhiteNoise
from qprr.trajectory import Hold, Phase


@pytest.fixture(scope="module")
def borinot():
    return qprr.load("borinot_flying_arm_2")


def options(name: str, **changes) -> dict:
    """The registered defaults of scenario ``name`` with ``changes``."""
    return {**{k: o.default for k, o in SCENARIOS[name].options.items()}, **changes}


@pytest.mark.parametrize(("field", "value"), [("trajectory", object()), ("controller", "idc"), ("plant", "borinot_flying_arm_2"), ("name", 3)])
def test_settings_refuse_wrong_types(field, value):
    with pytest.raises(InputError, match=f"MissionSettings.{field}"):
        missions.MissionSettings(**{field: value})


def test_scenario_disturbance_cannot_be_replaced(borinot):
    settings = missions.MissionSettings(disturbance=WhiteNoise(0.1))
    with pytest.raises(InputError, match="sets its own disturbance"):
        missions.noise(borinot, "idc", False, settings, **options("hover-noise", duration=0.5))


def test_noise_amplitude_bounds_the_disturbance(borinot):
    """Absolute amplitudes: every sample of the uniform noise within [-a, a], the extremes near +-a; a = 0 on a coordinate: none."""
    a = np.full(borinot.n_xi, 0.2)
    a[5] = 0.0
    res = missions.noise(borinot, "idc", False, amplitude=a, **options("hover-noise", duration=1.0))
    assert np.all(np.abs(res.u_ext) <= a + 1e-15)
    live = a > 0
    assert np.all(res.u_ext.max(axis=0)[live] > 0.9 * a[live]) and np.all(res.u_ext[:, 5] == 0.0)
    assert res.metrics["max_position_error"] < 0.05  # hover kept under the noise


@pytest.mark.parametrize("amplitude", [(0.1,) * 3, (-0.1,) * 8])
def test_noise_amplitude_refused(borinot, amplitude):
    assert borinot.n_xi == 8
    with pytest.raises(InputError, match="amplitude must"):
        missions.noise(borinot, "idc", False, amplitude=amplitude, **options("hover-noise", duration=0.5))


def test_pulse_train_acts_when_given(borinot):
    """A given train: the disturbance felt is Gamma inside [t1, t2), zero outside; the hover recovers after it."""
    gamma = np.zeros(borinot.n_xi)
    gamma[0] = 1.5
    res = missions.pulses(borinot, "idc", False, train=(Pulse(0.2, 0.4, tuple(gamma)),), **options("hover-pulses", duration=1.5))
    on = (res.t > 0.2 + 1e-9) & (res.t < 0.4 - 1e-9)
    np.testing.assert_array_equal(res.u_ext[on], np.tile(gamma, (on.sum(), 1)))
    assert np.all(res.u_ext[(res.t < 0.2 - 1e-9) | (res.t > 0.4 + 1e-9)] == 0.0)
    assert res.metrics["final_position_error"] < 0.5 * res.metrics["max_position_error"]
    with pytest.raises(InputError, match="train"):
        missions.pulses(borinot, "idc", False, train=(), **options("hover-pulses", duration=0.5))


def test_default_pulse_train_timing(borinot):
    """The registered train: 5 % of the run each, at 10 %, 40 %, 70 %; force on z, then x and y; torque on every arm joint."""
    train = missions.pulse_train(borinot, 10.0, 2.0, 0.05)
    np.testing.assert_allclose([(p.t1, p.t2) for p in train], [(1.0, 1.5), (4.0, 4.5), (7.0, 7.5)], rtol=0, atol=1e-12)
    n = borinot.n_xi
    assert train[0].gamma[2] == 2.0 and sum(train[0].gamma) == 2.0
    assert train[1].gamma[0] == train[1].gamma[1] == 2.0 and sum(train[1].gamma) == 4.0
    assert train[2].gamma[6:] == (0.05,) * (n - 6) and sum(train[2].gamma[:6]) == 0.0


def test_phase_tables_round_trip(borinot):
    phases = (Phase("z", 0.0, 1.0, 1.5), Phase(borinot.arm_names[0], 0.5, 1.0, 0.3))
    back, payload = missions.read_mission({"phase": missions.phase_tables(phases)})
    assert back == phases and payload is None
    with pytest.raises(InputError, match="Phase"):
        missions.phase_tables(({"coordinate": "z"},))


def test_mission_reference_given_once(borinot):
    settings = missions.MissionSettings(trajectory=Hold(tuple(borinot.neutral_xi() + np.r_[0, 0, 1.0, np.zeros(borinot.n_xi - 3)])))
    data = {"phase": [{"coordinate": "z", "start": 0.0, "end": 1.0, "target": 1.0}]}
    with pytest.raises(InputError, match="give one"):
        missions.mission(borinot, "idc", False, settings, **options("mission", duration=0.5, mission=data))
    # payload events alone with a given reference: the carried mass pulls the hover down, then it recovers
    events = {"payload": [{"time": 0.2, "mass": 0.1 * borinot.total_mass}]}
    res = missions.mission(borinot, "idc", False, settings, **options("mission", duration=1.0, mission=events))
    assert res.metrics["max_position_error"] > 1e-3
    with pytest.raises(InputError, match="at least one"):
        missions.mission(borinot, "idc", False, **options("mission", duration=0.5, mission=events))


def test_gains_object_reaches_the_controller(borinot):
    n = borinot.n_xi
    g = IDCGains((7.0,) * n, (3.0,) * n, (0.0,) * n)
    assert missions.gain_arguments("idc", borinot, g) == {"gains": g}
    assert missions.controller_for("idc", borinot, g).gains is g
    with pytest.raises(InputError, match="gains must be"):
        missions.gain_arguments("idc", borinot, 3.0)


# the generic missions' functions and the registered names, for the MissionSettings tests below
FUNCTIONS = {
    "takeoff-hover": missions.takeoff_hover,
    "fly-to": missions.fly_to,
    "mission": missions.mission,
    "grasp-drop": missions.grasp_drop,
    "hover-wind": missions.hover_wind,
    "motor-lag": missions.motor_lag,
    "hover-noise": missions.noise,
    "hover-pulses": missions.pulses,
}


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_given_reference_and_controller_are_flown(borinot, name):
    """MissionSettings.trajectory is the reference every mission flies (its xi_d), and MissionSettings.controller the
    controller (a built one with other gains flies otherwise than the mission's own)."""
    xi_ref = borinot.neutral_xi()
    xi_ref[2] = 1.5
    n = borinot.n_xi
    own = missions.controller_for("idc", borinot, "platform")
    fixed = missions.controller_for("idc", borinot, "class")
    o = options(name, duration=1.0)
    given = FUNCTIONS[name](borinot, "idc", False, missions.MissionSettings(trajectory=Hold(tuple(xi_ref)), controller=own), **o)
    flat = [k for k in range(n) if k not in (3, 4)]  # the logged roll and pitch references are the commanded tilt
    np.testing.assert_array_equal(given.xi_d[:, flat], np.tile(xi_ref[flat], (given.xi_d.shape[0], 1)))
    other = FUNCTIONS[name](borinot, "idc", False, missions.MissionSettings(trajectory=Hold(tuple(xi_ref)), controller=fixed), **o)
    assert not np.array_equal(given.xi, other.xi)
    assert given.controller == other.controller == "idc"


def test_ee_push_refuses_a_given_reference_or_controller(borinot):
    with pytest.raises(InputError, match="MissionSettings.trajectory and MissionSettings.controller must be None"):
        missions.push(borinot, "idc", False, missions.MissionSettings(trajectory=Hold(tuple(borinot.neutral_xi()))), **options("ee-push"))


def test_gains_object_must_fit_the_controller(borinot):
    from qprr.control.opspace_impedance import EndEffectorImpedance

    with pytest.raises(InputError, match="EndEffectorImpedance do not fit controller 'idc'"):
        missions.gain_arguments("idc", borinot, EndEffectorImpedance.from_frequency(4.0, 1.0, 1.0))


@pytest.mark.parametrize("name", sorted(FUNCTIONS) + ["ee-push"])
def test_every_mission_flies_the_plant_it_is_given(borinot, name):
    """A 10 % heavier plant flies otherwise than the model (the plant reaches the simulation of every mission)."""
    from qprr.sim.mismatch import ModelError, perturbed

    heavy = perturbed(borinot, ModelError(mass=1.1))
    controller = SCENARIOS[name].controllers[0]
    duration = 4.0 if name == "fly-to" else 1.0  # fly-to squeezed into 1 s asks more than borinot's arm can give
    nominal = SCENARIOS[name].run(platform=borinot, controller=controller, duration=duration)
    flown = SCENARIOS[name].run(platform=borinot, controller=controller, duration=duration, plant=heavy)
    assert not np.array_equal(nominal.xi, flown.xi)
