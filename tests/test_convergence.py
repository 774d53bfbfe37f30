"""Convergence as a property: the observed order of every integrator, with every input the simulator has.

For each case the integration step is halved three times, dt = T_c / s, T_c / 2s, T_c / 4s,
T_c / 8s, while the control period T_c stays fixed (the controller, the noise samples, the
payload changes and the switched wrenches sit on the control grid, so every run integrates
the same sampled-data system), and the state at the last control tick is compared with an RK4
run at T_c / 256.  The error is the largest entry of the Lie-group difference
q_ref (-) q (``pin.difference``), of v - v_ref and, with a contact model, of the object's
state.  The observed order log2(e(dt) / e(dt/2)) must be 1 for semi-implicit Euler, 2 for
the explicit midpoint rule and 4 for RK4, within +-0.2, for all three halvings.

Cases: free motion (no gravity, no input); gravity with constant thrust; each hook
(state-dependent end-effector wrench, state-dependent disturbance, payload change, white
noise, contact model with its own state); closed loop with each controller (Sec. 6.3: IDC,
desired-state ID, MFC, BSG + MFC; Sec. 6.4: payload IDC with a payload release, impedance
control with an end-effector wrench and base pulses).  The start step ``s`` per integrator
puts every ladder in its asymptotic range and above round-off (the MFC differentiates
measured velocities, which sets a floor near 1e-11).  Run ``python -m tests.test_convergence``
for the table of errors and orders.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
import pytest

import qprr.thesis
from qprr import kinematics as qm
from qprr import sim as it
from qprr.actuation import AllocationFlag
from qprr.charts import xi_to_qv
from qprr.control import PayloadIDC
from qprr.control.base import Controller
from qprr.control.impedance import ImpedanceController
from qprr.model import Platform
from qprr.sim import BaseDrag, PayloadChange, PayloadSchedule, Pulse, WhiteNoise, simulate
from qprr.sim.integrators import ORDERS
from qprr.thesis import gains
from qprr.thesis.bsg import CogStabilizer
from qprr.thesis.scenarios import flight_controller
from qprr.trajectory import Hold, TrajectorySample

REFERENCE_DIVISOR = 256
TOLERANCE = 0.2


class _Tau(Controller):
    """Constant generalised force in Pinocchio coordinates (constant rotor thrusts and arm efforts)."""

    output = "pinocchio"
    name = "constant"

    def __init__(self, tau) -> None:
        self.tau = np.asarray(tau, dtype=float)

    def step(self, t, state, ref):
        return self.tau


class _Ramp:
    """xi_d(t) = xi0 + t rate."""

    def __init__(self, xi0, rate) -> None:
        self.xi0, self.rate = np.asarray(xi0, dtype=float), np.asarray(rate, dtype=float)

    def sample(self, t) -> TrajectorySample:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        n = t.shape[0]
        return TrajectorySample(t, self.xi0 + t[:, None] * self.rate, np.tile(self.rate, (n, 1)), np.zeros((n, 9)))


ROBOT = qprr.thesis.load_qprr()
FREE = qprr.thesis.load_qprr(qprr.thesis.thesis_params().with_changes(g=0.0))
_M, _G = ROBOT.params.total_mass, ROBOT.params.g

# free tumbling with the arm moving (as tests/test_sim.py)
XI_FREE = np.r_[0, 0, 1, 0.1, -0.2, 0.3, 0.01, 0.3, -0.4]
XID_FREE = np.r_[0.5, -0.3, 0.2, 1.0, -2.0, 0.7, 0.05, 1.5, -2.0]
# open loop in gravity: arm hanging (a stable pendulum; joint stops off), 5 % more thrust than the weight,
# the arm efforts that hold it at rest plus a little
XI_OPEN = np.r_[0, 0, 1, 0.05, -0.05, 0.3, 0.01, 2.9, 0.3]
XID_OPEN = np.r_[0.3, -0.2, 0.1, 0.3, -0.4, 0.2, 0.02, 0.5, -0.6]
_G_OPEN = pin.computeGeneralizedGravity(ROBOT.model, ROBOT.model.createData(), xi_to_qv(XI_OPEN, np.zeros(9))[0])
TAU_OPEN = np.r_[0, 0, 1.05 * _M * _G, 0.01, -0.01, 0.005, _G_OPEN[6:9] + np.r_[0.05, 0.005, -0.001]]
# closed loop: off the reference, moving
XI_REF = np.r_[0, 0, 1, 0, 0, 0.2, 0.0, 0.3, -0.3]
XI_CL = np.r_[0.05, -0.05, 0.95, 0.05, -0.05, 0.1, 0.01, 0.4, -0.2]
XID_CL = np.r_[0.4, -0.2, 0.2, 0.4, -0.4, 0.2, 0.04, 0.6, -0.6]


_SPRING_DATA = ROBOT.model.createData()


def _ee_spring(t, q, v):
    """Stateless end-effector hook: a spring-damper (5 N/m, 0.5 N s/m) to a fixed point, from the stage's (q, v)."""
    J = pin.computeFrameJacobian(ROBOT.model, _SPRING_DATA, q, ROBOT.ee_frame, pin.LOCAL_WORLD_ALIGNED)
    p = _SPRING_DATA.oMf[ROBOT.ee_frame].translation
    h = np.zeros(6)
    h[0:3] = -5.0 * (p - np.r_[0.3, 0.1, 1.2]) - 0.5 * (J @ v)[0:3]
    return h


