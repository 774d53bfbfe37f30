"""Issue 16: the silent wrong answers, crashes and unclear errors it lists, one test each, and hypothesis properties.

The catalogue (tests/test_catalogue.py) feeds every public callable bad values of every kind;
here are the cases whose right answer needs physics or a scenario: angles wrapped in the RMSE,
attitudes, CLIKA's success, custom tasks, references beyond the joint limits, divergence named
with its time and variable, result files, parameter sets, solver objects in threads and child
processes.  Then properties over random inputs: IK success implies on target, within limits and
hover-feasible; allocation within bounds; a result file gives back the whole result; the IK
answer does not depend on what was solved before.
"""

from __future__ import annotations

import copy
import math
import multiprocessing
import pickle
import threading

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import qprr
import qprr.thesis
from qprr import charts as ch
from qprr import kinematics as kin
from qprr.actuation import Allocator
from qprr.control import make_controller
from qprr.control.base import Controller
from qprr.control.inverse_dynamics import PayloadIDC
from qprr.errors import (
    DivergenceError,
    InputError,
    LimitError,
    NonFiniteError,
    NonPhysicalError,
    QprrError,
    ShapeError,
)
from qprr.ik import IKSolver
from qprr.ik.tasks import PoseTask, Task
from qprr.payload import MassEstimator, PayloadModel
from qprr.sim import SimResult, simulate
from qprr.trajectory import Hold, MultiPhase, Phase
from tests.strategies import platform_xi_strategy

P = qprr.thesis.load_qprr()


# ------------------------------------------------------------------------------------ item 1
def _result(xi, xi_d) -> SimResult:
    m, n = xi.shape
    z = np.zeros((m, n))
    return SimResult(
        "s",
        "c",
        0.01,
        "euler",
        np.arange(m) * 0.01,
        xi,
        z,
        xi_d,
        z,
        z,
        np.zeros((m, 4)),
        np.zeros((m, n - 6)),
        np.zeros((m, 3)),
        z,
        np.zeros(m, dtype=np.int8),
        z,
        names=ch.xi_names(n - 6),
    )


def test_rmse_wraps_angle_errors():
    """A yaw manoeuvre across +-pi (true error 1e-6 rad) and a reference 2 pi away are errors of 1e-6 rad, not 6.28."""
    t = np.linspace(0.0, 1.0, 101)
    psi = np.pi - 0.5 + t  # crosses +pi at t = 0.5
    xi, xi_d = np.zeros((101, 9)), np.zeros((101, 9))
    xi[:, 5] = ch.wrap_angle(psi)
    xi_d[:, 5] = psi + 1e-6
    assert _result(xi, xi_d).rmse()["psi"] == pytest.approx(1e-6, rel=1e-6)
    xi_d[:, 5] = xi[:, 5] + 2 * np.pi
    assert _result(xi, xi_d).rmse()["psi"] < 1e-12
    xi_d[:, 6] = 0.3  # arm joints are not angles of the chart: not wrapped
    assert _result(xi, xi_d).rmse()["q1"] == pytest.approx(0.3)


# ------------------------------------------------------------------------------------ item 5
@pytest.mark.parametrize("quat, what", [((0.0, 0.0, 0.0, 0.0), "norm 0.0"), ((0.0, 0.0, 0.0, 2.0), "norm 2.0")])
def test_a_quaternion_off_the_unit_sphere_is_refused(quat, what):
    q = P.neutral_q()
    q[3:7] = quat
    for fn in (kin.ee_placement, kin.com_world, kin.ee_jacobian_world, qprr.dynamics.mass_matrix):
        with pytest.raises(ShapeError, match=rf"q\[3:7\] must be a unit quaternion .*{what}"):
            fn(P, P.data(), q)
    with pytest.raises(ShapeError, match=r"q\[3:7\]"):
        ch.q_to_xi(q)


def test_rotation_to_euler_checks_orthonormality():
    R = ch.euler_to_rotation([0.1, 0.2, 0.3])
    np.testing.assert_allclose(ch.rotation_to_euler(R), [0.1, 0.2, 0.3], atol=1e-15)
    for bad in (2.0 * R, R @ np.diag([1.0, 1.0, -1.0]), R + 1e-3):
        with pytest.raises(InputError, match="R must be a rotation matrix"):
            ch.rotation_to_euler(bad)


