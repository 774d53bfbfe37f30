"""Simulator: static equilibria, conservation laws, integrator accuracy, divergence, hooks, results."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import qprr
import qprr.thesis
from qprr.actuation import AllocationFlag
from qprr.charts import xi_to_qv
from qprr.control.base import Controller
from qprr.dynamics import dynamics_xi
from qprr.errors import DivergenceError, InputError, UnknownNameError
from qprr.kinematics import com_body
from qprr.scenarios import SCENARIOS, run
from qprr.sim import BaseDrag, Limits, PayloadChange, PayloadSchedule, Pulse, SimConfig, SimInputs, SimResult, WhiteNoise, simulate
from qprr.thesis.bsg import cog_betas
from qprr.trajectory import Hold


class OpenLoop(Controller):
    """Constant generalised force (thesis coordinates) - no feedback."""

    name = "open-loop"

    def __init__(self, u):
        self.u = np.asarray(u, dtype=float)

    def step(self, t, state, ref):
        return self.u


def _hover_u(robot, xi):
    """u = G(xi): the generalised force that holds the system at rest at xi."""
    _, _, G = dynamics_xi(robot, robot.data(), xi, np.zeros(9))
    return G


# ------------------------------------------------------------------------------ equilibria
def test_hover_total_thrust_equals_weight_with_zero_arm_effort(robot):
    xi = np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    u = _hover_u(robot, xi)
    m, g = robot.params.total_mass, robot.params.g
    np.testing.assert_allclose(u, [0, 0, m * g, 0, 0, 0, 0, 0, 0], atol=1e-10)
    res = simulate(robot, OpenLoop(u), Hold(tuple(xi)), 2.0, integrator="midpoint")
    np.testing.assert_allclose(res.f, m * g / 4, atol=1e-9)
    np.testing.assert_allclose(res.arm_effort, 0.0, atol=1e-12)
    assert np.abs(res.xi - xi).max() < 1e-9


def test_hover_at_a_cog_balanced_pose(robot):
    """CoG on the thrust axis (x_cm = 0 by (6.33)): equal rotor thrusts m g / 4 and the arm's static torques hold it."""
    b1, b2, b3 = cog_betas(robot.params)
    t2, t3 = 0.4, -0.4
    r0 = -(b2 * np.sin(t2) + b3 * np.sin(t2 + t3)) / b1
    xi = np.r_[1, 2, 5, 0, 0, 0.3, r0, t2, t3]
    q, _ = xi_to_qv(xi, np.zeros(9))
    assert abs(com_body(robot, robot.data(), q)[0]) < 1e-12
    u = _hover_u(robot, xi)
    res = simulate(robot, OpenLoop(u), Hold(tuple(xi)), 1.0, integrator="midpoint")
    np.testing.assert_allclose(res.f, robot.params.total_mass * robot.params.g / 4, atol=1e-9)
    assert np.abs(res.arm_effort[0] - u[6:9]).max() < 1e-12 and abs(u[7]) > 0.1  # theta2 holds its links
    assert np.abs(res.xi - xi).max() < 1e-8
    assert np.abs(res.x_cm[:, 0]).max() < 1e-9


# ------------------------------------------------------------------------------ conservation
@pytest.fixture(scope="module")
def free_robot():
    return qprr.thesis.load_qprr(qprr.thesis.thesis_params().with_changes(g=0.0))


XI0 = np.r_[0, 0, 0, 0.1, -0.2, 0.3, 0.01, 0.3, -0.4]
XID0 = np.r_[0.5, -0.3, 0.2, 1.0, -2.0, 0.7, 0.05, 1.5, -2.0]


def _invariants(robot, res, every=25):
    m, d = robot.model, robot.model.createData()
    E, P, L = [], [], []
    for k in range(0, res.n, every):
        q, v = xi_to_qv(res.xi[k], res.xi_dot[k])
        E.append(pin.computeKineticEnergy(m, d, q, v))
        h = pin.computeCentroidalMomentum(m, d, q, v)
        P.append(h.linear.copy())
        L.append(h.angular.copy())
    E, P, L = np.array(E), np.array(P), np.array(L)
    return np.abs(E - E[0]).max() / E[0], np.abs(P - P[0]).max(), np.abs(L - L[0]).max()


