"""Solve statistics of the receding-horizon MPC, readable without crocoddyl (the CLI prints them).

:class:`MPCStats` is the per-solve log :meth:`qprr.control.mpc.MPCController.stats` returns;
:func:`health_warnings` says when a completed run's MPC was not healthy (iteration limit hit too often, chattering
inputs: :func:`chatter_fraction`);
:func:`solve_summary` turns the ``mpc_*`` metrics the controller copies into a
:class:`~qprr.sim.SimResult` into one report line (``qprr simulate ... --controller mpc`` prints it).
``INSTALL`` is the install command of the ``mpc`` extra (docs/mpc.md, "Installing").
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

INSTALL = 'pip install "qprr[mpc]"  (crocoddyl 3.2.1 with pin 4.0.x, the pair its wheel is built for; docs/mpc.md)'

BACKENDS = ("native", "python")
"""Node models of the MPC: crocoddyl's compiled models ("native") or the Python reference models ("python")."""


class SolveStatus(str, Enum):
    """Outcome of one MPC solve (see the module docstring of :mod:`qprr.control.mpc`)."""

    CONVERGED = "converged"
    ITERATION_LIMIT = "iteration-limit"
    FAILED = "failed"


class Fallback(str, Enum):
    """What the controller applies after a failed solve."""

    PREVIOUS_PLAN = "previous-plan"
    HOVER = "hover"


@dataclass
class MPCStats:
    """Per-solve log of a run: one entry per MPC period.

    ``backend``: the node models used (:data:`BACKENDS`); ``t`` [s] solve instants; ``solve_time`` [s]
    wall time of crocoddyl's ``solve``; ``solve_cpu`` [s] the CPU time of this thread during it (less
    sensitive to a loaded machine); ``step_time`` [s] wall time of the whole MPC update (references,
    shift, solve, checks); ``iterations``; ``status`` (:class:`SolveStatus` values); ``cost``; ``gap``
    dynamic infeasibility after the solve; ``thrust_margin`` [N] min over the plan of the distance of
    every planned thrust to its nearest bound (negative: a bound exceeded); ``fallback`` ("" or a
    :class:`Fallback` value); ``u`` (n, nu) the control applied from each solve on (rotor thrusts [N],
    then arm efforts).
    """

    backend: str
    t: np.ndarray
    solve_time: np.ndarray
    solve_cpu: np.ndarray
    step_time: np.ndarray
    iterations: np.ndarray
    status: tuple[str, ...]
    cost: np.ndarray
    gap: np.ndarray
    thrust_margin: np.ndarray
    fallback: tuple[str, ...]
    u: np.ndarray

    def summary(self, skip_first: bool = True) -> dict[str, float]:
        """Median and 95th percentile of the solve time [s] (the cold first solve left out by default), counts.

        ``native_backend`` is 1.0 when crocoddyl's compiled models were used, 0.0 for the Python models.
        """
        sel = slice(1, None) if skip_first and len(self.t) > 1 else slice(None)
        st, cpu = self.solve_time[sel], self.solve_cpu[sel]

        def stat(fn, a):
            return float(fn(a)) if a.size else float("nan")

        return {
            "solves": float(len(self.t)),
            "native_backend": float(self.backend == "native"),
            "median_solve_s": stat(np.median, st),
            "p95_solve_s": stat(lambda a: np.percentile(a, 95), st),
            "max_solve_s": stat(np.max, st),
            "median_solve_cpu_s": stat(np.median, cpu),
            "p95_solve_cpu_s": stat(lambda a: np.percentile(a, 95), cpu),
            "median_iterations": stat(np.median, self.iterations[sel]),
            "converged": float(sum(s == SolveStatus.CONVERGED.value for s in self.status)),
            "iteration_limit": float(sum(s == SolveStatus.ITERATION_LIMIT.value for s in self.status)),
            "failed": float(sum(s == SolveStatus.FAILED.value for s in self.status)),
            "fallbacks": float(sum(bool(f) for f in self.fallback)),
            "min_thrust_margin_N": stat(np.min, self.thrust_margin),
        }


