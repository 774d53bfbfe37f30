"""Receding-horizon MPC (qprr.control.mpc): crocoddyl's native node models against the Python ones, and the MPC against the IDC.

    python benchmarks/mpc_benchmark.py [--window 10] [--duration 30] [--tilt-weights 10,1000] [--no-reach] [--platforms 3,10]
    python benchmarks/mpc_benchmark.py --quick        # a few seconds (tests/test_mpc.py runs it)

Prints the machine (with its load average), then:

1. solve times of the two backends side by side on the first ``--window`` seconds of the static mission
   (Thesis Sec. 6.3.1.4; RK2 nodes, 40 nodes of 10 ms, 100 Hz): median and p95 of the wall and thread-CPU
   time of crocoddyl's ``solve`` (cold first solve left out), iterations, failures, and the ratio Python / native.
   Without a consistent crocoddyl / pinocchio pair the native column is skipped with the fix command;
   without crocoddyl the script says how to install it and exits 0;
2. the whole mission (``--duration``, default 30 s) with the default backend against the IDC: RMSE (6.26) per
   coordinate and ratio, the wall time of the run against the simulated time (target: p95 solve <= 10 ms, so the
   mission runs in real time), and the roll/pitch RMSE of both controllers against one common reference;
3. roll/pitch: the MPC's logged attitude reference is the feedforward tilt (6.17) of the reference acceleration,
   the IDC's is the tilt its own position feedback commands (its attitude loop follows that to micro-radians).
   Row "common" measures both against the feedforward tilt; ``--tilt-weights`` reruns the window with other
   roll/pitch weights to show what weights change;
4. (unless ``--no-reach``) the aggressive reach (scenario ``aggressive-reach``, climb 2 m in 1 s): thrust bounds;
5. (``--platforms 3,10``, the default; '' for none) the generic hover-reach on borinot_flying_arm_2 and
   examples/my_platform for each duration: position RMSE of the IDC (derived gains) and of the default MPC with the
   feedforward tilt of the base's acceleration (``tilt_reference="base"``, before issue 35) and of the whole robot's
   centre of mass (``"system"``, the default), the ratio MPC / IDC (issue 35: within 2), the worst arm joint's
   RMSE ratio and the solves stopped at the iteration limit.

Times are wall-clock on a shared machine: the thread-CPU times are the steadier figure.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py
sys.path.insert(0, str(ROOT))  # this worktree's qprr
from machine import machine_lines  # noqa: E402

import qprr  # noqa: E402
from qprr.control.filters import tilt_6_17  # noqa: E402
from qprr.control.mpc_stats import INSTALL  # noqa: E402
from qprr.errors import MissingDependencyError, QprrError  # noqa: E402
from qprr.sim import SimResult, simulate  # noqa: E402
from qprr.thesis.missions import NAMES, static_mission  # noqa: E402
from qprr.thesis.scenarios import flight_controller  # noqa: E402

COG_WEIGHT = 100.0
"""The CoG-on-axis weight [1/m^2] of the "+ CoG term" row (the term is off by default: docs/mpc.md)."""


def run(platform, ctrl, traj, duration) -> SimResult:
    return simulate(platform, ctrl, traj, duration, progress=sys.stderr.isatty(), scenario="static")


def common_tilt_rmse(res: SimResult, traj, g: float = 9.81, max_tilt: float = 0.8) -> tuple[float, float]:
    """RMSE [rad] of roll and pitch against the feedforward tilt (6.17) of the trajectory's reference acceleration."""
    s = traj.sample(res.t)
    a = s.xi_ddot
    ref = np.array(
        [tilt_6_17(ax, ay, az + g, math.cos(psi), math.sin(psi), max_tilt) for ax, ay, az, psi in zip(a[:, 0], a[:, 1], a[:, 2], s.xi[:, 5])]
    )
    e = res.xi[:, 3:5] - ref
    return tuple(float(v) for v in np.sqrt(np.mean(e**2, axis=0)))


