"""Closed-loop simulation of the Q-PRR: Pinocchio ABA on the Lie group, fixed step.

A digital controller of period ``control_period`` (default: the integration step ``dt``)
drives the plant; at each control tick t_k:

1. state (q, v) -> thesis coordinates (xi, xi_dot) (:class:`qprr.control.base.State`);
2. the controller returns the desired generalised force u (thesis coordinates, Thesis (5.40));
3. tau_d = S^-T u is allocated to 4 rotor thrusts in [f_min, f_max] and 3 arm efforts
   (:class:`qprr.allocation.Allocator`); the applied force is tau = N f (Thesis (5.43));
4. the disturbances known in advance are added: u_ext of Thesis (6.27) (white noise, pulses
   (6.28)) as S^-T u_ext, sampled at the tick; payload changes take effect at the tick;
5. tau is held over the period (zero-order hold: the physics of a digital controller) while
   the plant is integrated over the period with ``control_period / dt`` steps of the
   integrator; ABA (LOCAL convention) gives a = M^-1 (tau + tau_state - h(q, v)) at every
   stage, where tau_state holds the inputs that depend on the state and are evaluated at
   that stage: the end-effector wrench J_e^T h (Jacobian and contact force) and the
   :class:`StateDisturbance` forces.  An :class:`qprr.environment.Environment` (contact
   model with its own state, e.g. a pushed object) is integrated together with the robot by
   the same integrator.

Integrators (``integrator=``, :mod:`qprr.integrators`, all on the Lie group):

* ``"midpoint"`` (the default): explicit midpoint, two ABA per step, second order;
* ``"rk4"``: classical Runge-Kutta 4 in the tangent chart at q_k (stage velocities mapped
  through the inverse differential of ``pin.integrate``), four ABA per step, fourth order:
  the accuracy reference;
* ``"euler"``: semi-implicit Euler, v+ = v + dt a(q, v), q+ = q (+) dt v+.  One ABA, first
  order; its energy drifts and it flatters tracking errors (see below).

The orders hold for every input above (tests/test_convergence.py measures them: free motion,
gravity and thrust, closed loop with every controller, each hook).  Measured
(tests/test_sim.py): free tumbling without gravity or input for 10 s at 1 kHz (|E| = 0.71 J),
relative energy error: midpoint 7e-7, RK4 3e-12, semi-implicit Euler 1.4 % and drifting.  In
closed loop on the static mission the midpoint trajectory stays within 1.1e-6 m of RK4 and
Euler's 1.9 mm off; Euler also flatters the tracking errors (its discretisation matches the
controllers' command filters).  Midpoint costs one extra ABA and ``integrate`` (~3 us per
step) over Euler and about half of RK4.

ABA runs in Pinocchio's LOCAL convention at every stage: the WORLD convention expresses the
spatial quantities about the world origin and loses precision far from it (relative error
of the acceleration 2e-11 at 10 m, 2e-7 at 1 km); LOCAL does not depend on the base position.

Hooks used by the interaction/payload work:

* ``external_wrench``: an :class:`qprr.environment.Environment` (contact models of
  :mod:`qprr.interaction`) or a plain callable ``(t, q, v) -> h`` (6,) = [force; moment] in
  world axes applied at the end-effector frame origin (:class:`ExternalWrench`), evaluated at
  every integration stage;
* ``payload``: a :class:`PayloadSchedule` of (time, mass, CoM offset in the end-effector
  frame).  The simulator owns a COPY of the model (``pin.Model(robot.model)``) and changes
  the inertia of the end effector's parent joint at the first control tick at or after
  each time; ``robot.model`` is never touched and the controller keeps its nominal model;
* ``disturbance``: a :class:`Disturbance` (known in advance, sampled at the ticks), a
  :class:`StateDisturbance` (e.g. :class:`BaseDrag`, evaluated at every stage) or a
  :class:`Disturbances` sum of both kinds.

A run that produces NaN, leaves the workspace bound or reaches the Euler singularity
raises :class:`DivergenceError` naming the time and the state; the partial result is
attached as ``error.result``.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np
import pinocchio as pin

from .allocation import Allocator
from .control.base import Controller, Reference, State
from .coordinates import as_vector, xi_dot_to_v, xi_to_q
from .environment import Environment
from .errors import DivergenceError, InputError, NonFiniteError, QprrError, ShapeError, UnknownNameError
from .integrators import STEPPERS, make_stepper
from .model import Robot
from .trajectory import XI_NAMES, check_sample

INTEGRATORS = tuple(STEPPERS)


# =============================================================================== disturbances
class Disturbance(Protocol):
    """Additive generalised force u_ext(t) of Thesis (6.27), thesis coordinates, known in advance.

    Sampled at the control ticks and held over each control period (a noise sample, a pulse
    edge sit on the control grid)."""

    def values(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """u_ext at the control ticks ``t`` (n,), shape (n, 9)."""


class StateDisturbance(Protocol):
    """A disturbance that depends on the state, evaluated at every integration stage.

    ``generalized_force(t, q, v)`` returns tau (9,) in Pinocchio's coordinates (the free
    flyer's entries are a body wrench [force; moment] in B at its origin)."""

    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class BaseDrag:
    """Linear aerodynamic drag on the multirotor: force -c_lin v_B, moment -c_ang omega_B (body axes, at B).

    ``linear`` [N s/m], ``angular`` [N m s/rad]; isotropic, so the world force is -c_lin p_dot.
    A :class:`StateDisturbance`."""

    linear: float = 0.0
    angular: float = 0.0

    def __post_init__(self) -> None:
        for name in ("linear", "angular"):
            c = getattr(self, name)
            if not (np.isfinite(c) and c >= 0.0):
                raise InputError(f"drag coefficient {name} must be finite and >= 0, got {c!r}")

    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        tau = np.zeros(v.shape[0])
        tau[0:3] = -self.linear * v[0:3]
        tau[3:6] = -self.angular * v[3:6]
        return tau


