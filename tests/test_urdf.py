"""The committed URDF is the generated one, and Pinocchio loads it as the Q-PRR."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr.thesis
from qprr.thesis.urdf import URDF_PATH, build_urdf


def test_committed_urdf_equals_generated():
    assert URDF_PATH.read_text() == build_urdf(), "run `qprr urdf` to regenerate urdf/qprr.urdf"


def test_free_flyer_dimensions_and_joints(robot):
    m = robot.model
    assert (m.nq, m.nv) == (10, 9)
    assert list(m.names) == ["universe", "root_joint", "r0", "theta2", "theta3"]
    assert m.joints[2].shortname() == "JointModelPX"
    assert m.joints[3].shortname() == "JointModelRY"
    assert m.joints[4].shortname() == "JointModelRY"


def test_limits_and_masses_match_parameters(robot):
    p, m = robot.params, robot.model
    np.testing.assert_allclose(m.lowerPositionLimit[7:], p.lower_limits)
    np.testing.assert_allclose(m.upperPositionLimit[7:], p.upper_limits)
    masses = [m.inertias[j].mass for j in range(1, 5)]
    np.testing.assert_allclose(masses, [p.multirotor_mass] + [k.mass for k in p.links])
    assert pin.computeTotalMass(m) == pytest.approx(p.total_mass, abs=1e-12)
    np.testing.assert_allclose(m.inertias[1].inertia, p.multirotor_inertia_matrix(), atol=1e-15)
    np.testing.assert_allclose(m.gravity.linear, [0.0, 0.0, -9.8])


def test_cad_variant_adds_rail_and_moves_coms(cad_robot, robot):
    assert cad_robot.params.total_mass == pytest.approx(robot.params.total_mass + 0.033)
    assert pin.computeTotalMass(cad_robot.model) == pytest.approx(cad_robot.params.total_mass)
    np.testing.assert_allclose(cad_robot.model.inertias[3].lever, [0.01245, 0.01931, 0.005])


def test_model_is_not_shared_between_loads():
    a, b = qprr.thesis.load_qprr(), qprr.thesis.load_qprr()
    assert a.model is not b.model