def ratio(a: float, b: float) -> str:
    return f" {a / b:>8.3g}" if b > 0 else f" {'-':>8}"


def solve_line(label: str, st) -> str:
    s = st.summary()
    return (
        f"{label:<22}{1e3 * s['median_solve_s']:>9.2f}{1e3 * s['p95_solve_s']:>9.2f}{1e3 * s['median_solve_cpu_s']:>10.2f}"
        f"{1e3 * s['p95_solve_cpu_s']:>10.2f}{s['median_iterations']:>7.0f}{s['failed']:>7.0f}{s['fallbacks']:>10.0f}"
    )


def section_backends(mpc, platform, traj, window: float, tilt_weights) -> dict:
    """Both backends (and other tilt weights) on the first ``window`` seconds; returns {label: (result, stats)}."""
    print(
        f"\n1. solve time per MPC step, static mission 0-{window:g} s (RK2, {mpc.MPCSettings().horizon} nodes of "
        f"{1e3 / mpc.MPCSettings().rate:g} ms), cold first solve left out"
    )
    head = f"{'backend':<22}{'median':>9}{'p95':>9}{'CPU med':>10}{'CPU p95':>10}{'iters':>7}{'failed':>7}{'fallbacks':>10}   [ms]"
    print(head)
    print("-" * len(head))
    out = {}
    backends = ["native", "python"] if not mpc.NATIVE_PROBLEM else ["python"]
    for backend in backends:
        ctrl = mpc.MPCController(platform, settings=mpc.MPCSettings(backend=backend))
        res = run(platform, ctrl, traj, window)
        out[backend] = (res, ctrl.stats())
        print(solve_line(backend, out[backend][1]))
    if mpc.NATIVE_PROBLEM:
        print(f"native: skipped, crocoddyl's compiled models fail their self-test ({mpc.NATIVE_PROBLEM}); fix: {mpc.FIX}")
    else:
        n, p = out["native"][1].summary(), out["python"][1].summary()
        print(
            f"{'python / native':<22}{p['median_solve_s'] / n['median_solve_s']:>9.2f}{p['p95_solve_s'] / n['p95_solve_s']:>9.2f}"
            f"{p['median_solve_cpu_s'] / n['median_solve_cpu_s']:>10.2f}{p['p95_solve_cpu_s'] / n['p95_solve_cpu_s']:>10.2f}"
        )
        ctrl = mpc.MPCController(platform, settings=mpc.MPCSettings(backend="native"), weights=mpc.MPCWeights(cog=COG_WEIGHT))
        res = run(platform, ctrl, traj, window)
        out["native + CoG term"] = (res, ctrl.stats())
        print(solve_line("native + CoG term", out["native + CoG term"][1]))
    for w in tilt_weights:
        ctrl = mpc.MPCController(platform, weights=mpc.MPCWeights(tilt=w))
        res = run(platform, ctrl, traj, window)
        out[f"tilt weight {w:g}"] = (res, ctrl.stats())
        print(solve_line(f"tilt weight {w:g}", out[f"tilt weight {w:g}"][1]))
    print("-" * len(head))
    return out


