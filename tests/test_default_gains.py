"""make_controller's default gains are derived from the platform (qprr.control.gains), and they fly:
exact pole placement of the arm from an offset, convergence from a base offset, the motor-lag
scenario through 5 and 10 ms rotors, the MFC on the turret of examples/my_platform."""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest
from scipy.linalg import expm

import qprr
from qprr.charts import rate_map
from qprr.control import IDCGains, ImpedanceGains, MFCGains, make_controller
from qprr.control.gains import (
    GAIN_ARGUMENTS,
    MFC_EIGENVALUE,
    ROTOR_LAG_ATTITUDE,
    ROTOR_LAG_FILTER,
    Authority,
    Targets,
    bandwidths,
    platform_gains,
)
from qprr.errors import InputError
from qprr.platforms import load
from qprr.scenarios import missions
from qprr.sim import simulate
from qprr.trajectory import Hold, hover_and_reach

MY = "examples/my_platform/"
PLATFORMS = {
    "q-prr": lambda: load("q-prr"),
    "borinot_flying_arm_2": lambda: load("borinot_flying_arm_2"),
    "HEX-RRR": lambda: qprr.build("HEX-RRR"),
}


@pytest.fixture(scope="module", params=list(PLATFORMS))
def platform(request):
    return PLATFORMS[request.param]()


@pytest.fixture(scope="module")
def quad():
    return qprr.from_urdf(MY + "quad_rrr.urdf", MY + "quad_rrr.rotors.toml", ee_frame="gripper")


def _no_force(t):
    return np.zeros(6)


def test_make_controller_defaults_to_the_platform_gains(platform):
    """Every controller with derived gains gets exactly platform_gains(name, platform); an explicit argument replaces only itself."""
    for name, args in GAIN_ARGUMENTS.items():
        extra = {"ee_sensor": _no_force} if name == "opspace-impedance" else {}
        ctrl = make_controller(name, platform, **extra)
        derived = platform_gains(name, platform)
        for arg in args:
            got, want = getattr(ctrl, "gains" if arg == "gains" else "impedance"), derived[arg]
            if arg == "impedance" and name == "opspace-impedance":
                for field in ("stiffness", "damping", "mass"):
                    np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
            elif name == "mfc":  # the controller stores the gains resolved to the platform: same values
                assert got == want.resolved(platform.n_xi)
            else:
                assert got == want, (name, arg)
    fixed = IDCGains.default(platform.n_arm)
    assert make_controller("idc", platform, gains=fixed).gains == fixed
    imp = make_controller("impedance", platform, gains=fixed)
    assert imp.gains == fixed and imp.impedance == platform_gains("impedance", platform)["impedance"]
    own = ImpedanceGains()
    imp = make_controller("impedance", platform, impedance=own)
    assert imp.impedance == own and imp.gains == platform_gains("impedance", platform)["gains"]
    assert make_controller("mfc", platform, gains=MFCGains()).gains == MFCGains().resolved(platform.n_xi)


def test_opspace_impedance_default_needs_the_contact_force(platform):
    """The derived end-effector impedance has a desired mass m / ratio^2: without ee_sensor the class says what to give."""
    with pytest.raises(InputError, match="ee_sensor"):
        make_controller("opspace-impedance", platform)


@pytest.mark.parametrize("integral", [False, True], ids=["pd", "integral"])
def test_arm_offset_decays_as_the_placed_poles_first_order_in_dt(platform, integral):
    """IDC at the derived gains, hover with the last arm joint 0.02 off.  PD (``integral = false``): e(t) = e0 (1 + w t)
    exp(-w t) with w the derived arm bandwidth; with integral action (the default): the error of the placed poles
    (s + w)^2 (s + w / 10) from e0 with a zero integral, [0 1 0] expm(A t) (0, e0, 0) with A the companion matrix of
    s^3 + k_D s^2 + k_P s + k_I.  The only deviation is the control's zero-order hold, first order in dt (ratio 4 for
    dt / 4)."""
    xi = platform.neutral_xi().copy()
    xi[2] = 2.0
    j = 5 + platform.n_arm
    targets = Targets(integral=integral)
    w = bandwidths(Authority.from_platform(platform), targets)[j]
    g = platform_gains("idc", platform, targets)["gains"]
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-g.ki[j], -g.kp[j], -g.kd[j]]])  # state (int e, e, e')
    x0 = xi.copy()
    x0[j] += 0.02
    dev = []
    for dt in (1e-3, 2.5e-4):
        r = simulate(platform, make_controller("idc", platform, gains=g), Hold(tuple(xi)), 1.0, xi0=x0, dt=dt)
        if integral:
            closed = np.array([(expm(A * t) @ [0.0, 0.02, 0.0])[1] for t in r.t])
        else:
            closed = 0.02 * (1.0 + w * r.t) * np.exp(-w * r.t)
        dev.append(np.abs(r.xi[:, j] - xi[j] - closed).max() / 0.02)
        assert dev[-1] < w * dt, (dt, dev[-1], w * dt)  # the hold delays u by dt / 2 on average
    assert 3.6 < dev[0] / dev[1] < 4.4, dev


