"""Impedance control (Thesis Sec. 6.4.3.3): filters (6.71)/(6.74)/(6.75), gains, closed-loop deflection h/K."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qprr import charts as co
from qprr.control.impedance import ImpedanceFilter, ImpedanceGains, analytic_wrench
from qprr.errors import InputError
from qprr.thesis import gains
from qprr.thesis import scenarios as scn
from qprr.thesis.gains import NAMES

SEED = 66


def _step_response(M, D, K, f, t):
    """Closed-form response of M x'' + D x' + K x = f from rest (any damping)."""
    wn = math.sqrt(K / M)
    z = D / (2 * math.sqrt(K * M))
    xs = f / K
    if z < 1:
        wd = wn * math.sqrt(1 - z * z)
        return xs * (1 - np.exp(-z * wn * t) * (np.cos(wd * t) + z * wn / wd * np.sin(wd * t)))
    if z == 1:
        return xs * (1 - np.exp(-wn * t) * (1 + wn * t))
    r1, r2 = -wn * (z - math.sqrt(z * z - 1)), -wn * (z + math.sqrt(z * z - 1))
    return xs * (1 + (r2 * np.exp(r1 * t) - r1 * np.exp(r2 * t)) / (r1 - r2))


def test_filter_is_the_exact_zoh_solution():
    """Under a held input the discrete filter reproduces the continuous solution (under-, critically and over-damped)."""
    M, D, K = np.array([0.1, 0.02, 0.5]), np.array([0.2, 1.0, 2 * math.sqrt(0.5)]), np.array([5.0, 0.08, 1.0])
    f = np.array([0.2, 0.05, -0.3])
    filt = ImpedanceFilter(M, D, K)
    dt, n = 1e-3, 3000
    out = np.array([filt.step(f, dt)[0].copy() for _ in range(n)])
    t = dt * np.arange(1, n + 1)
    for i in range(3):
        assert np.allclose(out[:, i], _step_response(M[i], D[i], K[i], f[i], t), rtol=1e-9, atol=1e-12)
    # residual of the ODE at the end of each step
    assert np.allclose(M * filt.delta_ddot + D * filt.delta_dot + K * filt.delta, f, atol=1e-12)


def test_filter_steady_state_is_h_over_K():
    filt = ImpedanceFilter([0.1, 0.1], [1.0, 1.0], [0.5, 5.0])
    f = np.array([0.2, -0.4])
    for _ in range(200):
        filt.step(f, 0.5)  # exact discretisation: large steps are as good as small ones (slow pole -0.53 /s)
    assert np.allclose(filt.delta, f / np.array([0.5, 5.0]), rtol=1e-9)
    assert np.allclose(filt.steady_state(f), [0.4, -0.08])
    with pytest.raises(InputError):
        ImpedanceFilter([0.1], [0.0], [1.0])


def test_analytic_wrench_virtual_power():
    """gamma = T_A^T h of (6.71): gamma . chi_dot = h . [p_dot; omega_world] for ZYX Euler rates."""
    rng = np.random.default_rng(SEED)
    for _ in range(10):
        e = rng.uniform(-1.2, 1.2, 3)
        ed = rng.normal(size=3)
        h = rng.normal(size=6)
        pd = rng.normal(size=3)
        omega = co.euler_to_rotation(e) @ co.euler_rate_matrix(e) @ ed
        assert analytic_wrench(e, h) @ np.concatenate([pd, ed]) == pytest.approx(h[0:3] @ pd + h[3:6] @ omega, rel=1e-12)


def test_printed_gain_tables_are_unstable_under_exact_linearisation():
    """Routh-Hurwitz on e''' + k_D e'' + k_P e' + k_I e: (6.56) attitude PI (Table 6.5) and (6.79) arm PI (Table 6.7)."""
    t65, t67 = gains.table_6_5(), gains.table_6_7()
    assert t65.unstable_axes(NAMES) == ["phi", "theta", "psi"]
    assert t67.unstable_axes(NAMES) == ["r0", "theta2", "theta3"]
    for g, axis in ((t65, "theta"), (t67, "theta2")):
        assert np.roots(g.characteristic_polynomials(NAMES)[axis]).real.max() > 0.0
    for g in (gains.payload_idc(), gains.impedance_idc()):
        assert g.unstable_axes(NAMES) == []
        assert all(np.roots(c).real.max() < 0 for c in g.characteristic_polynomials(NAMES).values())


def test_table_6_7_slider_stiffness_exceeds_the_stroke():
    """K_P^q = 0.08 N/m: 0.05 N along x_B deflects the slider reference by 0.625 m, 15 x the 0.04 m stroke."""
    k = gains.impedance_table_6_7().K_arm[0]
    assert 0.05 / k == pytest.approx(0.625)
    assert 0.05 / gains.impedance_filters().K_arm[0] == pytest.approx(0.02)


FAST = ImpedanceGains(M_base=(0.5,) * 4, D_base=(3.0,) * 4, K_base=(5.0,) * 4, M_arm=(0.05,) * 3, D_arm=(1.0, 0.5, 0.5), K_arm=(5.0, 1.0, 1.0))
"""Impedance gains whose slowest pole is -2.8 /s, so that a 6 s run reaches the steady state."""


def test_closed_loop_deflection_equals_h_over_K():
    """Hover, h_b = 0.2 N on x and h_q = [0.05, 0.01, 0.05] N on the end effector: the base yields h_b/K along +x,
    the arm yields K^-1 J_eb^T h_q (the compliant sign); y and z stay rigid."""
    res = scn.impedance(settings=scn.ImpedanceSettings(impedance_gains=FAST, duration=6.0, t_off=10.0))
    d = scn.impedance_steady_state(res, 5.99)
    meas, pred = d["measured"], d["predicted"]
    assert pred[0] == pytest.approx(0.04)
    assert meas[0] == pytest.approx(pred[0], rel=2e-4)  # measured 3e-5
    assert np.all(np.abs(meas[1:4]) < 1e-5)  # y, z, psi: no base compliance there
    assert meas[4:7] == pytest.approx(pred[4:7], rel=1e-4)  # measured 2e-6
    assert meas[4] > 0.0  # the slider yields along the +x force
    assert res.metrics["saturated_steps"] == 0