def _open(**extra):
    return ROBOT, _Tau(TAU_OPEN), Hold(tuple(XI_OPEN)), dict(xi0=XI_OPEN, xi_dot0=XID_OPEN, joint_stops=False, **extra)


def _closed(controller, **extra):
    kw = dict(xi0=XI_CL, xi_dot0=XID_CL, joint_stops=False)
    kw.update(extra)
    return ROBOT, controller, Hold(tuple(XI_REF)), kw


def _hooked_object():
    """IDC drags a 0.5 kg object with the hooked end effector (arm horizontal, contact pushing the end effector outward:
    the arm in tension), base reference moving at -0.2 m/s along x; the object slides (friction 0.05) all the time,
    in contact all the time: no event of the contact model during the run."""
    V, mu, mass, k = 0.2, 0.05, 0.5, 500.0
    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0])
    p0, _ = qm.ee_pose_xi(ROBOT, ROBOT.data(), xi0)
    pen = mu * mass * _G / k  # the steady sliding force
    obj = it.PushedMass(
        ROBOT, mass=mass, origin=p0 + np.r_[pen, 0.0, 0.0], direction=(-1.0, 0.0, 0.0), initial=(0.0, V), stiffness=k, damping=5.0, friction=mu
    )
    rate = np.r_[-V, np.zeros(8)]
    return ROBOT, flight_controller("idc", ROBOT), _Ramp(xi0, rate), dict(xi0=xi0, xi_dot0=rate, external_wrench=obj, joint_stops=False)


def _impedance():
    hb = np.r_[0.2, 0.0, 0.0, 0.0]
    ee = it.PrescribedWrench(np.r_[0.05, 0.01, 0.05, 0.0, 0.0, 0.0], 0.1, 0.4)
    gamma = np.zeros(9)
    gamma[[0, 1, 2, 5]] = hb
    ctrl = ImpedanceController(
        ROBOT, gains.impedance_idc(), gains.impedance_filters(), ee_sensor=ee.measured, base_sensor=lambda t: hb if 0.1 <= t < 0.4 else np.zeros(4)
    )
    return _closed(ctrl, external_wrench=ee, disturbance=Pulse(0.1, 0.4, tuple(gamma)))


def _payload_idc():
    # starts at rest on its reference carrying 0.1 kg it does not know of, released at 0.2 s (off the 8 ms grid:
    # the release acts at the tick 0.208 s)
    sched = PayloadSchedule((PayloadChange(0.0, 0.1), PayloadChange(0.2, 0.0)))
    return _closed(PayloadIDC(ROBOT, gains.payload_idc(), payload="estimate"), xi0=XI_REF, xi_dot0=np.zeros(9), payload=sched)


@dataclass(frozen=True)
class Case:
    """A run to measure: ``build() -> (robot, controller, trajectory, simulate kwargs)`` (fresh objects every call)."""

    build: Callable[[], tuple]
    control_period: float = 8e-3
    duration: float = 0.5
    start: dict = field(default_factory=lambda: {"euler": 4, "midpoint": 2, "rk4": 2})


_CL = {"euler": 4, "midpoint": 2, "rk4": 1}
CASES: dict[str, Case] = {
    "free motion": Case(lambda: (FREE, _Tau(np.zeros(9)), Hold(tuple(XI_FREE)), dict(xi0=XI_FREE, xi_dot0=XID_FREE, joint_stops=False))),
    "gravity + constant thrust": Case(_open),
    "hook: end-effector wrench": Case(lambda: _open(external_wrench=_ee_spring), start={"euler": 4, "midpoint": 2, "rk4": 1}),
    "hook: state disturbance (drag)": Case(lambda: _open(disturbance=BaseDrag(0.5, 0.05))),
    "hook: payload change": Case(lambda: _open(payload=PayloadSchedule((PayloadChange(0.0, 0.1), PayloadChange(0.1, 0.0))))),
    "hook: noise (6.27)": Case(lambda: _open(disturbance=WhiteNoise((0.3,) * 7 + (0.01, 0.01)))),
    "hook: contact model (idc)": Case(_hooked_object),
    "closed loop: idc": Case(lambda: _closed(flight_controller("idc", ROBOT)), start=_CL),
    "closed loop: dsid": Case(lambda: _closed(flight_controller("dsid", ROBOT)), control_period=4e-3, start=_CL),
    "closed loop: mfc": Case(lambda: _closed(flight_controller("mfc", ROBOT)), start=_CL),
    "closed loop: bsg + mfc": Case(lambda: _closed(CogStabilizer(ROBOT, flight_controller("mfc", ROBOT))), start=_CL),
    "closed loop: payload-idc": Case(_payload_idc, start={"euler": 8, "midpoint": 2, "rk4": 1}),
    "closed loop: impedance": Case(_impedance, start={"euler": 4, "midpoint": 4, "rk4": 2}),
}


