"""Throughput of the design maps (qprr.analysis): batched numpy against a plain Python loop over Pinocchio calls.

    python benchmarks/analysis_benchmark.py [--platform q-prr] [--samples 1000000] [--loop 5000] [--reps 3]

For each map the same per-configuration work is timed two ways in one run:

* **batched**: :class:`qprr.analysis.ArmChain` (forward kinematics as products of the joint
  transforms read from the Pinocchio model, entries that are constant kept as scalars) and the
  map's own vectorised algebra, over ``--samples`` configurations in chunks;
* **loop**: the same quantities from Pinocchio, one configuration at a time in Python
  (``framesForwardKinematics``, ``centerOfMass``, ``computeFrameJacobian``,
  ``computeGeneralizedGravity``...) followed by the same numpy algebra on that one
  configuration, over ``--loop`` configurations (its rate is extrapolated).

Both paths are checked against each other first (largest difference printed).  Times are the
minimum over ``--reps`` repetitions (the run least disturbed by other processes).  Then the
default ``qprr analyze workspace`` end to end (a child process, imports included, best of ``--reps``
runs; wall and CPU time, with and without the collision-free part) against issue 24's target of 5 s on an idle
2-core machine, and where the map's CPU time goes (forward kinematics, measure in B, hover
volume, collision check, the two collision-free measures); then the other maps.  The load
average is printed with the machine: on a shared machine every wall time grows, the CPU time
is the closer estimate of the idle wall time.
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the qprr of this checkout, not an installed one
import qprr
from qprr.analysis import ArmChain, cog_regions, hover, make_grid, opspace_map, singularity, wrench_set
from qprr.analysis import capacity as capacity_map
from qprr.analysis.hover import payload_limits
from qprr.analysis.singularity import system_det

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
from machine import machine_lines


def best_time(fn, reps: int) -> float:
    out = []
    for _ in range(reps):
        gc.collect()
        gc.disable()
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
        gc.enable()
    return min(out)


def batched(chain, grid, fid, what: str, W=None, eff=None, g=None):
    res = []
    for _, q in grid.chunks():
        pose = chain.pose(q)
        if what == "workspace":
            res.append(chain.frame_position(pose, fid))
        elif what == "cog":
            res.append(chain.com(pose))
        elif what == "singularity":
            J = chain.jacobian(pose, fid)
            p = chain.frame_position(pose, fid)
            res.append(np.column_stack([system_det(J, p), np.linalg.svd(J, compute_uv=False)]))
        elif what == "hover":
            st = chain.statics(pose, fid)
            w = st.wrench0
            res.append(np.column_stack([W.thrust_margin(w), W.authority(w).min(axis=2)]))
        elif what == "capacity":
            st = chain.statics(pose, fid)
            pl = payload_limits(st, W, eff, g)
            res.append(np.column_stack([pl.rotors, pl.effort]))
    return np.concatenate(res)


def looped(p, qs, fid, what: str, W=None, eff=None):
    model, data = p.model, p.data()
    q = pin.neutral(model)
    out = []
    if what == "capacity":  # the payload's wrench per kilogram: a second model with 1 kg at the end effector
        m1 = pin.Model(model)
        f = model.frames[fid]
        m1.inertias[f.parentJoint] = m1.inertias[f.parentJoint] + pin.Inertia(1.0, f.placement.translation, np.zeros((3, 3)))
        d1 = m1.createData()
    for row in qs:
        q[7:] = row
        if what == "workspace":
            pin.framesForwardKinematics(model, data, q)
            out.append(data.oMf[fid].translation.copy())
        elif what == "cog":
            out.append(pin.centerOfMass(model, data, q).copy())
        elif what == "singularity":
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)[:, 6:]
            pe = data.oMf[fid].translation
            out.append(np.concatenate([system_det(J[None], pe[None]), np.linalg.svd(J, compute_uv=False)]))
        elif what == "hover":
            w = pin.computeGeneralizedGravity(model, data, q)[0:6]
            out.append(np.concatenate([W.thrust_margin(w[None]), W.authority(w[None]).min(axis=2)[0]]))
        elif what == "capacity":
            g0 = pin.computeGeneralizedGravity(model, data, q).copy()
            g1 = pin.computeGeneralizedGravity(m1, d1, q) - g0
            lo, hi = W.ray(g0[None, 0:6], g1[0:6])
            a, b = g0[6:], g1[6:]
            with np.errstate(divide="ignore", invalid="ignore"):
                lim = np.where(np.abs(b) > 1e-15, (eff - a * np.sign(b)) / np.abs(b), np.inf)
            out.append(np.array([hi[0], lim.min()]))
    return np.array(out)


TARGET_S = 5.0
"""Issue 24: the default ``qprr analyze workspace`` (1e6 configurations per region) within 5 s on an idle 2-core machine."""


def command_time(argv: list[str]) -> tuple[float, float]:
    """(wall [s], CPU time [s] user + system) of ``python -m qprr analyze ...`` in a child process, imports included."""
    import os
    import resource
    import subprocess

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).resolve().parents[1]), os.environ.get("PYTHONPATH")]))}
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "qprr", "analyze", *argv], check=True, capture_output=True, env={**env, "MPLBACKEND": "Agg"})
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def workspace_stages(p, n: int) -> dict[str, float]:
    """CPU time [s] of each stage of the default workspace map, summed over its regions: the same calls as
    :func:`qprr.analysis.workspace` (forward kinematics, measure in B, hover volume, collision check, the two
    collision-free measures, taken with the whole ones in one pass), timed one by one (what is left: the affine hull, outlines and boundaries)."""
    from qprr.analysis._common import affine_span, collision_mask, resolve_collision
    from qprr.analysis.voxels import CellImage
    from qprr.analysis.workspace import default_variants, hover_profile

    chain, fid = ArmChain(p), p.ee_frame
    out: dict[str, float] = {}

    def timed(stage: str, fn, *args, **kwargs):
        t0 = time.process_time()
        r = fn(*args, **kwargs)
        out[stage] = out.get(stage, 0.0) + time.process_time() - t0
        return r

    cmodel, _ = timed("collision check", resolve_collision, p, None)
    for locked in [{}] + default_variants(p):
        g = make_grid(p, n, locked)
        pts = timed("forward kinematics", lambda grid: np.concatenate([chain.frame_position(chain.pose(q), fid) for _, q in grid.chunks()]), g)
        o, B = affine_span(pts)
        shape = tuple(s for s in g.shape if s > 1)
        image = CellImage(((pts - o) @ B.T).reshape(*shape, B.shape[0]))
        hover_image = CellImage(hover_profile(pts, o, B).reshape(*shape, 2), revolve=True)
        if cmodel is None:
            timed("measure in B", image.estimate, return_occupancy=True)
            timed("hover volume", hover_image.estimate, return_occupancy=True)
        else:  # each image's two measures (all configurations, collision-free) from one counting pass, as the map does
            valid = timed("collision check", collision_mask, cmodel, g).free.reshape(shape)
            timed("measure in B (all + collision-free)", image.estimate_pair, valid, return_occupancy=True)
            timed("hover volume (all + collision-free)", hover_image.estimate_pair, valid, return_occupancy=True)
    return out


def end_to_end(p, n: int, name: str, reps: int) -> None:
    """The default command against the 5 s target, with and without the collision-free part (each the best of ``reps``
    runs, wall and CPU time apart), and the stage split."""
    import os

    print(
        f"\nend to end: `qprr analyze workspace --platform {name} --samples {n}` (child process, imports included; best of "
        f"{reps} runs; target {TARGET_S:g} s on an idle 2-core machine; on a loaded machine the CPU time is the closer estimate "
        "of the idle wall time):\n"
    )
    print("| collision-free part | wall [s] | wall / target | CPU [s] | CPU / target | load average |")
    print("|---|---:|---:|---:|---:|---:|")
    for choice in ("auto", "off"):
        runs = [command_time(["workspace", "--platform", name, "--samples", str(n), "-q", "--collision", choice]) for _ in range(reps)]
        wall, cpu = min(r[0] for r in runs), min(r[1] for r in runs)
        label = "auto (default: on when the platform has a collision model)" if choice == "auto" else "off"
        print(f"| {label} | {wall:.2f} | {wall / TARGET_S:.2f} | {cpu:.2f} | {cpu / TARGET_S:.2f} | {os.getloadavg()[0]:.1f} |")
    stages = workspace_stages(p, n)
    total = sum(stages.values())
    print(
        f"\nstages of the map (CPU time of this process, every region; imports and the summary not included): {total:.2f} s "
        "(measure in B and hover volume include building the grid's cell zonotopes and, with a collision model, the collision-free "
        "measure counted on the same grids)\n"
    )
    print("| stage | CPU [s] | share |")
    print("|---|---:|---:|")
    for stage, t in stages.items():
        print(f"| {stage} | {t:.2f} | {100 * t / total:.0f} % |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--platform", default="q-prr")
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--loop", type=int, default=5000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="small sizes (seconds): the smoke run of tests/test_benchmarks.py")
    args = ap.parse_args(argv)
    if args.quick:
        args.samples, args.loop, args.reps = 20_000, 300, 1
    scale = 0.02 if args.quick else 1.0

    def sized(m: int) -> int:
        return max(2_000, int(m * scale))

    for line in machine_lines(("scipy",)):
        print(line)
    p = qprr.build(args.platform) if args.platform.isupper() else qprr.load(args.platform)
    print(f"platform {p!r}\n")
    chain = ArmChain(p)
    fid = p.ee_frame
    W = wrench_set(p)
    eff = np.array(p.arm_effort_limits)
    grid = make_grid(p, args.samples)
    rng = np.random.default_rng(0)
    sub = grid.configurations()[rng.choice(grid.size, args.loop, replace=False)]
    print(f"kernels: {grid.size} configurations batched, {len(sub)} in the Pinocchio loop (rate extrapolated)\n")
    print("| map | batched [s] | batched [configs/s] | Pinocchio loop [configs/s] | ratio | max difference |")
    print("|---|---:|---:|---:|---:|---:|")
    ratios = []
    for what in ("workspace", "cog", "singularity", "hover", "capacity"):
        ref = looped(p, sub, fid, what, W, eff)
        # same configurations batched, to compare values
        mine = []
        for start in range(0, len(sub), 4096):
            q = sub[start : start + 4096]
            pose = chain.pose(q)
            if what == "workspace":
                mine.append(chain.frame_position(pose, fid))
            elif what == "cog":
                mine.append(chain.com(pose))
            elif what == "singularity":
                J = chain.jacobian(pose, fid)
                mine.append(np.column_stack([system_det(J, chain.frame_position(pose, fid)), np.linalg.svd(J, compute_uv=False)]))
            elif what == "hover":
                w = chain.statics(pose, fid).wrench0
                mine.append(np.column_stack([W.thrust_margin(w), W.authority(w).min(axis=2)]))
            else:
                pl = payload_limits(chain.statics(pose, fid), W, eff, p.g)
                mine.append(np.column_stack([pl.rotors, pl.effort]))
        mine = np.concatenate(mine)
        fin = np.isfinite(ref) & np.isfinite(mine)
        diff = float(np.abs(mine[fin] - ref[fin]).max()) if fin.any() else 0.0
        assert np.array_equal(np.isfinite(ref), np.isfinite(mine)), what
        t_loop = best_time(lambda w=what: looped(p, sub, fid, w, W, eff), 1)
        t_b = best_time(lambda w=what: batched(chain, grid, fid, w, W, eff, p.g), args.reps)
        rb, rl = grid.size / t_b, len(sub) / t_loop
        print(f"| {what} | {t_b:.3f} | {rb:,.0f} | {rl:,.0f} | {rb / rl:.1f} | {diff:.1e} |")
        ratios.append(rb / rl)
    print(f"\nratio batched / Pinocchio loop (configurations per second): {min(ratios):.1f} to {max(ratios):.1f}")
    end_to_end(p, args.samples, args.platform, args.reps)
    print("\nother maps (default options of `qprr analyze`, one run each):\n")
    print("| map | configurations | wall [s] | where the time goes |")
    print("|---|---:|---:|---|")
    for name, fn, nn in [
        ("cog regions (2 payloads)", lambda: cog_regions(p, n_samples=sized(200_000), payload_masses=[0.0, 0.5]), sized(200_000)),
        ("singularity", lambda: singularity(p, n_samples=sized(200_000)), sized(200_000)),
        ("hover (6 payloads)", lambda: hover(p, n_samples=sized(100_000), payload_masses=[0, 0.25, 0.5, 1, 1.5, 2]), sized(100_000)),
        ("capacity", lambda: capacity_map(p, n_samples=sized(200_000)), sized(200_000)),
        ("opspace (Pinocchio per configuration)", lambda: opspace_map(p, n_samples=sized(10_000)), sized(10_000)),
    ]:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        print(f"| {name} | {nn:,} | {dt:.2f} | {nn / dt:,.0f} configurations/s |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