@pytest.mark.parametrize(
    "integrator, e_tol, p_tol, l_tol",
    [
        ("midpoint", 1e-6, 1e-5, 1e-6),  # scenarios' integrator: measured 7.0e-7, 7.1e-6, 6.2e-7 over 10 s
        ("rk4", 1e-10, 1e-6, 1e-8),  # measured 3.2e-12, 4.4e-7, 7.7e-9
    ],
)
def test_free_flight_conserves_energy_and_momentum(free_robot, integrator, e_tol, p_tol, l_tol):
    """No gravity, no input, tumbling with the arm moving: 10 s at 1 kHz (|E| = 0.71 J, |p| = 1.9 N s).

    The integrator on the smooth dynamics: joint stops off (the free arm would hit them).
    """
    zero = OpenLoop(np.zeros(9))
    res = simulate(free_robot, zero, Hold(tuple(XI0)), 10.0, integrator=integrator, xi0=XI0, xi_dot0=XID0, joint_stops=False)
    dE, dP, dL = _invariants(free_robot, res)
    assert dE < e_tol and dP < p_tol and dL < l_tol


def test_joint_stop_impulse_is_internal_and_plastic(free_robot):
    """At the stops: joints put back on their limits, outward rates removed, centroidal momentum unchanged
    (the impulses are joint reactions), kinetic energy lost, inward rates left alone."""
    from qprr.sim.stops import apply_joint_stops as _apply_joint_stops

    m, d = free_robot.model, free_robot.model.createData()
    p = free_robot.params
    lo, hi = p.lower_limits.tolist(), p.upper_limits.tolist()
    rng = np.random.default_rng(5)
    for case in range(20):
        xi = np.r_[rng.uniform(-1, 1, 6), rng.uniform(p.lower_limits, p.upper_limits)]
        v = rng.normal(size=9)
        xi[6], v[6] = hi[0], abs(v[6])  # slider exactly at its upper stop, moving out
        if case % 2:
            xi[8], v[8] = lo[2], -abs(v[8])  # and theta3 at its lower stop, moving out
        q = xi_to_qv(xi, np.zeros(9))[0]
        q2, v2 = _apply_joint_stops(m, d, q, v, lo, hi)
        np.testing.assert_allclose(q2, q, atol=1e-15)  # nothing to correct in position
        # no joint keeps moving out of its stop (a stop may release when the others push it inward)
        assert v2[6] < 1e-12 and (case % 2 == 0 or v2[8] > -1e-12)
        h1 = pin.computeCentroidalMomentum(m, d, q, v).np.copy()
        h2 = pin.computeCentroidalMomentum(m, d, q, v2).np.copy()
        np.testing.assert_allclose(h2, h1, atol=1e-12)
        assert pin.computeKineticEnergy(m, d, q, v2) < pin.computeKineticEnergy(m, d, q, v)
    # moving inward from a stop: no impulse
    q = xi_to_qv(np.r_[np.zeros(6), hi[0], 0.0, 0.0], np.zeros(9))[0]
    v = np.r_[np.zeros(6), -0.3, 0.0, 0.0]
    assert np.array_equal(_apply_joint_stops(m, d, q, v, lo, hi)[1], v)


def test_the_free_arm_stays_inside_its_stops(free_robot):
    """Free tumbling with the stops on: the arm never leaves its range, and the stops did act."""
    zero = OpenLoop(np.zeros(9))
    res = simulate(free_robot, zero, Hold(tuple(XI0)), 10.0, xi0=XI0, xi_dot0=XID0)
    p = free_robot.params
    assert np.all(res.xi[:, 6:9] >= p.lower_limits - 1e-12) and np.all(res.xi[:, 6:9] <= p.upper_limits + 1e-12)
    assert (res.flags & AllocationFlag.JOINT_STOP).any()


