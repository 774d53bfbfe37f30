"""Scenarios of Thesis Sec. 6.4: payload release, pushing with the thrust or the slider, impedance control.

Each scenario is ``fn(controller=None, progress=False, **options) -> SimResult`` (fixed seed,
fixed step 1 ms) and leaves its own logs in ``result.info``; ``PLOTS[name](result, path)``
draws the thesis-like figure (attitude, joints, forces, torques, interaction) into a PNG.

* ``payload-drop`` (Sec. 6.4.2.3): the static mission (climb to 10 m in 0-5 s, x to 3 m in
  5-10 s, y to 6 m in 10-15 s) carrying 0.1 kg at the end effector, arm manipulation from
  t = 15 s, release at t = 18 s.  ``info["recovery"]`` (:class:`Recovery`) gives the time
  to return to the no-payload hover.
* ``push-thrust`` (Sec. 6.4.3.1): arm locked with links 2-3 horizontal, the base flies 0.5 m
  along x and pushes a 0.5 kg object on a frictionless line (:class:`qprr.interaction.PushedMass`).
* ``push-prismatic`` (Sec. 6.4.3.2): hovering, the slider goes from r0 = -0.04 m to +0.04 m and
  pushes a 0.2 kg object on a line with Coulomb friction 0.3.
* ``impedance`` (Sec. 6.4.3.4): h_b = [0.2, 0, 0, 0] on the base and h_q = [0.05, 0.01, 0.05] N
  on the end effector from t = 0 to 18 s, impedance controller (6.74)-(6.81).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import model as qm
from .actuation import rotor_matrix
from .coordinates import as_vector
from .errors import UnknownNameError
from .interaction import PrescribedWrench, PushedMass
from .sim import PayloadChange, PayloadSchedule, Pulse, SimResult, simulate
from .trajectory import Hold, MultiPhase, Phase

SEED = 0
DT = 1e-3


# ============================================================================ helpers
def _robot():
    return qm.load()


def _make_controller(name: str, valid: tuple[str, ...], builders: dict[str, Callable[[], object]]):
    if name not in valid:
        raise UnknownNameError("controller", name, valid)
    return builders[name]()


def _ee_world(robot, xi) -> np.ndarray:
    p, _ = qm.ee_pose_xi(robot, robot.data(), xi)
    return p


@dataclass(frozen=True)
class Recovery:
    """Time to return to the no-payload hover after a release.

    ``time`` [s] after ``release_time``: from then on every |p_d - p| <= ``tol_position``
    (x, y, z and r0, m), every |q_d - q| <= ``tol_angle`` (theta2, theta3, psi, rad) and the
    total thrust is within ``tol_thrust`` (relative) of the no-payload weight m g / (c_phi c_theta).
    ``status`` "recovered" or "not recovered" (within the run); ``peak_*`` the largest
    deviations after the release.
    """

    release_time: float
    time: float
    tol_position: float
    tol_angle: float
    tol_thrust: float
    peak_position: float
    peak_angle: float
    peak_thrust: float
    status: str
    reason: str


def recovery(result: SimResult, release_time: float, total_mass: float, g: float, *, tol_position: float = 1e-3,
             tol_angle: float = 1e-3, tol_thrust: float = 0.01) -> Recovery:
    """Measure :class:`Recovery` on a logged run (no-payload weight ``total_mass`` g)."""
    t = result.t
    after = t >= release_time
    e = np.abs(result.xi_d - result.xi)
    pos = e[:, [0, 1, 2, 6]].max(axis=1)
    ang = e[:, [5, 7, 8]].max(axis=1)
    tilt = np.cos(result.xi[:, 3]) * np.cos(result.xi[:, 4])
    thrust = np.abs(result.f.sum(axis=1) * tilt / (total_mass * g) - 1.0)
    ok = (pos <= tol_position) & (ang <= tol_angle) & (thrust <= tol_thrust)
    idx = np.nonzero(after)[0]
    bad = idx[~ok[idx]]
    peaks = (float(pos[after].max()), float(ang[after].max()), float(thrust[after].max()))
    if bad.size == 0:
        return Recovery(release_time, 0.0, tol_position, tol_angle, tol_thrust, *peaks, "recovered", "within tolerance at the release")
    last = bad[-1]
    if last == idx[-1]:
        return Recovery(release_time, math.inf, tol_position, tol_angle, tol_thrust, *peaks, "not recovered",
                        f"still out of tolerance at the end of the run (t = {t[last]:.3f} s)")
    return Recovery(release_time, float(t[last + 1] - release_time), tol_position, tol_angle, tol_thrust, *peaks, "recovered",
                    "every tolerance holds from then to the end of the run")


def applied_generalized_forces(result: SimResult) -> np.ndarray:
    """u = S^T N f (n, 9) actually applied (thesis coordinates): u_fb world thrust, u_tau Euler torques, arm efforts.

    u_fb = R_b [0, 0, sum f_i] (Thesis (6.17)'s u_fb), u_tau = T^T tau_body (Thesis (5.41) corrected)."""
    robot = _robot()
    w = result.f @ rotor_matrix(robot).T  # (n, 6) body wrench at B
    phi, theta, psi = result.xi[:, 3], result.xi[:, 4], result.xi[:, 5]
    sf, cf, st, ct, sp, cp = np.sin(phi), np.cos(phi), np.sin(theta), np.cos(theta), np.sin(psi), np.cos(psi)
    fz = w[:, 2]
    out = np.zeros((result.n, 9))
    out[:, 0] = (cp * st * cf + sp * sf) * fz
    out[:, 1] = (sp * st * cf - cp * sf) * fz
    out[:, 2] = ct * cf * fz
    tx, ty, tz = w[:, 3], w[:, 4], w[:, 5]
    # T = [[1, 0, -s_theta], [0, c_phi, s_phi c_theta], [0, -s_phi, c_phi c_theta]] (omega_body = T euler_dot)
    out[:, 3] = tx
    out[:, 4] = cf * ty - sf * tz
    out[:, 5] = -st * tx + sf * ct * ty + cf * ct * tz
    out[:, 6:9] = result.arm_effort
    return out


# ============================================================================ payload-drop
PAYLOAD_CONTROLLERS = ("payload-idc", "payload-idc-known", "payload-idc-none", "idc")


def payload_drop(controller: str | None = None, progress: bool = False, *, mass: float = 0.1, release_time: float = 18.0,
                 duration: float = 25.0, mission: str = "thesis", arm_target=(-0.04, 0.3, 0.5),
                 arm_phase=(15.0, 17.0), noise: float = 0.0, seed: int = SEED) -> SimResult:
    """Carry ``mass`` at the end effector and release it at ``release_time`` (Thesis Sec. 6.4.2.3).

    ``mission="thesis"``: climb/x/y flight of Sec. 6.3.1.4 to (3, 6, 10) m, arm to ``arm_target``
    during ``arm_phase``; ``mission="hover"``: start hovering at (0, 0, 1) m with the arm already
    at ``arm_target`` (short runs for tests).  Controllers: "payload-idc" (mass estimated,
    default), "payload-idc-known" (known mass, told of the release), "payload-idc-none",
    "idc" (Sec. 6.3.1, nominal model).  ``noise`` > 0 adds the white noise of Thesis (6.27),
    uniform in [-noise, noise] N, on the three forces (seeded by ``seed``).
    """
    from .control.idc import InverseDynamicsController
    from .control.payload_idc import PayloadIDC
    from .sim import WhiteNoise

    robot = _robot()
    name = controller or "payload-idc"
    missions = ("thesis", "hover")
    if mission not in missions:
        raise UnknownNameError("mission", mission, missions)
    r0, t2, t3 = robot.check_arm_limits(arm_target, "arm_target")
    if mission == "thesis":
        phases = (Phase("z", 0.0, 5.0, 10.0), Phase("x", 5.0, 10.0, 3.0), Phase("y", 10.0, 15.0, 6.0))
        phases += tuple(Phase(c, *arm_phase, v) for c, v in (("r0", r0), ("theta2", t2), ("theta3", t3)) if v != 0.0)
        trajectory = MultiPhase(phases, name="payload-drop")
    else:
        trajectory = Hold((0.0, 0.0, 1.0, 0.0, 0.0, 0.0, r0, t2, t3))

    class _Told(PayloadIDC):
        def step(self, t, state, ref):
            if t >= release_time:
                self.set_known_mass(0.0)
            return super().step(t, state, ref)

    ctrl = _make_controller(name, PAYLOAD_CONTROLLERS, {
        "payload-idc": lambda: PayloadIDC(robot, payload="estimate"),
        "payload-idc-known": lambda: _Told(robot, payload="known", known_mass=mass),
        "payload-idc-none": lambda: PayloadIDC(robot, payload="none"),
        "idc": lambda: InverseDynamicsController(robot),
    })
    schedule = PayloadSchedule((PayloadChange(0.0, mass), PayloadChange(release_time, 0.0)))
    disturbance = WhiteNoise(noise, components=(0, 1, 2)) if noise > 0.0 else None
    res = simulate(robot, ctrl, trajectory, duration, dt=DT, payload=schedule, disturbance=disturbance, seed=seed,
                   progress=progress, scenario="payload-drop")
    res.info["payload_mass"] = np.where(res.t < release_time, mass, 0.0)
    if getattr(ctrl, "mode", None) == "estimate":
        res.info["mass_estimate"] = np.asarray(ctrl.mass_log)
        window = min(1.0, 0.5 * release_time)  # the last second before the release (half the carry time if shorter)
        before = (res.t >= release_time - window) & (res.t < release_time)
        res.info["mass_estimate_error"] = float(np.max(np.abs(res.info["mass_estimate"][before] - mass))) if before.any() else math.nan
    res.info["release_time"] = release_time
    res.info["recovery"] = recovery(res, release_time, robot.params.total_mass, robot.params.g)
    return res


# ============================================================================ pushing
ARM_PUSH = (0.0, math.pi / 2, 0.0)
"""Links 2 and 3 horizontal along x_B: the last segment parallel to the pushing direction (Sec. 6.4.3.1)."""

PUSH_CONTROLLERS = ("layered-idc-ft", "layered-idc", "idc")
SENSOR_FILTER = 50.0
"""Bandwidth [rad/s] of the first-order filter on the wrist-sensor reading (see :class:`LayeredIDC`)."""


def _push_controller(name: str, robot, contact):
    """"layered-idc-ft": layered IDC cancelling the contact wrench its wrist sensor read at the previous step
    ((6.76)), filtered at :data:`SENSOR_FILTER`; "layered-idc": the same without force feedback (the arm
    buckles under the compressive contact force); "idc": Sec. 6.3.1's controller."""
    from .control.idc import InverseDynamicsController
    from .control.payload_idc import LayeredIDC

    return _make_controller(name, PUSH_CONTROLLERS, {
        "layered-idc-ft": lambda: LayeredIDC(robot, ee_sensor=contact.measured, sensor_filter=SENSOR_FILTER),
        "layered-idc": lambda: LayeredIDC(robot),
        "idc": lambda: InverseDynamicsController(robot),
    })


def push_thrust(controller: str | None = None, progress: bool = False, *, distance: float = 0.5, push=(2.0, 7.0),
                duration: float = 12.0, object_mass: float = 0.5, friction: float = 0.3, stiffness: float = 500.0,
                damping: float = 20.0, seed: int = SEED) -> SimResult:
    """Push an object along x with the thrust, arm locked (Thesis Sec. 6.4.3.1).

    The Q-PRR hovers at (0, 0, 1) m with the arm at :data:`ARM_PUSH`, its end effector
    touching the object's face; x_d goes 0 -> ``distance`` during ``push`` ((6.16), septic law).
    The object (``object_mass`` kg, Coulomb ``friction`` on its line) is pushed through a
    compliant contact (``stiffness`` N/m, ``damping`` N s/m).  The thesis assumes a
    frictionless line (``friction=0``): the object then only resists its acceleration
    (0.06 N peak here) and slides on when the robot decelerates, the contact opening.
    """
    robot = _robot()
    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, *ARM_PUSH])
    trajectory = MultiPhase((Phase("x", push[0], push[1], distance),), tuple(xi0), name="push-thrust")
    obj = PushedMass(robot, mass=object_mass, origin=_ee_world(robot, xi0), stiffness=stiffness, damping=damping, friction=friction)
    ctrl = _push_controller(controller or PUSH_CONTROLLERS[0], robot, obj)
    res = simulate(robot, ctrl, trajectory, duration, dt=DT, external_wrench=obj, seed=seed, progress=progress, scenario="push-thrust")
    res.info["contact"] = obj.history()
    res.info["object_mass"] = object_mass
    return res


