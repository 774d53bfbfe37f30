"""The compiled QP-IK iteration (qprr/ik/iteration_fast.py, numba) against the readable forms: log6, Jlog6 and log3
against Pinocchio's, every default task's (J, e) against its ``linearize``, and the hierarchy's step against the
numpy path, on random configurations and targets of four platforms."""

from __future__ import annotations

from importlib.util import find_spec

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr import ik
from qprr.ik.hierarchy import HierarchySolver
from qprr.ik.tasks import ComTask, HoverTask, PoseTask, PositionTask, PostureTask, Task, update_kinematics

pytestmark = pytest.mark.skipif(find_spec("numba") is None, reason="numba is not installed: pip install 'qprr[fast]'")

PLATFORMS = ["q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR"]


def platform_of(name):
    return qprr.build(name) if name == "HEX-RRR" else qprr.load(name)


def random_q(platform, rng):
    """A configuration anywhere in a 6 m box, any attitude, the arm inside its limits."""
    xi = np.zeros(platform.n_xi)
    xi[0:3] = rng.uniform(-3.0, 3.0, 3)
    xi[3:6] = rng.uniform(-np.pi, np.pi, 3) * np.array([0.45, 0.45, 1.0])
    xi[6:] = rng.uniform(np.maximum(platform.arm_lower, -np.pi), np.minimum(platform.arm_upper, np.pi))
    return qprr.charts.xi_to_q(xi)


def test_log6_jlog6_log3_match_pinocchio():
    """Where Pinocchio's closed forms are accurate: below 1e-8 rad (its series) and from 0.5 rad to pi - 0.1 (its
    Jlog6 loses up to 1e-7 to cancellation at 1e-3 rad, its log3 up to 4e-11 near pi: measured against 50-digit
    arithmetic); the series in between is checked against the closed form where they meet."""
    from qprr.ik import iteration_fast as fast

    rng = np.random.default_rng(5)
    for k in range(300):
        angle = [1e-12, 1e-9, 0.5, 0.9, 1.5, 2.0, 2.8, np.pi - 0.1][k % 8]
        axis = rng.normal(size=3)
        R = pin.exp3(axis / np.linalg.norm(axis) * angle * rng.uniform(0.98, 1.0))
        p = rng.normal(size=3) * rng.uniform(0.1, 3.0)
        M = pin.SE3(R, p)
        v, w, theta = fast.log6(R, p)
        np.testing.assert_allclose(np.r_[v, w], pin.log6(M).vector, rtol=0, atol=1e-12 * (1.0 + np.abs(p).max()))
        np.testing.assert_allclose(fast.jlog6(R, p), pin.Jlog6(M), rtol=0, atol=1e-12 * (1.0 + np.abs(p).max()))
        np.testing.assert_allclose(fast.jlog3(w, theta), pin.Jlog3(R), rtol=0, atol=1e-13)


def test_beta_series_meets_closed_form():
    """beta and beta'/theta of Jlog3 / Jlog6: their series below SERIES_BELOW against the closed form just above it
    (where the closed form's cancellation costs less than 1e-12), and the series' limits at 0 (1/12, 1/360)."""
    from qprr.ik import iteration_fast as fast

    edge = fast.SERIES_BELOW
    below, above = fast._beta(edge * (1.0 - 1e-12)), fast._beta(edge * (1.0 + 1e-12))
    np.testing.assert_allclose(below, above, rtol=1e-11)
    np.testing.assert_allclose(fast._beta(0.0), (1.0 / 12.0, 1.0 / 360.0), rtol=1e-15)


def test_log3_near_pi_is_exact():
    """Near pi the axis comes from the symmetric part: the rotation vector to rounding (Pinocchio's log3 loses up to
    4e-11 between pi - 0.1 and pi - 1e-3, measured), checked against the vector R was made from."""
    from qprr.ik import iteration_fast as fast

    rng = np.random.default_rng(6)
    for gap in (0.3, 0.1, 1e-2, 4e-3, 1e-3, 1e-6):
        for _ in range(20):
            u = rng.normal(size=3)
            w = u / np.linalg.norm(u) * (np.pi - gap)
            np.testing.assert_allclose(fast.log3(pin.exp3(w))[0], w, rtol=0, atol=1e-14)


