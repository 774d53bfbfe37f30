"""Every Chapter 6 comparison, printed and drawn: ``qprr compare [NAME ...] [--plot DIR]``.

==============  ===================================================================================================
name            what (runs on the Q-PRR; the figures go to DIR with ``--plot``)
==============  ===================================================================================================
``table``       RMSE (6.26) of IDC, desired-state ID (the thesis's "MPC") and MFC on the static mission next to
                Table 6.3, wall times vs the thesis's T_x; bars ours vs thesis
``overlay``     the three controllers overlaid: base positions (Fig. 6.19), position errors (Fig. 6.20), arm
                joint errors (Fig. 6.21)
``noise``       the white-noise signal of (6.27) the ``noise`` scenario applies (Fig. 6.23), and its statistics
``sweeps``      the CoG stabiliser (BSG + MFC) for several theta_e^d and theta2^d: x_cm (Figs. 6.42, 6.43), r0
                (Fig. 6.44) and theta3 (Fig. 6.45)
``decoupled``   coupled IDC vs decoupled control (Sec. 6.2.2) at equal gains on the static mission, the spiral,
                the pulses and the payload drop
``mpc``         receding-horizon MPC vs IDC on the static mission, the spiral and the payload drop (RMSE, solve
                time per step, thrust margins) and on the aggressive reach (rotor bounds)
``realistic``   every controller with motor lag, drag in wind and joint friction (scenario ``realistic``)
``lag``         how slow the motors may be: each controller on the static mission for motor time constants
                0-20 ms (diverged or position RMSE)
==============  ===================================================================================================

Each function returns a :class:`Report` (text lines, figure paths, ok flag); runs shared by two
comparisons are made once per call of :func:`run_comparisons`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..control import CONTROLLERS
from ..errors import QprrError, UnknownNameError
from ..scenarios import SCENARIOS
from ..sim import SimConfig, SimInputs, SimResult, Status, simulate
from ..viz import figure_path, new_figure
from ..viz.compare import plot_overlay, plot_rmse_bars
from .bsg import CogStabilizer
from .control_scenarios import thrust_margins
from .missions import NAMES, dynamic_mission, static_mission
from .realistic import qprr_rotor_dynamics
from .robot import load_qprr
from .scenarios import NOISE_AMPLITUDE, TABLE_6_3, THESIS_NAMES, THESIS_RUN_TIME_S, flight_controller

NAMES_ALL = ("table", "overlay", "noise", "sweeps", "decoupled", "mpc", "realistic", "lag")


@dataclass
class Report:
    """What one comparison printed and drew; ``ok`` False when a run that should complete did not."""

    name: str
    lines: list[str] = field(default_factory=list)
    figures: list[Path] = field(default_factory=list)
    ok: bool = True


class _Runs:
    """Scenario runs made once per comparison session (keyed by scenario, controller and options)."""

    def __init__(self, duration: float | None, progress: bool) -> None:
        self.duration, self.progress = duration, progress
        self._cache: dict = {}

    def get(self, scenario: str, controller: str, **options) -> SimResult:
        sc = SCENARIOS[scenario]
        if self.duration is not None and "duration" in sc.options and "duration" not in options and scenario != "payload-drop":
            options["duration"] = self.duration
        key = (scenario, controller, tuple(sorted(options.items())))
        if key not in self._cache:
            t0 = time.perf_counter()
            try:
                res = sc.run(controller=controller, progress=self.progress, **options)
            except QprrError as err:
                res = err.result
                if res is None:
                    raise
            res.metrics.setdefault("comparison_wall_s", time.perf_counter() - t0)
            self._cache[key] = res
        return self._cache[key]


def _fmt_rmse(e: dict[str, float], names=NAMES) -> str:
    return " ".join(f"{n} {e[n]:.2e}" for n in names)


def _rmse_table(rows: dict[str, SimResult], variables=NAMES) -> list[str]:
    head = f"{'run':<28}{'status':<10}" + "".join(f"{v:>10}" for v in variables)
    out = [head, "-" * len(head)]
    for label, res in rows.items():
        e = res.rmse()
        out.append(f"{label:<28}{str(res.status):<10}" + "".join(f"{e[v]:>10.2e}" for v in variables))
    return out


def _save(report: Report, path: Path | None) -> None:
    if path is not None:
        report.figures.append(path)


def _dir(plot_dir: Path | None, name: str) -> Path | None:
    return None if plot_dir is None else Path(plot_dir) / name


# ============================================================================== comparisons
def compare_table(runs: _Runs, plot_dir: Path | None) -> Report:
    """Table 6.3: our RMSE and wall times next to the thesis's."""
    rep = Report("table")
    res = {c: runs.get(f"static-{c}", c) for c in ("idc", "dsid", "mfc")}
    head = f"{'variable':<9}" + "".join(f"{c + ' (ours)':>13}{THESIS_NAMES[c] + ' (thesis)':>15}" for c in res)
    rep.lines += ["RMSE (6.26) on the static mission (Sec. 6.3.1.4), ours vs Thesis Table 6.3 (thesis MPC = our dsid)", head, "-" * len(head)]
    for i, v in enumerate(NAMES):
        rep.lines.append(f"{v:<9}" + "".join(f"{r.rmse()[v]:>13.3e}{TABLE_6_3[c][i]:>15.4e}" for c, r in res.items()))
    rep.lines.append(f"{'time':<9}" + "".join(f"{r.wall_time:>12.3f}s{THESIS_RUN_TIME_S[c] / 60:>12.0f}min" for c, r in res.items()))
    rep.ok = all(r.status == Status.OK for r in res.values())
    if plot_dir is not None:
        table = {f"{c} (ours)": r.rmse() for c, r in res.items()}
        table.update({f"{THESIS_NAMES[c]} (thesis)": dict(zip(NAMES, TABLE_6_3[c])) for c in res})
        _save(rep, plot_rmse_bars(table, _dir(plot_dir, "table-6.3.png"), title="RMSE (6.26), static mission: ours vs Table 6.3"))
    return rep


