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
``thrust_command`` and ``rotor_speed``.  State-dependent disturbances with a
``realize(t_ticks, rng, period)`` method (wind: :mod:`qprr.sim.wind`) are realized once per
run from the run's seed.

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
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..actuation import DEMAND_BOUND, Allocator
from ..charts import State, as_vector
from ..control.base import Controller, Reference
from ..errors import DivergenceError, InputError, LimitError, NonFiniteError, QprrError, ShapeError, UnknownNameError
from ..joint_friction import JointFriction
from ..platform import Platform
from . import disturbances as dist
from .actuators import RotorDynamics
from .environment import Environment
from .integrators import STEPPERS, make_stepper
from .mismatch import PlantActuators, check_plant
from .payload import PayloadSchedule, PlantPayload
from .result import SimResult, Status
from .stops import apply_joint_stops

INTEGRATORS = tuple(STEPPERS)


class _Progress:
    """Minimal text progress bar on stderr (updates every 2 %)."""

    def __init__(self, n: int, label: str, enabled: bool) -> None:
        self.n, self.label, self.enabled = n, label, enabled
        self.every = max(1, n // 50)
        self.t0 = time.perf_counter()

    def update(self, k: int) -> None:
        frac = k / self.n
        bar = "#" * int(30 * frac)
        sys.stderr.write(f"\r{self.label} [{bar:<30}] {100 * frac:5.1f}% {time.perf_counter() - self.t0:6.2f} s")
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            self.update(self.n)
            sys.stderr.write("\n")


@dataclass(frozen=True)
class Limits:
    """Runaway bounds: a state beyond them stops the run with DivergenceError."""

    position: float = 1e3  # m
    linear_velocity: float = 100.0  # m/s
    angular_velocity: float = 100.0  # rad/s
    joint_velocity: float = 100.0  # m/s or rad/s

    def __post_init__(self) -> None:
        for name in ("position", "linear_velocity", "angular_velocity", "joint_velocity"):
            object.__setattr__(self, name, ch.as_real(getattr(self, name), f"limits {name}", positive=True, allow_inf=True))


def simulate(
    platform: Platform,
    controller: Controller,
    trajectory,
    duration: float,
    *,
    dt: float = 1e-3,
    integrator: str = "midpoint",
    control_period: float | None = None,
    xi0=None,
    xi_dot0=None,
    disturbance=None,
    external_wrench: Environment | Callable[[float, np.ndarray, np.ndarray], np.ndarray] | None = None,
    payload: PayloadSchedule | None = None,
    allocator: Allocator | None = None,
    actuators: RotorDynamics | None = None,
    seed: int | None = 0,
    limits: Limits = Limits(),
    joint_stops: bool = True,
    progress: bool = False,
    scenario: str = "custom",
    plant: Platform | None = None,
) -> SimResult:
    """Run ``controller`` on ``platform`` along ``trajectory`` for ``duration`` seconds.

    Parameters
    ----------
    trajectory : an object with ``sample(t) -> Sample`` (xi, xi_dot, xi_ddot of shape (m, 6 + n_arm)),
        e.g. :mod:`qprr.trajectory`.
    dt : integration step [s]; control_period : period of the digital controller [s] (default
        ``dt``), an integer multiple of ``dt``: the controller, the allocation, the disturbance
        samples and the payload changes act at the control ticks and are held in between, while
        the plant is integrated with ``control_period / dt`` steps per period.  The result has one
        row per control tick.
    xi0, xi_dot0 : initial state (default: the trajectory at t = 0, at rest).
    disturbance : a :class:`~qprr.sim.disturbances.Disturbance`, a
        :class:`~qprr.sim.disturbances.StateDisturbance` or a
        :class:`~qprr.sim.disturbances.Disturbances` sum.
    external_wrench : an :class:`~qprr.sim.environment.Environment` (contact model) or a callable
        ``(t, q, v) -> h`` (6,), the world wrench at the end effector, evaluated at every stage.
    payload : a :class:`~qprr.sim.payload.PayloadSchedule` (the plant's model is a copy).
    allocator : default ``Allocator(platform)``.  seed : seeds the noise (and the wind turbulence).
    actuators : a :class:`~qprr.sim.actuators.RotorDynamics` (motor lag, speed limits, thrust b w^2)
        between allocation and plant; None (default): thrusts applied as allocated.
    joint_stops : the arm joints end at mechanical stops at their limits
        (:func:`qprr.sim.stops.apply_joint_stops`; flag bit 4); the initial state and every arm
        reference must then lie inside the limits.
    plant : the robot simulated when it differs from ``platform``, the model the controller and
        the allocation know (model errors, :func:`qprr.sim.mismatch.perturbed`): same structure,
        other inertias and rotor constants; its rotors produce the commanded thrusts within their
        own bounds (:class:`qprr.sim.mismatch.PlantActuators`).  Default: ``platform``.

    Returns a :class:`~qprr.sim.result.SimResult`; raises :class:`~qprr.errors.DivergenceError`
    (with ``.result``) on NaN or runaway states.  See the module docstring for the step.
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    if integrator not in INTEGRATORS:
        raise UnknownNameError("integrator", integrator, INTEGRATORS)
    if not isinstance(dt, (int, float)) or not (math.isfinite(dt) and dt > 0.0):
        raise InputError(f"dt must be a positive number of seconds, got {dt!r}")
    if control_period is None:
        period, substeps = float(dt), 1
    else:
        if not isinstance(control_period, (int, float)) or not (math.isfinite(control_period) and control_period > 0.0):
            raise InputError(f"control_period must be a positive number of seconds, got {control_period!r}")
        substeps = int(round(control_period / dt))
        if substeps < 1 or abs(substeps * dt - control_period) > 1e-9 * control_period:
            raise InputError(f"control_period = {control_period!r} s must be an integer multiple of dt = {dt!r} s")
        period = float(control_period)
    if not isinstance(duration, (int, float)) or not (math.isfinite(duration) and duration >= period):
        raise InputError(f"duration must be a number of seconds >= the control period {period!r} s, got {duration!r}")
    if not isinstance(controller, Controller):
        raise InputError(f"controller must be a qprr.control Controller, got {type(controller).__name__}")
    if not hasattr(trajectory, "sample"):
        raise InputError(f"trajectory must have a sample(t) method (qprr.trajectory), got {type(trajectory).__name__}")
    if payload is not None and not isinstance(payload, PayloadSchedule):
        raise InputError(f"payload must be None or a qprr.sim.PayloadSchedule, got {type(payload).__name__} {payload!r:.60}")
    if seed is not None:
        seed = ch.as_int(seed, "seed", lo=0)
    if not isinstance(limits, Limits):
        raise InputError(f"limits must be a qprr.sim.Limits, got {type(limits).__name__}")
    nxi, n_arm = platform.n_xi, platform.n_arm
    n = int(round(duration / period))
    t = np.arange(n) * period
    sample = trajectory.sample(t)
    _check_sample(sample, n, nxi)
    xi_d = sample.xi.copy()
    xi_dot_d = sample.xi_dot.copy()
    xi_ddot_d = sample.xi_ddot.copy()
    xi0 = xi_d[0].copy() if xi0 is None else ch.as_xi(xi0, "xi0", nxi)
    lo, hi = platform.arm_lower.tolist(), platform.arm_upper.tolist()
    if joint_stops:
        platform.check_arm_limits(xi0[6:], "xi0[6:]")
        _check_arm_references(platform, t, xi_d)
    xi_dot0 = np.zeros(nxi) if xi_dot0 is None else as_vector(xi_dot0, nxi, "xi_dot0")
    rng = np.random.default_rng(seed)
    timed, state_dist = dist.split(disturbance)
    u_ext = np.zeros((n, nxi)) if timed is None else np.asarray(timed.values(t, rng, nxi), dtype=float)
    if u_ext.shape != (n, nxi):
        raise ShapeError(f"disturbance values must have shape ({n}, {nxi}), got {u_ext.shape}")
    if not np.all(np.isfinite(u_ext)):
        raise NonFiniteError("disturbance values must be finite")
    # state-dependent disturbances drawn once per run (wind turbulence), after the timed ones (same seed, same draws)
    state_dist = [d.realize(t, rng, period) if hasattr(d, "realize") else d for d in state_dist]
    ext_rows = np.any(u_ext != 0.0, axis=1)
    has_ext = bool(ext_rows.any())
    # per-tick disturbance rows as float lists (None where zero): no array indexing in the loop
    u_ext_rows = [row if nz else None for row, nz in zip(u_ext.tolist(), ext_rows.tolist())] if has_ext else None

    robot = platform if plant is None else check_plant(platform, plant)  # what is integrated
    plant_payload = PlantPayload(robot, payload or PayloadSchedule())
    model = plant_payload.model  # the plant: a copy, never platform.model
    data = model.createData()
    plant_payload.apply_until(0.0)
    alloc = allocator if allocator is not None else Allocator(platform)
    if not isinstance(alloc, Allocator) or alloc.platform.nv != platform.nv or alloc.n_rotors != platform.n_rotors:
        raise InputError("allocator must be a qprr.actuation.Allocator of this platform")
    N = np.array(robot.actuation_matrix)
    n_act = platform.n_actuators

    # logs (the world CoM is logged raw; x_cm in B and the unallocated force
    # tau_d - N f with tau_d = S^-T u are derived after the loop, vectorised)
    xi_log = np.zeros((n, nxi))
    xid_log = np.zeros((n, nxi))
    u_log = np.zeros((n, nxi))
    f_log = np.zeros((n, n_act))
    com_log = np.zeros((n, 3))
    flags = np.zeros(n, dtype=np.int8)

    q = ch.xi_to_q(xi0)
    v = ch.xi_dot_to_v(xi0, xi_dot0)
    state = State(n_arm)
    state.update(0.0, q, v)
    ref = Reference(xi_d[0], xi_dot_d[0], xi_ddot_d[0])
    if getattr(controller, "uses_preview", False):  # a planning controller sees the trajectory ahead
        controller.set_preview(trajectory)
    controller.reset(state, ref, period)
    tau = np.zeros(platform.nv)  # generalised force held over the control period (allocated + timed disturbance)
    if actuators is not None and not isinstance(actuators, RotorDynamics):
        raise InputError(f"actuators must be a qprr.sim.RotorDynamics or None, got {type(actuators).__name__}")
    rotors = actuators.bind(platform.n_rotors) if actuators is not None else None
    if rotors is not None and dt > min(actuators.time_constant):  # explicit schemes: stable for dt < 2 T (Euler, midpoint)
        raise InputError(f"dt = {dt!r} s exceeds the smallest motor time constant {min(actuators.time_constant)!r} s: "
                         "the explicit integrators would be unstable or inaccurate on the rotor speeds; reduce dt")
    plant = _Plant(model, data, tau, platform.ee_frame, external_wrench, state_dist, rotors, platform.rotor_matrix, dt)
    env, z = plant.env, plant.z0
    rhs, first_stage = plant.rhs, plant.first_stage
    settle = plant.settle if (env is not None and plant.n_env) else None
    if rotors is not None:
        nr, n_env = platform.n_rotors, plant.n_env
        w_log, fc_log = np.zeros((n, nr)), np.zeros((n, nr))
        Omega_r = np.array(platform.rotor_matrix)
        w_start = rotors.initial()
    stepper = make_stepper(integrator, model, dt)
    steps = [j * dt for j in range(substeps)]  # step start times within a control period
    plain = plant.plain  # ABA alone: no state-dependent input
    bar = _Progress(n, f"{scenario}/{getattr(controller, 'name', 'controller')}", progress)
    bounds = (limits.position, limits.linear_velocity, limits.angular_velocity, limits.joint_velocity)
    q_bound, v_bound = limits.position, min(bounds[1:])  # |any entry| beyond its bound => the norm beyond these
    hypot = math.hypot  # the norm of a list: 2-3x cheaper than ndarray.dot on these sizes (benchmarks/step_instructions.py)
    POSITION = pin.KinematicLevel.POSITION
    wants_applied = bool(getattr(controller, "uses_applied_force", False))
    pin_out = getattr(controller, "output", "xi") == "pinocchio"
    payload_pending = plant_payload.pending
    b1, tau_d_buf = np.empty(platform.nv), np.empty(platform.nv)
    add, com, step, aba = np.add, pin.centerOfMass, controller.step, pin.aba
    # the allocator's screened form checks tau_d itself (returns -1 on NaN, inf or |tau_d| >= DEMAND_BOUND)
    screened = getattr(alloc, "_screened_into", None) if robot is platform else None
    allocate = screened or (alloc.allocate_into if robot is platform else PlantActuators(alloc, robot).allocate_into)
    update, set_applied, force_from_xi = state.update, state.set_applied, state.force_from_xi
    arm_range = range(n_arm)
    t_start = time.perf_counter()
    k = 0
    status, reason = Status.OK, "completed"
    try:
        for k in range(n):
            tk = k * period
            if payload_pending:  # payload changes act at control ticks
                plant_payload.apply_until(tk)
                payload_pending = plant_payload.pending
            state.xi, state.xi_dot = xi_log[k], xid_log[k]  # the state writes its xi straight into the log
            if not update(tk, q, v, v_bound):  # |v| NaN or >= v_bound at the end of the previous tick: named check there
                if k:
                    k -= 1  # the state diverged during the previous tick: report it there (time, logged ticks)
                    _check(platform, tk, q, v, bounds)
                    k += 1
                update(tk, q, v)  # no entry beyond its own bound: go on
            ref.xi, ref.xi_dot, ref.xi_ddot = xi_d[k], xi_dot_d[k], xi_ddot_d[k]
            if pin_out:
                tau_d = step(tk, state, ref)
                u_log[k] = tau_d  # converted to u = S^T tau_d after the loop
            else:
                u = step(tk, state, ref)
                u_log[k] = u
                tau_d = force_from_xi(u, tau_d_buf)
            if screened is None and not hypot(*tau_d.tolist()) < DEMAND_BOUND:  # NaN, inf or absurd controller output
                raise _bad_output(platform, controller, tk, u_log[k], pin_out)
            fl = allocate(tau_d, f_log[k], tau)  # f straight into the log, N f into tau
            if fl:
                if fl < 0:  # the screened allocator refused tau_d: NaN, inf or absurd controller output
                    raise _bad_output(platform, controller, tk, u_log[k], pin_out)
                flags[k] = fl
            if rotors is not None:  # the allocated thrusts are speed commands; the base wrench comes from the speeds
                fc = f_log[k, 0:nr]
                fc_log[k] = fc
                w_c = rotors.command(fc)
                if k == 0:
                    if isinstance(w_start, str):  # "command": at the first command; "hover": thrusts that hold q0 still
                        w0 = w_c.copy() if w_start == "command" else rotors.speeds_of(
                            alloc.allocate(pin.computeGeneralizedGravity(model, data, q)).f[0:nr])
                    else:
                        w0 = w_start
                    z = np.concatenate([z[:n_env], w0])
                w = z[n_env:]
                w_log[k] = w
                f_log[k, 0:nr] = rotors.thrust(w)
                tau[0:6] = Omega_r @ f_log[k, 0:nr] if wants_applied else 0.0
            if wants_applied:
                set_applied(tau)
                if rotors is not None:
                    tau[0:6] = 0.0
            if has_ext:
                ue = u_ext_rows[k]
                if ue is not None:
                    add(tau, force_from_xi(ue, b1), tau)  # tau += S^-T u_ext, held over the period
            # stage 1 of the first step (an Environment observes its tick there); data then holds its kinematics
            a = aba(model, data, q, v, tau) if plain else first_stage(tk, q, v, z)
            com_log[k] = com(model, data, POSITION, False)
            for j in steps:
                if settle is None:
                    q, v, z = stepper(rhs, tk + j, q, v, z, a)
                else:
                    z_before = z
                    q, v, z = stepper(rhs, tk + j, q, v, z, a)
                    z = settle(tk + j, z_before, z)
                a = None
                if joint_stops:
                    qa = q[7:].tolist()
                    for i in arm_range:
                        if not lo[i] <= qa[i] <= hi[i]:
                            q, v = apply_joint_stops(model, data, q, v, lo, hi)
                            flags[k] |= 4
                            break
            # every tick: the norm of v bounds every velocity (NaN fails it), screened by the next tick's update (and the
            # final check); q, which only integrates v, every 16 ticks (a finite v keeps q finite; the position bound is
            # a slow drift); the named check only on failure
            if not (k & 15 or hypot(*q.tolist()) < q_bound):
                _check(platform, tk + period, q, v, bounds)
            if progress and k % bar.every == 0:
                bar.update(k)
        _check(platform, n * period, q, v, bounds)
        m = n
    except QprrError as err:
        m = k + 1
        err = _with_context(platform, err, k * period, q, v, bounds)
        status = Status.DIVERGED if isinstance(err, DivergenceError) else Status.FAILED
        reason = str(err)
        err.result = _result(platform, scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log,
                             com_log, N, flags, u_ext, time.perf_counter() - t_start, seed, m, status, reason, pin_out=pin_out,
                             period=period)
        _extras(err.result, m, state_dist, (w_log, fc_log) if rotors is not None else None)
        raise err from None
    finally:
        if progress:
            bar.close()
    res = _result(platform, scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log,
                  com_log, N, flags, u_ext, None, seed, m, status, reason, t_start, pin_out, period)
    _extras(res, m, state_dist, (w_log, fc_log) if rotors is not None else None)
    return res


def _extras(res: SimResult, m: int, state_dist, rotor_logs) -> None:
    """Series of the optional stages: rotor speeds and thrust commands, what realized disturbances report (the wind)."""
    if rotor_logs is not None:
        res.series["rotor_speed"] = rotor_logs[0][:m].copy()
        res.series["thrust_command"] = rotor_logs[1][:m].copy()
    for d in state_dist:
        report = getattr(d, "report", None)
        if callable(report):
            res.series.update({k: v[:m] for k, v in report().items()})


def _check_sample(sample, n: int, nxi: int) -> None:
    """A trajectory sample must hold finite xi, xi_dot, xi_ddot of shape (n, 6 + n_arm)."""
    for name in ("xi", "xi_dot", "xi_ddot"):
        a = getattr(sample, name, None)
        if not isinstance(a, np.ndarray) or a.shape != (n, nxi):
            shape = getattr(a, "shape", None)
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
        raise LimitError(f"trajectory: the reference of arm joint {joint.name!r} is {float(arm[k, j])!r} at t = {t[k]:.3f} s, outside its "
                         f"limits [{joint.lower!r}, {joint.upper!r}] (the joint would sit on its stop); "
                         "keep references inside the limits or pass joint_stops=False")


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

    def __init__(self, model, data, tau, ee_frame, external_wrench, state_dist, rotors=None, Omega=None, step=0.0) -> None:
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
        self.friction = JointFriction.from_model(model, step)  # the URDF's <dynamics damping friction> (None: none)
        self.plain = self.env is None and self.fn is None and not self.state_dist and rotors is None and self.friction is None
        if rotors is not None:  # rotor speeds appended to z (the first command sets them at tick 0)
            self.z0 = np.concatenate([self.z0 if self.z0 is not None else np.zeros(0), np.zeros(rotors.n)])
            self.rhs = self._rhs_rotors
        elif self.plain:
            self.rhs = lambda t, q, v: aba(model, data, q, v, tau)  # LOCAL convention (the default)
        elif self.z0 is None:
            self.rhs = self._rhs
        else:
            self.rhs = self._rhs_z

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
        return pin.aba(self.model, self.data, q, v, tau), (wd if not ne else np.concatenate([np.asarray(zd, dtype=float), wd]))

    def _force(self, t: float, q, v, z, tau=None) -> tuple[np.ndarray, np.ndarray | None]:
        """(tau + J_e^T h + state disturbances, z_dot) at one stage (``tau``: the held force, default a copy of the buffer)."""
        tau = self.tau.copy() if tau is None else tau
        zd = None
        for d in self.state_dist:
            tau += np.asarray(d.generalized_force(t, q, v), dtype=float)
        if self.friction is not None:
            self.friction.apply(self.model, v, tau)  # implicit in v: writes h K(v) into the plant model's armature
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
        return pin.aba(self.model, self.data, q, v, tau)

    def _rhs_z(self, t: float, q, v, z):
        tau, zd = self._force(t, q, v, z)
        return pin.aba(self.model, self.data, q, v, tau), np.asarray(zd, dtype=float)

    def first_stage(self, t: float, q, v, z):
        """The right-hand side at a control tick (the stepper's ``first``); an Environment observes the tick."""
        if self.env is None:
            return self.rhs(t, q, v) if z is None else self.rhs(t, q, v, z)
        self.env.on_tick(t)
        out = self.rhs(t, q, v) if z is None else self.rhs(t, q, v, z)
        p, R, twist, h = self._last
        if self.rotors is not None:  # the environment sees its own part of z
            z = z[:self.n_env] if self.n_env else None
        self.env.observe(t, p, R, twist, z if z is not None else _NO_STATE, h)
        return out


_NO_STATE = np.zeros(0)


def _result(platform, scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log, com_log,
            N, flags, u_ext, wall, seed, m, status, reason, t_start=None, pin_out=False, period=None) -> SimResult:
    xi = xi_log[:m]
    R = ch.euler_to_rotation_batch(xi[:, 3:6])
    x_cm = ch.to_body_batch(R, com_log[:m], xi[:, 0:3])  # R^T (c - p)
    if pin_out:  # the controller returned Pinocchio forces: log u = S^T tau_d
        tau_d = u_log[:m].copy()
        u_log[:m] = ch.force_to_xi_batch(R, xi, tau_d)
    else:
        tau_d = ch.force_from_xi_batch(R, xi, u_log[:m])
    unalloc = tau_d - f_log[:m] @ N.T
    if wall is None:
        wall = time.perf_counter() - t_start
    nr = platform.n_rotors
    res = SimResult(
        scenario=scenario, controller=getattr(controller, "name", type(controller).__name__), dt=dt,
        integrator=integrator, t=t[:m].copy(), xi=xi, xi_dot=xid_log[:m], xi_d=xi_d[:m], xi_dot_d=xi_dot_d[:m],
        u=u_log[:m], f=f_log[:m, 0:nr].copy(), arm_effort=f_log[:m, nr:].copy(), x_cm=x_cm, unallocated=unalloc,
        flags=flags[:m], u_ext=u_ext[:m], wall_time=wall, status=status, reason=reason, seed=seed, control_period=period,
        platform=platform.name, names=platform.xi_names, arm_kinds=tuple(j.kind for j in platform.arm),
    )
    metrics, series = controller.report()  # what the controller measured about itself (e.g. an MPC's solve times)
    res.metrics.update(metrics)
    res.series.update(series)
    return res


_BASE_V = ("v_x", "v_y", "v_z", "omega_x", "omega_y", "omega_z")


def _check(platform: Platform, t: float, q: np.ndarray, v: np.ndarray, bounds) -> None:
    """Raise DivergenceError naming the first offending state entry (NaN or beyond Limits)."""
    pos_lim, vlin_lim, w_lim, qd_lim = bounds
    ql, vl = q.tolist(), v.tolist()
    names = platform.xi_names
    for i in range(3):
        if not abs(ql[i]) < pos_lim:
            raise DivergenceError(f"diverged at t = {t:.3f} s: position {names[i]} = {ql[i]!r} m (bound {pos_lim} m)")
    for i in range(7, len(ql)):
        if not math.isfinite(ql[i]):
            raise DivergenceError(f"diverged at t = {t:.3f} s: joint {names[i - 1]} = {ql[i]!r}")
    if not all(math.isfinite(x) for x in ql[3:7]):
        raise DivergenceError(f"diverged at t = {t:.3f} s: attitude quaternion is NaN")
    for i, x in enumerate(vl):
        bound = vlin_lim if i < 3 else w_lim if i < 6 else qd_lim
        if not abs(x) < bound:
            label = _BASE_V[i] if i < 6 else f"{names[i]}_dot"
            raise DivergenceError(f"diverged at t = {t:.3f} s: velocity {label} = {x!r} (bound {bound})")


def _bad_output(platform: Platform, controller, t: float, u: np.ndarray, pin_out: bool) -> DivergenceError:
    """DivergenceError naming the first non-finite (or absurd) entry of a controller's output at time ``t``."""
    names = platform.xi_names
    k = next((i for i, x in enumerate(u.tolist()) if not abs(x) < 1e150), 0)
    what = "tau (Pinocchio generalised force)" if pin_out else "u (thesis generalised force)"
    label = (_BASE_F[k] if k < 6 else f"{names[k]} effort") if pin_out else (names[k] if k >= 6 else f"{names[k]} force/torque")
    return DivergenceError(f"diverged at t = {t:.3f} s: the controller {getattr(controller, 'name', type(controller).__name__)!r} "
                           f"returned a non-finite or absurd (|x| >= 1e150) {what}: entry {label} = {float(u[k])!r} (the measured state was finite)")


_BASE_F = ("f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z")


def _with_context(platform: Platform, err: QprrError, t: float, q, v, bounds) -> QprrError:
    """The error to report: the runaway state if the state has diverged (the root cause), else ``err`` with the time."""
    if isinstance(err, DivergenceError) and str(err).startswith("diverged at"):
        return err
    try:
        _check(platform, t, q, v, bounds)
    except DivergenceError as div:
        return DivergenceError(f"{div} (then: {type(err).__name__}: {err})")
    if isinstance(err, DivergenceError):
        return DivergenceError(f"diverged at t = {t:.3f} s: {err}")
    new = type(err).__new__(type(err))
    try:
        new.__init__(f"at t = {t:.3f} s of the run: {err}")
    except TypeError:  # an error class with another constructor: keep it
        return err
    return new


def check_sample(sample, n: int, nxi: int = 9) -> None:
    """Public form of the trajectory sample check (shape (n, 6 + n_arm), finite)."""
    _check_sample(sample, ch.as_int(n, "n", lo=0), ch.as_int(nxi, "nxi", lo=6))
