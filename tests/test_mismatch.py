"""Model errors: perturbed plant copies, the plant's actuators, and the physics of a mismatched run."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from qprr.actuation import AllocationFlag
from qprr.charts import xi_to_q
from qprr.control.base import Controller
from qprr.dynamics import generalized_gravity
from qprr.errors import InputError
from qprr.payload import with_payload
from qprr.scenarios import SCENARIOS, run
from qprr.sim import simulate
from qprr.sim.mismatch import ModelError, perturbed
from qprr.thesis import load_qprr
from qprr.trajectory import Hold

XI0 = np.array([0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def platform():
    return load_qprr()


class ConstantTau(Controller):
    """Open loop: a constant Pinocchio generalised force."""

    name = "constant-tau"
    output = "pinocchio"

    def __init__(self, tau):
        self.tau = np.asarray(tau, dtype=float)

    def step(self, t, state, ref):
        return self.tau


def _hover_tau(platform):
    return generalized_gravity(platform, platform.data(), xi_to_q(XI0))


def test_perturbed_scales_bodies_and_rotors_on_a_copy(platform):
    before = [pin.Inertia(Y) for Y in platform.model.inertias]
    e = ModelError(mass=1.2, arm_mass=0.5, inertia=0.8, kappa=1.3, f_max=0.9)
    p = perturbed(platform, e)
    for j in range(1, platform.model.njoints):
        Y, Z = platform.model.inertias[j], p.model.inertias[j]
        assert Y == before[j]  # the model is untouched
        assert Z.mass == pytest.approx(Y.mass * 1.2 * (0.5 if j >= 2 else 1.0), rel=1e-15)
        np.testing.assert_array_equal(Z.lever, Y.lever)
        np.testing.assert_allclose(Z.inertia, 0.8 * Y.inertia, rtol=1e-15, atol=0)
    for r, s in zip(platform.rotors, p.rotors):
        assert s.kappa == pytest.approx(1.3 * r.kappa, rel=1e-15) and s.f_max == pytest.approx(0.9 * r.f_max, rel=1e-15)
        assert s.position_body == r.position_body and s.f_min == r.f_min


def test_payload_error_is_the_known_payload_model(platform):
    p = perturbed(platform, ModelError(payload=0.25))
    ref = with_payload(platform, 0.25)
    assert p.total_mass == pytest.approx(platform.total_mass + 0.25, rel=1e-14)
    for j in range(platform.model.njoints):
        np.testing.assert_allclose(p.model.inertias[j].matrix(), ref.model.inertias[j].matrix(), rtol=0, atol=1e-15)


@pytest.mark.parametrize("kwargs", [{"mass": 0.0}, {"inertia": -1.0}, {"kappa": float("nan")}, {"f_max": True}, {"payload": -0.1}])
def test_model_error_rejects_bad_factors_naming_them(kwargs):
    with pytest.raises(InputError, match=next(iter(kwargs))):
        ModelError(**kwargs)


@pytest.mark.parametrize("s", [0.8, 1.1, 1.5])
def test_heavier_plant_under_nominal_hover_force_falls_at_g_times_one_minus_one_over_s(platform, s):
    """Every mass and inertia times s: M_p = s M, g_p = s g, so tau = g gives a = (1/s - 1) M^-1 g,
    the free fall of the whole robot scaled by (1 - 1/s): z(t) = z0 - (1 - 1/s) g t^2 / 2, no rotation."""
    plant = perturbed(platform, ModelError(mass=s, inertia=s))
    res = simulate(platform, ConstantTau(_hover_tau(platform)), Hold(XI0), 0.5, plant=plant, joint_stops=False)
    expected = XI0[2] - 0.5 * (1.0 - 1.0 / s) * platform.g * res.t**2
    np.testing.assert_allclose(res.xi[:, 2], expected, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res.xi[:, [0, 1, 3, 4, 5, 6, 7, 8]], 0.0, atol=1e-10)
    nominal = simulate(platform, ConstantTau(_hover_tau(platform)), Hold(XI0), 0.5, joint_stops=False)
    np.testing.assert_allclose(nominal.xi[:, 2], XI0[2], atol=1e-10)  # the model itself hovers


def test_plant_rotors_apply_their_own_drag_ratio(platform):
    """Yaw torque tz asked: the model's allocation commands the thrusts, the plant's kappa k turns them into k tz."""
    k, tz = 1.25, 0.05
    tau = _hover_tau(platform)
    tau[5] += tz
    plant = perturbed(platform, ModelError(kappa=k))
    res = simulate(platform, ConstantTau(tau), Hold(XI0), 0.01, plant=plant, joint_stops=False)
    nominal = simulate(platform, ConstantTau(tau), Hold(XI0), 0.01, joint_stops=False)
    np.testing.assert_array_equal(res.f[0], nominal.f[0])  # same commands
    assert res.unallocated[0, 5] == pytest.approx((1.0 - k) * tz, abs=1e-12)  # tau_d - N_plant f on the yaw row
    np.testing.assert_allclose(res.unallocated[0, [0, 1, 2, 3, 4, 6, 7, 8]], 0.0, atol=1e-12)


def test_weak_plant_rotors_clip_the_commands_and_flag_it(platform):
    plant = perturbed(platform, ModelError(f_max=0.1))
    f_cap = 0.1 * platform.thrust_max
    hover = ConstantTau(_hover_tau(platform))
    res = simulate(platform, hover, Hold(XI0), 0.05, plant=plant, joint_stops=False)
    assert np.all(hover.tau[2] / 4 > f_cap)  # the hover thrust is beyond the weak rotors
    np.testing.assert_array_equal(res.f, np.broadcast_to(f_cap, res.f.shape))
    assert np.all(res.flags & AllocationFlag.ROTOR_SATURATED)
    assert res.saturation_fraction() == 1.0


def test_scenario_with_nominal_plant_equals_the_plain_run(platform):
    a = run("static-idc", platform=platform, duration=0.5)
    b = run("static-idc", platform=platform, duration=0.5, plant=perturbed(platform, ModelError()))
    np.testing.assert_allclose(b.xi, a.xi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.f, a.f, rtol=0, atol=1e-9)


def test_scenarios_that_cannot_take_a_plant_say_so(platform):
    takes = {n for n, s in SCENARIOS.items() if s.takes_plant}
    assert {"hover-reach", "static-idc", "static-dsid", "static-mfc", "dynamic-bsg", "noise", "payload-drop"} <= takes
    assert "push-thrust" not in takes
    with pytest.raises(InputError, match="push-thrust"):
        run("push-thrust", platform=platform, plant=perturbed(platform, ModelError()))


def test_plant_of_another_structure_is_rejected(platform):
    import qprr

    other = qprr.load("borinot_flying_arm_2")
    with pytest.raises(InputError, match="structure"):
        run("static-idc", platform=platform, duration=0.1, plant=other)