def test_hover_from_a_base_and_arm_offset_converges(platform):
    """From 0.1 m off in x and y and every arm joint 0.02 off, the IDC with the derived PD gains settles on the hover
    reference in 8 s without overshooting; with the default gains (integral action) in 16 s (the integral poles, w / 2
    on position and w / 10 on the arm, are the slow ones)."""
    xi = platform.neutral_xi().copy()
    xi[2] = 2.0
    x0 = xi.copy()
    x0[0] += 0.1
    x0[1] -= 0.1
    x0[6:] += 0.02
    pd = platform_gains("idc", platform, Targets(integral=False))["gains"]
    r = simulate(platform, make_controller("idc", platform, gains=pd), Hold(tuple(xi)), 8.0, xi0=x0)
    assert r.status == "ok"
    assert np.abs(r.xi[-1] - xi).max() < 1e-6
    assert np.abs(r.xi[:, 0:3] - xi[0:3]).max() < 0.105  # no overshoot beyond 5 % of the offset
    r = simulate(platform, make_controller("idc", platform), Hold(tuple(xi)), 16.0, xi0=x0)
    assert r.status == "ok"
    assert np.abs(r.xi[-1] - xi).max() < 1e-6


# ------------------------------------------------------------------------------------------- motor lag
MOTOR_LAG = dict(
    duration=14.0,  # the default gains' integral poles are the slow ones: 10 s left the arm 1.7e-5 rad off at T = 10 ms
    dt=1e-3,
    integrator="midpoint",
    seed=0,
    law="septic",
    gains="platform",
    target=(1.0, 0.5, 2.0),
    reach_fraction=0.6,
    thrust_factor=1e-5,
)


@pytest.mark.parametrize("tau", [0.005, 0.01])
def test_motor_lag_on_my_platform_settles(quad, tau):
    """qprr simulate motor-lag on examples/my_platform (it diverged at 1.29 s with the gains derived for ideal rotors): the
    run completes, the base settles on the target, the arm on its posture, and the move never strays 1 cm."""
    res = missions.motor_lag(quad, "idc", tau=tau, **MOTOR_LAG)
    assert res.status == "ok"
    m = res.metrics
    assert m["final_position_error"] < 1e-4 and m["final_arm_error"] < 1e-5 and m["max_position_error"] < 0.01, m
    speeds = res.series["rotor_speed"]
    assert np.all(np.isfinite(speeds)) and speeds.max() < np.sqrt(8.0 / 1e-5)  # below w_max = sqrt(f_max / b): not saturated


def test_rotor_time_constant_bounds_the_attitude_loop_and_the_tilt_filter(quad):
    """With T known: w_att T <= 0.1 and omega_f T <= 0.075; T = 0 keeps the gains for ideal rotors."""
    ideal = platform_gains("idc", quad)["gains"]
    for T in (0.005, 0.02, 0.05):
        g = platform_gains("idc", quad, Targets(rotor_time_constant=T))["gains"]
        w_att = g.kd[4] / 3.0
        assert w_att * T <= ROTOR_LAG_ATTITUDE * (1 + 1e-12)
        assert g.filter_omega * T <= ROTOR_LAG_FILTER * (1 + 1e-12) and g.filter_omega <= ideal.filter_omega
        assert platform_gains("mfc", quad, Targets(rotor_time_constant=T))["gains"].filter_omega * T <= ROTOR_LAG_FILTER * (1 + 1e-12)
    assert platform_gains("idc", quad, Targets(rotor_time_constant=0.0))["gains"] == ideal
    with pytest.raises(InputError, match="rotor_time_constant"):
        Targets(rotor_time_constant=-1e-3)


# ------------------------------------------------------------------------------------------------ MFC
def _workspace_inverses(platform, n_random: int, seed: int):
    rng = np.random.default_rng(seed)
    S = rate_map(platform.neutral_xi())
    for _ in range(n_random):
        q = platform.neutral_q().copy()
        q[7:] = rng.uniform(platform.arm_lower, platform.arm_upper)
        yield np.linalg.inv(S.T @ pin.crba(platform.model, platform.data(), q) @ S)


