"""The simulator on any platform: hover-and-reach with the generic IDC on four platforms, reference limits,
divergence messages, disturbances sized by the platform."""

from __future__ import annotations

import math
import re

import numpy as np
import pinocchio as pin
import pytest

import qprr
import qprr.thesis
from qprr.actuation import AllocationFlag
from qprr.control.base import Controller
from qprr.errors import DivergenceError, InputError, LimitError, ShapeError
from qprr.scenarios import run
from qprr.sim import Limits, Pulse, StateDisturbance, WhiteNoise, simulate
from qprr.thesis.missions import NAMES
from qprr.trajectory import Hold, MultiPhase, Phase


@pytest.fixture(scope="module")
def platforms() -> dict[str, qprr.Platform]:
    return {
        "borinot_flying_arm_2": qprr.load("borinot_flying_arm_2"),
        "hextilt_flying_arm_5": qprr.load("hextilt_flying_arm_5"),
        "HEX-RRR": qprr.build("HEX-RRR"),
        "q-prr": qprr.thesis.load_qprr(),
    }


class OpenLoop(Controller):
    """Constant generalised force (thesis coordinates), switched to ``late`` (NaN entries allowed) after ``t_switch``."""

    name = "open-loop"

    def __init__(self, u, late=None, t_switch=math.inf):
        self.u, self.late, self.t_switch = np.asarray(u, dtype=float), late, t_switch

    def step(self, t, state, ref):
        return self.late if t > self.t_switch else self.u


# ------------------------------------------------------------------------------ hover and reach
@pytest.mark.parametrize("name", ["borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR", "q-prr"])
def test_hover_reach_with_the_generic_idc(platforms, name):
    """Climb to 2 m in 3 s, then every arm joint 60 % of the way to its upper limit in 3 s, generic IDC gains, 10 s.

    Measured (max over the run): position error 0.22-0.48 mm, attitude 3e-6-2e-5 rad, arm 1.0-5.6 mrad; no rotor
    or effort bound active; the fully actuated hextilt stays level (tilt references none: the trajectory's 0)."""
    p = platforms[name]
    res = run("hover-reach", platform=p)
    assert res.status == "ok" and res.n == 10_000 and res.platform == p.name and res.names == p.xi_names
    e = np.abs(res.xi_d - res.xi)
    assert e[:, 0:3].max() < 1e-3
    assert e[:, 3:6].max() < 1e-4
    assert e[:, 6:].max() < 1e-2
    # settled 4 s after the reach; hextilt's arm joints carry the URDF's Coulomb friction (0.1 N m, smoothed over 0.01 rad/s,
    # qprr.dynamics.friction): at rest they creep towards the reference, measured 1.4e-4-3.3e-4 rad 4 s after the reach
    assert e[-1, 0:6].max() < 1e-4 and e[-1, 6:].max() < (5e-4 if p.model.friction.any() else 1e-4)
    rmse = list(res.rmse().values())
    assert max(rmse[0:6]) < 2e-4 and max(rmse[6:]) < 5e-3  # measured <= 1.4e-4 m (base) and <= 1.8e-3 rad (arm)
    # no saturation: every thrust strictly inside its bounds, no effort clipped
    assert not (res.flags & (AllocationFlag.ROTOR_SATURATED | AllocationFlag.ARM_SATURATED)).any() and res.saturation_fraction() == 0.0
    assert np.all(res.f > p.thrust_min) and np.all(res.f < p.thrust_max)
    assert np.all(np.abs(res.arm_effort) <= p.arm_effort_limits)
    # the reach: 60 % of the way from the neutral posture to the upper limits
    q0 = p.neutral_q()[7:]
    np.testing.assert_allclose(res.xi_d[-1, 6:], q0 + 0.6 * (p.arm_upper - q0), rtol=1e-12)
    np.testing.assert_allclose(res.xi_d[-1, 0:3], [0.0, 0.0, 2.0], atol=1e-12)
    if p.fully_actuated:
        assert np.abs(res.xi[:, 3:5]).max() < 1e-4 and not res.xi_d[:, 3:5].any()


# ------------------------------------------------------------------------------ arm references and limits
@pytest.mark.parametrize("name, joint", [("q-prr", "r0"), ("HEX-RRR", "joint2"), ("borinot_flying_arm_2", None)])
def test_arm_reference_beyond_a_joint_limit_is_refused(platforms, name, joint):
    """A reference that crosses a joint limit would hold the joint on its stop: LimitError naming the joint, the value and the
    first time it is out (transition 1-2 s to 1.25 times the upper limit)."""
    p = platforms[name]
    k = p.arm_names.index(joint) if joint else p.n_arm - 1
    joint = p.arm_names[k]
    hi = p.arm_upper[k]
    traj = MultiPhase((Phase(6 + k, 1.0, 2.0, 1.25 * hi),), tuple(p.neutral_xi()), names=p.xi_names)
    t = np.arange(3000) * 1e-3
    first = t[np.argmax(traj.sample(t).xi[:, 6 + k] > hi + 1e-12)]
    with pytest.raises(LimitError) as err:
        simulate(p, OpenLoop(np.zeros(p.n_xi)), traj, 3.0)
    msg = str(err.value)
    assert f"arm joint {joint!r}" in msg and f"t = {first:.3f} s" in msg and 1.0 < first < 2.0
    assert re.search(r"outside its limits \[.*\]", msg)
    # the same reference without stops is the user's choice
    res = simulate(p, OpenLoop(np.zeros(p.n_xi)), traj, 0.01, joint_stops=False)
    assert res.n == 10