@pytest.mark.parametrize(
    "bad, what",
    [
        (np.ones(9) + 1j, "complex"),
        (np.ones(9, dtype=object), "Python objects"),
        (np.array(["1"] * 9), "strings"),
        (np.ones(9, dtype=bool), "booleans"),
    ],
)
def test_arrays_that_numpy_would_coerce_are_refused(bad, what):
    with pytest.raises(InputError, match=f"tau_desired must be real numbers, got {what}"):
        Allocator(P).allocate(bad)
    with pytest.raises(InputError, match=f"xi must be real numbers, got {what}"):
        ch.xi_to_q(bad)


def test_none_model_or_data_is_a_qprr_error():
    with pytest.raises(InputError, match="data must be a pinocchio.Data"):
        kin.ee_placement(P, None, P.neutral_q())
    with pytest.raises(InputError, match="platform must be a qprr Platform"):
        kin.ee_placement(None, P.data(), P.neutral_q())
    with pytest.raises(ShapeError, match="data was made for another model"):
        kin.ee_placement(P, qprr.load("borinot_flying_arm_2").data(), P.neutral_q())
    with pytest.raises(InputError, match="model must be a pinocchio.Model"):
        qprr.model.from_model(None, P.rotors)


# ------------------------------------------------------------------------------------ item 6
def test_clika_does_not_report_success_for_an_unflyable_pose():
    """Roll = pi/2: the pose is reachable only with the base on its side.  CLIKA reaches it, and says it is no success."""
    xi = P.neutral_xi()
    xi[0:3] = (0.2, -0.1, 1.0)
    xi[3] = math.pi / 2 - 1e-3
    data = P.data()
    M = kin.ee_placement(P, data, ch.xi_to_q(xi))
    res = IKSolver(P, "clika", {"weights": (1, 1, 1, 1, 1, 1, 1e4, 1, 1)}).solve(data, M, xi0=P.neutral_xi())
    assert not res.success and res.status == "not_hover_feasible" and not res.hover_feasible
    assert res.position_error < 1e-6 and abs(res.roll) > 1.0  # on target, but tilted


class _BadTask(Task):
    name, dim = "bad-task", 3

    def linearize(self, platform, data, q):
        return np.zeros((3, platform.nv)), np.zeros(2)  # e of shape (2,) for a 3-row J


def test_a_task_whose_error_has_the_wrong_shape_is_named():
    data = P.data()
    M = kin.ee_placement(P, data, ch.xi_to_q(P.neutral_xi()))
    levels = [[PoseTask(P, M)], [_BadTask()]]
    with pytest.raises(
        ShapeError,
        match=r"task _BadTask\(name='bad-task', dim=3\): linearize returned J of shape \(3, 9\) "
        r"and e of shape \(2,\)",
    ):
        IKSolver(P, "qp", {"levels": levels}).solve(data, M)


# ------------------------------------------------------------------------------------ item 7
def test_simulate_refuses_references_beyond_the_joint_limits():
    xi0 = P.neutral_xi()
    xi0[2] = 1.0
    traj = MultiPhase((Phase("theta2", 0.05, 0.1, 3.0),), tuple(xi0), names=P.xi_names)
    with pytest.raises(LimitError, match=r"arm joint 'theta2' is 2\.\d+ at t = 0\.\d+ s, outside its limits"):
        simulate(P, make_controller("idc", P), traj, 0.2)


# ------------------------------------------------------------------------------------ item 3 (sim)
class _NaNArm(Controller):
    """The IDC with its theta2 effort replaced by NaN from t = 0.05 s."""

    name = "nan-arm"

    def __init__(self):
        self.inner = make_controller("idc", P)
        self.output = self.inner.output

    def reset(self, state, ref, dt):
        self.inner.reset(state, ref, dt)

    def step(self, t, state, ref):
        u = np.array(self.inner.step(t, state, ref))
        if t >= 0.05:
            u[7] = np.nan
        return u


