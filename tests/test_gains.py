"""Gains derived from the platform (qprr.control.gains): pole placement, the authority formulas, mass scaling, overrides."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

import qprr
from qprr.cli import main
from qprr.control.gains import Authority, Targets, bandwidths, derive, idc_gains, load_gains, platform_gains
from qprr.control.opspace_impedance import EndEffectorImpedance
from qprr.errors import QprrError, UnknownNameError
from qprr.model import max_lift
from qprr.scenarios import run
from qprr.sim import simulate
from qprr.trajectory import Hold

MY = "examples/my_platform/"


@pytest.fixture(scope="module")
def quad():
    return qprr.from_urdf(MY + "quad_rrr.urdf", MY + "quad_rrr.rotors.toml", ee_frame="gripper")


POSITIVE = st.floats(0.05, 50.0)
AUTHORITY = st.builds(
    lambda m, i, margin, tau, ia, ea: Authority(m, (i, i, 0.5 * i), margin, (tau, tau, 0.2 * tau), (ia, ia), (ea, math.inf)),
    POSITIVE,
    POSITIVE,
    POSITIVE,
    POSITIVE,
    POSITIVE,
    POSITIVE,
)


@settings(max_examples=40, deadline=None)
@given(AUTHORITY)
def test_error_polynomials_have_their_poles_at_w(a):
    """Under exact linearisation e'' + k_D e' + k_P e (+ k_I int e) = 0: the polynomial is (s + w)^2, attitude (s + w)^3."""
    w = bandwidths(a)
    g = idc_gains(w)
    for i, wi in enumerate(w):
        poly = [1.0, g.kd[i], g.kp[i], g.ki[i]] if 3 <= i < 6 else [1.0, g.kd[i], g.kp[i]]
        np.testing.assert_allclose(poly, np.poly([-wi] * (len(poly) - 1)), rtol=1e-14, atol=0)
    assert not g.unstable_axes()


@settings(max_examples=40, deadline=None)
@given(AUTHORITY, st.floats(0.01, 100.0))
def test_scaling_every_mass_and_actuator_by_k_scales_force_gains_by_k(a, k):
    """A k times heavier, k times stronger robot: the same bandwidths and acceleration gains, force-level gains times k."""
    np.testing.assert_allclose(bandwidths(a.scaled(k)), bandwidths(a), rtol=1e-13)

    for name in ("impedance", "opspace-impedance"):
        base, big = derive(name, a, Targets()), derive(name, a.scaled(k), Targets())
        imp, imp_k = base["impedance"], big["impedance"]
        fields = (
            ("stiffness", "damping", "mass") if isinstance(imp, EndEffectorImpedance) else ("M_base", "D_base", "K_base", "M_arm", "D_arm", "K_arm")
        )
        for f in fields:
            np.testing.assert_allclose(np.asarray(getattr(imp_k, f)), k * np.asarray(getattr(imp, f)), rtol=1e-13)
        if "gains" in base:
            np.testing.assert_allclose(big["gains"].kp, base["gains"].kp, rtol=1e-13)


@settings(max_examples=40, deadline=None)
@given(AUTHORITY, st.floats(1.0, 10.0), st.floats(0.05, 2.0))
def test_bandwidths_follow_the_formulas(a, ratio, e):
    t = Targets(position_error=e, attitude_error=e, arm_error=e, ratio=ratio, cap=1e6)
    w = bandwidths(a, t)
    w_lift = math.sqrt(a.thrust_margin / (a.mass * e))
    w_tilt = min(math.sqrt(a.torque[k] / (a.inertia[k] * e)) for k in (0, 1))
    assert w[0] == pytest.approx(min(w_lift, w_tilt / ratio), rel=1e-14)
    assert w[3] == w[4] == pytest.approx(ratio * w[0], rel=1e-14)
    assert w[5] == pytest.approx(min(w[3], math.sqrt(a.torque[2] / (a.inertia[2] * e))), rel=1e-14)
    assert w[6] == pytest.approx(min(math.sqrt(a.arm_effort[0] / (a.arm_inertia[0] * e)), w[3]), rel=1e-14)
    assert w[7] == pytest.approx(w[3], rel=1e-14)  # unlimited effort: the attitude bandwidth


def test_authority_of_the_x_quadrotor_in_closed_form(quad):
    """Equal hover thrusts m g / 4; each moves by min(f_max - f_h, f_h - f_min) = f_h; roll torque sum |y_i| f_h."""
    a = Authority.from_platform(quad)
    f_h = quad.total_mass * quad.g / 4
    assert a.thrust_margin == pytest.approx(max_lift(quad) - quad.total_mass * quad.g, rel=1e-14)
    np.testing.assert_allclose(a.torque, [4 * 0.1414 * f_h, 4 * 0.1414 * f_h, 4 * 0.016 * f_h], rtol=1e-12)
    assert a.mass == pytest.approx(quad.total_mass, rel=1e-15)