def section_mission(mpc, platform, traj, duration: float) -> tuple:
    print(f"\n2. static mission (Sec. 6.3.1.4), {duration:g} s at 1 kHz: default MPC against the IDC")
    t0 = time.perf_counter()
    idc = run(platform, flight_controller("idc", platform), traj, duration)
    idc_wall = time.perf_counter() - t0
    ctrl = mpc.MPCController(platform)
    t0, c0 = time.perf_counter(), time.process_time()
    res = run(platform, ctrl, traj, duration)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    head = f"{'RMSE (6.26)':<12}{'idc':>11}{'mpc':>11}{'ratio':>9}"
    print(head)
    print("-" * len(head))
    e_idc, e = idc.rmse(), res.rmse()
    for name in NAMES:
        print(f"{name:<12}{e_idc[name]:>11.3e}{e[name]:>11.3e}{ratio(e[name], e_idc[name])}")
    ci, cm = common_tilt_rmse(idc, traj), common_tilt_rmse(res, traj)
    for k, name in enumerate(("phi common", "theta common")):
        print(f"{name:<12}{ci[k]:>11.3e}{cm[k]:>11.3e}{ratio(cm[k], ci[k])}")
    print("-" * len(head))
    s = ctrl.stats().summary()
    print(
        f"status idc {idc.status}, mpc {res.status} (backend {ctrl.backend}); solve median {1e3 * s['median_solve_s']:.2f} ms, "
        f"p95 {1e3 * s['p95_solve_s']:.2f} ms (CPU {1e3 * s['median_solve_cpu_s']:.2f} / {1e3 * s['p95_solve_cpu_s']:.2f} ms); "
        f"{s['failed']:.0f} failed, {s['fallbacks']:.0f} fallbacks"
    )
    print(
        f"wall time: mpc {wall:.1f} s for {duration:g} s simulated (ratio {wall / duration:.2f}; target <= ~1), idc {idc_wall:.1f} s; "
        f"load average now {os.getloadavg()[0]:.2f}; CPU time of the mpc run (this process, all threads) {cpu:.1f} s "
        f"(ratio {cpu / duration:.2f}: the wall time on an otherwise idle machine)"
    )
    return idc, res


def section_attitude(runs: dict, traj) -> None:
    print(
        "\n3. roll/pitch against the common feedforward tilt (6.17) and against each run's logged reference, "
        "first window; x, y RMSE for the same runs"
    )
    head = f"{'run':<22}{'phi common':>12}{'theta common':>14}{'phi logged':>12}{'theta logged':>14}{'x':>11}{'y':>11}"
    print(head)
    print("-" * len(head))
    for label, (res, _) in runs.items():
        c, e = common_tilt_rmse(res, traj), res.rmse()
        print(f"{label:<22}{c[0]:>12.3e}{c[1]:>14.3e}{e['phi']:>12.3e}{e['theta']:>14.3e}{e['x']:>11.3e}{e['y']:>11.3e}")
    print("-" * len(head))


def section_reach(platform) -> None:
    from qprr.scenarios import run as run_scenario
    from qprr.thesis.control_scenarios import thrust_margins

    print("\n4. aggressive reach (climb 2 m and 0.6 m forward in 1 s, arm out, 3 s): rotor bounds [N]")
    for cname in ("idc", "mpc"):
        try:
            res = run_scenario("aggressive-reach", cname)
        except QprrError as err:  # the IDC may diverge: the simulator attaches the run so far
            res = err.result
        m, e = thrust_margins(res, platform), res.rmse()
        plan = f", smallest planned margin {res.metrics['mpc_min_plan_thrust_margin_N']:.2g} N" if cname == "mpc" else ""
        print(
            f"{cname}: {res.status}; a rotor clipped on {100 * m['saturated_fraction']:.2f} % of the ticks, asked-for margin "
            f"{m['asked_margin_N']:.3g} N{plan}; RMSE x {e['x']:.2e} m, z {e['z']:.2e} m, theta2 {e['theta2']:.2e} rad"
        )


EXAMPLE = ROOT / "examples" / "my_platform"


def other_platforms() -> dict:
    """The platforms of issue 35's MPC acceptance: borinot and examples/my_platform's quad_rrr."""
    quad = qprr.from_urdf(EXAMPLE / "quad_rrr.urdf", EXAMPLE / "quad_rrr.rotors.toml", ee_frame="gripper")
    return {"borinot_flying_arm_2": qprr.load("borinot_flying_arm_2"), "examples/my_platform": quad}