def push_prismatic(controller: str | None = None, progress: bool = False, *, push=(2.0, 7.0), duration: float = 10.0,
                   object_mass: float = 0.2, friction: float = 0.3, stiffness: float = 500.0, damping: float = 20.0,
                   seed: int = SEED) -> SimResult:
    """Push an object with the slider from r0 = -0.04 m to +0.04 m while the rotors hold the pose (Thesis Sec. 6.4.3.2)."""
    robot = _robot()
    lo, hi = robot.params.r0_limits
    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, lo, ARM_PUSH[1], ARM_PUSH[2]])
    trajectory = MultiPhase((Phase("r0", push[0], push[1], hi),), tuple(xi0), name="push-prismatic")
    obj = PushedMass(robot, mass=object_mass, origin=_ee_world(robot, xi0), stiffness=stiffness, damping=damping, friction=friction)
    ctrl = _push_controller(controller or PUSH_CONTROLLERS[0], robot, obj)
    res = simulate(robot, ctrl, trajectory, duration, dt=DT, external_wrench=obj, seed=seed, progress=progress, scenario="push-prismatic")
    res.info["contact"] = obj.history()
    res.info["object_mass"] = object_mass
    return res


# ============================================================================ impedance
IMPEDANCE_CONTROLLERS = ("impedance", "impedance-table-6.7", "idc")


