"""Decoupled control (Thesis Sec. 6.2.2, Fig. 6.2): it recovers the coupled IDC when the arm is fixed, its parts are
the models they claim (composite rigid body; fixed-base arm (5.53)), and the coupling it ignores costs tracking."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.charts import State, xi_to_qv
from qprr.control import DecoupledController, IDCGains, InverseDynamicsController, Reference, lock_arm, make_controller
from qprr.control.decoupled import fixed_base_inverse_dynamics
from qprr.errors import InputError, UnknownNameError
from qprr.sim import simulate
from qprr.thesis import gains, params_of, printed
from qprr.thesis.missions import static_mission
from qprr.trajectory import MultiPhase, Phase

PLATFORM = qprr.load()


def _state(xi, xi_dot) -> State:
    s = State(len(xi) - 6)
    s.update(0.0, *xi_to_qv(np.asarray(xi, float), np.asarray(xi_dot, float)))
    return s


def test_with_the_arm_fixed_decoupled_is_the_coupled_idc_bit_for_bit():
    """Arm locked at a reach posture (a rigid multirotor): the decoupled controller's run is the IDC's, to the last bit."""
    locked = lock_arm(PLATFORM, (0.02, 0.6, -0.4))
    assert locked.n_arm == 0 and locked.total_mass == pytest.approx(PLATFORM.total_mass, rel=1e-14)
    g = gains.idc()
    g6 = IDCGains(g.kp[:6], g.kd[:6], g.ki[:6], g.filter_omega, g.max_tilt)
    trajectory = MultiPhase((Phase("z", 0, 3, 4.0), Phase("x", 3, 6, 2.0), Phase("y", 5, 8, -1.0)), xi0=(0.0,) * 6, names=locked.xi_names)
    a = simulate(locked, InverseDynamicsController(locked, g6), trajectory, 10.0)
    b = simulate(locked, DecoupledController(locked, g6), trajectory, 10.0)
    assert a.status == b.status == "ok"
    for field in ("xi", "xi_dot", "u", "f", "x_cm"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert np.abs(a.xi[-1, 0:3] - [2.0, -1.0, 4.0]).max() < 0.05  # it flew the mission


def test_at_rest_on_the_arm_reference_the_base_wrench_is_the_coupled_one():
    """On the full Q-PRR, with the arm at rest on its reference (no arm motion to ignore), the decoupled base wrench equals
    the coupled IDC's (the composite rigid body is the whole model with the arm's rates and accelerations at zero)."""
    rng = np.random.default_rng(4)
    g = gains.idc()
    for _ in range(5):
        xi = np.r_[rng.normal(size=3), 0.1 * rng.normal(size=3), 0.02, rng.uniform(-1, 1, 2)]
        xi_dot = np.r_[rng.normal(size=6) * 0.3, 0.0, 0.0, 0.0]
        ref_xi = xi.copy()
        ref_xi[0:3] += rng.normal(size=3) * 0.1
        coupled, decoupled = InverseDynamicsController(PLATFORM, g), DecoupledController(PLATFORM, g)
        out = []
        for c in (coupled, decoupled):
            ref = Reference(ref_xi.copy(), np.zeros(9), np.r_[rng.normal(size=3) * 0, np.zeros(6)])
            s = _state(xi, xi_dot)
            c.reset(s, ref, 1e-3)
            out.append(np.array(c.step(0.0, s, ref)))
        np.testing.assert_allclose(out[1][0:6], out[0][0:6], rtol=1e-12, atol=1e-10)


def test_base_wrench_ignores_the_arm_motion():
    """The multirotor controller treats the arm's rates and accelerations as a disturbance: its base wrench does not
    depend on them (it does on the arm's configuration: the composite inertia)."""
    g = gains.idc()
    xi = np.r_[0.1, 0.2, 3.0, 0.05, -0.04, 0.3, 0.01, 0.5, -0.3]
    outs = []
    for arm_rate, arm_ref_acc in ((0.0, 0.0), (1.5, 3.0)):
        c = DecoupledController(PLATFORM, g)
        s = _state(xi, np.r_[0.1, 0, 0, 0, 0, 0, 0.0, arm_rate, -arm_rate])
        ref = Reference(xi.copy(), np.zeros(9), np.r_[np.zeros(6), 0.0, arm_ref_acc, arm_ref_acc])
        c.reset(s, ref, 1e-3)
        outs.append(c.step(0.0, s, ref))
    np.testing.assert_allclose(outs[0][0:6], outs[1][0:6], rtol=1e-13, atol=1e-12)
    assert np.abs(outs[0][6:] - outs[1][6:]).max() > 1e-3  # the arm controller does react


def test_arm_controller_is_the_fixed_base_model_of_sec_5_5():
    """fixed_base_inverse_dynamics on Platform.arm_model() = B q_ddot + C q_dot + G of Sec. 5.5 (corrected B and C, the
    printed G whose gravity is along +x_B) for random states."""
    params = params_of(PLATFORM)
    arm = PLATFORM.arm_model()
    data = arm.createData()
    rng = np.random.default_rng(7)
    for _ in range(10):
        q = np.r_[rng.uniform(-0.04, 0.04), rng.uniform(-2.0, 2.0, 2)]
        qd, qdd = rng.normal(size=3), rng.normal(size=3)
        u = fixed_base_inverse_dynamics(arm, data, q, qd, qdd, gravity_base=(params.g, 0.0, 0.0))
        np.testing.assert_allclose(u, printed.arm_u_5_5_corrected(q, qd, qdd, params), rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(arm.gravity.linear, [0.0, 0.0, -params.g])  # the model is restored
    # level base (the default): RNEA's gravity along -z_B
    np.testing.assert_allclose(fixed_base_inverse_dynamics(arm, data, q, qd, qdd), pin.rnea(arm, arm.createData(), q, qd, qdd), rtol=1e-15)


def test_measured_gravity_option_turns_gravity_into_the_base_frame():
    c = DecoupledController(PLATFORM, gains.idc(), arm_gravity="measured")
    xi = np.r_[0, 0, 1, 0.3, -0.2, 0.4, 0.01, 0.5, -0.3]
    s = _state(xi, np.zeros(9))
    ref = Reference(xi.copy(), np.zeros(9), np.zeros(9))
    c.reset(s, ref, 1e-3)
    tau = c.step(0.0, s, ref)
    g_b = s.R.T @ np.array([0.0, 0.0, -PLATFORM.g])
    expected = fixed_base_inverse_dynamics(PLATFORM.arm_model(), PLATFORM.arm_model().createData(), xi[6:], np.zeros(3), np.zeros(3), g_b)
    np.testing.assert_allclose(tau[6:], expected, rtol=1e-12)


def test_coupling_costs_the_decoupled_scheme_arm_tracking():
    """The static mission at equal gains: the decoupled arm loop suffers the base's accelerations (a disturbance to it),
    the coupled IDC cancels them - the decoupled arm RMSE is more than 10 times the coupled one; base tracking is alike."""
    g = gains.idc()
    mission = static_mission()
    a = simulate(PLATFORM, InverseDynamicsController(PLATFORM, g), mission, 30.0)
    b = simulate(PLATFORM, make_controller("decoupled", PLATFORM, gains=g), mission, 30.0)
    ea, eb = a.rmse(), b.rmse()
    assert b.status == "ok"
    assert eb["theta2"] > 10 * ea["theta2"] and eb["theta3"] > 10 * ea["theta3"]
    assert eb["y"] == pytest.approx(ea["y"], rel=0.1)


def test_validation():
    with pytest.raises(InputError, match="Platform"):
        DecoupledController(object())
    with pytest.raises(UnknownNameError, match="arm gravity"):
        DecoupledController(PLATFORM, arm_gravity="up")
    with pytest.raises(qprr.errors.LimitError):
        lock_arm(PLATFORM, (1.0, 0.0, 0.0))