def test_a_nan_arm_effort_is_named_not_a_pitch_singularity():
    xi = P.neutral_xi()
    xi[2] = 1.0
    with pytest.raises(DivergenceError) as info:
        simulate(P, _NaNArm(), Hold(xi), 0.2, dt=0.005)
    msg = str(info.value)
    assert msg.startswith("diverged at t = 0.050 s") and "theta2 effort = nan" and "nan-arm" in msg
    assert "pitch" not in msg and info.value.result.status == "diverged" and info.value.result.t[-1] == pytest.approx(0.05)


def test_a_runaway_state_is_named_the_tick_it_happens():
    """A 1e4 N world push from t = 0.1 s: the state leaves the bounds within the tick; the error names time and variable."""
    xi = P.neutral_xi()
    xi[2] = 1.0

    def push(t, q, v):
        return np.array([1e4 if t >= 0.1 else 0.0, 0, 0, 0, 0, 0])

    with pytest.raises(DivergenceError, match=r"diverged at t = 0\.1\d\d s: (velocity v_x|position x) = ") as info:
        simulate(
            P, make_controller("idc", P), Hold(xi), 1.0, dt=0.002, external_wrench=push, limits=qprr.sim.Limits(position=1e3, linear_velocity=5.0)
        )
    assert info.value.result.status == "diverged"


# ------------------------------------------------------------------------------------ item 8
def _run() -> SimResult:
    xi = P.neutral_xi()
    xi[2] = 1.0
    res = simulate(P, make_controller("idc", P), Hold(xi), 0.05, dt=0.005)
    res.series["mass_estimate"] = np.linspace(0.0, 1.0, res.n)
    res.metrics["recovery_time"] = 1.25
    return res


def test_result_files_keep_series_and_metrics_and_refuse_bad_content(tmp_path):
    res = _run()
    back = SimResult.load(res.save(tmp_path / "r.npz"))
    np.testing.assert_array_equal(back.series["mass_estimate"], res.series["mass_estimate"])
    assert back.metrics == {"recovery_time": 1.25} and back.status == res.status and back.names == res.names
    arrays = {k: getattr(res, k) for k in qprr.sim.result.ARRAYS}
    meta = dict(
        format_version=qprr.sim.result.FORMAT_VERSION,
        scenario="s",
        controller="c",
        dt=0.005,
        integrator="midpoint",
        control_period=0.005,
        wall_time=0.0,
        status="ok",
        reason="",
        seed=0,
        platform="p",
        names=list(res.names),
        metrics={},
        series=[],
    )
    import json

    def write(name, **changes):
        a = {**arrays, **{k: v for k, v in changes.items() if k in arrays}}
        m = {**meta, **{k: v for k, v in changes.items() if k in meta}}
        np.savez(tmp_path / name, **a, meta=np.array(json.dumps(m)))
        return tmp_path / name

    cases = [
        (write("cols.npz", xi=np.zeros((res.n, 8))), r"xi_dot must have shape \(\d+, 8\)"),
        (write("rows.npz", u=res.u[:-1]), r"u has shape \(\d+, 9\), t has \d+ rows"),
        (write("flags.npz", flags=np.array(3)), r"flags has shape \(\), t has \d+ rows"),
        (write("dt.npz", dt="fast"), "metadata dt must be a number > 0, got 'fast'"),
        (write("version.npz", format_version=1), "format version 1"),
        (write("dtype.npz", xi=res.xi.astype(complex)), "xi must be float"),
    ]
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    np.savez(tmp_path / "foreign.npz", a=np.zeros(3))
    cases += [
        (tmp_path / "junk.npz", "not a qprr result file"),
        (tmp_path / "foreign.npz", "no qprr metadata"),
        (tmp_path / "nope.npz", "does not exist"),
    ]
    for path, match in cases:
        with pytest.raises(InputError, match=match):
            SimResult.load(path)


# ------------------------------------------------------------------------------------ items 2, 3, 4
@pytest.mark.parametrize(
    "field, value", [("thrust_factor", 0.0), ("drag_factor", -1e-7), ("arm_length", 0.0), ("d2", -0.1), ("multirotor_mass", float("nan"))]
)
def test_nonphysical_parameters_are_refused_naming_them(field, value):
    with pytest.raises(NonPhysicalError, match=field if field != "multirotor_mass" else "multirotor: mass"):
        qprr.thesis.thesis_params().with_changes(**{field: value})


