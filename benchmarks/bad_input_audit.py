"""Bad-input audit (issue 16): how a qprr tree answers bad input, counted per category.

    python benchmarks/bad_input_audit.py                       # this tree
    python benchmarks/bad_input_audit.py --old /tmp/old         # and an old tree, side by side
    python benchmarks/bad_input_audit.py --quick               # qprr.charts' cases and two scenarios: a smoke run
    (git -C /work/main archive main | tar -x -C /tmp/old makes the old tree)

Two sets of cases, both run in child interpreters (a case that kills the interpreter is a crash):

* the catalogue (tests/catalogue.py): every public callable fed wrong shapes, dtypes, NaN, inf,
  empty, None, unknown names, bad files... (the engine reads only names, so it also walks an old
  tree; its "robot" parameter is the old qprr.model.Robot);
* the issue's scenarios: the silent wrong answers and crashes issue 16 lists by number, each
  written against both APIs (the current one and the old main's).

Categories: ``silent`` (a wrong answer returned: no error; a catalogue case the allow-list
documents as a valid result is counted apart), ``crash`` (the interpreter died), ``unclear`` (an
error that does not say which argument, or not a qprr error), ``good`` (a qprr error naming the
argument, or the right answer for a scenario).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent
CATEGORIES = ("silent", "crash", "unclear", "good", "allowed")

_CHILD = r"""
import importlib.util, json, sys
spec = importlib.util.spec_from_file_location("catalogue", sys.argv[1])
cat = importlib.util.module_from_spec(spec)
sys.modules["catalogue"] = cat
spec.loader.exec_module(cat)
start_at, out = int(sys.argv[2]), open(sys.argv[3], "a", buffering=1)

def on_start(i):
    out.write(json.dumps({"start": i}) + "\n")

def on_outcome(i, o):
    out.write(json.dumps({"index": i, "target": o.target, "param": o.param, "label": o.label, "verdict": o.verdict,
                          "detail": o.detail[:200]}) + "\n")

prefix = sys.argv[4]
include = (lambda t: t.module == prefix or t.module.startswith(prefix + ".")) if prefix else None
rep = cat.run(include=include, hooks=cat._Hooks(start_at=start_at, on_start=on_start, on_outcome=on_outcome))
out.write(json.dumps({"done": True, "fed": len({o.target for o in rep.outcomes}), "not_fed": len(rep.not_fed),
                      "baseline_failed": len(rep.baseline_failed)}) + "\n")
"""


def catalogue(tree: Path, timeout: float, module: str = "") -> tuple[Counter, dict, list]:
    """Run the catalogue on ``tree`` in child processes; a child that dies marks its current case as a crash and the next
    child resumes after it.  ``module``: only the callables of this module (and its submodules); "": all."""
    counts, info, crashes = Counter(), {}, []
    env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "log.jsonl"
        start_at = 0
        t0 = time.perf_counter()
        while True:
            proc = subprocess.run(
                [sys.executable, "-c", _CHILD, str(HERE / "tests" / "catalogue.py"), str(start_at), str(log), module],
                cwd=tmp,
                env=env,
                capture_output=True,
                text=True,
                timeout=timeout,
            )
            lines = [json.loads(ln) for ln in log.read_text().splitlines() if ln.strip()]
            if lines and "done" in lines[-1]:
                info = lines[-1]
                break
            started = [ln["start"] for ln in lines if "start" in ln]
            if not started or started[-1] <= start_at:
                raise RuntimeError(f"the catalogue child failed before any case (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
            crashes.append((started[-1], proc.returncode))
            start_at = started[-1]
            log.open("a").write(
                json.dumps(
                    {"index": start_at, "verdict": "crash", "target": "?", "param": "?", "label": "?", "detail": f"exit code {proc.returncode}"}
                )
                + "\n"
            )
        outcomes = [ln for ln in lines if "verdict" in ln]
        info["seconds"] = time.perf_counter() - t0
    for o in outcomes:
        counts[o["verdict"] if o["verdict"] != "hang" else "silent"] += 1
    return counts, info, [o for o in outcomes if o["verdict"] in ("silent", "crash", "unclear", "hang")]


# ------------------------------------------------------------------------ the scenarios
# Each prints one verdict word; the API of the tree decides which branch runs (new: qprr.model; old: qprr.model).
_PRELUDE = r"""
import copy, math, pickle, sys, threading
import numpy as np, pinocchio as pin
import qprr
NEW = __import__("importlib").util.find_spec("qprr.model") is not None
if NEW:
    import qprr.thesis
    P = qprr.thesis.load_qprr(); DATA = P.data()
    from qprr.charts import xi_to_q, euler_to_rotation, rotation_to_euler
    from qprr import kinematics as kin
