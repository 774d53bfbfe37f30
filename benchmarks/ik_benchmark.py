"""Inverse kinematics of the Q-PRR: every qprr.ik method and the peers, on the same targets; then the cold starts of
the other shipped platforms (borinot_flying_arm_2, hextilt_flying_arm_5, HEX-RRR) against the same peers.

    python benchmarks/ik_benchmark.py [--n 200] [--n-unreachable 50] [--seed 0] [--reps 5]
                                      [--no-peers] [--no-platforms] [--png ik_benchmark.png] [--quick]
                                      [--placo-venv DIR] [--make-placo-venv]

``--quick``: 12 reachable and 4 unreachable targets, one timed run each, pink as the only peer, the Q-PRR
only (a test runs it in seconds; its times are too few for a verdict).

Peers: pink (differential IK on Pinocchio, ``pip install --no-deps pin-pink``), mink (the same API on MuJoCo,
``pip install --no-deps mink``: both only need qpsolvers besides what qprr has), PlaCo (C++ on Pinocchio), rtb and
ikpy.  PlaCo 0.10.2 pins ``pin==3.8.0``, which cannot live beside qprr's pin 4 (crocoddyl is built against it): it
runs in its own environment, by default ``~/.cache/qprr/placo-venv`` (``--placo-venv DIR``), which
``--make-placo-venv`` creates (``python -m venv`` and ``pip install placo==0.10.2``: the package registry and a few
minutes).  The benchmark writes the problem to a file, ``benchmarks/placo_worker.py`` solves and times it with that
environment's Python and returns the configurations, which are checked here like every other answer; where the
environment is missing, PlaCo's row says "not available" and why.

Other platforms: targets from random level configurations (base in the same box, arm uniform in its range cut to
+-pi), every solver from qprr's default guess (:func:`qprr.ik.default_guess`: level base, arm neutral, end effector
placed on the target); qprr's qp with its default four levels (level 2: hover on the under-actuated borinot and
HEX-RRR, a level base on the fully actuated hextilt), the peers on the platform's hover chain (its URDF with x, y, z,
yaw joints instead of the free flyer); no unreachable targets there.

Targets (seeded): ``--n`` reachable ones, the end-effector pose (forward kinematics) of
random hover configurations (roll = pitch = 0, base in a 6 m box, yaw and arm uniform in
their ranges), and ``--n-unreachable`` ones obtained by turning such a pose's y axis out of
the horizontal plane by 1e-3..0.5 rad: no hover configuration reaches those (under hover
R_e = Rz(psi) Ry(theta2 + theta3), whose y axis is horizontal).

The problem is the static (hover) IK.  qprr's "qp" works on the free-flyer model (9 dof)
with hover as priority level 2; "igm", "dls" and "clika (hover)" search hover
configurations only; the thesis CLIKA searches all 9 dof and ignores hover.  The peers are
given the same 7-dof hover problem through a URDF chain x, y, z (prismatic), yaw
(revolute), then the arm -- like for like -- since none of them takes a free-flyer root
with a hover constraint; every solver starts from the same guess (hover below the target,
arm straight) except "qp (IGM start)" which starts from the analytic IGM.

Success (checked here, independently, with Pinocchio's forward kinematics on the full
model): position error < 1e-6 m, orientation error < 1e-6 rad and arm joints within
limits.  Tolerances given to the peers are made equivalent: pink iterates full steps
(dt = 1) and stops on this very criterion; rtb ik_LM stops at E = 1/2 |e|^2 < 5e-13, i.e.
|e| < 1e-6 on the stacked [position; angle-axis] error; ikpy (scipy least_squares) has
no absolute tolerance, so ftol = xtol = 1e-15 lets it go as far as it can.

Protocol: correctness pass on every target first (results checked, disagreements between
a qprr method's own success flag and the independent check are errors: every qprr method
requires hover for success by default on the under-actuated Q-PRR, the thesis CLIKA included,
so the check's verdict is "pose and limits and hover"), then warm-up,
then timing with the garbage collector off: each target solved ``--reps`` times (once
for methods slower than 1 ms) and its *minimum* kept -- the run least disturbed by other
processes, timeit's convention -- then the median and 95th percentile over the reachable
targets.  Times are this thread's CPU time by default (``--clock cpu``; ``--clock wall`` for
wall-clock time): other processes on a shared machine do not count; the load average is
printed with the machine: on a busy one every number still grows (shared caches).  Progress
is printed as each method completes; then a markdown table whose speed columns are ratios
measured in this run (vs qprr's QP and vs the fastest peer that succeeds as often):
absolute times hold on this machine only.  Saves a PNG.
"""

from __future__ import annotations

import argparse
import gc
import logging
import math
import sys
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

import qprr
from qprr import ik
from qprr import kinematics as kin
from qprr.ik.solver import IKSolver
from qprr.ik.tasks import HoverTask, PoseTask
from qprr.thesis import igm
from qprr.thesis.urdf import build_urdf
from qprr.viz import new_figure

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
from machine import machine_lines

TOL = 1e-6
HOVER_COLS = [0, 1, 2, 5, 6, 7, 8]  # xi entries of the 7-dof hover chain


# --------------------------------------------------------------------------- machine
def print_machine() -> None:
    print("## Machine")
    for line in machine_lines(("pin-pink", "roboticstoolbox-python", "ikpy", "numba")):
        print(f"- {line}")
    print()


# --------------------------------------------------------------------------- targets
def make_targets(robot, data, n: int, n_unreachable: int, seed: int):
    rng = np.random.default_rng(seed)
    lo, hi = robot.arm_lower, robot.arm_upper

    def hover_xi():
        xi = np.zeros(9)
        xi[0:2] = rng.uniform(-3.0, 3.0, 2)
        xi[2] = rng.uniform(0.5, 3.0)
        xi[5] = rng.uniform(-np.pi, np.pi)
        xi[6:9] = rng.uniform(lo, hi)
        return xi

    reach = [kin.ee_placement(robot, data, qprr.charts.xi_to_q(hover_xi())) for _ in range(n)]
    unreach = []
    for _ in range(n_unreachable):
        M = kin.ee_placement(robot, data, qprr.charts.xi_to_q(hover_xi()))
        u = np.cross([0.0, 0.0, 1.0], M.rotation[:, 1])
        u /= np.linalg.norm(u)
        angle = math.exp(rng.uniform(math.log(1e-3), math.log(0.5))) * rng.choice([-1.0, 1.0])
        unreach.append(pin.SE3(pin.exp3(angle * u) @ M.rotation, M.translation.copy()))
    return reach, unreach


