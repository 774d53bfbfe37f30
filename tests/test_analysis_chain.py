"""qprr.analysis.chain: batched kinematics and statics of any arm against Pinocchio, to round-off."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr.analysis import ArmChain
from qprr.analysis._common import JointGrid, check_locked, make_grid
from qprr.errors import InputError, LimitError, ShapeError, UnknownNameError

PLATFORMS = ("q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")


def platform_by_name(name):
    return qprr.build(name) if name.isupper() else qprr.load(name)


@pytest.fixture(scope="module", params=PLATFORMS)
def platform(request):
    return platform_by_name(request.param)


def loaded_model(p, m, offset):
    """A copy of the model with a point mass m at ``offset`` (end-effector frame): the independent reference."""
    model = pin.Model(p.model)
    f = p.model.frames[p.ee_frame]
    model.inertias[f.parentJoint] = model.inertias[f.parentJoint] + pin.Inertia(m, f.placement.act(np.asarray(offset)), np.zeros((3, 3)))
    return model


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), m=st.floats(0.0, 3.0))
def test_chain_matches_pinocchio_on_every_platform(platform, seed, m):
    """Placement, Jacobian, CoM, generalised gravity (arm and base rows) with and without a payload."""
    p = platform
    rng = np.random.default_rng(seed)
    q_arm = rng.uniform(p.arm_lower, p.arm_upper, (6, p.n_arm))
    offset = rng.uniform(-0.05, 0.05, 3)
    ch = ArmChain(p)
    pose = ch.pose(q_arm)
    R, t = ch.frame_placement(pose, p.ee_frame)
    J = ch.jacobian(pose, p.ee_frame)
    com = ch.com(pose)
    stc = ch.statics(pose, p.ee_frame, offset)
    model2 = loaded_model(p, m, offset)
    d, d2 = p.data(), model2.createData()
    for i in range(len(q_arm)):
        q = pin.neutral(p.model)
        q[7:] = q_arm[i]
        pin.framesForwardKinematics(p.model, d, q)
        M = d.oMf[p.ee_frame]
        np.testing.assert_allclose(t[i], M.translation, atol=1e-14)
        np.testing.assert_allclose(R[i], M.rotation, atol=1e-14)
        Jp = pin.computeFrameJacobian(p.model, d, q, p.ee_frame, pin.LOCAL_WORLD_ALIGNED)[:, 6:]
        np.testing.assert_allclose(J[i], Jp, atol=1e-14)
        np.testing.assert_allclose(com[i], pin.centerOfMass(p.model, d, q), atol=1e-15)
        g = pin.computeGeneralizedGravity(model2, d2, q)
        np.testing.assert_allclose(stc.tau_arm(m)[i], g[6:], atol=1e-12)
        np.testing.assert_allclose(stc.wrench(m)[i], g[0:6], atol=1e-12)
        np.testing.assert_allclose(stc.com_loaded(m)[i], pin.centerOfMass(model2, d2, q), atol=1e-15)


def test_level_hover_wrench_is_the_weight_and_its_moment(platform):
    """Base rows of the generalised gravity at level hover = [0, 0, M g, M g c_y, -M g c_x, 0] (c: CoM in B)."""
    p = platform
    ch = ArmChain(p)
    q = np.random.default_rng(0).uniform(p.arm_lower, p.arm_upper, (50, p.n_arm))
    stc = ch.statics(ch.pose(q), p.ee_frame)
    Mg = p.total_mass * p.g
    c = stc.com
    expect = np.column_stack([np.zeros(50), np.zeros(50), np.full(50, Mg), Mg * c[:, 1], -Mg * c[:, 0], np.zeros(50)])
    np.testing.assert_allclose(stc.wrench0, expect, atol=1e-12)


def test_chain_input_errors():
    p = qprr.load("q-prr")
    ch = ArmChain(p)
    with pytest.raises(ShapeError, match="q_arm"):
        ch.pose(np.zeros((3, 2)))
    with pytest.raises(InputError, match="finite"):
        ch.pose([0.0, np.nan, 0.0])
    with pytest.raises(InputError, match="Platform"):
        ArmChain("q-prr")


def test_grid_is_balanced_odd_and_keeps_the_limits():
    p = qprr.load("q-prr")
    g = make_grid(p, 100_000)
    assert isinstance(g, JointGrid)
    assert all(n % 2 == 1 for n in g.shape)
    assert 0.8e5 < g.size < 1.2e5
    for k, j in enumerate(p.arm):
        assert g.axes[k][0] == j.lower and g.axes[k][-1] == j.upper
    # theta2 (lever 0.28 m, 4.19 rad) gets more values than r0 (0.08 m stroke)
    assert g.shape[1] > g.shape[2] > g.shape[0]
    with pytest.raises(UnknownNameError, match="r0"):
        check_locked(p, {"slider": 0.0})
    with pytest.raises(LimitError, match="outside the joint limits"):
        check_locked(p, {"r0": 0.5})
    with pytest.raises(InputError, match="n_samples"):
        make_grid(p, 0)
