"""Operational-space impedance (Thesis (6.72)-(6.73)) on the inverse-dynamics core: the law against Khatib's form with
Lambda, mu, p of (5.51)-(5.52), static deflection K^-1 h, natural frequency and damping of the end-effector response
(and their first-order convergence in the control period), free-space tracking against the IDC, the ee-impedance scenario."""

from __future__ import annotations

import numpy as np
import pytest

import qprr
from qprr import charts as ch
from qprr.actuation import AllocationFlag
from qprr.analysis import opspace_model_xi
from qprr.charts import State
from qprr.control import InverseDynamicsController, make_controller
from qprr.control.base import Reference
from qprr.control.gains import platform_gains
from qprr.control.opspace_impedance import EndEffectorImpedance, OperationalSpaceImpedance, fit_second_order
from qprr.dynamics.friction import JointFriction
from qprr.errors import InputError, UnknownNameError
from qprr.kinematics import ee_pose_xi
from qprr.sim import simulate
from qprr.sim.contact import PrescribedWrench
from qprr.trajectory import Hold, hover_and_reach


def _platform(name):
    return qprr.build(name) if name.isupper() else qprr.load(name)


def _hover(p, fraction=0.3):
    q0 = p.neutral_q()[7:]
    hi = np.where(np.isfinite(p.arm_upper), p.arm_upper, q0 + 1.0)
    return np.concatenate([[0.0, 0.0, 2.0, 0.0, 0.0, 0.0], q0 + fraction * (hi - q0)])


def _push(p, imp, force, *, t_on=0.2, duration=3.0, dt=1e-3, xi0=None, sensor=True, **kwargs):
    """Hover with a constant force on the end effector from t_on; returns (controller history, result)."""
    xi0 = _hover(p) if xi0 is None else xi0
    env = PrescribedWrench(np.concatenate([force, np.zeros(3)]), t_on)
    c = OperationalSpaceImpedance(p, imp, ee_sensor=env.measured if sensor else None, **kwargs)
    res = simulate(p, c, Hold(tuple(xi0)), duration, dt=dt, external_wrench=env)
    return c.history(), res


# ------------------------------------------------------------------------------ the law
def test_fully_actuated_law_is_khatibs_with_the_operational_space_model():
    """Every coordinate free, inertia weighting, no damping: tau = J^T (Lambda a* + mu + p) + N^T tau_0 - J^T h with
    Lambda, mu, p of opspace_model_xi (position rows), N^T = I - J^T J_bar^T and tau_0 the IDC's output (B alpha_0 + n)."""
    p = qprr.load("hextilt_flying_arm_5")
    rng = np.random.default_rng(3)
    for _ in range(3):
        xi = np.concatenate([rng.uniform(-1, 1, 3), rng.uniform(-0.3, 0.3, 3), rng.uniform(0.5 * p.arm_lower, 0.5 * p.arm_upper)])
        xd = 0.3 * rng.normal(size=p.n_xi)
        h = np.concatenate([rng.normal(size=3), 0.1 * rng.normal(size=3)])
        ref = Reference(xi + 0.02 * rng.normal(size=p.n_xi), 0.1 * rng.normal(size=p.n_xi), 0.1 * rng.normal(size=p.n_xi))
        st = State(p.n_arm)
        st.update(0.0, *ch.xi_to_qv(xi, xd))
        imp = EndEffectorImpedance(np.diag([30.0, 20.0, 40.0]) + 5.0, [6.0, 5.0, 7.0], np.diag([0.8, 1.0, 1.3]))
        c = OperationalSpaceImpedance(p, imp, ee_sensor=lambda t, h=h: h, weighting="inertia", damping=0.0)
        c.reset(st, ref, 1e-3)
        tau = c.step(0.0, st, ref)
        idc = InverseDynamicsController(p, c.gains)
        idc.reset(st, Reference(ref.xi.copy(), ref.xi_dot.copy(), ref.xi_ddot.copy()), 1e-3)
        tau0 = idc.step(0.0, st, Reference(ref.xi.copy(), ref.xi_dot.copy(), ref.xi_ddot.copy()))
        m = opspace_model_xi(p, p.data(), xi, xd, rows="position")
        J = m.J_v[0:3]  # Pinocchio's LOCAL_WORLD_ALIGNED Jacobian, position rows
        Jbar = np.linalg.solve(m.M, J.T) @ m.Lambda
        p_e, _ = ee_pose_xi(p, p.data(), ref.xi)
        hist = c.history()
        assert np.allclose(hist["p_r"][-1], p_e, atol=1e-12)
        a_star = hist["a_star"][-1]
        e, e_dot = hist["e"][-1], m.velocity[0:3] - _ref_velocity(p, ref)
        assert np.allclose(a_star, _ref_acc(p, ref) + np.linalg.solve(imp.mass, h[0:3] - imp.damping @ e_dot - imp.stiffness @ e), atol=1e-10)
        # the URDF's joint friction is compensated in full at the reference arm rates (qprr.dynamics.friction), outside the projection
        ff = -JointFriction.from_model(p.model).generalized_force(np.r_[np.zeros(6), ref.xi_dot[6:]])
        khatib = J.T @ (m.Lambda @ a_star + m.mu + m.p) + (np.eye(p.nv) - J.T @ Jbar.T) @ (tau0 - ff) + ff - _J6(p, xi).T @ h
        assert np.abs(tau - khatib).max() < 1e-9 * max(1.0, np.abs(tau).max())