def test_a_joint_pushed_into_its_stop_stays_there(free_robot):
    """No gravity, 5 N pushing the slider outward from rest: it travels to +0.04 m and stays pressed there."""
    xi = np.zeros(9)
    u = np.zeros(9)
    u[6] = 5.0
    res = simulate(free_robot, OpenLoop(u), Hold(tuple(xi)), 1.0, xi0=xi)
    hi = free_robot.params.r0_limits[1]
    assert res.xi[:, 6].max() <= hi + 1e-12
    assert res.xi[-1, 6] == pytest.approx(hi, abs=1e-12)
    assert np.abs(res.xi_dot[-100:, 6]).max() < 1e-9
    assert (res.flags[-100:] & AllocationFlag.JOINT_STOP).all()
    with pytest.raises(qprr.errors.LimitError, match="xi0"):
        simulate(free_robot, OpenLoop(u), Hold(tuple(xi)), 0.01, xi0=np.r_[0, 0, 0, 0, 0, 0, 0.05, 0, 0])


def test_semi_implicit_euler_drifts_at_first_order(free_robot):
    """Why it is not the default: its energy drifts (1.4 % in 10 s here) and halving dt halves the drift."""
    zero = OpenLoop(np.zeros(9))
    drift = []
    for dt in (1e-3, 5e-4):
        res = simulate(free_robot, zero, Hold(tuple(XI0)), 5.0, dt=dt, integrator="euler", xi0=XI0, xi_dot0=XID0, joint_stops=False)
        drift.append(_invariants(free_robot, res)[0])
    assert drift[0] > 1e-3
    assert drift[0] / drift[1] == pytest.approx(2.0, rel=0.1)


class ConstantTau(Controller):
    """Constant generalised force in Pinocchio coordinates (constant rotor thrusts and arm efforts)."""

    name = "constant"
    output = "pinocchio"

    def __init__(self, tau):
        self.tau = np.asarray(tau, dtype=float)

    def step(self, t, state, ref):
        return self.tau


def _error_at(robot, res, ref, t):
    """Largest entry of q_ref (-) q and v - v_ref at time t (a row of both logs)."""
    qa, va = xi_to_qv(res.xi[int(round(t / res.dt))], res.xi_dot[int(round(t / res.dt))])
    qb, vb = xi_to_qv(ref.xi[int(round(t / ref.dt))], ref.xi_dot[int(round(t / ref.dt))])
    return max(np.abs(pin.difference(robot.model, qb, qa)).max(), np.abs(va - vb).max())


def _orders(robot, controller, xi0, integrator, steps, **kw):
    """Observed orders at t = 0.392 s (a row of every log) against RK4 at steps[0] / 64."""
    ref = simulate(robot, controller, Hold(tuple(xi0)), 0.4, dt=steps[0] / 64, integrator="rk4", xi0=xi0, **kw)
    errors = [
        _error_at(robot, simulate(robot, controller, Hold(tuple(xi0)), 0.4, dt=dt, integrator=integrator, xi0=xi0, **kw), ref, 0.392) for dt in steps
    ]
    return np.array(errors), np.log2(np.array(errors[:-1]) / errors[1:])


def test_rk4_is_fourth_order_for_the_base_too(free_robot):
    """Free tumbling: halving dt (8, 4, 2, 1 ms) divides the error of the whole state (base position and attitude
    included) by 16.  RK4 summing stage velocities taken at different points of the group without the inverse
    differential of the exponential was second order for the base (ratios 4)."""
    errors, orders = _orders(free_robot, ConstantTau(np.zeros(9)), XI0, "rk4", (8e-3, 4e-3, 2e-3, 1e-3), xi_dot0=2 * XID0, joint_stops=False)
    assert np.all(np.abs(orders - 4.0) < 0.2), (errors, orders)