def compare_overlay(runs: _Runs, plot_dir: Path | None) -> Report:
    """Figs. 6.19-6.21: the three controllers on the static mission."""
    rep = Report("overlay")
    res = {f"{c} ({THESIS_NAMES[c]})": runs.get(f"static-{c}", c) for c in ("idc", "dsid", "mfc")}
    rep.lines += ["three controllers on the static mission (Figs. 6.19-6.21)", *_rmse_table(res)]
    if plot_dir is not None:
        _save(
            rep,
            plot_overlay(
                res,
                _dir(plot_dir, "fig-6.19-6.21.png"),
                rows=("position", "position error", "arm error"),
                title="Figs. 6.19-6.21: IDC, desired-state ID (thesis MPC), MFC - positions, position errors, arm errors",
            ),
        )
    rep.ok = all(r.status == Status.OK for r in res.values())
    return rep


def compare_noise(runs: _Runs, plot_dir: Path | None) -> Report:
    """Fig. 6.23: the white noise of (6.27) (uniform, a new value each 1 ms) the noise scenario applies."""
    rep = Report("noise")
    res = runs.get("noise", "idc")
    u = res.u_ext
    amp = np.array(NOISE_AMPLITUDE)
    rep.lines.append("white noise (6.27) of the noise scenario: uniform in [-a, a], a new sample every control tick; per component")
    rep.lines.append(f"{'component':<10}{'a':>8}{'mean':>11}{'std':>10}{'a/sqrt(3)':>11}{'max|u|':>9}")
    for i, n in enumerate(NAMES):
        rep.lines.append(
            f"{n:<10}{amp[i]:>8.3g}{u[:, i].mean():>11.2e}{u[:, i].std():>10.4f}{amp[i] / math.sqrt(3):>11.4f}{np.abs(u[:, i]).max():>9.4f}"
        )
    rep.lines.append(f"tracking with it (IDC): {_fmt_rmse(res.rmse())}")
    if plot_dir is not None:
        fig = new_figure((13, 7))
        ax = fig.subplots(3, 2, sharex="col")
        groups = ((0, 1, 2), (3, 4, 5), (6, 7, 8))
        titles = ("forces on x, y, z [N]", "torques on phi, theta, psi [N m]", "arm: r0 [N], theta2, theta3 [N m]")
        for r, (g, title) in enumerate(zip(groups, titles)):
            for i in g:
                ax[r, 0].plot(res.t, u[:, i], lw=0.3, label=NAMES[i])
                sel = res.t < 0.1
                ax[r, 1].step(res.t[sel], u[sel, i], where="post", lw=0.8, label=NAMES[i])
            ax[r, 0].set_title(title, fontsize=9)
            ax[r, 1].set_title(title + " - first 0.1 s", fontsize=9)
            for a in ax[r]:
                a.grid(alpha=0.3)
                a.legend(fontsize=7, loc="upper right")
        ax[2, 0].set_xlabel("t [s]")
        ax[2, 1].set_xlabel("t [s]")
        fig.suptitle(
            "Fig. 6.23: white noise u_ext of (6.27) (seeded, uniform; +-0.3 on seven forces, +-0.01 N m on the revolute joints)", fontsize=10
        )
        p = figure_path(_dir(plot_dir, "fig-6.23-noise.png"))
        fig.savefig(p, dpi=80)
        _save(rep, p)
    return rep