def levels_for(platform, rng, kind: str, weighted: bool):
    """A default hierarchy aimed at a random pose (or position) target, some tasks weighted."""
    target = pin.SE3(pin.exp3(rng.normal(size=3)), rng.uniform(-3.0, 3.0, 3)) if kind == "pose" else rng.uniform(-3.0, 3.0, 3)
    posture = rng.uniform(np.maximum(platform.arm_lower, -np.pi), np.minimum(platform.arm_upper, np.pi))
    levels = ik.default_levels(platform, target, posture, rng.uniform(-np.pi, np.pi))
    if weighted:  # the row scales of the compiled form
        n = platform.n_arm
        first = PoseTask(platform, target, weights=rng.uniform(0.5, 2.0, 6)) if kind == "pose" else PositionTask(platform, target, weights=[1, 2, 3])
        levels[0] = [first]
        levels[2] = [ComTask(rng.normal(size=2) * 0.01, weights=[2.0, 0.5])]
        levels[3] = [PostureTask(platform, posture, weights=rng.uniform(0.5, 2.0, n))]
    return levels


@pytest.mark.parametrize("name", PLATFORMS)
def test_compiled_tasks_match_linearize(name):
    from qprr.ik import iteration_fast as fast

    platform = platform_of(name)
    data = platform.data()
    rng = np.random.default_rng(12)
    for k in range(40):
        q = random_q(platform, rng)
        levels = levels_for(platform, rng, "pose" if k % 3 else "position", weighted=k % 2 == 1)
        update_kinematics(platform, data, q)
        packed = fast.compiled_levels(platform, levels)
        assert packed is not None
        frame, base = fast.kinematics(platform, data, packed)
        A, b, offsets = fast.linearize(packed.levels, frame, base, q, platform.nv)
        for j, level in enumerate(levels):
            J, e = level[0].linearize(platform, data, q)
            rows = slice(offsets[j], offsets[j + 1])
            scale = 1.0 + np.abs(J).max()
            np.testing.assert_allclose(A[rows], J, rtol=0, atol=1e-12 * scale, err_msg=f"{level[0].name} J")
            np.testing.assert_allclose(b[rows], e, rtol=0, atol=1e-12 * (1.0 + np.abs(e).max()), err_msg=f"{level[0].name} e")
        # the errors alone (no Jacobian computed) are those of the linearisation, bit for bit
        norms = [float(np.sqrt(np.sum(b[i:j] * b[i:j]))) for i, j in zip(offsets[:-1], offsets[1:])]
        assert fast.level_norms(packed.levels, frame, base, q).tolist() == norms


def test_hover_task_upside_down_compiled():
    """The hover level's branch within 1e-6 rad of upside down (no tilt direction) agrees too."""
    from qprr.ik import iteration_fast as fast

    platform = qprr.load("q-prr")
    data = platform.data()
    q = platform.neutral_q()
    q[3:7] = pin.Quaternion(pin.exp3(np.array([np.pi - 1e-8, 0.0, 0.0]))).coeffs()
    update_kinematics(platform, data, q)
    levels = [[HoverTask()]]
    packed = fast.compiled_levels(platform, levels)
    frame, base = fast.kinematics(platform, data, packed)
    A, b, _ = fast.linearize(packed.levels, frame, base, q, platform.nv)
    J, e = levels[0][0].linearize(platform, data, q)
    np.testing.assert_allclose(A, J, rtol=0, atol=1e-14)
    np.testing.assert_allclose(b, e, rtol=0, atol=1e-14)
    assert fast.level_norms(packed.levels, frame, base, q).tolist() == [float(np.sqrt(np.sum(b * b)))]


class Given(Task):
    """A task returning a given (J, e): the readable path fed the compiled form's linearisation."""

    def __init__(self, J, e):
        self.J, self.e, self.dim = J.copy(), e.copy(), e.shape[0]

    def linearize(self, platform, data, q):
        return self.J, self.e


