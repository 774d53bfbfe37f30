"""PX4 export and import (qprr.flightstack.frames, qprr.flightstack.px4): frames, PX4's effectiveness and normalised
mix against hand-worked numbers and qprr's own rotor matrix, .params files float32-exact, refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr.errors import ActuationError, InputError, ShapeError
from qprr.flightstack import frames as fr
from qprr.flightstack import px4
from qprr.rotors import Rotor, ring, rotor_matrix

LOG = Path(__file__).resolve().parents[2] / "shared" / "data" / "flightlogs" / "sample_px4_events.ulg"
C = np.diag([1.0, -1.0, -1.0])


@pytest.fixture(scope="module")
def platforms():
    return {
        "q-prr": qprr.load("q-prr"),
        "borinot": qprr.load("borinot_flying_arm_2"),
        "hextilt": qprr.load("hextilt_flying_arm_5"),
        "HEX-RRR": qprr.build("HEX-RRR"),
    }


def iris_geometry() -> px4.Px4Geometry:
    """PX4 SITL's iris (the CA_* parameters of sample_px4_events.ulg): 4 rotors, CT 6.5 N, KM +-0.05 m."""
    pos = [(0.1515, 0.245), (-0.1515, -0.1875), (0.1515, -0.245), (-0.1515, 0.1875)]
    km = [0.05, 0.05, -0.05, -0.05]
    return px4.Px4Geometry(tuple(px4.Px4Rotor((px4.f32(x), px4.f32(y), 0.0), (0.0, 0.0, -1.0), 6.5, px4.f32(k)) for (x, y), k in zip(pos, km)))


# ------------------------------------------------------------------ frames
def test_frames_round_trip_and_rotation():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(20, 3))
    w = rng.normal(size=(20, 3))
    np.testing.assert_array_equal(fr.body_from_frd(fr.frd_from_body(v)), v)
    np.testing.assert_array_equal(fr.world_from_ned(fr.ned_from_world(v)), v)
    np.testing.assert_array_equal(fr.frd_from_body(v[0]), C @ v[0])
    # a proper rotation: cross products commute with the map (moments map like vectors)
    np.testing.assert_allclose(np.cross(fr.frd_from_body(v), fr.frd_from_body(w)), fr.frd_from_body(np.cross(v, w)), atol=1e-15)
    assert np.linalg.det(fr.FLU_TO_FRD) == 1.0
    # forward stays forward, up becomes -down, left becomes -right
    np.testing.assert_array_equal(fr.frd_from_body([1.0, 2.0, 3.0]), [1.0, -2.0, -3.0])


def test_attitude_conversions_and_quaternion():
    rng = np.random.default_rng(1)
    q = rng.normal(size=(10, 4))
    R = fr.R_ned_frd_from_quaternion_wxyz(q)
    assert R.shape == (10, 3, 3)
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    Rw = fr.R_world_body_from_ned_frd(R)
    np.testing.assert_allclose(fr.R_ned_frd_from_world_body(Rw), R, atol=0)
    # the same physical vector: v_ned = R_nf v_frd  <=>  v_world = R_wb v_body
    v_body = rng.normal(size=3)
    np.testing.assert_allclose(fr.world_from_ned(R[0] @ fr.frd_from_body(v_body)), Rw[0] @ v_body, atol=1e-12)
    # PX4's level attitude heading north is qprr's identity; yaw 90 deg (east) is qprr's yaw -90 deg (NWU)
    np.testing.assert_allclose(fr.R_world_body_from_quaternion_wxyz([1.0, 0, 0, 0]), np.eye(3))
    c = math.cos(math.pi / 4)
    R_east = fr.R_world_body_from_quaternion_wxyz([c, 0, 0, c])
    np.testing.assert_allclose(R_east @ [1.0, 0, 0], [0.0, -1.0, 0.0], atol=1e-15)  # nose east = -y of NWU
    with pytest.raises(ShapeError, match="q must have shape"):
        fr.R_ned_frd_from_quaternion_wxyz([1.0, 0.0, 0.0])
    with pytest.raises(InputError, match="zero quaternion"):
        fr.R_ned_frd_from_quaternion_wxyz([0.0, 0.0, 0.0, 0.0])


