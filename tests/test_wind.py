"""Wind, aerodynamic drag D and viscous friction F_v of (5.36) (qprr.sim.wind): spectra, closed forms, steady states.

Statistical checks are seeded and use enough samples for the stated bounds: a Welch
periodogram of 2^18 samples (nperseg 4096, ~127 averaged segments) averaged over frequency
bands of >= 20 bins has a relative standard error near 1 / sqrt(127 * 20 / 2) = 3 %; the bounds
below (10 %) are three times that.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import quad
from scipy.signal import welch

import qprr
from qprr import charts as ch
from qprr.errors import InputError, ShapeError
from qprr.sim import simulate
from qprr.sim.wind import FT, AerodynamicDrag, Dryden, Gust, ViscousFriction, Wind
from qprr.trajectory import Hold

DRYDEN = Dryden(sigma=(1.5, 1.2, 0.8), length=(20.0, 20.0, 5.0), airspeed=10.0)
TS = 0.01
N = 2**18


@pytest.fixture(scope="module")
def samples():
    return DRYDEN.sample(N, TS, np.random.default_rng(2024))


def test_psd_integrates_to_the_variance_and_the_filters_realise_it():
    """int_0^inf Phi = sigma^2 (quadrature) and |H(j omega)|^2 = pi Phi for the state-space shaping filters."""
    for i in range(3):
        total, _ = quad(lambda w, i=i: DRYDEN.psd(w)[i, 0], 0.0, np.inf, limit=200)
        assert total == pytest.approx(DRYDEN.sigma[i] ** 2, rel=1e-8)
    A, B, C = DRYDEN.shaping_filter()
    for w in (0.01, 0.3, 1.0, 7.0, 50.0):
        H = C @ np.linalg.solve(1j * w * np.eye(5) - A, B)
        np.testing.assert_allclose(np.abs(np.diag(H)) ** 2, math.pi * DRYDEN.psd(w)[:, 0], rtol=1e-12)
        assert np.abs(H - np.diag(np.diag(H))).max() == 0.0  # independent components
    Ad, Ld, C, P = DRYDEN.discretization(TS)
    np.testing.assert_allclose(np.diag(C @ P @ C.T), np.array(DRYDEN.sigma) ** 2, rtol=1e-10)  # stationary variance
    np.testing.assert_allclose(Ad @ P @ Ad.T + Ld @ Ld.T, P, atol=1e-12 * np.abs(P).max())  # P is stationary for the discrete chain


def test_exact_discretisation_has_the_continuous_autocorrelation():
    """C A_d^k P C^T = R(k T_s): the sampled chain has the model's autocorrelation at every lag (exact, not to O(T_s))."""
    Ad, _, C, P = DRYDEN.discretization(TS)
    lags = np.array([0, 1, 7, 50, 300])
    for k in lags:
        R = np.diag(C @ np.linalg.matrix_power(Ad, int(k)) @ P @ C.T)
        np.testing.assert_allclose(R, DRYDEN.autocorrelation(k * TS)[:, 0], rtol=1e-9, atol=1e-12)


def test_sampled_spectrum_matches_the_model_psd(samples):
    """Welch PSD of 2^18 seeded samples vs the model: within 10 % in every band of >= 20 bins (bands from 0.05 Hz to
    Nyquist); where aliasing is negligible (f < 2 Hz) the sampled process's PSD is the continuous 2 pi Phi(2 pi f) to 1 %."""
    f, P = welch(samples, fs=1.0 / TS, nperseg=4096, axis=0)
    P = P.T
    model = DRYDEN.discrete_psd(f[1:], TS)
    edges = np.geomspace(0.05, 0.5 / TS, 16)
    for lo, hi in zip(edges[:-1], edges[1:]):
        band = (f[1:] >= lo) & (f[1:] < hi)
        if band.sum() < 20:
            continue
        ratio = P[:, 1:][:, band].mean(axis=1) / model[:, band].mean(axis=1)
        assert np.all(np.abs(ratio - 1.0) < 0.10), f"band [{lo:.3g}, {hi:.3g}) Hz: estimate / model = {ratio}"
    low = f[1:] < 2.0
    continuous = 2 * math.pi * DRYDEN.psd(2 * math.pi * f[1:][low])
    np.testing.assert_allclose(model[:, low], continuous, rtol=1e-2)