def test_closed_loop_arm_error_decays_as_its_error_polynomial():
    """On the fully actuated hextilt the inverse dynamics cancel the coupling: an arm offset e0 follows the error
    polynomial (s + w)^2 (s + w / 10) of the derived gains with integral action (Targets(integral=True); the integral
    starting at zero): [int e, e, e']' = A [int e, e, e']
    with A the companion matrix of [1, k_D, k_P, k_I], solved by the matrix exponential (RK4, 0.5 ms, exact model
    without the URDF's joint friction, which the controller does not feed back, no saturation)."""
    p = qprr.load("hextilt_flying_arm_5").without_joint_friction()
    gains = platform_gains("idc", p, Targets(integral=True))
    ctrl = qprr.make_controller("idc", p, **gains)
    xi = p.neutral_xi()
    xi[2] = 2.0
    e0 = 0.02
    xi_start = xi.copy()
    xi_start[6] += e0
    res = simulate(p, ctrl, Hold(tuple(xi)), 0.3, dt=5e-4, integrator="rk4", xi0=xi_start)
    g = gains["gains"]
    w = bandwidths(Authority.from_platform(p))[6]
    np.testing.assert_allclose([1.0, g.kd[6], g.kp[6], g.ki[6]], np.poly([-w, -w, -w / 10.0]), rtol=1e-13)
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-g.ki[6], -g.kp[6], -g.kd[6]]])
    expected = np.array([(expm(A * t) @ [0.0, e0, 0.0])[1] for t in res.t])
    np.testing.assert_allclose(res.xi[:, 6] - xi[6], expected, rtol=0, atol=2e-3 * e0)


def test_gains_file_overrides_targets_and_fields(tmp_path, quad):
    f = tmp_path / "g.toml"
    f.write_text("[targets]\nratio = 4.0\n[idc.gains]\nki = 0.0\nfilter_omega = 30.0\n")
    g = load_gains(f, "idc", quad)["gains"]
    w = bandwidths(Authority.from_platform(quad), Targets(ratio=4.0))
    assert g.kp[3] == pytest.approx(3 * w[3] ** 2) and w[3] == pytest.approx(4 * w[0])
    assert g.ki == (0.0,) * quad.n_xi and g.filter_omega == 30.0
    f.write_text("[mfc.gains]\nkp = 1.0\n")
    with pytest.raises(QprrError, match=r"not for the controller 'idc'"):
        load_gains(f, "idc", quad)
    f.write_text("[idc.gains]\nkq = 1.0\n")
    with pytest.raises(UnknownNameError, match="kq"):
        load_gains(f, "idc", quad)
    with pytest.raises(UnknownNameError, match="mpc"):
        platform_gains("mpc", quad)


def test_print_gains_names_the_platforms_coordinates(capsys):
    own = ["--urdf", MY + "quad_rrr.urdf", "--rotors", MY + "quad_rrr.rotors.toml", "--ee-frame", "gripper"]
    assert main(["simulate", "fly-to", *own, "--print-gains"]) == 0
    out = capsys.readouterr().out
    assert "shoulder" in out and "elbow" in out and "theta2" not in out and "IDCGains" in out
    assert main(["simulate", "takeoff-hover", "--platform", "borinot_flying_arm_2", "--gains", "q-prr:idc", "--print-gains"]) == 0
    assert "kp" in capsys.readouterr().out  # a registered table prints; running it on borinot would fail on its size
    assert main(["simulate", "static-idc", "--gains", "x.toml"]) == 2


def test_print_gains_of_motor_lag_are_the_flown_ones(capsys):
    """motor-lag derives its gains knowing the rotor time constant: --print-gains shows those, for the tau of the run
    (the roll/pitch reference filter at 0.075 / tau)."""
    from qprr.scenarios.missions import lag_gains

    assert main(["simulate", "motor-lag", "--set", "tau=0.02", "--print-gains"]) == 0
    out = capsys.readouterr().out
    assert "filter_omega = 3.75" in out
    assert lag_gains("idc", qprr.load(), 0.02)["gains"].filter_omega == pytest.approx(3.75, rel=1e-12)


def test_hover_reach_takes_the_gains_option(capsys):
    """hover-reach flies the derived gains by default and any gain set by name, like the generic missions."""
    assert main(["simulate", "hover-reach", "--platform", "borinot_flying_arm_2", "--print-gains"]) == 0
    rows = {line.split()[0]: line.split()[1:] for line in capsys.readouterr().out.splitlines() if line.startswith("  ")}
    p = qprr.load("borinot_flying_arm_2")
    g = platform_gains("idc", p)["gains"]
    for k, name in enumerate(p.xi_names):  # the printed kp, kd are the derived ones (5 significant digits)
        assert float(rows[name][0]) == pytest.approx(g.kp[k], rel=1e-4) and float(rows[name][1]) == pytest.approx(g.kd[k], rel=1e-4)
    derived = run("hover-reach", "idc", platform=p, duration=1.0)
    fixed = run("hover-reach", "idc", platform=p, duration=1.0, gains="class")
    assert not np.array_equal(derived.xi, fixed.xi)  # two gain sets, two flights
    assert abs(derived.xi[-1, 2] - derived.xi_d[-1, 2]) < 0.05


def test_print_gains_of_a_controller_without_derived_gains(capsys):
    """mpc has cost weights, not gains: --print-gains says it flies its class's own settings (what the run uses)."""
    assert main(["simulate", "hover-reach", "--controller", "mpc", "--print-gains"]) == 0
    assert "the defaults of the mpc class" in capsys.readouterr().out


def test_ee_impedance_called_directly_names_the_missing_options():
    from qprr.scenarios.impedance import run_ee_impedance

    with pytest.raises(QprrError, match="missing .*'contact'.*qprr.scenarios.run"):
        run_ee_impedance(None, "idc", False, duration=1.0)
