"""The batched plant (qprr.sim.batch) against the scalar simulator, Pinocchio's integrate and its own per-copy path."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from qprr import charts as ch
from qprr.actuation import Allocator
from qprr.charts import State
from qprr.control import make_controller
from qprr.control.base import Controller, Reference
from qprr.errors import InputError, ShapeError
from qprr.platforms import load
from qprr.sim import PayloadChange, PayloadSchedule, SimConfig, simulate
from qprr.sim.batch import BatchSimulator, integrate
from qprr.sim.payload import PlantPayload
from qprr.trajectory import hover_and_reach


class _Recorder(Controller):
    """A controller that records the state the scalar simulator hands it at every tick (Pinocchio's q, v)."""

    def __init__(self, inner: Controller) -> None:
        self.inner, self.name, self.platform, self.output = inner, inner.name, inner.platform, inner.output
        self.q, self.v = [], []

    def reset(self, state, ref, dt) -> None:
        self.inner.reset(state, ref, dt)
        self.dt = dt

    def step(self, t, state, ref):
        self.q.append(state.q.copy())
        self.v.append(state.v.copy())
        return self.inner.step(t, state, ref)


def _mission(platform):
    return hover_and_reach(platform, p_hover=(0.3, -0.2, 1.0), climb=(0.0, 1.5), reach=(1.0, 2.0))


def _scalar_states(platform, config: SimConfig, xi0=None) -> tuple[np.ndarray, np.ndarray]:
    """(q, v) at every control tick of a 2 s IDC flight of the scalar simulator."""
    recorder = _Recorder(make_controller("idc", platform))
    simulate(platform, recorder, _mission(platform), 2.0, config=config, xi0=xi0)
    return np.array(recorder.q), np.array(recorder.v)


def _batch_states(platform, config: SimConfig, n: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The same flight on ``n`` copies of the batch: one IDC and the simulator's allocator per copy (what simulate
    does at a tick: state, controller, allocation, then the plant held over the period)."""
    t = np.arange(int(round(2.0 / config.period))) * config.period
    sample = _mission(platform).sample(t)
    sim = BatchSimulator(platform, n, config, threads=2)
    sim.reset(ch.xi_to_q(sample.xi[0]), np.zeros(platform.nv))
    controllers = [make_controller("idc", platform) for _ in range(n)]
    states = [State(platform.n_arm) for _ in range(n)]
    allocator, f, tau, tau_d = Allocator(platform), np.zeros(platform.n_actuators), np.zeros((n, platform.nv)), np.zeros(platform.nv)
    ref = Reference(sample.xi[0], sample.xi_dot[0], sample.xi_ddot[0])
    for controller, state, q, v in zip(controllers, states, sim.q, sim.v):
        state.update(0.0, q, v)
        controller.reset(state, ref, config.period)
    qs, vs = [], []
    for k, tk in enumerate(t):
        qs.append(sim.q.copy())
        vs.append(sim.v.copy())
        ref = Reference(sample.xi[k], sample.xi_dot[k], sample.xi_ddot[k])
        for i, (controller, state) in enumerate(zip(controllers, states)):
            state.update(tk, sim.q[i], sim.v[i])
            out = controller.step(tk, state, ref)
            allocator.allocate_screened_into(out if controller.output == "pinocchio" else state.force_from_xi(out, tau_d), f, tau[i])
        sim.step(tau, config.substeps)
    return np.array(qs), np.array(vs)


@pytest.mark.parametrize("integrator", ["euler", "midpoint", "rk4"])
@pytest.mark.parametrize("name", ["q-prr", "borinot_flying_arm_2"])
def test_batch_matches_the_scalar_simulator(name, integrator):
    """Issue 32: step by step, every copy within 1e-12 of simulate() over a 2 s closed-loop flight."""
    platform = load(name)
    config = SimConfig(dt=1e-3, integrator=integrator)
    q_ref, v_ref = _scalar_states(platform, config)
    q, v = _batch_states(platform, config)
    assert np.abs(q - q_ref[:, None, :]).max() <= 1e-12
    assert np.abs(v - v_ref[:, None, :]).max() <= 1e-12


@pytest.mark.parametrize("integrator", ["euler", "midpoint", "rk4"])
def test_batch_matches_the_scalar_simulator_with_stiff_friction(integrator):
    """hextilt_flying_arm_5 (URDF damping and Coulomb friction, its wrist implicit at 1 ms): within 1e-12 of simulate()
    too.  Its Coulomb reversals amplify round-off (the scalar simulator itself moves by about 2e-12 when its initial
    position moves by 2e-16 m), so the batch must do the scalar simulator's arithmetic: ``pin.integrate`` per copy."""
    platform = load("hextilt_flying_arm_5")
    config = SimConfig(dt=1e-3, integrator=integrator)
    q_ref, v_ref = _scalar_states(platform, config)
    q, v = _batch_states(platform, config)
    assert np.abs(q - q_ref[:, None, :]).max() <= 1e-12
    assert np.abs(v - v_ref[:, None, :]).max() <= 1e-12


def _random_configurations(model: pin.Model, n: int, rng) -> np.ndarray:
    return np.array([pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)) for _ in range(n)])


