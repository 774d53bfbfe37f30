"""Singularity map: det(J J^T) of (4.44) and the printed (4.46)-(4.48), det J* of (4.28), Pinocchio, distance."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.analysis import singularity
from qprr.errors import InputError, UnknownNameError


def printed():
    from qprr.thesis import printed as printed_forms  # an import error is a failure, not a skip

    return printed_forms


@pytest.fixture(scope="module")
def qp():
    return qprr.load("q-prr")


@pytest.fixture(scope="module")
def pose_map(qp):
    return singularity(qp, n_samples=30_000)


def test_system_det_is_4_44_and_the_printed_4_46_to_4_48(qp, pose_map):
    th = printed()
    p = qp.params
    d = (p.d0, p.d1, p.d2, p.d3)
    q = pose_map.grid.configurations()
    for i in np.random.default_rng(0).choice(len(q), 300, replace=False):
        assert abs(pose_map.det_system[i] - th.det_JJt_4_44(q[i][0], q[i][1], d)) < 1e-11
    g = pose_map.grid
    D = pose_map.det_system.reshape(g.shape)
    for r0, fn in [(-0.04, th.sol_4_46), (0.0, th.sol_4_47), (0.04, th.sol_4_48)]:
        i = int(np.argmin(np.abs(g.axes[0] - r0)))
        assert g.axes[0][i] == r0
        ref = np.array([fn(t) for t in g.axes[1]])
        assert np.abs(D[i, :, :] - ref[:, None]).max() < 2e-4  # 4-digit coefficients as printed
    assert D.min() > 6.0  # never singular, as the thesis concludes from (4.46)-(4.48)


def test_system_det_is_pinocchio_on_every_platform():
    """det(J J^T) with J = Pinocchio's world Jacobian times the rate map of the thesis chart (4.13), at zero Euler angles."""
    from qprr import charts, kinematics

    for name in ("q-prr", "hextilt_flying_arm_5", "HEX-RRR"):
        p = qprr.build(name) if name.isupper() else qprr.load(name)
        r = singularity(p, n_samples=3000)
        q = r.grid.configurations()
        d = p.data()
        for i in np.random.default_rng(1).choice(len(q), 20, replace=False):
            xi = np.concatenate([np.zeros(6), q[i]])
            J = kinematics.jacobian_xi(p, d, xi)
            assert abs(np.linalg.det(J @ J.T) - r.det_system[i]) < 1e-11 * r.det_system[i]
            np.testing.assert_allclose(charts.rate_map(xi)[0:6, 0:6], np.eye(6))


def test_task_det_is_4_28_and_the_singular_set_is_theta2_zero(qp, pose_map):
    """Rows (x, z, omega_y) of the arm Jacobian (4.27): det J* = -d2 s2 (4.28), times the length scale of the omega row."""
    r = pose_map
    assert r.rows == ("v_x", "v_z", "w_y") and r.rank == 3
    q = r.grid.configurations()
    L = r.length
    np.testing.assert_allclose(r.det_task, -L * qp.params.d2 * np.sin(q[:, 1]), atol=1e-15)
    th2 = q[:, 1]
    step = r.grid.spacing[1]
    assert np.all(r.singular[np.abs(th2) < 1e-12])
    assert not np.any(r.singular[np.abs(th2) > 1.01 * step])
    # distance to the plane theta2 = 0 (radians): |theta2| to the grid's resolution
    assert np.abs(r.distance - np.abs(th2)).max() <= step + 1e-12


def test_manipulability_and_condition_from_pinocchio(qp, pose_map):
    r = pose_map
    q = r.grid.configurations()
    d = qp.data()
    W = np.diag([1.0, 1.0, r.length])
    for i in np.random.default_rng(2).choice(len(q), 50, replace=False):
        qq = pin.neutral(qp.model)
        qq[7:] = q[i]
        J = pin.computeFrameJacobian(qp.model, d, qq, qp.ee_frame, pin.LOCAL_WORLD_ALIGNED)[[0, 2, 4], 6:]
        s = np.linalg.svd(W @ J, compute_uv=False)
        np.testing.assert_allclose(r.sigma[i], s, rtol=1e-10, atol=1e-15)
        assert abs(r.manipulability[i] - np.sqrt(abs(np.linalg.det(W @ J @ J.T @ W)))) < 1e-12


def test_position_task_of_the_2r_arm_is_singular_when_stretched(qp):
    """Slider locked, position task: det = d2 d3 sin(theta3) vanishes at theta3 = 0 only (the arm straight)."""
    r = singularity(qp, n_samples=20_000, task="position", locked={"r0": 0.0})
    assert r.rows == ("v_x", "v_z") and r.rank == 2
    q = r.grid.configurations()
    np.testing.assert_allclose(r.manipulability, qp.params.d2 * qp.params.d3 * np.abs(np.sin(q[:, 2])), atol=1e-15)
    assert np.all(r.singular[np.abs(q[:, 2]) < 1e-12])
    assert not np.any(r.singular[np.abs(q[:, 2]) > 0.1])


def test_generic_platforms():
    b = singularity(qprr.load("borinot_flying_arm_2"), n_samples=5000)
    assert b.rank == 2 and not b.singular.any() and np.all(np.isinf(b.distance))  # two parallel axes: full column rank
    h = singularity(qprr.load("hextilt_flying_arm_5"), n_samples=20_000, task="position")
    assert h.rank == 3 and h.singular.any() and np.isfinite(h.distance).all()


def test_singularity_input_errors(qp):
    with pytest.raises(UnknownNameError, match="pose"):
        singularity(qp, n_samples=1000, task="orientation")
    with pytest.raises(InputError, match="tol"):
        singularity(qp, n_samples=1000, tol=0.0)


def test_singularity_options_and_keywords_agree(qp):
    from qprr.analysis import SingularityOptions

    a = singularity(qp, SingularityOptions(n_samples=2000, task="position"))
    b = singularity(qp, n_samples=2000, task="position")
    np.testing.assert_array_equal(a.manipulability, b.manipulability)
    np.testing.assert_array_equal(a.distance, b.distance)
    with pytest.raises(InputError, match="SingularityOptions"):
        singularity(qp, {"n_samples": 2000})
