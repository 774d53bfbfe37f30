"""N copies of a platform stepped by one call: the batched plant of the learning environments (:mod:`qprr.envs`).

The states are arrays, one row per copy ("env"): ``q`` (n, nq) in Pinocchio's configuration space (free flyer:
``p_world`` (3), the attitude quaternion (x, y, z, w), then the arm joints) and ``v`` (n, nv) in its tangent space (the
base twist ``v_body``, ``omega_body`` in the body frame, then the joint rates).  One :meth:`BatchSimulator.step` holds a
generalised force ``tau`` (n, nv) over ``steps`` integration steps of ``dt``, as the scalar simulator holds its allocated
force over a control period (:mod:`qprr.sim.loop`, step 5); the same integrators run on the whole batch:

* the forward dynamics a = M^-1 (tau + tau_f(v) + tau_s(q, v) - h(q, v)) of every copy by Pinocchio's compiled
  ``abaInParallel`` over a :class:`pinocchio.ModelPool` (LOCAL convention, as ``pin.aba`` in the scalar loop); tau_f is
  the URDF's joint friction (:class:`qprr.dynamics.friction.JointFriction`, explicit joints), tau_s an optional
  state-dependent force evaluated at every stage (wind drag: :meth:`step`'s ``force``);
* the rotor thrusts folded into tau as the scalar simulator does: tau = N [f; effort] (Thesis (5.43),
  :meth:`tau_from_thrusts`);
* the Lie-group step q (+) dq by Pinocchio's compiled ``pin.integrate``, copy by copy (:func:`integrate_each`), the
  stages of ``euler`` / ``midpoint`` / ``rk4`` as in :mod:`qprr.sim.integrators`: bit for bit the scalar simulator's
  arithmetic.  The numpy form of the same map, :func:`integrate` (vectorised SE(3) exponential, equal to
  ``pin.integrate`` to 1e-14), serves the environments' sensor noise; in the steps it was slower up to N = 64
  (14.7 against 8.8 us per copy and midpoint step on the Q-PRR), 8 % faster at N = 256, and its last-bit differences,
  amplified by Coulomb friction reversals, put the hextilt 2.2e-12 away from the scalar simulator (0 with
  ``pin.integrate``);
* the arm's mechanical stops (:func:`qprr.sim.stops.apply_joint_stops`) on the copies that reach one, one by one (rare
  events: the impulse solve is per copy).

Copies with their own inertias (a payload in the gripper, a randomised mass: :meth:`set_payload`,
:meth:`set_mass_scale`) get their own models; the batch is then stepped with one ``pin.aba`` call per copy (the pool
holds one model per thread, not per copy).  Joint friction is treated as in the scalar simulator: each copy's joints
are chosen explicit or implicit at its reset state (:meth:`qprr.dynamics.friction.JointFriction.choose`); while every
joint is explicit the friction force is one vectorised term, and a stiff joint (hextilt's wrist at 1 ms) is solved copy
by copy with :meth:`~qprr.dynamics.friction.JointFriction.solve` (slower: a smaller ``dt`` keeps the fast path).

``tests/test_batch.py`` checks the batch against :func:`qprr.sim.simulate` step by step (max difference <= 1e-12 over a
2 s flight, every integrator, the Q-PRR, borinot and hextilt with its Coulomb friction); ``benchmarks/env_benchmark.py`` measures it against one
bare ``pin.aba`` + ``pin.integrate`` step.
"""

from __future__ import annotations

import os

import numpy as np
import pinocchio as pin

from ..dynamics.friction import JointFriction, Treatment
from ..errors import InputError, ShapeError
from ..model import Platform, check_platform
from ..validation import as_int
from .config import SimConfig
from .payload import PayloadChange, PayloadSchedule, PlantPayload
from .stops import apply_joint_stops

__all__ = ["BatchSimulator", "cross", "integrate", "integrate_each", "quaternion_product", "rotate"]

_TAYLOR = 1e-4
"""|omega dt| [rad] below which the SE(3) exponential's coefficients take their Taylor series (error < 1e-18)."""