# ------------------------------------------------------------------ effectiveness and sign convention
@pytest.mark.parametrize("name", ["q-prr", "borinot", "hextilt", "HEX-RRR"])
def test_effectiveness_is_qprr_rotor_matrix_in_frd(platforms, name):
    """PX4's CT (p x a) - CT KM a, CT a equals qprr's f_max [p x a + s kappa a; a] about the CoG, mapped to FRD:
    the sign of KM (-s kappa) and the frames are right."""
    p = platforms[name]
    q_arm = 0.5 * (p.arm_lower + p.arm_upper) + 0.3 * (p.arm_upper - p.arm_lower)
    g = px4.geometry_from_platform(p, q_arm)
    c = px4.com_body_at(p, q_arm)
    moved = tuple(Rotor(tuple(np.subtract(r.position_body, c)), r.axis_body, r.spin, r.kappa, r.f_min, r.f_max) for r in p.rotors)
    Omega = rotor_matrix(moved) * np.array([r.f_max for r in p.rotors])
    expected = np.vstack([C @ Omega[3:6], C @ Omega[0:3]])
    np.testing.assert_allclose(g.effectiveness(), expected, atol=1e-6 * np.abs(expected).max())


def test_km_sign_matches_px4_ccw_positive():
    """A lifting rotor turning counter-clockwise seen from above pushes the body clockwise (about +z down, FRD):
    PX4's KM > 0; in qprr its drag torque points down, -axis: spin -1."""
    r = Rotor((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), -1, 0.02, 0.0, 10.0)
    g = px4.geometry_from_rotors([r] * 1, check=False)
    assert g.rotors[0].km == pytest.approx(0.02)
    assert g.effectiveness()[2, 0] == pytest.approx(10.0 * 0.02)  # Mz (FRD, down) = CT KM > 0
    assert px4.rotors_from_geometry(g)[0].spin == -1


# ------------------------------------------------------------------ PX4's mix on the iris
def test_iris_mix_by_hand():
    g = iris_geometry()
    E = g.effectiveness()
    np.testing.assert_allclose(E[5], [-6.5] * 4)
    np.testing.assert_allclose(E[2], 6.5 * np.array([0.05, 0.05, -0.05, -0.05]), rtol=1e-6)
    np.testing.assert_allclose(E[0], -6.5 * np.array([0.245, -0.1875, -0.245, 0.1875]), rtol=1e-6)  # Mx = -CT py
    np.testing.assert_allclose(E[1], 6.5 * np.array([0.1515, -0.1515, 0.1515, -0.1515]), rtol=1e-6)  # My = CT px
    M = g.mix()
    raw = np.linalg.pinv(E)
    # a right inverse on the controllable rows: E M = diag(scale) on Mx, My, Mz, Fz
    s = g.normalization_scale()
    rows = [0, 1, 2, 5]
    np.testing.assert_allclose((E @ M)[np.ix_(rows, rows)], np.diag(1.0 / s[rows]), atol=1e-9)
    # the normalisation, by hand: roll/pitch share sqrt(|col|^2 / (4/2)) of the larger, yaw by its largest entry,
    # thrust by the mean |entry| (so every rotor gets -1 per unit of thrust z)
    sr = max(math.sqrt(raw[:, 0] @ raw[:, 0] / 2.0), math.sqrt(raw[:, 1] @ raw[:, 1] / 2.0))
    np.testing.assert_allclose(s[[0, 1, 2, 5]], [sr, sr, raw[:, 2].max(), np.abs(raw[:, 5]).mean()], rtol=1e-12)
    np.testing.assert_allclose(M[:, 5], [-1.0] * 4, rtol=1e-12)
    np.testing.assert_allclose(M[:, 2].max(), 1.0)
    np.testing.assert_array_equal(M[:, 3:5], 0.0)  # no lateral thrust: empty columns (scaled by z's scale, then 0)
    np.testing.assert_allclose(s[3:5], s[5])
    # hover: thrust z -0.6 gives 0.6 on every motor; a roll-right command (Mx > 0, FRD) raises the left motors (y < 0)
    np.testing.assert_allclose(g.allocate([0, 0, 0, 0, 0, -0.6]), [0.6] * 4)
    u = g.allocate(np.array([[0.1, 0, 0, 0, 0, -0.5]]))
    assert u.shape == (1, 4) and u[0, 1] > 0.5 and u[0, 2] > 0.5 and u[0, 0] < 0.5 and u[0, 3] < 0.5


def test_mix_zeroes_small_entries():
    g = iris_geometry()
    M = g.mix()
    assert np.all((M == 0.0) | (np.abs(M) >= px4.MIX_ZERO))


@pytest.mark.skipif(not LOG.exists(), reason="the SITL log is not in ../shared/data/flightlogs")
def test_sitl_log_parameters_are_the_iris():
    pyulog = pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")
    params = pyulog.ULog(str(LOG), message_name_filter_list=[]).initial_parameters
    g = px4.Px4Geometry.from_parameters(params)
    assert g.n == 4 and g.airframe == 0
    np.testing.assert_array_equal(g.effectiveness(), iris_geometry().effectiveness())
    # export - import - export: the log's own numbers come back bit for bit
    again = px4.geometry_from_rotors(px4.rotors_from_geometry(g))
    assert again.parameters() == {k: v for k, v in g.parameters().items()}
    for k, v in g.parameters().items():
        assert params[k] == v


