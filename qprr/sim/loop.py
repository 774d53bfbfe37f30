"""Closed-loop simulation of any platform: Pinocchio ABA on the Lie group, fixed step.

A digital controller of period ``control_period`` (default: the integration step ``dt``)
drives the plant; at each control tick t_k:

1. state (q, v) -> thesis coordinates (xi, xi_dot) (:class:`qprr.charts.State`);
2. the controller returns the desired generalised force u (thesis coordinates, Thesis (5.40))
   or Pinocchio's tau (controllers with ``output = "pinocchio"``);
3. tau_d = S^-T u is allocated to the rotor thrusts in [f_min, f_max] and the arm efforts
   (:class:`qprr.actuation.Allocator`); the applied force is tau = N f (Thesis (5.43));
4. the disturbances known in advance are added: u_ext of Thesis (6.27) (white noise, pulses
   (6.28)) as S^-T u_ext, sampled at the tick; payload changes take effect at the tick;
5. tau is held over the period (zero-order hold: the physics of a digital controller) while
   the plant is integrated over the period with ``control_period / dt`` steps of the
   integrator; ABA (LOCAL convention) gives a = M^-1 (tau + tau_state - h(q, v)) at every
   stage, where tau_state holds the inputs that depend on the state and are evaluated at
   that stage: the end-effector wrench J_e^T h (Jacobian and contact force) and the
   :class:`~qprr.sim.disturbances.StateDisturbance` forces.  An
   :class:`~qprr.sim.environment.Environment` (contact model with its own state, e.g. a pushed
   object) is integrated together with the robot by the same integrator.

Optional actuator stage (``actuators=``, :mod:`qprr.sim.actuators`, off by default): the
allocated thrusts of step 3 are then speed *commands* of rotors with a first-order motor lag;
the rotor speeds are extra states integrated with the robot (and an environment's state) by
the same integrator, and the base wrench Omega f(w) is evaluated at every stage.  The logged
``f`` is then the thrust the rotors produce at the tick (b w^2); ``series`` hold
``thrust_command`` and ``rotor_speed``.  State-dependent disturbances
(:class:`~qprr.sim.disturbances.StateDisturbance`) are realized once per run from the run's seed
(:meth:`~qprr.sim.disturbances.StateDisturbance.realize`: the wind's turbulence, :mod:`qprr.sim.wind`).

Integrators (``integrator=``, :mod:`qprr.sim.integrators`, all on the Lie group): ``"midpoint"``
(default: explicit midpoint, two ABA per step, second order), ``"rk4"`` (Runge-Kutta 4 in the
tangent chart at q_k, fourth order: the accuracy reference), ``"euler"`` (semi-implicit, first
order; its energy drifts and it flatters tracking errors).  The orders hold for every input
above (tests/test_convergence.py measures them).  ABA runs in Pinocchio's LOCAL convention,
which does not lose precision far from the world origin.

A run that produces NaN, leaves the workspace bound or reaches the Euler singularity raises
:class:`~qprr.errors.DivergenceError` naming the time and the state variable; another qprr error
during the run is re-raised with the time and the state; the partial result is attached as
``error.result`` in both cases.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..actuation import AllocationFlag, Allocator
from ..charts import State
from ..control.base import Controller, Reference
from ..dynamics.friction import JointFriction, Treatment
from ..errors import DivergenceError, InputError, LimitError, NonFiniteError, QprrError, ShapeError
from ..model import Platform
from ..progress import Progress
from ..trajectory import Trajectory, TrajectorySample
from ..validation import as_int, as_vector
from . import disturbances as dist
from .actuators import RotorDynamics
from .config import INTEGRATORS, Limits, SimConfig, SimInputs, config_and_inputs
from .environment import Environment
from .integrators import make_stepper
from .mismatch import PlantActuators, check_plant
from .payload import PayloadSchedule, PlantPayload
from .result import SimResult, Status
from .stops import apply_joint_stops

__all__ = ["INTEGRATORS", "Limits", "SimConfig", "SimInputs", "check_sample", "simulate"]


def simulate(
    platform: Platform,
    controller: Controller,
    trajectory,
    duration: float,
    *,
    config: SimConfig | None = None,
    inputs: SimInputs | None = None,
    **options,
) -> SimResult:
    """Run ``controller`` on ``platform`` along ``trajectory`` for ``duration`` seconds.

    Parameters
    ----------
    trajectory : an object with ``sample(t) -> Sample`` (xi, xi_dot, xi_ddot of shape (m, 6 + n_arm)),
        e.g. :mod:`qprr.trajectory`.
    duration : run length [s], at least one control period; a run whose logs would not fit in
        :attr:`SimConfig.log_bound <qprr.sim.config.SimConfig.log_bound>` is refused.
    config : the settings, a :class:`~qprr.sim.config.SimConfig` (``dt``, ``integrator``,
        ``control_period``, ``seed``, ``limits``, ``joint_stops``, ``progress``, ``scenario``,
        ``max_log_bytes``); default ``SimConfig()``.
    inputs : what the run starts from and what acts on it, a :class:`~qprr.sim.config.SimInputs`
        (``xi0``, ``xi_dot0``, ``disturbance``, ``external_wrench``, ``payload``, ``allocator``,
        ``actuators``, ``plant``); default: none of them.
    **options : any field of either by name, e.g. ``simulate(p, c, ref, 5.0, dt=2e-3, xi0=x0)``; a
        name given here overrides ``config`` and ``inputs``, an unknown name raises
        :class:`~qprr.errors.UnknownNameError`.

    Returns a :class:`~qprr.sim.result.SimResult` (one row per control tick); raises
    :class:`~qprr.errors.DivergenceError` (with ``.result``) on NaN or runaway states.  See the
    module docstring for the step.
    """
    config, inputs = config_and_inputs(config, inputs, options)
    run = _setup(platform, controller, trajectory, duration, config, inputs)
    bar = Progress(run.n, f"{config.scenario}/{controller.name}", quiet=not config.progress, unit="tick")
    t_start = time.perf_counter()
    try:
        m, err, q, v = _loop(run, bar)
        bar.update_to(m)
    finally:
        bar.close()
    wall = time.perf_counter() - t_start
    if err is None:
        found = controller.run_warnings() + _saturation_warning(run.logs.flags[:m])  # a completed run that was not healthy
        return _result(run, m, Status.OK, "completed with warnings: " + "; ".join(found) if found else "completed", wall)
    err = _with_context(platform, err, (m - 1) * config.period, q, v, run.bounds)
    err.result = _result(run, m, Status.DIVERGED if isinstance(err, DivergenceError) else Status.FAILED, str(err), wall)
    raise err from None


# ------------------------------------------------------------------------------------- setup
@dataclass
class _Logs:
    """The per-tick logs of a run, one row per control tick, filled in place by :func:`_loop`.

    The world CoM is logged raw; x_cm in B and the unallocated force tau_d - N f (tau_d = S^-T u)
    are derived after the loop, vectorised (:func:`_result`).  ``rotor_speed`` and
    ``thrust_command``: the actuator stage's (None without it).
    """

    xi: np.ndarray
    xi_dot: np.ndarray
    u: np.ndarray
    f: np.ndarray
    com: np.ndarray
    flags: np.ndarray
    rotor_speed: np.ndarray | None = None
    thrust_command: np.ndarray | None = None

    @classmethod
    def empty(cls, n: int, platform: Platform, rotor_stage: bool) -> _Logs:
        nxi, nr = platform.n_xi, platform.n_rotors
        rotor = (np.zeros((n, nr)), np.zeros((n, nr))) if rotor_stage else (None, None)
        return cls(
            np.zeros((n, nxi)),
            np.zeros((n, nxi)),
            np.zeros((n, nxi)),
            np.zeros((n, platform.n_actuators)),
            np.zeros((n, 3)),
            np.zeros(n, dtype=np.int8),
            *rotor,
        )


def _bytes_per_tick(platform: Platform, rotor_stage: bool) -> int:
    """Memory one control tick takes [bytes], from above: the logs, the reference samples and disturbance rows (also
    as Python floats), and what :func:`_result` derives from them (float64 arrays)."""
    nxi, nv, na, nr = platform.n_xi, platform.nv, platform.n_actuators, platform.n_rotors
    logs = 3 * nxi + na + 3 + (2 * nr if rotor_stage else 0)
    reference = 1 + 3 * nxi + nxi + 4 * nxi  # t, the samples, u_ext and its rows as Python floats (32 bytes each)
    derived = 9 + 3 + 2 * nv + na  # rotation matrices, x_cm, tau_d and the unallocated force, copies of f
    return 8 * (logs + reference + derived) + 1


@dataclass
class _Run:
    """Everything a run needs, built once by :func:`_setup`, read by :func:`_loop` and :func:`_result`."""

    platform: Platform
    controller: Controller
    config: SimConfig
    n: int  # control ticks
    t: np.ndarray  # their times [s]
    xi_d: np.ndarray  # the reference at the ticks (n, n_xi), and its rates and accelerations
    xi_dot_d: np.ndarray
    xi_ddot_d: np.ndarray
    u_ext: np.ndarray  # the timed disturbance at the ticks (n, n_xi), thesis coordinates
    u_ext_rows: list  # the same per tick as a list of floats, None where zero
    state_dist: list  # the state-dependent disturbances, realized for this run
    logs: _Logs
    plant_payload: PlantPayload
    plant: _Plant
    allocate: Callable  # allocate_screened_into of the allocator (or of PlantActuators with another plant)
    N: np.ndarray  # the plant's actuation matrix
    rotor_bounds: np.ndarray
    state: State  # the measured state, updated at every tick
    reference: Reference  # the reference handed to the controller, set at every tick
    tau_d: np.ndarray  # the controller's generalised force in Pinocchio coordinates, set at every tick
    q: np.ndarray  # the initial state
    v: np.ndarray
    stepper: Callable
    rotor_stage: _RotorStage | None
    bounds: tuple[float, float, float, float]  # position, linear, angular and joint velocity bounds (config.limits)


def _setup(platform, controller, trajectory, duration, config: SimConfig, inputs: SimInputs) -> _Run:
    """Check the arguments against the platform and build the run: reference samples, disturbances, plant, logs, state."""
    _check_types(platform, controller, trajectory, inputs)
    rotors = _bind_rotors(platform, inputs.actuators, config.dt)
    n = config.ticks(duration, _bytes_per_tick(platform, rotors is not None))
    t = np.arange(n) * config.period
    sample = trajectory.sample(t)
    _check_sample(sample, n, platform.n_xi)
    xi_d, xi_dot_d, xi_ddot_d = sample.xi.copy(), sample.xi_dot.copy(), sample.xi_ddot.copy()  # the controllers write roll/pitch
    xi0, xi_dot0 = _initial_state(platform, config, inputs, t, xi_d)
    u_ext, state_dist = _disturbances(platform, config, inputs.disturbance, t)
    robot = platform if inputs.plant is None else check_plant(platform, inputs.plant)  # what is integrated
    plant_payload = PlantPayload(robot, inputs.payload or PayloadSchedule())
    plant_payload.apply_until(0.0)
    alloc = _allocator(platform, inputs.allocator)
    q, v = ch.xi_to_q(xi0), ch.xi_dot_to_v(xi0, xi_dot0)
    state = State(platform.n_arm)
    state.update(0.0, q, v)
    reference = Reference(xi_d[0], xi_dot_d[0], xi_ddot_d[0])
    if controller.uses_preview:  # a planning controller sees the trajectory ahead
        controller.set_preview(trajectory)
    controller.reset(state, reference, config.period)
    model = plant_payload.model  # the plant: a copy, never platform.model
    tau = np.zeros(platform.nv)  # generalised force held over the control period (allocated + timed disturbance)
    plant = _Plant(model, model.createData(), tau, platform.ee_frame, inputs.external_wrench, state_dist, rotors, platform.rotor_matrix)
    plant.add_joint_friction(JointFriction.from_model(model, config.dt, q=q))  # implicit joints chosen at the first state
    logs = _Logs.empty(n, platform, rotors is not None)
    lim = config.limits
    return _Run(
        platform=platform,
        controller=controller,
        config=config,
        n=n,
        t=t,
        xi_d=xi_d,
        xi_dot_d=xi_dot_d,
        xi_ddot_d=xi_ddot_d,
        u_ext=u_ext,
        u_ext_rows=[row if row.any() else None for row in u_ext],
        state_dist=state_dist,
        logs=logs,
        plant_payload=plant_payload,
        plant=plant,
        allocate=alloc.allocate_screened_into if robot is platform else PlantActuators(alloc, robot).allocate_screened_into,
        N=np.array(robot.actuation_matrix),
        rotor_bounds=np.column_stack([alloc.f_min, alloc.f_max]),
        state=state,
        reference=reference,
        tau_d=np.zeros(platform.nv),
        q=q,
        v=v,
        stepper=_stepper(config, plant),
        rotor_stage=None if rotors is None else _RotorStage(rotors, platform, plant, alloc, logs, controller.uses_applied_force),
        bounds=(lim.position, lim.linear_velocity, lim.angular_velocity, lim.joint_velocity),
    )


def _initial_state(platform: Platform, config: SimConfig, inputs: SimInputs, t: np.ndarray, xi_d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(xi0, xi_dot0): the given ones (checked), or the reference's first pose at rest; inside the arm's stops."""
    xi0 = xi_d[0].copy() if inputs.xi0 is None else ch.as_xi(inputs.xi0, "xi0", platform.n_xi)
    if config.joint_stops:
        platform.check_arm_limits(xi0[6:], "xi0[6:]")
        _check_arm_references(platform, t, xi_d)
    xi_dot0 = np.zeros(platform.n_xi) if inputs.xi_dot0 is None else as_vector(inputs.xi_dot0, platform.n_xi, "xi_dot0")
    return xi0, xi_dot0