def _J6(p, xi):
    import pinocchio as pin

    return pin.computeFrameJacobian(p.model, p.data(), ch.xi_to_q(xi), p.ee_frame, pin.LOCAL_WORLD_ALIGNED)


def _ref_velocity(p, ref):
    return (_J6(p, ref.xi) @ ch.xi_dot_to_v(ref.xi, ref.xi_dot))[0:3]


def _ref_acc(p, ref):
    import pinocchio as pin

    d = p.data()
    q, v = ch.xi_to_qv(ref.xi, ref.xi_dot)
    pin.forwardKinematics(p.model, d, q, v, ch.xi_ddot_to_a(ref.xi, ref.xi_dot, ref.xi_ddot))
    return pin.getFrameClassicalAcceleration(p.model, d, p.ee_frame, pin.LOCAL_WORLD_ALIGNED).linear.copy()


@pytest.mark.parametrize("name", ["q-prr", "hextilt_flying_arm_5"])
def test_realised_end_effector_acceleration_is_the_task(name):
    """One control step at a random hover state: the acceleration the plant realises (ABA with the controller's tau
    and the measured wrench) moves the end effector by a* along every direction the task coordinates reach."""
    import pinocchio as pin

    p = qprr.load(name).without_joint_friction()  # the law of a frictionless arm (joint friction: tests/test_friction.py)
    rng = np.random.default_rng(5)
    for _ in range(4):
        xi = _hover(p, rng.uniform(0.1, 0.5))
        xi[5] = rng.uniform(-np.pi, np.pi)
        if name != "q-prr":
            xi[3:5] = rng.uniform(-0.05, 0.05, 2)
        xd = 0.05 * rng.normal(size=p.n_xi)
        h = np.concatenate([rng.normal(size=3), np.zeros(3)])
        c = OperationalSpaceImpedance(p, EndEffectorImpedance.from_frequency(4.0, 0.5, 1.0), ee_sensor=lambda t, h=h: h)
        st = State(p.n_arm)
        q, v = ch.xi_to_qv(xi, xd)
        st.update(0.0, q, v)
        ref = Reference(_hover(p), np.zeros(p.n_xi), np.zeros(p.n_xi))
        c.reset(st, ref, 1e-3)
        tau = c.step(0.0, st, ref)
        assert np.abs(tau[c._lost]).max(initial=0.0) < 1e-10  # producible by the rotors
        a = pin.aba(p.model, p.data(), q, v, tau + _J6(p, xi).T @ h)
        d = p.data()
        pin.forwardKinematics(p.model, d, q, v, a)
        acc = pin.getFrameClassicalAcceleration(p.model, d, p.ee_frame, pin.LOCAL_WORLD_ALIGNED).linear
        a_star = c.history()["a_star"][-1]
        if c.tilt is None:
            assert np.allclose(acc, a_star, atol=1e-4 * np.abs(a_star).max())  # the inverse's damping only
        else:  # level Q-PRR: its arm moves in the x-z plane of B, z also by the thrust; sideways (y of B) is the hover's
            served = np.array([[np.cos(xi[5]), np.sin(xi[5]), 0.0], [0.0, 0.0, 1.0]])
            assert np.allclose(served @ acc, served @ a_star, atol=1e-4 * np.abs(a_star).max())