# --------------------------------------------------------------------------- methods
@dataclass
class Outcome:
    xi: np.ndarray | None  # returned configuration, thesis coordinates
    claimed: bool | None  # the solver's own success flag (None: it has none)
    iterations: float  # nan when the solver does not say


@dataclass
class Method:
    name: str
    problem: str
    init: str
    solve: object = None  # callable(M) -> Outcome
    hover_problem: bool = True  # does the method search hover configurations only (roll = pitch = 0)?
    requires_hover: bool = True  # does its success flag require hover (qprr's default on an under-actuated platform)?
    unavailable: str = ""
    peer: bool = False
    batch: object = None  # callable(reach, unreach, reps, clock) -> (outcomes, unreachable outcomes, times, reps): a solver run elsewhere
    results: list = field(default_factory=list)
    unreach_results: list = field(default_factory=list)
    times: list = field(default_factory=list)


def qprr_methods(robot, data):
    """qprr's methods through the thesis front end (qprr.thesis.igm: thesis guesses, IGM start for the QP);
    solvers and options built once, outside the timing, as an application would."""

    def make(method, options=None, init="igm"):
        if method == "igm":
            opts = igm.make_options("igm", options, igm.OPTIONS)

            def run(M):
                r = igm.solve_igm(robot, data, M, None, opts)
                return Outcome(r.xi, r.success, r.iterations)

            return run
        solver = igm.solver(robot, method, options, init=init)

        def run(M):
            r = solver.solve(data, M)
            return Outcome(r.xi, r.success, r.iterations)

        return run

    w = (1, 1, 1, 1, 1, 1, 1e4, 1, 1)
    guess = "hover below target, arm straight"
    return [
        Method("qp (IGM start)", "free flyer 9 dof, hover = level 2", "analytic IGM", make("qp")),
        Method("igm (thesis Alg. 3-5)", "hover, 7 dof", guess, make("igm")),
        Method("igm (balanced theta2)", "hover, 7 dof", guess, make("igm", {"theta2": "balance"})),
        Method("clika (thesis, 9 dof)", "free flyer, 9 dof, no hover", guess, make("clika"), hover_problem=False),
        Method("clika (hover, W: r0 x1e4)", "hover, 7 dof", guess, make("clika", {"hover": True, "weights": w})),
        Method("dls (LM on log6)", "hover, 7 dof", guess, make("dls")),
        Method("qp (cold start)", "free flyer 9 dof, hover = level 2", guess, make("qp", init="guess")),
        Method("qp (cold start, pose > hover)", "free flyer 9 dof, 2 levels: pose, hover", guess, pose_over_hover(robot, data)),
    ]


def pose_over_hover(robot, data):
    """The QP IK on pink's problem: two levels only (end-effector pose, then hover; no CoG or posture level), from the
    thesis guess: how much of the cold start's time the two lower levels of the default hierarchy cost."""
    pose = PoseTask(robot, pin.SE3.Identity())
    solver = IKSolver(robot, "qp", {"levels": [[pose], [HoverTask()]]})

    def run(M):
        pose.set_target(M)
        r = solver.solve(data, M, igm.hover_guess(robot.params, M.translation, M.rotation))
        return Outcome(r.xi, r.success, r.iterations)

    return run


def hover_chain_urdf(params) -> str:
    """The Q-PRR's hover chain (:func:`chain_urdf` of the thesis URDF)."""
    return chain_urdf(build_urdf(params), "multirotor")