def _check_types(platform, controller, trajectory, inputs: SimInputs) -> None:
    """The objects ``simulate`` is given are of the kinds it runs (InputError naming the argument)."""
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    if not isinstance(controller, Controller):
        raise InputError(f"controller must be a qprr.control Controller, got {type(controller).__name__}")
    if not isinstance(trajectory, Trajectory):
        raise InputError(f"trajectory must have a sample(t) method (qprr.trajectory.Trajectory), got {type(trajectory).__name__}")
    payload = inputs.payload
    if payload is not None and not isinstance(payload, PayloadSchedule):
        raise InputError(f"payload must be None or a qprr.sim.PayloadSchedule, got {type(payload).__name__} {payload!r:.60}")


def _bind_rotors(platform: Platform, actuators, dt: float):
    """The actuator stage's rotors bound to the platform (None without the stage); dt must resolve the motor lag."""
    if actuators is None:
        return None
    if not isinstance(actuators, RotorDynamics):
        raise InputError(f"actuators must be a qprr.sim.RotorDynamics or None, got {type(actuators).__name__}")
    rotors = actuators.bind(platform.n_rotors)
    if dt > min(actuators.time_constant):  # explicit schemes: stable for dt < 2 T (Euler, midpoint)
        raise InputError(
            f"dt = {dt!r} s exceeds the smallest motor time constant {min(actuators.time_constant)!r} s: "
            "the explicit integrators would be unstable or inaccurate on the rotor speeds; reduce dt"
        )
    return rotors