# ------------------------------------------------------------------ round trips
@pytest.mark.parametrize("name", ["q-prr", "borinot", "hextilt", "HEX-RRR"])
def test_params_file_round_trip_float32_exact(platforms, name, tmp_path):
    p = platforms[name]
    g = px4.geometry_from_platform(p)
    path = px4.write_params(g, tmp_path / "x.params", header=[f"platform {p.name}"])
    read = px4.read_params(path)
    assert read == g.parameters()
    g2 = px4.Px4Geometry.from_parameters(read)
    rotors = px4.rotors_from_geometry(g2)
    g3 = px4.geometry_from_rotors(rotors)
    for k, v in g.parameters().items():
        assert np.float32(g3.parameters()[k]).tobytes() == np.float32(v).tobytes(), k
    np.testing.assert_allclose(g3.effectiveness(), g.effectiveness(), rtol=1e-6, atol=1e-6)


def test_params_text_is_qgroundcontrol(tmp_path):
    path = px4.write_params(iris_geometry(), tmp_path / "iris.params", header=["platform iris"])
    lines = path.read_text().splitlines()
    assert lines[0].startswith("#") and any("qprr" in x for x in lines if x.startswith("#"))
    body = [x.split("\t") for x in lines if not x.startswith("#")]
    assert all(len(x) == 5 for x in body)
    kinds = {x[2]: x[4] for x in body}
    assert kinds["CA_ROTOR_COUNT"] == "6" and kinds["CA_AIRFRAME"] == "6" and kinds["CA_ROTOR0_PX"] == "9"
    assert dict((x[2], x[3]) for x in body)["CA_ROTOR0_PX"] == "0.1515"


def test_read_params_refuses_malformed_lines(tmp_path):
    path = tmp_path / "bad.params"
    path.write_text("# header\n1\t1\tCA_ROTOR_COUNT\t4\t6\n1\t1\tCA_ROTOR0_PX\tabc\t9\n")
    with pytest.raises(InputError, match="line 3"):
        px4.read_params(path)
    path.write_text("1\t1\tCA_ROTOR_COUNT\t4\n")
    with pytest.raises(InputError, match="line 1.*5 fields"):
        px4.read_params(path)
    path.write_text("1\t1\tCA_ROTOR_COUNT\t4\t6\n1\t1\tCA_ROTOR_COUNT\t4\t6\n")
    with pytest.raises(InputError, match="given twice"):
        px4.read_params(path)


def test_missing_parameter_is_named():
    params = iris_geometry().parameters()
    del params["CA_ROTOR2_KM"]
    with pytest.raises(InputError, match="CA_ROTOR2_KM is missing"):
        px4.Px4Geometry.from_parameters(params)


# ------------------------------------------------------------------ refusals
def test_refuses_infinite_thrust():
    with pytest.raises(InputError, match="f_max = inf"):
        px4.geometry_from_rotors(ring(4, 0.2, kappa=0.02))


def test_refuses_same_spins_lost_yaw():
    rotors = ring(4, 0.2, kappa=0.02, f_max=10.0, spins=(1, 1, 1, 1))
    with pytest.raises(ActuationError, match="Mz"):
        px4.geometry_from_rotors(rotors)


def test_refuses_rotors_on_a_line():
    rotors = tuple(Rotor((x, 0.0, 0.0), (0, 0, 1), s, 0.02, 0.0, 10.0) for x, s in [(-0.3, 1), (-0.1, -1), (0.1, 1), (0.3, -1)])
    with pytest.raises(ActuationError, match="Mx"):
        px4.geometry_from_rotors(rotors)


def test_refuses_upside_down_axes():
    rotors = tuple(Rotor(r.position_body, (0.0, 0.0, -1.0), r.spin, r.kappa, 0.0, 10.0) for r in ring(4, 0.2, kappa=0.02))
    with pytest.raises(ActuationError, match="points down"):
        px4.geometry_from_rotors(rotors)


def test_refuses_ill_conditioned_yaw():
    rotors = ring(4, 0.2, kappa=1e-6, f_max=10.0)
    with pytest.raises(ActuationError, match="condition number"):
        px4.geometry_from_rotors(rotors)


def test_fully_actuated_keeps_six_rows(platforms):
    g = px4.geometry_from_platform(platforms["hextilt"])
    M = g.mix()
    E = g.effectiveness()
    s = g.normalization_scale()
    np.testing.assert_allclose(E @ M, np.diag(1.0 / s), atol=1e-6)  # a right inverse on all six rows


def test_pose_outside_limits_refused(platforms):
    p = platforms["q-prr"]
    with pytest.raises(InputError, match="not in"):
        px4.geometry_from_platform(p, p.arm_upper + 1.0)
