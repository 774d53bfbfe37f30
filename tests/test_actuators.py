"""The actuator stage (qprr.sim.actuators): motor-lag step response, saturation, and the integrators' orders with it on.

The orders are measured as in tests/test_convergence.py: the control period T_c stays fixed
while the step is halved three times (dt = T_c / s ... T_c / 8s), and the state at the last
control tick - (q, v), the rotor speeds and, with an environment, its state - is compared with
an RK4 run at T_c / 256.  The observed order log2(e(dt) / e(dt/2)) must be 1, 2, 4 (+-0.2).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.charts import xi_to_qv
from qprr.control import IDCGains, make_controller
from qprr.control.base import Controller
from qprr.errors import InputError, ShapeError, UnknownNameError
from qprr.platforms import rotor_dynamics
from qprr.sim import ORDERS, simulate
from qprr.sim.actuators import RotorDynamics, time_constant_of
from qprr.sim.wind import AerodynamicDrag, Dryden, Gust, ViscousFriction, Wind
from qprr.trajectory import Hold

PLATFORM = qprr.load()
B = PLATFORM.params.thrust_factor


class _Thrusts(Controller):
    """Constant rotor thrust commands f (n_rotors,) and zero arm efforts, as Pinocchio's tau = N [f; 0]."""

    output = "pinocchio"
    name = "constant-thrusts"

    def __init__(self, platform, f) -> None:
        self.tau = np.array(platform.actuation_matrix) @ np.r_[f, np.zeros(platform.n_arm)]

    def step(self, t, state, ref):
        return self.tau


# ------------------------------------------------------------------------------ step response
def test_motor_lag_step_response_has_the_stated_time_constant():
    """From rest speeds w0 the rotors follow a thrust-command step with w(t) = w_c + (w0 - w_c) e^(-t/T), T = 5 ms:
    the logged speeds match the closed form to the RK4 error, the thrust is b w^2, and the 63.2 % crossing is T."""
    T = 0.005
    w0 = np.full(4, 400.0)
    f_c = np.array([9.0, 10.0, 11.0, 12.0])
    act = RotorDynamics.for_rotors(PLATFORM.rotors, B, T, initial=tuple(w0))
    res = simulate(PLATFORM, _Thrusts(PLATFORM, f_c), Hold((0.0,) * 9), 0.05, dt=1e-4, integrator="rk4", actuators=act, joint_stops=False)
    w = res.series["rotor_speed"]
    w_c = np.sqrt(f_c / B)
    exact = act.step_response(res.t, w0, w_c)
    assert np.max(np.abs(w - exact)) < 1e-8 * np.max(w_c)
    np.testing.assert_allclose(res.f, B * w * w, rtol=1e-15)
    np.testing.assert_allclose(res.series["thrust_command"], np.tile(f_c, (res.n, 1)), rtol=1e-12)
    for i in range(4):
        assert time_constant_of(res.t, w[:, i], w0[i], w_c[i]) == pytest.approx(T, rel=2e-4)


def test_speed_saturation_caps_the_thrust():
    """A command above b w_max^2 spins the rotor to w_max and no further; a negative or tiny one to w_min."""
    act = RotorDynamics((B,) * 4, 0.005, 100.0, 700.0)
    np.testing.assert_allclose(act.speed_command([30.0, 1e-9, -5.0, B * 300.0**2]), [700.0, 100.0, 100.0, 300.0])
    res = simulate(
        PLATFORM,
        _Thrusts(PLATFORM, np.array([19.0, 19.0, 19.0, 19.0])),
        Hold((0.0,) * 9),
        0.1,
        dt=1e-4,
        integrator="rk4",
        actuators=RotorDynamics.for_rotors(PLATFORM.rotors, B, 0.005, w_max=700.0, initial=(100.0,) * 4),
        joint_stops=False,
    )
    w = res.series["rotor_speed"]
    assert np.all(w <= 700.0 + 1e-9) and w[-1, 0] == pytest.approx(700.0, rel=1e-8)
    assert np.all(res.f <= B * 700.0**2 * (1 + 1e-12))


def test_start_at_the_command_is_steady():
    """initial="command": the rotors start at the first command, so a constant command leaves them there."""
    f_c = np.full(4, 8.0)
    res = simulate(PLATFORM, _Thrusts(PLATFORM, f_c), Hold((0.0,) * 9), 0.02, actuators=rotor_dynamics("q-prr"), joint_stops=False)
    np.testing.assert_allclose(res.series["rotor_speed"], np.sqrt(8.0 / B), rtol=1e-14)


def test_start_hovering_holds_the_initial_configuration():
    """initial="hover": the rotors start at the speeds whose thrusts b w^2 carry the weight (CoG on the thrust axis: m g / 4
    each), whatever the controller's first command."""
    act = rotor_dynamics("q-prr", initial="hover")
    res = simulate(
        PLATFORM, _Thrusts(PLATFORM, np.zeros(4)), Hold((0.0,) * 9), 0.003, actuators=act, joint_stops=False, xi0=np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    )
    np.testing.assert_allclose(res.f[0], PLATFORM.total_mass * PLATFORM.g / 4, rtol=1e-12)
    assert res.series["rotor_speed"][1, 0] < res.series["rotor_speed"][0, 0]  # then they spin down to the zero command


