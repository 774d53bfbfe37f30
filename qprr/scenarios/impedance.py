"""The generic ``ee-impedance`` scenario: an end effector under operational-space impedance touches its environment.

Any platform hovers at (0, 0, ``z``) with its arm ``reach_fraction`` of the way from the
neutral posture to the upper joint limits, under :class:`~qprr.control.opspace_impedance.OperationalSpaceImpedance`
(Thesis (6.72)-(6.73); a wrist sensor reads the contact force at the control ticks).

* ``contact="wall"``: a :class:`~qprr.sim.contact.CompliantWall` faces the end effector ``gap``
  ahead along world x; the reference moves the base by ``gap + penetration`` (so the
  end-effector reference ends ``penetration`` inside the wall) between ``t_on`` and ``t_on + 2`` s,
  holds, and retreats between ``t_off`` and ``t_off + 2`` s.  In contact the impedance and the wall
  are two springs in series: the end effector stops where K_d (p_r - p_e) = k_wall delta.
* ``contact="wrench"``: a :class:`~qprr.sim.contact.PrescribedWrench` pushes the end effector with
  ``force`` [N] (world x, y, z) from ``t_on`` to ``t_off`` while the reference holds: the
  end effector steps by K_d^-1 h with the impedance's natural frequency and damping.

The result carries the controller's history (``ee_position``, ``ee_reference``, ``ee_error``,
``ee_force``, ``ee_ideal`` = the ideal impedance response to the measured force, and the
stiffness, damping and mass matrices); :func:`plot_ee_impedance` draws it and
:func:`ee_impedance_summary` reports the steady-state deflection against K_d^-1 h.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..control import InverseDynamicsController
from ..control.opspace_impedance import EndEffectorImpedance, OperationalSpaceImpedance, fit_second_order
from ..errors import InputError, UnknownNameError
from ..kinematics import ee_pose_xi
from ..sim import SimConfig, SimInputs, SimResult, simulate
from ..sim.contact import CompliantWall, PrescribedWrench
from ..trajectory import Hold, MultiPhase, Phase
from ..validation import as_vector

CONTROLLERS = ("opspace-impedance", "idc")
"""Controllers of the scenario: the operational-space impedance with a wrist sensor, the plain IDC (no compliance law)."""

CONTACTS = ("wall", "wrench")
OPTION_NAMES = (
    "contact", "duration", "dt", "integrator", "seed", "z", "reach_fraction", "omega_n", "zeta", "mass", "gap", "penetration",
    "wall_stiffness", "wall_damping", "force", "t_on", "t_off",
)  # fmt: skip
"""The options :func:`run_ee_impedance` reads (their defaults: the scenario's Option table in :mod:`qprr.scenarios`)."""


def run_ee_impedance(platform=None, controller: str = "opspace-impedance", progress: bool = False, **o) -> SimResult:
    """Run the scenario (module docstring); ``o``: every option of :data:`qprr.scenarios.SCENARIOS` ``["ee-impedance"]``
    (their one home; ``qprr.scenarios.run("ee-impedance", ...)`` fills the defaults)."""
    from ..platforms import load

    missing = sorted(set(OPTION_NAMES) - set(o))
    if missing:
        raise InputError(f"ee-impedance needs every option, missing {missing}: run it as qprr.scenarios.run('ee-impedance', ...)")
    _check_options(controller, o)
    platform = load() if platform is None else platform
    q0 = platform.neutral_q()[7:]
    hi = np.where(np.isfinite(platform.arm_upper), platform.arm_upper, q0 + 1.0)
    q_arm = q0 + o["reach_fraction"] * (hi - q0)
    xi0 = np.concatenate([[0.0, 0.0, float(o["z"]), 0.0, 0.0, 0.0], q_arm])
    env, trajectory = _environment(platform, xi0, o)
    imp = EndEffectorImpedance.from_frequency(o["omega_n"], o["zeta"], o["mass"])
    if controller == "opspace-impedance":
        ctrl = OperationalSpaceImpedance(platform, imp, ee_sensor=env.measured)
    else:
        ctrl = InverseDynamicsController(platform)
    config = SimConfig(dt=o["dt"], integrator=o["integrator"], seed=o["seed"], progress=progress, scenario="ee-impedance")
    res = simulate(platform, ctrl, trajectory, o["duration"], config=config, inputs=SimInputs(external_wrench=env))
    _record(res, platform, env, ctrl, imp)
    res.metrics.update({"t_on": float(o["t_on"]), "t_off": float(o["t_off"]), "contact_wall": float(o["contact"] == "wall")})
    return res


def _check_options(controller: str, o: dict) -> None:
    if o["contact"] not in CONTACTS:
        raise UnknownNameError("contact", o["contact"], CONTACTS)
    if controller not in CONTROLLERS:
        raise UnknownNameError("controller", controller, CONTROLLERS)
    fraction = o["reach_fraction"]
    if not (isinstance(fraction, (int, float)) and 0.0 <= fraction <= 1.0):
        raise InputError(f"reach_fraction must be in [0, 1], got {fraction!r}")
    t_on, t_off, duration = o["t_on"], o["t_off"], o["duration"]
    if not (0.0 <= t_on < t_off <= duration):
        raise InputError(f"need 0 <= t_on < t_off <= duration, got {t_on!r}, {t_off!r}, {duration!r}")


def _environment(platform, xi0: np.ndarray, o: dict):
    """(the contact: a compliant wall ``gap`` ahead of the end effector or a prescribed wrench, the reference)."""
    t_on, t_off, duration = o["t_on"], o["t_off"], o["duration"]
    if o["contact"] != "wall":
        h = np.concatenate([as_vector(o["force"], 3, "force"), np.zeros(3)])
        return PrescribedWrench(h, t_on, t_off), Hold(tuple(xi0))
    gap, penetration = o["gap"], o["penetration"]
    if not (gap >= 0.0 and penetration > 0.0):
        raise InputError(f"need gap >= 0 and penetration > 0 m, got {gap!r}, {penetration!r}")
    p_e0, _ = ee_pose_xi(platform, platform.data(), xi0)
    env = CompliantWall(
        platform, point=p_e0 + np.array([gap, 0.0, 0.0]), normal=(-1.0, 0.0, 0.0), stiffness=o["wall_stiffness"], damping=o["wall_damping"]
    )
    phases = (Phase("x", t_on, t_on + 2.0, gap + penetration), Phase("x", t_off, t_off + 2.0, 0.0))
    if t_off < t_on + 2.0 or t_off + 2.0 > duration:
        raise InputError(f"the wall scenario needs t_off >= t_on + 2 s and duration >= t_off + 2 s, got {t_on!r}, {t_off!r}, {duration!r}")
    return env, MultiPhase(phases, tuple(xi0), name="ee-impedance-wall")


def _record(res: SimResult, platform, env, ctrl, imp: EndEffectorImpedance) -> None:
    """The contact force, the end effector's position, reference and error, and the impedance, into ``res.series``."""
    s = res.series
    s["ee_force"] = _wrenches(env, res)[:, 0:3]
    if isinstance(ctrl, OperationalSpaceImpedance):
        hist = ctrl.history()
        s["ee_position"], s["ee_reference"], s["ee_error"] = hist["p_e"], hist["p_r"], hist["e"]
    else:
        s["ee_position"], s["ee_reference"] = _ee_positions(platform, res)
        s["ee_error"] = s["ee_position"] - s["ee_reference"]
    s["impedance_K"], s["impedance_D"] = imp.stiffness, imp.damping
    if imp.mass is not None:
        s["impedance_M"] = imp.mass
        s["ee_ideal"] = imp.response(res.t, s["ee_force"])[0]


def _wrenches(env, res: SimResult) -> np.ndarray:
    """The wrench the environment applied at each control tick (from its log; a prescribed one from its law)."""
    if isinstance(env, CompliantWall):
        return env.history().wrench
    return np.array([env.measured(t) for t in res.t])


def _ee_positions(platform, res: SimResult) -> tuple[np.ndarray, np.ndarray]:
    data = platform.data()
    pe = np.array([ee_pose_xi(platform, data, xi)[0] for xi in res.xi])
    pr = []
    for xi in res.xi_d:
        x = xi.copy()
        x[3:5] = 0.0  # the trajectory's roll and pitch (a hover mission: level)
        pr.append(ee_pose_xi(platform, data, x)[0])
    return pe, np.array(pr)


def steady_state(result: SimResult, at: float) -> dict[str, np.ndarray]:
    """End-effector deflection e = p_e - p_r at time ``at`` against K_d^-1 h of the force measured there."""
    s = result.series
    k = min(int(np.searchsorted(result.t, at)), result.n - 1)
    h = s["ee_force"][k]
    return {"t": result.t[k], "e": s["ee_error"][k], "h": h, "predicted": np.linalg.solve(s["impedance_K"], h)}


def ee_impedance_summary(result: SimResult) -> list[str]:
    """Steady-state deflection against K_d^-1 h just before the release; the step-response fit of a force step."""
    s, m = result.series, result.metrics
    d = steady_state(result, m["t_off"] - result.dt)
    lines = [
        f"at t = {d['t']:.3f} s: force {np.round(d['h'], 4).tolist()} N, deflection {np.round(1e3 * d['e'], 3).tolist()} mm, "
        f"K^-1 h = {np.round(1e3 * d['predicted'], 3).tolist()} mm"
    ]
    if "ee_ideal" in s:
        err = np.abs(s["ee_error"] - s["ee_ideal"]).max(axis=0)
        lines.append(f"max |e - e_ideal| (ideal impedance driven by the measured force): {np.round(1e3 * err, 3).tolist()} mm")
    if not m["contact_wall"] and "impedance_M" in s:
        h = s["ee_force"][np.searchsorted(result.t, m["t_on"])]
        i = int(np.argmax(np.abs(h)))
        k = (result.t >= m["t_on"]) & (result.t < m["t_off"])
        Mi = s["impedance_M"][i, i]
        w0, z0 = np.sqrt(s["impedance_K"][i, i] / Mi), s["impedance_D"][i, i] / (2.0 * np.sqrt(s["impedance_K"][i, i] * Mi))
        if z0 < 1.0:
            w, z, _ = fit_second_order(result.t[k] - result.t[k][0], s["ee_error"][k, i])
            lines.append(f"step response along {'xyz'[i]}: omega_n {w:.4f} rad/s (set {w0:.4f}), zeta {z:.4f} (set {z0:.4f})")
    return lines


def plot_ee_impedance(result: SimResult, path) -> Path:
    """End-effector error against the ideal impedance, contact force against the spring force, base, arm, thrusts, path."""
    from ..viz import figure_path, new_figure

    path = figure_path(path)
    s, t = result.series, result.t
    fig = new_figure((14, 8.5))
    ax = fig.subplots(2, 3)
    cols = ("C0", "C1", "C2")
    for i, c in enumerate(cols):
        ax[0, 0].plot(t, 1e3 * s["ee_error"][:, i], c, lw=1.3, label=f"$e_{'xyz'[i]}$")
        if "ee_ideal" in s:
            ax[0, 0].plot(t, 1e3 * s["ee_ideal"][:, i], c + "--", lw=1.0, label=f"ideal $e_{'xyz'[i]}$" if i == 0 else None)
    ax[0, 0].set_title("end-effector deflection $e = p_e - p_r$ [mm]\n(dashed: $M\\ddot e + D\\dot e + K e = h$, measured $h$)")
    K = s["impedance_K"]
    spring = s["ee_error"] @ K.T
    for i, c in enumerate(cols):
        ax[0, 1].plot(t, s["ee_force"][:, i], c, lw=1.3, label=f"$h_{'xyz'[i]}$")
        ax[0, 1].plot(t, spring[:, i], c + ":", lw=1.4, label=f"$(K e)_{'xyz'[i]}$")
    ax[0, 1].set_title("force on the end effector [N]\n(dotted: $K e$, equal to $h$ at rest)")
    for i, c in enumerate(cols):
        ax[0, 2].plot(t, s["ee_position"][:, i] - s["ee_position"][0, i], c, lw=1.3, label=f"$p_{{e,{'xyz'[i]}}}$")
        ax[0, 2].plot(t, s["ee_reference"][:, i] - s["ee_position"][0, i], c + "--", lw=1.0)
    ax[0, 2].set_title("end effector from its start [m]\n(dashed: reference)")
    for i, c in zip((0, 1, 2), cols):
        ax[1, 0].plot(t, result.xi[:, i] - result.xi[0, i], c, lw=1.2, label=result.names[i])
    for i, c in zip((3, 4, 5), ("C3", "C4", "C5")):
        ax[1, 0].plot(t, result.xi[:, i], c, lw=1.0, label=result.names[i])
    ax[1, 0].set_title("base: position from start [m],\nattitude [rad]")
    for k in range(6, result.xi.shape[1]):
        ax[1, 1].plot(t, result.xi[:, k], lw=1.2, label=result.names[k][-12:])
        ax[1, 1].plot(t, result.xi_d[:, k], "k:", lw=0.7)
    ax[1, 1].set_title("arm joints [m, rad]\n(dotted: posture reference)")
    ax[1, 2].plot(t, result.f[:, : result.f.shape[1]], lw=0.9)
    ax[1, 2].set_title("actuator efforts: rotor thrusts [N],\narm efforts [N, N m]")
    for a in ax.flat:
        a.grid(alpha=0.3)
        a.set_xlabel("t [s]")
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7, loc="best")
    for a in ax.flat:
        for x in (result.metrics["t_on"], result.metrics["t_off"]):
            a.axvline(x, color="k", lw=0.6, ls=":")
    law = " (Thesis (6.72)-(6.73))" if result.controller.startswith("opspace") else " (no impedance law; dashed: what it would do)"
    fig.suptitle(f"{result.scenario} on {result.platform}: {result.controller}{law}")
    fig.savefig(path, dpi=80)
    return path