def test_end_effector_hook_keeps_the_midpoint_second_order(robot):
    """A state-dependent end-effector wrench (spring-damper to a point) is re-evaluated at every stage: the midpoint
    rule stays second order (the wrench held over the step made it first order)."""
    data = robot.model.createData()

    def spring(t, q, v):
        J = pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame, pin.LOCAL_WORLD_ALIGNED)
        h = np.zeros(6)
        h[0:3] = -5.0 * (data.oMf[robot.ee_frame].translation - np.r_[0.3, 0.1, 1.2]) - 0.5 * (J @ v)[0:3]
        return h

    m, g = robot.params.total_mass, robot.params.g
    xi0 = np.r_[0, 0, 1, 0.05, -0.05, 0.3, 0.01, 2.9, 0.3]  # arm hanging: a stable pendulum (joint stops off)
    G = pin.computeGeneralizedGravity(robot.model, data, xi_to_qv(xi0, np.zeros(9))[0])
    tau = np.r_[0, 0, 1.05 * m * g, 0.01, -0.01, 0.005, G[6:9]]
    errors, orders = _orders(
        robot,
        ConstantTau(tau),
        xi0,
        "midpoint",
        (4e-3, 2e-3, 1e-3, 5e-4),
        external_wrench=spring,
        xi_dot0=np.r_[0.3, -0.2, 0.1, 0.3, -0.4, 0.2, 0.02, 0.5, -0.6],
        joint_stops=False,
    )
    assert np.all(np.abs(orders - 2.0) < 0.2), (errors, orders)


def test_far_from_the_origin_the_dynamics_do_not_change(robot):
    """Translation invariance: the same flight started 10 m and 1 km away gives the same velocities and attitude (ABA in
    the LOCAL convention does not see the base position) and positions shifted by the offset to round-off.  With the
    WORLD convention the accelerations lost precision with the distance (2e-10 m/s at 10 m, 2e-6 m/s at 1 km here)."""
    m, g = robot.params.total_mass, robot.params.g
    tau = np.r_[0, 0, 1.1 * m * g, 0.02, -0.03, 0.01, 0.5, 0.02, -0.005]
    xi0 = np.r_[0, 0, 0, 0.1, -0.2, 0.3, 0.01, 0.3, -0.4]
    # open loop, no stops: theta3 spins past 100 rad/s within the second (a fast state, not a runaway)
    kw = dict(xi_dot0=np.r_[0.5, -0.3, 0.2, 1.0, -2.0, 0.7, 0.05, 1.5, -2.0], joint_stops=False, limits=Limits(position=1e5, joint_velocity=math.inf))
    near = simulate(robot, ConstantTau(tau), Hold(tuple(xi0)), 1.0, xi0=xi0, **kw)
    for offset in (10.0, 1e3):
        far0 = xi0.copy()
        far0[0:3] += (offset, -offset, 0.5 * offset)
        far = simulate(robot, ConstantTau(tau), Hold(tuple(far0)), 1.0, xi0=far0, **kw)
        assert np.abs(far.xi_dot - near.xi_dot).max() < 1e-13  # measured 0 (bit-identical)
        assert np.abs(far.xi[:, 3:] - near.xi[:, 3:]).max() < 1e-13
        assert np.abs(far.xi[:, 0:3] - far0[0:3] - near.xi[:, 0:3]).max() < 1e-11 * offset  # measured 1.4e-12 m at 1 km


def test_midpoint_and_rk4_agree_in_closed_loop(robot):
    """On the static mission (first 16 s) the default integrator matches RK4 to well under a millimetre."""
    a = run("static-idc", platform=robot, duration=16.0)
    b = run("static-idc", platform=robot, duration=16.0, integrator="rk4")
    e = run("static-idc", platform=robot, duration=16.0, integrator="euler")
    assert np.abs(a.xi - b.xi)[:, 0:3].max() < 1e-5  # measured 1.1e-6 m
    assert np.abs(a.xi - b.xi)[:, 3:9].max() < 1e-5
    assert np.abs(e.xi - b.xi)[:, 0:3].max() > 1e-3  # semi-implicit Euler: 1.9 mm off


# ------------------------------------------------------------------------------ divergence
class NaNController(Controller):
    name = "nan"

    def step(self, t, state, ref):
        return np.full(9, np.nan) if t > 0.05 else np.r_[0, 0, 34.5, 0, 0, 0, 0, 0, 0]


def test_divergence_raises_with_time_and_state(robot):
    with pytest.raises(DivergenceError, match=r"t = 0\.0[5-9]\d* s") as err:
        simulate(robot, NaNController(), Hold((0, 0, 1, 0, 0, 0, 0, 0, 0)), 1.0, integrator="midpoint")
    res = err.value.result
    assert res.status == "diverged" and res.n < 100