SWEEP_PAIRS = ((0.0, -0.5), (0.3, -0.5), (-0.3, -0.5), (0.6, -0.2))
"""(theta_e^d, theta2^d) of the Fig. 6.42 comparison (the thesis does not print its values)."""
SWEEP_THETA2 = (-0.8, -0.5, -0.2, 0.2, 0.5)
"""theta2^d of Figs. 6.43-6.45 (theta_e^d = 0)."""


def _bsg_run(theta_e: float, theta2: float, duration: float, progress: bool) -> SimResult:
    platform = load_qprr()
    ctrl = CogStabilizer(platform, flight_controller("mfc", platform), theta_e_d=theta_e)
    try:
        return simulate(platform, ctrl, dynamic_mission(theta2_d=theta2), duration, config=SimConfig(progress=progress, scenario="dynamic-bsg"))
    except QprrError as err:
        if err.result is None:
            raise
        return err.result


def compare_sweeps(runs: _Runs, plot_dir: Path | None) -> Report:
    """Figs. 6.42-6.45: the CoG stabiliser for several end-effector pitches theta_e^d and theta2^d."""
    rep = Report("sweeps")
    duration = runs.duration or 30.0
    pairs = {(te, t2): _bsg_run(te, t2, duration, runs.progress) for te, t2 in SWEEP_PAIRS}
    theta2 = {t2: (pairs[(0.0, t2)] if (0.0, t2) in pairs else _bsg_run(0.0, t2, duration, runs.progress)) for t2 in SWEEP_THETA2}
    rep.lines.append("BSG + MFC, dynamic mission (Sec. 6.3.3.3): final x_cm, r0, theta3 and max |x_cm| after the arm phase starts (15 s)")
    rep.lines.append(f"{'theta_e^d':>10}{'theta2^d':>10}{'status':>10}{'x_cm [mm]':>11}{'max|x_cm|':>11}{'r0 [m]':>9}{'theta3':>9}{'theta_e':>9}")
    for (te, t2), r in list(pairs.items()) + [((0.0, t2), r) for t2, r in theta2.items() if (0.0, t2) not in pairs]:
        after = r.t >= 15.0
        te_meas = r.xi[-1, 4] + r.xi[-1, 7] + r.xi[-1, 8]  # (6.34)
        rep.lines.append(
            f"{te:>10.2f}{t2:>10.2f}{str(r.status):>10}{1e3 * r.x_cm[-1, 0]:>11.3f}"
            f"{1e3 * np.abs(r.x_cm[after, 0]).max() if after.any() else float('nan'):>11.3f}{r.xi[-1, 6]:>9.4f}"
            f"{r.xi[-1, 8]:>9.4f}{te_meas:>9.4f}"
        )
        rep.ok &= r.status == Status.OK
    if plot_dir is not None:
        fig = new_figure((14, 9))
        ax = fig.subplots(2, 2)
        for k, ((te, t2), r) in enumerate(pairs.items()):
            ax[0, 0].plot(r.t, 1e3 * r.x_cm[:, 0], color=f"C{k}", lw=1.0, label=f"theta_e = {te:g}, theta2 = {t2:g}")
        ax[0, 0].set_title("Fig. 6.42: x_cm for several (theta_e^d, theta2^d)", fontsize=9)
        ax[0, 0].set_ylabel("x_cm [mm]")
        for k, (t2, r) in enumerate(theta2.items()):
            ax[0, 1].plot(r.t, 1e3 * r.x_cm[:, 0], color=f"C{k}", lw=1.0, label=f"theta2 = {t2:g}")
            ax[1, 0].plot(r.t, r.xi[:, 6], color=f"C{k}", lw=1.0, label=f"theta2 = {t2:g}")
            ax[1, 1].plot(r.t, r.xi[:, 8], color=f"C{k}", lw=1.0, label=f"theta2 = {t2:g}")
        ax[0, 1].set_title("Fig. 6.43: x_cm for several theta2^d, theta_e^d = 0", fontsize=9)
        ax[0, 1].set_ylabel("x_cm [mm]")
        ax[1, 0].set_title("Fig. 6.44: slider r0 for several theta2^d, theta_e^d = 0", fontsize=9)
        ax[1, 0].set_ylabel("r0 [m]")
        ax[1, 1].set_title("Fig. 6.45: theta3 for several theta2^d, theta_e^d = 0", fontsize=9)
        ax[1, 1].set_ylabel("theta3 [rad]")
        for a in ax.flat:
            a.grid(alpha=0.3)
            a.legend(fontsize=7)
            a.set_xlabel("t [s]")
        fig.suptitle("Figs. 6.42-6.45: CoG stabiliser (BSG + MFC) on the dynamic mission", fontsize=10)
        p = figure_path(_dir(plot_dir, "fig-6.42-6.45-sweeps.png"))
        fig.savefig(p, dpi=80)
        _save(rep, p)
    return rep


