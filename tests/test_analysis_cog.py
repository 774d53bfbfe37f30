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


def planar_rrp_xcm(geo, th1, th12, r):
    """x_cm [m] in B of a planar R_y R_y P_x arm on a body with its CoM at the origin (closed form of (3.76)-(3.78))."""
    m, lever, (l1, l2) = geo["m"], geo["lever"], geo["joints"]
    s1, s12, c12 = np.sin(th1), np.sin(th12), np.cos(th12)
    x = m[1] * lever[1][2] * s1 + m[2] * (l1 * s1 + lever[2][2] * s12)
    x = x + m[3] * (l1 * s1 + (r + lever[3][0]) * c12 + (l2 + lever[3][2]) * s12)
    return x / sum(m)


def planar_rrp_geometry(p):
    """Lengths, masses and CoM levers of a planar R_y R_y P_x arm (the slider at the tip, across link 2), checked."""
    model = p.model
    assert model.njoints == 5 and [model.joints[i].shortname() for i in (2, 3, 4)] == ["JointModelRY", "JointModelRY", "JointModelPX"]
    assert np.allclose(model.inertias[1].lever, 0.0)
    f = model.frames[p.ee_frame]
    assert f.parentJoint == 4 and np.allclose(f.placement.rotation, np.eye(3)) and np.allclose(f.placement.translation[:2], 0)
    for i in (2, 3, 4):
        assert np.allclose(model.jointPlacements[i].translation[:2], 0) and np.allclose(model.jointPlacements[i].rotation, np.eye(3))
    joints = (model.jointPlacements[3].translation[2], model.jointPlacements[4].translation[2])
    return {
        "base": model.jointPlacements[2].translation[2],
        "joints": joints,
        "tip": f.placement.translation[2],
        "m": [model.inertias[i].mass for i in range(1, 5)],
        "lever": [model.inertias[i].lever.copy() for i in range(1, 5)],
    }


def planar_rrp_balanced_area(p, n_side=200, n_r=41):
    """Independent count of the end-effector positions reachable with x_cm = 0 (and of the workspace), by points.

    A stratified n_side^2 grid of points covers the plane of the arm; a point is reachable at slider position r if
    the 2R arm of links l1 and (r, l2 + tip) reaches it (closed-form IK, two elbows) within the joint limits; it
    is reachable balanced if x_cm (closed form) changes sign or vanishes along r in [lo, hi] (n_r values) on one
    elbow branch.  Returns (workspace area, balanced area, balanced count) [m^2, m^2, points].
    """
    geo = planar_rrp_geometry(p)
    (a1, b1), (a2, b2), (lo, hi) = ((j.lower, j.upper) for j in p.arm)
    l1, l2 = geo["joints"][0], geo["joints"][1] + geo["tip"]
    reach = l1 + np.hypot(l2, max(abs(lo), abs(hi)))
    u = -reach + 2 * reach * (np.arange(n_side) + 0.5) / n_side
    X, Z = (c.reshape(-1, 1) for c in np.meshgrid(u, u, indexing="ij"))
    r = np.linspace(lo, hi, n_r)[None, :]
    rho2 = r**2 + l2**2
    rho, alpha = np.sqrt(rho2), np.arctan2(r, l2)  # the tip (r, 0, l2) in link-2 axes: length rho, angle alpha from z
    cos_b = (X**2 + Z**2 - l1**2 - rho2) / (2 * l1 * rho)
    inside = np.abs(cos_b) <= 1.0
    reached = np.zeros(X.shape[0], dtype=bool)
    balanced = np.zeros(X.shape[0], dtype=bool)
    for elbow in (1.0, -1.0):
        beta = elbow * np.arccos(np.clip(cos_b, -1.0, 1.0))  # theta2 + alpha
        th1 = np.arctan2(X, Z) - np.arctan2(rho * np.sin(beta), l1 + rho * np.cos(beta))
        th1 = (th1 + np.pi) % (2 * np.pi) - np.pi
        th2 = beta - alpha
        ok = inside & (th1 >= a1) & (th1 <= b1) & (th2 >= a2) & (th2 <= b2)
        reached |= ok.any(axis=1)
        x = planar_rrp_xcm(geo, th1, th1 + th2, r)
        cross = ok[:, 1:] & ok[:, :-1] & (np.sign(x[:, 1:]) != np.sign(x[:, :-1]))
        balanced |= cross.any(axis=1) | (ok & (x == 0.0)).any(axis=1)
    cell = (2 * reach / n_side) ** 2
    return reached.sum() * cell, balanced.sum() * cell, int(balanced.sum())