CHATTER_JUMP = 0.25
"""A chatter event: an input channel's change between consecutive solves reverses its sign while both changes exceed
this fraction of the channel's bound range (u_ub - u_lb), e.g. an arm effort thrown from one bound to the other and back."""


def chatter_fraction(u: np.ndarray, u_lb: np.ndarray, u_ub: np.ndarray) -> float:
    """Fraction of the solves (after the first two) at which some input channel chatters (:data:`CHATTER_JUMP`).

    ``u`` (n, nu) the inputs applied from each solve on (rotor thrusts [N], then arm efforts); ``u_lb``, ``u_ub``
    (nu,) their finite bounds.  A smooth run gives 0; bang-bang inputs that switch every solve give 1.
    """
    if len(u) < 3:
        return 0.0
    jump = CHATTER_JUMP * (np.asarray(u_ub, dtype=float) - np.asarray(u_lb, dtype=float))
    du = np.diff(np.asarray(u, dtype=float), axis=0)  # (n - 1, nu) change of each input between consecutive solves
    reversal = (du[1:] * du[:-1] < 0.0) & (np.abs(du[1:]) > jump) & (np.abs(du[:-1]) > jump)
    return float(np.mean(np.any(reversal, axis=1)))


def health_warnings(stats: MPCStats, u_lb: np.ndarray, u_ub: np.ndarray, limits: tuple[float, float]) -> tuple[str, ...]:
    """Sentences on a run whose MPC was not healthy although it completed.

    ``limits`` = (largest fraction of solves stopped at the iteration limit, largest :func:`chatter_fraction`)
    tolerated, :class:`~qprr.control.mpc.MPCSettings`' ``warn_iteration_limit`` and ``warn_chatter``.
    """
    found = []
    n = len(stats.status)
    at_limit = sum(s == SolveStatus.ITERATION_LIMIT.value for s in stats.status) / n if n else 0.0
    if at_limit > limits[0]:
        found.append(
            f"{100 * at_limit:.1f} % of the MPC's solves stopped at the iteration limit (more than {100 * limits[0]:g} %): "
            "raise MPCSettings.max_iter or lower the rate, or check the weights"
        )
    chatter = chatter_fraction(stats.u, u_lb, u_ub)
    if chatter > limits[1]:
        found.append(
            f"the MPC's inputs chattered on {100 * chatter:.1f} % of its solves (more than {100 * limits[1]:g} %: an input's change "
            f"reversed with jumps above {CHATTER_JUMP:g} of its range): raise the input weights (MPCWeights.thrust, arm_acceleration) "
            "or the horizon"
        )
    return tuple(found)


def solve_summary(metrics: dict[str, float]) -> str | None:
    """One line on the MPC's solves from a result's ``mpc_*`` metrics (None when the run had no MPC).

    Times in ms (the cold first solve left out of median and p95), iteration and status counts,
    fallbacks, and which node models were used.
    """
    if "mpc_solves" not in metrics:
        return None
    m = metrics
    backend = "crocoddyl's native models" if m["mpc_native_backend"] == 1.0 else "Python models (qprr.control.mpc_reference)"
    return (
        f"mpc ({backend}): {m['mpc_solves']:.0f} solves, solve time median {1e3 * m['mpc_median_solve_s']:.2f} ms, "
        f"p95 {1e3 * m['mpc_p95_solve_s']:.2f} ms (thread CPU median {1e3 * m['mpc_median_solve_cpu_s']:.2f} ms, "
        f"p95 {1e3 * m['mpc_p95_solve_cpu_s']:.2f} ms); median {m['mpc_median_iterations']:.0f} iterations; "
        f"{m['mpc_converged']:.0f} converged, {m['mpc_iteration_limit']:.0f} at the iteration limit, {m['mpc_failed']:.0f} failed, "
        f"{m['mpc_fallbacks']:.0f} fallbacks"
    )


__all__ = ["BACKENDS", "CHATTER_JUMP", "INSTALL", "Fallback", "MPCStats", "SolveStatus", "chatter_fraction", "health_warnings", "solve_summary"]
