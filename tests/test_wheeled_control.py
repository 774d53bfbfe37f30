"""Feedback laws on the exact kinematic simulator: convergence, rates, the zero-order-hold floor."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qprr.charts import wrap_angle
from qprr.errors import InputError
from qprr.wheeled import control as ctl
from qprr.wheeled.robots import Car, Unicycle
from qprr.wheeled.sim import simulate_wheeled


def _err(res, ref, offset=0.0):
    P = res.q[:, :2] + offset * np.column_stack([np.cos(res.q[:, 2]), np.sin(res.q[:, 2])])
    return np.linalg.norm(P - np.array([ref.derivatives(t)[0] for t in res.t]), axis=1)


def test_kanayama_tracking_converges_to_the_zero_order_hold_floor():
    """The residual error is the sampling's: it halves with dt (first order), the law itself converges."""
    ref = ctl.Lemniscate()
    floors = []
    for dt in (0.04, 0.02):
        r = simulate_wheeled(Unicycle(), [0.5, -0.6, 0.4], ctl.KanayamaTracking(ref), 30.0, dt)
        e = _err(r, ref)
        floors.append(e[int(22 / dt) :].max())
        assert e[0] > 0.7
    assert floors[1] < 5e-3
    assert floors[0] / floors[1] == pytest.approx(2.0, rel=0.25)


def test_point_tracking_decays_at_the_chosen_rate():
    """I/O linearisation: B_dot = p_d' + k (p_d - B) gives |e(t)| = |e(0)| exp(-k t) (up to the hold)."""
    ref, k = ctl.Circle(), 2.0
    r = simulate_wheeled(Unicycle(), [1.0, -0.5, 0.0], ctl.PointTracking(ref, b=0.2, k=k), 2.0, 0.001)
    e = _err(r, ref, 0.2)
    assert e[-1] / e[0] == pytest.approx(math.exp(-k * 2.0), rel=0.02)


@pytest.mark.parametrize("start", [(-2.0, 1.5, 0.5), (1.5, 1.5, 3.0), (0.0, 1.0, 0.0), (-1.0, -1.0, -2.5)])
def test_polar_posture_regulation_reaches_the_goal(start):
    goal = np.array([0.5, -0.3, 0.4])
    r = simulate_wheeled(Unicycle(), start, ctl.PosturePolar(goal), 30.0, 0.02)
    assert np.linalg.norm(r.q[-1, :2] - goal[:2]) < 1e-6
    assert abs(wrap_angle(r.q[-1, 2] - goal[2])) < 1e-6


def test_car_tracking_by_dynamic_feedback_linearisation():
    ref = ctl.Lemniscate(a=4.5, w=0.15)
    car = Car()
    floors = []
    for dt in (0.04, 0.02):
        r = simulate_wheeled(car, [0.3, -0.4, 0.6, 0.0], ctl.CarTracking(ref, car.D), 24.0, dt)
        floors.append(_err(r, ref)[int(16 / dt) :].max())
        assert np.abs(r.q[int(10 / dt) :, 3]).max() <= car.psi_max  # within the steering limit once converged
    assert floors[1] < 5e-3 and floors[0] / floors[1] == pytest.approx(2.0, rel=0.25)


def test_sinusoidal_parking_reaches_the_posture():
    """Murray-Sastry sinusoids in chained form: 1 m sideways; the error is the hold's (falls with dt)."""
    car = Car()
    goal = np.array([0.0, 1.0, 0.0, 0.0])
    errs = []
    for dt in (0.04, 0.02):
        pk = ctl.SinusoidalParking(goal, car.D)
        r = simulate_wheeled(car, np.zeros(4), pk, pk.duration, dt)
        errs.append(np.linalg.norm(r.q[-1] - goal))
        assert np.abs(r.q[:, 3]).max() < car.psi_max
    assert errs[1] < 1e-3 and errs[0] / errs[1] > 2.0


def test_chained_form_of_the_car():
    """z3' = z2 v1 and z4' = z3 v1 with v1 = u1 cos theta: the chained form holds for the car's velocities."""
    car = Car()
    pk = ctl.SinusoidalParking([0, 1, 0, 0], car.D)
    q, u, h = np.array([0.2, 0.1, 0.3, 0.2]), np.array([0.7, 0.4]), 1e-6
    z0, z1 = pk.chained(q), pk.chained(car.flow(q, u, h))
    zd = (z1 - z0) / h
    v1 = u[0] * math.cos(q[2])
    assert zd[0] == pytest.approx(v1, rel=1e-5) and zd[2] == pytest.approx(z0[1] * v1, rel=1e-5)
    assert zd[3] == pytest.approx(z0[2] * v1, rel=1e-5)


def test_controller_input_errors():
    with pytest.raises(InputError, match="gain kx"):
        ctl.KanayamaTracking(ctl.Circle(), kx=-1.0)
    with pytest.raises(InputError, match="chained form"):
        ctl.SinusoidalParking([0, 0, 2.0, 0], 0.5)
    with pytest.raises(InputError, match="speed is zero"):
        ctl.reference_posture(ctl.Circle(R=1.0, w=0.0), 0.0)
