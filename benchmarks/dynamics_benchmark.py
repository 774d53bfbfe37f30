"""Cost of B, C, G in thesis coordinates: Pinocchio (qprr.model.dynamics_xi) vs the
lambdified sympy Lagrange model (qprr.thesis.symbolic).

    python benchmarks/dynamics_benchmark.py [--states 300] [--reps 20] [--variant thesis|cad] [--quick]

Prints the machine, checks that both implementations agree at every benchmark state,
warms up, then times each variant at N seeded states (each state: mean of ``reps`` calls)
and reports the median and the 5th/95th percentiles over states in microseconds, the
one-off derivation + code-generation time of the sympy model, and sympy/pinocchio ratios.
``--quick``: 10 states x 2 calls, no fresh derivation (the cached model): a smoke run of a few seconds.
Needs sympy (``pip install sympy``); without it, says so and exits 0.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
from machine import machine_lines

from qprr.thesis import load_qprr, params_of


def _states(robot, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    p = params_of(robot)
    out = []
    for _ in range(n):
        xi = np.r_[
            rng.uniform(-5, 5, 3),
            rng.uniform(-np.pi, np.pi),
            rng.uniform(-1.3, 1.3),
            rng.uniform(-np.pi, np.pi),
            rng.uniform(p.lower_limits, p.upper_limits),
        ]
        out.append((xi, rng.uniform(-3, 3, 9)))
    return out


def _time(fn, states, reps: int) -> np.ndarray:
    """Per-state mean call time [us] of fn(xi, xi_dot) over ``reps`` calls."""
    out = np.empty(len(states))
    for i, (xi, w) in enumerate(states):
        t0 = time.perf_counter()
        for _ in range(reps):
            fn(xi, w)
        out[i] = (time.perf_counter() - t0) / reps * 1e6
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--states", type=int, default=300, help="number of seeded random states")
    ap.add_argument("--reps", type=int, default=20, help="calls per state (timed together)")
    ap.add_argument("--variant", default="thesis", choices=["thesis", "cad"])
    ap.add_argument("--seed", type=int, default=2021)
    ap.add_argument("--quick", action="store_true", help="10 states x 2 calls, no fresh derivation (a smoke run)")
    args = ap.parse_args(argv)
    if args.quick:
        args.states, args.reps = 10, 2
    try:
        import sympy  # noqa: F401
    except ImportError:
        print("dynamics_benchmark: sympy is not installed (pip install sympy, or pip install 'qprr[symbolic]'); nothing measured")
        return 0

    import pinocchio as pin

    from qprr import charts as co
    from qprr import dynamics as qd
    from qprr.thesis import symbolic as sy

    print("machine")
    for line in machine_lines(("sympy",)):
        print(f"  {line}")

    robot = load_qprr(args.variant)
    data = robot.data()

    # one-off costs: a fresh derivation + code generation (no cache), then the cached path
    if not args.quick:
        t0 = time.perf_counter()
        src = sy._generate(params_of(robot))
        t_derive = time.perf_counter() - t0
        t0 = time.perf_counter()
        compile(src, "<bench>", "exec")
        t_compile = time.perf_counter() - t0
        print(
            f"\nsympy model ({args.variant}): derivation + CSE code generation {t_derive:.2f} s (fresh, in-process), "
            f"compile {t_compile * 1e3:.1f} ms, {len(src) / 1024:.0f} KiB of generated code"
        )
    sm = sy.symbolic_model(params_of(robot))
    print(
        f"  symbolic_model() setup: {sm.setup_seconds * 1e3:.1f} ms "
        f"({'read from the disk cache' if sm.from_disk_cache else 'derived, now written to the disk cache'})"
    )

    states = _states(robot, args.states, args.seed)

    # correctness first
    worst = {"B": 0.0, "C": 0.0, "G": 0.0}
    for xi, w in states:
        for name, a, b in zip("BCG", qd.dynamics_xi(robot, data, xi, w), sm.dynamics(xi, w)):
            worst[name] = max(worst[name], float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300)))
    print(f"\nagreement at {len(states)} states (max relative Frobenius error): " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))
    if max(worst.values()) > 1e-9:
        print("FAILED: the implementations disagree; not timing")
        return 1

    model = robot.model

    def pin_bcg(xi, w):
        return qd.dynamics_xi(robot, data, xi, w)

    def pin_bg_xi(xi, w):  # B = S^T M S, G = S^T g in thesis coordinates
        q = co.xi_to_q(xi)
        S = co.rate_map(xi)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        return S.T @ M @ S, S.T @ pin.computeGeneralizedGravity(model, data, q)

    qs = {id(xi): co.xi_to_q(xi) for xi, _ in states}

    def pin_bg_raw(xi, w):  # crba + gravity on a ready q (Pinocchio coordinates, no conversion)
        q = qs[id(xi)]
        return pin.crba(model, data, q), pin.computeGeneralizedGravity(model, data, q)

    def sym_bcg(xi, w):
        return sm.dynamics(xi, w)

    def sym_bg(xi, w):
        return sm.B(xi), sm.G(xi)

    raw = sm._ns["dynamics"]

    def sym_raw(xi, w):  # the generated function alone (no numpy assembly, no Christoffel sum)
        return raw(*xi.tolist())

    cases = [
        ("pinocchio dynamics_xi  B, C, G", pin_bcg),
        ("pinocchio B + G, xi coords (crba + gravity)", pin_bg_xi),
        ("pinocchio crba + gravity on q (no xi map)", pin_bg_raw),
        ("sympy     B, C, G (SymbolicModel.dynamics)", sym_bcg),
        ("sympy     B + G (SymbolicModel.B, .G)", sym_bg),
        ("sympy     generated B, dB/dxi, G only", sym_raw),
    ]
    for _, fn in cases:  # warm up
        _time(fn, states[:20], 5)
    results = {}
    print(f"\ntiming: {len(states)} states x {args.reps} calls, per-call time over states [us]")
    print(f"  {'':46s} {'median':>8s} {'p5':>8s} {'p95':>8s}")
    for name, fn in cases:
        t = _time(fn, states, args.reps)
        results[name] = float(np.median(t))
        print(f"  {name:46s} {np.median(t):8.1f} {np.percentile(t, 5):8.1f} {np.percentile(t, 95):8.1f}")

    names = [n for n, _ in cases]
    print("\nratios (sympy / pinocchio, medians)")
    print(f"  ratio B, C, G : {results[names[3]] / results[names[0]]:.2f}")
    print(f"  ratio B + G   : {results[names[4]] / results[names[1]]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