def chain_urdf(urdf: str, base_link: str) -> str:
    """A platform's URDF with a 4-joint base (x, y, z prismatic, yaw revolute) from a fixed world link to ``base_link``
    instead of a free flyer, without visual and collision shapes (no mesh to find) and without the Q-PRR's rotor
    frames (massless, off the chain): the level-base configurations as a serial chain."""
    root = ET.fromstring(urdf)
    for el in list(root):
        name = el.get("name", "")
        if el.tag in ("link", "joint") and name.startswith("rotor_"):
            root.remove(el)
    for link in root.iter("link"):
        for shape in [*link.findall("visual"), *link.findall("collision")]:
            link.remove(shape)
    chain = [
        ("base_x", "prismatic", "1 0 0", "world", "slider_x", 100.0),
        ("base_y", "prismatic", "0 1 0", "slider_x", "slider_y", 100.0),
        ("base_z", "prismatic", "0 0 1", "slider_y", "slider_z", 100.0),
        ("base_yaw", "revolute", "0 0 1", "slider_z", base_link, 2.0 * math.pi),
    ]
    new = [ET.Element("link", name="world")]
    for name, kind, axis, parent, child, lim in chain:
        if child != base_link:
            new.append(ET.Element("link", name=child))
        j = ET.Element("joint", name=name, type=kind)
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=child)
        ET.SubElement(j, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(j, "axis", xyz=axis)
        ET.SubElement(j, "limit", lower=repr(-lim), upper=repr(lim), effort="1000", velocity="1000")
        new.append(j)
    i = next(k for k, el in enumerate(root) if el.tag == "link" and el.get("name") == base_link)
    for k, el in enumerate(new):
        root.insert(i + k, el)
    return ET.tostring(root, encoding="unicode")


def hover_cols(robot) -> list[int]:
    """The xi entries of the hover chain: x, y, z, yaw, then the arm."""
    return [0, 1, 2, 5, *range(6, robot.n_xi)]


def random_level_xi(robot, rng) -> np.ndarray:
    """A level configuration: base in a 6 m box (0.5..3 m high), yaw and arm uniform (arm ranges cut to +-pi)."""
    xi = np.zeros(robot.n_xi)
    xi[0:2] = rng.uniform(-3.0, 3.0, 2)
    xi[2] = rng.uniform(0.5, 3.0)
    xi[5] = rng.uniform(-np.pi, np.pi)
    xi[6:] = rng.uniform(np.maximum(robot.arm_lower, -np.pi), np.minimum(robot.arm_upper, np.pi))
    return xi


def check_chain(robot, data, urdf_path: str, ee: str = "end_effector") -> None:
    """The peers' hover chain has the same end-effector pose as the free-flyer model at every
    hover configuration (checked at 100 random ones) and the same joint limits."""
    model = pin.buildModelFromUrdf(urdf_path)
    cdata = model.createData()
    fid = model.getFrameId(ee)
    rng = np.random.default_rng(1)
    cols = hover_cols(robot)
    worst = 0.0
    for _ in range(100):
        xi = random_level_xi(robot, rng)
        pin.framesForwardKinematics(model, cdata, xi[cols])
        worst = max(worst, float(np.abs(cdata.oMf[fid].homogeneous - kin.ee_placement(robot, data, qprr.charts.xi_to_q(xi)).homogeneous).max()))
    if not (
        worst < 1e-12 and np.allclose(model.lowerPositionLimit[4:], robot.arm_lower) and np.allclose(model.upperPositionLimit[4:], robot.arm_upper)
    ):
        raise RuntimeError(f"the peers' hover chain of {robot.name} differs from the free-flyer model (max pose difference {worst:.1e})")
    print(
        f"hover chain of {robot.name} for the peers: same end-effector pose as the free-flyer model at 100 hover "
        f"configurations (max difference {worst:.1e}), same arm limits"
    )


def _xi_of_chain(h, cols=HOVER_COLS, n: int = 9) -> np.ndarray:
    xi = np.zeros(n)
    xi[cols] = h
    return xi


def _why(exc: Exception) -> str:
    hint = " (pip install 'qprr[peers]')" if isinstance(exc, ImportError) else ""
    return f"{type(exc).__name__}: {exc}{hint}"


@dataclass
class Case:
    """One platform's problem: its model, the targets, the guess every solver starts from (``guess(M) -> xi0``) and the
    peers' hover chain (``urdf_path``); ``methods`` its rows."""

    name: str
    robot: object
    data: object
    guess: object
    guess_label: str
    reach: list
    unreach: list = field(default_factory=list)
    urdf_path: str = ""
    methods: list = field(default_factory=list)

    @property
    def ee(self) -> str:
        return self.robot.model.frames[self.robot.ee_frame].name

    @property
    def chain(self) -> str:
        return f"hover chain, {len(hover_cols(self.robot))} dof"

    def h0(self, M) -> np.ndarray:
        return self.guess(M)[hover_cols(self.robot)]

    def xi_of_chain(self, h) -> np.ndarray:
        return _xi_of_chain(h, hover_cols(self.robot), self.robot.n_xi)


def peer_methods(case: Case, only_pink: bool = False, placo_python: Path | None = None):
    """The peers on ``case``'s hover chain: pink, mink and PlaCo (rtb and ikpy too on the Q-PRR)."""
    out = [pink_method(case)]
    if only_pink:
        return out
    out += [mink_method(case), placo_method(case, placo_python)]
    if case.name == "Q-PRR":
        out += rtb_ikpy_methods(case)
    return out


def pink_method(case: Case) -> Method:
    """pink: differential IK (one QP per step on proxqp), iterated with full steps."""
    m = Method("pink FrameTask (proxqp)", case.chain, case.guess_label, peer=True)
    try:
        import pink
        from pink.limits import ConfigurationLimit
        from pink.tasks import FrameTask

        model = pin.buildModelFromUrdf(case.urdf_path)
        pdata = model.createData()
        limits = [ConfigurationLimit(model)]
        ee = case.ee

        def run_pink(M, model=model, pdata=pdata, limits=limits):
            conf = pink.Configuration(model, pdata, case.h0(M))
            task = FrameTask(ee, position_cost=1.0, orientation_cost=1.0)
            task.set_target(M)
            for it in range(100):  # noqa: B007 (the count is reported)
                pe, oe = ik.pose_errors(conf.get_transform_frame_to_world(ee), M.translation, M.rotation)
                if pe < TOL and oe < TOL:
                    break
                v = pink.solve_ik(conf, [task], 1.0, solver="proxqp", limits=limits)
                conf.integrate_inplace(v, 1.0)
            return Outcome(case.xi_of_chain(conf.q), None, it)

        m.solve = run_pink
    except Exception as exc:
        m.unavailable = _why(exc)
    return m


def mujoco_chain(case: Case):
    """The hover chain as a MuJoCo model (static bodies kept, so the end-effector frame is a body), its FK checked
    against Pinocchio's chain at 20 random configurations."""
    import mujoco

    root = ET.fromstring(Path(case.urdf_path).read_text())
    mj = ET.Element("mujoco")
    ET.SubElement(mj, "compiler", fusestatic="false", discardvisual="true", boundmass="1e-9", boundinertia="1e-12")
    root.insert(0, mj)
    model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    mdata = mujoco.MjData(model)
    pmodel = pin.buildModelFromUrdf(case.urdf_path)
    pdata = pmodel.createData()
    fid, body = pmodel.getFrameId(case.ee), model.body(case.ee).id
    rng = np.random.default_rng(2)
    worst = 0.0
    for _ in range(20):
        h = random_level_xi(case.robot, rng)[hover_cols(case.robot)]
        mdata.qpos[:] = h
        mujoco.mj_kinematics(model, mdata)
        pin.framesForwardKinematics(pmodel, pdata, h)
        M = pdata.oMf[fid]
        worst = max(worst, float(np.abs(mdata.xpos[body] - M.translation).max()), float(np.abs(mdata.xmat[body].reshape(3, 3) - M.rotation).max()))
    if worst > 1e-9 or model.nq != pmodel.nq:
        raise RuntimeError(f"the MuJoCo hover chain differs from Pinocchio's (max pose difference {worst:.1e}, nq {model.nq} vs {pmodel.nq})")
    return model


def mink_method(case: Case) -> Method:
    """mink: differential IK on MuJoCo (pink's API), one QP per step on proxqp, iterated with full steps."""
    m = Method("mink FrameTask (proxqp)", case.chain, case.guess_label, peer=True)
    try:
        import mink

        model = mujoco_chain(case)
        limits = [mink.ConfigurationLimit(model)]
        ee = case.ee

        def run_mink(M, model=model, limits=limits):
            conf = mink.Configuration(model, case.h0(M))
            task = mink.FrameTask(ee, "body", position_cost=1.0, orientation_cost=1.0)
            task.set_target(mink.SE3.from_matrix(M.homogeneous))
            for it in range(100):  # noqa: B007 (the count is reported)
                pe, oe = ik.pose_errors(pin.SE3(conf.get_transform_frame_to_world(ee, "body").as_matrix()), M.translation, M.rotation)
                if pe < TOL and oe < TOL:
                    break
                v = mink.solve_ik(conf, [task], 1.0, "proxqp", limits=limits)
                conf.integrate_inplace(v, 1.0)
            return Outcome(case.xi_of_chain(conf.q), None, it)

        m.solve = run_mink
    except Exception as exc:
        m.unavailable = _why(exc)
    return m


PLACO_VENV = Path.home() / ".cache" / "qprr" / "placo-venv"
"""Where --make-placo-venv creates PlaCo's environment (outside the repository) and where the benchmark looks for it."""
PLACO_PIN = "placo==0.10.2"


def make_placo_venv(venv: Path) -> str:
    """Create PlaCo's own environment (``python -m venv``, then pip install placo 0.10.2 with its pin 3.8.0; needs the
    package registry and a few minutes): "" when it works, else the reason."""
    import subprocess

    print(f"creating PlaCo's environment in {venv} (python -m venv; pip install {PLACO_PIN})", flush=True)
    for cmd in ([sys.executable, "-m", "venv", str(venv)], [str(venv / "bin" / "python"), "-m", "pip", "install", "-q", PLACO_PIN]):
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            return f"{' '.join(cmd[-2:])} failed: {(run.stderr or run.stdout).strip().splitlines()[-1:]}"
    return ""


def placo_method(case: Case, python: Path | None) -> Method:
    """PlaCo (C++ on Pinocchio 3.8): its whole correctness and timing passes run in PlaCo's environment
    (benchmarks/placo_worker.py, through a subprocess), the returned configurations checked here."""
    m = Method("PlaCo KinematicsSolver (C++)", case.chain, case.guess_label, peer=True)
    if python is None or not python.is_file():
        where = python.parent.parent if python is not None else PLACO_VENV
        m.unavailable = (
            f"no PlaCo environment at {where} (PlaCo 0.10.2 pins pin==3.8.0, it cannot share qprr's pin 4: "
            "create one with python benchmarks/ik_benchmark.py --make-placo-venv)"
        )
        return m

    def batch(reach, unreach, reps: int, clock: str):
        import subprocess

        tmp = Path(tempfile.mkdtemp(prefix="qprr_placo_"))
        np.savez(
            tmp / "in.npz",
            urdf=case.urdf_path,
            frame=case.ee,
            tol=TOL,
            reps=reps,
            clock=clock,
            targets=np.array([M.homogeneous for M in reach]),
            guesses=np.array([case.h0(M) for M in reach]),
            unreach_targets=np.array([M.homogeneous for M in unreach]).reshape(-1, 4, 4),
            unreach_guesses=np.array([case.h0(M) for M in unreach]).reshape(len(unreach), len(hover_cols(case.robot))),
        )
        worker = Path(__file__).resolve().parent / "placo_worker.py"
        run = subprocess.run([str(python), str(worker), str(tmp / "in.npz"), str(tmp / "out.npz")], capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError(f"placo_worker.py failed: {run.stderr.strip().splitlines()[-1:]}")
        out = np.load(tmp / "out.npz")
        res = [Outcome(case.xi_of_chain(q), None, it) for q, it in zip(out["q"], out["iterations"])]
        res_u = [Outcome(case.xi_of_chain(q), None, float("nan")) for q in out["q_unreach"]]
        return res, res_u, list(out["times"]), int(out["reps"])

    m.batch = batch
    return m


def rtb_ikpy_methods(case: Case) -> list:
    """roboticstoolbox and ikpy on the Q-PRR's hover chain."""
    out = []
    urdf_path, h0_of = case.urdf_path, case.h0
    guess = case.guess_label
    # --- roboticstoolbox: C++ Levenberg-Marquardt, one search (no random restarts)
    m = Method("rtb ik_LM (C++, 1 search)", "hover chain, 7 dof", guess, peer=True)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import roboticstoolbox as rtb

            ets = rtb.Robot.URDF(urdf_path).ets(end="end_effector")

        def run_rtb(M, ets=ets):
            sol = ets.ik_LM(M.homogeneous, q0=h0_of(M), ilimit=100, slimit=1, tol=5e-13, joint_limits=True)
            return Outcome(_xi_of_chain(sol.q), bool(sol.success), sol.iterations)

        run_rtb(pin.SE3.Identity())
        m.solve = run_rtb
    except Exception as exc:
        m.unavailable = _why(exc)
    out.append(m)

    # --- ikpy: scipy least_squares with joint bounds
    m = Method("ikpy (scipy least_squares)", "hover chain, 7 dof", guess, peer=True)
    try:
        import ikpy.chain

        logging.getLogger("ikpy").setLevel(logging.ERROR)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            chain = ikpy.chain.Chain.from_urdf_file(urdf_path, base_elements=["world"], active_links_mask=[False] + [True] * 7 + [False])
        if len(chain.links) != 9:
            raise RuntimeError(f"unexpected chain {[link.name for link in chain.links]}")

        import inspect

        import ikpy.inverse_kinematics

        params = inspect.signature(ikpy.inverse_kinematics.inverse_kinematic_optimization).parameters
        # ikpy >= 4 names the tolerance and the budget; older versions only take max_iter
        extra = {"tol": 1e-15, "optimizer_budget": 5000} if "optimizer_budget" in params else {"max_iter": 5000}

        def run_ikpy(M, chain=chain, extra=extra):
            full0 = np.zeros(9)
            full0[1:8] = h0_of(M)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sol = chain.inverse_kinematics_frame(M.homogeneous, initial_position=full0, orientation_mode="all", **extra)
            return Outcome(_xi_of_chain(sol[1:8]), None, float("nan"))

        m.solve = run_ikpy
    except Exception as exc:
        m.unavailable = _why(exc)
    out.append(m)
    return out


# --------------------------------------------------------------------------- checks
@dataclass
class Check:
    pose_ok: bool
    within: bool
    hover: bool
    x_cm: float

    @property
    def success(self) -> bool:
        return self.pose_ok and self.within


def check(robot, data, xi, M) -> Check:
    """Independent verdict on a returned configuration, with Pinocchio on the full model."""
    if xi is None or not np.all(np.isfinite(xi)):
        return Check(False, False, False, float("nan"))
    q = qprr.charts.xi_to_q(xi)
    Me = kin.ee_placement(robot, data, q)
    pe, oe = np.linalg.norm(Me.translation - M.translation), np.linalg.norm(pin.log3(M.rotation.T @ Me.rotation))
    lo, hi = robot.arm_lower, robot.arm_upper
    within = bool(np.all(xi[6:] >= lo - 1e-12) and np.all(xi[6:] <= hi + 1e-12))
    hover = abs(xi[3]) < TOL and abs(xi[4]) < TOL
    return Check(pe < TOL and oe < TOL, within, hover, float(kin.cog_offset_body(robot, data, q)[0]))


# --------------------------------------------------------------------------- running
def correctness_pass(robot, data, methods, reach, unreach, reps: int = 5) -> int:
    """Every method on every target, each answer checked independently (a method run elsewhere, ``batch``, also
    brings its times: it cannot be timed from here)."""
    bad = 0
    for m in methods:
        if m.unavailable:
            continue
        t0 = time.perf_counter()
        if m.batch is not None:
            try:
                outs, outs_u, m.times, r = m.batch(reach, unreach, reps, _clock_name)
            except Exception as exc:
                m.unavailable = _why(exc)
                print(f"  not available: {m.name}: {m.unavailable}", flush=True)
                continue
        else:
            outs, outs_u = [m.solve(M) for M in reach], [m.solve(M) for M in unreach]
        for o, M in zip(outs, reach):
            c = check(robot, data, o.xi, M)
            m.results.append((o, c))
            expected = c.success and (c.hover or not m.requires_hover)
            if not m.peer and o.claimed != expected:
                bad += 1
                print(f"  !! {m.name}: own flag {o.claimed} but independent check {c}", file=sys.stderr)
        for o, M in zip(outs_u, unreach):
            m.unreach_results.append((o, check(robot, data, o.xi, M)))
        rate = 100.0 * np.mean([c.success for _, c in m.results])
        print(f"  checked {m.name:<30s} {rate:5.1f} % success on the reachable targets ({time.perf_counter() - t0:5.1f} s)", flush=True)
    return bad


def timing_pass(methods, reach, reps: int) -> None:
    ref = None
    for m in methods:
        if m.unavailable:
            continue
        if m.batch is not None:  # timed where it ran (correctness_pass)
            med = float(np.median(m.times))
            ref = med if ref is None else ref
            print(
                f"  timed   {m.name:<30s} median {_fmt_us(med):>6} us on this machine = {med / ref:6.2f} x the first row (in its own process)",
                flush=True,
            )
            continue
        for M in reach[:10]:  # warm-up
            m.solve(M)
        slow = np.median([_time_once(m.solve, M) for M in reach[:10]]) > 1e-3
        r = 1 if slow else reps
        gc.disable()
        try:
            for M in reach:
                m.times.append(min(_time_once(m.solve, M) for _ in range(r)))
        finally:
            gc.enable()
        med = float(np.median(m.times))
        ref = med if ref is None else ref  # the first method timed (the Q-PRR: qp, IGM start) is the reference
        print(
            f"  timed   {m.name:<30s} median {_fmt_us(med):>6} us on this machine = {med / ref:6.2f} x the first row ({r} run(s) per target)",
            flush=True,
        )


CLOCK = {"cpu": time.thread_time, "wall": time.perf_counter}
_clock = CLOCK["cpu"]
_clock_name = "cpu"


def _time_once(fn, M) -> float:
    t0 = _clock()
    fn(M)
    return _clock() - t0


# --------------------------------------------------------------------------- report
def _fmt_us(t: float) -> str:
    us = t * 1e6
    return f"{us:.0f}" if us >= 100 else f"{us:.1f}"


def _best_peer(methods):
    """The fastest available peer (median time) among those with the highest success rate."""
    peers = [m for m in methods if m.peer and not m.unavailable and m.times]
    if not peers:
        return None
    top = max(np.mean([c.success for _, c in m.results]) for m in peers)
    return min((m for m in peers if np.mean([c.success for _, c in m.results]) == top), key=lambda m: np.median(m.times))


def table(methods, ref_prefix: str = "qp (IGM") -> str:
    """The markdown table of ``methods``; "vs qp" divides by the median of the first method named ``ref_prefix``..."""
    ref = next((m for m in methods if m.name.startswith(ref_prefix) and m.times), None)
    ref_t = np.median(ref.times) if ref else float("nan")
    peer = _best_peer(methods)
    peer_t = np.median(peer.times) if peer else float("nan")
    head = (
        "| method | problem | initial guess | success (reachable) | median [us] | p95 [us] | vs qp | vs best peer | "
        "median iters | median abs(x_cm) [mm] | CoG on axis | hover-feasible | unreachable: refused | wrong success |"
    )
    lines = [head, "|" + "---|" * 14]
    for m in methods:
        if m.unavailable:
            lines.append(f"| {m.name} | {m.problem} | | not available: {m.unavailable} | | | | | | | | | | |")
            continue
        n = len(m.results)
        succ = [c.success for _, c in m.results]
        its = [o.iterations for o, _ in m.results if not (isinstance(o.iterations, float) and math.isnan(o.iterations))]
        xcm = [abs(c.x_cm) * 1e3 for _, c in m.results if c.success]
        hov = [c.success and c.hover for _, c in m.results]
        centred = [c.success and abs(c.x_cm) < 1e-6 for _, c in m.results]
        med, p95 = np.median(m.times), np.percentile(m.times, 95)
        if not m.hover_problem:
            refused = wrong = "n/a (no hover goal)"
        elif not m.unreach_results:
            refused = wrong = "n/a (none given)"
        else:
            nu = len(m.unreach_results)
            claims = [o.claimed for o, _ in m.unreach_results]
            if all(cl is None for cl in claims):
                refused = "no flag"
            else:
                refused = f"{sum(cl is False for cl in claims)}/{nu}"
            wrong_n = sum(1 for o, c in m.unreach_results if (o.claimed is True or (o.claimed is None and c.success)) and not (c.success and c.hover))
            wrong = f"{wrong_n}/{nu}"
        vs_peer = f"{med / peer_t:.2f}x" if peer else "n/a"
        lines.append(
            f"| {m.name} | {m.problem} | {m.init} | {100.0 * np.mean(succ):.1f} % ({sum(succ)}/{n}) | {_fmt_us(med)} | "
            f"{_fmt_us(p95)} | {med / ref_t:.2f}x | {vs_peer} | {np.median(its) if its else 'n/a'} | "
            f"{np.median(xcm) if xcm else float('nan'):.3f} | {100.0 * np.mean(centred):.1f} % | {100.0 * np.mean(hov):.1f} % | "
            f"{refused} | {wrong} |"
        )
    return "\n".join(lines)


def _clean(m) -> bool:
    """Measured, every reachable target reached (independent check) and no unreachable target claimed."""
    if m.unavailable or not m.times or not all(c.success for _, c in m.results):
        return False
    return not any((o.claimed is True or (o.claimed is None and c.success)) and not (c.success and c.hover) for o, c in m.unreach_results)


def fastest_line(label: str, methods) -> str:
    """The fastest method of ``methods`` among those with 100 % success and no wrong success, and the next ones."""
    ok = sorted((m for m in methods if _clean(m)), key=lambda m: np.median(m.times))
    if not ok:
        return f"- {label}: no method with 100 % success and no wrong success"
    best = float(np.median(ok[0].times))
    rest = ", ".join(f"{m.name} {np.median(m.times) / best:.2f}x" for m in ok[1:4])
    return f"- {label}: fastest **{ok[0].name}** ({_fmt_us(best)} us median){'; then ' + rest if rest else ''}"


def done_when(methods) -> list[str]:
    """Issue 36's criteria, each with this run's numbers: speed as ratios of medians (the peer's over qprr's)."""
    by = {m.name: m for m in methods if not m.unavailable and m.times}
    pink, mink, placo = "pink FrameTask (proxqp)", "mink FrameTask (proxqp)", "PlaCo KinematicsSolver (C++)"
    rows = [
        ("qp (cold start, pose > hover)", pink, 2.0),
        ("qp (cold start, pose > hover)", mink, 1.0),
        ("qp (cold start, pose > hover)", placo, 1.0),
        ("qp (cold start)", pink, 1.0),
        ("qp (IGM start)", pink, 2.0),
    ]
    out = []
    for name, peer_name, need in rows:
        m, peer = by.get(name), by.get(peer_name)
        if m is None or peer is None:
            out.append(f"- {name} vs {peer_name}: not measured in this run")
            continue
        ratio = float(np.median(peer.times) / np.median(m.times))
        verdict = "met" if ratio >= need else "NOT met"
        out.append(f"- {name}: {ratio:.2f}x the speed of {peer.name} (needed >= {need:g}x): {verdict}")
    ours = [m for m in methods if not m.peer and not m.unavailable and m.hover_problem and m.name.startswith("qp")]
    clean = all(_clean(m) for m in ours)
    out.append(f"- every qp row: 100 % success and 0 wrong successes: {'met' if clean else 'NOT met'}")
    return out


def ratios_report(methods) -> list[str]:
    """The speed of qprr's methods as ratios measured in this run (absolute times: this machine only)."""
    by = {m.name: m for m in methods if not m.unavailable and m.times}
    qp, igm_m = by.get("qp (IGM start)"), by.get("igm (thesis Alg. 3-5)")
    out = []
    if qp is not None:
        rate = np.mean([c.success for _, c in qp.results])
        out.append(f"- QP IK (IGM start): {100 * rate:.1f} % success within limits; median {_fmt_us(np.median(qp.times))} us on this machine")
    if qp is not None and igm_m is not None:
        out.append(f"- the analytic IGM takes {np.median(igm_m.times) / np.median(qp.times):.3f} of the QP's median time (it also starts the QP)")
    peers = [m for m in methods if m.peer and not m.unavailable and m.times]
    for m in peers:
        rate = np.mean([c.success for _, c in m.results])
        if qp is not None:
            out.append(f"- {m.name}: {np.median(m.times) / np.median(qp.times):.2f} x the QP's median time, {100 * rate:.1f} % success")
    if not peers:
        out.append("- peers not measured (--no-peers, or pip install 'qprr[peers]')")
    pink = by.get("pink FrameTask (proxqp)")
    if pink is None or pink.unavailable:
        out.append("- no ratio to pink: pink is not installed (pip install pin-pink, or pip install 'qprr[peers]')")
    for name in ("qp (IGM start)", "qp (cold start)"):
        m = by.get(name)
        if m is not None and pink is not None:
            rate = np.mean([c.success for _, c in m.results])
            prate = np.mean([c.success for _, c in pink.results])
            out.append(
                f"- ratio to pink, {name}: pink's median time / qprr's = {np.median(pink.times) / np.median(m.times):.2f} "
                f"(target >= 2; success {100 * rate:.1f} % vs pink's {100 * prate:.1f} %)"
            )
    cold = by.get("qp (cold start)")
    if cold is not None and qp is not None and pink is not None:
        out += cold_start_why(cold, qp, pink, by.get("qp (cold start, pose > hover)"))
    return out


def cold_start_why(cold, qp, pink, two_levels) -> list[str]:
    """Where the cold start's time goes, from this run's numbers: the fixed cost of a solve (the IGM start's time: the
    IGM and one check of its answer, no Newton step) and the cost of a Newton iteration of the hierarchy."""
    n_cold = float(np.mean([o.iterations for o, _ in cold.results]))
    n_pink = float(np.mean([o.iterations for o, _ in pink.results]))
    t_cold, t_fixed, t_pink = (float(np.median(m.times)) for m in (cold, qp, pink))
    per_it = (t_cold - t_fixed) / max(n_cold - 1.0, 1.0)
    lines = [
        f"- why the cold start is {t_cold / t_pink:.1f}x pink's time: {n_cold:.2f} Newton iterations (mean; the last "
        f"one finds the step below step_tol or settle_tol) of the four-level hierarchy at about {_fmt_us(per_it)} us each, on top of "
        f"the {_fmt_us(t_fixed)} us of a solve whose start is already the answer (the IGM start, the IGM included); pink takes "
        f"{n_pink:.2f} full steps (mean) of one weighted QP over the 7 hover coordinates at {_fmt_us(t_pink / max(n_pink, 1.0))} us "
        f"each.  A 2x lead would leave {_fmt_us(t_pink / 2)} us per solve; with the compiled kernel (qprr[fast]) an "
        "iteration is one numba call (the tasks' Jacobians, the levels' linear algebra, the step control and the "
        "stopping tests: qprr/ik/newton_fast.py) between Pinocchio's kinematics and integrate, called from Python"
    ]
    if two_levels is not None and two_levels.times:
        t2 = float(np.median(two_levels.times))
        n2 = float(np.mean([o.iterations for o, _ in two_levels.results]))
        lines.append(
            f"- on pink's own problem (two levels, pose then hover): {_fmt_us(t2)} us, {n2:.2f} iterations (mean), "
            f"{t_pink / t2:.2f}x pink's speed: the CoG and posture levels cost {100 * (1 - t2 / t_cold):.0f} % of the cold start"
        )
    return lines


def plot(methods, path: Path) -> None:
    """Times (log scale, box: quartiles, whiskers 5-95 %) and success rates per method; a Figure without pyplot."""
    ms = [m for m in methods if not m.unavailable and m.times]
    fig = new_figure((13, 0.55 * len(ms) + 2.6))
    ax0, ax1 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [3, 2]})
    labels = [m.name for m in ms]
    y = np.arange(len(ms))
    ax0.boxplot([np.array(m.times) * 1e6 for m in ms], positions=y, orientation="horizontal", tick_labels=labels, showfliers=False, whis=(5, 95))
    ax0.set_xscale("log")
    ax0.set_xlabel("time per target [us] on this machine (box: quartiles, whiskers: 5-95 %)")
    ax0.set_ylim(len(ms) - 0.5, -0.5)
    ax0.grid(alpha=0.3, axis="x")
    succ = [100 * np.mean([c.success for _, c in m.results]) for m in ms]
    hov = [100 * np.mean([c.success and c.hover for _, c in m.results]) for m in ms]
    cog = [100 * np.mean([c.success and abs(c.x_cm) < 1e-6 for _, c in m.results]) for m in ms]
    ax1.barh(y - 0.27, succ, height=0.27, label="success (pose 1e-6 & limits)")
    ax1.barh(y, hov, height=0.27, label="... and hover-feasible")
    ax1.barh(y + 0.27, cog, height=0.27, label="... and CoG on the thrust axis")
    ax1.set_yticks(y, [""] * len(ms))
    ax1.set_xlim(0, 105)
    ax1.set_ylim(len(ms) - 0.5, -0.5)
    ax1.set_xlabel("reachable targets [%]")
    ax1.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=8)
    fig.suptitle("Q-PRR inverse kinematics: qprr methods and peers on the same seeded targets")
    fig.savefig(path, dpi=120)


