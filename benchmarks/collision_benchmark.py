"""Cost of the self-collision filter of the design maps, side by side with the map it filters.

    python benchmarks/collision_benchmark.py [N_SAMPLES]     (default 100000; --quick: 3000, the tests' smoke run)

Per shipped platform: the collision model (pairs checked), the time of the workspace map without the filter and of
the collision check (the coarse-to-fine mask over the same joint grid, ``CollisionModel.colliding_batch``), both
measured in this run, their ratio, the cost per configuration, and the collision-free fraction; the same mask with
the pair screen off (``colliding_batch(..., screen=False)``: every pair of every configuration checked by coal), its
CPU time against the screened one's (measured alternately, best of two each) and whether the two masks are
identical; for grids up to 300000 configurations also the check of every configuration (the reference of the
coarse-to-fine inference) and how many configurations the two disagree on.  Exits 0.
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

import qprr
from qprr.analysis import workspace
from qprr.analysis._common import collision_mask, make_grid
from qprr.analysis.collision import collision_model

PLATFORMS = ("q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")


class Unscreened:
    """A collision model whose batched check has the pair screen off (the reference of the screened check)."""

    def __init__(self, model) -> None:
        self.model = model

    def colliding_batch(self, q_arm):
        return self.model.colliding_batch(q_arm, screen=False)


def screen_ratio(cm, grid) -> str:
    """CPU time of the coarse-to-fine mask with the pair screen off and on (best of two each, alternated)."""
    times: dict[str, list[float]] = {"off": [], "on": []}
    masks = {}
    for _ in range(2):
        for label, model in (("off", Unscreened(cm)), ("on", cm)):
            t = time.process_time()
            masks[label] = collision_mask(model, grid).free
            times[label].append(time.process_time() - t)
    off, on = min(times["off"]), min(times["on"])
    same = "identical" if np.array_equal(masks["off"], masks["on"]) else f"{int((masks['off'] != masks['on']).sum())} configurations DIFFER"
    return f"    pair screen: CPU {off:.2f} s off, {on:.2f} s on (x{off / on:.1f}); masks {same}"


def main(n_samples: int, exact_max: int = 300_000) -> int:
    print(f"load average {os.getloadavg()[0]:.1f} (2 cores); {n_samples} samples per grid")
    for name in PLATFORMS:
        p = qprr.platforms.resolve(name)
        t = time.perf_counter()
        cm = collision_model(p)
        t_build = time.perf_counter() - t
        grid = make_grid(p, n_samples)
        t = time.perf_counter()
        workspace(p, n_samples=n_samples, variants=[], hover=False, collision=False)
        t_map = time.perf_counter() - t
        t = time.perf_counter()
        mask = collision_mask(cm, grid)
        t_coll = time.perf_counter() - t
        t = time.perf_counter()
        exact = ~cm.colliding_arm(grid.configurations()) if grid.size <= exact_max else None
        t_exact = time.perf_counter() - t
        print(
            f"{name}: {len(cm.pairs)} pairs, model built in {t_build:.2f} s; grid {grid.size}: map {t_map:.2f} s, collisions "
            f"{t_coll:.2f} s ({1e6 * t_coll / grid.size:.1f} us/configuration, ratio to the map {t_coll / t_map:.1f}); "
            f"collision-free {100 * mask.free.mean():.2f}%; {mask.describe()}",
            flush=True,
        )
        print(screen_ratio(cm, grid), flush=True)
        if exact is not None:
            print(
                f"    every configuration checked: {t_exact:.2f} s (x{t_exact / t_coll:.1f} the coarse-to-fine check); "
                f"{int((exact != mask.free).sum())} configurations differ",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    args = sys.argv[1:]
    sys.exit(main(3_000 if args == ["--quick"] else int(args[0]) if args else 100_000))