def test_validation():
    with pytest.raises(InputError, match="time_constant"):
        RotorDynamics((B,) * 4, 0.0, 0.0, 800.0)
    with pytest.raises(InputError, match="w_min < w_max"):
        RotorDynamics((B,) * 4, 0.01, 900.0, 800.0)
    with pytest.raises(ShapeError, match="one per rotor"):
        RotorDynamics((B,) * 4, (0.01, 0.02), 0.0, 800.0)
    with pytest.raises(ShapeError, match="4 rotors, the platform 6"):
        simulate(
            qprr.load("borinot_flying_arm_2"),
            make_controller("idc", qprr.load("borinot_flying_arm_2")),
            Hold((0,) * 8),
            0.01,
            actuators=rotor_dynamics("q-prr"),
        )
    with pytest.raises(InputError, match="motor time constant"):
        simulate(PLATFORM, make_controller("idc", PLATFORM), Hold((0.0,) * 9), 0.1, dt=1e-2, actuators=rotor_dynamics("q-prr"))
    with pytest.raises(InputError, match="RotorDynamics"):
        simulate(PLATFORM, make_controller("idc", PLATFORM), Hold((0.0,) * 9), 0.1, actuators="on")
    with pytest.raises(InputError, match="no motor data"):
        rotor_dynamics("hextilt_flying_arm_5")
    with pytest.raises(UnknownNameError, match="motor key"):
        rotor_dynamics("borinot_flying_arm_2", inertia=1.0)


def test_borinot_motor_data_is_its_gazebo_model():
    """qprr/data: b = 4.511e-6 N s^2, w_max = 2236 rad/s (b w_max^2 = the rotors' f_max), T = 5 ms."""
    act = rotor_dynamics("borinot_flying_arm_2")
    pf = qprr.load("borinot_flying_arm_2")
    assert act.n_rotors == 6 and act.time_constant == (0.005,) * 6
    np.testing.assert_allclose(np.array(act.thrust_factor) * np.array(act.w_max) ** 2, pf.thrust_max, rtol=1e-9)


# ------------------------------------------------------------------------------ convergence
# off the reference and moving (half the offsets of tests/test_convergence.py: no rotor bound is reached, so no
# allocation QP, whose 1e-10 tolerance would floor the RK4 ladder)
XI_REF = np.r_[0, 0, 1, 0, 0, 0.2, 0.0, 0.3, -0.3]
XI_CL = XI_REF + 0.5 * (np.r_[0.05, -0.05, 0.95, 0.05, -0.05, 0.1, 0.01, 0.4, -0.2] - XI_REF)
XID_CL = 0.5 * np.r_[0.4, -0.2, 0.2, 0.4, -0.4, 0.2, 0.04, 0.6, -0.6]
T_C = 4e-3
REFERENCE_DIVISOR = 256


def _wind():
    return Wind((2.0, 1.0, 0.0), Dryden.low_altitude(10.0, 7.7, 2.2), (Gust(0.1, 0.3, (0.0, 1.5, 0.0)),))


CASES = {
    "idc + motor lag": lambda: dict(actuators=rotor_dynamics("q-prr", time_constant=0.005)),
    "idc + motor lag + wind drag + friction": lambda: dict(
        actuators=rotor_dynamics("q-prr", time_constant=0.005),
        disturbance=qprr.sim.Disturbances(
            (AerodynamicDrag((1.0, 1.0, 0.3), (0.03, 0.03, 0.09), 0.01, _wind()), ViscousFriction((0.0,) * 6 + (0.5, 0.0075, 0.00025)))
        ),
    ),
}
START = {"euler": 4, "midpoint": 4, "rk4": 4}


def _final(name: str, integrator: str, substeps: int):
    kw = CASES[name]()
    res = simulate(
        PLATFORM,
        make_controller("idc", PLATFORM, gains=IDCGains.default(PLATFORM.n_arm)),  # the fixed (s + 6)^2 arm, (s + 10)^3 attitude gains
        Hold(tuple(XI_REF)),
        0.5,
        dt=T_C / substeps,
        control_period=T_C,
        integrator=integrator,
        xi0=XI_CL,
        xi_dot0=XID_CL,
        joint_stops=False,
        seed=3,
        **kw,
    )
    assert res.status == "ok" and not np.any(res.flags)
    q, v = xi_to_qv(res.xi[-1], res.xi_dot[-1])
    return q, v, res.series["rotor_speed"][-1]


def _error(a, b) -> float:
    return max(
        float(np.abs(pin.difference(PLATFORM.model, a[0], b[0])).max()), float(np.abs(a[1] - b[1]).max()), float(np.abs(a[2] - b[2]).max()) / 100.0
    )  # rotor speeds in hundreds of rad/s


@pytest.fixture(scope="module")
def references():
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = _final(name, "rk4", REFERENCE_DIVISOR)
        return cache[name]

    return get


@pytest.mark.parametrize("integrator", list(ORDERS))
@pytest.mark.parametrize("name", list(CASES))
def test_observed_order_with_the_actuator_stage(name, integrator, references):
    """Closed-loop IDC (4 ms period) with the rotor speeds (T = 5 ms) as plant states (and wind drag, friction): orders 1, 2, 4."""
    ref = references(name)
    s0 = START[integrator]
    errors = np.array([_error(_final(name, integrator, s0 * 2**i), ref) for i in range(4)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - ORDERS[integrator]) <= 0.2), f"{name}, {integrator}: errors {errors}, orders {orders}"


def test_no_stage_is_the_plain_simulator():
    """actuators=None and no wind: the run is the plain simulator's, bit for bit (the thesis scenarios are unchanged)."""
    a = simulate(PLATFORM, make_controller("idc", PLATFORM), Hold(tuple(XI_REF)), 0.2, xi0=XI_CL, xi_dot0=XID_CL, joint_stops=False)
    b = simulate(PLATFORM, make_controller("idc", PLATFORM), Hold(tuple(XI_REF)), 0.2, xi0=XI_CL, xi_dot0=XID_CL, joint_stops=False, actuators=None)
    np.testing.assert_array_equal(a.xi, b.xi)
    assert "rotor_speed" not in a.series
    assert math.isfinite(a.xi.sum())