def _allocator(platform: Platform, allocator) -> Allocator:
    """``allocator`` checked against the platform (default: ``Allocator(platform)``)."""
    alloc = allocator if allocator is not None else Allocator(platform)
    if not isinstance(alloc, Allocator) or alloc.platform.nv != platform.nv or alloc.n_rotors != platform.n_rotors:
        raise InputError("allocator must be a qprr.actuation.Allocator of this platform")
    return alloc


def _disturbances(platform: Platform, config: SimConfig, disturbance, t: np.ndarray) -> tuple[np.ndarray, list]:
    """(u_ext (n, n_xi) of the timed disturbances at the ticks, the state-dependent ones realized for this run)."""
    n, nxi = t.shape[0], platform.n_xi
    rng = np.random.default_rng(config.seed)
    timed, state_dist = dist.split(disturbance)
    u_ext = np.zeros((n, nxi)) if timed is None else np.asarray(timed.values(t, rng, nxi), dtype=float)
    if u_ext.shape != (n, nxi):
        raise ShapeError(f"disturbance values must have shape ({n}, {nxi}), got {u_ext.shape}")
    if not np.all(np.isfinite(u_ext)):
        raise NonFiniteError("disturbance values must be finite")
    # state-dependent disturbances drawn once per run (wind turbulence), after the timed ones (same seed, same draws)
    return u_ext, [d.realize(t, rng, config.period) for d in state_dist]