def integrate_each(model: pin.Model, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """q (+) dq row by row with ``pin.integrate`` on ``model`` (its joints: every copy of a batch shares them), (n, nq)."""
    return np.array([pin.integrate(model, q_i, dq_i) for q_i, dq_i in zip(q, dq)])


def integrate(q: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """q (+) dq for a batch of free-flyer-plus-arm configurations: ``pin.integrate`` row by row, vectorised.

    ``q`` (n, 7 + n_arm): p_world, quaternion (x, y, z, w), arm joints; ``dq`` (n, 6 + n_arm): the increment in the
    tangent space (linear and angular in the body frame, then the joints).  The base moves by the SE(3) exponential,
    M1 = M0 exp6(dq[:, 0:6]) (Pinocchio's ``SpecialEuclideanOperationTpl<3>::integrate``): with theta = |w|,
        p1 = p0 + R0 (nu + (1 - cos theta) / theta^2 w x nu + (theta - sin theta) / theta^3 w x (w x nu)),
        quat1 = quat0 * (sin(theta / 2) w / theta, cos(theta / 2)),
    the sign of quat1 chosen on quat0's side (quat1 . quat0 >= 0) and its norm corrected to first order,
    quat1 (3 - |quat1|^2) / 2, as Pinocchio does.  The arm's revolute and prismatic joints add: q1 = q0 + dq.
    """
    p0, quat0 = q[:, 0:3], q[:, 3:7]
    nu, w = dq[:, 0:3], dq[:, 3:6]
    theta2 = np.einsum("ij,ij->i", w, w)
    theta = np.sqrt(theta2)
    small = theta < _TAYLOR
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 0.5 - theta2 / 24.0, (1.0 - np.cos(safe)) / safe**2)  # (1 - cos) / theta^2
    b = np.where(small, 1.0 / 6.0 - theta2 / 120.0, (safe - np.sin(safe)) / safe**3)  # (theta - sin) / theta^3
    s = np.where(small, 0.5 - theta2 / 48.0, np.sin(0.5 * safe) / safe)  # sin(theta / 2) / theta
    w_x_nu = cross(w, nu)
    translation_body = nu + a[:, None] * w_x_nu + b[:, None] * cross(w, w_x_nu)
    out = np.empty_like(q)
    out[:, 0:3] = p0 + rotate(quat0, translation_body)
    quat1 = quaternion_product(quat0, np.column_stack([s[:, None] * w, np.cos(0.5 * theta)]))
    quat1 *= np.where(np.einsum("ij,ij->i", quat1, quat0) < 0.0, -1.0, 1.0)[:, None]
    out[:, 3:7] = quat1 * (0.5 * (3.0 - np.einsum("ij,ij->i", quat1, quat1)))[:, None]
    out[:, 7:] = q[:, 7:] + dq[:, 6:]
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products a x b of (n, 3) arrays: a_(i+1) b_(i+2) - a_(i+2) b_(i+1) (``np.cross`` costs several
    times more on small batches)."""
    return a[:, _NEXT] * b[:, _AFTER] - a[:, _AFTER] * b[:, _NEXT]


_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of (n, 4) quaternions stored (x, y, z, w) (Pinocchio's / Eigen's order)."""
    va, wa, vb, wb = a[:, 0:3], a[:, 3:4], b[:, 0:3], b[:, 3:4]
    return np.column_stack([wa * vb + wb * va + cross(va, vb), wa * wb - np.einsum("ij,ij->i", va, vb)[:, None]])


def rotate(quat: np.ndarray, x: np.ndarray) -> np.ndarray:
    """R(quat) x for (n, 4) unit quaternions (x, y, z, w) and (n, 3) vectors: x + 2 w (u x x) + 2 u x (u x x)."""
    u, w = quat[:, 0:3], quat[:, 3:4]
    t = 2.0 * cross(u, x)
    return x + w * t + cross(u, t)


class BatchSimulator:
    """``n`` copies of ``platform`` integrated together (module docstring).

    Parameters
    ----------
    platform : the platform (its model is copied: the plant, as in the scalar simulator).
    n : number of copies (>= 1).
    config : a :class:`~qprr.sim.config.SimConfig`; its ``dt``, ``integrator``, ``joint_stops`` and ``limits`` apply
        (default ``SimConfig()``: 1 ms, midpoint, stops on).
    threads : threads of ``abaInParallel`` (default: the machine's cores).
    """

    def __init__(self, platform: Platform, n: int, config: SimConfig | None = None, threads: int | None = None) -> None:
        check_platform(platform)
        self.config = SimConfig() if config is None else config
        if not isinstance(self.config, SimConfig):
            raise InputError(f"config must be a qprr.sim.SimConfig, got {type(self.config).__name__}")
        self.platform, self.n = platform, as_int(n, "n", lo=1)
        self.threads = as_int(os.cpu_count() or 1 if threads is None else threads, "threads", lo=1)
        self.dt = self.config.dt
        self.model = PlantPayload(platform, PayloadSchedule()).model
        self.pool = pin.ModelPool(self.model, self.threads)
        self.models: list[pin.Model] | None = None  # per-copy models (payload, mass scale); None: the shared one
        self.datas: list[pin.Data] = [self.model.createData() for _ in range(self.n)]
        self.payload_mass, self.mass_scale = np.zeros(self.n), np.ones(self.n)
        self.friction = JointFriction.from_model(self.model)  # the URDF's friction, every joint explicit (None: none)
        self.frictions: list[JointFriction | None] = [None] * self.n  # each copy's, chosen at its reset state
        self.implicit = False  # some copy takes a joint's friction implicitly: the per-copy path
        self.N = np.array(platform.actuation_matrix)
        self.q = np.tile(platform.neutral_q(), (self.n, 1))
        self.v = np.zeros((self.n, platform.nv))
        if self.config.integrator not in _STAGES:  # a plug-in's integrator: the batch has no vectorised form of it
            raise InputError(
                f"config.integrator = {self.config.integrator!r}: the batched plant steps with {', '.join(_STAGES)} "
                "(vectorised forms of qprr.sim.integrators); choose one of them, or run simulate() for this integrator"
            )
        self._stage = _STAGES[self.config.integrator]
        self._choose_friction(np.arange(self.n))

    # ------------------------------------------------------------------------------ state and inputs
    def reset(self, q, v, index=None) -> None:
        """Set the copies ``index`` (None: all; an int array or a boolean mask) to (q, v): rows of shape (nq,) / (nv,)
        broadcast, or one row per chosen copy.  The quaternions must be unit (Pinocchio's ``normalize`` first)."""
        rows = self._rows(index)
        q_rows = np.broadcast_to(np.asarray(q, dtype=float), (rows.size, self.platform.nq))
        v_rows = np.broadcast_to(np.asarray(v, dtype=float), (rows.size, self.platform.nv))
        norms = np.linalg.norm(q_rows[:, 3:7], axis=1)
        if not (np.all(np.isfinite(q_rows)) and np.all(np.isfinite(v_rows)) and np.all(np.abs(norms - 1.0) < 1e-9)):
            raise InputError(f"reset: q and v must be finite with unit quaternions q[3:7], got quaternion norms {norms.tolist()[:4]}")
        self.q[rows], self.v[rows] = q_rows, v_rows
        self._choose_friction(rows)

    def tau_from_thrusts(self, f, effort=None) -> np.ndarray:
        """tau = N [f; effort] (n, nv): rotor thrusts f (n, n_rotors) [N] and arm efforts (n, n_arm) [N m or N] as the
        generalised force (Thesis (5.43), the actuation matrix of :attr:`qprr.model.Platform.actuation_matrix`)."""
        nr, na = self.platform.n_rotors, self.platform.n_arm
        u = np.zeros((self.n, nr + na))
        u[:, 0:nr] = _rows_of(f, (self.n, nr), "f")
        if effort is not None:
            u[:, nr:] = _rows_of(effort, (self.n, na), "effort")
        return u @ self.N.T

    def set_payload(self, mass, index=None) -> None:
        """A point-mass payload [kg] at the end-effector frame of the copies ``index`` (0: none), the model of
        :class:`qprr.sim.payload.PlantPayload`; the batch then steps one model per copy."""
        rows = self._rows(index)
        self.payload_mass[rows] = np.broadcast_to(_nonnegative(mass, "mass", "kg"), rows.shape)
        self._rebuild(rows)

    def set_mass_scale(self, scale, index=None) -> None:
        """Scale the base body's mass and rotational inertia by ``scale`` (> 0) on the copies ``index`` (a randomised
        airframe); the batch then steps one model per copy."""
        rows = self._rows(index)
        s = _nonnegative(scale, "scale", "(a ratio)")
        if np.any(s <= 0.0):
            raise InputError(f"set_mass_scale: scale must be > 0, got {np.ravel(s).tolist()[:4]}; 1 keeps the airframe's mass")
        self.mass_scale[rows] = np.broadcast_to(s, rows.shape)
        self._rebuild(rows)

    # --------------------------------------------------------------------------------------- stepping
    def step(self, tau, steps: int = 1, force=None) -> None:
        """Hold ``tau`` (n, nv) over ``steps`` integration steps of ``dt``, updating :attr:`q`, :attr:`v` in place.

        ``force(q, v) -> (n, nv)``: a state-dependent generalised force added at every stage (e.g. wind drag)."""
        tau = _rows_of(tau, (self.n, self.platform.nv), "tau")
        for _ in range(as_int(steps, "steps", lo=1)):
            if self.implicit:  # the implicit joints are taken from the step's start velocity (qprr.sim.loop)
                for friction, v in zip(self.frictions, self.v):
                    friction.start(v)
            q, v = self._stage(self, tau, force)
            if self.config.joint_stops:
                q, v = self._stops(q, v)
            self.q, self.v = q, v

    def acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, force=None) -> np.ndarray:
        """a = M^-1 (tau + tau_f(v) + force(q, v) - h(q, v)) of every copy (n, nv), ABA in the LOCAL convention."""
        total = tau.copy()
        if force is not None:
            total += _rows_of(force(q, v), (self.n, self.platform.nv), "force(q, v)")
        if self.implicit:
            return self._acceleration_per_copy(q, v, total)
        if self.friction is not None:
            self.friction.apply(v, total)
        a = np.empty_like(v)
        if self.models is None:
            pin.abaInParallel(self.threads, self.pool, q.T, v.T, total.T, a.T)
        else:
            for i, (model, data) in enumerate(zip(self.models, self.datas)):
                a[i] = pin.aba(model, data, q[i], v[i], total[i])
        return a

    def diverged(self) -> np.ndarray:
        """(n,) True where a copy's state is not finite or beyond the run's :class:`~qprr.sim.config.Limits`."""
        lim, q, v = self.config.limits, self.q, self.v
        finite = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(v), axis=1)
        with np.errstate(invalid="ignore"):
            inside = (
                np.all(np.abs(q[:, 0:3]) < lim.position, axis=1)
                & np.all(np.abs(v[:, 0:3]) < lim.linear_velocity, axis=1)
                & np.all(np.abs(v[:, 3:6]) < lim.angular_velocity, axis=1)
                & np.all(np.abs(v[:, 6:]) < lim.joint_velocity, axis=1)
            )
        return ~(finite & inside)

    # -------------------------------------------------------------------------------------- internals
    def _rows(self, index) -> np.ndarray:
        if index is None:
            return np.arange(self.n)
        rows = np.arange(self.n)[np.asarray(index)]
        return np.atleast_1d(rows)

    def _rebuild(self, rows: np.ndarray) -> None:
        """The per-copy models of ``rows`` from the nominal plant, the payload and the mass scale."""
        if self.models is None:
            self.models = [self.model] * self.n
        for i in rows.tolist():
            plant = PlantPayload(self.platform, PayloadSchedule((PayloadChange(0.0, float(self.payload_mass[i])),)))
            plant.apply_until(0.0)
            model = plant.model
            base = model.inertias[1]
            s = float(self.mass_scale[i])
            model.inertias[1] = pin.Inertia(s * base.mass, base.lever, s * base.inertia)
            self.models[i], self.datas[i] = model, model.createData()
        self._choose_friction(rows)

    def _acceleration_per_copy(self, q: np.ndarray, v: np.ndarray, total: np.ndarray) -> np.ndarray:
        """The scalar plant's right-hand side copy by copy: explicit friction, ABA, the implicit joints' solve."""
        a = np.empty_like(v)
        for i, (friction, data) in enumerate(zip(self.frictions, self.datas)):
            model = self.model if self.models is None else self.models[i]
            friction.apply(v[i], total[i])
            a[i] = friction.solve(model, data, q[i], v[i], pin.aba(model, data, q[i], v[i], total[i]))
        return a

    def _choose_friction(self, rows: np.ndarray) -> None:
        """Each copy's friction treatment at its (new) state, as the scalar simulator chooses it at a run's start."""
        if self.friction is None:
            return
        for i in rows.tolist():
            model = self.model if self.models is None else self.models[i]
            self.frictions[i] = JointFriction.from_model(model, self.dt, q=self.q[i])
        self.implicit = any(f is not None and Treatment.IMPLICIT in f.treatments for f in self.frictions)

    def _stops(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The mechanical stops of the copies whose arm left its limits after a step (:func:`apply_joint_stops`)."""
        lo, hi = self.platform.arm_lower, self.platform.arm_upper
        outside = (q[:, 7:] < lo) | (q[:, 7:] > hi)
        if not outside.any():
            return q, v
        for i in np.flatnonzero(outside.any(axis=1)).tolist():
            model = self.model if self.models is None else self.models[i]
            q[i], v[i] = apply_joint_stops(model, self.datas[i], q[i], v[i], lo.tolist(), hi.tolist())
        return q, v


def _euler(sim: BatchSimulator, tau: np.ndarray, force) -> tuple[np.ndarray, np.ndarray]:
    """Semi-implicit Euler: v+ = v + dt a(q, v), q+ = q (+) dt v+ (:func:`qprr.sim.integrators.semi_implicit_euler`)."""
    dt = sim.dt
    v_next = sim.v + dt * sim.acceleration(sim.q, sim.v, tau, force)
    return integrate_each(sim.model, sim.q, dt * v_next), v_next


def _midpoint(sim: BatchSimulator, tau: np.ndarray, force) -> tuple[np.ndarray, np.ndarray]:
    """Explicit midpoint on the group (:func:`qprr.sim.integrators.explicit_midpoint`)."""
    dt, h, q, v = sim.dt, 0.5 * sim.dt, sim.q, sim.v
    v_half = v + h * sim.acceleration(q, v, tau, force)
    q_half = integrate_each(sim.model, q, h * v)
    a_half = sim.acceleration(q_half, v_half, tau, force)
    return integrate_each(sim.model, q, dt * v_half), v + dt * a_half


def _rk4(sim: BatchSimulator, tau: np.ndarray, force) -> tuple[np.ndarray, np.ndarray]:
    """Runge-Kutta 4 in the tangent chart at q (:func:`qprr.sim.integrators.rk4`): the chart velocities
    J(delta)^-1 v through ``pin.dDifference`` copy by copy (the one per-copy call of this integrator)."""
    dt, h, q, v = sim.dt, 0.5 * sim.dt, sim.q, sim.v
    a1 = sim.acceleration(q, v, tau, force)
    d1 = v
    v2 = v + h * a1
    q2 = integrate_each(sim.model, q, h * d1)
    d2 = _chart_velocity(sim, q, q2, v2)
    a2 = sim.acceleration(q2, v2, tau, force)
    v3 = v + h * a2
    q3 = integrate_each(sim.model, q, h * d2)
    d3 = _chart_velocity(sim, q, q3, v3)
    a3 = sim.acceleration(q3, v3, tau, force)
    v4 = v + dt * a3
    q4 = integrate_each(sim.model, q, dt * d3)
    d4 = _chart_velocity(sim, q, q4, v4)
    a4 = sim.acceleration(q4, v4, tau, force)
    s = dt / 6.0
    return integrate_each(sim.model, q, s * (d1 + 2.0 * (d2 + d3) + d4)), v + s * (a1 + 2.0 * (a2 + a3) + a4)


def _chart_velocity(sim: BatchSimulator, q0: np.ndarray, q1: np.ndarray, v: np.ndarray) -> np.ndarray:
    """J(delta)^-1 v = dDifference(q0, q1, ARG1) v for every copy (:mod:`qprr.sim.integrators`, rk4)."""
    out = np.empty_like(v)
    for i in range(sim.n):
        out[i] = pin.dDifference(sim.model, q0[i], q1[i], pin.ArgumentPosition.ARG1) @ v[i]
    return out


_STAGES = {"euler": _euler, "midpoint": _midpoint, "rk4": _rk4}


def _rows_of(x, shape: tuple[int, int], name: str) -> np.ndarray:
    """``x`` as a float array of ``shape`` (a single row broadcast to every copy)."""
    a = np.asarray(x, dtype=float)
    if a.shape != shape and a.shape != shape[1:]:
        raise ShapeError(f"{name} must have shape {shape} (one row per copy) or {shape[1:]}, got {a.shape}")
    a = np.broadcast_to(a, shape)
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be finite, got non-finite entries in rows {np.flatnonzero(~np.all(np.isfinite(a), axis=1)).tolist()[:8]}")
    return a


def _nonnegative(x, name: str, unit: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a < 0.0):
        raise InputError(f"{name} must be finite and >= 0 {unit}, got {np.ravel(a).tolist()[:4]}")
    return a