def impedance(controller: str | None = None, progress: bool = False, *, h_b=(0.2, 0.0, 0.0, 0.0), h_q=(0.05, 0.01, 0.05),
              t_on: float = 0.0, t_off: float = 18.0, duration: float = 25.0, arm=ARM_PUSH, impedance_gains=None,
              seed: int = SEED) -> SimResult:
    """Interaction forces from ``t_on`` to ``t_off`` on a hovering Q-PRR under impedance control (Thesis Sec. 6.4.3.4).

    ``h_b`` = generalised force on [x, y, z, psi] of the base (N, N, N, N m), applied as the
    disturbance (6.28) pulse; ``h_q`` = force on the end effector [N, world axes] (the moments
    are neglected, as the thesis states), applied through the end-effector wrench hook.  The
    controller measures both exactly.  Controllers: "impedance" (default gains), "impedance-
    table-6.7" (printed impedance gains: the slider reference saturates), "idc" (no compliance).
    """
    from .control.idc import InverseDynamicsController
    from .control.impedance import ImpedanceController, ImpedanceGains

    robot = _robot()
    hb = as_vector(h_b, 4, "h_b").copy()
    hq = np.concatenate([as_vector(h_q, 3, "h_q"), np.zeros(3)])
    ee = PrescribedWrench(hq, t_on, t_off)

    def base_sensor(t: float) -> np.ndarray:
        return hb if t_on <= t < t_off else np.zeros(4)

    gamma = np.zeros(9)
    gamma[[0, 1, 2, 5]] = hb
    pulse = Pulse(t_on, t_off, tuple(gamma))
    xi0 = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0, *arm)
    name = controller or "impedance"
    ctrl = _make_controller(name, IMPEDANCE_CONTROLLERS, {
        "impedance": lambda: ImpedanceController(robot, impedance=impedance_gains, ee_sensor=ee.measured, base_sensor=base_sensor),
        "impedance-table-6.7": lambda: ImpedanceController(robot, impedance=ImpedanceGains.table_6_7(), ee_sensor=ee.measured,
                                                           base_sensor=base_sensor),
        "idc": lambda: InverseDynamicsController(robot),
    })
    res = simulate(robot, ctrl, Hold(xi0), duration, dt=DT, external_wrench=ee, disturbance=pulse, seed=seed,
                   progress=progress, scenario="impedance")
    wrench = np.array([ee.measured(t) for t in res.t])
    res.info["ee_wrench"] = wrench
    res.info["t_off"] = t_off
    res.info["base_wrench"] = np.array([base_sensor(t) for t in res.t])
    if hasattr(ctrl, "history"):
        h = ctrl.history()
        res.info["impedance"] = h
        res.info["impedance_gains"] = ctrl.impedance
        res.info["saturated_steps"] = ctrl.saturated_steps
    return res


