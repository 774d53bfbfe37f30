"""Runnable catalogue of the lecture: robots, exercises, control laws and mobile manipulation.

``run_demo(name)`` returns a :class:`Demo`: the text ``qprr wheeled NAME`` prints, and a function
that saves the figure (``--plot FILE.png``).  The catalogue is the single list the command
line, the docs figures and the tests iterate over.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import MissingDependencyError, UnknownNameError
from . import control as ctl
from . import plots
from .chassis import admissible_types
from .robots import (
    ROBOTS,
    TRICYCLE_CASES,
    TYPE_EXAMPLES,
    Car,
    Unicycle,
    bicycle_exercise,
    differential_drive,
    differential_drive_inverse,
    get_robot,
    icr_offset,
    tricycle_exercise,
)
from .sim import chord_slip, euler_step, rk4_step, simulate_wheeled


@dataclass
class Demo:
    """What one catalogue entry produced: ``lines`` to print, ``plot(path)`` to save its figure."""

    name: str
    lines: list[str]
    plot: Callable[[str | Path], Path]
    ok: bool = True


def _fmt(v) -> str:
    return "[" + ", ".join(f"{x:.4g}" for x in np.asarray(v, dtype=float)) + "]"


def _frobenius_lines(model) -> list[str]:
    from .liebracket import frobenius

    try:
        r = frobenius(model)
    except MissingDependencyError as exc:  # pragma: no cover - sympy missing: the line says how to install it
        return [f"Lie brackets: {exc}"]
    forms = "; ".join(str(list(f)) for f in r.integrable_forms) or "none"
    return [
        f"Lie brackets (Frobenius): dim of the distribution by bracket depth {list(r.growth)} of n = {r.n}: "
        f"{r.status.value} ({r.n_integrable} of {r.k} constraints integrable; integrable forms: {forms})"
    ]


# ============================================================================ robots
_PROGRAMS: dict[str, Callable[[float, np.ndarray], tuple]] = {
    "fixed-wheel": lambda t, q: (0.5, 0.4 * math.sin(0.5 * t)),
    "unicycle": lambda t, q: (0.5, 0.6 * math.sin(0.4 * t)),
    "tricycle-front": lambda t, q: (0.5, 0.4 * math.cos(0.5 * t)),
    "tricycle-rear": lambda t, q: (0.5, 0.4 * math.cos(0.5 * t)),
    "car": lambda t, q: (0.6, 0.25 * math.cos(0.5 * t)),
    "bicycle": lambda t, q: (2.0, 0.2 * math.cos(0.4 * t)),
    "omni": lambda t, q: (0.3 * math.cos(0.3 * t), 0.3 * math.sin(0.3 * t), 0.4),
    "mecanum": lambda t, q: (0.3 * math.cos(0.3 * t), 0.3 * math.sin(0.3 * t), 0.4),
    "synchro": lambda t, q: (0.5, 0.5 * math.sin(0.3 * t)),
}
"""Input programs of the robot demos (20 s): slaloms and loops within the steering limits."""


def _robot_demo(name: str) -> Demo:
    model = get_robot(name)
    q0 = np.zeros(model.n)
    res = simulate_wheeled(model, q0, _PROGRAMS[name], 20.0, 0.02)
    mob = model.robot.mobility()
    sig = np.full(model.robot.n_steering, 0.3)
    icr = model.robot.icr(sig)
    lines = [
        f"{model.name}: {model.description}  [Lecture: {model.lecture}]",
        f"q = {list(model.coordinates)}, u = {[f'{n} [{u}]' for n, u in zip(model.inputs, model.input_units)]}",
        f"degrees: delta_m = {mob.delta_m}, delta_s = {mob.delta_s}, delta_M = {mob.delta_M} -> {mob.status.value} "
        f"({mob.reason}); rank C1s = {mob.rank_C1s}",
        f"ICR at steering {sig.tolist() or 'none'}: {icr.status.value}"
        + (f" at {_fmt(icr.point_R)} m (robot frame)" if icr.point_R is not None else "")
        + (f", direction {_fmt(icr.direction)}" if icr.direction is not None else ""),
    ]
    lines += _frobenius_lines(model)
    lines.append(
        f"simulation, 20 s, input program of qprr.wheeled.demos: {res.status.value} ({res.reason}); "
        f"final q = {_fmt(res.q[-1])}; max |A^T q_dot| = {res.residual.max():.2e}"
    )
    if name == "unicycle":
        u = Unicycle()
        pd, pg = differential_drive_inverse(0.5, 0.3, u.r, u.L)
        lines.append(
            f"differential drive (slide convention): v = 0.5 m/s, omega = 0.3 rad/s <- phi_dot_d = {pd:.4g}, "
            f"phi_dot_g = {pg:.4g} rad/s; back: {differential_drive(pd, pg, u.r, u.L)}; rho = {icr_offset(pd, pg, u.L):.4g} m "
            f"(= v/omega = {0.5 / 0.3:.4g})"
        )
        lines += _integrator_lines()

    def plot(path):
        fig, ax = plots.figure(2, 2, size=(5.0, 4.0))
        plots.plot_path(ax[0, 0], res, model, n_robots=7)
        ax[0, 0].set_title(f"{model.name}: path (exact flow), robot every {res.t[-1] / 6:.3g} s", fontsize=9)
        k = len(res.t) // 2
        tw = model.body_twist(res.q[k], res.u[k])
        sig_k = res.q[k, 3 : 3 + model.robot.n_steering]
        plots.plot_icr(ax[0, 1], model.robot, sig_k, tw)
        ax[0, 1].set_title(f"ICR at t = {res.t[k]:.3g} s ({model.robot.icr(sig_k, tw).status.value})", fontsize=9)
        plots.plot_wheel_speeds(ax[1, 0], res)
        ax[1, 0].set_title("wheel spin rates from the rolling constraints", fontsize=9)
        plots.plot_residual(ax[1, 1], res)
        ax[1, 1].set_title("constraint residual |A^T(q) q_dot| along the run", fontsize=9)
        return plots.save(fig, path)

    return Demo(name, lines, plot)


def _integrator_lines() -> list[str]:
    m = Unicycle()
    dt, n = 0.05, 600
    q = {"exact": np.zeros(3), "rk4": np.zeros(3), "euler": np.zeros(3)}
    slip = dict.fromkeys(q, 0.0)
    for k in range(n):
        u = np.array([1.0, math.sin(k * dt)])
        for name, step in (
            ("exact", m.flow),
            ("rk4", lambda q_, u_, h: rk4_step(m, q_, u_, h)),
            ("euler", lambda q_, u_, h: euler_step(m, q_, u_, h)),
        ):
            nxt = step(q[name], u, dt)
            slip[name] = max(slip[name], abs(chord_slip(q[name], nxt)))
            q[name] = nxt
    return [
        f"integrators, unicycle, v = 1 m/s, omega = sin t, dt = {dt} s, {n * dt:g} s: max lateral slip per step "
        + ", ".join(f"{k} {v:.1e} m" for k, v in slip.items())
        + f"; final position error vs exact: rk4 {np.linalg.norm(q['rk4'][:2] - q['exact'][:2]):.1e} m, "
        f"euler {np.linalg.norm(q['euler'][:2] - q['exact'][:2]):.1e} m"
    ]


# ============================================================================ exercises
def _tricycle_demo() -> Demo:
    runs = {(d, c): tricycle_exercise(c, d) for d in ("rear", "front") for c in TRICYCLE_CASES}
    lines = [
        "Exercise (tricycle), point 3: q0 = [0, 0, pi/4, 0], D = 0.3 m, 30 s; "
        + ", ".join(f"{c}) u1 = {u[0]:g} m/s, u2 = {u[1]:.4g} rad/s" for c, u in TRICYCLE_CASES.items())
    ]
    for (d, c), r in runs.items():
        lines.append(
            f"  {d:5s}-driven, case {c}: {r.status.value:8s} t_end = {r.t[-1]:6.2f} s, q_end = {_fmt(r.q[-1])}"
            + ("" if r.status.value == "ok" else f"  <- {r.reason}")
        )
    lines.append(
        "Point 2: the rear-driven model B(q) (tan psi / D) is undefined at psi = +-pi/2: in case a the steering "
        "reaches pi/2 at t = 3 s and the motion cannot continue (theta_dot -> infinity); the front-driven model "
        "(sin psi / D) is valid everywhere.  In case c (u1 = 0) both robots stay in place while the wheel turns."
    )

    def plot(path):
        fig, ax = plots.figure(2, 3, size=(4.2, 3.8))
        models = {"rear": get_robot("tricycle-rear", D=0.3), "front": get_robot("tricycle-front", D=0.3)}
        for i, d in enumerate(("rear", "front")):
            for j, c in enumerate(TRICYCLE_CASES):
                r = runs[(d, c)]
                a = ax[i, j]
                plots.plot_path(a, r, models[d], n_robots=5 if c != "b" else 4)
                u = TRICYCLE_CASES[c]
                a.set_title(f"{d}-driven, case {c}: u1 = {u[0]:g} m/s, u2 = {u[1]:.3g} rad/s\n{r.status.value}, t_end = {r.t[-1]:.3g} s", fontsize=9)
        return plots.save(fig, path)

    return Demo("tricycle-exercise", lines, plot)


def _bicycle_demo() -> Demo:
    ex = bicycle_exercise()
    lines = ["Bicycles in the lecture's frame (front wheel alpha = 0, rear alpha = pi, ell = 0.5 m):"]
    for label, mob in (
        ("Example 2, both wheels fixed", ex.fixed),
        ("Exercise 1, front wheel steerable", ex.front_steered),
        ("Exercise 2, rear wheel steerable", ex.rear_steered),
    ):
        lines.append(f"  {label:36s} delta_m = {mob.delta_m}, delta_s = {mob.delta_s}, delta_M = {mob.delta_M}: {mob.reason}")
    lines.append(
        "Steering one wheel turns the fixed bicycle (delta_M = 1: it can only roll along its line) into a type "
        "(1, 1) robot like the tricycle and the car; steering the rear wheel gives the same degrees (delta_M = 2): "
        "the same manoeuvrability, harder to drive."
    )

    def plot(path):
        from .robots import _bicycle_lecture

        fig, ax = plots.figure(1, 3, size=(4.0, 4.0))
        for a, (f, r) in zip(ax[0], (("fixed", "fixed"), ("steerable", "fixed"), ("fixed", "steerable"))):
            robot = _bicycle_lecture(f, r)
            plots.plot_icr(a, robot, [0.35] if robot.n_steering else None, extent=2.0)
            a.set_title(f"{robot.name}\n{robot.mobility().reason}", fontsize=8)
        return plots.save(fig, path)

    return Demo("bicycle-exercise", lines, plot)


def _types_demo() -> Demo:
    adm = admissible_types()
    lines = [f"admissible (delta_m, delta_s) from the lecture's conditions a), b), c): {adm}"]
    for t, robot in TYPE_EXAMPLES.items():
        mob = robot.mobility()
        lines.append(
            f"  {robot.name:36s} wheels: {', '.join(w.kind.value for w in robot.wheels)} -> computed type "
            f"{mob.type} (lecture: {t}), delta_M = {mob.delta_M}"
        )

    def plot(path):
        fig, ax = plots.figure(1, 5, size=(3.4, 3.6))
        for a, robot in zip(ax[0], TYPE_EXAMPLES.values()):
            sig = np.array([0.5, -0.4][: robot.n_steering])
            plots.plot_icr(a, robot, sig, extent=1.2)
            a.set_title(f"computed type {robot.mobility().type}\n{robot.name}\nICR {robot.icr(sig).status.value}", fontsize=8)
        return plots.save(fig, path)

    return Demo("types", lines, plot)


def _ackermann_demo() -> Demo:
    car = Car()
    lines = [f"car: wheelbase D = {car.D} m, front track 2L = {2 * car.L} m; the lecture's relations for psi (virtual wheel):"]
    for psi in (0.1, 0.3, 0.55):
        pl, pr = car.front_angles(psi)
        pi_, po = (pl, pr) if psi > 0 else (pr, pl)
        icr = car.robot.icr([psi])
        lines.append(
            f"  psi = {psi:.2f}: psi_i = {pi_:.4f}, psi_o = {po:.4f}; cot psi_o - cot psi_i - 2L/D = "
            f"{1 / math.tan(po) - 1 / math.tan(pi_) - 2 * car.L / car.D:.1e}; cot psi - cot psi_i - L/D = "
            f"{1 / math.tan(psi) - 1 / math.tan(pi_) - car.L / car.D:.1e}; ICR {icr.status.value} at y_R = "
            f"{icr.point_R[1]:.4f} m = D cot psi = {car.D / math.tan(psi):.4f} m"
        )
    from .chassis import WheeledRobot

    parallel = WheeledRobot("parallel steering", car.robot.wheels)  # both front wheels at the same angle
    mob = parallel.mobility([0.3, 0.3])
    lines.append(f"both front wheels at 0.3 rad (no Ackermann): delta_m = {mob.delta_m}: {mob.reason}")

    def plot(path):
        fig, ax = plots.figure(1, 2, size=(5.0, 5.0))
        plots.plot_icr(ax[0, 0], car.robot, [0.35], extent=2.2)
        psi = 0.35
        R = car.D / math.tan(psi)
        ax[0, 0].plot([car.D, 0], [0, R], ls=":", color="tab:purple", lw=1.2, label="virtual wheel's axis")
        ax[0, 0].legend(fontsize=7, loc="lower left")
        ax[0, 0].set_title("Ackermann: every axis through one ICR\n(virtual central wheel dotted)", fontsize=9)
        plots.plot_icr(ax[0, 1], parallel, [0.35, 0.35], extent=2.2)
        ax[0, 1].set_title(f"parallel steering: no common point\n{mob.reason[:60]}", fontsize=9)
        return plots.save(fig, path)

    return Demo("ackermann", lines, plot)


def _brackets_demo() -> Demo:
    from .liebracket import WithWheelAngles, commutator_motion, frobenius

    lines = ["Frobenius test, generic rank of the distribution spanned by B and its Lie brackets:"]
    for name in ROBOTS:
        r = frobenius(get_robot(name))
        lines.append(
            f"  {name:16s} n = {r.n}, k = {r.k}, dims {list(r.growth)}: {r.status.value}"
            + (f", integrable: {'; '.join(str(list(f)) for f in r.integrable_forms)}" if r.integrable_forms else "")
        )
    for name in ("unicycle", "omni", "synchro"):
        r = frobenius(WithWheelAngles(get_robot(name)))
        lines.append(
            f"  {r.model:28s} n = {r.n}, k = {r.k}, dims {list(r.growth)}: {r.status.value}, integrable: "
            f"{'; '.join(str(list(f)) for f in r.integrable_forms)}"
        )
    cases = [(get_robot("unicycle"), np.zeros(3)), (get_robot("car"), np.zeros(4))]

    def plot(path):
        import sympy as sp

        from .liebracket import lie_bracket

        fig, ax = plots.figure(1, 2, size=(5.0, 4.2))
        for a, (m, q0) in zip(ax[0], cases):
            qs, _, B = m.symbolic()
            br = np.array(sp.lambdify(list(qs), lie_bracket(B[:, 0], B[:, 1], qs))(*q0), dtype=float).ravel()
            for eps, c in zip((0.4, 0.3, 0.2), ("tab:blue", "tab:orange", "tab:green")):
                pts = commutator_motion(m, q0, 0, 1, eps)
                legs = [
                    m.flow(pts[i], s * np.eye(2)[k], tau)
                    for i, (k, s) in enumerate(((0, 1), (1, 1), (0, -1), (1, -1)))
                    for tau in np.linspace(0, eps, 20)
                ]
                P = np.array(legs)
                a.plot(P[:, 0], P[:, 1], color=c, lw=1, label=f"eps = {eps}: net {_fmt((pts[-1] - q0)[:3] / eps**2)} / eps^2")
                a.plot(pts[-1, 0], pts[-1, 1], "o", color=c, ms=4)
                h = 0.06 * np.array([math.cos(pts[-1, 2]), math.sin(pts[-1, 2])])
                a.annotate(
                    "", xy=(pts[-1, 0] + h[0], pts[-1, 1] + h[1]), xytext=(pts[-1, 0], pts[-1, 1]), arrowprops={"arrowstyle": "->", "color": c}
                )
            a.annotate("", xy=(0.2 * br[0], 0.2 * br[1]), xytext=(0, 0), arrowprops={"arrowstyle": "->", "color": "k"})
            a.set_title(
                f"{m.name}: legs b1, b2, -b1, -b2 of eps s each (end: dot, heading arrow)\n"
                f"[b1, b2](0) = {_fmt(br)} (black arrow: its x, y part x 0.2)",
                fontsize=8,
            )
            a.set_aspect("equal", adjustable="datalim")
            a.legend(fontsize=6)
            a.grid(alpha=0.3)
        return plots.save(fig, path)

    return Demo("lie-brackets", lines, plot)


# ============================================================================ control
def _unicycle_tracking_demo() -> Demo:
    ref = ctl.Lemniscate()
    m = get_robot("unicycle")
    runs = {
        "Kanayama": simulate_wheeled(m, [0.5, -0.6, 0.4], ctl.KanayamaTracking(ref), 60.0, 0.01),
        "point offset b = 0.2 m": simulate_wheeled(m, [0.5, -0.6, 0.4], ctl.PointTracking(ref), 60.0, 0.01),
    }
    errs = {}
    for k, r in runs.items():
        off = 0.2 if "point" in k else 0.0
        P = r.q[:, :2] + off * np.column_stack([np.cos(r.q[:, 2]), np.sin(r.q[:, 2])])
        errs[k] = np.linalg.norm(P - np.array([ref.derivatives(t)[0] for t in r.t]), axis=1)
    lines = [f"unicycle on a figure-eight (a = {ref.a} m, w = {ref.w} rad/s), start 0.78 m off, 60 s, dt = 0.01 s:"]
    lines += [f"  {k:24s} position error: start {e[0]:.3f} m, max over the last 10 s {e[-1000:].max():.2e} m" for k, e in errs.items()]

    def plot(path):
        fig, ax = plots.figure(1, 2, size=(5.2, 4.2))
        P = np.array([ref.derivatives(t)[0] for t in np.linspace(0, 2 * math.pi / ref.w, 400)])
        ax[0, 0].plot(P[:, 0], P[:, 1], "k--", lw=0.8, label="reference")
        for (k, r), c in zip(runs.items(), ("tab:blue", "tab:orange")):
            plots.plot_path(ax[0, 0], r, m if c == "tab:blue" else None, n_robots=4, color=c, label=k)
            ax[0, 1].semilogy(r.t, np.maximum(errs[k], 1e-9), color=c, label=k)
        ax[0, 0].legend(fontsize=7)
        ax[0, 0].set_title("unicycle tracking a figure-eight", fontsize=9)
        ax[0, 1].set_xlabel("t [s]")
        ax[0, 1].set_ylabel("position error [m]")
        ax[0, 1].legend(fontsize=7)
        ax[0, 1].grid(alpha=0.3)
        ax[0, 1].set_title("tracking error (zero-order hold, dt = 0.01 s)", fontsize=9)
        return plots.save(fig, path)

    return Demo("unicycle-tracking", lines, plot)


def _unicycle_posture_demo() -> Demo:
    m = get_robot("unicycle")
    starts = [(-2.0, 1.5, 0.5), (-2.0, -1.0, -2.5), (1.5, 1.5, 3.0), (0.0, 1.0, 0.0)]
    runs = [simulate_wheeled(m, s, ctl.PosturePolar([0.0, 0.0, 0.0]), 30.0, 0.01) for s in starts]
    lines = ["posture regulation to (0, 0, 0) in polar coordinates (Aicardi et al. 1995), 30 s:"]
    lines += [f"  from {_fmt(s)}: final {_fmt(r.q[-1])}" for s, r in zip(starts, runs)]
    lines.append("(0, 1, 0): the goal straight to the side, the case no smooth static feedback can handle (Brockett)")

    def plot(path):
        fig, ax = plots.figure(1, 1, size=(6.0, 5.0))
        for r, c in zip(runs, ("tab:blue", "tab:orange", "tab:green", "tab:red")):
            plots.plot_path(ax[0, 0], r, m, n_robots=3, color=c, label=f"from {_fmt(r.q[0])}")
        ax[0, 0].legend(fontsize=7)
        ax[0, 0].set_title("unicycle posture regulation to (0, 0, 0)", fontsize=9)
        return plots.save(fig, path)

    return Demo("unicycle-posture", lines, plot)


def _car_tracking_demo() -> Demo:
    ref = ctl.Lemniscate(a=4.5, w=0.15)
    car = Car()
    r = simulate_wheeled(car, [0.3, -0.4, 0.6, 0.0], ctl.CarTracking(ref, car.D), 60.0, 0.01)
    e = np.linalg.norm(r.q[:, :2] - np.array([ref.derivatives(t)[0] for t in r.t]), axis=1)
    lines = [
        f"car (D = {car.D} m) on a figure-eight (a = {ref.a} m), dynamic feedback linearisation, poles at -1.5 1/s:",
        f"  {r.status.value}; position error start {e[0]:.3f} m, max over the last 10 s {e[-1000:].max():.2e} m; "
        f"max |psi| = {np.abs(r.q[:, 3]).max():.3f} rad (after 5 s: {np.abs(r.q[500:, 3]).max():.3f})",
    ]

    def plot(path):
        fig, ax = plots.figure(1, 2, size=(5.2, 4.2))
        P = np.array([ref.derivatives(t)[0] for t in np.linspace(0, 2 * math.pi / ref.w, 400)])
        ax[0, 0].plot(P[:, 0], P[:, 1], "k--", lw=0.8, label="reference")
        plots.plot_path(ax[0, 0], r, car, n_robots=6, label="car (rear-axle centre)")
        ax[0, 0].legend(fontsize=7)
        ax[0, 0].set_title("car tracking a figure-eight", fontsize=9)
        ax[0, 1].semilogy(r.t, np.maximum(e, 1e-9), label="position error [m]")
        ax[0, 1].plot(r.t, np.abs(r.q[:, 3]), label="|psi| [rad]")
        ax[0, 1].set_xlabel("t [s]")
        ax[0, 1].legend(fontsize=7)
        ax[0, 1].grid(alpha=0.3)
        return plots.save(fig, path)

    return Demo("car-tracking", lines, plot)


def _car_parking_demo() -> Demo:
    car = Car()
    goal = np.array([0.0, 1.0, 0.0, 0.0])
    pk = ctl.SinusoidalParking(goal, car.D)
    r = simulate_wheeled(car, [0.0, 0.0, 0.0, 0.0], pk, pk.duration, 0.01)
    lines = [
        f"parallel parking of the car 1 m to the left by sinusoids in chained form (3 phases of {pk.T:g} s), dt = 0.01 s:",
        f"  {r.status.value}; final q = {_fmt(r.q[-1])}, posture error {np.linalg.norm(r.q[-1] - goal):.1e}; "
        f"max |psi| = {np.abs(r.q[:, 3]).max():.3f} rad, max |theta| = {np.abs(r.q[:, 2]).max():.3f} rad",
    ]

    def plot(path):
        fig, ax = plots.figure(1, 2, size=(5.2, 4.2))
        plots.plot_path(ax[0, 0], r, car, n_robots=9)
        ax[0, 0].set_title("car: parallel parking by sinusoids (Murray-Sastry)", fontsize=9)
        plots.plot_states(ax[0, 1], r)
        for k in (1, 2):
            ax[0, 1].axvline(k * pk.T, color="k", lw=0.5, ls=":")
        still = int(np.sum([np.ptp(r.q[(r.t >= (k - 1) * pk.T) & (r.t <= k * pk.T)], axis=0).max() < 1e-12 for k in (1, 2, 3)]))
        note = f"\n(z1, z2, z3) start at their goal: phase{'s 1-2 move' if still > 1 else ' 1 moves'} nothing" if still else ""
        ax[0, 1].set_title("phases: (z1, z2) to goal | z3 | z4" + note, fontsize=9)
        return plots.save(fig, path)

    return Demo("car-parking", lines, plot)


# ============================================================================ manipulation
def _manipulation_demo(arm: str) -> Demo:
    from .manipulation import car_scenario, solve_ik

    sc = car_scenario(arm)
    res = {True: solve_ik(sc.robot, sc.target, sc.z0), False: solve_ik(sc.robot, sc.target, sc.z0, {"respect_constraint": False})}
    lines = [sc.description + f"; target {_fmt(sc.target)} m"]
    for k, r in res.items():
        lines.append(
            f"  {'Pfaffian imposed' if k else 'constraint ignored':18s}: {r.status.value} in {r.iterations} iterations "
            f"({r.reason}); base travel {r.base_travel:.3f} m; max |A^T dq| of the QP {r.qp_residual.max():.1e}, of the "
            f"applied motion {r.applied_residual.max():.1e}; total slip {r.slip:.3g} m; final z = {_fmt(r.z)}"
        )

    def plot(path):
        fig, ax = plots.figure(1, 2, size=(5.4, 4.6))
        a = ax[0, 0]
        robot = sc.robot.base.robot
        plots.draw_robot(a, robot, sc.z0[0:3], sc.z0[3:4], color="0.3", alpha=0.8)
        for (k, r), c in zip(res.items(), ("tab:blue", "tab:red")):
            P = r.path
            lab = "Pfaffian imposed" if k else "constraint ignored"
            a.plot(P[:, 0], P[:, 1], color=c, lw=1.5, label=f"{lab}: rear-axle centre (slip {r.slip:.2g} m)")
            E = np.array([sc.robot.ee_position(z) for z in P])
            a.plot(E[:, 0], E[:, 1], color=c, lw=0.8, ls="--", label=f"{lab}: end effector")
            plots.draw_robot(a, robot, P[-1, 0:3], P[-1, 3:4], color=c, alpha=0.9)
        a.plot(*sc.target[:2], "k*", ms=12, label="target (z = 0.5 m)")
        a.set_aspect("equal", adjustable="datalim")
        a.legend(fontsize=6, loc="lower right")
        a.grid(alpha=0.3)
        a.set_title(f"{sc.robot.model.name}: top view, start (grey) and final robots", fontsize=9)
        b = ax[0, 1]
        for (k, r), c in zip(res.items(), ("tab:blue", "tab:red")):
            lab = "imposed" if k else "ignored"
            b.semilogy(np.arange(len(r.ee_error)), np.maximum(r.ee_error, 1e-12), color=c, label=f"EE error [m], {lab}")
            b.semilogy(
                np.arange(1, len(r.applied_residual) + 1),
                np.maximum(r.applied_residual, 1e-18),
                color=c,
                ls=":",
                label=f"|A^T dq| of the base step [m], {lab}",
            )
        b.set_xlabel("IK iteration")
        b.legend(fontsize=6)
        b.grid(alpha=0.3)
        b.set_title("end-effector error and no-slip violation", fontsize=9)
        return plots.save(fig, path)

    return Demo(f"mobile-manipulation{'-3r' if arm == '3r' else ''}", lines, plot)


# ============================================================================ catalogue
EXERCISES: dict[str, tuple[str, Callable[[], Demo]]] = {
    "tricycle-exercise": ("Exercise (tricycle): q0 = [0, 0, pi/4, 0], D = 0.3 m, 30 s, cases a, b, c", _tricycle_demo),
    "bicycle-exercise": ("Exercise (steerable bicycle) and Example 2: degrees of mobility and steerability", _bicycle_demo),
    "types": ("the five admissible types (delta_m, delta_s), computed on three-wheel robots", _types_demo),
    "ackermann": ("Ackermann relation cot psi_o - cot psi_i = 2L/D, the virtual wheel and the unique ICR", _ackermann_demo),
    "lie-brackets": ("Frobenius test by Lie brackets for every robot; the bracket as a four-leg manoeuvre", _brackets_demo),
    "unicycle-tracking": ("unicycle trajectory tracking: Kanayama et al. 1990, point-offset linearisation", _unicycle_tracking_demo),
    "unicycle-posture": ("unicycle posture regulation in polar coordinates (Aicardi et al. 1995)", _unicycle_posture_demo),
    "car-tracking": ("car trajectory tracking by dynamic feedback linearisation (De Luca, Oriolo, Samson 1998)", _car_tracking_demo),
    "car-parking": ("car parallel parking by sinusoids in chained form (Murray and Sastry 1993)", _car_parking_demo),
    "mobile-manipulation": ("Q-PRR arm on a car: task-priority IK with the Pfaffian constraint vs without", lambda: _manipulation_demo("qprr")),
    "mobile-manipulation-3r": ("3R arm on a car: task-priority IK with the Pfaffian constraint vs without", lambda: _manipulation_demo("3r")),
}
"""Exercises, control laws and mobile manipulation: name -> (description, runner)."""


def catalogue() -> dict[str, str]:
    """Every runnable name with a one-line description (robots first)."""
    out = {n: f"robot: {ROBOTS[n]().description}" for n in ROBOTS}
    out.update({n: d for n, (d, _) in EXERCISES.items()})
    return out


def run_demo(name: str) -> Demo:
    """Run the catalogue entry ``name`` (a robot of :data:`~qprr.wheeled.robots.ROBOTS` or an exercise)."""
    if name in ROBOTS:
        return _robot_demo(name)
    if name in EXERCISES:
        return EXERCISES[name][1]()
    raise UnknownNameError("wheeled robot or exercise", name, tuple(ROBOTS) + tuple(EXERCISES))


__all__ = ["EXERCISES", "Demo", "catalogue", "run_demo"]