_DECOUPLED_MISSIONS = (("static-idc", {}), ("spiral", {}), ("pulses", {}), ("payload-drop", {}))


def compare_decoupled(runs: _Runs, plot_dir: Path | None) -> Report:
    """Coupled IDC vs decoupled control (Sec. 6.2.2) at the same gains."""
    rep = Report("decoupled")
    rows = {}
    for sc, opts in _DECOUPLED_MISSIONS:
        for c in ("idc", "decoupled"):
            rows[f"{sc} / {c}"] = runs.get(sc, c, **opts)
    rep.lines += ["coupled IDC vs decoupled control (Sec. 6.2.2, Fig. 6.2) at the Table 6.2 gains", *_rmse_table(rows)]
    for sc, _ in _DECOUPLED_MISSIONS:
        a, b = rows[f"{sc} / idc"].rmse(), rows[f"{sc} / decoupled"].rmse()
        ratio = {n: b[n] / a[n] if a[n] > 0 else float("nan") for n in ("x", "y", "z", "r0", "theta2", "theta3")}
        rep.lines.append(f"{sc}: decoupled / coupled RMSE " + ", ".join(f"{n} {v:.2f}" for n, v in ratio.items()))
    rep.ok = all(r.status == Status.OK for r in rows.values())
    if plot_dir is not None:
        res = {"coupled IDC": rows["static-idc / idc"], "decoupled": rows["static-idc / decoupled"]}
        _save(
            rep,
            plot_overlay(
                res,
                _dir(plot_dir, "coupled-vs-decoupled.png"),
                rows=("position error", "attitude error", "arm error"),
                title="coupled IDC vs decoupled control (Sec. 6.2.2), static mission, Table 6.2 gains",
            ),
        )
        _save(
            rep,
            plot_rmse_bars(
                {k: v.rmse() for k, v in rows.items()}, _dir(plot_dir, "coupled-vs-decoupled-rmse.png"), title="RMSE (6.26): coupled IDC vs decoupled"
            ),
        )
    return rep


