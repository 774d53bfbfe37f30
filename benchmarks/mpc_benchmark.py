"""Receding-horizon MPC (qprr.control.mpc) against the IDC, side by side in one run.

    python benchmarks/mpc_benchmark.py [--duration 30] [--integrators rk2,euler] [--plot docs/figures/mpc-benchmark.png]

Prints the machine, then:

1. the static mission of Thesis Sec. 6.3.1.4 (30 s at 1 kHz, midpoint simulator): RMSE (6.26) per
   coordinate of the IDC and of the MPC (one run per MPC integrator) and their ratio, the
   end-effector position RMSE (world, against FK of the trajectory with the feedforward tilt
   (6.17) of its acceleration, the same reference for both), the MPC's solve time per step
   (median, p95, max; wall and thread CPU time; the cold first solve left out), iterations,
   statuses, and the wall times of the runs;
2. the aggressive reach (scenario ``aggressive-reach``, climb 1.5 m or 2 m): for both controllers
   the fraction of ticks where the allocator hit a rotor bound, the applied thrust range, the
   thrust *asked for* and its margin to the bounds [0, 20] N (negative: the demand exceeded a
   bound and was clipped), the MPC's smallest planned margin, and the tracking RMSE.

Roll/pitch RMSE are against different references (the IDC's filtered (6.17) of its own feedback
force, the MPC's feedforward (6.17) of the reference acceleration): compare the other seven
coordinates.  The MPC previews the trajectory over its horizon; the IDC sees the current
reference only.  Times are wall-clock on a shared machine: the CPU times are the steadier figure.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py
sys.path.insert(0, str(ROOT))  # this worktree's qprr
from machine import machine_lines  # noqa: E402

import qprr  # noqa: E402
from qprr.charts import xi_to_q  # noqa: E402
from qprr.control.mpc import MPCController, MPCSettings  # noqa: E402
from qprr.errors import QprrError  # noqa: E402
from qprr.scenarios import run as run_scenario  # noqa: E402
from qprr.sim import SimResult, simulate  # noqa: E402
from qprr.thesis.control_scenarios import thrust_margins  # noqa: E402
from qprr.thesis.missions import NAMES, static_mission  # noqa: E402
from qprr.thesis.scenarios import flight_controller  # noqa: E402
from qprr.viz import figure_path, new_figure  # noqa: E402
from qprr.viz.plots import legend  # noqa: E402


def run(platform, ctrl, traj, duration) -> SimResult:
    try:
        return simulate(platform, ctrl, traj, duration, progress=sys.stderr.isatty(), scenario=getattr(traj, "name", "custom"))
    except QprrError as err:
        if getattr(err, "result", None) is None:
            raise
        return err.result


def ee_rmse(platform, res: SimResult, traj, mpc: MPCController, every: int = 10) -> float:
    """RMSE [m] of the end-effector position (world) against FK of the trajectory with roll and pitch of (6.17) on the
    reference acceleration (the attitude exact tracking needs); the same reference for both controllers."""
    data = platform.data()
    idx = np.arange(0, res.n, every)
    s = traj.sample(res.t[idx])
    err = np.empty(idx.size)
    for j, k in enumerate(idx):
        pin.framesForwardKinematics(platform.model, data, xi_to_q(res.xi[k]))
        M_ref = mpc.reference(s.xi[j], s.xi_dot[j], s.xi_ddot[j])[1]
        err[j] = np.linalg.norm(data.oMf[platform.ee_frame].translation - M_ref.translation)
    return float(np.sqrt(np.mean(err**2)))


def ratio(a: float, b: float) -> str:
    return f"{a / b:>8.2f}" if b > 0 else f"{'-':>8}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=30.0, help="static mission length [s] (default 30)")
    ap.add_argument("--integrators", default="rk2", help="MPC integrators to time on the static mission (comma list)")
    ap.add_argument("--plot", default=str(ROOT / "docs" / "figures" / "mpc-benchmark.png"), help="figure path ('' for none)")
    args = ap.parse_args(argv)
    print(" | ".join(machine_lines(extra=("crocoddyl",))))
    platform = qprr.load()

    # ---------------------------------------------------------------- static mission
    traj = static_mission()
    print(f"\n1. static mission (Sec. 6.3.1.4), {args.duration:g} s at 1 kHz, midpoint simulator")
    t0 = time.perf_counter()
    idc = run(platform, flight_controller("idc", platform), traj, args.duration)
    idc_wall = time.perf_counter() - t0
    mpcs = {}
    for integ in args.integrators.split(","):
        ctrl = MPCController(platform, settings=MPCSettings(integrator=integ))
        t0 = time.perf_counter()
        res = run(platform, ctrl, traj, args.duration)
        mpcs[integ] = (res, ctrl, time.perf_counter() - t0)
    head = f"{'RMSE (6.26)':<12}{'idc':>11}" + "".join(f"{'mpc-' + k:>11}{'ratio':>8}" for k in mpcs)
    print(head)
    print("-" * len(head))
    e_idc = idc.rmse()
    for name in NAMES:
        row = f"{name:<12}{e_idc[name]:>11.3e}"
        for res, _, _ in mpcs.values():
            e = res.rmse()[name]
            row += f"{e:>11.3e}{ratio(e, e_idc[name])}"
        print(row)
    ref_ctrl = next(iter(mpcs.values()))[1]
    ee_idc = ee_rmse(platform, idc, traj, ref_ctrl)
    row = f"{'ee [m]':<12}{ee_idc:>11.3e}"
    for res, _, _ in mpcs.values():
        e = ee_rmse(platform, res, traj, ref_ctrl)
        row += f"{e:>11.3e}{ratio(e, ee_idc)}"
    print(row)
    print("-" * len(head))
    print(f"status: idc {idc.status}" + "".join(f", mpc-{k} {r.status}" for k, (r, _, _) in mpcs.items()))
    for integ, (res, ctrl, wall) in mpcs.items():
        st = ctrl.stats()
        s = st.summary()
        s_set = ctrl.settings
        m = thrust_margins(res, platform)
        print(f"mpc-{integ} (N = {s_set.horizon} nodes of {1e3 / s_set.rate:g} ms, {s_set.max_iter} iterations max): "
              f"solve per MPC step median {1e3 * s['median_solve_s']:.1f} ms, p95 {1e3 * s['p95_solve_s']:.1f} ms, "
              f"max {1e3 * s['max_solve_s']:.1f} ms; CPU time median {1e3 * s['median_solve_cpu_s']:.1f} ms, "
              f"p95 {1e3 * s['p95_solve_cpu_s']:.1f} ms (whole update median {1e3 * np.median(st.step_time[1:]):.1f} ms; "
              f"cold first solve {1e3 * st.solve_time[0]:.0f} ms, {st.iterations[0]} iterations); "
              f"median {s['median_iterations']:.0f} iterations; {s['converged']:.0f} converged, "
              f"{s['iteration_limit']:.0f} at the iteration limit, {s['failed']:.0f} failed, {ctrl.fallback_count} fallbacks; "
              f"median CPU solve / period {s['median_solve_cpu_s'] * s_set.rate:.2f}")
        print(f"  wall time: idc {idc_wall:.2f} s, mpc-{integ} {wall:.1f} s for {args.duration:g} s simulated; thrust margins: "
              f"applied {m['applied_margin_N']:.2f} N, smallest planned {s['min_thrust_margin_N']:.2f} N "
              f"(idc applied {thrust_margins(idc, platform)['applied_margin_N']:.2f} N)")

    # ---------------------------------------------------------------- aggressive reach
    lo, hi = float(platform.thrust_min.min()), float(platform.thrust_max.max())
    print(f"\n2. aggressive reach: climb C m and 0.6 m forward in 1 s from hover at 2 m, arm to (0.03 m, 0.6, -0.3); "
          f"3 s; rotor bounds [{lo:g}, {hi:g}] N")
    head = (f"{'case':<14}{'status':<10}{'sat %':>7}{'applied f [N]':>18}{'asked f [N]':>22}{'asked margin':>13}"
            f"{'plan margin':>12}{'stops':>6}{'x':>9}{'z':>9}{'theta2':>9}{'theta3':>9}")
    print(head)
    print("-" * len(head))
    reach = {}
    for climb in (1.5, 2.0):
        for cname in ("idc", "mpc"):
            try:
                res = run_scenario("aggressive-reach", cname, climb=climb)
            except QprrError as err:
                res = err.result
            m = thrust_margins(res, platform)
            plan = f"{res.metrics['mpc_min_plan_thrust_margin_N']:>12.2g}" if cname == "mpc" else f"{'-':>12}"
            e = res.rmse()
            case = f"C={climb:g} {cname}"
            applied = f"[{res.f.min():.2f}, {res.f.max():.2f}]"
            asked = f"[{m['asked_min_N']:.3g}, {m['asked_max_N']:.3g}]"
            print(f"{case:<14}{str(res.status):<10}{100 * m['saturated_fraction']:>7.2f}{applied:>18}{asked:>22}"
                  f"{m['asked_margin_N']:>13.3g}{plan}{int(np.any(res.flags & 4)):>6}{e['x']:>9.2e}{e['z']:>9.2e}"
                  f"{e['theta2']:>9.2e}{e['theta3']:>9.2e}")
            if cname == "mpc":
                mm = res.metrics
                print(f"{'':<14}mpc solve median {1e3 * mm['mpc_median_solve_s']:.1f} ms, p95 {1e3 * mm['mpc_p95_solve_s']:.1f} ms "
                      f"(CPU {1e3 * mm['mpc_median_solve_cpu_s']:.1f}, {1e3 * mm['mpc_p95_solve_cpu_s']:.1f} ms); "
                      f"{mm['mpc_converged']:.0f} converged, {mm['mpc_iteration_limit']:.0f} at the iteration limit, "
                      f"{mm['mpc_failed']:.0f} failed; max plan bound violation {mm['mpc_max_plan_bound_violation_N']:.2g} N")
            reach[(climb, cname)] = res
    print("-" * len(head))
    print("sat %: ticks where the allocator clipped a rotor; asked margin < 0: the controller asked beyond a bound; "
          "stops: an arm joint hit its mechanical stop")
    if args.plot:
        print(f"\nfigure {plot(args.plot, idc, mpcs, reach, lo, hi)}")
    return 0


def plot(path, idc, mpcs, reach, lo, hi) -> Path:
    path = figure_path(path)
    fig = new_figure((14, 9))
    ax = fig.subplots(2, 2)
    res_m = next(iter(mpcs.values()))[0]
    label_m = "mpc-" + next(iter(mpcs))
    for a, i in zip((ax[0, 0], ax[0, 1]), (0, 2)):
        a.plot(idc.t, 1e3 * (idc.xi_d[:, i] - idc.xi[:, i]), label="idc")
        a.plot(res_m.t, 1e3 * (res_m.xi_d[:, i] - res_m.xi[:, i]), label=label_m)
        a.set_title(f"static mission: {NAMES[i]} error")
        a.set_ylabel(f"{NAMES[i]}_d - {NAMES[i]} [mm]")
        a.set_xlabel("t [s]")
        legend(a)  # below the panel: never over the curves
    res_i, res_r = reach[(2.0, "idc")], reach[(2.0, "mpc")]
    a = ax[1, 0]
    a.plot(res_i.t, res_i.f[:, 0], color="tab:red", label="idc: rotor 1 applied")
    for j in range(4):
        a.plot(res_r.t, res_r.f[:, j], color="tab:blue", lw=1, label="mpc: rotors 1-4 applied" if j == 0 else None)
    for b in (lo, hi):
        a.axhline(b, color="k", ls="--", lw=0.8, label="rotor bounds" if b == lo else None)
    a.set_xlim(0.3, 2.5)
    a.set_title("aggressive reach (climb 2 m in 1 s): rotor thrusts and bounds")
    a.set_ylabel("thrust [N]")
    a.set_xlabel("t [s]")
    legend(a)
    a = ax[1, 1]
    for res, name, c in ((res_i, "idc", "tab:red"), (res_r, "mpc", "tab:blue")):
        a.plot(res.t, res.xi[:, 2], color=c, label=f"{name} z [m]")
        a.plot(res.t, res.xi[:, 7], color=c, ls=":", label=f"{name} theta2 [rad]")
    a.plot(res_r.t, res_r.xi_d[:, 2], "k--", lw=0.8, label="reference")
    a.plot(res_r.t, res_r.xi_d[:, 7], "k--", lw=0.8)
    a.set_title("aggressive reach (climb 2 m): z and theta2")
    a.set_xlabel("t [s]")
    a.set_ylabel("z [m], theta2 [rad]")
    legend(a)
    fig.savefig(path, dpi=90)
    return path


if __name__ == "__main__":
    sys.exit(main())