def test_sampled_variance_and_autocorrelation(samples):
    """Sample variance and autocorrelation at lags 0.1, 0.5, 2 s within 5 sigma of their statistical error."""
    x = samples - samples.mean(axis=0)
    T_total = N * TS
    for lag_s in (0.0, 0.1, 0.5, 2.0):
        k = int(round(lag_s / TS))
        r = (x[: N - k] * x[k:]).mean(axis=0)
        R = DRYDEN.autocorrelation(lag_s)[:, 0]
        # standard error of a sample covariance of a process with correlation time L / V: sigma^2 sqrt(2 (L/V) / T)
        se = np.array(DRYDEN.sigma) ** 2 * np.sqrt(2 * np.array(DRYDEN.length) / DRYDEN.airspeed / T_total)
        assert np.all(np.abs(r - R) < 5 * se), (lag_s, r, R, se)


def test_seeded_and_reproducible():
    a = DRYDEN.sample(100, TS, np.random.default_rng(1))
    b = DRYDEN.sample(100, TS, np.random.default_rng(1))
    c = DRYDEN.sample(100, TS, np.random.default_rng(2))
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).max() > 0.1


def test_mil_low_altitude_parameters():
    """MIL-F-8785C low altitude at h = 10 m, W_20 = 7.7 m/s, by the printed formulas in feet."""
    d = Dryden.low_altitude(10.0, 7.7, 3.0)
    h = 10.0 / FT
    assert d.length[2] == pytest.approx(10.0)
    assert d.length[0] == d.length[1] == pytest.approx(h / (0.177 + 0.000823 * h) ** 1.2 * FT)
    assert d.sigma[2] == pytest.approx(0.77)
    assert d.sigma[0] == pytest.approx(0.77 / (0.177 + 0.000823 * h) ** 0.4)
    with pytest.raises(InputError, match="altitude"):
        Dryden.low_altitude(400.0, 7.7, 3.0)
    with pytest.raises(InputError, match="airspeed"):
        Dryden((1, 1, 1), (1, 1, 1), 0.0)


def test_gust_and_turbulence_axes():
    g = Gust(2.0, 4.0, (0.0, 3.0, 0.0))
    v = g.velocity([1.0, 2.0, 4.0, 6.0, 7.0])
    np.testing.assert_allclose(v[:, 1], [0.0, 0.0, 3.0, 0.0, 0.0], atol=1e-15)
    w = Wind((3.0, 4.0, 0.0))
    np.testing.assert_allclose(w.turbulence_axes()[:, 0], [0.6, 0.8, 0.0])
    np.testing.assert_allclose(w.turbulence_axes()[:, 1], [-0.8, 0.6, 0.0])
    np.testing.assert_allclose(Wind().turbulence_axes(), np.eye(3))


# ------------------------------------------------------------------------------------ drag
def test_drag_closed_form():
    """F_B = -K_1 v_r - K_2 |v_r| v_r with v_r = v_B - R^T w; moment -k_w omega; the arm rows are zero."""
    pf = qprr.load()
    drag = AerodynamicDrag((1.0, 2.0, 0.3), (0.03, 0.05, 0.09), 0.02, Wind((2.0, -1.0, 0.5)))
    rng = np.random.default_rng(5)
    xi = np.r_[1.0, 2.0, 3.0, 0.2, -0.3, 0.7, 0.01, 0.3, -0.2]
    q, v = ch.xi_to_qv(xi, rng.normal(size=9))
    tau = drag.generalized_force(0.0, q, v)
    R = ch.euler_to_rotation(xi[3:6])
    vr = v[0:3] - R.T @ np.array([2.0, -1.0, 0.5])
    np.testing.assert_allclose(tau[0:3], -np.array([1.0, 2.0, 0.3]) * vr - np.array([0.03, 0.05, 0.09]) * np.linalg.norm(vr) * vr, rtol=1e-13)
    np.testing.assert_allclose(tau[3:6], -0.02 * v[3:6], rtol=1e-15)
    assert np.all(tau[6:] == 0.0) and tau.shape == (pf.nv,)


def test_drag_realization_interpolates_the_sampled_wind_linearly():
    drag = AerodynamicDrag(1.0, 0.0, 0.0, Wind((1.0, 0.0, 0.0), DRYDEN))
    t = np.arange(10) * 0.004
    r1 = drag.realize(t, np.random.default_rng(0), 0.004)
    r2 = drag.realize(t, np.random.default_rng(0), 0.004)
    np.testing.assert_array_equal(r1.w, r2.w)
    np.testing.assert_allclose(r1.wind_velocity(0.008), r1.w[2], rtol=1e-15)
    np.testing.assert_allclose(r1.wind_velocity(0.009), 0.75 * r1.w[2] + 0.25 * r1.w[3], rtol=1e-12)
    assert r1.report()["wind_velocity"].shape == (10, 3)