def compare_mpc(runs: _Runs, plot_dir: Path | None) -> Report:
    """Receding-horizon MPC vs IDC: RMSE, solve time per step, thrust margins; the aggressive reach."""
    rep = Report("mpc")
    if "mpc" not in CONTROLLERS:
        from ..control import OPTIONAL

        rep.lines.append(f"skipped: the MPC needs crocoddyl ({OPTIONAL['mpc'][2]})")
        rep.ok = False
        return rep
    platform = load_qprr()
    rows = {}
    for sc, idc in (("static-idc", "idc"), ("spiral", "idc"), ("payload-drop", "idc"), ("aggressive-reach", "idc")):
        for c in (idc, "mpc"):
            rows[f"{sc} / {c}"] = runs.get(sc, c)
    rep.lines += ["receding-horizon MPC (100 Hz, 40 nodes, Box-FDDP, rotor bounds) vs IDC", *_rmse_table(rows)]
    rep.lines.append(
        f"{'run':<28}{'applied margin':>15}{'asked margin':>14}{'saturated %':>13}{'solve med/p95 [ms]':>20}"
        f"{'CPU med/p95 [ms]':>18}{'failed':>8}{'plan margin':>12}"
    )
    for label, r in rows.items():
        m = thrust_margins(r, platform)
        mm = r.metrics
        mpc = (
            (
                f"{1e3 * mm['mpc_median_solve_s']:>9.1f}/{1e3 * mm['mpc_p95_solve_s']:<10.1f}"
                f"{1e3 * mm['mpc_median_solve_cpu_s']:>8.1f}/{1e3 * mm['mpc_p95_solve_cpu_s']:<9.1f}{mm['mpc_failed']:>8.0f}"
                f"{mm['mpc_min_plan_thrust_margin_N']:>12.3g}"
            )
            if "mpc_solves" in mm
            else f"{'-':>20}{'-':>18}{'-':>8}{'-':>12}"
        )
        rep.lines.append(f"{label:<28}{m['applied_margin_N']:>15.3g}{m['asked_margin_N']:>14.3g}{100 * m['saturated_fraction']:>13.2f}{mpc}")
    rep.lines.append(
        "margins in N: applied = closest applied thrust to [0, 20] N; asked = closest thrust the controller asked for "
        "(negative: beyond a bound, clipped by the allocator); plan = smallest margin of any MPC plan"
    )
    rep.ok = all(r.status == Status.OK for k, r in rows.items() if k.endswith("/ mpc"))
    if plot_dir is not None:
        res = {"IDC": rows["static-idc / idc"], "MPC": rows["static-idc / mpc"]}
        _save(
            rep,
            plot_overlay(
                res, _dir(plot_dir, "mpc-vs-idc-static.png"), rows=("position error", "arm error", "thrust"), title="MPC vs IDC, static mission"
            ),
        )
        _save(rep, _plot_reach(rows["aggressive-reach / idc"], rows["aggressive-reach / mpc"], platform, _dir(plot_dir, "mpc-vs-idc-reach.png")))
        _save(
            rep,
            plot_rmse_bars(
                {k: v.rmse() for k, v in rows.items() if not k.startswith("aggressive")},
                _dir(plot_dir, "mpc-vs-idc-rmse.png"),
                title="RMSE (6.26): MPC vs IDC",
            ),
        )
    return rep


