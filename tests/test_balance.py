"""qprr.ik.balance_prismatic: the prismatic value that puts the CoG on the thrust axis (closed form).

Checked against kinematics.cog_offset_body (Pinocchio's CoM) at the returned posture, against the
thesis's closed form (3.79)-(3.81) for the Q-PRR, and on built platforms whose slider is not the
first joint (its axis then turns with the joints before it).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr import kinematics as kin
from qprr.errors import InputError, LimitError, UnknownNameError
from qprr.ik import balance_prismatic
from qprr.thesis.igm import arm_constants

QPRR = qprr.load()
QPRR_CAD = qprr.load("q-prr", params="cad")
QRPR = qprr.build("Q-RPR")  # revolute, then the slider (its axis turns with joint 1), then revolute
HEX_RRP = qprr.build("HEX-RRP", layout="x")


def offset_at(platform, q_arm):
    q = platform.neutral_q()
    q[7:] = q_arm
    return kin.cog_offset_body(platform, platform.data(), q)


angles = st.floats(-2.0, 2.0)


@settings(max_examples=60, deadline=None)
@given(t2=angles, t3=angles)
def test_qprr_matches_the_thesis_closed_form(t2, t3):
    """Thesis (3.79)-(3.81): m_G x_cm = M_s r0 + k0 + a_s s2 + a_c c2 + b_s s23 + b_c c23 = 0, both parameter sets."""
    for platform in (QPRR, QPRR_CAD):
        K = arm_constants(platform.params)
        r0 = -(K.k0 + K.a_s * math.sin(t2) + K.a_c * math.cos(t2) + K.b_s * math.sin(t2 + t3) + K.b_c * math.cos(t2 + t3)) / K.M_s
        r = balance_prismatic(platform, platform.data(), [0.3, t2, t3])  # the slider entry is only a start value
        assert r.joint == "r0"
        assert r.unclamped == pytest.approx(r0, abs=1e-15)
        assert r.within_limits == (-0.04 <= r0 <= 0.04)
        assert r.status == ("balanced" if r.within_limits else "limited")
        assert r.value == pytest.approx(min(max(r0, -0.04), 0.04), abs=1e-15)
        # residual offset = Pinocchio's at the returned posture: x_cm = 0 when balanced; y_cm (the CAD
        # parameters' lateral CoMs, K.y0) is out of the slider's reach and unchanged
        assert np.array_equal(r.offset, offset_at(platform, r.q_arm))
        assert r.q_arm[1:].tolist() == [t2, t3]
        assert r.slope[1] == 0.0 and r.slope[0] == pytest.approx(K.M_s / K.m_G, rel=1e-12)
        assert r.offset[1] == pytest.approx(offset_at(platform, [0.3, t2, t3])[1], abs=1e-17)
        if r.within_limits:
            assert abs(r.offset[0]) < 1e-16


@settings(max_examples=60, deadline=None)
@given(q=st.tuples(angles, st.floats(-0.05, 0.05), angles))
def test_slider_after_a_revolute_joint(q):
    """Q-RPR: the slider's axis is Ry(q1) x_B; the offset along it vanishes, the normal part is untouched."""
    r = balance_prismatic(QRPR, QRPR.data(), list(q))
    assert r.joint == "joint2"
    o_start = offset_at(QRPR, q)
    assert np.array_equal(r.offset, offset_at(QRPR, r.q_arm))
    # affine: offset(value) = offset(start) + slope (value - start), to rounding
    assert np.allclose(r.offset, o_start + r.slope * (r.value - q[1]), rtol=0, atol=1e-15)
    # the slope is the slider's axis in the plane normal to the thrust axis, scaled by the mass it carries
    assert r.slope[1] == 0.0 and r.slope[0] == pytest.approx(math.cos(q[0]) * abs(r.slope[0]) / abs(math.cos(q[0])), rel=1e-12)
    if r.status == "balanced":
        assert abs(r.offset @ r.slope) < 1e-15
        assert -0.05 <= r.unclamped <= 0.05
    else:  # the offset along the slope only shrinks towards the limit it stopped at
        assert r.status == "limited" and r.value in (-0.05, 0.05)
        assert abs(r.offset @ r.slope) < abs(o_start @ r.slope) + 1e-18


def test_finite_difference_confirms_the_slope():
    q = [0.4, 0.01, -0.3]
    r = balance_prismatic(QRPR, QRPR.data(), q)
    h = 1e-3  # affine: any step gives the slope to rounding
    fd = (offset_at(QRPR, [0.4, 0.01 + h, -0.3]) - offset_at(QRPR, [0.4, 0.01 - h, -0.3])) / (2 * h)
    assert np.allclose(fd, r.slope, rtol=0, atol=1e-13)


def test_slider_last_on_a_hexarotor():
    r = balance_prismatic(HEX_RRP, HEX_RRP.data(), [0.3, -0.5, 0.0])
    assert r.joint == "joint3" and r.status in ("balanced", "limited")
    assert np.array_equal(r.offset, offset_at(HEX_RRP, r.q_arm))


def test_a_slider_parallel_to_the_thrust_axis_has_no_effect():
    r = balance_prismatic(QRPR, QRPR.data(), [math.pi / 2, 0.02, 0.3])  # joint 1 turns the slider onto z_B
    assert r.status == "no_effect" and math.isnan(r.unclamped) and not r.within_limits
    assert r.value == 0.02 and "parallel to the thrust axis" in r.reason


def test_bad_input():
    with pytest.raises(InputError, match="no prismatic arm joint"):
        balance_prismatic(qprr.load("borinot_flying_arm_2"), None, [0.0, 0.0])
    q_pp = qprr.build("Q-PP")
    with pytest.raises(InputError, match="2 prismatic joints"):
        balance_prismatic(q_pp, q_pp.data(), [0.0, 0.0])
    assert balance_prismatic(q_pp, q_pp.data(), [0.0, 0.0], joint="joint2").joint == "joint2"
    with pytest.raises(InputError, match="revolute, not prismatic"):
        balance_prismatic(QPRR, QPRR.data(), [0.0, 0.1, 0.1], joint="theta2")
    with pytest.raises(UnknownNameError, match="r0"):
        balance_prismatic(QPRR, QPRR.data(), [0.0, 0.1, 0.1], joint="slider")
    with pytest.raises(LimitError, match="theta2"):
        balance_prismatic(QPRR, QPRR.data(), [0.0, 3.0, 0.1])
    with pytest.raises(InputError, match="q_arm"):
        balance_prismatic(QPRR, QPRR.data(), [0.0, 0.1])
    with pytest.raises(InputError, match="finite"):
        balance_prismatic(QPRR, QPRR.data(), [0.0, float("nan"), 0.1])