NOTES = """\
- success: position error < 1e-6 m, orientation error < 1e-6 rad and arm within limits, checked here with
  Pinocchio on the free-flyer model; CoG on axis: success with |x_cm| < 1e-6 m (body frame); hover-feasible:
  success with |roll|, |pitch| < 1e-6 rad.  Time per target: best of --reps runs; vs qp: median / median of
  "qp (IGM start)"; vs best peer: / the fastest peer among those with the highest success rate.
- unreachable (no hover configuration reaches them): refused = the solver's own flag says failure; wrong
  success = it claims success (a peer without a flag: it returns a configuration that passes the check).
- like for like: the peers solve the same 7-dof hover problem (x, y, z, yaw, r0, theta2, theta3) from the
  same guess; qprr's qp solves the 9-dof free-flyer problem with hover as priority level 2.  On the other
  platforms likewise: the peers on the hover chain, qprr's qp on the free flyer with four levels.
- tolerances: pink and mink iterate full steps (dt = 1) of one QP (proxqp; joint limits by their
  ConfigurationLimit, default gains) until this very criterion; PlaCo applies full steps of its
  KinematicsSolver (one soft frame task, weight 1, joint limits on) until the same criterion, its times
  taken in its own process with the same protocol (benchmarks/placo_worker.py); rtb ik_LM stops at
  E = |e|^2 / 2 < 5e-13 (|e| < 1e-6 on [position; angle-axis]); ikpy's least_squares has no absolute
  tolerance: ftol = xtol = 1e-15, budget 5000 evaluations.
- rtb ik_LM treats joint limits by rejecting a converged solution (and restarting from random
  configurations, disabled here: slimit = 1, a single start like every other solver); it fails whenever the
  unconstrained descent ends with r0 outside +-0.04 m.  pink enforces limits in its QP (ConfigurationLimit),
  ikpy through scipy's bounds, qprr's dls by an active set, its qp as hard QP inequalities.
"""