def final_state(case: Case, integrator: str, substeps: int) -> tuple[Platform, np.ndarray, np.ndarray, np.ndarray]:
    """(robot, q, v, z) at the last control tick of ``case`` run with dt = T_c / substeps."""
    robot, ctrl, traj, kw = case.build()
    T = case.control_period
    res = simulate(robot, ctrl, traj, case.duration, dt=T / substeps, control_period=T, integrator=integrator, **kw)
    assert res.status == "ok" and not (res.flags & AllocationFlag.JOINT_STOP).any()
    q, v = xi_to_qv(res.xi[-1], res.xi_dot[-1])
    env = kw.get("external_wrench")
    z = np.zeros(0)
    if hasattr(env, "history") and env.state_size:
        h = env.history()
        z = np.array([h.position[-1], h.velocity[-1]])
    return robot, q, v, z


def state_error(robot, a, b) -> float:
    return max(
        float(np.abs(pin.difference(robot.model, a[0], b[0])).max()),
        float(np.abs(a[1] - b[1]).max()),
        float(np.abs(a[2] - b[2]).max()) if a[2].size else 0.0,
    )


def observed_orders(case: Case, integrator: str, reference=None) -> tuple[np.ndarray, np.ndarray]:
    """(errors (4,), orders (3,)) of ``integrator`` on ``case`` against the RK4 reference at T_c / 256."""
    if reference is None:
        reference = final_state(case, "rk4", REFERENCE_DIVISOR)
    robot = reference[0]
    s0 = case.start[integrator]
    errors = np.array([state_error(robot, final_state(case, integrator, s0 * 2**i)[1:], reference[1:]) for i in range(4)])
    return errors, np.log2(errors[:-1] / errors[1:])


@pytest.fixture(scope="module")
def references():
    out: dict[str, tuple] = {}

    def get(name: str):
        if name not in out:
            out[name] = final_state(CASES[name], "rk4", REFERENCE_DIVISOR)
        return out[name]

    return get


@pytest.mark.parametrize("integrator", list(ORDERS))
@pytest.mark.parametrize("name", list(CASES))
def test_observed_order(name, integrator, references):
    errors, orders = observed_orders(CASES[name], integrator, references(name))
    expected = ORDERS[integrator]
    assert np.all(np.abs(orders - expected) <= TOLERANCE), f"{name}, {integrator}: errors {errors}, orders {orders}"


def _invariants(robot, q, v) -> np.ndarray:
    d = robot.model.createData()
    h = pin.computeCentroidalMomentum(robot.model, d, q, v)
    return np.r_[pin.computeKineticEnergy(robot.model, d, q, v), h.linear, h.angular]


@pytest.mark.parametrize("integrator", list(ORDERS))
def test_free_motion_energy_and_momentum_drift_orders(integrator):
    """Free motion conserves kinetic energy and centroidal momentum; their drift over 0.5 s converges at the integrator's order."""
    case = CASES["free motion"]
    robot, ctrl, traj, kw = case.build()
    q0, v0 = xi_to_qv(kw["xi0"], kw["xi_dot0"])
    I0 = _invariants(robot, q0, v0)
    drift = []
    for i in range(4):
        _, q, v, _ = final_state(case, integrator, case.start[integrator] * 2**i)
        d = np.abs(_invariants(robot, q, v) - I0)
        drift.append([d[0] / I0[0], d[1:4].max(), d[4:7].max()])  # relative energy, linear and angular momentum
    drift = np.array(drift)
    orders = np.log2(drift[:-1] / drift[1:])
    assert np.all(np.abs(orders - ORDERS[integrator]) <= TOLERANCE), f"{integrator}: drift {drift}, orders {orders}"


def table() -> str:
    """The observed orders of every integrator on every case, as a text table (python -m tests.test_convergence)."""
    lines = [f"{'case':<34}" + "".join(f"{k + ' e(dt0)':>16}{k + ' orders':>24}" for k in ORDERS)]
    for name, case in CASES.items():
        ref = final_state(case, "rk4", REFERENCE_DIVISOR)
        row = f"{name:<34}"
        for integ in ORDERS:
            e, p = observed_orders(case, integ, ref)
            row += f"{e[0]:>16.1e}{' '.join(f'{x:5.2f}' for x in p):>24}"
        lines.append(row)
    return "\n".join(lines)


if __name__ == "__main__":
    print(table())