def test_runaway_names_the_state(free_robot):
    """No gravity, no input, 10 m/s along x: the position bound stops the run and says which coordinate."""
    zero = OpenLoop(np.zeros(9))
    with pytest.raises(DivergenceError, match=r"t = 2\.0\d\d s: position x") as err:
        simulate(
            free_robot, zero, Hold((0.0,) * 9), 5.0, xi_dot0=np.r_[10.0, 0, 0, 0, 0, 0, 0, 0, 0], limits=Limits(position=20.0), integrator="midpoint"
        )
    assert err.value.result.status == "diverged"


def test_velocity_runaway_is_reported_at_the_tick_it_happened(free_robot):
    """No gravity, constant thrust: v_z grows by (f / M_eff) per second; the velocity bound stops the run at the end
    of the first tick whose v_z is beyond it, and the logged ticks stop there (the named check is screened by the
    next tick's State.update, the report is the same as a check at the end of the tick)."""
    m = free_robot.params.total_mass
    push = OpenLoop(np.r_[0, 0, 2.0 * m, 0, 0, 0, 0, 0, 0])  # about 2 m/s^2 up
    with pytest.raises(DivergenceError, match=r"diverged at t = (\d\.\d{3}) s: velocity v_z = ") as err:
        simulate(free_robot, push, Hold((0.0,) * 9), 3.0, limits=Limits(linear_velocity=1.0), integrator="midpoint")
    t_report = float(err.value.args[0].split("t = ")[1].split(" s")[0])
    res = err.value.result
    assert res.status == "diverged" and t_report == pytest.approx(res.n * 1e-3, abs=1e-9)
    assert 0.45 < t_report < 0.55  # 1 m/s at about 0.5 s
    vz_last = res.xi_dot[res.n - 1, 2]  # the last logged tick starts below the bound (world z = body z: level hold)
    assert 0.99 < vz_last < 1.0


# ------------------------------------------------------------------------------ hooks
def test_payload_changes_the_plant_copy_only(robot):
    """Hover with a 0.2 kg payload needs (m + m_p) g; at m g the system sinks at m_p g / (m + m_p)."""
    m, g, mp = robot.params.total_mass, robot.params.g, 0.2
    inertia_before = [robot.model.inertias[j].mass for j in range(robot.model.njoints)]
    xi = np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    sched = PayloadSchedule((PayloadChange(0.0, mp, (0.0, 0.0, 0.02)),))
    held = simulate(robot, OpenLoop(np.r_[0, 0, (m + mp) * g, 0, 0, 0, 0, 0, 0]), Hold(tuple(xi)), 1.0, payload=sched, integrator="midpoint")
    assert np.abs(held.xi - xi).max() < 1e-9
    np.testing.assert_allclose(held.f.sum(axis=1), (m + mp) * g)
    sink = simulate(robot, OpenLoop(np.r_[0, 0, m * g, 0, 0, 0, 0, 0, 0]), Hold(tuple(xi)), 1.0, payload=sched, integrator="midpoint")
    a = -mp * g / (m + mp)
    assert sink.xi[-1, 2] - 5.0 == pytest.approx(0.5 * a * sink.t[-1] ** 2, rel=1e-3)
    # a release at 0.5 s: from then on the same thrust lifts the lighter system
    drop = PayloadSchedule((PayloadChange(0.0, mp), PayloadChange(0.5, 0.0)))
    rel = simulate(robot, OpenLoop(np.r_[0, 0, (m + mp) * g, 0, 0, 0, 0, 0, 0]), Hold(tuple(xi)), 1.0, payload=drop, integrator="midpoint")
    assert abs(rel.xi[500, 2] - 5.0) < 1e-9 and rel.xi[-1, 2] - 5.0 == pytest.approx(0.5 * mp * g / m * 0.5**2, rel=2e-2)
    assert [robot.model.inertias[j].mass for j in range(robot.model.njoints)] == inertia_before
    with pytest.raises(InputError):
        PayloadChange(-1.0, 0.1)
    with pytest.raises(InputError):
        PayloadSchedule((PayloadChange(1.0, 0.1), PayloadChange(0.5, 0.0)))