PLATFORMS = ("borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")
"""The shipped platforms other than the Q-PRR: cold starts only (no analytic IGM), one table each."""


def platform_case(name: str, n: int, seed: int) -> Case:
    """``name``'s cold-start problem: ``n`` targets (FK of random level configurations), qprr's qp from its default
    guess (level base, arm neutral, end effector placed on the target), the peers from the same guess."""
    robot = qprr.build(name) if name == "HEX-RRR" else qprr.load(name)
    data = robot.data()
    rng = np.random.default_rng(seed)
    reach = [kin.ee_placement(robot, data, qprr.charts.xi_to_q(random_level_xi(robot, rng))) for _ in range(n)]
    label = "level base, arm neutral, end effector on the target"
    case = Case(name, robot, data, lambda M: ik.default_guess(robot, data, M.translation, M.rotation), label, reach)
    solver = IKSolver(robot, "qp")

    def run(M):
        r = solver.solve(data, M)
        return Outcome(r.xi, r.success, r.iterations)

    level2 = "base level" if robot.fully_actuated else "hover"
    case.methods = [
        Method("qp (cold start)", f"free flyer {robot.nv} dof, 4 levels ({level2} = level 2)", label, run, requires_hover=not robot.fully_actuated)
    ]
    return case


def write_chain(case: Case) -> None:
    """The peers' hover chain of ``case`` in a temporary URDF file, checked against the free-flyer model."""
    base = case.robot.model.frames[case.robot.base_frame].name
    urdf = Path(tempfile.mkdtemp(prefix="qprr_ik_")) / f"{case.name}_hover_chain.urdf"
    urdf.write_text(chain_urdf(case.robot.urdf, base))
    case.urdf_path = str(urdf)
    check_chain(case.robot, case.data, case.urdf_path, case.ee)


