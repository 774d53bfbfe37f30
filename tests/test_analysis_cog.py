"""CoG regions and the balance map: closed forms (3.78)-(3.80), (6.33) and Pinocchio's CoM, any platform."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr import kinematics
from qprr.analysis import balance, cog_regions
from qprr.errors import InputError, UnknownNameError


def printed():
    from qprr.thesis import printed as printed_forms  # an import error is a failure, not a skip

    return printed_forms


@pytest.fixture(scope="module")
def qp():
    return qprr.load("q-prr")


@pytest.fixture(scope="module")
def regions(qp):
    return cog_regions(qp, n_samples=40_000, payload_masses=[0.0, 0.5], payload_offset=[0.0, 0.0, 0.03])


def loaded(p, m, offset):
    model = pin.Model(p.model)
    f = p.model.frames[p.ee_frame]
    model.inertias[f.parentJoint] = model.inertias[f.parentJoint] + pin.Inertia(m, f.placement.act(np.asarray(offset)), np.zeros((3, 3)))
    return p.with_model(model)


def test_cog_region_is_3_78_corrected_and_3_80(qp, regions):
    """CoG in B over the grid = (3.78) corrected (payload at d_cl along link 3 = the end-effector z), x_cm = (3.80)."""
    th = printed()
    for k, m in enumerate(regions.masses):
        r = regions.regions[(0, k)]
        q = r.grid.configurations()
        idx = np.random.default_rng(k).choice(len(q), 200, replace=False)
        for i in idx:
            ref = th.com_3_78_corrected(q[i], qp.params, m_l=m, d_cl=0.03)
            np.testing.assert_allclose(r.com[i], ref, atol=1e-15)
            if m == 0.0:
                assert abs(r.com[i, 0] - th.x_cm_3_80(q[i], qp.params)) < 1e-15
        np.testing.assert_allclose(r.offset, r.com[:, [0, 1]], atol=1e-16)  # thrust axis = z_B: offset = (x_cm, y_cm)


def test_cog_region_matches_pinocchio_with_payload(qp, regions):
    p2 = loaded(qp, 0.5, [0.0, 0.0, 0.03])
    d = p2.data()
    r = regions.regions[(0, 1)]
    q = r.grid.configurations()
    for i in np.random.default_rng(1).choice(len(q), 100, replace=False):
        qq = pin.neutral(p2.model)
        qq[7:] = q[i]
        np.testing.assert_allclose(r.com[i], kinematics.com_body(p2, d, qq), atol=1e-15)


def test_thesis_statements_on_the_cog_regions(qp, regions):
    """Sec. 6.3.3: the CoG stays below d0 + d1; Fig. 6.47/6.48: a payload and the slider both widen the region."""
    p = qp.params
    for r in regions.regions.values():
        assert r.com[:, 2].max() < p.d0 + p.d1
        np.testing.assert_array_equal(r.com[:, 1], 0.0)  # y_cm = 0 (3.78)
    free0, lock0 = regions.regions[(0, 0)], regions.regions[(1, 0)]
    free1, lock1 = regions.regions[(0, 1)], regions.regions[(1, 1)]
    assert free0.measure.measure > lock0.measure.measure and free1.measure.measure > lock1.measure.measure
    assert free1.measure.measure > free0.measure.measure and lock1.measure.measure > lock0.measure.measure
    # the slider moves the CoG by beta1 r0 = (m1 + m2 + m3)/m_G r0 along x (6.33), whatever theta2, theta3
    beta1 = p.arm_mass / p.total_mass
    g = free0.grid
    C = free0.com.reshape(*g.shape, 3)
    mid = g.shape[0] // 2
    shift = C - C[mid][None]
    np.testing.assert_allclose(shift[..., 0], beta1 * (g.axes[0] - g.axes[0][mid])[:, None, None] * np.ones(g.shape), atol=1e-16)
    np.testing.assert_allclose(shift[..., 1:], 0.0, atol=1e-16)


def test_balance_is_the_zero_of_6_33(qp):
    """r* = -(beta2 s2 + beta3 s23)/beta1 (6.33), and balanced iff |r*| <= 0.04 m; Pinocchio's offset is 0 there."""
    th = printed()
    b = balance(qp, n_samples=20_000)
    assert b.slider == "r0"
    q = b.grid.configurations()
    p = qp.params
    mG = p.total_mass
    ref = -np.array([th.x_cm_3_80((0.0, t2, t3), p) for _, t2, t3 in q]) * mG / p.arm_mass
    np.testing.assert_allclose(b.r_star, ref, atol=1e-14)
    np.testing.assert_array_equal(b.balanced, np.abs(ref) <= 0.04 + 1e-12)
    np.testing.assert_allclose(b.residual, 0.0, atol=1e-16)  # y_cm = 0: a single slider always zeroes the offset


def test_balanced_configurations_have_the_cog_on_the_thrust_axis(qp):
    for m, off in [(0.0, (0, 0, 0)), (0.3, (0.0, 0.0, 0.05))]:
        b = balance(qp, n_samples=20_000, payload_mass=m, payload_offset=off)
        p2 = loaded(qp, m, off)
        d = p2.data()
        q = b.grid.configurations()
        ok = np.flatnonzero(b.balanced)
        assert 0.05 < len(ok) / len(q) < 0.5
        for i in np.random.default_rng(2).choice(ok, 50, replace=False):
            qq = pin.neutral(p2.model)
            qq[7:] = q[i]
            qq[7] = b.r_star[i]
            assert np.abs(kinematics.cog_offset_body(p2, d, qq)).max() < 1e-13
            qq[7:] = q[i]
            pin.framesForwardKinematics(p2.model, d, np.r_[qq[:7], b.r_star[i], q[i][1:]])
            np.testing.assert_allclose(d.oMf[p2.ee_frame].translation, b.ee_body[i], atol=1e-14)


def test_balance_fraction_of_the_workspace(qp):
    b = balance(qp, n_samples=60_000)
    f = b.fraction_workspace
    assert 0.10 < f.value < 0.16 and f.error < 0.01
    assert b.workspace_measure.measure > b.balanced_measure.measure > 0


@pytest.mark.parametrize("name", ["borinot_flying_arm_2", "HEX-RRR", "hextilt_flying_arm_5"])
def test_balance_without_slider_maps_the_offset(name):
    p = qprr.build(name) if name.isupper() else qprr.load(name)
    b = balance(p, n_samples=20_000, tol=5e-3)
    assert b.slider is None
    d = p.data()
    q = b.grid.configurations()
    for i in np.random.default_rng(0).choice(len(q), 30, replace=False):
        qq = pin.neutral(p.model)
        qq[7:] = q[i]
        assert abs(np.linalg.norm(kinematics.cog_offset_body(p, d, qq)) - b.offset_clamped[i]) < 1e-14
        assert b.balanced[i] == (b.offset_clamped[i] <= 5e-3)


def test_cog_input_errors(qp):
    with pytest.raises(InputError, match="payload_masses"):
        cog_regions(qp, n_samples=1000, payload_masses=[-1.0])
    with pytest.raises(UnknownNameError, match="slider"):
        balance(qp, n_samples=1000, slider="theta9")
    with pytest.raises(InputError, match="prismatic"):
        balance(qp, n_samples=1000, slider="theta2")
    with pytest.raises(InputError, match="pitch"):
        cog_regions(qp, n_samples=1000, pitch=(0.0, 2.0))