@pytest.mark.parametrize("scale", [1e-9, 1e-5, 1e-3, 0.1, 1.0, 3.0])
def test_integrate_is_pinocchios(scale):
    """The vectorised q (+) dq equals pin.integrate row by row, across the Taylor threshold and for large turns."""
    model = load("hextilt_flying_arm_5").model
    rng = np.random.default_rng(7)
    q = _random_configurations(model, 50, rng)
    dq = scale * rng.standard_normal((50, model.nv))
    expected = np.array([pin.integrate(model, qi, dqi) for qi, dqi in zip(q, dq)])
    assert np.abs(integrate(q, dq) - expected).max() <= 1e-14


def test_copies_are_independent_and_the_per_copy_path_agrees():
    """Copy i of a batch with inputs tau_i moves as a batch of one with tau_i; the per-copy models path (taken when a
    payload or mass scale is set) gives the pool's accelerations when the models are the nominal ones."""
    platform = load("borinot_flying_arm_2")
    rng = np.random.default_rng(3)
    sim = BatchSimulator(platform, 4, SimConfig(integrator="rk4"), threads=2)
    hover = Allocator(platform).hover_thrusts()
    tau = sim.tau_from_thrusts(hover * (1.0 + 0.05 * rng.standard_normal((4, platform.n_rotors))))
    sim.step(tau, 50)
    for i in range(4):
        one = BatchSimulator(platform, 1, SimConfig(integrator="rk4"), threads=1)
        one.step(tau[i : i + 1], 50)
        np.testing.assert_allclose(one.q[0], sim.q[i], rtol=0, atol=1e-14)
    pool_a = sim.acceleration(sim.q, sim.v, tau)
    sim.set_payload(0.0)
    assert sim.models is not None
    np.testing.assert_allclose(sim.acceleration(sim.q, sim.v, tau), pool_a, rtol=0, atol=1e-12)


def test_payload_and_mass_scale_are_the_plant_models():
    """set_payload is PlantPayload's model; set_mass_scale scales the base body's mass and rotational inertia."""
    platform = load("q-prr")
    sim = BatchSimulator(platform, 3, threads=1)
    sim.set_payload([0.0, 0.4, 0.0])
    sim.set_mass_scale(1.2, index=[2])
    plant = PlantPayload(platform, PayloadSchedule((PayloadChange(0.0, 0.4),)))
    plant.apply_until(0.0)
    tau = np.tile(Allocator(platform).hover_thrusts() @ platform.rotor_matrix.T, (3, 1))
    tau = np.concatenate([tau, np.zeros((3, platform.n_arm))], axis=1)
    a = sim.acceleration(sim.q, sim.v, tau)
    expected = pin.aba(plant.model, plant.model.createData(), sim.q[1], sim.v[1], tau[1])
    np.testing.assert_allclose(a[1], expected, rtol=0, atol=1e-12)
    masses = [sum(inertia.mass for inertia in model.inertias) for model in sim.models]
    assert masses[1] == pytest.approx(masses[0] + 0.4, abs=1e-12)
    assert masses[2] == pytest.approx(masses[0] + 0.2 * platform.model.inertias[1].mass, abs=1e-12)
    assert a[1, 2] < a[0, 2]  # the loaded copy sinks under the nominal hover thrust


def test_joint_stops_and_divergence():
    """A copy driven into its joint limit ends on the stop (qprr.sim.stops); a copy pushed to NaN is flagged."""
    platform = load("q-prr")
    sim = BatchSimulator(platform, 2, threads=1)
    effort = np.zeros((2, platform.n_arm))
    effort[0, 0] = 20.0  # push the prismatic joint outward
    sim.step(sim.tau_from_thrusts(np.tile(Allocator(platform).hover_thrusts(), (2, 1)), effort), 500)
    assert sim.q[0, 7] == pytest.approx(platform.arm_upper[0], abs=1e-12)
    assert not sim.diverged().any()
    sim.v[1, 0] = np.nan
    assert sim.diverged().tolist() == [False, True]


def test_bad_inputs_are_refused():
    platform = load("q-prr")
    with pytest.raises(InputError, match="n must"):
        BatchSimulator(platform, 0)
    sim = BatchSimulator(platform, 2, threads=1)
    with pytest.raises(ShapeError, match=r"tau must have shape \(2, 9\)"):
        sim.step(np.zeros((3, 9)))
    with pytest.raises(InputError, match="tau must be finite"):
        sim.step(np.full((2, 9), np.nan))
    with pytest.raises(InputError, match="mass must be finite and >= 0 kg"):
        sim.set_payload(-0.1)
    with pytest.raises(InputError, match="scale must be > 0"):
        sim.set_mass_scale(0.0)
    q = platform.neutral_q()
    q[3:7] = [0.0, 0.0, 0.0, 2.0]
    with pytest.raises(InputError, match="unit quaternions"):
        sim.reset(q, np.zeros(platform.nv))
    with pytest.raises(InputError, match="config must be a qprr.sim.SimConfig"):
        BatchSimulator(platform, 1, config={"dt": 1e-3})