else:
    from qprr import model as kin
    P = kin.load(); DATA = P.model.createData()
    from qprr.coordinates import xi_to_q, euler_to_rotation, rotation_to_euler
from qprr.errors import QprrError
def verdict(fn, names=()):
    try:
        ok = fn()
    except QprrError as e:
        print("good" if (not names or any(n in str(e) for n in names)) else "unclear")
    except Exception as e:
        print("unclear")
    else:
        print("good" if ok else "silent")
"""

SCENARIOS = {
    "1 rmse wraps a yaw error across +-pi": r"""
def f():
    from qprr.sim import SimResult
    m, n = 101, 9
    t = np.linspace(0, 1, m); z = np.zeros((m, n)); xi = z.copy(); xd = z.copy()
    psi = np.pi - 0.5 + t
    xi[:, 5] = (psi + np.pi) % (2 * np.pi) - np.pi; xd[:, 5] = psi + 1e-6
    kw = dict(scenario="s", controller="c", dt=0.01, integrator="euler", t=t, xi=xi, xi_dot=z, xi_d=xd, xi_dot_d=z, u=z,
              f=np.zeros((m, 4)), arm_effort=np.zeros((m, 3)), x_cm=np.zeros((m, 3)), unallocated=z, flags=np.zeros(m, dtype=np.int8),
              u_ext=z)
    import inspect
    kw = {k: v for k, v in kw.items() if k in inspect.signature(SimResult).parameters}
    return abs(SimResult(**kw).rmse()["psi"] - 1e-6) < 1e-9
verdict(f)
""",
    "2 a NaN link mass in the parameters": r"""
def f():
    mod = __import__("qprr.thesis.params" if NEW else "qprr.params", fromlist=["x"])
    p = mod.thesis_params().with_changes(multirotor_mass=float("nan"))
    return False
verdict(f, ("mass",))
""",
    "2 zero thrust factor": r"""
def f():
    mod = __import__("qprr.thesis.params" if NEW else "qprr.params", fromlist=["x"])
    mod.thesis_params().with_changes(thrust_factor=0.0)
    return False
verdict(f, ("thrust_factor",))
""",
    "3 parameters contradicting the URDF (d3 = 0.5)": r"""
def f():
    if NEW:
        qprr.thesis.load_qprr(qprr.thesis.thesis_params().with_changes(d3=0.5), urdf_path=qprr.thesis.URDF_PATH)
    else:
        import qprr.params as prm, qprr.urdf as u
        kin.load(prm.thesis_params().with_changes(d3=0.5), urdf_path=u.URDF_PATH)
    return False
verdict(f, ("d3",))
""",
    "4 negative payload mass (PayloadModel.set_mass)": r"""
def f():
    from qprr.payload import PayloadModel
    PayloadModel(P).set_mass(-1.0)
    return False
verdict(f, ("mass",))
""",
    "4 mass estimator after a NaN sample": r"""
def f():
    from qprr.payload import MassEstimator
    e = MassEstimator(P)
    nv = P.model.nv
    q = pin.neutral(P.model)
    e.update(q, np.zeros(nv), np.full(nv, np.nan), np.zeros(nv), 0.01)
    return False
verdict(f, ("tau_prev",))
""",
    "5 zero quaternion in q": r"""
def f():
    q = pin.neutral(P.model); q[3:7] = 0.0
    kin.ee_placement(P, DATA, q)
    return False