def _plot_reach(idc: SimResult, mpc: SimResult, platform, path) -> Path:
    """Rotor thrusts (applied and asked for) and the climb of the aggressive reach, IDC vs MPC."""
    fig = new_figure((14, 5))
    ax = fig.subplots(1, 2)
    Omega = np.array(platform.rotor_matrix)
    rows = [i for i in range(6) if np.abs(Omega[i]).max() > 1e-12]
    tau_d = np.hstack([idc.f, idc.arm_effort]) @ np.array(platform.actuation_matrix).T + idc.unallocated
    asked = tau_d[:, rows] @ np.linalg.pinv(Omega[rows]).T
    ax[0].plot(idc.t, np.clip(asked[:, 0], -15, 35), color="tab:red", alpha=0.4, lw=1.0, label="IDC: rotor 1 asked (clipped to the view)")
    ax[0].plot(idc.t, idc.f[:, 0], color="tab:red", lw=1.2, label="IDC: rotor 1 applied")
    for j in range(mpc.f.shape[1]):
        ax[0].plot(mpc.t, mpc.f[:, j], color="tab:blue", lw=0.9, label="MPC: rotors applied" if j == 0 else None)
    for b in (float(platform.thrust_min.min()), float(platform.thrust_max.max())):
        ax[0].axhline(b, color="k", ls="--", lw=0.8)
    ax[0].set_xlim(0.3, min(2.5, mpc.t[-1]))
    ax[0].set_ylabel("thrust [N]")
    ax[0].set_title("aggressive reach: rotor thrusts and bounds", fontsize=9)
    for res, name, c in ((idc, "IDC", "tab:red"), (mpc, "MPC", "tab:blue")):
        ax[1].plot(res.t, res.xi[:, 2], color=c, label=f"{name} z [m]")
        ax[1].plot(res.t, res.xi[:, 7], color=c, ls=":", label=f"{name} theta2 [rad]")
    ax[1].plot(mpc.t, mpc.xi_d[:, 2], "k--", lw=0.8, label="reference")
    ax[1].plot(mpc.t, mpc.xi_d[:, 7], "k--", lw=0.8)
    ax[1].set_title(f"aggressive reach: z and theta2 (IDC {idc.status}, MPC {mpc.status})", fontsize=9)
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
        a.set_xlabel("t [s]")
    path = figure_path(path)
    fig.savefig(path, dpi=80)
    return path


def compare_realistic(runs: _Runs, plot_dir: Path | None) -> Report:
    """Every controller on the static mission with motor lag, drag in wind and joint friction."""
    rep = Report("realistic")
    ctrls = [c for c in ("idc", "dsid", "mfc", "decoupled", "mpc") if c in CONTROLLERS]
    rows = {c: runs.get("realistic", c) for c in ctrls}
    ideal = {c: runs.get(f"static-{c}" if c in ("idc", "dsid", "mfc") else "static-idc", c) for c in ctrls}
    rep.lines += [
        "every controller on the static mission with motor lag (5 ms), drag in wind (2.2 m/s mean, Dryden light "
        "turbulence, a 2 m/s gust) and joint friction (scenario realistic, seed 0)",
        *_rmse_table(rows),
    ]
    rep.lines.append(
        "position RMSE (max of x, y, z) realistic / ideal: "
        + ", ".join(f"{c} {max(rows[c].rmse()[n] for n in 'xyz') / max(ideal[c].rmse()[n] for n in 'xyz'):.1f}x" for c in ctrls)
    )
    for c, r in rows.items():
        m = thrust_margins(r, load_qprr())
        rep.lines.append(f"{c}: {r.status}; thrust margin applied {m['applied_margin_N']:.3g} N, asked {m['asked_margin_N']:.3g} N")
    rep.ok = all(r.status == Status.OK for r in rows.values())
    if plot_dir is not None:
        _save(
            rep,
            plot_overlay(
                rows,
                _dir(plot_dir, "realistic.png"),
                rows=("position error", "attitude error", "arm error"),
                title="realistic: motor lag, drag in wind, joint friction - every controller",
            ),
        )
        _save(
            rep,
            plot_rmse_bars(
                {c: r.rmse() for c, r in rows.items()}, _dir(plot_dir, "realistic-rmse.png"), title="RMSE (6.26) with motor lag, wind and friction"
            ),
        )
    return rep


LAG_TIME_CONSTANTS = (0.0, 0.0025, 0.005, 0.01, 0.015, 0.02)
"""Motor time constants of the ``lag`` comparison [s] (0: no actuator stage)."""