# ------------------------------------------------------------------------------ statics and dynamics in simulation
@pytest.mark.parametrize("name", ["hextilt_flying_arm_5", "q-prr"])
def test_static_deflection_is_K_inverse_h(name):
    """A constant force: the end effector settles at e = K^-1 h (full SPD K on the fully actuated hexarotor, to 1e-4).  On the
    Q-PRR along its arm's plane (x to 1e-4; z to 1 %: the roll that holds h_y tilts that plane by h_y / (m g) = 0.5 deg and
    the unserved sideways residual leaks into z by that angle), while sideways the hover loop holds the base and the end
    effector moves only with that lean (2.2 mm here, 15 % of K^-1 h_y)."""
    p = qprr.load(name).without_joint_friction()  # the law of a frictionless arm (joint friction: tests/test_friction.py)
    if name == "q-prr":
        K = np.diag([20.0, 20.0, 30.0])
    else:
        K = np.array([[30.0, 5.0, 0.0], [5.0, 20.0, -4.0], [0.0, -4.0, 25.0]])
    w, V = np.linalg.eigh(K)
    imp = EndEffectorImpedance(K, 2.0 * (V * np.sqrt(w)) @ V.T, np.eye(3))  # D = 2 K^(1/2): every mode critically damped
    h = np.array([0.4, -0.3, 0.5])
    hist, res = _push(p, imp, h, duration=6.0)
    assert not np.any(res.flags & (AllocationFlag.ROTOR_SATURATED | AllocationFlag.JOINT_STOP))  # no rotor bound, no joint stop
    e = hist["e"][-1]
    target = imp.deflection(h)
    if name == "q-prr":
        assert abs(e[0] - target[0]) < 1e-4 * abs(target[0]) and abs(e[2] - target[2]) < 1e-2 * abs(target[2])
        assert abs(e[1]) < 0.2 * abs(target[1])
    else:
        assert np.abs(e - target).max() < 1e-4 * np.abs(target).max()


def test_sensorless_static_deflection_and_apparent_mass_lambda():
    """Without a sensor (M_d = Lambda of the free system, Khatib's inertia weighting) the static deflection is still
    K^-1 h (fully actuated platform; its lightest end-effector direction weighs 15 g here, so D / Lambda = 500 1/s)."""
    p = qprr.load("hextilt_flying_arm_5").without_joint_friction()  # the law of a frictionless arm (joint friction: tests/test_friction.py)
    imp = EndEffectorImpedance(16.0, 8.0, None)
    h = np.array([0.3, 0.2, -0.3])
    hist, res = _push(p, imp, h, duration=5.0, sensor=False, weighting="inertia")
    assert np.abs(hist["h"]).max() == 0.0
    assert np.abs(hist["e"][-1] - h / 16.0).max() < 1e-4 * np.abs(h / 16.0).max()
    with pytest.raises(InputError, match="needs the contact force"):
        OperationalSpaceImpedance(p, EndEffectorImpedance.from_frequency(4.0))


def _fit(hist, axis, t_on):
    k = hist["t"] >= t_on - 1e-12
    return fit_second_order(hist["t"][k] - hist["t"][k][0], hist["e"][k, axis])


def test_natural_frequency_and_damping_converge_at_first_order_in_the_control_period():
    """Fully actuated hexarotor, force step along x: the fitted (omega_n, zeta) approach the impedance's (4 rad/s, 0.3)
    with the control period (zero-order hold): errors at 1 ms 6e-5 and 2.8e-3 (relative), halved at 0.5 ms (order 1)."""
    p = qprr.load("hextilt_flying_arm_5").without_joint_friction()  # the law of a frictionless arm (joint friction: tests/test_friction.py)
    imp = EndEffectorImpedance.from_frequency(4.0, 0.3, 1.0)
    errs = []
    for dt in (1e-3, 5e-4):
        hist, res = _push(p, imp, np.array([0.5, 0.0, 0.0]), duration=3.0, dt=dt)
        w, z, y_inf = _fit(hist, 0, 0.2)
        errs.append((abs(w - 4.0) / 4.0, abs(z - 0.3) / 0.3))
        assert abs(y_inf - 0.5 / 16.0) < 1e-3 * 0.5 / 16.0
    (ew1, ez1), (ew2, ez2) = errs
    assert ew1 < 2e-4 and ez1 < 5e-3
    assert 1.6 < ew1 / ew2 < 2.5 and 1.6 < ez1 / ez2 < 2.5


@pytest.mark.parametrize("axis", [0, 2])
def test_q_prr_step_response_along_the_arm_plane(axis):
    """Q-PRR (coplanar rotors, tilt strategy), force step along x or z: omega_n and zeta of the fitted response within
    1 % of the impedance's, and the whole response within 1 % of its peak from the ideal model driven by the same force."""
    p = qprr.load("q-prr")
    imp = EndEffectorImpedance.from_frequency(4.0, 0.3, 1.0)
    f = np.zeros(3)
    f[axis] = 0.5
    xi0 = np.concatenate([[0.0, 0.0, 2.0, 0.0, 0.0, 0.0], [0.0, 1.0, -0.5]])
    hist, res = _push(p, imp, f, duration=3.0, xi0=xi0)
    w, z, _ = _fit(hist, axis, 0.2)
    assert abs(w - 4.0) < 0.01 * 4.0 and abs(z - 0.3) < 0.01 * 0.3
    ideal, _ = imp.response(hist["t"], hist["h"])
    assert np.abs(hist["e"][:, axis] - ideal[:, axis]).max() < 0.01 * np.abs(ideal[:, axis]).max()