verdict(f, ("q[3:7]", "quaternion"))
""",
    "5 rotation_to_euler of 2 R": r"""
def f():
    rotation_to_euler(2.0 * euler_to_rotation([0.1, 0.2, 0.3]))
    return False
verdict(f, ("rotation",))
""",
    "5 complex xi": r"""
def f():
    xi_to_q(np.ones(9) + 1j)
    return False
verdict(f, ("xi",))
""",
    "6 CLIKA success at roll = pi/2": r"""
def f():
    xi = np.zeros(9); xi[2] = 1.0; xi[3] = math.pi / 2 - 1e-3
    M = kin.ee_placement(P, DATA, xi_to_q(xi))
    if NEW:
        from qprr.ik import IKSolver
        r = IKSolver(P, "clika", {"weights": (1, 1, 1, 1, 1, 1, 1e4, 1, 1)}).solve(DATA, M, xi0=np.zeros(9))
    else:
        from qprr import ik
        r = ik.solve(P, DATA, M, "clika", xi0=np.zeros(9), options={"weights": (1, 1, 1, 1, 1, 1, 1e4, 1, 1)})
    return not r.success
verdict(f)
""",
    "7 simulate a reference beyond the joint limits": r"""
def f():
    from qprr.sim import simulate
    from qprr.control import make_controller
    from qprr.trajectory import MultiPhase, Phase
    xi0 = (0, 0, 1.0, 0, 0, 0, 0, 0, 0)
    traj = MultiPhase((Phase("theta2", 0.05, 0.1, 3.0),), xi0)
    simulate(P, make_controller("idc", P), traj, 0.2)
    return False
verdict(f, ("theta2",))
""",
    "8 result file with dt = 'fast'": r"""
def f():
    import json, tempfile, os
    from qprr.sim import SimResult
    d = tempfile.mkdtemp(); path = os.path.join(d, "r.npz")
    m = 3; z = np.zeros((m, 9))
    arrays = dict(t=np.arange(m) * 1.0, xi=z, xi_dot=z, xi_d=z, xi_dot_d=z, u=z, f=np.zeros((m, 4)), arm_effort=np.zeros((m, 3)),
                  x_cm=np.zeros((m, 3)), unallocated=z, flags=np.zeros(m, dtype=np.int8), u_ext=z)
    meta = dict(format_version=2, scenario="s", controller="c", dt="fast", integrator="euler", control_period=0.01, wall_time=0.0,
                status="ok", reason="", seed=0, platform="p", names=[], metrics={}, series=[])
    np.savez(path, **arrays, meta=np.array(json.dumps(meta)), dt=np.array("fast"))
    SimResult.load(path)
    return False
verdict(f, ("dt",))
""",
    "9 qp IK: 4 threads vs serial": r"""
def f():
    rng = np.random.default_rng(9); targets = []
    for _ in range(12):
        xi = np.zeros(9); xi[0:3] = rng.uniform(-2, 2, 3); xi[5] = rng.uniform(-3, 3); xi[6:] = rng.uniform(-0.03, 0.03, 3)
        targets.append(kin.ee_placement(P, DATA, xi_to_q(xi)))
    if NEW:
        from qprr.ik import IKSolver
        make = lambda: (lambda d, M: IKSolver(P, "qp").solve(d, M))
    else:
        from qprr import ik
        make = lambda: (lambda d, M: ik.solve(P, d, M, "qp"))
    solve = make()
    d0 = P.model.createData()
    serial = [solve(d0, M).q for M in targets]
    out = {}
    def work(k):
        s, d = make(), P.model.createData()
        for i in range(k, 12, 4):
            out[i] = s(d, targets[i]).q
    th = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    [t.start() for t in th]; [t.join() for t in th]
    return all(np.array_equal(out[i], serial[i]) for i in range(12))
verdict(f)
""",
    "10 deepcopy(Allocator), then a saturated allocation": r"""
