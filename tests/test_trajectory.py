"""Trajectories: the transition law (6.16) (printed, quintic, septic), missions, spiral (6.25)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qprr.errors import InputError, ShapeError, UnknownNameError
from qprr.sim.loop import check_sample
from qprr.thesis.missions import NAMES, STATIC_TARGET, dynamic_mission, static_mission
from qprr.trajectory import Hold, MultiPhase, Phase, Spiral, transition


def _fd(f, t, h=1e-6):
    return (f(t + h) - f(t - h)) / (2 * h)


@pytest.mark.parametrize("law", ["septic", "quintic", "thesis"])
@settings(max_examples=30, deadline=None)
@given(t1=st.floats(0.0, 5.0), T=st.floats(0.5, 10.0), a=st.floats(-10, 10), b=st.floats(-10, 10), tau=st.floats(0.01, 0.99))
def test_transition_derivatives_match_finite_differences(law, t1, T, a, b, tau):
    t2 = t1 + T
    t = t1 + tau * T
    s = transition(t, t1, t2, a, b, order=4, law=law)
    for n in range(3):
        fd = _fd(lambda x, n=n: transition(x, t1, t2, a, b, order=4, law=law)[n], t)
        assert abs(fd - s[n + 1]) <= 1e-5 * (1 + abs(s[n + 1])) * max(1.0, 1.0 / T**n)


@pytest.mark.parametrize("law", ["septic", "quintic", "thesis"])
def test_transition_endpoints(law):
    t = np.array([-1.0, 2.0, 7.0, 9.0])
    s, sd, sdd = transition(t, 2.0, 7.0, 1.0, 4.0, order=2, law=law)
    np.testing.assert_allclose(s, [1.0, 1.0, 4.0, 4.0], atol=1e-12)
    np.testing.assert_allclose(sd, 0.0, atol=1e-12)
    np.testing.assert_allclose(sdd, 0.0, atol=1e-12)


def test_thesis_law_is_flat_to_fourth_order_and_quintic_only_to_second():
    """(6.16) printed: first four derivatives vanish at t1; the quintic has jerk 60 L / T^3 there."""
    eps = 1e-4  # s''' ~ 60 tau^2 for the printed law
    thesis = transition(eps, 0.0, 1.0, 0.0, 1.0, order=4, law="thesis")
    quintic = transition(eps, 0.0, 1.0, 0.0, 1.0, order=4, law="quintic")
    assert max(abs(v) for v in thesis[1:4]) < 1e-6
    assert quintic[3] == pytest.approx(60.0, rel=1e-2)


def test_septic_law_is_flat_to_third_order_with_bounded_snap():
    """The missions' law: rate, acceleration and jerk vanish at both ends (the tilt (6.17) starts and stops
    turning smoothly), snap is +-840 L / T^4 there; peaks 2.1875 L / T (speed) and 7.513 L / T^2 (acceleration)."""
    eps = 1e-4
    for tau, sign in ((eps, 1.0), (1.0 - eps, -1.0)):
        s = transition(tau, 0.0, 1.0, 0.0, 1.0, order=4, law="septic")
        assert abs(s[1]) < 1e-9 and abs(s[2]) < 1e-5  # 140 eps^3, 420 eps^2
        assert s[3] == pytest.approx(840.0 * eps, rel=1e-2)  # jerk vanishes linearly (the quintic's is 60)
        assert s[4] == pytest.approx(sign * 840.0, rel=1e-2)
    t = np.linspace(0.0, 5.0, 200001)
    _, v, a = transition(t, 0.0, 5.0, 0.0, 10.0, order=2, law="septic")
    assert v.max() == pytest.approx(2.1875 * 10 / 5, rel=1e-6)
    x = (5 - 5**0.5) / 10  # jerk zero: 1 - 5 x + 5 x^2 = 0
    assert np.abs(a).max() == pytest.approx(420 * x**2 * (1 - x) ** 2 * (1 - 2 * x) * 10 / 25, rel=1e-6)  # 3.005 m/s^2


def test_thesis_law_peak_acceleration_makes_the_climb_infeasible():
    """Erratum (6.16): 10 m in 5 s with the printed law needs a 15.2 m/s^2 deceleration (> g).

    A rotor can only push: a deceleration above g (9.8 m/s^2) would need negative total thrust.
    The quintic of the same phase peaks at 2.31 m/s^2.
    """
    t = np.linspace(0.0, 5.0, 200001)
    acc_thesis = transition(t, 0.0, 5.0, 0.0, 10.0, order=2, law="thesis")[2]
    acc_quintic = transition(t, 0.0, 5.0, 0.0, 10.0, order=2, law="quintic")[2]
    assert acc_thesis.min() == pytest.approx(-38.076 * 10 / 25, rel=1e-3)
    assert acc_thesis.min() < -9.8  # infeasible: more than free fall
    assert np.abs(acc_quintic).max() == pytest.approx(5.7735 * 10 / 25, rel=1e-3)
    assert transition(t, 0.0, 5.0, 0.0, 10.0, order=1, law="thesis")[1].max() == pytest.approx(10.0, rel=1e-6)  # 5 L / T


def test_thesis_Ts_read_as_sampling_period_overshoots():
    """Erratum (6.16): with T_s = sampling period (1 ms) the printed formula does not end at L_Qp.

    sigma = L tau^5 / (tau^5 + (T_s - tau)^5), tau = t - t1: at tau = t2 - t1 = 5 s it is ~L tau / (5 T_s).
    """
    L, Ts, tau = 10.0, 1e-3, 5.0
    printed = L * tau**5 / (tau**5 + (Ts - tau) ** 5)
    assert printed > 100 * L
    # with T_s = t2 - t1 it ends exactly at L
    assert transition(5.0, 0.0, 5.0, 0.0, L, law="thesis")[0] == pytest.approx(L)


def test_transition_rejects_bad_input():
    with pytest.raises(InputError):
        transition(0.0, 2.0, 1.0)
    with pytest.raises(UnknownNameError, match="quintic"):
        transition(0.0, 0.0, 1.0, law="cubic")


def test_static_mission_phases_and_target():
    m = static_mission()
    t = np.array([0.0, 5.0, 10.0, 15.0, 25.0, 30.0])
    s = m.sample(t)
    x, y, z, psi, r0, t2, t3 = STATIC_TARGET
    np.testing.assert_allclose(s.xi[1], [0, 0, z, 0, 0, 0, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(s.xi[2], [x, 0, z, 0, 0, 0, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(s.xi[3], [x, y, z, 0, 0, 0, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(s.xi[-1], [x, y, z, 0, 0, psi, r0, t2, t3], atol=1e-12)
    check_sample(s, 6)


def test_mission_rates_are_derivatives_of_positions():
    m = dynamic_mission()
    t = np.linspace(0.0, 30.0, 30001)
    s = m.sample(t)
    np.testing.assert_allclose(np.gradient(s.xi, t, axis=0)[1:-1], s.xi_dot[1:-1], atol=2e-4)
    np.testing.assert_allclose(np.gradient(s.xi_dot, t, axis=0)[1:-1], s.xi_ddot[1:-1], atol=2e-3)
    assert s.xi[-1, 7] == pytest.approx(-0.5)


def test_overlapping_phases_and_bad_coordinates_raise():
    with pytest.raises(InputError, match="overlap"):
        MultiPhase((Phase("x", 0, 5, 1.0), Phase("x", 4, 6, 2.0)))
    with pytest.raises(UnknownNameError, match="theta2"):  # names are checked against the platform's coordinates
        MultiPhase((Phase("elbow", 0, 1, 1.0),), names=NAMES)
    with pytest.raises(InputError):
        Phase("x", 3, 1, 1.0)


@pytest.mark.parametrize("blend", [0.0, 2.0])
def test_spiral_is_6_25_and_consistent(blend):
    """(6.25) exactly from t_f + blend on; rates and accelerations are the derivatives of the positions."""
    sp = Spiral(blend=blend)
    t = np.linspace(5.0, 30.0, 25001)
    s = sp.sample(t)
    exact = t >= 5.0 + blend
    np.testing.assert_allclose(s.xi[exact, 0], (t[exact] - 5.0) / 5 * np.sin(2 * np.pi * t[exact] / 20), atol=1e-12)
    np.testing.assert_allclose(s.xi[exact, 1], (t[exact] - 5.0) / 5 * np.cos(2 * np.pi * t[exact] / 20), atol=1e-12)
    np.testing.assert_allclose(np.gradient(s.xi[:, 0:2], t, axis=0)[1:-1], s.xi_dot[1:-1, 0:2], atol=1e-5)
    np.testing.assert_allclose(np.gradient(s.xi_dot[:, 0:2], t, axis=0)[1:-1], s.xi_ddot[1:-1, 0:2], atol=1e-5)


def test_printed_spiral_steps_and_the_blended_one_starts_at_rest():
    """(6.25) as printed starts at t_f = 5 s with 0.2 m/s in x and -2 rate w = -0.126 m/s^2 in y (a step
    of the thrust direction (6.17)); faded in by the septic over 2 s it starts at rest, its acceleration
    and jerk continuous (jerk by finite differences of the sampled acceleration)."""
    printed, blended = Spiral(blend=0.0), Spiral()
    before, after = printed.sample([4.999]), printed.sample([5.0])
    assert before.xi_dot[0, 0] == 0.0 and after.xi_dot[0, 0] == pytest.approx(0.2)
    assert before.xi_ddot[0, 1] == 0.0 and after.xi_ddot[0, 1] == pytest.approx(-2 * 0.2 * 2 * np.pi / 20)
    largest_jerk_change = []
    for h in (2e-4, 1e-4):
        t = np.arange(4.9, 7.1, h)
        s = blended.sample(t)
        jerk = np.diff(s.xi_ddot[:, 0:2], axis=0) / h
        near = np.abs(t - 5.0) < 1e-3
        assert np.abs(s.xi_dot[near, 0:2]).max() < 1e-9  # at rest around t_f (|v| = O((t - t_f)^4))
        assert np.abs(jerk[near[1:]]).max() < 1e-4  # no jerk step at t_f (|j| = O((t - t_f)^2))
        largest_jerk_change.append(np.abs(np.diff(jerk, axis=0)).max())
    # jerk continuous on [4.9, 7.1] s: its largest change between samples halves with the spacing
    assert largest_jerk_change[0] / largest_jerk_change[1] == pytest.approx(2.0, rel=0.05)
    with pytest.raises(InputError, match="blend"):
        Spiral(blend=-1.0)


def test_hold_and_sample_checks():
    s = Hold((1, 2, 3, 0, 0, 0, 0, 0, 0)).sample([0.0, 1.0])
    assert s.xi.shape == (2, 9) and np.all(s.xi_dot == 0)
    with pytest.raises(ShapeError):
        check_sample(s, 3)