def impedance_steady_state(result: SimResult, at: float) -> dict[str, np.ndarray]:
    """Deflection of the measured state from the unperturbed reference at time ``at`` vs the filter's K^-1 h.

    Returns ``measured`` ([x, y, z, psi, r0, theta2, theta3] - their constant set points),
    ``filter`` (the impedance filters' Delta at that step: what the inner loop tracks) and
    ``predicted`` = [K_base^-1 h_b, K_arm^-1 u_e,mu] from the logged wrench (:class:`ImpedanceGains`).
    """
    k = int(np.searchsorted(result.t, at))
    k = min(k, result.n - 1)
    gains = result.info["impedance_gains"]
    h = result.info["impedance"]
    u_e = h["u_e"][k]
    hb = result.info["base_wrench"][k]
    predicted = np.concatenate([hb / np.asarray(gains.K_base), u_e[6:9] / np.asarray(gains.K_arm)])
    set_point = result.xi[0]  # the run starts at rest on its set point
    idx = [0, 1, 2, 5, 6, 7, 8]
    filt = np.concatenate([h["delta_eta"][k], h["delta_q"][k]])
    return {"measured": result.xi[k, idx] - set_point[idx], "filter": filt, "predicted": predicted, "t": result.t[k]}


SCENARIOS: dict[str, Callable[..., SimResult]] = {
    "payload-drop": payload_drop,
    "push-thrust": push_thrust,
    "push-prismatic": push_prismatic,
    "impedance": impedance,
}
"""Scenario name -> ``fn(controller=None, progress=False, **options) -> SimResult``."""