@pytest.mark.parametrize("name", PLATFORMS)
def test_compiled_step_matches_numpy_path(name):
    """HierarchySolver's step in one compiled call (each level's optimum, the errors, the damping, the residuals)
    against its readable glue (tasks one by one, norms, damping, Lexicographic) on the same (J, e) (the tasks' agreement
    is the test above; the lower levels' conditioning, up to 1e8 with the regularisation 1e-7, would turn their 1e-13
    into 1e-8 here), joint limits active in some; against the glue with the same compiled lexicographic kernel and with
    the numpy kernel: to 1e-7 of the step (eps times that condition number is 2e-8, and the damping, computed in
    either place, differs by rounding; 3.8e-8 the largest difference seen, on random attitudes far from any answer).
    The hextilt's draws include a posture level with one free direction and a joint on its limit that this direction
    moves only by rounding (lexicographic's ``_clamped_1d``)."""
    platform = platform_of(name)
    data = platform.data()
    rng = np.random.default_rng(21)
    fused = HierarchySolver(platform, kernel="numba")
    glue, reference = HierarchySolver(platform, kernel="numba"), HierarchySolver(platform, kernel="numpy")
    active = 0
    for k in range(30):
        q = random_q(platform, rng)
        levels = levels_for(platform, rng, "pose" if k % 3 else "position", weighted=k % 4 == 3)
        update_kinematics(platform, data, q)
        for solver in (fused, glue, reference):
            solver.reset()
        rf = fused.solve(platform, data, q, levels, validate=False)
        assert rf.level_residuals  # the compiled call made this step (the readable path leaves them to .residuals)
        # the levels' errors alone (the stopping tests'), compiled against the tasks' error (Pinocchio's log6 near pi: 1e-11)
        np.testing.assert_allclose(fused.level_errors(platform, data, q, levels), reference.level_errors(platform, data, q, levels), rtol=1e-10)
        given = [[Given(J, e)] for J, e in rf.linearized]
        ra = glue.solve(platform, data, q, given, validate=False)
        size = 1.0 + np.abs(ra.dv).max()
        for xa, xf in zip(ra.dv_levels, rf.dv_levels, strict=True):
            np.testing.assert_allclose(xf, xa, rtol=0, atol=1e-7 * size)
        np.testing.assert_allclose(rf.errors, ra.errors, rtol=1e-14, atol=0)
        np.testing.assert_allclose(rf.damping, ra.damping, rtol=1e-13, atol=0)
        np.testing.assert_allclose(rf.residuals, ra.residuals, rtol=0, atol=1e-7 * size * (1.0 + max(ra.errors)))
        rn = reference.solve(platform, data, q, given, validate=False)
        for xa, xf in zip(rn.dv_levels, rf.dv_levels, strict=True):
            np.testing.assert_allclose(xf, xa, rtol=0, atol=1e-7 * size)
        q_arm = q[7:] + rf.dv[6:]
        active += int(np.any(np.isclose(q_arm, platform.arm_lower, atol=1e-9) | np.isclose(q_arm, platform.arm_upper, atol=1e-9)))
    assert active >= 3  # joint limits bind in some of the steps


def test_a_retargeted_task_is_read_again_by_the_compiled_step():
    """HierarchySolver.solve on the same levels after a task's set_target, without reset: the compiled step follows the
    new target as the readable path does (the packed parameters are refilled at every call)."""
    platform = qprr.load("borinot_flying_arm_2")
    data = platform.data()
    rng = np.random.default_rng(5)
    fused, reference = HierarchySolver(platform, kernel="numba"), HierarchySolver(platform, kernel="numpy")
    levels = levels_for(platform, rng, "pose", weighted=False)
    q = random_q(platform, rng)
    update_kinematics(platform, data, q)
    fused.solve(platform, data, q, levels, validate=False)
    levels[0][0].set_target(pin.SE3(pin.exp3(rng.normal(size=3)), rng.uniform(-3.0, 3.0, 3)))
    levels[3][0].set_reference(rng.uniform(np.maximum(platform.arm_lower, -np.pi), np.minimum(platform.arm_upper, np.pi)))
    rf = fused.solve(platform, data, q, levels, validate=False)
    rn = reference.solve(platform, data, q, levels, validate=False)
    assert rf.level_residuals
    np.testing.assert_allclose(rf.errors, rn.errors, rtol=1e-10)
    np.testing.assert_allclose(rf.dv, rn.dv, rtol=0, atol=1e-7 * (1.0 + np.abs(rn.dv).max()))


def test_levels_the_compiled_form_does_not_take():
    from qprr.ik import iteration_fast as fast

    platform = qprr.load("q-prr")
    target = pin.SE3(np.eye(3), np.array([0.3, 0.0, 1.0]))

    class MyPose(PoseTask):  # a subclass may linearise otherwise
        pass

    assert fast.compiled_levels(platform, [[MyPose(platform, target)], [HoverTask()]]) is None
    assert fast.compiled_levels(platform, [[PoseTask(platform, target), HoverTask()]]) is None  # two tasks in a level
    base = PoseTask(platform, target, frame=platform.base_frame)
    assert fast.compiled_levels(platform, [[PoseTask(platform, target)], [base]]) is None  # two frames
    assert fast.compiled_levels(platform, [[PoseTask(platform, target)], [HoverTask()]]) is not None