# ------------------------------------------------------------------------------ free space
@pytest.mark.parametrize("name", ["q-prr", "hextilt_flying_arm_5"])
def test_free_space_tracks_like_the_idc(name):
    """No contact, a climb-and-reach mission: the same xi tracking as the IDC once the motion ends, and the end effector
    on its path at least as well (the Q-PRR's arm takes out, in its plane, the motion the tilt gives the end effector)."""
    p = qprr.load(name).without_joint_friction()  # frictionless arm (joint friction: tests/test_friction.py)
    traj = hover_and_reach(p, (0.5, 0.3, 1.0), climb=(0.0, 2.0), reach=(2.0, 3.5))
    out = {}
    for label, c in (
        ("idc", InverseDynamicsController(p)),
        ("ops", OperationalSpaceImpedance(p, EndEffectorImpedance.from_frequency(4.0, 1.0, 1.0), ee_sensor=lambda t: np.zeros(6))),
    ):
        res = simulate(p, c, traj, 5.0)
        assert not np.any(res.flags & (AllocationFlag.ROTOR_SATURATED | AllocationFlag.JOINT_STOP))
        d = p.data()
        ee = np.array([ee_pose_xi(p, d, x)[0] for x in res.xi])
        xr = res.xi_d.copy()
        xr[:, 3:5] = 0.0  # the mission's own roll and pitch
        ee_r = np.array([ee_pose_xi(p, d, x)[0] for x in xr])
        err = res.xi_d - res.xi
        err[:, 3:6] = ch.wrap_angle(err[:, 3:6])
        keep = [i for i in range(p.n_xi) if i not in (3, 4)]
        out[label] = (np.sqrt(((ee - ee_r) ** 2).mean(axis=0)), np.abs(err[-1, keep]).max())
    (ee_idc, final_idc), (ee_ops, final_ops) = out["idc"], out["ops"]
    assert final_ops < 1e-3 and final_idc < 1e-3
    if name == "q-prr":
        assert ee_ops[0] < 0.05 * ee_idc[0] and ee_ops[2] < 0.5 * ee_idc[2]
        assert ee_ops[1] < 1.05 * ee_idc[1]  # sideways: the hover loop, as the IDC
    else:
        assert np.linalg.norm(ee_ops) < 1e-3 and np.linalg.norm(ee_idc) < 1e-3


# ------------------------------------------------------------------------------ pieces and input checks
def test_ideal_response_and_fit_on_the_closed_form():
    imp = EndEffectorImpedance.from_frequency([3.0, 5.0, 2.0], [0.2, 0.5, 0.7], [1.0, 0.5, 2.0])
    assert np.allclose(np.sort(imp.natural_frequency()), [2.0, 3.0, 5.0])
    assert np.allclose(imp.damping_ratio(), [0.2, 0.5, 0.7])
    t = np.arange(0, 6, 1e-3)
    h = np.tile([1.0, 1.0, 1.0], (t.size, 1))
    e, _ = imp.response(t, h)
    for i, (w, z, m) in enumerate(((3.0, 0.2, 1.0), (5.0, 0.5, 0.5), (2.0, 0.7, 2.0))):
        wd = w * np.sqrt(1 - z * z)
        y_inf = 1.0 / (m * w * w)
        closed = y_inf * (1 - np.exp(-z * w * t) * (np.cos(wd * t) + z * w / wd * np.sin(wd * t)))
        assert np.abs(e[:, i] - closed).max() < 1e-12 * y_inf  # row k: the state at t_k, h[k] held over [t_k, t_k+1)
        wf, zf, yf = fit_second_order(t, closed)
        assert abs(wf - w) < 1e-6 * w and abs(zf - z) < 1e-6 and abs(yf - y_inf) < 1e-6 * y_inf


