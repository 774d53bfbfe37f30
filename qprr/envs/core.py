"""The batched environment: n episodes of one task on one platform, stepped together through one BatchSimulator.

:class:`BatchCore` is the one implementation behind both front ends: the vector environment
(:class:`qprr.envs.vector.AerialVectorEnv`, n copies, autoreset) and the scalar one (:class:`qprr.envs.scalar.AerialEnv`,
n = 1).  It knows nothing of Gymnasium: arrays in, arrays out.  Each copy draws everything random from its own
generator, in the same order whatever n, so copy i of a batch and a scalar environment given the same generator fly
the same episode.

A step (control period h, :meth:`BatchCore.step`), for the live copies:

1. the action (n, m), clipped to [-1, 1] (a non-finite entry raises), becomes thrust commands and arm efforts (:mod:`qprr.envs.actions`) from the
   measured state at t_k and the plan at t_k;
2. the thrusts pass the rotors' first-order lag (:func:`qprr.envs.randomize.lag_factors`: the period's mean is held);
3. tau = N [f; effort] (Thesis (5.43)) is held over h = ``substeps`` dt while the plant integrates, with the base drag
   in the wind sampled at t_k + h / 2 evaluated at every stage (:func:`qprr.envs.randomize.drag_force`);
4. Carry's payload attaches when the end effector comes within :data:`qprr.envs.tasks.ATTACH_RADIUS` of it (a point mass
   at the end-effector frame from then on, :meth:`qprr.sim.batch.BatchSimulator.set_payload`);
5. the state is measured (noise), observed (:mod:`qprr.envs.observation`), rewarded (:class:`qprr.envs.tasks.RewardWeights`)
   and judged: terminated when the state is not finite or beyond the simulator's limits (:class:`qprr.sim.config.Limits`),
   the base farther than ``box`` from its reference, tilted beyond ``max_tilt``, or the controller of the reference mode
   failed; truncated at the episode's time limit.

Copies marked frozen do not advance (the vector environment's autoreset: a copy reset at this step keeps its initial
state, its reward is 0 and its flags are False).
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..errors import InputError, NonFiniteError, ShapeError
from ..sim.batch import BatchSimulator, integrate
from ..validation import as_array, as_int
from .actions import ReferenceMap, ThrustMap, Tick, WrenchMap
from .observation import ObservationLayout, rotation_rows, wrap
from .randomize import GUST_LENGTH, Draw, Randomization, check_rng, drag_force, lag_factors, wind_world
from .settings import ActionMode, EnvSettings, TaskKind, task_kind
from .tasks import ATTACH_RADIUS, CARRY_MASS_FRACTION, TASKS, Success, ee_positions, mission_sample, plan_episode


class EndReason(Enum):
    """Why an episode ended at a step ("" while it runs)."""

    RUNNING = ""
    TIME_LIMIT = "time limit"
    DIVERGED = "state not finite or beyond the simulator's limits"
    LEFT_BOX = "base farther than box from its reference"
    TILTED = "tilt beyond max_tilt"
    CONTROLLER = "the reference mode's controller failed"


class BatchCore:
    """``n`` copies of the task ``task`` (a :class:`~qprr.envs.settings.TaskKind`, its value or its Gymnasium id)
    under ``settings`` (:class:`~qprr.envs.settings.EnvSettings`); module docstring."""

    def __init__(self, task, n: int, settings: EnvSettings) -> None:
        self.kind = task_kind(task)
        self.spec = TASKS[self.kind]
        if not isinstance(settings, EnvSettings):
            raise InputError(f"settings must be a qprr.envs.settings.EnvSettings, got {type(settings).__name__} {settings!r}")
        self.settings = settings
        n = as_int(n, "n", lo=1)
        if settings.mission is not None and self.kind is not TaskKind.TRACK:
            raise InputError(f"mission is Track's reference (qprr/Track-v0); the {self.kind.value} task draws its own plan: drop mission=")
        self.platform = platform = settings.resolve_platform()
        if settings.mission is not None:
            mission_sample(settings.mission, np.zeros(1), platform.n_xi)  # a trajectory of this platform's coordinates
        self.n = n
        self.period = settings.control_period
        self.duration = settings.duration if settings.duration is not None else self.spec.duration
        self.ticks = max(1, int(round(self.duration / self.period)))
        self.steps = settings.actuation_steps  # thrust commands (controller calls) per action
        given = settings.randomize if settings.randomize is not None else self.spec.randomize
        self.randomization = Randomization.from_mapping(given or {})
        self.sim = BatchSimulator(platform, n, settings.sim_config(), threads=settings.threads)
        self.actions = _action_map(settings, platform, n)
        self.layout = ObservationLayout(platform, settings.box)
        self.data = platform.data()
        self.Omega_pinv = np.linalg.pinv(np.array(platform.rotor_matrix))
        self.N = np.array(platform.actuation_matrix)
        self.f_min, self.f_max = np.array(platform.thrust_min), np.array(platform.thrust_max)
        self._allocate_rows()

    # ------------------------------------------------------------------------------------------ per-copy arrays
    def _allocate_rows(self) -> None:
        n, p, k = self.n, self.platform, self.ticks * self.steps + 1
        self.tick = np.zeros(n, dtype=int)
        self.draws = [Draw()] * n
        self.wind_mean, self.gust_peak = np.zeros((n, 3)), np.zeros((n, 3))
        self.gust_start, self.drag, self.noise = np.zeros(n), np.zeros(n), np.zeros(n)
        self.lag_end, self.lag_mean = np.zeros(n), np.zeros(n)
        self.thrust = np.tile(np.array(p.thrust_min), (n, 1))  # the lag's state [N]
        self.ref_xi, self.ref_xi_dot, self.ref_xi_ddot = (np.zeros((n, k, p.n_xi)) for _ in range(3))  # the plan
        self.ee_plan = np.zeros((n, self.ticks + 1, 3))  # Hover, Track: the plan's end effector at the ticks (their target)
        self.ee_goal = np.zeros((n, 2, 3))  # Reach: the target (twice); Carry: the payload's point, the goal
        self.carried = np.zeros(n)  # Carry: the payload's mass [kg]
        self.attached = np.zeros(n, dtype=bool)
        self.inside_time, self.error_sum = np.zeros(n), np.zeros(n)
        self.q_meas, self.v_meas = self.sim.q.copy(), self.sim.v.copy()
        self.obs = np.zeros((n, self.layout.size), dtype=np.float32)
        self.trajectories: list = [None] * n

    @property
    def action_size(self) -> int:
        return self.actions.size

    # --------------------------------------------------------------------------------------------------- reset
    def reset_rows(self, rows: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """New episodes for the copies ``rows``, copy ``rows[j]`` drawing from ``rngs[j]``: the randomisation, the
        task's goals and initial state, then the first measurement's noise."""
        rows = self._check_rows(rows)
        _check_rngs(rngs, rows.size)
        q0 = np.zeros((rows.size, self.platform.nq))
        for j, i in enumerate(rows.tolist()):
            self.draws[i] = self.randomization.draw(rngs[j], self.duration)
            q0[j] = self._plan_row(i, rngs[j])
        self._apply_draws(rows)
        self.sim.reset(q0, np.zeros(self.platform.nv), rows)
        self.thrust[rows] = self._hover_thrusts(q0)
        self.tick[rows] = 0
        self.attached[rows] = False
        self.inside_time[rows], self.error_sum[rows] = 0.0, 0.0
        self._measure(rows, rngs)
        live = np.zeros(self.n, dtype=bool)
        live[rows] = True
        self.actions.reset(rows, self._tick_context(live), self.trajectories)
        self.obs[rows] = self._observe()[rows]

    def _check_rows(self, rows) -> np.ndarray:
        """``rows`` as distinct copy indices in [0, n) (an int array), else an InputError naming them."""
        a = np.asarray(rows)
        if a.ndim != 1 or (a.size and a.dtype.kind not in "iu"):
            raise InputError(f"rows must be a 1-D array of copy indices (ints in [0, {self.n})), got {rows!r}")
        a = a.astype(int)
        if a.size and (a.min() < 0 or a.max() >= self.n or np.unique(a).size != a.size):
            raise InputError(f"rows must be distinct copy indices in [0, {self.n}), got {a.tolist()}")
        return a

    def _plan_row(self, i: int, rng: np.random.Generator) -> np.ndarray:
        """Copy i's episode plan sampled at every actuation tick (the reference mode's controller reads it there, the
        observation at the control ticks); returns its initial configuration q0."""
        plan = plan_episode(self.kind, self.platform, rng, self.settings.geometry, self.settings.mission)
        t = np.arange(self.ticks * self.steps + 1) * self.settings.actuation_period
        sample = mission_sample(plan.trajectory, t, self.platform.n_xi)
        self.ref_xi[i], self.ref_xi_dot[i], self.ref_xi_ddot[i] = sample.xi, sample.xi_dot, sample.xi_ddot
        if plan.goals:
            goals = ee_positions(self.platform, self.data, np.array(plan.goals))
            self.ee_goal[i] = goals[[0, -1]]
        else:
            self.ee_plan[i] = ee_positions(self.platform, self.data, sample.xi[:: self.steps])
        self.trajectories[i] = plan.trajectory
        return ch.xi_to_q(plan.xi0)

    def _apply_draws(self, rows: np.ndarray) -> None:
        """The drawn plant of ``rows``: mass scale and payload (per-copy models only when they change), wind, lag, noise."""
        draws = [self.draws[i] for i in rows.tolist()]
        if self.kind is TaskKind.CARRY:  # the carried payload: drawn as model.payload, else CARRY_MASS_FRACTION x the mass
            default = CARRY_MASS_FRACTION * self.platform.total_mass
            self.carried[rows] = [d.payload if self.randomization.has("model.payload") else default for d in draws]
        scale = np.array([d.mass_scale for d in draws])
        changed = scale != self.sim.mass_scale[rows]
        if changed.any():
            self.sim.set_mass_scale(scale[changed], rows[changed])
        payload = np.array([0.0 if self.kind is TaskKind.CARRY else d.payload for d in draws])  # Carry: attached when picked
        changed = payload != self.sim.payload_mass[rows]
        if changed.any():
            self.sim.set_payload(payload[changed], rows[changed])
        self.wind_mean[rows] = [d.mean_wind_world for d in draws]
        self.gust_peak[rows] = [d.gust_peak_world for d in draws]
        self.gust_start[rows] = [d.gust_start for d in draws]
        self.drag[rows] = [d.drag for d in draws]
        self.noise[rows] = [d.sensor_noise for d in draws]
        self.lag_end[rows], self.lag_mean[rows] = lag_factors(np.array([d.tau for d in draws]), self.settings.actuation_period)

    def _hover_thrusts(self, q: np.ndarray) -> np.ndarray:
        """Thrusts (m, n_rotors) [N] holding each configuration still: Omega^+ g(q)[0:6] clipped (the lag's start)."""
        model, data = self.platform.model, self.data
        g = np.array([pin.computeGeneralizedGravity(model, data, row)[0:6] for row in q])
        return np.clip(np.einsum("ij,kj->ik", g, self.Omega_pinv), self.f_min, self.f_max)

    # ---------------------------------------------------------------------------------------------------- step
    def step(self, actions, frozen: np.ndarray, rngs: list[np.random.Generator]) -> tuple:
        """One control period of every copy but the ``frozen`` ones (module docstring); ``rngs`` one generator per copy.

        Returns (observations (n, size) float32, rewards (n,), terminated (n,), truncated (n,), info: dict of (n,) arrays).
        """
        a = np.clip(check_actions(actions, (self.n, self.action_size), "actions"), -1.0, 1.0)  # Gymnasium's Box: clipped
        frozen = np.asarray(frozen)
        if frozen.shape != (self.n,) or frozen.dtype != bool:
            raise InputError(f"frozen must be a boolean array of shape ({self.n},) (one flag per copy), got {frozen!r}")
        _check_rngs(rngs, self.n)
        live = ~frozen
        rows = np.flatnonzero(live)
        failed = np.zeros(self.n, dtype=bool)
        for j in range(self.settings.actuation_steps):
            if j:  # the reference mode's controller runs faster than the actions: a new measurement
                self._measure(rows, [rngs[i] for i in rows.tolist()])
            failed |= self._actuate(a, live, j)
        self.tick[live] += 1
        p_ee = self._ee_positions(self.sim.q)
        picked = self._attach(p_ee, live)
        self._measure(rows, [rngs[i] for i in rows.tolist()])
        reward, end, info = self._judge(a, p_ee, picked, failed, live)
        end = np.where(live, end, EndReason.RUNNING.value)
        terminated = live & (end != EndReason.RUNNING.value) & (end != EndReason.TIME_LIMIT.value)
        truncated = live & (end == EndReason.TIME_LIMIT.value)
        info["success"] &= truncated
        info["end"] = end
        self.obs[live] = self._observe()[live]
        return self.obs.copy(), np.where(live, reward, 0.0), terminated, truncated, info

    def _actuate(self, a: np.ndarray, live: np.ndarray, j: int) -> np.ndarray:
        """The ``j``-th actuation period after the control tick: commands, rotor lag, tau held while the plant
        integrates; returns the copies whose controller failed."""
        f_cmd, effort, failed = self.actions.commands(a, self._tick_context(live, j), self.thrust)
        f_cmd = np.where(live[:, None], f_cmd, self.thrust)
        f_mean = f_cmd + (self.thrust - f_cmd) * self.lag_mean[:, None]
        self.thrust = np.where(live[:, None], f_cmd + (self.thrust - f_cmd) * self.lag_end[:, None], self.thrust)
        tau = _generalized_force(self.N, f_mean, effort)
        self.actions.set_applied(tau, live)  # the model-free controller reads it
        self._integrate(tau, live, j * self.settings.actuation_period)
        return failed

    def _integrate(self, tau: np.ndarray, live: np.ndarray, s: float) -> None:
        """Hold ``tau`` over the actuation period from ``s`` [s] after the tick (the wind's drag at every stage); frozen
        copies keep their state."""
        frozen = np.flatnonzero(~live)
        q_keep, v_keep = self.sim.q[frozen].copy(), self.sim.v[frozen].copy()
        force = None
        if self.randomization.has("drag"):
            t_mid = self.tick * self.period + s + 0.5 * self.settings.actuation_period
            wind = wind_world(self.wind_mean, self.gust_peak, self.gust_start, GUST_LENGTH * self.duration, t_mid)
            drag = self.drag

            def force(q, v):
                return drag_force(q, v, wind, drag)

        self.sim.step(tau, steps=self.settings.substeps, force=force)
        if frozen.size:
            self.sim.reset(q_keep, v_keep, frozen)

    def _attach(self, p_ee: np.ndarray, live: np.ndarray) -> np.ndarray:
        """Carry: the live copies whose end effector reached the payload (past the plan's start) pick it; returns them."""
        if self.kind is not TaskKind.CARRY:
            return np.zeros(self.n, dtype=bool)
        near = np.linalg.norm(p_ee - self.ee_goal[:, 0], axis=1) < ATTACH_RADIUS
        picked = live & ~self.attached & near
        if picked.any():
            masses = np.array([self.carried[i] for i in np.flatnonzero(picked).tolist()])
            self.sim.set_payload(masses, np.flatnonzero(picked))
            self.attached |= picked
        return picked

    # ----------------------------------------------------------------------------------- measure, observe, judge
    def _measure(self, rows: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """The measured state of ``rows``: q (+) sigma n_q, v + sigma n_v with n ~ N(0, I), one draw of 2 nv per copy
        whose randomisation has ``sensor_noise`` (none otherwise)."""
        rows = np.asarray(rows, dtype=int)
        self.q_meas[rows], self.v_meas[rows] = self.sim.q[rows], self.sim.v[rows]
        if not self.randomization.has("sensor_noise") or rows.size == 0:
            return
        nv = self.platform.nv
        n = np.array([rng.standard_normal(2 * nv) for rng in rngs]) * self.noise[rows, None]
        self.q_meas[rows] = integrate(self.sim.q[rows], n[:, 0:nv])
        self.v_meas[rows] = self.sim.v[rows] + n[:, nv:]

    def _plan(self, j: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The plan (xi_d, xi_dot_d, xi_ddot_d), each (n, n_xi), at the ``j``-th actuation tick after each copy's control tick."""
        rows, k = np.arange(self.n), self.tick * self.steps + j
        return self.ref_xi[rows, k], self.ref_xi_dot[rows, k], self.ref_xi_ddot[rows, k]

    def _tick_context(self, live: np.ndarray, j: int = 0) -> Tick:
        """What the action maps see at the ``j``-th actuation tick after the control tick: the measured state and the
        plan there (sampled exactly: a reference held or extrapolated between the control ticks made the IDC's
        roll and pitch references (6.17) jump every period, which destabilised borinot_flying_arm_2 on Track)."""
        xi, xi_dot, xi_ddot = self._plan(j)
        return Tick(self.tick * self.period + j * self.settings.actuation_period, self.q_meas, self.v_meas, xi, xi_dot, xi_ddot, live)

    def _ee_positions(self, q: np.ndarray) -> np.ndarray:
        """End-effector positions (n, 3) [m], world frame (NaN for a non-finite state)."""
        out = np.full((self.n, 3), np.nan)
        finite = np.all(np.isfinite(q), axis=1)
        model, data, frame = self.platform.model, self.data, self.platform.ee_frame
        for i in np.flatnonzero(finite).tolist():  # frame_position without its checks: the simulator's own states
            pin.forwardKinematics(model, data, q[i])
            out[i] = pin.updateFramePlacement(model, data, frame).translation
        return out

    def _ee_target(self) -> np.ndarray:
        """The task's end-effector target (n, 3) [m], world frame (module docstring of :mod:`qprr.envs.tasks`)."""
        if self.kind is TaskKind.REACH:
            return self.ee_goal[:, 0]
        if self.kind is TaskKind.CARRY:
            return np.where(self.attached[:, None], self.ee_goal[:, 1], self.ee_goal[:, 0])
        return self.ee_plan[np.arange(self.n), self.tick]

    def _observe(self) -> np.ndarray:
        """Observations (n, size) of every copy from its measured state (:mod:`qprr.envs.observation`)."""
        q, v = self.q_meas, self.v_meas
        xi_d, xi_dot_d, _ = self._plan()
        R = rotation_rows(q[:, 3:7])
        p_ee = self._ee_positions(q) if self.randomization.has("sensor_noise") else self._ee_positions(self.sim.q)
        span = self.f_max - self.f_min
        parts = {
            "base_error_world": xi_d[:, 0:3] - q[:, 0:3],
            "rotation_world_body": R,
            "v_body": v[:, 0:3],
            "omega_body": v[:, 3:6],
            "q_arm": q[:, 7:],
            "q_arm_dot": v[:, 6:],
            "ee_error_world": self._ee_target() - p_ee,
            "yaw_error": wrap(xi_d[:, 5] - np.arctan2(R[:, 3], R[:, 0]))[:, None],
            "v_ref_world": xi_dot_d[:, 0:3],
            "thrust": 2.0 * (self.thrust - self.f_min) / np.where(span > 0.0, span, 1.0) - 1.0,
            "attached": self.attached[:, None].astype(float),
        }
        return self.layout.build(parts)

    def _judge(self, a: np.ndarray, p_ee: np.ndarray, picked: np.ndarray, failed: np.ndarray, live: np.ndarray) -> tuple:
        """(reward (n,), end reason (n,) str, info) of every copy at its new state (true, not measured)."""
        k, q, v, s = self.tick, self.sim.q, self.sim.v, self.settings
        xi_d = self._plan()[0]
        cap = 2.0 * s.box
        e_base = _capped(np.linalg.norm(xi_d[:, 0:3] - q[:, 0:3], axis=1), cap)
        e_ee = _capped(np.linalg.norm(self._ee_target() - p_ee, axis=1), cap)
        R = rotation_rows(q[:, 3:7])
        e_yaw = np.abs(wrap(xi_d[:, 5] - np.arctan2(R[:, 3], R[:, 0])))
        e_yaw = np.where(np.isfinite(e_yaw), e_yaw, math.pi)
        rate = _capped(np.linalg.norm(v[:, 3:6], axis=1), cap)
        end = np.full(self.n, EndReason.RUNNING.value, dtype=object)
        end[k >= self.ticks] = EndReason.TIME_LIMIT.value
        end[failed] = EndReason.CONTROLLER.value
        end[R[:, 8] < math.cos(s.max_tilt)] = EndReason.TILTED.value
        end[e_base > s.box] = EndReason.LEFT_BOX.value
        end[self.sim.diverged()] = EndReason.DIVERGED.value
        crashed = (end != EndReason.RUNNING.value) & (end != EndReason.TIME_LIMIT.value)
        w = self.spec.weights
        reward = w.alive - w.base * e_base - w.ee * e_ee - w.yaw * e_yaw - w.rate * rate - w.action * np.mean(a * a, axis=1)
        reward = reward + w.pickup * picked - w.crash * crashed
        success = self._success(e_base, e_ee, live)
        info = {"t": k * self.period, "base_error": e_base, "ee_error": e_ee, "attached": self.attached.copy(), "success": success}
        return reward, end.astype(str), info

    def _success(self, e_base: np.ndarray, e_ee: np.ndarray, live: np.ndarray) -> np.ndarray:
        """Update the success trackers of the ``live`` copies with this step's errors; True where the criterion holds."""
        spec = self.spec
        if spec.success is Success.MEAN_BASE:
            self.error_sum += np.where(live, e_base, 0.0)
            return self.error_sum / np.maximum(self.tick, 1) < spec.tolerance
        ok = {
            Success.BASE_WINDOW: e_base < spec.tolerance,
            Success.EE_WINDOW: e_ee < spec.tolerance,
            Success.CARRY_WINDOW: self.attached & (e_ee < spec.tolerance),
        }[spec.success]
        self.inside_time = np.where(live, np.where(ok, self.inside_time + self.period, 0.0), self.inside_time)
        return self.inside_time >= spec.window - 1e-9


def check_actions(actions, shape: tuple[int, ...], name: str) -> np.ndarray:
    """``actions`` as a float array of ``shape`` with finite entries, else a qprr error naming ``name``, the value and the
    fix.  Entries beyond [-1, 1] pass (the environment clips them, as Gymnasium's Box bounds say); NaN and inf do not: they
    would fly the plant on a NaN thrust."""
    a = as_array(actions, name)
    if a.shape != shape:
        rows = " (one row per environment)" if len(shape) == 2 else ""
        raise ShapeError(f"{name} must have shape {shape}{rows}, values in [-1, 1] (docs/rl.md, action modes), got shape {a.shape}")
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        first = tuple(bad[0].tolist())
        raise NonFiniteError(
            f"{name} must be finite, got {name}[{', '.join(map(str, first))}] = {float(a[first])!r} ({len(bad)} non-finite entries of "
            f"{a.size}): check the policy's output (a diverged network gives NaN); values in [-1, 1]"
        )
    return a


def _check_rngs(rngs, n: int) -> None:
    """``rngs``: a list of ``n`` numpy Generators (one per copy stepped or reset)."""
    if not isinstance(rngs, (list, tuple)) or len(rngs) != n:
        raise InputError(f"rngs must be a list of {n} numpy.random.Generator (one per copy), got {rngs!r}")
    for j, rng in enumerate(rngs):
        check_rng(rng, f"rngs[{j}]")


def _generalized_force(N: np.ndarray, f: np.ndarray, effort: np.ndarray) -> np.ndarray:
    """tau = N [f; effort] (n, nv), Thesis (5.43), as :meth:`qprr.sim.batch.BatchSimulator.tau_from_thrusts` computes it
    but row by row (``einsum``): BLAS's matrix product sums in an order that depends on the batch size, and a copy of a
    batch must compute exactly what a batch of one does (the vector and the scalar environments agree bit for bit)."""
    return np.einsum("ij,kj->ik", np.concatenate([f, effort], axis=1), N)


def _capped(x: np.ndarray, cap: float) -> np.ndarray:
    """``x`` with non-finite entries and entries beyond ``cap`` set to ``cap`` (a crash's reward stays bounded)."""
    return np.minimum(np.where(np.isfinite(x), x, cap), cap)


def _action_map(settings: EnvSettings, platform, n: int):
    """The action map of ``settings.action_mode`` (:mod:`qprr.envs.actions`)."""
    if settings.action_mode is ActionMode.THRUSTS:
        return ThrustMap(platform, n)
    if settings.action_mode is ActionMode.WRENCH:
        return WrenchMap(platform, n)
    return ReferenceMap(platform, n, settings.controller, settings.actuation_period, settings.residual)


__all__ = ["BatchCore", "EndReason", "check_actions"]