def design_study_q_rrp():
    """The Q-RRP of the design study examples/design/thesis_architectures.toml (thesis masses and reach, +-4 cm slider)."""
    from qprr.nomenclature import LinkSpec, build

    links = [
        LinkSpec("R", length=0.18, mass=0.1),
        LinkSpec("R", length=0.1, mass=0.092),
        LinkSpec("P", length=0.055, mass=0.1375, lower=-0.04, upper=0.04),
    ]
    return build("Q-RRP", links=links, body_mass=3.19)


@pytest.mark.parametrize("make", [lambda: qprr.build("Q-RRP"), design_study_q_rrp], ids=["Q-RRP", "design-study-Q-RRP"])
def test_balanced_workspace_of_a_tip_slider_matches_an_independent_count(make):
    """Slider at the tip (across link 2): the balanced band in joint space is thin and r* is steep near s = 0.  The
    measured balanced area and share of the workspace agree with a point-by-point count (closed-form IK and x_cm,
    the latter checked against Pinocchio) within the reported error bar plus the count's own sampling error."""
    p = make()
    geo = planar_rrp_geometry(p)
    rng = np.random.default_rng(3)
    d = p.model.createData()
    for _ in range(10):
        q = pin.neutral(p.model)
        q[7:] = [rng.uniform(j.lower, j.upper) for j in p.arm]
        x_ref = pin.centerOfMass(p.model, d, q)[0]
        assert abs(planar_rrp_xcm(geo, q[7], q[7] + q[8], q[9]) - x_ref) < 1e-15
    ws_area, bal_area, hits = planar_rrp_balanced_area(p)
    b = balance(p, n_samples=50_000)
    bm, f = b.balanced_measure, b.fraction_workspace
    count_err = 3.0 * np.sqrt(hits) / hits * bal_area  # 3 sigma of the count (Poisson)
    assert abs(b.workspace_measure.measure - ws_area) < b.workspace_measure.error + 0.01 * ws_area
    assert abs(bm.measure - bal_area) <= bm.error + count_err, (bm, bal_area)
    assert abs(f.value - bal_area / ws_area) <= f.error + count_err / ws_area, (f, bal_area / ws_area)


