"""Controllers: coordinate maps, (6.17), gains analysis, iPID sign, BSG closed form, IDC properties."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from qprr import charts as co
from qprr.charts import State
from qprr.control import (
    DecoupledController,
    DesiredStateInverseDynamics,
    IDCGains,
    InverseDynamicsController,
    MFCGains,
    ModelFreeController,
    Reference,
    ipid,
    make_controller,
)
from qprr.control.filters import CommandFilter, tilt_6_17
from qprr.dynamics import dynamics_xi
from qprr.errors import InputError, NotResetError, UnknownNameError
from qprr.kinematics import com_body
from qprr.sim import simulate
from qprr.thesis import gains
from qprr.thesis.bsg import CogStabilizer, cog_betas, x_cm_thesis
from qprr.thesis.missions import static_mission
from qprr.thesis.printed import ipid_thesis_printed
from qprr.thesis.scenarios import flight_controller
from qprr.trajectory import Hold
from tests.conftest import random_xi


# ----------------------------------------------------------------------------- coordinate maps
def test_state_maps_match_coordinates(robot):
    rng = np.random.default_rng(1)
    st = State(3)
    for _ in range(200):
        xi = random_xi(rng, robot)
        xi_dot, xi_ddot, tau = rng.normal(size=(3, 9))
        q, v = co.xi_to_qv(xi, xi_dot)
        st.update(0.0, q, v)
        np.testing.assert_allclose(st.xi, xi, atol=1e-9)
        np.testing.assert_allclose(st.xi_dot, xi_dot, atol=1e-8)
        np.testing.assert_allclose(st.accel_to_v(xi_ddot), co.xi_ddot_to_a(xi, xi_dot, xi_ddot), atol=1e-8)
        S = co.rate_map(xi)
        np.testing.assert_allclose(st.force_to_xi(tau), S.T @ tau, atol=1e-10)
        np.testing.assert_allclose(st.force_from_xi(S.T @ tau), tau, atol=1e-8)
        st2 = State(3)
        st2.update_xi(0.0, xi, xi_dot)
        np.testing.assert_allclose(st2.v, v, atol=1e-10)
        np.testing.assert_allclose(pin.difference(robot.model, st2.q, q), 0.0, atol=1e-10)


def test_thrust_direction_6_17_recovers_roll_and_pitch():
    """(6.17): for u_fb = R_b [0, 0, f] the formulas return the roll and pitch of R_b (any yaw)."""
    rng = np.random.default_rng(2)
    for _ in range(100):
        phi, theta, psi = rng.uniform(-0.7, 0.7), rng.uniform(-0.7, 0.7), rng.uniform(-np.pi, np.pi)
        u = co.euler_to_rotation([phi, theta, psi]) @ np.array([0.0, 0.0, rng.uniform(5, 50)])
        got = tilt_6_17(*u, np.cos(psi), np.sin(psi), 0.8)
        np.testing.assert_allclose(got, (phi, theta), atol=1e-12)


def test_command_filter_tracks_with_consistent_derivatives():
    f = CommandFilter(1, 50.0)
    f.reset([0.0])
    x, xd = 0.0, 0.0
    for k in range(3000):  # a plant integrated like the simulator follows the filter exactly
        f.update([1.0 + 0.1 * k * 1e-3], 1e-3)
        xd += 1e-3 * f.xdd[0]
        x += 1e-3 * xd
    assert x == pytest.approx(f.x[0], abs=1e-12) and xd == pytest.approx(f.xd[0], abs=1e-12)
    assert f.x[0] == pytest.approx(1.3 - 0.1 * 2 / 50, abs=1e-4)  # ramp lag 2 / omega


# ----------------------------------------------------------------------------- gains analysis
def test_table_6_2_attitude_pids_are_unstable_under_exact_linearisation():
    """e''' + k_D e'' + k_P e' + k_I e = 0 has roots in the right half-plane for all three angles."""
    g = gains.table_6_2()
    for i in (3, 4, 5):
        roots = np.roots([1.0, g.kd[i], g.kp[i], g.ki[i]])
        assert roots.real.max() > 0.1
        assert g.kd[i] * g.kp[i] < g.ki[i]  # Routh-Hurwitz violated
    d = gains.idc()
    for i in (3, 4, 5):
        assert np.roots([1.0, d.kd[i], d.kp[i], d.ki[i]]).real.max() < 0


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
def test_table_6_2_gains_lose_the_attitude_in_the_static_mission(robot):
    """With the printed attitude gains the pitch error grows exponentially until the vehicle tumbles."""
    from qprr.errors import DivergenceError

    ctrl = InverseDynamicsController(robot, gains.table_6_2())
    try:
        res = simulate(robot, ctrl, static_mission(), 30.0, integrator="midpoint")
    except DivergenceError as err:
        res = err.result
    e = np.abs(res.xi_d[:, 4] - res.xi[:, 4])
    early, late = e[(res.t > 3) & (res.t < 6)].max(), e[res.t > 24].max()
    assert late > 1e3 * early and late > 0.5
    ok = simulate(robot, InverseDynamicsController(robot, gains.idc()), static_mission(), 30.0, integrator="midpoint")
    assert np.abs(ok.xi_d[:, 4] - ok.xi[:, 4]).max() < 1e-3


def test_mfc_alpha_choice_and_the_naive_one(robot):
    """F_est uses last step's inputs: u_k = (I - diag(1/alpha) B^-1) u_(k-1) + ... must contract."""
    B, _, _ = dynamics_xi(robot, robot.data(), np.zeros(9), np.zeros(9))
    Binv = np.linalg.inv(B)
    naive = np.eye(9) - np.diag(np.diag(B)) @ Binv  # alpha = 1 / B_ii
    assert max(abs(np.linalg.eigvals(naive))) > 10
    ctrl = ModelFreeController(robot, gains.mfc())
    ctrl.reset(_state_at(np.zeros(9)), Reference(), 1e-3)
    ours = np.eye(9) - np.diag(1.0 / np.array(ctrl.alpha)) @ Binv
    assert max(abs(np.linalg.eigvals(ours)[3:])) < 1.0 or max(abs(np.linalg.eigvals(ours))) < 1.0


def _state_at(xi, xi_dot=None):
    st = State(3)
    q, v = co.xi_to_qv(xi, np.zeros(9) if xi_dot is None else xi_dot)
    st.update(0.0, q, v)
    return st


# ----------------------------------------------------------------------------- iPID sign (6.37)
def test_ipid_printed_sign_diverges_and_corrected_converges():
    """Erratum (6.37): with y'' = F + alpha u the printed iPID gives e'' - K_D e' - ... (unstable)."""
    kp, ki, kd, alpha, F, dt = 60.0, 8.0, 35.0, 2.0, -3.0, 1e-3

    def run(law):
        y, yd, ie, u = 0.1, 0.0, 0.0, 0.0
        for _ in range(20000):
            Fe = F  # exact estimate: isolates the sign of the law
            e, ed = -y, -yd
            ie += e * dt
            u = law(Fe, 0.0, e, ie, ed)
            ydd = F + alpha * u
            yd += dt * ydd
            y += dt * yd
            if abs(y) > 1e6:
                return y
        return y

    assert abs(run(lambda *err: ipid(*err, alpha, (kp, ki, kd)))) < 5e-3  # slow pole s = -0.146 of s^3 + 35 s^2 + 60 s + 8
    assert abs(run(lambda *err: ipid_thesis_printed(*err, alpha, kp, ki, kd))) > 1e6


# ----------------------------------------------------------------------------- BSG (6.33)-(6.35)
def test_x_cm_6_33_matches_pinocchio(robot):
    rng = np.random.default_rng(3)
    data = robot.data()
    for _ in range(100):
        xi = np.zeros(9)
        xi[6:9] = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
        c = com_body(robot, data, co.xi_to_q(xi))
        assert x_cm_thesis(robot.params, *xi[6:9]) == pytest.approx(c[0], abs=1e-12)


def test_bsg_references_zero_x_cm_and_keep_end_effector_pitch(robot):
    inner = flight_controller("mfc", robot)
    bsg = CogStabilizer(robot, inner, theta_e_d=0.1)
    b1, b2, b3 = cog_betas(robot.params)
    for theta in (-0.1, 0.0, 0.05):
        r0, t3 = bsg.joint_references(theta, -0.2)
        assert theta + (-0.2) + t3 == pytest.approx(0.1)  # (6.34)-(6.35)
        assert x_cm_thesis(robot.params, r0, -0.2, t3) == pytest.approx(0.0, abs=1e-12)  # (6.33)
    # theta2_d = -0.5, theta_e^d = 0: r0 would be 4.1 cm, beyond the 4 cm stroke -> clamped
    bsg0 = CogStabilizer(robot, inner, theta_e_d=0.0)
    r0, _ = bsg0.joint_references(0.0, -0.5)
    assert r0 == pytest.approx(robot.params.r0_limits[1])
    assert -(b2 * np.sin(-0.5) + b3 * np.sin(0.0)) / b1 > robot.params.r0_limits[1]
    with pytest.raises(UnknownNameError):
        CogStabilizer(robot, inner, pitch="guessed")


# ----------------------------------------------------------------------------- IDC properties
def test_idc_at_rest_returns_gravity_and_no_lateral_body_force(robot):
    rng = np.random.default_rng(4)
    for _ in range(20):
        xi = np.zeros(9)
        xi[0:3] = rng.uniform(-1, 1, 3)
        xi[5] = rng.uniform(-1, 1)
        xi[6:9] = rng.uniform(robot.params.lower_limits, robot.params.upper_limits) * 0.5
        st = _state_at(xi)
        ctrl = InverseDynamicsController(robot, gains.idc(), realizable=False)
        ref = Reference(xi.copy(), np.zeros(9), np.zeros(9))
        ctrl.reset(st, ref, 1e-3)
        assert ctrl.output == "pinocchio"
        u = st.force_to_xi(ctrl.step(0.0, st, ref))
        _, _, G = dynamics_xi(robot, robot.data(), st.xi.copy(), np.zeros(9))
        # at rest on the reference the roll/pitch references may differ from 0 (CoG off axis):
        # compare the force and the arm efforts, which do not depend on them at rest
        np.testing.assert_allclose(u[[0, 1, 2, 6, 7, 8]], G[[0, 1, 2, 6, 7, 8]], atol=1e-8)
    # realizable: the applied force has no body-lateral part
    xi = random_xi(rng, robot, max_pitch=0.3)
    st = _state_at(xi, rng.normal(size=9) * 0.1)
    ctrl = InverseDynamicsController(robot, gains.idc())
    ref = Reference(xi + 0.01, np.zeros(9), np.zeros(9))
    ctrl.reset(st, ref, 1e-3)
    tau = ctrl.step(0.0, st, ref)
    np.testing.assert_allclose(tau[0:2], 0.0, atol=1e-9)


def test_controllers_take_the_control_period_from_reset_only(robot):
    """No made-up default step: dt is unset until reset(state, ref, dt) (NotResetError before, also on step), then it is
    the period given; a BSG asked for the inner controller's desired pitch refuses an inner one that derives none."""
    xi = np.r_[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.3, -0.2]
    st = _state_at(xi)
    for ctrl in (
        InverseDynamicsController(robot),
        DesiredStateInverseDynamics(robot),
        ModelFreeController(robot),
        DecoupledController(robot),
        CogStabilizer(robot, ModelFreeController(robot)),
    ):
        with pytest.raises(NotResetError, match=r"dt .*reset\(state, ref, dt\)"):
            _ = ctrl.dt
        with pytest.raises(NotResetError, match="reset"):
            ctrl.step(0.0, st, Reference(xi.copy(), np.zeros(9), np.zeros(9)))
        ctrl.reset(st, Reference(xi.copy(), np.zeros(9), np.zeros(9)), 2e-3)
        assert ctrl.dt == 2e-3
        assert np.all(np.isfinite(ctrl.step(0.0, st, Reference(xi.copy(), np.zeros(9), np.zeros(9)))))
    with pytest.raises(InputError, match="pitch='desired'.*tilt is None"):
        CogStabilizer(robot, DecoupledController(robot), pitch="desired").reset(st, Reference(xi.copy()), 1e-3)


def test_controller_registry_and_gain_validation(robot):
    assert isinstance(make_controller("dsid", robot), DesiredStateInverseDynamics)
    with pytest.raises(UnknownNameError, match="'idc', 'dsid', 'mfc'"):
        make_controller("pid", robot)
    with pytest.raises(InputError):  # gain vectors of different lengths
        IDCGains(kp=(1.0,) * 8, kd=(1.0,) * 9, ki=(0.0,) * 9)
    with pytest.raises(InputError, match="8 entries"):  # 8 gains (6 + 2 arm joints) for the Q-PRR's 9 coordinates
        InverseDynamicsController(robot, IDCGains(kp=(1.0,) * 8, kd=(1.0,) * 8, ki=(0.0,) * 8))
    with pytest.raises(InputError):
        dataclasses.replace(gains.idc(), kd=(-1.0,) * 9)
    with pytest.raises(InputError):
        MFCGains(alpha=(0.0,) * 9)
    with pytest.raises(InputError):
        InverseDynamicsController(robot, gains=MFCGains())


def test_hover_hold_with_each_controller(robot):
    """Every controller holds hover (2 s) to sub-millimetre error."""
    for name in ("idc", "dsid", "mfc"):
        res = simulate(robot, flight_controller(name, robot), Hold((0, 0, 5, 0, 0, 0, 0, 0, 0)), 2.0, integrator="midpoint")
        assert np.abs(res.xi_d - res.xi)[:, 0:3].max() < 1e-3, name