def test_external_wrench_at_the_end_effector(robot):
    """A world-vertical pull of m g at the end effector (on the thrust axis at the zero pose) holds the unpowered system.

    The hook is evaluated at every integration stage: at t_k and t_k + dt/2 for the midpoint rule."""
    m, g = robot.params.total_mass, robot.params.g
    seen = []

    def pull(t, q, v):
        seen.append(t)
        return np.array([0.0, 0.0, m * g, 0.0, 0.0, 0.0])

    xi = np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    res = simulate(robot, OpenLoop(np.zeros(9)), Hold(tuple(xi)), 1.0, external_wrench=pull, integrator="midpoint")
    assert np.abs(res.xi - xi).max() < 1e-9 and len(seen) == 2 * res.n
    np.testing.assert_allclose(seen[0::2], res.t, atol=1e-15)
    np.testing.assert_allclose(seen[1::2], res.t + 0.5 * res.dt, atol=1e-15)
    with pytest.raises(InputError):
        simulate(robot, OpenLoop(np.zeros(9)), Hold(tuple(xi)), 0.01, external_wrench=lambda t, q, v: np.zeros(3), integrator="midpoint")


# ------------------------------------------------------------------------------ control period
class Counting(Controller):
    """Open loop that counts its calls and records the period it was reset with."""

    name = "counting"

    def __init__(self, u):
        self.u = np.asarray(u, dtype=float)
        self.calls = []

    def reset(self, state, ref, dt):
        self.period = dt

    def step(self, t, state, ref):
        self.calls.append(t)
        return self.u


def test_control_period_holds_the_controller_and_logs_one_row_per_tick(robot):
    xi = np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    u = _hover_u(robot, xi) + np.r_[0.3, 0, 0.5, 0, 0.01, 0, 0, 0, 0]
    ctrl = Counting(u)
    res = simulate(robot, ctrl, Hold(tuple(xi)), 0.2, dt=1e-3, control_period=4e-3)
    assert res.n == 50 and ctrl.period == 4e-3 and res.control_period == 4e-3 and res.dt == 1e-3
    np.testing.assert_allclose(ctrl.calls, np.arange(50) * 4e-3, atol=1e-15)
    np.testing.assert_allclose(res.t, np.arange(50) * 4e-3, atol=1e-15)
    # the default is one control call per integration step: the same run as an explicit control_period = dt
    a = simulate(robot, OpenLoop(u), Hold(tuple(xi)), 0.2, dt=1e-3)
    b = simulate(robot, OpenLoop(u), Hold(tuple(xi)), 0.2, dt=1e-3, control_period=1e-3)
    np.testing.assert_array_equal(a.xi, b.xi)
    assert a.control_period == a.dt == 1e-3
    for bad in (2.5e-3, 0.5e-3, -1.0):
        with pytest.raises(InputError, match="control_period"):
            simulate(robot, OpenLoop(u), Hold(tuple(xi)), 0.2, dt=1e-3, control_period=bad)


def test_noise_and_payload_changes_sit_on_the_control_grid(robot):
    """A noise sample is held over a control period; a release at 0.5021 s acts at the tick 0.504 s (control period 4 ms),
    whatever the integration step."""
    xi = np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    m, g, mp = robot.params.total_mass, robot.params.g, 0.2
    noisy = simulate(robot, OpenLoop(_hover_u(robot, xi)), Hold(tuple(xi)), 0.1, dt=1e-3, control_period=4e-3, disturbance=WhiteNoise(0.3))
    assert noisy.u_ext.shape == (25, 9) and len(np.unique(noisy.u_ext[:, 0])) == 25
    drop = PayloadSchedule((PayloadChange(0.0, mp), PayloadChange(0.5021, 0.0)))
    u = np.r_[0, 0, (m + mp) * g, 0, 0, 0, 0, 0, 0]
    for dt in (1e-3, 5e-4):
        res = simulate(robot, OpenLoop(u), Hold(tuple(xi)), 0.6, dt=dt, control_period=4e-3, payload=drop)
        k = int(round(0.504 / 4e-3))
        assert np.abs(res.xi[: k + 1, 2] - 5.0).max() < 1e-12 and res.xi[k + 1, 2] > 5.0 + 1e-7