def q_prr_balanced_area(p, n_side=300, n_r=81):
    """Independent count for the Q-PRR (slider r0 at the base along x, then theta2, theta3 about y): a point (x, z)
    is reached at r0 = r by the 2R IK of (x - r, z - z0) within the limits (two elbows), and reached balanced where
    x_cm (closed form, checked against Pinocchio) changes sign or vanishes along r.  (workspace, balanced [m^2], count)."""
    model = p.model
    z0 = model.jointPlacements[2].translation[2] + model.jointPlacements[3].translation[2]
    l2, l3 = model.jointPlacements[4].translation[2], model.frames[p.ee_frame].placement.translation[2]
    m = [model.inertias[i].mass for i in range(1, 5)]
    lever = [model.inertias[i].lever for i in range(1, 5)]

    def xcm(r, t2, t23):
        return (m[1] * (r + lever[1][0]) + m[2] * (r + lever[2][2] * np.sin(t2)) + m[3] * (r + l2 * np.sin(t2) + lever[3][2] * np.sin(t23))) / sum(m)

    d, rng = model.createData(), np.random.default_rng(5)
    for _ in range(10):
        q = pin.neutral(model)
        q[7:] = [rng.uniform(j.lower, j.upper) for j in p.arm]
        assert abs(pin.centerOfMass(model, d, q)[0] - xcm(q[7], q[8], q[8] + q[9])) < 1e-15
    (lo, hi), (a2, b2), (a3, b3) = ((j.lower, j.upper) for j in p.arm)
    reach = l2 + l3
    xs = -reach + lo + (reach * 2 + hi - lo) * (np.arange(n_side) + 0.5) / n_side
    zs = z0 - reach + 2 * reach * (np.arange(n_side) + 0.5) / n_side
    r = np.linspace(lo, hi, n_r)[None, :]
    n_reached = n_balanced = 0
    for x in xs:
        X, Z = x - r, (zs - z0)[:, None] + 0.0 * r
        c3 = (X**2 + Z**2 - l2**2 - l3**2) / (2 * l2 * l3)
        reached = np.zeros(n_side, dtype=bool)
        balanced = np.zeros(n_side, dtype=bool)
        for elbow in (1.0, -1.0):
            t3 = elbow * np.arccos(np.clip(c3, -1.0, 1.0))
            t2 = np.arctan2(X, Z) - np.arctan2(l3 * np.sin(t3), l2 + l3 * np.cos(t3))
            t2 = (t2 + np.pi) % (2 * np.pi) - np.pi
            ok = (np.abs(c3) <= 1.0) & (t2 >= a2) & (t2 <= b2) & (t3 >= a3) & (t3 <= b3)
            reached |= ok.any(axis=1)
            f = xcm(r, t2, t2 + t3)
            cross = ok[:, 1:] & ok[:, :-1] & (np.sign(f[:, 1:]) != np.sign(f[:, :-1]))
            balanced |= cross.any(axis=1) | (ok & (f == 0.0)).any(axis=1)
        n_reached += int(reached.sum())
        n_balanced += int(balanced.sum())
    cell = (xs[1] - xs[0]) * (zs[1] - zs[0])
    return n_reached * cell, n_balanced * cell, n_balanced


def test_q_prr_balanced_workspace_matches_an_independent_count(qp):
    """The published share (docs/analysis.md, 12.74 +- 0.12 % at 2e5 samples) measured at 6e4 samples: its error bar
    covers the point-by-point count within the count's own 3-sigma sampling error."""
    ws_area, bal_area, hits = q_prr_balanced_area(qp)
    b = balance(qp, n_samples=60_000)
    count_err = 3.0 * np.sqrt(hits) / hits * bal_area
    assert abs(b.workspace_measure.measure - ws_area) < b.workspace_measure.error + 0.01 * ws_area
    assert abs(b.balanced_measure.measure - bal_area) <= b.balanced_measure.error + count_err, (b.balanced_measure, bal_area)
    f = b.fraction_workspace
    assert abs(f.value - bal_area / ws_area) <= f.error + count_err / ws_area


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


def test_options_and_keywords_are_one_setting(qp):
    """balance/cog_regions take their settings as an options dataclass or as keywords, the same result either way."""
    from qprr.analysis import BalanceOptions, CoGOptions

    a = balance(qp, BalanceOptions(n_samples=3000, tol=1e-3))
    b = balance(qp, n_samples=3000, tol=1e-3)
    c = balance(qp, BalanceOptions(n_samples=5000), n_samples=3000, tol=1e-3)  # keywords replace the options' fields
    for r in (b, c):
        np.testing.assert_array_equal(a.offset_clamped, r.offset_clamped)
        assert a.fraction_workspace == r.fraction_workspace
    g1 = cog_regions(qp, CoGOptions(n_samples=3000, payload_masses=(0.0, 0.5)))
    g2 = cog_regions(qp, n_samples=3000, payload_masses=(0.0, 0.5))
    np.testing.assert_array_equal(g1.regions[(1, 1)].com, g2.regions[(1, 1)].com)
    with pytest.raises(TypeError):
        balance(qp, n_sample=3000)
    with pytest.raises(InputError, match="BalanceOptions"):
        balance(qp, CoGOptions())