def position_rmse(res: SimResult) -> float:
    """RMSE [m] of the base position error's norm, sqrt(mean |p_d - p|^2) (tests/test_mpc.py's yardstick)."""
    e = res.xi_d[:, :3] - res.xi[:, :3]
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def section_platforms(durations) -> None:
    """Generic hover-reach (climb 2 m, then the arm 60 % of the way to its upper limits from t = 3 s) on borinot and
    examples/my_platform: position RMSE of the IDC (derived gains) and of the default MPC with each tilt reference
    (``MPCSettings.tilt_reference``: "base", the behaviour before issue 35, and "system", the default), their ratio,
    the worst arm joint's RMSE over the IDC's and the solves stopped at the iteration limit."""
    from qprr.scenarios import run as run_scenario

    print("\n5. hover-reach on other platforms: position RMSE [m] (norm), IDC (derived gains) against the default MPC")
    print(
        f"{'platform':<22}{'duration':>9}{'tilt ref':>9}{'IDC':>11}{'MPC':>11}{'MPC/IDC':>9}{'x':>10}{'psi':>10}"
        f"{'arm/IDC':>9}{'iter-lim':>9}  (x, psi: the MPC's RMSE; arm/IDC: the worst joint's ratio)"
    )
    for name, pf in other_platforms().items():
        for duration in durations:
            idc = run_scenario("hover-reach", "idc", platform=pf, duration=duration)
            r_idc, e_idc = position_rmse(idc), idc.rmse()
            for tilt in ("base", "system"):
                res = run_scenario("hover-reach", "mpc", platform=pf, duration=duration, gains={"mpc": {"settings": {"tilt_reference": tilt}}})
                r, e = position_rmse(res), res.rmse()
                arm = max((e[j] / e_idc[j] for j in pf.arm_names if e_idc[j] > 1e-12), default=float("nan"))
                limit = f"{res.metrics['mpc_iteration_limit']:.0f}/{res.metrics['mpc_solves']:.0f}"
                print(
                    f"{name:<22}{duration:>8g}s{tilt:>9}{r_idc:>11.3e}{r:>11.3e}{ratio(r, r_idc)}{e['x']:>10.2e}{e['psi']:>10.2e}"
                    f"{arm:>9.3g}{limit:>9}"
                )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--window", type=float, default=10.0, help="seconds of the static mission both backends are timed on (default 10)")
    ap.add_argument("--duration", type=float, default=30.0, help="static mission length for the MPC vs IDC run [s] (default 30)")
    ap.add_argument("--tilt-weights", default="1000", help="other MPC roll/pitch weights run on the window (comma list, '' for none)")
    ap.add_argument("--no-reach", action="store_true", help="skip the aggressive reach")
    ap.add_argument(
        "--platforms", default="3,10", help="hover-reach durations [s] flown on borinot and examples/my_platform (comma list, '' for none)"
    )
    ap.add_argument("--quick", action="store_true", help="a few seconds: 0.3 s window and mission, no reach, no extra weights, no platforms")
    args = ap.parse_args(argv)
    if args.quick:
        args.window, args.duration, args.tilt_weights, args.no_reach, args.platforms = 0.3, 0.3, "", True, ""
    print(" | ".join(machine_lines(extra=("crocoddyl",))))
    try:
        import qprr.control.mpc as mpc
    except MissingDependencyError:
        print(f"crocoddyl is not installed: no MPC to measure ({INSTALL})")
        return 0
    platform = qprr.load()
    traj = static_mission()
    weights = [float(w) for w in args.tilt_weights.split(",") if w.strip()]
    runs = section_backends(mpc, platform, traj, args.window, weights)
    section_mission(mpc, platform, traj, args.duration)
    section_attitude(runs, traj)
    if not args.no_reach:
        section_reach(platform)
    durations = [float(d) for d in args.platforms.split(",") if d.strip()]
    if durations:
        section_platforms(durations)
    return 0


if __name__ == "__main__":
    sys.exit(main())
