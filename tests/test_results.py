"""SimResult: the RMSE (6.26) with wrapped Euler angles, and its versioned file format (round trip, bad files)."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from qprr.errors import InputError, ShapeError
from qprr.sim import FORMAT_VERSION, SimResult, Status, simulate
from qprr.sim.result import ARRAYS
from qprr.thesis import scenarios as scn
from qprr.thesis.missions import NAMES
from qprr.thesis.scenarios import flight_controller
from qprr.trajectory import Hold

FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)
TEXT = st.text(max_size=20)
# a zip member name ends at NUL, a lone surrogate has no UTF-8 form: both are refused (test_save_writes_...)
SERIES_NAMES = st.text(st.characters(blacklist_characters="\x00", blacklist_categories=("Cs",)), max_size=20)


@st.composite
def results(draw) -> SimResult:
    """Any SimResult: m rows, 0-5 arm joints, 1-8 rotors, any float values (NaN, inf, -0.0 included),
    any status and metadata, named extra series (any dtype and shape) and metrics (any float)."""
    m = draw(st.integers(1, 12))
    n_arm = draw(st.integers(0, 5))
    n_rotors = draw(st.integers(1, 8))
    n_xi = 6 + n_arm

    def arr(shape):
        return draw(hnp.arrays(np.float64, shape, elements=FLOATS))

    steps = draw(hnp.arrays(np.float64, m, elements=st.floats(1e-6, 1.0)))
    t = np.cumsum(steps) - steps[0]
    t = t if np.all(np.diff(t) > 0) else np.arange(m) * 1e-3
    series = draw(
        st.dictionaries(
            SERIES_NAMES,
            hnp.arrays(st.sampled_from([np.float64, np.float32, np.int64, np.int8, np.bool_]), st.sampled_from([(m,), (m, 3), (7,), (), (0,)])),
            max_size=4,
        )
    )
    metrics = draw(st.dictionaries(TEXT, FLOATS, max_size=4))
    names = draw(st.one_of(st.just(()), st.lists(TEXT, min_size=n_xi, max_size=n_xi).map(tuple)))
    lows = draw(hnp.arrays(np.float64, n_rotors, elements=st.floats(0.0, 10.0)))
    bounds = draw(st.one_of(st.none(), st.just(np.column_stack([lows, lows + 5.0]))))
    return SimResult(
        scenario=draw(TEXT),
        controller=draw(TEXT),
        dt=draw(st.floats(1e-6, 1.0)),
        integrator=draw(TEXT),
        t=t,
        xi=arr((m, n_xi)),
        xi_dot=arr((m, n_xi)),
        xi_d=arr((m, n_xi)),
        xi_dot_d=arr((m, n_xi)),
        u=arr((m, n_xi)),
        f=arr((m, n_rotors)),
        arm_effort=arr((m, n_arm)),
        x_cm=arr((m, 3)),
        unallocated=arr((m, n_xi)),
        flags=draw(hnp.arrays(np.int8, m, elements=st.integers(0, 7))),
        u_ext=arr((m, n_xi)),
        wall_time=draw(st.floats(0.0, 1e4)),
        status=draw(st.sampled_from(list(Status))),
        reason=draw(TEXT),
        seed=draw(st.one_of(st.none(), st.integers(0, 2**63 - 1))),
        control_period=draw(st.floats(1e-6, 1.0)),
        platform=draw(TEXT),
        names=names,
        series=series,
        metrics=metrics,
        rotor_bounds=bounds,
    )


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit for bit: dtype, shape and bytes (NaN payloads and signed zeros included)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _same_number(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1.0, a) == math.copysign(1.0, b))


@settings(max_examples=60, deadline=None)
@given(results())
def test_save_load_round_trip_is_bit_exact(res):
    with tempfile.TemporaryDirectory() as tmp:
        back = SimResult.load(res.save(Path(tmp) / "run.npz"))
    for k in ARRAYS:
        assert _same_array(getattr(back, k), getattr(res, k)), k
    for k in ("scenario", "controller", "dt", "integrator", "wall_time", "status", "reason", "seed", "control_period", "platform", "names"):
        assert getattr(back, k) == getattr(res, k), k
    assert isinstance(back.status, Status)
    assert (back.rotor_bounds is None) == (res.rotor_bounds is None)
    if res.rotor_bounds is not None:
        assert _same_array(back.rotor_bounds, res.rotor_bounds)
    assert set(back.series) == set(res.series) and all(_same_array(back.series[k], np.asarray(v)) for k, v in res.series.items())
    assert set(back.metrics) == set(res.metrics) and all(_same_number(back.metrics[k], v) for k, v in res.metrics.items())


def test_a_scenario_run_with_extras_round_trips(tmp_path):
    """A payload release: its series (carried mass, estimate) and metrics (release and recovery times) come back."""
    res = scn.payload_drop(settings=scn.PayloadDropSettings(mission="hover", release_time=0.1, duration=0.3))
    assert {"payload_mass", "mass_estimate"} <= set(res.series) and {"release_time", "recovery_time"} <= set(res.metrics)
    back = SimResult.load(res.save(tmp_path / "drop.npz"))
    for k in ARRAYS:
        np.testing.assert_array_equal(getattr(back, k), getattr(res, k))
    for k, v in res.series.items():
        np.testing.assert_array_equal(back.series[k], v)
    assert back.metrics == res.metrics  # the recovery time is inf here (not recovered in 0.2 s): kept as inf
    assert back.platform == res.platform and back.names == res.names == ("x", "y", "z", "phi", "theta", "psi", "r0", "theta2", "theta3")
    assert scn.recovery_of(back) == scn.recovery_of(res)


def test_save_writes_the_format_version_and_never_creates_folders(tmp_path):
    res = _result()
    path = res.save(tmp_path / "r.npz")
    with np.load(path) as z:
        assert json.loads(str(z["meta"]))["format_version"] == FORMAT_VERSION == 3
    with pytest.raises(InputError, match="folder .*missing.* does not exist"):
        res.save(tmp_path / "missing" / "r.npz")
    assert not (tmp_path / "missing").exists()
    with pytest.raises(InputError, match=r"\.npz"):
        res.save(tmp_path / "r.txt")
    with pytest.raises(InputError, match="metric 'x' must be a number"):
        _result(metrics={"x": "fast"}).save(tmp_path / "m.npz")
    with pytest.raises(InputError, match="series name 'a\\\\x00b' cannot be stored"):
        _result(series={"a\x00b": np.zeros(6)}).save(tmp_path / "s.npz")
    with pytest.raises(InputError, match="series name '.ud800' cannot be stored"):
        _result(series={"\ud800": np.zeros(6)}).save(tmp_path / "s.npz")
    with pytest.raises(InputError, match="named by strings, got 3"):
        _result(series={3: np.zeros(6)}).save(tmp_path / "s.npz")
    assert not (tmp_path / "m.npz").exists() and not (tmp_path / "s.npz").exists()


# ------------------------------------------------------------------------------ bad files
def _result(m: int = 6, n_arm: int = 3, n_rotors: int = 4, **extra) -> SimResult:
    rng = np.random.default_rng(7)
    n_xi = 6 + n_arm
    a = {k: rng.normal(size=(m, n_xi)) for k in ("xi", "xi_dot", "xi_d", "xi_dot_d", "u", "u_ext", "unallocated")}
    kw = dict(
        scenario="s",
        controller="c",
        dt=1e-3,
        integrator="midpoint",
        t=np.arange(m) * 1e-3,
        f=rng.normal(size=(m, n_rotors)),
        arm_effort=rng.normal(size=(m, n_arm)),
        x_cm=rng.normal(size=(m, 3)),
        flags=np.zeros(m, dtype=np.int8),
        series={"contact_force": np.linspace(0.0, 1.0, m)},
        metrics={"release_time": 0.5},
        **a,
    )
    kw.update(extra)
    return SimResult(**kw)


@pytest.fixture()
def saved(tmp_path) -> Path:
    return _result().save(tmp_path / "good.npz")


def _rewrite(src: Path, dst: Path, arrays=None, meta=None, drop=()) -> Path:
    """Copy of a result file with arrays replaced or dropped and metadata entries changed (``meta`` a dict) or replaced (a string)."""
    with np.load(src) as z:
        content = {k: z[k] for k in z.files}
    m = json.loads(str(content["meta"]))
    if isinstance(meta, dict):
        m.update(meta)
    content["meta"] = np.array(meta if isinstance(meta, str) else json.dumps(m))
    content.update(arrays or {})
    for k in drop:
        content.pop(k)
    np.savez(dst, **content)
    return dst


def test_load_rejects_missing_foreign_truncated_and_corrupted_files(saved, tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        SimResult.load(tmp_path / "nothing.npz")
    raw = saved.read_bytes()
    cases = {
        "empty": b"",
        "text": b"t,x,y\n0,1,2\n",
        "truncated": raw[: len(raw) // 2],
        "tail cut": raw[:-40],
    }
    for name, content in cases.items():
        path = tmp_path / f"{name}.npz"
        path.write_bytes(content)
        with pytest.raises(InputError, match=r"not a qprr result file") as err:
            SimResult.load(path)
        assert str(path) in str(err.value), name
    # a data member damaged inside an intact zip: the array it breaks is named
    damaged = bytearray(raw)
    with np.load(saved) as z:
        assert "xi" in z.files
    start = raw.index(b"xi.npy") + 100  # inside the compressed data of xi
    damaged[start : start + 40] = bytes(40)
    path = tmp_path / "damaged.npz"
    path.write_bytes(bytes(damaged))
    with pytest.raises(InputError, match=r"cannot read 'xi'.*truncated, corrupted"):
        SimResult.load(path)
    # a foreign .npz, a single .npy array, a version-1 file (qprr 0.1: no metadata), pickled objects
    np.savez(tmp_path / "foreign.npz", a=np.zeros(3))
    with pytest.raises(InputError, match="no qprr metadata"):
        SimResult.load(tmp_path / "foreign.npz")
    np.save(tmp_path / "single.npy", np.zeros(3))
    (tmp_path / "single.npz").write_bytes((tmp_path / "single.npy").read_bytes())
    with pytest.raises(InputError, match="single array"):
        SimResult.load(tmp_path / "single.npz")
    with pytest.raises(InputError, match="format version 1; this qprr reads versions 2, 3"):
        SimResult.load(_rewrite(saved, tmp_path / "v1.npz", meta={"format_version": 1}))
    objects = np.empty(6, dtype=object)
    with pytest.raises(InputError, match="cannot read 'xi'"):
        SimResult.load(_rewrite(saved, tmp_path / "obj.npz", arrays={"xi": objects}))


@pytest.mark.parametrize(
    "change, error, pattern",
    [
        (dict(drop=("u",)), InputError, r"lacks the arrays \['u'\]"),
        (dict(drop=("series_contact_force",)), InputError, r"lacks the series \['contact_force'\]"),
        (dict(meta="{not json"), InputError, "corrupted metadata"),
        (dict(meta="[1, 2]"), InputError, "corrupted metadata .*JSON object"),
        (dict(meta={"status": "exploded"}), InputError, "unknown status 'exploded'"),
        (dict(meta={"dt": float("nan")}), InputError, "dt must be a number > 0"),
        (dict(meta={"scenario": None}), InputError, "scenario must be a string"),
        (dict(meta={"seed": "7"}), InputError, "seed must be an integer"),
        (dict(meta={"metrics": {"release_time": "soon"}}), InputError, "metrics must map names to numbers"),
        (dict(meta={"names": ["x", "y"]}), ShapeError, "names has 2 entries for xi's 9 columns"),
        (dict(arrays={"t": np.zeros((6, 1))}), ShapeError, "t must be a 1-D float array"),
        (dict(arrays={"t": np.array([0.0, 2e-3, 1e-3, 3e-3, 4e-3, 5e-3])}), InputError, "t must be finite and increasing"),
        (dict(arrays={"xi": np.zeros((6, 5))}), ShapeError, r"xi must have shape \(6, 6 \+ n_arm\), got \(6, 5\)"),
        (dict(arrays={"xi": np.zeros((6, 9), dtype=int)}), InputError, "xi must be float"),
        (dict(arrays={"xi_dot": np.zeros((6, 8))}), ShapeError, r"xi_dot must have shape \(6, 9\), got \(6, 8\)"),
        (dict(arrays={"u": np.zeros((5, 9))}), ShapeError, "u has shape .* t has 6 rows"),
        (dict(arrays={"arm_effort": np.zeros((6, 2))}), ShapeError, r"arm_effort must have shape \(6, 3\)"),
        (dict(arrays={"x_cm": np.zeros((6, 2))}), ShapeError, r"x_cm must have shape \(6, 3\)"),
        (dict(arrays={"unallocated": np.zeros((6, 4))}), ShapeError, r"unallocated must have shape \(6, 9\)"),
        (dict(arrays={"f": np.zeros(6)}), ShapeError, r"f must have shape \(6, n_rotors >= 1\)"),
        (dict(arrays={"flags": np.zeros(6)}), InputError, "flags must be a 1-D integer array"),
    ],
)
def test_load_rejects_wrong_shapes_types_and_metadata(saved, tmp_path, change, error, pattern):
    path = _rewrite(saved, tmp_path / "bad.npz", **change)
    with pytest.raises(error, match=pattern) as err:
        SimResult.load(path)
    assert str(path) in str(err.value)


# ------------------------------------------------------------------------------ RMSE
def test_rmse_wraps_euler_angle_errors():
    """Yaw reference pi - 0.01, measured -pi + 0.01 (and the same for roll): the true error is 0.02 rad, not 2 pi - 0.02.
    Arm joints and positions are not wrapped."""
    m = 10
    res = _result(m=m, series={}, metrics={}, names=NAMES)
    res.xi[:] = 0.0
    res.xi_d[:] = 0.0
    res.xi_d[:, 5], res.xi[:, 5] = math.pi - 0.01, -math.pi + 0.01
    res.xi_d[:, 3], res.xi[:, 3] = -math.pi + 0.005, math.pi - 0.005
    res.xi_d[:, 7], res.xi[:, 7] = 3.0, -3.0  # a revolute arm joint: 6 rad is its true error
    res.xi_d[:, 0], res.xi[:, 0] = 4.0, -3.0
    e = res.rmse()
    assert e["psi"] == pytest.approx(0.02, abs=1e-12)
    assert e["phi"] == pytest.approx(0.01, abs=1e-12)
    assert e["theta2"] == pytest.approx(6.0, rel=1e-15) and e["x"] == pytest.approx(7.0, rel=1e-15)
    assert e["theta"] == 0.0


def test_yaw_held_across_pi_reports_the_true_error(robot):
    """The IDC holds psi_d = pi - 0.005 from psi = -pi + 0.005 (0.01 rad away across the +-pi cut): the logged yaw jumps by
    2 pi where it crosses the cut, the RMSE reports the 0.01 rad error decaying to zero."""
    xi_d = np.array([0.0, 0.0, 2.0, 0.0, 0.0, math.pi - 0.005, 0.0, 0.0, 0.0])
    xi0 = xi_d.copy()
    xi0[5] = -math.pi + 0.005
    res = simulate(robot, flight_controller("idc", robot), Hold(tuple(xi_d)), 2.0, xi0=xi0)
    assert res.xi[0, 5] < -3.1 and res.xi[-1, 5] > 3.1  # crossed the cut
    naive = np.sqrt(np.mean((res.xi_d[:, 5] - res.xi[:, 5]) ** 2))
    assert naive > 0.5
    e = res.rmse()["psi"]
    assert 1e-4 < e < 0.01
    late = res.rmse(start=1.5)["psi"]
    assert late < 1e-3 * e


# ------------------------------------------------------------------------------ rotor bounds (format 3)
def test_rotor_bounds_are_recorded_by_a_run_and_kept_in_its_file(robot, tmp_path):
    """A run records its allocation's bounds per rotor (the Q-PRR's [0, 20] N); the file keeps them (format 3); a
    format-2 file (no rotor_bounds member) still loads, without them; a bounds array of another shape is refused."""
    res = simulate(robot, flight_controller("idc", robot), Hold((0, 0, 1, 0, 0, 0, 0, 0, 0)), 0.05)
    expected = np.column_stack([robot.thrust_min, robot.thrust_max])
    np.testing.assert_array_equal(res.rotor_bounds, expected)
    assert np.all(res.f >= res.rotor_bounds[:, 0]) and np.all(res.f <= res.rotor_bounds[:, 1])
    path = res.save(tmp_path / "r.npz")
    np.testing.assert_array_equal(SimResult.load(path).rotor_bounds, expected)
    old = SimResult.load(_rewrite(path, tmp_path / "v2.npz", meta={"format_version": 2}, drop=("rotor_bounds",)))
    assert old.rotor_bounds is None
    np.testing.assert_array_equal(old.f, res.f)
    with pytest.raises(ShapeError, match=r"rotor_bounds must have shape \(4, 2\)") as err:
        SimResult.load(_rewrite(path, tmp_path / "bad.npz", arrays={"rotor_bounds": np.zeros((3, 2))}))
    assert "bad.npz" in str(err.value)
    with pytest.raises(InputError, match=r"f_min <= f_max"):
        _result(rotor_bounds=np.array([[1.0, 0.0]] * 4))


def test_rmse_from_a_start_after_the_run_is_refused():
    res = _result(m=6, series={}, metrics={})  # ticks at 0 ... 5 ms
    assert set(res.rmse(start=5e-3)) == set(res.names)
    for start in (6e-3, 1.0):
        with pytest.raises(InputError, match=r"start = .* after the last logged tick .*\[0\.0, 0\.005\] s"):
            res.rmse(start=start)