@dataclass(frozen=True)
class WhiteNoise:
    """Uniform white noise in [-amplitude, amplitude] on the selected generalised forces (Sec. 6.3.2.1).

    A new value per ``sample_time`` (default: every control tick), held in between.  Units are those
    of each generalised force (N for x, y, z, r0; N m for the angles and revolute joints),
    as in the thesis which applies the same [-0.3, 0.3] to all nine.
    """

    amplitude: float | tuple[float, ...] = 0.3
    components: tuple[int, ...] = tuple(range(9))
    sample_time: float | None = None

    def __post_init__(self) -> None:
        amp = np.broadcast_to(np.asarray(self.amplitude, dtype=float), (len(self.components),))
        if not np.all(np.isfinite(amp)) or np.any(amp < 0):
            raise InputError(f"noise amplitude must be finite and >= 0, got {self.amplitude!r}")
        if any(c not in range(9) for c in self.components):
            raise InputError(f"noise components must be indices 0..8, got {self.components!r}")
        if self.sample_time is not None and not self.sample_time > 0:
            raise InputError(f"sample_time must be > 0 s, got {self.sample_time!r}")

    def values(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        n = t.shape[0]
        out = np.zeros((n, 9))
        if self.sample_time is None:
            idx = np.arange(n)
            m = n
        else:
            idx = np.floor((t - t[0]) / self.sample_time + 1e-9).astype(int)
            m = int(idx[-1]) + 1
        amp = np.broadcast_to(np.asarray(self.amplitude, dtype=float), (len(self.components),))
        draws = rng.uniform(-1.0, 1.0, size=(m, len(self.components))) * amp
        out[:, list(self.components)] = draws[idx]
        return out


@dataclass(frozen=True)
class Pulse:
    """Finite pulse Gamma [H(t - t1) - H(t - t2)] (Thesis (6.28)); ``gamma`` (9,) per generalised force."""

    t1: float
    t2: float
    gamma: tuple[float, ...]

    def __post_init__(self) -> None:
        as_vector(self.gamma, 9, "gamma")
        if not (self.t2 > self.t1):
            raise InputError(f"pulse needs t1 < t2, got t1 = {self.t1!r}, t2 = {self.t2!r}")

    def values(self, t: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        on = ((t >= self.t1) & (t < self.t2)).astype(float)
        return on[:, None] * np.asarray(self.gamma, dtype=float)[None, :]


@dataclass(frozen=True)
class Disturbances:
    """Sum of several disturbances (:class:`Disturbance` and :class:`StateDisturbance` may be mixed)."""

    parts: tuple

    def values(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        out = np.zeros((t.shape[0], 9))
        for p in self.parts:
            if not hasattr(p, "generalized_force"):
                out += p.values(t, rng)
        return out


# ================================================================================== hooks
class ExternalWrench(Protocol):
    """Wrench applied by a stateless environment at the end-effector frame origin.

    Called at every integration stage as ``h = wrench(t, q, v)`` with the stage's Pinocchio
    state (an environment with its own state is an :class:`qprr.environment.Environment`); returns
    h = [f_x, f_y, f_z, m_x, m_y, m_z] in world axes (N, N m).  It enters the dynamics as
    tau_ext = J_e^T h with J_e the LOCAL_WORLD_ALIGNED end-effector Jacobian (Thesis (5.38)).
    """

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class PayloadChange:
    """From ``time`` on [s], the end effector carries ``mass`` [kg] (a point mass) at ``com_ee`` (end-effector frame) [m].

    mass = 0 removes the payload (e.g. a release).  In a simulation the change takes effect at
    the first control tick at or after ``time`` (payload changes sit on the control grid).
    """

    time: float
    mass: float
    com_ee: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.time) and self.time >= 0.0):
            raise InputError(f"payload change time must be >= 0, got {self.time!r}")
        if not (np.isfinite(self.mass) and self.mass >= 0.0):
            raise InputError(f"payload mass must be >= 0, got {self.mass!r}")
        as_vector(self.com_ee, 3, "com_ee")


@dataclass(frozen=True)
class PayloadSchedule:
    """Payload changes applied during a run, in time order (see :class:`PayloadChange`)."""

    changes: tuple[PayloadChange, ...] = ()

    def __post_init__(self) -> None:
        times = [c.time for c in self.changes]
        if times != sorted(times):
            raise InputError(f"payload changes must be in time order, got times {times}")

    def mass_at(self, t: float) -> float:
        m = 0.0
        for c in self.changes:
            if c.time <= t:
                m = c.mass
        return m


class _PayloadModel:
    """Owns a copy of the model and sets the end effector's parent-joint inertia to nominal + payload."""

    def __init__(self, robot: Robot, schedule: PayloadSchedule) -> None:
        self.model = pin.Model(robot.model)
        frame = self.model.frames[robot.ee_frame]
        self.joint = frame.parentJoint
        self.placement = frame.placement
        self.nominal = pin.Inertia(self.model.inertias[self.joint])
        self.changes = list(schedule.changes)
        self.next = 0

    def apply_until(self, t: float) -> bool:
        changed = False
        while self.next < len(self.changes) and self.changes[self.next].time <= t + 1e-12:
            c = self.changes[self.next]
            lever = self.placement.act(np.asarray(c.com_ee, dtype=float))
            self.model.inertias[self.joint] = self.nominal + pin.Inertia(c.mass, lever, np.zeros((3, 3)))
            self.next += 1
            changed = True
        return changed


# ================================================================================= result
_ARRAYS = ("t", "xi", "xi_dot", "xi_d", "xi_dot_d", "u", "f", "arm_effort", "x_cm", "unallocated", "flags", "u_ext")


@dataclass
class SimResult:
    """Logged run (one row per control tick, values at the tick).

    ``dt`` [s] is the integration step, ``control_period`` [s] the controller's period (the
    spacing of the rows; equal to ``dt`` unless the run set it).

    t (n,) [s]; xi, xi_dot (n, 9) measured thesis coordinates; xi_d, xi_dot_d (n, 9)
    references actually tracked (roll/pitch from the controller); u (n, 9) controller output
    (thesis generalised forces: u_fb world force, u_tau Euler torques, u_mu arm efforts);
    f (n, 4) rotor thrusts [N]; arm_effort (n, 3) [N, N m, N m] applied; x_cm (n, 3) system
    CoM in B [m] (Thesis (3.78)); unallocated (n, 9) tau_d - N f (Pinocchio coordinates);
    flags (n,) bits: 1 rotor bound, 2 arm effort clipped (allocation), 4 an arm joint at its mechanical stop;
    u_ext (n, 9) disturbance.
    """

    scenario: str
    controller: str
    dt: float
    integrator: str
    t: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    xi_d: np.ndarray
    xi_dot_d: np.ndarray
    u: np.ndarray
    f: np.ndarray
    arm_effort: np.ndarray
    x_cm: np.ndarray
    unallocated: np.ndarray
    flags: np.ndarray
    u_ext: np.ndarray
    wall_time: float = 0.0
    status: str = "ok"
    reason: str = ""
    seed: int | None = None
    info: dict = field(default_factory=dict)
    control_period: float | None = None

    def __post_init__(self) -> None:
        if self.control_period is None:
            self.control_period = self.dt

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def rmse(self, start: float = 0.0) -> dict[str, float]:
        """Thesis (6.26): sqrt(mean((xi_d - xi)^2)) per variable over t >= ``start``."""
        sel = self.t >= start
        e = self.xi_d[sel] - self.xi[sel]
        return {name: float(np.sqrt(np.mean(e[:, i] ** 2))) for i, name in enumerate(XI_NAMES)}

    def saturation_fraction(self) -> float:
        """Fraction of steps where a rotor thrust bound was active."""
        return float(np.mean((self.flags & 1) != 0)) if self.n else 0.0

    def save(self, path: str | Path) -> Path:
        """Write every array and the metadata to a ``.npz`` file."""
        path = Path(path)
        if path.suffix != ".npz":
            raise InputError(f"result files end in .npz, got {str(path)!r}")
        path.parent.mkdir(parents=True, exist_ok=True)
        meta = dict(scenario=self.scenario, controller=self.controller, dt=self.dt, integrator=self.integrator,
                    control_period=self.control_period, wall_time=self.wall_time, status=self.status, reason=self.reason,
                    seed=-1 if self.seed is None else self.seed)
        arrays = {k: getattr(self, k) for k in _ARRAYS}
        np.savez_compressed(path, **arrays, **{f"meta_{k}": np.asarray(v) for k, v in meta.items()})
        return path

    @classmethod
    def load(cls, path: str | Path) -> SimResult:
        """Read a file written by :meth:`save`."""
        with np.load(Path(path), allow_pickle=False) as z:
            arrays = {k: z[k] for k in _ARRAYS}
            meta = {k[5:]: z[k].item() for k in z.files if k.startswith("meta_")}
        seed = int(meta.pop("seed"))
        return cls(**arrays, **{k: meta[k] for k in ("scenario", "controller", "dt", "integrator", "wall_time", "status", "reason")},
                   seed=None if seed < 0 else seed, control_period=meta.get("control_period"))


# ============================================================================== progress
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


# ============================================================================ simulation
@dataclass(frozen=True)
class Limits:
    """Runaway bounds: a state beyond them stops the run with DivergenceError."""

    position: float = 1e3  # m
    linear_velocity: float = 100.0  # m/s
    angular_velocity: float = 100.0  # rad/s
    joint_velocity: float = 100.0  # m/s or rad/s


def simulate(
    robot: Robot,
    controller: Controller,
    trajectory,
    duration: float,
    *,
    dt: float = 1e-3,
    integrator: str = "midpoint",
    control_period: float | None = None,
    xi0=None,
    xi_dot0=None,
    disturbance: Disturbance | StateDisturbance | None = None,
    external_wrench: Environment | Callable[[float, np.ndarray, np.ndarray], np.ndarray] | None = None,
    payload: PayloadSchedule | None = None,
    allocator: Allocator | None = None,
    seed: int | None = 0,
    limits: Limits = Limits(),
    joint_stops: bool = True,
    progress: bool = False,
    scenario: str = "custom",
) -> SimResult:
    """Run ``controller`` on the Q-PRR along ``trajectory`` for ``duration`` seconds.

    ``dt`` [s] is the integration step; ``control_period`` [s] (default ``dt``) the period of
    the digital controller, an integer multiple of ``dt``: the controller, the allocation, the
    disturbance samples of :class:`Disturbance` and the payload changes act at the control
    ticks k control_period and are held in between (zero-order hold), while the plant is
    integrated with ``control_period / dt`` steps of ``integrator`` per period.  The result
    has one row per control tick.  State-dependent inputs (``external_wrench``, a
    :class:`StateDisturbance`) are evaluated at every integration stage.
    ``xi0`` defaults to the trajectory at t = 0 (zero rates); ``seed`` seeds the noise.
    ``joint_stops``: the arm joints end at mechanical stops (the joint limits of the
    parameters, e.g. the +-0.04 m slider stroke): see :func:`_apply_joint_stops`; steps
    where a stop acted carry bit 4 in ``SimResult.flags``.
    Returns a :class:`SimResult`; raises :class:`DivergenceError` (with ``.result``) on NaN
    or runaway states.  See the module docstring for the step.
    """
    if integrator not in INTEGRATORS:
        raise UnknownNameError("integrator", integrator, INTEGRATORS)
    if not (np.isfinite(dt) and dt > 0.0):
        raise InputError(f"dt must be a positive number of seconds, got {dt!r}")
    if control_period is None:
        period, substeps = dt, 1
    else:
        if not (np.isfinite(control_period) and control_period > 0.0):
            raise InputError(f"control_period must be a positive number of seconds, got {control_period!r}")
        substeps = int(round(control_period / dt))
        if substeps < 1 or abs(substeps * dt - control_period) > 1e-9 * control_period:
            raise InputError(f"control_period = {control_period!r} s must be an integer multiple of dt = {dt!r} s")
        period = float(control_period)
    if not (np.isfinite(duration) and duration >= period):
        raise InputError(f"duration must be >= the control period {period!r} s, got {duration!r}")
    if not isinstance(controller, Controller):
        raise InputError(f"controller must be a qprr.control Controller, got {type(controller).__name__}")
    n = int(round(duration / period))
    t = np.arange(n) * period
    sample = trajectory.sample(t)
    check_sample(sample, n)
    xi_d = sample.xi.copy()
    xi_dot_d = sample.xi_dot.copy()
    xi_ddot_d = sample.xi_ddot.copy()
    xi0 = xi_d[0].copy() if xi0 is None else as_vector(xi0, 9, "xi0")
    lo, hi = robot.params.lower_limits.tolist(), robot.params.upper_limits.tolist()
    if joint_stops:
        robot.check_arm_limits(xi0[6:9], "xi0[6:9]")
    xi_dot0 = np.zeros(9) if xi_dot0 is None else as_vector(xi_dot0, 9, "xi_dot0")
    rng = np.random.default_rng(seed)
    timed, state_dist = _split_disturbance(disturbance)
    u_ext = np.zeros((n, 9)) if timed is None else np.asarray(timed.values(t, rng), dtype=float)
    if u_ext.shape != (n, 9):
        raise ShapeError(f"disturbance values must have shape ({n}, 9), got {u_ext.shape}")
    if not np.all(np.isfinite(u_ext)):
        raise NonFiniteError("disturbance values must be finite")
    ext_rows = np.any(u_ext != 0.0, axis=1)
    has_ext = bool(ext_rows.any())
    # per-tick disturbance rows as float lists (None where zero): no array indexing in the loop
    u_ext_rows = [row if nz else None for row, nz in zip(u_ext.tolist(), ext_rows.tolist())] if has_ext else None

    payload_model = _PayloadModel(robot, payload or PayloadSchedule())
    model = payload_model.model  # the plant: a copy, never robot.model
    data = model.createData()
    payload_model.apply_until(0.0)
    alloc = allocator if allocator is not None else Allocator(robot)
    N = np.zeros((9, 7))
    N[0:6, 0:4] = alloc.Omega
    N[6:9, 4:7] = np.eye(3)

    # logs (the world CoM is logged raw; x_cm in B and the unallocated force
    # tau_d - N f with tau_d = S^-T u are derived after the loop, vectorised)
    xi_log = np.zeros((n, 9))
    xid_log = np.zeros((n, 9))
    u_log = np.zeros((n, 9))
    f_log = np.zeros((n, 7))
    com_log = np.zeros((n, 3))
    flags = np.zeros(n, dtype=np.int8)

    q = xi_to_q(xi0)
    v = xi_dot_to_v(xi0, xi_dot0)
    state = State()
    state.update(0.0, q, v)
    ref = Reference(xi_d[0], xi_dot_d[0], xi_ddot_d[0])
    controller.reset(state, ref, period)
    tau = np.zeros(9)  # generalised force held over the control period (allocated + timed disturbance)
    plant = _Plant(model, data, tau, robot.ee_frame, external_wrench, state_dist)
    env, z = plant.env, plant.z0
    rhs, first_stage = plant.rhs, plant.first_stage
    settle = env.settle if (env is not None and z is not None) else None
    stepper = make_stepper(integrator, model, dt)
    steps = [j * dt for j in range(substeps)]  # step start times within a control period
    plain = plant.plain  # ABA alone: no state-dependent input
    bar = _Progress(n, f"{scenario}/{getattr(controller, 'name', 'controller')}", progress)
    pos_lim, vlin_lim, w_lim, qd_lim = limits.position, limits.linear_velocity, limits.angular_velocity, limits.joint_velocity
    POSITION = pin.KinematicLevel.POSITION
    wants_applied = bool(getattr(controller, "uses_applied_force", False))
    pin_out = getattr(controller, "output", "xi") == "pinocchio"
    payload_pending = len(payload_model.changes) > payload_model.next
    b1, tau_d_buf = np.empty(9), np.empty(9)
    add, com, step, aba = np.add, pin.centerOfMass, controller.step, pin.aba
    allocate = alloc.allocate_into
    update, set_applied, force_from_xi = state.update, state.set_applied, state.force_from_xi
    t_start = time.perf_counter()
    k = 0
    status, reason = "ok", "completed"
    try:
        for k in range(n):
            tk = k * period
            if payload_pending:  # payload changes act at control ticks
                payload_model.apply_until(tk)
                payload_pending = len(payload_model.changes) > payload_model.next
            state.xi, state.xi_dot = xi_log[k], xid_log[k]  # the state writes its xi straight into the log
            update(tk, q, v)
            ref.xi, ref.xi_dot, ref.xi_ddot = xi_d[k], xi_dot_d[k], xi_ddot_d[k]
            if pin_out:
                tau_d = step(tk, state, ref)
                u_log[k] = tau_d  # converted to u = S^T tau_d after the loop
            else:
                u = step(tk, state, ref)
                u_log[k] = u
                tau_d = force_from_xi(u, tau_d_buf)
            fl = allocate(tau_d, f_log[k], tau)  # f straight into the log, N f into tau
            if fl:
                flags[k] = fl
            if wants_applied:
                set_applied(tau)
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
                    r0, t2, t3 = q[7:10].tolist()
                    if not (lo[0] <= r0 <= hi[0] and lo[1] <= t2 <= hi[1] and lo[2] <= t3 <= hi[2]):
                        q, v = _apply_joint_stops(model, data, q, v, lo, hi)
                        flags[k] |= 4
            if not k & 15:
                _check(tk + period, q, v, pos_lim, vlin_lim, w_lim, qd_lim)
                if progress and k % bar.every == 0:
                    bar.update(k)
        _check(n * period, q, v, pos_lim, vlin_lim, w_lim, qd_lim)
        m = n
    except QprrError as err:
        m = k + 1
        if isinstance(err, DivergenceError) and not str(err).startswith(("t =", "diverged at")):
            err = DivergenceError(f"diverged at t = {k * period:.3f} s: {err}")
        status, reason = ("diverged" if isinstance(err, DivergenceError) else "failed"), str(err)
        err.result = _result(scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log,
                             com_log, N, flags, u_ext, time.perf_counter() - t_start, seed, m, status, reason, pin_out=pin_out,
                             period=period)
        raise err
    finally:
        if progress:
            bar.close()
    return _result(scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log,
                   com_log, N, flags, u_ext, None, seed, m, status, reason, t_start, pin_out, period)


class _Plant:
    """Right-hand side a = M^-1 (tau - h(q, v)) of the plant, Pinocchio's ABA in the LOCAL convention.

    ``tau`` (a buffer the simulator refills at each control tick) is held over the period;
    state-dependent inputs are evaluated at every call, i.e. at every integration stage:
    the end-effector wrench J_e^T h (Jacobian and wrench at the stage's q, v and environment
    state z) and the :class:`StateDisturbance` forces.  Without them the right-hand side is
    ABA alone.  With an :class:`Environment` that has a state, ``rhs(t, q, v, z)`` returns
    (a, z_dot) (the form :mod:`qprr.integrators` expects).
    """

    def __init__(self, model, data, tau, ee_frame, external_wrench, state_dist) -> None:
        self.model, self.data, self.tau, self.ee = model, data, tau, ee_frame
        self.state_dist = tuple(state_dist)
        self.env = external_wrench if isinstance(external_wrench, Environment) else None
        self.fn = None if self.env is not None else external_wrench
        self.z0 = None
        if self.env is not None:
            self.env.reset()
            z0 = np.array(self.env.initial_state(), dtype=float).ravel()
            if not np.all(np.isfinite(z0)):
                raise NonFiniteError(f"environment initial state must be finite, got {z0.tolist()}")
            self.z0 = z0 if z0.size else None
        aba = pin.aba
        self.plain = self.env is None and self.fn is None and not self.state_dist
        if self.plain:
            self.rhs = lambda t, q, v: aba(model, data, q, v, tau)  # LOCAL convention (the default)
        elif self.z0 is None:
            self.rhs = self._rhs
        else:
            self.rhs = self._rhs_z

    def _force(self, t: float, q, v, z) -> tuple[np.ndarray, np.ndarray | None]:
        """(tau + J_e^T h + state disturbances, z_dot) at one stage."""
        tau = self.tau.copy()
        zd = None
        for d in self.state_dist:
            tau += np.asarray(d.generalized_force(t, q, v), dtype=float)
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
            return self.rhs(t, q, v)
        self.env.on_tick(t)
        out = self.rhs(t, q, v) if z is None else self.rhs(t, q, v, z)
        p, R, twist, h = self._last
        self.env.observe(t, p, R, twist, z if z is not None else _NO_STATE, h)
        return out


_NO_STATE = np.zeros(0)


def _split_disturbance(disturbance) -> tuple[object | None, list]:
    """(timed part with ``values(t, rng)`` or None, state-dependent parts with ``generalized_force(t, q, v)``)."""
    if disturbance is None:
        return None, []
    parts = disturbance.parts if isinstance(disturbance, Disturbances) else (disturbance,)
    timed, state = [], []
    for p in parts:
        if hasattr(p, "generalized_force"):
            state.append(p)
        elif hasattr(p, "values"):
            timed.append(p)
        else:
            raise InputError(f"a disturbance needs values(t, rng) (known in advance) or generalized_force(t, q, v) "
                             f"(state-dependent), got {type(p).__name__}")
    if not timed:
        return None, state
    return (timed[0] if len(timed) == 1 else Disturbances(tuple(timed))), state


def _apply_joint_stops(model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """Mechanical stops of the arm joints: plastic impacts at the limits.

    Position: a joint past its limit is moved back onto it by the mass-weighted correction
    dq = -M^-1 E (E^T M^-1 E)^-1 penetration, the displacement an internal joint force
    produces, so the system's centre of mass does not move (and the base recoils as it would).
    Velocity: the impulses E lambda that zero the outward rates of the joints at their stops
    act on the whole tree, v+ = v - M^-1 E lambda (M^-1 from Pinocchio), found by projected
    Gauss-Seidel (an impulse only pushes a joint inward).  Being internal they leave the
    momentum unchanged, and kinetic energy can only decrease; a joint held against its stop by
    the controller stays there step after step.
    """
    stops = []  # (velocity index, limit, +1 at the upper stop / -1 at the lower): on or past it
    for j in range(3):
        if q[7 + j] <= lo[j]:
            stops.append((6 + j, lo[j], -1.0))
        elif q[7 + j] >= hi[j]:
            stops.append((6 + j, hi[j], 1.0))
    if not stops:
        return q, v
    idx = [i for i, _, _ in stops]
    Minv = pin.computeMinverse(model, data, q)
    cols = np.array([_upper_column(Minv, i) for i in idx]).T  # M^-1 E
    penetration = np.array([q[i + 1] - limit for i, limit, _ in stops])
    q = pin.integrate(model, q, -(cols @ np.linalg.solve(cols[idx], penetration)))
    for i, limit, _ in stops:
        q[i + 1] = limit  # exactly on the stop (the correction is exact to first order)
    Minv = pin.computeMinverse(model, data, q)  # the impulses act at the corrected configuration
    cols = {i: _upper_column(Minv, i) for i in idx}
    v = v.copy()
    impulse = {i: 0.0 for i in idx}  # accumulated; side * impulse >= 0 (pushes inward)
    for _ in range(50):
        largest = 0.0
        for i, _, side in stops:
            c = cols[i]
            new = side * max(0.0, side * (impulse[i] + v[i] / c[i]))
            d = new - impulse[i]
            if d != 0.0:
                v -= c * d
                impulse[i] = new
                largest = max(largest, abs(d) * c[i])
        if largest < 1e-12:
            break
    return q, v


def _upper_column(Minv: np.ndarray, i: int) -> np.ndarray:
    """Column i of the symmetric M^-1 read from its upper triangle (all Pinocchio versions fill it)."""
    return np.concatenate((Minv[:i, i], Minv[i, i:]))


def _force_from_xi(R: np.ndarray, xi: np.ndarray, u: np.ndarray) -> np.ndarray:
    """tau = S^-T u row by row (vectorised :meth:`State.force_from_xi`): R^T u_p, T^-T u_tau, u_mu."""
    tau = np.empty_like(u)
    tau[:, 0:3] = np.einsum("nji,nj->ni", R, u[:, 0:3])
    sf, cf = np.sin(xi[:, 3]), np.cos(xi[:, 3])
    st, ct = np.sin(xi[:, 4]), np.cos(xi[:, 4])
    m0, m1, m2 = u[:, 3], u[:, 4], u[:, 5]
    w = (m2 + st * m0) / ct
    tau[:, 3] = m0
    tau[:, 4] = cf * m1 + sf * w
    tau[:, 5] = -sf * m1 + cf * w
    tau[:, 6:9] = u[:, 6:9]
    return tau


def _force_to_xi(R: np.ndarray, xi: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """u = S^T tau row by row (vectorised :meth:`State.force_to_xi`): R tau_lin, T^T tau_ang, tau_arm."""
    u = np.empty_like(tau)
    u[:, 0:3] = np.einsum("nij,nj->ni", R, tau[:, 0:3])
    sf, cf = np.sin(xi[:, 3]), np.cos(xi[:, 3])
    st, ct = np.sin(xi[:, 4]), np.cos(xi[:, 4])
    m0, m1, m2 = tau[:, 3], tau[:, 4], tau[:, 5]
    u[:, 3] = m0
    u[:, 4] = cf * m1 - sf * m2
    u[:, 5] = -st * m0 + sf * ct * m1 + cf * ct * m2
    u[:, 6:9] = tau[:, 6:9]
    return u


def _rotations(euler: np.ndarray) -> np.ndarray:
    """R = Rz(psi) Ry(theta) Rx(phi) for rows [phi, theta, psi], shape (n, 3, 3) (vectorised (3.4))."""
    sf, cf = np.sin(euler[:, 0]), np.cos(euler[:, 0])
    st, ct = np.sin(euler[:, 1]), np.cos(euler[:, 1])
    sp, cp = np.sin(euler[:, 2]), np.cos(euler[:, 2])
    R = np.empty((euler.shape[0], 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 0, 2] = cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf
    R[:, 1, 0], R[:, 1, 1], R[:, 1, 2] = sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf
    R[:, 2, 0], R[:, 2, 1], R[:, 2, 2] = -st, ct * sf, ct * cf
    return R


def _result(scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log, com_log,
            N, flags, u_ext, wall, seed, m, status, reason, t_start=None, pin_out=False, period=None) -> SimResult:
    xi = xi_log[:m]
    R = _rotations(xi[:, 3:6])
    x_cm = np.einsum("nji,nj->ni", R, com_log[:m] - xi[:, 0:3])  # R^T (c - p)
    if pin_out:  # the controller returned Pinocchio forces: log u = S^T tau_d
        tau_d = u_log[:m].copy()
        u_log[:m] = _force_to_xi(R, xi, tau_d)
    else:
        tau_d = _force_from_xi(R, xi, u_log[:m])
    unalloc = tau_d - f_log[:m] @ N.T
    if wall is None:
        wall = time.perf_counter() - t_start
    return SimResult(
        scenario=scenario, controller=getattr(controller, "name", type(controller).__name__), dt=dt,
        integrator=integrator, t=t[:m].copy(), xi=xi, xi_dot=xid_log[:m], xi_d=xi_d[:m], xi_dot_d=xi_dot_d[:m],
        u=u_log[:m], f=f_log[:m, 0:4].copy(), arm_effort=f_log[:m, 4:7].copy(), x_cm=x_cm, unallocated=unalloc,
        flags=flags[:m], u_ext=u_ext[:m], wall_time=wall, status=status, reason=reason, seed=seed, control_period=period,
    )


_V_NAMES = ("v_x", "v_y", "v_z", "omega_x", "omega_y", "omega_z", "r0_dot", "theta2_dot", "theta3_dot")


def _check(t: float, q: np.ndarray, v: np.ndarray, pos_lim: float, vlin_lim: float, w_lim: float, qd_lim: float) -> None:
    """Raise DivergenceError naming the first offending state entry (NaN or beyond Limits)."""
    ql, vl = q.tolist(), v.tolist()
    bounds = (vlin_lim,) * 3 + (w_lim,) * 3 + (qd_lim,) * 3
    for i in range(3):
        if not abs(ql[i]) < pos_lim:
            raise DivergenceError(f"diverged at t = {t:.3f} s: position {XI_NAMES[i]} = {ql[i]!r} m (bound {pos_lim} m)")
    for i in range(7, 10):
        if not math.isfinite(ql[i]):
            raise DivergenceError(f"diverged at t = {t:.3f} s: joint {XI_NAMES[i - 1]} = {ql[i]!r}")
    if not all(math.isfinite(x) for x in ql[3:7]):
        raise DivergenceError(f"diverged at t = {t:.3f} s: attitude quaternion is NaN")
    for i in range(9):
        if not abs(vl[i]) < bounds[i]:
            raise DivergenceError(f"diverged at t = {t:.3f} s: velocity {_V_NAMES[i]} = {vl[i]!r} (bound {bounds[i]})")
