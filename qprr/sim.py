"""Closed-loop simulation of the Q-PRR: Pinocchio ABA on the Lie group, fixed step.

One step (period ``dt``, 1 kHz by default), inputs held constant over the step (zero-order hold):

1. state (q, v) -> thesis coordinates (xi, xi_dot) (:class:`qprr.control.base.State`);
2. the controller returns the desired generalised force u (thesis coordinates, Thesis (5.40));
3. tau_d = S^-T u is allocated to 4 rotor thrusts in [f_min, f_max] and 3 arm efforts
   (:class:`qprr.allocation.Allocator`); the applied force is tau = N f (Thesis (5.43));
4. disturbances are added: u_ext of Thesis (6.27) (white noise, pulses (6.28)) as S^-T u_ext,
   and an optional end-effector wrench h (world axes) as J_e^T h;
5. ABA gives a = M^-1 (tau - h(q, v)) and the state is integrated on the Lie group.

Integrators (``integrator=``), inputs held over the step:

* ``"midpoint"`` (the default): explicit midpoint on the Lie group, a1 = ABA(q, v),
  v_h = v + dt/2 a1, q_h = q (+) dt/2 v, a2 = ABA(q_h, v_h), q+ = q (+) dt v_h,
  v+ = v + dt a2 (``pin.integrate`` for (+)).  Two ABA per step, second order.
* ``"rk4"``: classical Runge-Kutta 4 on the tangent space at q (stages q (+) c dt k),
  four ABA per step, fourth order: the accuracy reference.
* ``"euler"``: semi-implicit Euler, v+ = v + dt a(q, v), q+ = q (+) dt v+.  One ABA;
  cheap but its energy drifts and it flatters tracking errors (see below).

Measured (tests/test_sim.py): free tumbling without gravity or input for 10 s at 1 kHz
(|E| = 0.71 J), relative energy error: midpoint 7e-7, RK4 3e-12, semi-implicit Euler 1.4 %
and drifting (first order: the velocity-dependent Coriolis terms in body axes break its
symplecticity).  In closed loop on the static mission the midpoint trajectory stays within
1.1e-6 m of RK4 and Euler's 1.9 mm off; Euler also flatters the tracking errors (its
discretisation matches the controllers' command filters).  Midpoint costs one extra ABA
and ``integrate`` (~3 us per step) over Euler and about half of RK4.

Hooks used by the interaction/payload work:

* ``external_wrench``: a callable ``(t, q, v) -> h`` (6,) = [force; moment] in world
  axes applied at the end-effector frame origin (:class:`ExternalWrench` documents it);
* ``payload``: a :class:`PayloadSchedule` of (time, mass, CoM offset in the end-effector
  frame).  The simulator owns a COPY of the model (``pin.Model(robot.model)``) and changes
  the inertia of the end effector's parent joint at those times; ``robot.model`` is never
  touched and the controller keeps its nominal model.

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
from .errors import DivergenceError, InputError, NonFiniteError, QprrError, ShapeError, UnknownNameError
from .model import Robot
from .trajectory import XI_NAMES, check_sample

INTEGRATORS = ("euler", "midpoint", "rk4")


# =============================================================================== disturbances
class Disturbance(Protocol):
    """Additive generalised force u_ext(t) of Thesis (6.27), thesis coordinates, known in advance."""

    def values(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """u_ext at the step times ``t`` (n,), shape (n, 9)."""


@dataclass(frozen=True)
class WhiteNoise:
    """Uniform white noise in [-amplitude, amplitude] on the selected generalised forces (Sec. 6.3.2.1).

    A new value per ``sample_time`` (default: every step), held in between.  Units are those
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
    """Sum of several disturbances."""

    parts: tuple

    def values(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        out = np.zeros((t.shape[0], 9))
        for p in self.parts:
            out += p.values(t, rng)
        return out


# ================================================================================== hooks
class ExternalWrench(Protocol):
    """Wrench applied by the environment at the end-effector frame origin.

    Called once per step as ``h = wrench(t, q, v)`` with the Pinocchio state; returns
    h = [f_x, f_y, f_z, m_x, m_y, m_z] in world axes (N, N m).  It enters the dynamics as
    tau_ext = J_e^T h with J_e the LOCAL_WORLD_ALIGNED end-effector Jacobian (Thesis (5.38)).
    """

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class PayloadChange:
    """From ``time`` on [s], the end effector carries ``mass`` [kg] (a point mass) at ``com_ee`` (end-effector frame) [m].

    mass = 0 removes the payload (e.g. a release).
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
    """Logged run (one row per step, values at the start of the step).

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
                    wall_time=self.wall_time, status=self.status, reason=self.reason,
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
                   seed=None if seed < 0 else seed)


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
    xi0=None,
    xi_dot0=None,
    disturbance: Disturbance | None = None,
    external_wrench: Callable[[float, np.ndarray, np.ndarray], np.ndarray] | None = None,
    payload: PayloadSchedule | None = None,
    allocator: Allocator | None = None,
    seed: int | None = 0,
    limits: Limits = Limits(),
    joint_stops: bool = True,
    progress: bool = False,
    scenario: str = "custom",
) -> SimResult:
    """Run ``controller`` on the Q-PRR along ``trajectory`` for ``duration`` seconds.

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
    if not (np.isfinite(duration) and duration >= dt):
        raise InputError(f"duration must be >= dt = {dt!r} s, got {duration!r}")
    if not isinstance(controller, Controller):
        raise InputError(f"controller must be a qprr.control Controller, got {type(controller).__name__}")
    n = int(round(duration / dt))
    t = np.arange(n) * dt
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
    u_ext = np.zeros((n, 9)) if disturbance is None else np.asarray(disturbance.values(t, rng), dtype=float)
    if u_ext.shape != (n, 9):
        raise ShapeError(f"disturbance values must have shape ({n}, 9), got {u_ext.shape}")
    if not np.all(np.isfinite(u_ext)):
        raise NonFiniteError("disturbance values must be finite")
    ext_rows = np.any(u_ext != 0.0, axis=1)
    has_ext = bool(ext_rows.any())
    # per-step disturbance rows as float lists (None where zero): no array indexing in the loop
    u_ext_rows = [row if nz else None for row, nz in zip(u_ext.tolist(), ext_rows.tolist())] if has_ext else None

    payload_model = _PayloadModel(robot, payload or PayloadSchedule())
    model = payload_model.model  # the plant: a copy, never robot.model
    data = model.createData()
    payload_model.apply_until(0.0)
    alloc = allocator if allocator is not None else Allocator(robot)
    N = np.zeros((9, 7))
    N[0:6, 0:4] = alloc.Omega
    N[6:9, 4:7] = np.eye(3)
    ee_frame = robot.ee_frame

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
    controller.reset(state, ref, dt)
    tau = np.zeros(9)
    bar = _Progress(n, f"{scenario}/{getattr(controller, 'name', 'controller')}", progress)
    pos_lim, vlin_lim, w_lim, qd_lim = limits.position, limits.linear_velocity, limits.angular_velocity, limits.joint_velocity
    POSITION = pin.KinematicLevel.POSITION
    WORLD = pin.Convention.WORLD
    rk4 = integrator == "rk4"
    rk2 = integrator == "midpoint"
    wants_applied = bool(getattr(controller, "uses_applied_force", False))
    pin_out = getattr(controller, "output", "xi") == "pinocchio"
    payload_pending = len(payload_model.changes) > payload_model.next
    half = 0.5 * dt
    # the step sizes as arrays: array * array is cheaper than float * array, and the same numbers
    half_v, dt_v = np.full(9, half), np.full(9, dt)
    mul, add, b1, vh, tau_d_buf = np.multiply, np.add, np.empty(9), np.empty(9), np.empty(9)
    aba, integrate, com, step = pin.aba, pin.integrate, pin.centerOfMass, controller.step
    allocate = alloc.allocate_into
    update, set_applied, force_from_xi = state.update, state.set_applied, state.force_from_xi
    t_start = time.perf_counter()
    k = 0
    status, reason = "ok", "completed"
    try:
        for k in range(n):
            tk = k * dt
            if payload_pending:
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
            fl = allocate(tau_d, f_log[k], tau)  # f straight into the log
            if fl:
                flags[k] = fl
            if wants_applied:
                set_applied(tau)
            if has_ext:
                ue = u_ext_rows[k]
                if ue is not None:
                    add(tau, force_from_xi(ue, b1), tau)  # tau += S^-T u_ext
            if external_wrench is not None:
                h = np.asarray(external_wrench(tk, q, v), dtype=float)
                if h.shape != (6,) or not np.all(np.isfinite(h)):
                    raise InputError(f"external_wrench must return 6 finite values, got {h!r} at t = {tk}")
                J = pin.computeFrameJacobian(model, data, q, ee_frame, pin.LOCAL_WORLD_ALIGNED)
                tau += J.T @ h
            a = aba(model, data, q, v, tau, WORLD)
            com_log[k] = com(model, data, POSITION, False)
            if rk2:  # temporaries in buffers (v itself is a new array each step: the caller may keep it)
                vh = add(v, mul(half_v, a, b1), vh)
                a2 = aba(model, data, integrate(model, q, mul(half_v, v, b1)), vh, tau)
                q = integrate(model, q, mul(dt_v, vh, b1))
                v = v + mul(dt_v, a2, b1)
            elif rk4:
                v2 = v + half * a
                a2 = aba(model, data, integrate(model, q, half * v), v2, tau)
                v3 = v + half * a2
                a3 = aba(model, data, integrate(model, q, half * v2), v3, tau)
                v4 = v + dt * a3
                a4 = aba(model, data, integrate(model, q, dt * v3), v4, tau)
                q = integrate(model, q, (dt / 6.0) * (v + 2.0 * (v2 + v3) + v4))
                v = v + (dt / 6.0) * (a + 2.0 * (a2 + a3) + a4)
            else:
                v = v + dt * a
                q = integrate(model, q, dt * v)
            if joint_stops:
                r0, t2, t3 = q[7:10].tolist()
                if not (lo[0] <= r0 <= hi[0] and lo[1] <= t2 <= hi[1] and lo[2] <= t3 <= hi[2]):
                    q, v = _apply_joint_stops(model, data, q, v, lo, hi)
                    flags[k] |= 4
            if not k & 15:
                _check(tk + dt, q, v, pos_lim, vlin_lim, w_lim, qd_lim)
                if progress and k % bar.every == 0:
                    bar.update(k)
        _check(n * dt, q, v, pos_lim, vlin_lim, w_lim, qd_lim)
        m = n
    except QprrError as err:
        m = k + 1
        if isinstance(err, DivergenceError) and not str(err).startswith(("t =", "diverged at")):
            err = DivergenceError(f"diverged at t = {k * dt:.3f} s: {err}")
        status, reason = ("diverged" if isinstance(err, DivergenceError) else "failed"), str(err)
        err.result = _result(scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log,
                             com_log, N, flags, u_ext, time.perf_counter() - t_start, seed, m, status, reason, pin_out=pin_out)
        raise err
    finally:
        if progress:
            bar.close()
    return _result(scenario, controller, dt, integrator, t, xi_log, xid_log, xi_d, xi_dot_d, u_log, f_log,
                   com_log, N, flags, u_ext, None, seed, m, status, reason, t_start, pin_out)


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
            N, flags, u_ext, wall, seed, m, status, reason, t_start=None, pin_out=False) -> SimResult:
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
        flags=flags[:m], u_ext=u_ext[:m], wall_time=wall, status=status, reason=reason, seed=seed,
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