def test_input_errors():
    p = qprr.load("q-prr")
    with pytest.raises(InputError, match="stiffness"):
        EndEffectorImpedance([1.0, -1.0, 1.0], 1.0, 1.0)
    with pytest.raises(InputError, match="symmetric"):
        EndEffectorImpedance([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 1.0)
    with pytest.raises(InputError, match="damping_ratio"):
        EndEffectorImpedance(np.array([[2.0, 0.5, 0.0], [0.5, 2.0, 0.0], [0.0, 0.0, 1.0]]), 1.0, 1.0).damping_ratio()
    with pytest.raises(UnknownNameError):
        OperationalSpaceImpedance(p, weighting="heaviest")
    with pytest.raises(UnknownNameError):
        OperationalSpaceImpedance(p, coordinates=["z", "elbow"])
    with pytest.raises(InputError, match="ee_sensor"):
        OperationalSpaceImpedance(p, ee_sensor=np.zeros(6))
    c = OperationalSpaceImpedance(p, coordinates=["z", "theta2", 8])
    assert c.coordinates == (2, 7, 8)
    with pytest.raises(InputError, match=r"unknown keyword argument\(s\) \['at'\]"):  # the core is at the measured state
        OperationalSpaceImpedance(p, at="desired")
    c = OperationalSpaceImpedance(p, tilt="single", output="xi", name="ops-single")  # options of the core pass on
    assert (c.tilt_mode, c.output, c.name, c.realizable) == ("single", "xi", "ops-single", True)
    assert OperationalSpaceImpedance(p).impedance.mass is None  # the class's default: the natural inertia, no sensor
    # make_controller's default is the platform-derived impedance, whose desired mass needs the contact force
    with pytest.raises(InputError, match="ee_sensor"):
        make_controller("opspace-impedance", p)
    derived = platform_gains("opspace-impedance", p)["impedance"]
    c = make_controller("opspace-impedance", p, ee_sensor=lambda t: np.zeros(6))
    np.testing.assert_array_equal(c.impedance.stiffness, derived.stiffness)
    np.testing.assert_array_equal(c.impedance.mass, derived.mass)


# ------------------------------------------------------------------------------ scenario
def test_ee_impedance_scenario_and_figure(tmp_path):
    """The generic scenario on a coplanar hexarotor: the wall stops the end effector where K e = h (two springs in series),
    and the figure is written."""
    from qprr import scenarios
    from qprr.scenarios.impedance import plot_ee_impedance, steady_state

    res = scenarios.run("ee-impedance", platform=_platform("HEX-RRR"), t_on=0.5, t_off=3.5, duration=6.0)
    d = steady_state(res, 3.5 - res.dt)
    assert d["h"][0] < -0.5  # in contact
    assert np.abs(d["e"] - d["predicted"]).max() < 2e-3 * np.abs(d["predicted"]).max()
    assert plot_ee_impedance(res, tmp_path / "ee.png").stat().st_size > 10_000
    assert any("K^-1 h" in line for line in scenarios.get_scenario("ee-impedance").summary(res))


def test_printed_6_73_is_an_end_effector_acceleration_and_damps_the_velocity():
    """(6.73) as printed, y = T_A^-1 M_d^-1 (M_d chi_ddot_d + K_D chi_dot + K_P chi_tilde - M_d J_A_dot xi_dot - h_A), has the
    6 rows of chi_e, while (6.72) multiplies y by the 9 x 9 B of the Q-PRR: the inverse of J_A (Siciliano-Villani's
    y = J_A^-1 M_d^-1 (...); for a 6 x 9 J_A a generalised one, the task of OperationalSpaceImpedance) is missing.  Its
    damping acts on chi_dot, not on the error rate: at zero error with the reference moving at v it asks for
    M_d^-1 K_D v instead of the reference's acceleration (0 here); the law here uses e_dot (a* = 0 there: see
    test_fully_actuated_law_is_khatibs_with_the_operational_space_model for a*)."""
    from qprr.dynamics import dynamics_xi

    p = qprr.load("q-prr")
    xi = _hover(p)
    B, _, _ = dynamics_xi(p, p.data(), xi, np.zeros(p.n_xi))
    phi_e = np.array([0.1, -0.2, 0.3])
    T_A = np.eye(6)
    T_A[3:6, 3:6] = ch.euler_rate_matrix(phi_e)
    M_d, K_D = 0.5 * np.eye(6), 2.0 * np.eye(6)  # the K_P chi_tilde term vanishes at zero error
    v = np.array([0.1, 0.0, -0.05, 0.0, 0.0, 0.0])  # reference rate, error and its rate zero, no wrench
    y_printed = np.linalg.solve(T_A, np.linalg.solve(M_d, K_D @ v))
    assert y_printed.shape == (6,) and B.shape == (9, 9)
    with pytest.raises(ValueError):
        B @ y_printed
    assert np.allclose(y_printed[0:3], [0.4, 0.0, -0.2])  # M_d^-1 K_D v: 0.4 m/s^2 where the reference does not accelerate