def _stepper(config: SimConfig, plant: _Plant):
    """One integration step of the configured integrator, followed by the environment's discrete events at its end
    (:meth:`~qprr.sim.environment.Environment.settle`) when the environment has a state."""
    step = make_stepper(config.integrator, plant.model, config.dt)
    if plant.friction is not None and plant.friction.treatments.count(Treatment.IMPLICIT):
        step = _from_step_start(step, plant.friction)
    if plant.env is None or not plant.n_env:
        return step
    settle = plant.settle

    def step_and_settle(f, t, q, v, z, first):
        q1, v1, z1 = step(f, t, q, v, z, first)
        return q1, v1, settle(t, z, z1)

    return step_and_settle


def _from_step_start(step, friction: JointFriction):
    """``step`` that first hands the friction the step's start velocity v0 (its implicit joints are taken from there)."""
    start = friction.start

    def step_from_v0(f, t, q, v, z, first):
        start(v)
        return step(f, t, q, v, z, first)

    return step_from_v0


class _RotorStage:
    """The actuator stage at a control tick: the allocated thrusts are speed commands, the thrusts the rotors
    produce (b w^2 of the integrated speeds) are logged and, for a controller that uses the applied force, held."""

    def __init__(self, rotors, platform: Platform, plant: _Plant, alloc: Allocator, logs: _Logs, wants_applied: bool) -> None:
        self.rotors, self.plant, self.alloc, self.logs, self.wants_applied = rotors, plant, alloc, logs, wants_applied
        self.nr, self.n_env = platform.n_rotors, plant.n_env
        self.Omega = np.array(platform.rotor_matrix)
        self.w_start = rotors.initial()

    def tick(self, k: int, q: np.ndarray, z: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Log tick ``k``'s command and speeds, put the produced thrusts in the f log; returns z (set at tick 0)."""
        nr, n_env, rotors, logs = self.nr, self.n_env, self.rotors, self.logs
        fc = logs.f[k, 0:nr]
        logs.thrust_command[k] = fc
        w_c = rotors.command(fc)
        if k == 0:
            w0 = self.w_start
            if isinstance(w0, str):  # "command": at the first command; "hover": thrusts that hold q0 still
                w0 = (
                    w_c.copy()
                    if w0 == "command"
                    else rotors.speeds_of(self.alloc.allocate(pin.computeGeneralizedGravity(self.plant.model, self.plant.data, q)).f[0:nr])
                )
            z = np.concatenate([z[:n_env], w0])
        w = z[n_env:]
        logs.rotor_speed[k] = w
        logs.f[k, 0:nr] = rotors.thrust(w)
        tau[0:6] = self.Omega @ logs.f[k, 0:nr] if self.wants_applied else 0.0
        return z


# -------------------------------------------------------------------------------------- loop
def _loop(run: _Run, bar: Progress) -> tuple[int, QprrError | None, np.ndarray, np.ndarray]:
    """The control ticks, steps 1-5 of the module docstring: (ticks logged, the qprr error that ended the run or None,
    the last q, v).  An error during a tick ends the logs with that tick (its row as far as it was written)."""
    q, v, z = run.q, run.v, run.plant.z0
    period = run.config.period
    every = max(1, run.n // 1000)  # progress: at most a thousand updates per run (lines are rate-limited)
    logged = 0
    try:
        for k in range(run.n):
            t = k * period
            logged = k + 1
            if run.plant_payload.pending:  # payload changes act at the control ticks (4)
                run.plant_payload.apply_until(t)
            _measure(run, k, t, q, v)  # 1. (q, v) -> (xi, xi_dot), logged
            tau_d = _control(run, k, t)  # 2. the controller's force, tau_d = S^-T u
            z = _actuate(run, k, t, tau_d, q, z)  # 3. allocated: tau = N f, held over the period
            _add_timed_disturbance(run, k)  # 4. tau += S^-T u_ext(t_k)
            q, v, z = _integrate(run, k, t, q, v, z)  # 5. the plant over the period, tau held
            _screen(run, k, (k + 1) * period, q, v)
            if k % every == 0:
                bar.update_to(k)
        _check(run.platform, run.n * period, q, v, run.bounds)
    except QprrError as err:
        return logged, err, q, v
    return run.n, None, q, v


def _measure(run: _Run, k: int, t: float, q: np.ndarray, v: np.ndarray) -> None:
    """Step 1: the measured state from (q, v), thesis coordinates written straight into tick ``k``'s log."""
    state = run.state
    state.xi, state.xi_dot = run.logs.xi[k], run.logs.xi_dot[k]
    state.update(t, q, v)


def _control(run: _Run, k: int, t: float) -> np.ndarray:
    """Step 2: the controller's output at tick ``k`` for the reference there, logged in u; returned as Pinocchio's
    tau_d (S^-T u for a controller in thesis coordinates; a Pinocchio tau_d is logged as is and converted after the
    loop, u = S^T tau_d).  A missing output or one of another shape raises ShapeError naming the controller."""
    ref, controller = run.reference, run.controller
    ref.xi, ref.xi_dot, ref.xi_ddot = run.xi_d[k], run.xi_dot_d[k], run.xi_ddot_d[k]
    out = controller.step(t, run.state, ref)
    pin_out = controller.output == "pinocchio"
    if out is None:  # numpy would store it as NaN
        raise _bad_shape(run.platform, controller, out, pin_out)
    try:
        run.logs.u[k] = out
    except (TypeError, ValueError):  # a wrong length, text: the controller's output, not the simulator
        raise _bad_shape(run.platform, controller, out, pin_out) from None
    return out if pin_out else run.state.force_from_xi(out, run.tau_d)


def _actuate(run: _Run, k: int, t: float, tau_d: np.ndarray, q: np.ndarray, z):
    """Step 3: tau_d allocated to the rotor thrusts and arm efforts (logged in f, with the allocation flags); the
    applied force N f into the plant's held force.  With the actuator stage the thrusts are speed commands and the
    base wrench comes from the rotor speeds (returns z with them).  A refused demand (NaN, infinite, absurd) raises
    DivergenceError naming the controller's entry."""
    tau, logs = run.plant.tau, run.logs
    flags = run.allocate(tau_d, logs.f[k], tau)
    if flags == AllocationFlag.REFUSED:
        raise _bad_output(run.platform, run.controller, t, logs.u[k], run.controller.output == "pinocchio")
    logs.flags[k] = flags
    if run.rotor_stage is not None:
        z = run.rotor_stage.tick(k, q, z, tau)
    if run.controller.uses_applied_force:  # the measured input of the next step (model-free control)
        run.state.set_applied(tau)
        if run.rotor_stage is not None:  # the plant adds the rotors' wrench at every stage
            tau[0:6] = 0.0
    return z


def _add_timed_disturbance(run: _Run, k: int) -> None:
    """Step 4: the disturbance known in advance, u_ext(t_k) of (6.27)-(6.28), added to the held force as S^-T u_ext."""
    u_ext = run.u_ext_rows[k]
    if u_ext is not None:
        run.plant.tau += run.state.force_from_xi(u_ext)


def _integrate(run: _Run, k: int, t: float, q: np.ndarray, v: np.ndarray, z):
    """Step 5: the plant over the control period with its force held: the first stage at the tick (an Environment
    observes it there; the kinematics it leaves give the logged CoM), then ``substeps`` steps of the integrator, the
    arm's stops after each."""
    plant, dt = run.plant, run.config.dt
    a = plant.first_stage(t, q, v, z)
    run.logs.com[k] = pin.centerOfMass(plant.model, plant.data, pin.KinematicLevel.POSITION, False)
    for j in range(run.config.substeps):
        q, v, z = run.stepper(plant.rhs, t + j * dt, q, v, z, a)
        a = None  # the later steps start from their own first stage
        if run.config.joint_stops:
            q, v = _arm_stops(run, k, q, v)
    return q, v, z


def _arm_stops(run: _Run, k: int, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An arm joint past its limit is put on its stop (:func:`qprr.sim.stops.apply_joint_stops`, flag JOINT_STOP)."""
    lo, hi = run.platform.arm_lower, run.platform.arm_upper
    arm = q[7:]
    if ((lo <= arm) & (arm <= hi)).all():  # (NaN is outside)
        return q, v
    run.logs.flags[k] |= AllocationFlag.JOINT_STOP
    return apply_joint_stops(run.plant.model, run.plant.data, q, v, lo.tolist(), hi.tolist())


def _screen(run: _Run, k: int, t: float, q: np.ndarray, v: np.ndarray) -> None:
    """The state at the end of tick ``k`` (time ``t``) against the run's bounds: the norm of v at every tick, of q
    (which integrates v) every 16 ticks; beyond, :func:`_check` names the entry (or lets the run go on when no entry is
    beyond its own bound)."""
    position, velocities = run.bounds[0], min(run.bounds[1:])
    if not math.hypot(*v.tolist()) < velocities or (k % 16 == 0 and not math.hypot(*q.tolist()) < position):
        _check(run.platform, t, q, v, run.bounds)


# ------------------------------------------------------------------------------------ result
SATURATION_WARNING = 0.25
"""Fraction of the ticks with a rotor thrust bound active above which a completed run ends "completed with warnings":
the rotors could not give the wrench the controller asked for (a vehicle too weak for its load, its mission or its
wind), so its tracking numbers describe a saturated vehicle."""


def _saturation_warning(flags: np.ndarray) -> tuple[str, ...]:
    """The warning of a run whose rotors were saturated on more than :data:`SATURATION_WARNING` of its ticks (``flags``:
    the logged :class:`~qprr.actuation.AllocationFlag` bits), else none."""
    fraction = float(np.mean((flags & AllocationFlag.ROTOR_SATURATED) != 0)) if flags.size else 0.0
    if fraction <= SATURATION_WARNING:
        return ()
    return (
        f"a rotor thrust bound was active on {100 * fraction:.0f} % of the ticks (above {100 * SATURATION_WARNING:.0f} %): "
        "the rotors could not give the wrench asked for (too little thrust for the load, the mission or the wind?)",
    )


def _result(run: _Run, m: int, status: Status, reason: str, wall: float) -> SimResult:
    """The first ``m`` ticks as a :class:`SimResult`: the logs, what is derived from them, and what the controller and the
    optional stages report (the controller's metrics and series, rotor speeds and commands, the wind)."""
    platform, cfg, logs = run.platform, run.config, run.logs
    xi = logs.xi[:m]
    R = ch.euler_to_rotation_batch(xi[:, 3:6])
    x_cm = ch.to_body_batch(R, logs.com[:m], xi[:, 0:3])  # R^T (c - p)
    u = logs.u[:m]
    if run.controller.output == "pinocchio":  # the controller returned Pinocchio forces: log u = S^T tau_d
        tau_d = u.copy()
        u[:] = ch.force_to_xi_batch(R, xi, tau_d)
    else:
        tau_d = ch.force_from_xi_batch(R, xi, u)
    nr = platform.n_rotors
    res = SimResult(
        scenario=cfg.scenario,
        controller=run.controller.name,
        dt=cfg.dt,
        integrator=cfg.integrator,
        t=run.t[:m].copy(),
        xi=xi,
        xi_dot=logs.xi_dot[:m],
        xi_d=run.xi_d[:m],
        xi_dot_d=run.xi_dot_d[:m],
        u=u,
        f=logs.f[:m, 0:nr].copy(),
        arm_effort=logs.f[:m, nr:].copy(),
        x_cm=x_cm,
        unallocated=tau_d - logs.f[:m] @ run.N.T,
        flags=logs.flags[:m],
        u_ext=run.u_ext[:m],
        wall_time=wall,
        status=status,
        reason=reason,
        seed=cfg.seed,
        control_period=cfg.period,
        platform=platform.name,
        names=platform.xi_names,
        arm_kinds=tuple(j.kind for j in platform.arm),
        rotor_bounds=run.rotor_bounds,
        rotor_names=tuple(r.name for r in platform.rotors),
    )
    metrics, series = run.controller.report()  # what the controller measured about itself (e.g. an MPC's solve times)
    res.metrics.update(metrics)
    res.series.update(series)
    if run.plant_payload.changes:  # what the end effector carried at each tick (figures and animations draw it)
        res.series["payload_mass"], res.series["payload_com_ee"] = run.plant_payload.carried(res.t)
    if run.rotor_stage is not None:
        res.series["rotor_speed"] = logs.rotor_speed[:m].copy()
        res.series["thrust_command"] = logs.thrust_command[:m].copy()
    for d in run.state_dist:
        res.series.update({k: v[:m] for k, v in d.report().items()})
    return res


def _check_sample(sample, n: int, nxi: int) -> None:
    """A trajectory sample must be a TrajectorySample holding finite xi, xi_dot, xi_ddot of shape (n, 6 + n_arm)."""
    if not isinstance(sample, TrajectorySample):
        raise InputError(f"trajectory.sample(t) must return a qprr.trajectory.TrajectorySample, got {type(sample).__name__}")
    for name in ("xi", "xi_dot", "xi_ddot"):
        a = getattr(sample, name)  # the field of that name
        if not isinstance(a, np.ndarray) or a.shape != (n, nxi):
            shape = a.shape if isinstance(a, np.ndarray) else type(a).__name__
            raise ShapeError(f"trajectory sample {name} must have shape ({n}, {nxi}) (the platform's 6 + n_arm), got {shape}")
        if not np.all(np.isfinite(a)):
            raise NonFiniteError(f"trajectory sample {name} must be finite")


def _check_arm_references(platform: Platform, t: np.ndarray, xi_d: np.ndarray) -> None:
    """Every arm reference inside the joint limits (a reference beyond a stop is a mistake, not a run)."""
    arm = xi_d[:, 6:]
    lo, hi = platform.arm_lower, platform.arm_upper
    bad = (arm < lo - 1e-12) | (arm > hi + 1e-12)
    if bad.any():
        k, j = np.argwhere(bad)[0]
        joint = platform.arm[j]
        raise LimitError(
            f"trajectory: the reference of arm joint {joint.name!r} is {float(arm[k, j])!r} at t = {t[k]:.3f} s, outside its "
            f"limits [{joint.lower!r}, {joint.upper!r}] (the joint would sit on its stop); "
            "keep references inside the limits or pass joint_stops=False"
        )


class _Plant:
    """Right-hand side a = M^-1 (tau - h(q, v)) of the plant, Pinocchio's ABA in the LOCAL convention.

    ``tau`` (a buffer the simulator refills at each control tick) is held over the period;
    state-dependent inputs are evaluated at every call, i.e. at every integration stage:
    the end-effector wrench J_e^T h (Jacobian and wrench at the stage's q, v and environment
    state z) and the state-dependent disturbances.  Without them the right-hand side is ABA
    alone.  With an :class:`Environment` that has a state, ``rhs(t, q, v, z)`` returns
    (a, z_dot) (the form :mod:`qprr.sim.integrators` expects).  With the actuator stage the
    rotor speeds w are appended to z (z = [z_env, w]): the base wrench Omega b w^2 is added to
    ``tau`` at every stage and dw/dt = (w_c - w) / T is part of z_dot.
    """

    def __init__(self, model, data, tau, ee_frame, external_wrench, state_dist, rotors=None, Omega=None) -> None:
        self.model, self.data, self.tau, self.ee = model, data, tau, ee_frame
        self.state_dist = tuple(state_dist)
        self.env = external_wrench if isinstance(external_wrench, Environment) else None
        if external_wrench is not None and self.env is None and not callable(external_wrench):
            raise InputError(f"external_wrench must be an Environment or a callable (t, q, v) -> h, got {type(external_wrench).__name__}")
        self.fn = None if self.env is not None else external_wrench
        self.z0 = None
        if self.env is not None:
            self.env.reset()
            z0 = np.array(self.env.initial_state(), dtype=float).ravel()
            if not np.all(np.isfinite(z0)):
                raise NonFiniteError(f"environment initial state must be finite, got {z0.tolist()}")
            self.z0 = z0 if z0.size else None
        self.n_env = 0 if self.z0 is None else self.z0.shape[0]
        self.rotors, self.Omega = rotors, (None if Omega is None else np.array(Omega))
        aba = pin.aba
        self.friction = None  # the URDF's joint damping and friction: :meth:`add_joint_friction`
        self.plain = self.env is None and self.fn is None and not self.state_dist and rotors is None
        if rotors is not None:  # rotor speeds appended to z (the first command sets them at tick 0)
            self.z0 = np.concatenate([self.z0 if self.z0 is not None else np.zeros(0), np.zeros(rotors.n)])
            self.rhs = self._rhs_rotors
        elif self.plain:
            self.rhs = lambda t, q, v: aba(model, data, q, v, tau)  # LOCAL convention (the default)
        elif self.z0 is None:
            self.rhs = self._rhs
        else:
            self.rhs = self._rhs_z

    def add_joint_friction(self, friction: JointFriction | None) -> None:
        """The joints' viscous damping and Coulomb friction (:class:`qprr.dynamics.friction.JointFriction`, from the
        URDF's ``<dynamics damping friction>``; None: none) in every stage's generalised force."""
        self.friction = friction
        if friction is not None and self.plain:
            self.plain = False
            self.rhs = self._rhs if self.z0 is None else self._rhs_z

    def settle(self, t: float, z_before, z_after):
        """The environment's discrete events on its part of z (the rotor speeds have none)."""
        if self.rotors is None:
            return self.env.settle(t, z_before, z_after)
        ne = self.n_env
        return np.concatenate([self.env.settle(t, z_before[:ne], z_after[:ne]), z_after[ne:]])

    def _rhs_rotors(self, t: float, q, v, z):
        ne = self.n_env
        w = z[ne:]
        base = self.tau.copy()
        base[0:6] += self.Omega @ self.rotors.thrust(w)
        tau, zd = self._force(t, q, v, z[:ne] if ne else None, base)
        wd = self.rotors.rate(w)
        return self._solve(q, v, pin.aba(self.model, self.data, q, v, tau)), (wd if not ne else np.concatenate([np.asarray(zd, dtype=float), wd]))

    def _force(self, t: float, q, v, z, tau=None) -> tuple[np.ndarray, np.ndarray | None]:
        """(tau + J_e^T h + state disturbances, z_dot) at one stage (``tau``: the held force, default a copy of the buffer)."""
        tau = self.tau.copy() if tau is None else tau
        zd = None
        for d in self.state_dist:
            tau += np.asarray(d.generalized_force(t, q, v), dtype=float)
        if self.friction is not None:
            self.friction.apply(v, tau)  # the explicit joints' (the implicit joints': self._solve after ABA)
        if self.env is not None or self.fn is not None:
            J = pin.computeFrameJacobian(self.model, self.data, q, self.ee, pin.LOCAL_WORLD_ALIGNED)
            if self.env is not None:
                M = self.data.oMf[self.ee]
                twist = J @ v
                h, zd = self.env.evaluate(t, M.translation, M.rotation, twist, z if z is not None else _NO_STATE)
                self._last = (M.translation.copy(), M.rotation.copy(), twist, h)
            else:
                h = np.asarray(self.fn(t, q, v), dtype=float)
            if h.shape != (6,) or not np.all(np.isfinite(h)):
                raise InputError(f"external_wrench must return 6 finite values, got {h!r} at t = {t}")
            tau += J.T @ h
        return tau, zd

    def _rhs(self, t: float, q, v):
        tau, _ = self._force(t, q, v, None)
        return self._solve(q, v, pin.aba(self.model, self.data, q, v, tau))

    def _rhs_z(self, t: float, q, v, z):
        tau, zd = self._force(t, q, v, z)
        return self._solve(q, v, pin.aba(self.model, self.data, q, v, tau)), np.asarray(zd, dtype=float)

    def _solve(self, q, v, a):
        """``a`` with the implicit joint friction (:meth:`qprr.dynamics.friction.JointFriction.solve`; none: ``a``)."""
        return a if self.friction is None else self.friction.solve(self.model, self.data, q, v, a)

    def first_stage(self, t: float, q, v, z):
        """The right-hand side at a control tick (the stepper's ``first``); an Environment observes the tick."""
        if self.friction is not None:
            self.friction.start(v)  # the first stage of a step: v0 = v
        if self.env is None:
            return self.rhs(t, q, v) if z is None else self.rhs(t, q, v, z)
        self.env.on_tick(t)
        out = self.rhs(t, q, v) if z is None else self.rhs(t, q, v, z)
        p, R, twist, h = self._last
        if self.rotors is not None:  # the environment sees its own part of z
            z = z[: self.n_env] if self.n_env else None
        self.env.observe(t, p, R, twist, z if z is not None else _NO_STATE, h)
        return out


_NO_STATE = np.zeros(0)


_BASE_V = ("v_x", "v_y", "v_z", "omega_x", "omega_y", "omega_z")


def _check(platform: Platform, t: float, q: np.ndarray, v: np.ndarray, bounds) -> None:
    """Raise DivergenceError naming the first offending state entry (NaN or beyond Limits)."""
    pos_lim, vlin_lim, w_lim, qd_lim = bounds
    ql, vl = q.tolist(), v.tolist()
    names = platform.xi_names
    for i in range(3):
        if not abs(ql[i]) < pos_lim:
            raise DivergenceError.at(t, f"position {names[i]} = {ql[i]!r} m (bound {pos_lim} m)")
    for i in range(7, len(ql)):
        if not math.isfinite(ql[i]):
            raise DivergenceError.at(t, f"joint {names[i - 1]} = {ql[i]!r}")
    if not all(math.isfinite(x) for x in ql[3:7]):
        raise DivergenceError.at(t, "attitude quaternion is NaN")
    for i, x in enumerate(vl):
        bound = vlin_lim if i < 3 else w_lim if i < 6 else qd_lim
        if not abs(x) < bound:
            label = _BASE_V[i] if i < 6 else f"{names[i]}_dot"
            raise DivergenceError.at(t, f"velocity {label} = {x!r} (bound {bound})")


def _bad_output(platform: Platform, controller, t: float, u: np.ndarray, pin_out: bool) -> DivergenceError:
    """DivergenceError naming the first non-finite (or absurd) entry of a controller's output at time ``t``."""
    names = platform.xi_names
    k = next((i for i, x in enumerate(u.tolist()) if not abs(x) < 1e150), 0)
    what = "tau (Pinocchio generalised force)" if pin_out else "u (thesis generalised force)"
    label = (_BASE_F[k] if k < 6 else f"{names[k]} effort") if pin_out else (names[k] if k >= 6 else f"{names[k]} force/torque")
    return DivergenceError.at(
        t,
        f"the controller {controller.name!r} returned a non-finite or absurd (|x| >= 1e150) {what}: "
        f"entry {label} = {float(u[k])!r} (the measured state was finite)",
    )


_BASE_F = ("f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z")


def _bad_shape(platform: Platform, controller, out, pin_out: bool) -> ShapeError:
    """ShapeError: the controller's ``step`` returned something that is not one generalised force of the platform."""
    n = platform.nv
    what = (
        f"tau, the Pinocchio generalised force: {n} numbers (6 base wrench entries, then the {platform.n_arm} arm efforts)"
        if pin_out
        else f"u, the generalised force in the thesis coordinates xi = {list(platform.xi_names)}: {n} numbers"
    )
    shape = f"shape {np.shape(out)}" if isinstance(out, (np.ndarray, list, tuple)) else type(out).__name__
    return ShapeError(
        f"the controller {controller.name!r} ({type(controller).__name__}).step returned {shape} "
        f"{' '.join(repr(out).split())[:80]}: it must return {what}, an array of shape ({n},); fix the controller's step"
    )


def _with_context(platform: Platform, err: QprrError, t: float, q, v, bounds) -> QprrError:
    """The error to report: the runaway state if the state has diverged (the root cause), else ``err`` naming the time.

    An error that already names its time (:attr:`~qprr.errors.QprrError.time`: the loop's own state and output
    checks) is reported as is; any other keeps its type and attributes and gets the time in front of its message
    (:meth:`~qprr.errors.QprrError.with_time`)."""
    if err.time is not None:
        return err
    try:
        _check(platform, t, q, v, bounds)
    except DivergenceError as div:
        root = DivergenceError(f"{div} (then: {type(err).__name__}: {err})")
        root.time = div.time
        return root
    return err.with_time(t)


def check_sample(sample, n: int, nxi: int = 9) -> None:
    """Public form of the trajectory sample check (shape (n, 6 + n_arm), finite)."""
    _check_sample(sample, as_int(n, "n", lo=0), as_int(nxi, "nxi", lo=6))