def compare_lag(runs: _Runs, plot_dir: Path | None) -> Report:
    """Each controller on the static mission for motor time constants 0-20 ms (no wind): how slow may the motors be?"""
    rep = Report("lag")
    platform = load_qprr()
    duration = runs.duration or 30.0
    ctrls = ("idc", "dsid", "mfc", "decoupled")
    table: dict[str, list[tuple[float, str, float]]] = {c: [] for c in ctrls}
    for c in ctrls:
        for T in LAG_TIME_CONSTANTS:
            act = qprr_rotor_dynamics(platform, time_constant=T) if T > 0 else None
            try:
                config = SimConfig(progress=runs.progress, scenario="lag")
                r = simulate(platform, flight_controller(c, platform), static_mission(), duration, config=config, inputs=SimInputs(actuators=act))
            except QprrError as err:
                r = err.result
                if r is None:
                    raise
            table[c].append((T, r.status, max(r.rmse()[n] for n in "xyz") if r.status == Status.OK else float(r.t[-1])))
    rep.lines.append("static mission with the motor lag only: max position RMSE [m], or 'diverged at t s'")
    rep.lines.append(f"{'T [ms]':<8}" + "".join(f"{c:>22}" for c in ctrls))
    for k, T in enumerate(LAG_TIME_CONSTANTS):
        cells = []
        for c in ctrls:
            _, status, v = table[c][k]
            cells.append(f"{v:>22.3e}" if status == Status.OK else f"{'diverged at ' + format(v, '.2f') + ' s':>22}")
        rep.lines.append(f"{1e3 * T:<8.1f}" + "".join(cells))
    if plot_dir is not None:
        fig = new_figure((8, 4.5))
        ax = fig.subplots()
        styles = (("o", "-"), ("s", "--"), ("^", "-."), ("D", ":"))
        for k, c in enumerate(ctrls):
            Ts = [1e3 * T for T, s, _ in table[c] if s == Status.OK]
            vs = [v for _, s, v in table[c] if s == Status.OK]
            ax.plot(Ts, vs, marker=styles[k][0], ls=styles[k][1], color=f"C{k}", label=c, ms=5 + 2 * (len(ctrls) - k))
            bad = [1e3 * T for T, s, _ in table[c] if s != Status.OK]
            if bad:  # diverged: a cross above the plot, one row per controller
                ax.plot(bad, [2.0 * 1.6**k] * len(bad), "x", color=f"C{k}", ms=10, mew=2)
        ax.set_yscale("log")
        ax.set_xlabel("motor time constant T [ms]")
        ax.set_ylabel("max position RMSE [m] (crosses above 1 m: diverged)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title("static mission with a first-order motor lag", fontsize=10)
        p = figure_path(_dir(plot_dir, "motor-lag.png"))
        fig.savefig(p, dpi=80)
        _save(rep, p)
    return rep


COMPARISONS: dict[str, Callable[[_Runs, Path | None], Report]] = {
    "table": compare_table,
    "overlay": compare_overlay,
    "noise": compare_noise,
    "sweeps": compare_sweeps,
    "decoupled": compare_decoupled,
    "mpc": compare_mpc,
    "realistic": compare_realistic,
    "lag": compare_lag,
}


def run_comparisons(names: Sequence[str] = ("table",), *, duration: float | None = None, plot_dir=None, progress: bool = False) -> list[Report]:
    """Run the comparisons ``names`` (or "all") sharing their runs; ``duration`` [s] overrides the missions' 30 s
    (not the payload drop's); ``plot_dir`` (an existing folder) receives the figures."""
    names = list(COMPARISONS) if "all" in names else list(names)
    for n in names:
        if n not in COMPARISONS:
            raise UnknownNameError("comparison", n, (*COMPARISONS, "all"))
    if plot_dir is not None and not Path(plot_dir).is_dir():
        from ..errors import InputError

        raise InputError(f"--plot {str(plot_dir)!r}: the folder does not exist")
    runs = _Runs(duration, progress)
    return [COMPARISONS[n](runs, None if plot_dir is None else Path(plot_dir)) for n in names]


__all__ = ["COMPARISONS", "LAG_TIME_CONSTANTS", "NAMES_ALL", "SWEEP_PAIRS", "SWEEP_THETA2", "Report", "run_comparisons"]