CONTROLLERS: dict[str, tuple[str, ...]] = {
    "payload-drop": PAYLOAD_CONTROLLERS,
    "push-thrust": PUSH_CONTROLLERS,
    "push-prismatic": PUSH_CONTROLLERS,
    "impedance": IMPEDANCE_CONTROLLERS,
}
"""Scenario name -> valid controller names (the first is the default)."""


# ============================================================================ figures
_LABELS = ("x", "y", "z", r"$\phi$", r"$\theta$", r"$\psi$", r"$r_0$", r"$\theta_2$", r"$\theta_3$")


def _figure(result: SimResult, path, extra_title: str, extra: Callable) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    u = applied_generalized_forces(result)
    t = result.t
    fig, ax = plt.subplots(3, 2, figsize=(11, 9), sharex=True)
    for i, c in zip((3, 4, 5), ("C0", "C1", "C2")):
        ax[0, 0].plot(t, result.xi[:, i], c, lw=1.2, label=_LABELS[i])
        ax[0, 0].plot(t, result.xi_d[:, i], c + "--", lw=0.8)
    ax[0, 0].set_title("attitude (solid measured, dashed desired) [rad]")
    for i, c in zip((6, 7, 8), ("C0", "C1", "C2")):
        ax[0, 1].plot(t, result.xi[:, i], c, lw=1.2, label=_LABELS[i])
        ax[0, 1].plot(t, result.xi_d[:, i], c + "--", lw=0.8)
    ax[0, 1].set_title("arm joints [m, rad]")
    for i, n in zip(range(3), (r"$u_{f_b,x}$", r"$u_{f_b,y}$", r"$u_{f_b,z}$")):
        ax[1, 0].plot(t, u[:, i], lw=1.0, label=n)
    ax[1, 0].set_title("thrust force, world axes [N]")
    for i, n in zip(range(3, 6), (r"$u_{\tau_\phi}$", r"$u_{\tau_\theta}$", r"$u_{\tau_\psi}$")):
        ax[1, 1].plot(t, u[:, i], lw=1.0, label=n)
    ax[1, 1].set_title("attitude torques [N m]")
    for i, n in zip(range(6, 9), (r"$u_{\mu,r_0}$ [N]", r"$u_{\mu,\theta_2}$ [N m]", r"$u_{\mu,\theta_3}$ [N m]")):
        ax[2, 0].plot(t, u[:, i], lw=1.0, label=n)
    ax[2, 0].set_title("slider force and joint torques")
    extra(ax, t)
    ax[2, 1].set_title(extra_title)
    for a in ax.flat:
        a.grid(alpha=0.3)
        a.legend(fontsize=7, loc="best")
    ax[2, 0].set_xlabel("t [s]")
    ax[2, 1].set_xlabel("t [s]")
    fig.suptitle(f"{result.scenario} / {result.controller}")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def plot_payload_drop(result: SimResult, path) -> Path:
    """Attitude, joints, forces, torques and the payload mass (true and estimated) of ``payload-drop``."""
    def extra(ax, t):
        ax[2, 1].plot(t, result.info["payload_mass"], "k", lw=1.2, label="carried mass")
        if "mass_estimate" in result.info:
            ax[2, 1].plot(t, result.info["mass_estimate"], "C3", lw=1.0, label="estimate")
        e = result.xi_d - result.xi
        ax2 = ax[2, 1].twinx()
        ax2.plot(t, np.linalg.norm(e[:, 0:3], axis=1), "C0", lw=0.8, label="|p_d - p| [m]")
        ax2.set_yscale("log")
        ax2.legend(fontsize=7, loc="center right")
        for a in ax.flat:
            a.axvline(result.info["release_time"], color="k", lw=0.6, ls=":")

    return _figure(result, path, "payload mass [kg] (release dotted)", extra)


