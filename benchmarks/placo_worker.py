"""PlaCo's side of benchmarks/ik_benchmark.py, run by the Python of PlaCo's own environment (never imports qprr).

    <placo-venv>/bin/python benchmarks/placo_worker.py IN.npz OUT.npz

PlaCo 0.10.2 pins pin == 3.8.0 and cannot share qprr's environment (pin 4.0): ik_benchmark.py writes the problem
(the hover chain's URDF file, its end-effector frame, the targets and the guesses, the tolerance, the repetitions and
the clock) to IN.npz, this script solves it with PlaCo's KinematicsSolver and writes the configurations it returns,
its step counts and its times to OUT.npz; ik_benchmark.py then checks every configuration independently, as for
every other solver.  Protocol as in ik_benchmark.py: a correctness pass over every target (reachable and
unreachable), then a warm-up on the first 10 and the timing pass with the garbage collector off, the minimum of
``reps`` runs per target (one run when a solve takes more than 1 ms), this thread's CPU time (or wall time).

The solve: the hover chain's base is fixed to the world (``mask_fbase``), one frame task on the end effector (PlaCo's
"soft" priority, weight 1, position and orientation weights 1), joint limits on (PlaCo's default), full steps
(``solve(True)`` applies each step as a whole), stopped on the benchmark's own criterion (position error and
orientation angle below ``tol``) or after 100 steps.
"""

from __future__ import annotations

import gc
import math
import sys
import time
from importlib.metadata import version

import numpy as np
import placo


def pose_errors(T: np.ndarray, T_d: np.ndarray) -> tuple[float, float]:
    """(||p - p_d|| [m], angle of R_d^T R [rad]) from sine and cosine (accurate near 0 and pi)."""
    N = T_d[:3, :3].T @ T[:3, :3]
    sin = 0.5 * math.sqrt((N[2, 1] - N[1, 2]) ** 2 + (N[0, 2] - N[2, 0]) ** 2 + (N[1, 0] - N[0, 1]) ** 2)
    return float(np.linalg.norm(T[:3, 3] - T_d[:3, 3])), math.atan2(sin, 0.5 * (np.trace(N) - 1.0))


class Solver:
    """One PlaCo robot and solver for every target (built once, as an application would)."""

    def __init__(self, urdf: str, frame: str, tol: float) -> None:
        self.robot = placo.RobotWrapper(urdf, placo.Flags.ignore_collisions)
        self.solver = placo.KinematicsSolver(self.robot)
        self.solver.mask_fbase(True)
        self.task = self.solver.add_frame_task(frame, np.eye(4))
        self.task.configure("end_effector", "soft", 1.0, 1.0)
        self.frame, self.tol = frame, tol

    def solve(self, T_d: np.ndarray, h0: np.ndarray) -> tuple[np.ndarray, int]:
        robot = self.robot
        robot.state.q = np.concatenate([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0], h0])
        robot.update_kinematics()
        self.task.T_world_frame = T_d
        for it in range(100):  # noqa: B007 (the count is reported)
            pe, oe = pose_errors(robot.get_T_world_frame(self.frame), T_d)
            if pe < self.tol and oe < self.tol:
                break
            self.solver.solve(True)
            robot.update_kinematics()
        return robot.state.q[7:].copy(), it


def main(argv: list[str]) -> int:
    src, dst = argv
    job = np.load(src)
    solver = Solver(str(job["urdf"]), str(job["frame"]), float(job["tol"]))
    clock = time.thread_time if str(job["clock"]) == "cpu" else time.perf_counter
    targets, guesses = job["targets"], job["guesses"]
    out = [solver.solve(T, h0) for T, h0 in zip(targets, guesses)]
    out_u = [solver.solve(T, h0) for T, h0 in zip(job["unreach_targets"], job["unreach_guesses"])]

    def once(k: int) -> float:
        t0 = clock()
        solver.solve(targets[k], guesses[k])
        return clock() - t0

    n_warm = min(10, len(targets))
    for k in range(n_warm):
        once(k)
    reps = 1 if np.median([once(k) for k in range(n_warm)]) > 1e-3 else int(job["reps"])
    gc.disable()
    try:
        times = [min(once(k) for _ in range(reps)) for k in range(len(targets))]
    finally:
        gc.enable()
    n_chain = guesses.shape[1]
    np.savez(
        dst,
        q=np.array([q for q, _ in out]).reshape(-1, n_chain),
        iterations=np.array([it for _, it in out], dtype=float),
        q_unreach=np.array([q for q, _ in out_u]).reshape(-1, n_chain),
        times=np.array(times),
        reps=reps,
        version=version("placo"),
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