def f():
    if NEW:
        from qprr.actuation import Allocator
    else:
        from qprr.allocation import Allocator
    a = Allocator(P)
    Om = np.asarray(a.Omega) if hasattr(a, "Omega") else None
    tau = np.zeros(P.model.nv); tau[2] = 1e3; tau[3] = 50.0
    first = a.allocate(tau).f
    b = copy.deepcopy(a)
    return np.allclose(b.allocate(tau).f, first, atol=1e-7)
verdict(f)
""",
    "10 pickle(Allocator), then a saturated allocation": r"""
def f():
    if NEW:
        from qprr.actuation import Allocator
    else:
        from qprr.allocation import Allocator
    a = Allocator(P)
    tau = np.zeros(P.model.nv); tau[2] = 1e3; tau[3] = 50.0
    first = a.allocate(tau).f
    b = pickle.loads(pickle.dumps(a))
    return np.allclose(b.allocate(tau).f, first, atol=1e-7)
verdict(f)
""",
}


def scenarios(tree: Path, timeout: float, names=None) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names or SCENARIOS:
            body = SCENARIOS[name]
            proc = subprocess.run(
                [sys.executable, "-c", _PRELUDE + textwrap.dedent(body)], cwd=tmp, env=env, capture_output=True, text=True, timeout=timeout
            )
            word = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else ""
            out[name] = word if proc.returncode == 0 and word in CATEGORIES else ("crash" if proc.returncode < 0 else "unclear")
    return out


def table(rows: dict[str, Counter], title: str) -> str:
    trees = list(rows)
    lines = [title, f"{'category':<22}" + "".join(f"{t:>12}" for t in trees)]
    for c in CATEGORIES:
        label = {"silent": "silent wrong answer", "crash": "crash", "unclear": "unclear error", "good": "good error", "allowed": "documented result"}[
            c
        ]
        lines.append(f"{label:<22}" + "".join(f"{rows[t].get(c, 0):>12}" for t in trees))
    lines.append(f"{'total':<22}" + "".join(f"{sum(rows[t].values()):>12}" for t in trees))
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default=None, help="an old qprr tree to audit side by side (e.g. /tmp/old)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per child process")
    ap.add_argument("--show", type=int, default=15, help="list this many failing catalogue cases per tree")
    ap.add_argument("--quick", action="store_true", help="the catalogue of qprr.charts only and two scenarios (a smoke run)")
    args = ap.parse_args(argv)
    module, names = ("qprr.charts", list(SCENARIOS)[:2]) if args.quick else ("", list(SCENARIOS))
    trees = {"current": HERE}
    if args.old:
        trees = {"old main": Path(args.old).resolve(), **trees}
    cat_rows, sc_rows, sc_detail = {}, {}, {}
    for label, tree in trees.items():
        counts, info, bad = catalogue(tree, args.timeout, module)
        cat_rows[label] = counts
        print(
            f"[{label}] {tree}: catalogue fed {info.get('fed')} callables, {sum(counts.values())} cases in {info['seconds']:.0f} s "
            f"(not fed: {info.get('not_fed')}, no valid call from the table: {info.get('baseline_failed')})"
        )
        for o in bad[: args.show]:
            print(f"    {o['verdict']:8s} {o['target']}({o['param']} = {o['label']}): {o['detail'][:110]}")
        sc = scenarios(tree, args.timeout, names)
        sc_detail[label] = sc
        sc_rows[label] = Counter(sc.values())
    print()
    print(table(cat_rows, "catalogue (tests/catalogue.py): bad-input cases per category"))
    print()
    print(table(sc_rows, "issue 16 scenarios (by item number)"))
    width = max(map(len, names))
    print("\n" + f"{'scenario':<{width}}" + "".join(f"{t:>12}" for t in trees))
    for name in names:
        print(f"{name:<{width}}" + "".join(f"{sc_detail[t][name]:>12}" for t in trees))
    print()
    for t in trees:
        cases = cat_rows[t] + sc_rows[t]
        good = cases["good"] + cases["allowed"]
        print(
            f"ratio of good answers (good error, documented result or right answer), {t}: {good / max(1, sum(cases.values())):.3f} "
            f"of {sum(cases.values())} cases"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