@pytest.mark.parametrize("name", PLATFORMS)
def test_steps_without_refresh_and_on_leading_levels_match(name):
    """HierarchySolver.solve with refresh=False (the IK's steps after the first of a solve: the packed targets kept)
    gives the step of refresh=True when no task changed, and the leading levels packed beside the full ones (the IK
    once its lower levels are frozen) give the readable path's step on those levels."""
    platform = platform_of(name)
    data = platform.data()
    rng = np.random.default_rng(21)
    fused, reference = HierarchySolver(platform, kernel="numba"), HierarchySolver(platform, kernel="numpy")
    levels = levels_for(platform, rng, "pose", weighted=True)
    leading = levels[:2]
    for k in range(10):
        q = random_q(platform, rng)
        update_kinematics(platform, data, q)
        for solver in (fused, reference):
            solver.reset()
        first = fused.solve(platform, data, q, levels, validate=False, refresh=k == 0)
        fused.reset()
        again = fused.solve(platform, data, q, levels, validate=False)
        np.testing.assert_array_equal(first.dv, again.dv)
        assert first.errors == again.errors
        lead = fused.solve(platform, data, q, leading, validate=False, refresh=False)
        ref = reference.solve(platform, data, q, leading, validate=False)
        size = 1.0 + np.abs(ref.dv).max()
        np.testing.assert_allclose(lead.dv, ref.dv, rtol=0, atol=1e-7 * size)
        np.testing.assert_allclose(
            fused.level_errors(platform, data, q, levels, refresh=False), reference.level_errors(platform, data, q, levels), rtol=1e-10, atol=1e-14
        )


def cold_targets(platform, rng, n: int):
    """``n`` targets from random level configurations (every third a position alone), the solver's default guess."""
    data = platform.data()
    targets = []
    for k in range(n):
        xi = np.zeros(platform.n_xi)
        xi[0:3] = rng.uniform(-3.0, 3.0, 3)
        xi[5] = rng.uniform(-np.pi, np.pi)
        xi[6:] = rng.uniform(np.maximum(platform.arm_lower, -np.pi), np.minimum(platform.arm_upper, np.pi))
        pin.framesForwardKinematics(platform.model, data, qprr.charts.xi_to_q(xi))
        M = data.oMf[platform.ee_frame].copy()
        targets.append(M.translation.copy() if k % 3 == 2 else M)
    return targets


def readable_solver(platform, monkeypatch, options=None):
    """An IKSolver whose QP runs the readable Newton loop (its engine offers no compiled loop)."""
    solver = ik.IKSolver(platform, "qp", options)
    monkeypatch.setattr(solver.engine, "newton_loop", lambda *args: None)
    return solver