def test_a_link_length_is_the_joint_offset_it_names():
    """Link.length was never read: now it must equal its d_i (with_changes keeps them together)."""
    from dataclasses import replace

    p = qprr.thesis.thesis_params()
    assert p.with_changes(d2=0.2).links[1].length == 0.2
    links = (p.links[0], replace(p.links[1], length=0.5), p.links[2])
    with pytest.raises(InputError, match=r"link2\.length = 0\.5 m contradicts d2 = 0\.18 m"):
        p.with_changes(links=links)


def test_a_non_numeric_urdf_mass_is_refused():
    from qprr.thesis.urdf import URDF_PATH

    text = URDF_PATH.read_text().replace('<mass value="3.029"/>', '<mass value="heavy"/>', 1)
    assert "heavy" in text
    with pytest.raises(NonPhysicalError, match="link 'multirotor' has a non-numeric mass or inertia"):
        qprr.from_urdf(text, P.rotors, ee_frame="end_effector")


def test_payload_masses_and_estimator_inputs():
    with pytest.raises(InputError, match="mass must be >= 0 kg, got -0.5"):
        PayloadModel(P).set_mass(-0.5)
    ctrl = PayloadIDC(P, payload="known")
    with pytest.raises(InputError, match="mass must be >= 0 kg, got -1.0"):
        ctrl.set_known_mass(-1.0)
    with pytest.raises(NonFiniteError, match="prior_weight must be finite, got nan"):
        MassEstimator(P, prior_weight=float("nan"))
    est = MassEstimator(P)
    q, v = P.neutral_q(), np.zeros(P.nv)
    with pytest.raises(NonFiniteError, match="tau_prev must be finite"):
        est.update(q, v, np.full(P.nv, np.nan), v, 0.01)
    assert est.samples == 0 and est.estimate().mass == 0.0  # the NaN sample left no trace


# ------------------------------------------------------------------------------------ items 9, 10
def _targets(n: int, seed: int):
    rng = np.random.default_rng(seed)
    data = P.data()
    out = []
    for _ in range(n):
        xi = P.neutral_xi()
        xi[0:3] = rng.uniform(-2, 2, 3)
        xi[5] = rng.uniform(-math.pi, math.pi)
        xi[6:] = rng.uniform(P.arm_lower, P.arm_upper)
        out.append(kin.ee_placement(P, data, ch.xi_to_q(xi)))
    return out


def test_qp_ik_in_four_threads_equals_the_serial_answers():
    """Issue 16 item 9: 24 targets solved by 4 threads (each its IKSolver and pin.Data) and serially: bit-identical q."""
    targets = _targets(24, 9)
    serial_solver, data = IKSolver(P, "qp"), P.data()
    serial = [serial_solver.solve(data, M).q for M in targets]
    out: dict[int, np.ndarray] = {}
    errors: list[BaseException] = []

    def work(k):
        try:
            solver, d = IKSolver(P, "qp"), P.data()
            for i in range(k, len(targets), 4):
                out[i] = solver.solve(d, targets[i]).q
        except BaseException as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for i, q in enumerate(serial):
        np.testing.assert_array_equal(out[i], q)


def _saturated_thrusts(alloc_bytes: bytes) -> list:
    """In a spawned child: a pickled allocator's first saturated allocation."""
    alloc = pickle.loads(alloc_bytes)
    p = alloc.platform
    tau = np.r_[p.rotor_matrix @ (2.0 * p.thrust_max), np.zeros(p.n_arm)]
    return alloc.allocate(tau).f.tolist()


def test_allocator_copies_survive_a_saturated_allocation_here_and_in_a_spawned_process():
    """Issue 16 item 10: deepcopy, pickle and a spawn-started child (as campaigns run) all give the fresh answer."""
    alloc = Allocator(P)
    tau = np.r_[P.rotor_matrix @ (2.0 * P.thrust_max), np.zeros(P.n_arm)]
    expected = alloc.allocate(tau).f
    assert np.all(expected[:4] <= P.thrust_max + 1e-12)
    for other in (copy.deepcopy(alloc), pickle.loads(pickle.dumps(alloc))):
        np.testing.assert_allclose(other.allocate(tau).f, expected, atol=1e-9)
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        child = pool.apply(_saturated_thrusts, (pickle.dumps(alloc),))
    np.testing.assert_allclose(child, expected, atol=1e-9)