def test_state_disturbance_drag_is_evaluated_at_every_stage(free_robot):
    """Linear drag -c v on the base, no gravity, no input, arm straight up (CoM on z_B), climbing along z: a pure
    translation with m_G v_z' = -c v_z, v_z(t) = v0 exp(-c t / m_G) (RK4 matches it to 1e-12)."""
    c, v0 = 0.8, 2.0
    xi = np.zeros(9)
    res = simulate(
        free_robot,
        OpenLoop(np.zeros(9)),
        Hold(tuple(xi)),
        1.0,
        dt=1e-3,
        integrator="rk4",
        xi0=xi,
        xi_dot0=np.r_[0, 0, v0, 0, 0, 0, 0, 0, 0],
        disturbance=BaseDrag(linear=c),
    )
    mG = free_robot.params.total_mass
    np.testing.assert_allclose(res.xi_dot[:, 2], v0 * np.exp(-c * res.t / mG), rtol=1e-12)
    assert np.abs(res.xi_dot[:, [0, 1, 3, 4, 5, 6, 7, 8]]).max() < 1e-14
    with pytest.raises(InputError):
        BaseDrag(linear=-1.0)


# ------------------------------------------------------------------------------ results, disturbances
def test_result_save_load_and_rmse(robot, tmp_path):
    res = run("static-idc", platform=robot, duration=3.0)
    path = res.save(tmp_path / "r.npz")
    back = SimResult.load(path)
    for name in ("t", "xi", "xi_d", "u", "f", "arm_effort", "x_cm", "unallocated", "flags", "u_ext"):
        np.testing.assert_array_equal(getattr(back, name), getattr(res, name))
    assert back.control_period == res.control_period == res.dt
    assert back.scenario == "static-idc" and back.controller == "idc" and back.status == "ok"
    e = res.xi_d - res.xi
    assert res.rmse()["z"] == pytest.approx(np.sqrt(np.mean(e[:, 2] ** 2)))
    with pytest.raises(InputError):
        res.save(tmp_path / "r.txt")


def test_noise_is_seeded_and_bounded_and_pulses_are_timed():
    t = np.arange(1000) * 1e-3
    a = WhiteNoise(0.3).values(t, np.random.default_rng(5), 9)
    b = WhiteNoise(0.3).values(t, np.random.default_rng(5), 9)
    c = WhiteNoise(0.3).values(t, np.random.default_rng(6), 9)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c) and np.abs(a).max() <= 0.3 and np.abs(a).max() > 0.29
    held = WhiteNoise(0.3, sample_time=0.1).values(t, np.random.default_rng(5), 9)
    assert len(np.unique(held[:, 0])) == 10
    p = Pulse(0.2, 0.4, (0, 0, 5.0, 0, 0, 0, 0, 0, 0)).values(t)
    assert p[199, 2] == 0 and p[200, 2] == 5.0 and p[399, 2] == 5.0 and p[400, 2] == 0
    with pytest.raises(InputError):
        Pulse(1.0, 0.5, (0,) * 9)
    with pytest.raises(InputError):
        WhiteNoise(-1.0)


def test_bad_simulation_arguments(robot):
    ctrl = OpenLoop(np.zeros(9))
    with pytest.raises(UnknownNameError, match="midpoint"):
        simulate(robot, ctrl, Hold((0.0,) * 9), 1.0, integrator="verlet")
    with pytest.raises(InputError):
        simulate(robot, ctrl, Hold((0.0,) * 9), 1.0, dt=-1.0, integrator="midpoint")
    with pytest.raises(InputError):
        simulate(robot, object(), Hold((0.0,) * 9), 1.0, integrator="midpoint")


def test_progress_bar_on_stderr(robot, capsys):
    simulate(robot, OpenLoop(_hover_u(robot, np.zeros(9))), Hold((0.0,) * 9), 0.2, progress=True, integrator="midpoint")
    err = capsys.readouterr().err  # capsys's stderr is no terminal: plain lines, the last at 100 %
    assert "\r" not in err and "custom/open-loop: 200/200 (100%)" in err.splitlines()[-1]