def test_initial_arm_state_beyond_a_limit_is_refused(platforms):
    p = platforms["HEX-RRR"]
    xi0 = p.neutral_xi()
    xi0[7] = p.arm_upper[1] + 0.1
    with pytest.raises(LimitError, match=r"xi0\[6:\]: joint2"):
        simulate(p, OpenLoop(np.zeros(p.n_xi)), Hold(tuple(p.neutral_xi())), 0.01, xi0=xi0)


# ------------------------------------------------------------------------------ divergence messages
class _Spin(StateDisturbance):
    """A body moment m_z about z_B."""

    def __init__(self, m_z):
        self.m_z = m_z

    def generalized_force(self, t, q, v):
        tau = np.zeros(v.shape[0])
        tau[5] = self.m_z
        return tau


def test_runaway_rate_names_time_and_variable():
    """No gravity, arm straight up (CoG on z_B, a principal axis once the multirotor's products of inertia are zeroed),
    a 0.5 N m yaw moment: a pure spin omega_z = m_z t / I_zz that reaches the 2 rad/s bound at t* = 2 I_zz / m_z; the run
    stops at the first check after t* (every 16 steps) naming omega_z and the time."""
    p0 = qprr.thesis.thesis_params()
    free = qprr.thesis.load_qprr(p0.with_changes(g=0.0, multirotor_inertia=(*p0.multirotor_inertia[0:3], 0.0, 0.0, 0.0)))
    data = free.data()
    pin.ccrba(free.model, data, free.neutral_q(), np.zeros(9))
    assert np.abs(data.Ig.inertia - np.diag(np.diag(data.Ig.inertia))).max() == 0.0 and np.abs(data.com[0][0:2]).max() == 0.0
    I_zz = data.Ig.inertia[2, 2]
    t_star = 2.0 * I_zz / 0.5
    with pytest.raises(DivergenceError) as err:
        simulate(free, OpenLoop(np.zeros(9)), Hold((0.0,) * 9), 1.0, disturbance=_Spin(0.5), limits=Limits(angular_velocity=2.0))
    m = re.fullmatch(r"diverged at t = (\d+\.\d{3}) s: velocity omega_z = (\S+) \(bound 2\.0\)", str(err.value))
    assert m, str(err.value)
    t_stop, omega = float(m.group(1)), float(m.group(2))
    assert t_star <= t_stop <= t_star + 16e-3 + 5e-4
    assert omega == pytest.approx(0.5 * t_stop / I_zz, rel=1e-9)  # pure spin about z (the rate at the logged time)
    res = err.value.result
    assert res.status == "diverged" and res.reason == str(err.value) and res.t[-1] <= t_stop


@pytest.mark.parametrize("name", ["HEX-RRR", "borinot_flying_arm_2"])
def test_non_finite_controller_output_names_time_and_variable(platforms, name):
    """NaN asked for an arm joint or for z: the controller, the entry by its name and the tick are named."""
    p = platforms[name]
    u = np.zeros(p.n_xi)
    u[2] = p.total_mass * p.g
    xi = tuple(p.neutral_xi())
    for index, pattern in (
        (7, f"controller 'open-loop' returned .* entry {p.arm_names[1]} = nan"),
        (2, "controller 'open-loop' returned .* entry z force/torque = nan"),
    ):
        late = u.copy()
        late[index] = math.nan
        with pytest.raises(DivergenceError, match=r"^diverged at t = 0\.051 s: .*" + pattern) as err:
            simulate(p, OpenLoop(u, late, 0.05), Hold(xi), 1.0)
        assert err.value.result.status == "diverged" and err.value.result.n == 52


# ------------------------------------------------------------------------------ disturbances sized by the platform
def test_disturbances_are_sampled_with_the_platforms_coordinates(platforms):
    p = platforms["borinot_flying_arm_2"]  # n_xi = 8
    u = np.zeros(p.n_xi)
    u[2] = p.total_mass * p.g
    xi = tuple(p.neutral_xi())
    res = simulate(p, OpenLoop(u), Hold(xi), 0.05, disturbance=WhiteNoise(0.3), seed=1)
    assert res.u_ext.shape == (50, 8) and np.all(np.abs(res.u_ext) <= 0.3) and np.abs(res.u_ext).max() > 0.25
    res = simulate(p, OpenLoop(u), Hold(xi), 0.05, disturbance=Pulse(0.01, 0.02, (0.0,) * 7 + (0.01,)))
    assert res.u_ext[10:20, 7].tolist() == [0.01] * 10 and not res.u_ext[:10].any() and not res.u_ext[20:].any()
    with pytest.raises(ShapeError, match="pulse gamma has 9 entries, the platform's xi has 8"):
        simulate(p, OpenLoop(u), Hold(xi), 0.05, disturbance=Pulse(0.01, 0.02, (0.0,) * 9))
    with pytest.raises(ShapeError, match="noise amplitude has 9 entries"):
        simulate(p, OpenLoop(u), Hold(xi), 0.05, disturbance=WhiteNoise((0.3,) * 9))
    with pytest.raises(InputError, match=r"indices 0\.\.7"):
        simulate(p, OpenLoop(u), Hold(xi), 0.05, disturbance=WhiteNoise(0.3, components=(8,)))
    with pytest.raises(ShapeError, match=r"shape \(50, 8\) \(the platform's 6 \+ n_arm\)"):
        simulate(p, OpenLoop(u), MultiPhase((Phase("z", 0.0, 1.0, 1.0),), names=NAMES), 0.05)