# ------------------------------------------------------------------------------------ properties
_PROPS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _ik_case(xi, level, offset, method, require_hover):
    data = P.data()
    if level:
        xi = xi.copy()
        xi[3:5] = 0.0
    M = kin.ee_placement(P, data, ch.xi_to_q(xi))
    M = pin.SE3(M.rotation, M.translation + np.array([0.0, 0.0, offset]))
    opts = {"require_hover": require_hover}
    if method == "clika":  # the thesis's weighting of the slider; hover: keep roll = pitch = 0 when hover is asked
        opts.update(weights=(1, 1, 1, 1, 1, 1, 1e4, 1, 1), hover=require_hover)
    return data, M, IKSolver(P, method, opts).solve(data, M)


@_PROPS
@given(
    xi=platform_xi_strategy(P, max_pitch=0.6),
    level=st.booleans(),
    offset=st.sampled_from([0.0, 0.5]),
    method=st.sampled_from(["qp", "dls", "clika"]),
    require_hover=st.booleans(),
)
def test_ik_success_means_on_target_within_limits_and_hover_feasible(xi, level, offset, method, require_hover):
    """Targets: the end-effector pose of a random level configuration (reachable in hover) or of a tilted one (in general
    not), possibly moved up 0.5 m."""
    data, M, res = _ik_case(xi, level, offset, method, require_hover)
    if res.success:
        pin.framesForwardKinematics(P.model, data, res.q)
        Me = data.oMf[P.ee_frame]
        assert np.linalg.norm(Me.translation - M.translation) < 1e-6
        assert np.linalg.norm(pin.log3(M.rotation.T @ Me.rotation)) < 1e-6
        assert np.all(res.q[7:] >= P.arm_lower - 1e-12) and np.all(res.q[7:] <= P.arm_upper + 1e-12)
        if require_hover:
            R = pin.Quaternion(res.q[6], *res.q[3:6]).toRotationMatrix()
            assert np.linalg.norm(R[:, 2] - [0.0, 0.0, 1.0]) < 2e-6  # thrust axis vertical
    else:
        assert res.reason and res.status != "converged"


def test_the_ik_property_is_not_vacuous():
    """The property above sees successes and failures of every method (seeded targets, hover required)."""
    rng = np.random.default_rng(4)
    for method in ("qp", "dls", "clika"):
        outcomes = []
        for k in range(12):
            xi = P.neutral_xi()
            xi[0:3], xi[5], xi[6:] = rng.uniform(-2, 2, 3), rng.uniform(-3, 3), rng.uniform(P.arm_lower, P.arm_upper)
            xi[3] = 0.5  # a rolled target orientation: unreachable in hover unless levelled below
            outcomes.append(_ik_case(xi, k % 3 != 0, 0.0, method, True)[2].success)
        assert 0 < sum(outcomes) < len(outcomes), (method, outcomes)


@_PROPS
@given(w=st.lists(st.floats(-200.0, 200.0), min_size=9, max_size=9), platform=st.sampled_from(["q-prr", "hextilt_flying_arm_5"]))
def test_allocation_stays_within_bounds(w, platform):
    p = P if platform == "q-prr" else _HEXTILT
    tau = np.resize(np.array(w), p.nv)
    res = Allocator(p).allocate(tau)
    f = res.f[: p.n_rotors]
    assert np.all(f >= p.thrust_min - 1e-9) and np.all(f <= p.thrust_max + 1e-9)
    assert np.all(np.abs(res.f[p.n_rotors :]) <= p.arm_effort_limits + 1e-12)
    np.testing.assert_allclose(res.tau_achieved, p.actuation_matrix @ res.f, atol=1e-9)


_HEXTILT = qprr.load("hextilt_flying_arm_5")