class _Off(qprr.control.Controller):
    """Rotors and arm motors off (tau = 0)."""

    output = "pinocchio"
    name = "off"

    def step(self, t, state, ref):
        return np.zeros(state.v.shape[0])


@pytest.mark.parametrize("updraft", [0.0, 4.0])
def test_falling_vehicle_reaches_the_terminal_velocity_relative_to_the_air(updraft):
    """Rotors off, arm straight (CoG on z_B: the drag at B exerts no moment), an updraft w_z: the vehicle falls level and
    settles at v_z = w_z - v_t with m g = K_1z v_t + K_2z v_t^2 (closed form), to 1e-9 m/s."""
    pf = qprr.load()
    K1z, K2z = 0.3, 0.09
    drag = AerodynamicDrag((1.0, 1.0, K1z), (0.03, 0.03, K2z), 0.01, Wind((0.0, 0.0, updraft)))
    m, g = pf.total_mass, pf.g
    v_t = (-K1z + math.sqrt(K1z**2 + 4 * K2z * m * g)) / (2 * K2z)
    res = simulate(
        pf, _Off(), Hold((0, 0, 500, 0, 0, 0, 0, 0, 0)), 30.0, disturbance=drag, integrator="rk4", dt=2e-3, limits=qprr.sim.Limits(position=1e4)
    )
    assert res.xi_dot[-1, 2] == pytest.approx(updraft - v_t, abs=1e-9)
    assert np.abs(res.xi[:, 3:5]).max() < 1e-12  # level all the way


# -------------------------------------------------------------------------------- friction
def test_viscous_friction_is_minus_fv_xi_dot_in_thesis_coordinates():
    """S^T tau = -F_v xi_dot (Thesis (5.36) moved to the right-hand side), both branches (arm only, base too)."""
    rng = np.random.default_rng(9)
    xi = np.r_[0.3, 0.1, 2.0, 0.2, -0.1, 0.5, 0.01, 0.4, -0.3]
    xi_dot = rng.normal(size=9)
    q, v = ch.xi_to_qv(xi, xi_dot)
    for F in ((0.0,) * 6 + (0.5, 0.0075, 0.00025), (0.4, 0.5, 0.6, 0.01, 0.02, 0.03, 0.5, 0.0075, 0.00025)):
        tau = ViscousFriction(F).generalized_force(0.0, q, v)
        np.testing.assert_allclose(ch.force_to_xi(xi, tau), -np.array(F) * xi_dot, rtol=1e-12, atol=1e-15)
    with pytest.raises(ShapeError, match="coefficients"):
        ViscousFriction((0.1,) * 8).generalized_force(0.0, q, v)
    with pytest.raises(InputError, match="friction"):
        ViscousFriction((-0.1,) * 9)


def test_friction_dissipates_energy_of_a_free_swinging_arm():
    """Rotors and motors off, the arm swinging in free fall: d(T + U)/dt = -xi_dot^T F_v xi_dot: the energy decreases
    monotonically and the loss equals the dissipated work (trapezoid at 1 ms, to 1e-4)."""
    pf = qprr.load()
    fr = ViscousFriction((0.0,) * 6 + (0.5, 0.0075, 0.00025))
    res = simulate(
        pf,
        _Off(),
        Hold((0.0,) * 9),
        0.3,
        xi0=np.r_[0, 0, 100, 0, 0, 0, 0.0, 0.2, -0.2],
        xi_dot0=np.r_[0, 0, 0, 0, 0, 0, 0.02, 1.0, -2.0],
        disturbance=fr,
        integrator="rk4",
        dt=1e-4,
        control_period=1e-3,
        joint_stops=False,
    )
    d = pf.data()
    E = []
    for x, xd in zip(res.xi, res.xi_dot):
        q, v = ch.xi_to_qv(x, xd)
        E.append(pin.computeKineticEnergy(pf.model, d, q, v) + pin.computePotentialEnergy(pf.model, d, q))
    E = np.array(E)
    assert np.all(np.diff(E) < 0.0)  # free fall + arm swing: only friction removes energy
    p_diss = (np.array(fr.coefficients) * res.xi_dot**2).sum(axis=1)  # xi_dot^T F_v xi_dot [W]
    dissipated = float(np.sum(0.5 * (p_diss[1:] + p_diss[:-1]) * np.diff(res.t)))
    assert E[0] - E[-1] == pytest.approx(dissipated, rel=1e-4)