# ------------------------------------------------------------------------------ configuration
def test_settings_as_keywords_or_as_objects_give_the_same_run(robot):
    """simulate's keyword settings are SimConfig / SimInputs fields: either form gives the same run bit for bit, a keyword
    overrides the object, an unknown keyword names the valid ones."""
    xi = np.r_[0, 0, 5, 0, 0, 0, 0, 0, 0]
    ctrl = OpenLoop(_hover_u(robot, xi) + np.r_[0.2, 0, 0.3, 0, 0.01, 0, 0, 0, 0])
    noise = WhiteNoise(0.05)
    a = simulate(robot, ctrl, Hold(tuple(xi)), 0.1, dt=2e-3, integrator="rk4", seed=3, disturbance=noise, xi_dot0=np.r_[0.1, 0, 0, 0, 0, 0, 0, 0, 0])
    cfg = SimConfig(dt=2e-3, integrator="euler", seed=3)
    inputs = SimInputs(disturbance=noise, xi_dot0=np.r_[0.1, 0, 0, 0, 0, 0, 0, 0, 0])
    b = simulate(robot, ctrl, Hold(tuple(xi)), 0.1, config=cfg, inputs=inputs, integrator="rk4")
    for name in ("xi", "xi_dot", "u", "f", "u_ext"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.integrator == b.integrator == "rk4" and a.dt == b.dt == 2e-3 and np.any(a.u_ext)
    with pytest.raises(UnknownNameError, match="'dtt'.*valid.*dt.*xi0"):
        simulate(robot, ctrl, Hold(tuple(xi)), 0.1, dtt=1e-3)


def test_config_is_validated_once_with_named_errors():
    assert SimConfig().dt == SimConfig.dt == 1e-3 and SimConfig().period == 1e-3 and SimConfig().substeps == 1
    assert SimConfig(dt=1e-3, control_period=4e-3).substeps == 4
    for kwargs, pattern in [
        ({"dt": 0.0}, "dt must be a positive number"),
        ({"dt": float("nan")}, "dt must"),
        ({"dt": "1ms"}, "dt must"),
        ({"control_period": 2.5e-3}, "integer multiple of dt"),
        ({"seed": -1}, "seed"),
        ({"limits": (1, 2)}, "limits must be a qprr.sim.Limits"),
        ({"joint_stops": 1}, "joint_stops must be True or False"),
        ({"max_log_bytes": -5}, "max_log_bytes"),
    ]:
        with pytest.raises(InputError, match=pattern):
            SimConfig(**kwargs)
    with pytest.raises(UnknownNameError, match="integrator"):
        SimConfig(integrator="verlet")


def test_scenarios_take_the_step_from_the_simulation_config():
    """One home for the default step: every scenario offering a dt option defaults to SimConfig.dt."""
    with_dt = [s for s in SCENARIOS.values() if "dt" in s.options]
    assert with_dt and all(s.options["dt"].default == SimConfig.dt for s in with_dt)


def test_a_run_whose_logs_cannot_fit_is_refused_before_allocating(robot):
    """duration = 1e12 s at dt = 1 ms: 1e15 ticks, an exbibyte of logs: an InputError naming the duration, the step and the
    size, at once (no MemoryError); the same with an explicit, small bound on the logs."""
    ctrl = OpenLoop(np.zeros(9))
    with pytest.raises(InputError, match=r"duration = 1000000000000\.0 s .*dt = 0\.001 s.* 1e\+15 control ticks.* EiB") as err:
        simulate(robot, ctrl, Hold((0.0,) * 9), 1e12)
    assert "max_log_bytes" in str(err.value)
    with pytest.raises(InputError, match=r"duration = 20\.0 s .*control period of 0\.004 s.*MiB, more than the 1 MiB allowed"):
        simulate(robot, ctrl, Hold((0.0,) * 9), 20.0, control_period=4e-3, max_log_bytes=2**20)
    res = simulate(robot, OpenLoop(_hover_u(robot, np.zeros(9))), Hold((0.0,) * 9), 0.1, max_log_bytes=2**20)  # 100 ticks fit
    assert res.n == 100
    with pytest.raises(InputError, match="duration must be a number of seconds >= the control period"):
        simulate(robot, ctrl, Hold((0.0,) * 9), 1e-4)