@pytest.mark.parametrize("name", ["quad_rrr", *PLATFORMS])
def test_mfc_estimator_contracts_over_the_workspace(name, quad):
    """The iPID's estimator steps alpha u_k = (I - diag(1/alpha) B^-1) alpha u_(k-1) + ...: with the derived alpha its
    eigenvalues 1 - lam stay in (-1, 1) at random arm configurations (not the grid alpha was read on), lam <= 1.5 about."""
    p = quad if name == "quad_rrr" else PLATFORMS[name]()
    alpha = np.array(platform_gains("mfc", p)["gains"].alpha)
    ev = np.concatenate([np.linalg.eigvals(Bi / alpha[:, None]) for Bi in _workspace_inverses(p, 300, 7)])
    assert np.abs(ev.imag).max() < 1e-9 * np.abs(ev).max()  # diag(1/alpha) times an SPD matrix: real, positive
    lam = ev.real
    assert lam.min() > 0.0 and lam.max() < 2.0, (lam.min(), lam.max())  # step-matrix eigenvalues 1 - lam in (-1, 1)
    assert lam.max() < 1.1 * MFC_EIGENVALUE, lam.max()  # the fastest mode near 1 - 1.5 = -0.5 off the grid too


def test_mfc_tracks_the_turret_of_my_platform(quad):
    """hover-reach with the MFC on examples/my_platform (the turret swings 1.8 rad): the derived gains track it better than
    the class's (K_P = 60, K_I = 8, K_D = 35: 0.24 rad RMSE) and the other joints to < 1 mm-rad; the turret's limit is the
    estimator rate g = min beta / (alpha T_c): halving the control period more than halves its error."""
    from qprr.scenarios.missions import reach_posture

    traj = hover_and_reach(quad, (0.0, 0.0, 2.0), reach_posture(quad, 0.6))

    def rmse(ctrl, dt=1e-3):
        r = simulate(quad, ctrl, traj, 10.0, dt=dt)
        assert r.status == "ok"
        return np.sqrt(((r.xi - r.xi_d) ** 2).mean(axis=0))

    cls = rmse(make_controller("mfc", quad, gains=MFCGains()))
    der = rmse(make_controller("mfc", quad))
    fine = rmse(make_controller("mfc", quad, **platform_gains("mfc", quad, Targets(control_period=5e-4))), dt=5e-4)
    turret, arm = 6, slice(7, 9)
    assert cls[turret] > 0.2 and der[turret] < 0.85 * cls[turret], (cls[turret], der[turret])
    assert np.all(der[arm] < 1e-3) and np.all(der[arm] < cls[arm] / 5.0), (der[arm], cls[arm])
    assert fine[turret] < 0.5 * der[turret], (fine[turret], der[turret])


def test_mfc_bandwidth_respects_the_estimator_quartic(quad):
    """Each derived MFC coordinate has w <= g / 4 (g = min beta / (alpha T_c)); the quartic s^4 + g s^3 + g k_D s^2 +
    g k_P s + g k_I of iPID plus estimator is then Hurwitz at every g >= g_min."""
    a = Authority.from_platform(quad)
    gains = platform_gains("mfc", quad)["gains"]
    lo = np.array([v[0] for v in a.inverse_inertia])
    g_min = lo / (np.array(gains.alpha) * Targets().control_period)
    for i in range(quad.n_xi):
        w = gains.kd[i] / 3.0
        assert w <= g_min[i] / 4.0 * (1 + 1e-12)
        for g in g_min[i] * np.array([1.0, 3.0, 30.0]):
            roots = np.roots([1.0, g, g * gains.kd[i], g * gains.kp[i], g * gains.ki[i]])
            assert roots.real.max() < 0.0, (i, g, roots)


def test_workspace_grid_holds_the_neutral_posture_and_the_limits(quad):
    """The turret's inverse inertia is largest with the arm folded on its axis (the neutral posture) and smallest reached out."""
    a = Authority.from_platform(quad)
    S = rate_map(quad.neutral_xi())
    neutral = np.linalg.inv(S.T @ pin.crba(quad.model, quad.data(), quad.neutral_q()) @ S)[6, 6]
    assert a.inverse_inertia[6][1] == pytest.approx(neutral, rel=1e-12)
    corners = []
    for qa in itertools.product(*zip(quad.arm_lower, quad.arm_upper)):
        q = quad.neutral_q().copy()
        q[7:] = qa
        corners.append(np.linalg.inv(S.T @ pin.crba(quad.model, quad.data(), q) @ S)[6, 6])
    assert a.inverse_inertia[6][0] <= min(corners) * (1 + 1e-12)
    assert a.inverse_inertia[6][1] / a.inverse_inertia[6][0] > 100.0  # why a constant alpha limits the MFC here


def test_class_defaults_on_request():
    """make_controller(defaults="class") builds the class's own fixed gains, nothing derived; anything else is refused."""
    from qprr.control import InverseDynamicsController, make_controller
    from qprr.errors import UnknownNameError

    p = qprr.load("borinot_flying_arm_2")
    assert make_controller("idc", p, defaults="class").gains == InverseDynamicsController(p).gains
    assert make_controller("idc", p).gains != InverseDynamicsController(p).gains
    with pytest.raises(UnknownNameError, match="class"):
        make_controller("idc", p, defaults="thesis")
