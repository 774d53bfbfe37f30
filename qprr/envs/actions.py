"""From an action in [-1, 1]^m to rotor thrust commands and arm efforts, one map per :class:`ActionMode`.

Each map turns a batch of actions (n, m) into thrust commands f_c (n, n_rotors) [N] and arm efforts (n, n_arm)
[N m or N], for the copies marked live (the others keep their last command); the environment then lags the thrusts
(:func:`qprr.envs.randomize.lag_factors`) and applies tau = N [f; effort] (Thesis (5.43)).

* :class:`ThrustMap` (``thrusts``): f_c,i = f_min,i + (a_i + 1) / 2 (f_max,i - f_min,i), effort_j = a_j e_j with e_j the
  joint's effort limit; m = n_rotors + n_arm.
* :class:`WrenchMap` (``wrench``): the body wrench [f_B; tau_B] (at B, body axes) = w_hover + a s on the rows the
  rotors produce (coplanar rotors: f_z and the three torques; a tilted hexarotor: all six), w_hover = (0, 0, m g, 0,
  0, 0), s = m g on f_z, m g / 2 on f_x and f_y, the torque authority around hover on the torques
  (:attr:`qprr.control.gains.Authority.torque`); then f_c = clip(Omega^+ w, f_min, f_max), least squares through the
  pseudo-inverse of the rotor matrix Omega clipped to the bounds, vectorised (not the prioritised QP of
  :class:`qprr.actuation.Allocator`: clipping can change the wrench's direction when a bound is hit); efforts as
  above; m = rows + n_arm.
* :class:`ReferenceMap` (``reference``): residual learning.  The task's reference xi_d(t) plus the action's offsets,
  dx, dy, dz = a_0..2 r_p [m] (world), dpsi = a_3 r_psi [rad], dq_j = a_(4+j) r_q (range_j / 2) (clipped to the joint
  limits), is tracked by one qprr controller per copy (gains derived from the platform, :mod:`qprr.control.gains`,
  for the control period), allocated by one :class:`qprr.actuation.Allocator` per copy as :func:`qprr.sim.simulate`
  does; m = 4 + n_arm.  A zero action flies the classical controller on the task's plan (the baselines,
  :mod:`qprr.envs.baseline`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..actuation import Allocator
from ..charts import State
from ..control import CONTROLLERS, OPTIONAL, make_controller
from ..control.base import Reference
from ..control.gains import Authority, Targets, platform_gains
from ..errors import InputError, MissingDependencyError, QprrError
from ..model import Platform, check_platform
from ..validation import as_int, as_name, as_real, as_vector
from .settings import REFERENCE_CONTROLLERS


@dataclass
class Tick:
    """What a control tick hands the action maps (n copies): ``t`` (n,) each copy's episode time [s]; ``q``, ``v``
    (n, nq), (n, nv) the measured state (Pinocchio's; the sensor noise included); ``xi_d``, ``xi_dot_d``,
    ``xi_ddot_d`` (n, n_xi) the plan's reference at t (thesis coordinates); ``live`` (n,) the copies that step."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    xi_d: np.ndarray
    xi_dot_d: np.ndarray
    xi_ddot_d: np.ndarray
    live: np.ndarray


def effort_limits(platform: Platform) -> np.ndarray:
    """The arm's effort limits (n_arm,) [N m or N]: the full scale of an effort action (finite, checked)."""
    check_platform(platform)
    limits = np.array(platform.arm_effort_limits, dtype=float)
    bad = [platform.arm_names[j] for j in range(platform.n_arm) if not (math.isfinite(limits[j]) and limits[j] > 0.0)]
    if bad:
        raise InputError(
            f"platform {platform.name!r}: the arm joints {bad} have no finite effort limit, which the thrusts and wrench "
            "action modes map the actions to: give them an effort limit in the URDF (<limit effort=...>) or use action_mode='reference'"
        )
    return limits


class _OpenLoop:
    """What the maps without a controller share: nothing to start at a reset, no applied force to read."""

    def reset(self, rows: np.ndarray, tick: Tick, trajectories: list) -> None:
        """Start the copies ``rows`` on a new episode (nothing to do without a controller)."""

    def set_applied(self, tau: np.ndarray, live: np.ndarray) -> None:
        """The applied generalised force (n, nv) (no controller reads it)."""


class ThrustMap(_OpenLoop):
    """``thrusts`` (module docstring)."""

    def __init__(self, platform: Platform, n: int) -> None:
        _check_map_arguments(platform, n)
        self.platform, self.n_rotors = platform, platform.n_rotors
        self.size = platform.n_rotors + platform.n_arm
        self.f_min, self.f_max = np.array(platform.thrust_min), np.array(platform.thrust_max)
        self.limits = effort_limits(platform)

    def commands(self, actions: np.ndarray, tick: Tick, f_last: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f_c (n, n_rotors) [N], efforts (n, n_arm), failed (n,) all False)."""
        nr = self.n_rotors
        f = self.f_min + 0.5 * (actions[:, 0:nr] + 1.0) * (self.f_max - self.f_min)
        effort = actions[:, nr:] * self.limits
        return f, effort, np.zeros(actions.shape[0], dtype=bool)


class WrenchMap(_OpenLoop):
    """``wrench`` (module docstring): ``rows`` the body-wrench rows the rotors produce, ``hover`` (6,) and ``scale`` (6,)
    the wrench at a zero action and per unit action."""

    def __init__(self, platform: Platform, n: int) -> None:
        _check_map_arguments(platform, n)
        Omega = np.array(platform.rotor_matrix)
        self.platform, self.limits = platform, effort_limits(platform)
        self.rows = [i for i in range(6) if np.abs(Omega[i]).max() > 1e-12]
        self.size = len(self.rows) + platform.n_arm
        self.Omega_pinv = np.linalg.pinv(Omega)
        self.f_min, self.f_max = np.array(platform.thrust_min), np.array(platform.thrust_max)
        authority = Authority.from_platform(platform)
        weight = authority.mass * platform.g
        self.hover = np.array([0.0, 0.0, weight, 0.0, 0.0, 0.0])
        self.scale = np.array([0.5 * weight, 0.5 * weight, weight, *authority.torque])

    def commands(self, actions: np.ndarray, tick: Tick, f_last: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f_c (n, n_rotors) [N], efforts (n, n_arm), failed (n,) all False)."""
        k = len(self.rows)
        wrench = np.tile(self.hover, (actions.shape[0], 1))
        wrench[:, self.rows] += actions[:, 0:k] * self.scale[self.rows]
        f = np.clip(np.einsum("ij,kj->ik", wrench, self.Omega_pinv), self.f_min, self.f_max)  # row by row (core.py)
        return f, actions[:, k:] * self.limits, np.zeros(actions.shape[0], dtype=bool)


class ReferenceMap:
    """``reference`` (module docstring): one ``controller`` (a name of :data:`qprr.envs.settings.REFERENCE_CONTROLLERS`)
    per copy, its gains derived once for the control ``period`` [s]; ``residual`` = (r_p [m], r_psi [rad], r_q)."""

    def __init__(self, platform: Platform, n: int, controller: str, period: float, residual: tuple[float, float, float]) -> None:
        _check_map_arguments(platform, n)
        kwargs = controller_arguments(controller, platform, period)
        self.platform, self.period = platform, period
        self.size = 4 + platform.n_arm
        residual = as_vector(residual, 3, "residual")
        if (residual < 0.0).any():
            raise InputError(f"residual must be full scales >= 0 (position m, yaw rad, arm fraction), got {residual.tolist()}")
        self.residual = tuple(residual.tolist())
        half_range = 0.5 * (platform.arm_upper - platform.arm_lower)
        self.arm_scale = residual[2] * np.where(np.isfinite(half_range), half_range, math.pi)
        self.controllers = [make_controller(controller, platform, **kwargs) for _ in range(n)]
        self.allocators = [Allocator(platform) for _ in range(n)]
        self.states = [State(platform.n_arm) for _ in range(n)]
        self.refs = [Reference(n_xi=platform.n_xi) for _ in range(n)]
        self.nr = platform.n_rotors

    def reference(self, actions: np.ndarray, tick: Tick) -> np.ndarray:
        """xi_d + the offsets (n, n_xi), the arm clipped to its limits (module docstring)."""
        xi = tick.xi_d.copy()
        xi[:, 0:3] += actions[:, 0:3] * self.residual[0]
        xi[:, 5] += actions[:, 3] * self.residual[1]
        xi[:, 6:] = np.clip(xi[:, 6:] + actions[:, 4:] * self.arm_scale, self.platform.arm_lower, self.platform.arm_upper)
        return xi

    def reset(self, rows: np.ndarray, tick: Tick, trajectories: list) -> None:
        """Start the controllers of ``rows`` on their new episode (state, reference, preview of the plan) with new
        allocators (an allocator warm-starts its QPs from its last call)."""
        for i in rows.tolist():
            controller, state, ref = self.controllers[i], self.states[i], self.refs[i]
            self.allocators[i] = Allocator(self.platform)  # no warm start from the last episode: results depend on it alone
            state.update(0.0, tick.q[i].copy(), tick.v[i].copy())
            _fill(ref, tick.xi_d[i], tick.xi_dot_d[i], tick.xi_ddot_d[i])
            if controller.uses_preview:  # a planning controller (MPC) previews the plan
                controller.set_preview(trajectories[i])
            controller.reset(state, ref, self.period)

    def commands(self, actions: np.ndarray, tick: Tick, f_last: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f_c (n, n_rotors) [N], efforts (n, n_arm), failed (n,)): each live copy's controller and allocation.

        A copy whose controller or allocation raises a qprr error (the Euler singularity, a non-finite demand) keeps
        its last thrusts, no effort, and is marked failed (its episode terminates).  This loop over the copies is the
        slowest part of the reference mode at large n: a vectorised inverse-dynamics controller (RNEA over the batch
        and (6.17)-(6.24) on arrays) and a vectorised allocation would remove it."""
        xi_ref = self.reference(actions, tick)
        n = actions.shape[0]
        f, effort = f_last.copy(), np.zeros((n, self.platform.n_arm))
        failed = np.zeros(n, dtype=bool)
        out = np.empty(self.platform.n_actuators)
        for i in np.flatnonzero(tick.live).tolist():
            try:
                self._command(i, float(tick.t[i]), tick, xi_ref[i], out)
            except QprrError:
                failed[i] = True
                continue
            f[i], effort[i] = out[0 : self.nr], out[self.nr :]
        return f, effort, failed

    def _command(self, i: int, t: float, tick: Tick, xi_ref: np.ndarray, out: np.ndarray) -> None:
        """Controller i on its measured state and reference, allocated into ``out`` (thrusts, efforts)."""
        controller, state, ref = self.controllers[i], self.states[i], self.refs[i]
        state.update(t, tick.q[i].copy(), tick.v[i].copy())
        _fill(ref, xi_ref, tick.xi_dot_d[i], tick.xi_ddot_d[i])
        u = controller.step(t, state, ref)
        tau_d = np.array(u, dtype=float) if controller.output == "pinocchio" else state.force_from_xi(u)
        if self.allocators[i].allocate_screened_into(tau_d, out) < 0:
            raise InputError(f"controller {controller.name!r} asked for a non-finite or absurd force at t = {t:.3f} s")

    def set_applied(self, tau: np.ndarray, live: np.ndarray) -> None:
        """Hand the applied generalised force (n, nv) to the controllers that read it (the model-free controller)."""
        for i in np.flatnonzero(live).tolist():
            if self.controllers[i].uses_applied_force:
                self.states[i].set_applied(tau[i].copy())


def controller_arguments(controller: str, platform: Platform, period: float) -> dict[str, object]:
    """Constructor arguments of ``controller`` for a controller period ``period`` [s]: the platform-derived gains
    (:func:`qprr.control.gains.platform_gains` with ``Targets(control_period=period)``: the MFC's estimator runs
    at it; ``integral=False``: the inverse-dynamics controllers fly their PD gains, whose steady errors under an
    unknown mass are what the residual policies of docs/rl.md learn to cancel, and an integral state would outlive
    the policy's offsets across steps; ``payload=0.0``: the tasks carry nothing at the end effector, so the
    roll/pitch filter keeps the class's bandwidth, that of the committed experiments); none for the MPC, which
    solves at its own rate (:class:`qprr.control.mpc.MPCSettings`, 100 Hz) and holds its input in between (the
    period must divide 1 / rate: the default 5 ms does); a controller whose optional dependency is missing raises
    :class:`~qprr.errors.MissingDependencyError` with its install command."""
    as_name(controller, "controller", REFERENCE_CONTROLLERS, "controller of the reference action mode")
    if controller not in CONTROLLERS:
        raise MissingDependencyError(*OPTIONAL[controller])
    check_platform(platform)
    period = as_real(period, "period", positive=True, unit="s")
    return {} if controller == "mpc" else platform_gains(controller, platform, Targets(control_period=period, integral=False, payload=0.0))


def _check_map_arguments(platform, n) -> None:
    """The arguments every action map takes: a Platform and a number of copies >= 1."""
    check_platform(platform)
    as_int(n, "n", lo=1)


def _fill(ref: Reference, xi, xi_dot, xi_ddot) -> None:
    """Copy a reference row into ``ref``'s own arrays (controllers write roll and pitch into them)."""
    ref.xi[:] = xi
    ref.xi_dot[:] = xi_dot
    ref.xi_ddot[:] = xi_ddot


__all__ = ["ReferenceMap", "ThrustMap", "Tick", "WrenchMap", "controller_arguments", "effort_limits"]