def plot_push(result: SimResult, path) -> Path:
    """Attitude, joints, forces, torques and the contact force / object motion of a push scenario."""
    c = result.info["contact"]

    def extra(ax, t):
        ax[2, 1].plot(c.t, c.force, "C3", lw=1.2, label="contact force [N]")
        ax[1, 0].plot(c.t, c.wrench[:, 0], "k--", lw=1.0, label="interaction $h_x$ [N]")
        ax2 = ax[2, 1].twinx()
        ax2.plot(c.t, c.position, "C0", lw=1.0, label="object position [m]")
        ax2.legend(fontsize=7, loc="center right")

    return _figure(result, path, "object: contact force and position", extra)


def plot_impedance(result: SimResult, path) -> Path:
    """Attitude, joints, forces, torques and the impedance deflections of the ``impedance`` scenario."""
    def extra(ax, t):
        w = result.info["ee_wrench"]
        hb = result.info["base_wrench"]
        ax[1, 0].plot(t, w[:, 0] + hb[:, 0], "k--", lw=1.0, label="interaction x [N]")
        set_point = result.xi[0]
        ax[2, 1].plot(t, result.xi[:, 0] - set_point[0], "C0", lw=1.2, label="x - x_d [m]")
        ax[2, 1].plot(t, result.xi[:, 6] - set_point[6], "C1", lw=1.2, label="r0 - r0_d [m]")
        ax[2, 1].plot(t, result.xi[:, 7] - set_point[7], "C2", lw=1.2, label=r"$\theta_2 - \theta_{2d}$ [rad]")
        if "impedance" in result.info:
            h = result.info["impedance"]
            ax[2, 1].plot(h["t"], h["delta_eta"][:, 0], "C0:", lw=1.0, label="filter $\\Delta x$")
            ax[2, 1].plot(h["t"], h["delta_q"][:, 0], "C1:", lw=1.0, label="filter $\\Delta r_0$")
            ax[2, 1].plot(h["t"], h["delta_q"][:, 1], "C2:", lw=1.0, label="filter $\\Delta\\theta_2$")

    return _figure(result, path, "compliant deflections (dotted: impedance filter)", extra)


PLOTS: dict[str, Callable[[SimResult, object], Path]] = {
    "payload-drop": plot_payload_drop,
    "push-thrust": plot_push,
    "push-prismatic": plot_push,
    "impedance": plot_impedance,
}
"""Scenario name -> ``plot_fn(result, path)`` writing one PNG."""


# ============================================================================ command line
def summary(result: SimResult) -> list[str]:
    """The numbers a scenario reports, one per line."""
    lines = [f"{result.scenario} / {result.controller}: {result.n} steps, wall time {result.wall_time:.2f} s, status {result.status}"]
    info = result.info
    if "recovery" in info:
        r = info["recovery"]
        lines.append(f"recovery after release at {r.release_time:g} s: {r.time:.3f} s ({r.status}; |p_d - p| <= {r.tol_position:g} m, "
                     f"|q_d - q| <= {r.tol_angle:g} rad, thrust within {100 * r.tol_thrust:g} % of m g); peaks after release: "
                     f"position {r.peak_position:.4f} m, angle {r.peak_angle:.4f} rad, thrust {100 * r.peak_thrust:.2f} %")
    if "mass_estimate_error" in info:
        lines.append(f"mass estimate: max |m_hat - m| over the last second before the release = {info['mass_estimate_error']:.3e} kg")
    if "contact" in info:
        c = info["contact"]
        lines.append(f"contact force: max {c.force.max():.3f} N, min {c.force.min():.3f} N; object moved {c.position[-1] - c.position[0]:.4f} m")
    if "impedance" in info:
        d = impedance_steady_state(result, min(result.t[-1], info["t_off"] - result.dt))
        names = ("x", "y", "z", "psi", "r0", "theta2", "theta3")
        parts = [f"{n} {m:+.5f} (filter {f:+.5f}, h/K {p:+.5f})" for n, m, f, p in zip(names, d["measured"], d["filter"], d["predicted"])
                 if abs(p) > 0 or abs(m) > 1e-6]
        lines.append(f"deflection at t = {d['t']:.3f} s: " + ", ".join(parts))
        lines.append(f"arm reference saturated on {info['saturated_steps']} steps")
    return lines