@settings(max_examples=15, deadline=None)
@given(m=st.integers(1, 6), n_arm=st.integers(0, 4), seed=st.integers(0, 2**31 - 1), status=st.sampled_from(["ok", "diverged"]))
def test_a_result_file_gives_back_the_whole_result(tmp_path_factory, m, n_arm, seed, status):
    rng = np.random.default_rng(seed)
    n = 6 + n_arm
    a = lambda *shape: rng.normal(size=shape)  # noqa: E731
    res = SimResult(
        "sc",
        "ctrl",
        1e-3,
        "rk4",
        np.arange(m) * 1e-3,
        a(m, n),
        a(m, n),
        a(m, n),
        a(m, n),
        a(m, n),
        a(m, 4),
        a(m, n_arm),
        a(m, 3),
        a(m, n),
        rng.integers(0, 8, m).astype(np.int8),
        a(m, n),
        wall_time=0.5,
        status=status,
        reason="why",
        seed=seed,
        control_period=2e-3,
        platform="p",
        names=ch.xi_names(n_arm),
        series={"s": a(m)},
        metrics={"k": float(rng.normal())},
    )
    back = SimResult.load(res.save(tmp_path_factory.mktemp("r") / "r.npz"))
    for k in qprr.sim.result.ARRAYS:
        np.testing.assert_array_equal(getattr(back, k), getattr(res, k))
    assert (
        back.scenario,
        back.controller,
        back.dt,
        back.integrator,
        back.wall_time,
        back.reason,
        back.seed,
        back.control_period,
        back.platform,
        back.names,
        back.metrics,
    ) == (
        res.scenario,
        res.controller,
        res.dt,
        res.integrator,
        res.wall_time,
        res.reason,
        res.seed,
        res.control_period,
        res.platform,
        res.names,
        res.metrics,
    )
    assert back.status.value == status
    np.testing.assert_array_equal(back.series["s"], res.series["s"])


_SOLVER = IKSolver(P, "qp")
_HISTORY_TARGETS = _targets(4, 3)


@settings(max_examples=10, deadline=None)
@given(history=st.lists(st.integers(0, 3), min_size=0, max_size=4), k=st.integers(0, 3))
def test_the_ik_answer_does_not_depend_on_the_call_history(history, k):
    data = P.data()
    for i in history:  # whatever was solved before, on this solver and this data
        _SOLVER.solve(data, _HISTORY_TARGETS[i])
    fresh = IKSolver(P, "qp").solve(P.data(), _HISTORY_TARGETS[k])
    np.testing.assert_array_equal(_SOLVER.solve(data, _HISTORY_TARGETS[k]).q, fresh.q)


def test_every_error_above_is_a_qprr_error():
    for cls in (InputError, ShapeError, NonFiniteError, LimitError, NonPhysicalError, DivergenceError):
        assert issubclass(cls, QprrError)


# ------------------------------------------------------------------- booleans from text (issue 34)
@pytest.mark.parametrize(
    "given, value", [(True, True), (False, False), (1, True), (0, False), ("true", True), ("No", False), (" yes ", True), ("0", False)]
)
def test_a_boolean_is_read_strictly(given, value):
    from qprr.validation import as_bool

    assert as_bool(given, "flag") is value


@pytest.mark.parametrize("given", ["maybe", "on", "", 2, None, 0.5, "Falsch"])
def test_anything_else_is_refused_naming_the_flag(given):
    from qprr.validation import as_bool

    with pytest.raises(InputError, match=r"flag must be true or false"):
        as_bool(given, "flag")


def test_a_scenario_flag_given_as_text_no_is_false():
    """``as_printed="no"`` (a campaign's TOML, a Python call) was taken as True (a non-empty string)."""
    from qprr.scenarios import Option, Scenario

    seen = {}
    sc = Scenario("flag-probe", "", lambda platform, controller, progress, **o: seen.update(o), ("idc",), {"as_printed": Option(False, "")})
    sc.run(as_printed="no")
    assert seen["as_printed"] is False
    sc.run(as_printed="yes")
    assert seen["as_printed"] is True
    with pytest.raises(InputError, match="as_printed.*'maybe'"):
        sc.run(as_printed="maybe")