def run_case(case: Case, args, placo_python: Path | None) -> int:
    """Correctness and timing passes of ``case``'s methods (the peers added unless --no-peers): the disagreements."""
    if not args.no_peers:
        write_chain(case)
        case.methods += peer_methods(case, only_pink=args.quick, placo_python=placo_python)
    print(f"\n### {case.name}: correctness pass (independent check with Pinocchio FK on the full model)")
    bad = correctness_pass(case.robot, case.data, case.methods, case.reach, case.unreach, args.reps)
    print(f"  disagreements between a qprr method's success flag and the check: {bad}")
    print("Timing pass (warm-up, gc off):")
    timing_pass(case.methods, case.reach, args.reps)
    return bad


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=200, help="reachable targets")
    ap.add_argument("--n-unreachable", type=int, default=50, help="targets unreachable in hover")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--reps", type=int, default=5, help="timed runs per target (fast methods)")
    ap.add_argument("--no-peers", action="store_true", help="skip pink, mink, PlaCo, rtb and ikpy")
    ap.add_argument("--no-platforms", action="store_true", help="the Q-PRR only (no borinot, hextilt, HEX-RRR rows)")
    ap.add_argument("--placo-venv", type=Path, default=PLACO_VENV, help=f"PlaCo's own environment (default {PLACO_VENV})")
    ap.add_argument("--make-placo-venv", action="store_true", help="create --placo-venv first (python -m venv; pip install placo==0.10.2)")
    ap.add_argument("--png", default="ik_benchmark.png", help="figure file (its folder must exist)")
    ap.add_argument(
        "--clock",
        choices=tuple(CLOCK),
        default="cpu",
        help="cpu: this thread's CPU time (default: other processes on a shared machine do not count); wall",
    )
    ap.add_argument("--quick", action="store_true", help="12 + 4 targets, 1 run each, pink as the only peer, no other platform (seconds)")
    args = ap.parse_args(argv)
    if args.quick:
        args.n, args.n_unreachable, args.reps, args.no_platforms = 12, 4, 1, True
    if Path(args.png).suffix.lower() != ".png" or not Path(args.png).parent.is_dir():
        ap.error(f"--png {args.png!r}: a .png file in an existing folder")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    global _clock, _clock_name
    _clock, _clock_name = CLOCK[args.clock], args.clock
    placo_python = args.placo_venv / "bin" / "python"
    if args.make_placo_venv and not placo_python.is_file():
        why = make_placo_venv(args.placo_venv)
        print(f"PlaCo's environment: {why or 'created'}\n")
    print("# Inverse kinematics benchmark: the Q-PRR, then the other shipped platforms (cold starts)\n")
    print_machine()
    robot = qprr.load()
    data = robot.data()
    reach, unreach = make_targets(robot, data, args.n, args.n_unreachable, args.seed)
    print(
        f"Q-PRR: {len(reach)} reachable targets (FK of random in-limit hover configurations), {len(unreach)} unreachable "
        f"in hover (y axis tilted 1e-3..0.5 rad out of the horizontal plane), seed {args.seed}"
    )
    guess = "hover below target, arm straight"
    qprr_case = Case("Q-PRR", robot, data, lambda M: igm.hover_guess(robot.params, M.translation, M.rotation), guess, reach, unreach)
    qprr_case.methods = qprr_methods(robot, data)
    cases = [qprr_case] + ([] if args.no_platforms else [platform_case(name, args.n, args.seed) for name in PLATFORMS])
    bad = sum(run_case(case, args, placo_python) for case in cases)
    print("\n## Results\n")
    for case in cases:
        print(f"### {case.name}\n")
        print(table(case.methods, "qp (IGM" if case is qprr_case else "qp (cold"))
        print()
    print(NOTES)
    print("## Fastest per problem (100 % success and no wrong success; median time)\n")
    print(fastest_line("Q-PRR, any start", qprr_case.methods))
    print(fastest_line("Q-PRR, cold start (the thesis guess for all)", [m for m in qprr_case.methods if m.init == guess]))
    for case in cases[1:]:
        print(fastest_line(f"{case.name}, cold start", case.methods))
    print("\n## Speed as ratios (measured in this run)\n")
    for line in ratios_report(qprr_case.methods):
        print(line)
    print("\n## Issue 36's criteria (this run)\n")
    for line in done_when(qprr_case.methods):
        print(line)
    plot(qprr_case.methods, Path(args.png))
    print(f"\nfigure: {args.png}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