def assert_same_answer(rc, rr):
    """The compiled loop's result against the readable loop's: the same verdicts and iteration counts, the pose
    errors, CoG offset and attitude to 1e-12, the configuration and the level errors to 1e-9.  Both loops take the
    same compiled steps and differ by rounding only (the compiled loop shifts the kinematics of a base move instead of
    asking Pinocchio again), which the lower levels' conditioning (up to 1e8 with the regularisation 1e-7) amplifies
    where a level cannot be met: 4.5e-10 at most in q on hextilt_flying_arm_5's 150 benchmark targets."""
    verdicts = ("status", "success", "iterations", "hover_feasible", "within_limits")
    assert [getattr(rc, f) for f in verdicts] == [getattr(rr, f) for f in verdicts]
    np.testing.assert_allclose(rc.q, rr.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(rc.xi, rr.xi, rtol=0, atol=1e-9)  # the compiled loop's xi of q against finish's
    np.testing.assert_allclose(rc.level_errors, rr.level_errors, rtol=0, atol=1e-9)
    errors = ("position_error", "orientation_error", "x_cm", "y_cm", "roll", "pitch")
    np.testing.assert_allclose([getattr(rc, f) for f in errors], [getattr(rr, f) for f in errors], rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", PLATFORMS)
def test_compiled_loop_matches_readable_loop(name, monkeypatch):
    """The QP IK's Newton loop compiled (qprr/ik/newton_fast.py) against the readable loop of QPMethod on cold starts
    from the default guess, poses and positions (hextilt_flying_arm_5's position targets freeze lower levels): the same
    statuses, iteration counts and answers; the compiled loop ran every solve (no fallback)."""
    from qprr.ik import newton_fast

    platform = platform_of(name)
    data = platform.data()
    compiled, readable = ik.IKSolver(platform, "qp"), readable_solver(platform, monkeypatch)
    ran = []
    run = newton_fast.NewtonLoop.run
    monkeypatch.setattr(newton_fast.NewtonLoop, "run", lambda self, *args: ran.append(run(self, *args)) or ran[-1])
    targets = cold_targets(platform, np.random.default_rng(8), 45)
    for target in targets:
        assert_same_answer(compiled.solve(data, target), readable.solve(data, target))
    assert len(ran) == len(targets) and all(out is not None for out in ran)


def test_compiled_loop_matches_on_the_qprr_problems(monkeypatch):
    """The Q-PRR: the thesis guess (four levels; pose then hover alone, pink's problem) and the analytic IGM start,
    targets reachable in hover and not (status not_hover_feasible), against the readable loop."""
    from qprr.ik.tasks import HoverTask
    from qprr.thesis import igm

    platform = qprr.load("q-prr")
    data = platform.data()
    rng = np.random.default_rng(3)
    targets = [t for t in cold_targets(platform, rng, 30) if isinstance(t, pin.SE3)]
    tilt = pin.exp3(np.array([0.3, 0.0, 0.1]))  # the end effector's y axis out of the horizontal: no hover reaches it
    targets += [pin.SE3(tilt @ M.rotation, M.translation) for M in targets[:6]]
    pose = PoseTask(platform, pin.SE3.Identity())
    two = {"levels": [[pose], [HoverTask()]]}
    pairs = [(igm.solver(platform, "qp", init=init), igm.solver(platform, "qp", init=init)) for init in ("guess", "igm")]
    pairs.append((ik.IKSolver(platform, "qp", two), ik.IKSolver(platform, "qp", two)))
    for _, readable in pairs:
        monkeypatch.setattr(readable.engine, "newton_loop", lambda *args: None)
    statuses = set()
    for M in targets:
        pose.set_target(M)
        guess = igm.hover_guess(platform.params, M.translation, M.rotation)
        for compiled, readable in pairs:
            rc, rr = compiled.solve(data, M, guess), readable.solve(data, M, guess)
            assert_same_answer(rc, rr)
            statuses.add(str(rc.status))
    assert statuses == {"converged", "not_hover_feasible"}


def test_compiled_loop_hands_a_solve_to_the_readable_loop(monkeypatch):
    """A pass the compiled loop cannot take (here forced at its third pass) ends it: the readable loop solves the
    target from its start, so the answer is the readable loop's."""
    from qprr.ik import newton_fast

    platform = qprr.load("borinot_flying_arm_2")
    data = platform.data()
    targets = cold_targets(platform, np.random.default_rng(9), 6)
    readable = readable_solver(platform, monkeypatch)
    expected = [readable.solve(data, t) for t in targets]
    newton, passes = newton_fast.newton, []

    def failing(*args):
        passes.append(1)
        return newton_fast.FALLBACK if len(passes) % 3 == 0 else newton(*args)

    monkeypatch.setattr(newton_fast, "newton", failing)
    solver = ik.IKSolver(platform, "qp")
    for target, rr in zip(targets, expected, strict=True):
        passes.clear()
        assert_same_answer(solver.solve(data, target), rr)
        assert len(passes) >= 3


@pytest.mark.parametrize("options", [{"max_iter": 2}, {"max_step": 0.3, "settle_tol": 1e-9}, {"require_hover": False, "position_tol": 1e-3}])
def test_compiled_loop_matches_with_other_options(options, monkeypatch):
    """The options the compiled loop reads (an iteration limit that ends solves with status max_iterations, a smaller
    step cap, a tighter settle tolerance, hover not required, a looser tolerance) give the readable loop's answers."""
    platform = qprr.load("q-prr")
    data = platform.data()
    compiled, readable = ik.IKSolver(platform, "qp", options), readable_solver(platform, monkeypatch, options)
    statuses = set()
    for target in cold_targets(platform, np.random.default_rng(4), 15):
        rc, rr = compiled.solve(data, target), readable.solve(data, target)
        assert_same_answer(rc, rr)
        statuses.add(str(rc.status))
    assert ("max_iterations" in statuses) == (options.get("max_iter") == 2)
