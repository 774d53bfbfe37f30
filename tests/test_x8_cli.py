"""The X8 test robot of issue 35 (tests/x8_robot.py) through the command line."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from tests import x8_robot
from tests.x8_robot import JOINTS, ROTOR_NAMES, TELESCOPE_STROKE, TOTAL_MASS


@pytest.fixture(scope="module")
def x8():
    return x8_robot.load()


def test_x8_files_say_what_is_built(x8):
    """Mass, joint types and limits, rotor names and the hover thrust m g / 8 per rotor, from the files."""
    assert sum(x8.model.inertias[i].mass for i in range(1, x8.model.njoints)) == TOTAL_MASS
    assert tuple(x8.model.names[2:]) == JOINTS
    assert tuple(r.name for r in x8.rotors) == ROTOR_NAMES and len(ROTOR_NAMES) == 8
    telescope = x8.model.joints[x8.model.getJointId("telescope")]
    assert telescope.nq == 1 and x8.model.lowerPositionLimit[telescope.idx_q] == 0.0
    assert x8.model.upperPositionLimit[telescope.idx_q] == TELESCOPE_STROKE
    for i in range(1, x8.model.njoints):  # physically plausible: the principal moments satisfy the triangle inequality
        moments = np.linalg.eigvalsh(x8.model.inertias[i].inertia)
        assert moments.sum() >= 2.0 * moments.max()
    summary = x8.actuation_summary()  # the CoG is on the thrust axis at the neutral pose: equal thrusts m g / 8
    assert summary.rank == 4 and summary.can_hover and summary.can_control_attitude
    np.testing.assert_allclose(summary.hover_thrusts, TOTAL_MASS * 9.81 / 8, rtol=1e-12)
    com = pin.centerOfMass(x8.model, x8.model.createData(), x8.neutral_q())
    np.testing.assert_allclose(com[:2], 0.0, atol=1e-15)
