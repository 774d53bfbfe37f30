"""Parameters are validated on construction; the default set is physical; Table 3.2 as printed is an explicit opt-in."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr.thesis
from qprr.errors import InputError, NonPhysicalError, UnknownNameError
from qprr.thesis.params import (
    _TABLE_3_2_INERTIA,
    LINK2_INERTIA_PHYSICAL,
    Link,
    cad_params,
    check_rigid_body,
    nearest_physical_moments,
    second_moments,
    thesis_params,
)


def _bodies(p):
    yield "multirotor", p.multirotor_inertia
    for link in p.links + ((p.rail,) if p.rail is not None else ()):
        yield link.name, link.inertia


@pytest.mark.parametrize("params", [thesis_params(), cad_params()], ids=["thesis", "cad"])
def test_default_parameter_sets_are_physical(params):
    """Every body: positive mass, positive-definite inertia, no negative second moment of mass (with a margin that
    survives another program's rounding)."""
    assert params.nonphysical == ()
    for name, inertia in _bodies(params):
        ixx, iyy, izz, ixy, ixz, iyz = inertia
        moments = np.linalg.eigvalsh(np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
        assert moments.min() > 0.0, name
        assert second_moments(moments).min() > 1e-6 * moments.max(), name


def test_table_3_2_link2_breaks_the_triangle_inequality():
    """I_yy > I_xx + I_zz by 4.623e-6 kg m^2: a negative second moment of mass along y, -2.3115e-6 kg m^2."""
    ixx, iyy, izz = _TABLE_3_2_INERTIA["link2"]
    assert iyy - (ixx + izz) == pytest.approx(4.623e-6, rel=1e-9)
    np.testing.assert_allclose(second_moments((ixx, iyy, izz)), [2.50785e-5, -2.3115e-6, 2.50515e-5], rtol=1e-9)
    for name in ("link1", "link3", "base"):  # the other rows of Table 3.2 are physical
        assert second_moments(_TABLE_3_2_INERTIA[name]).min() > 0.0


def test_link2_correction_is_the_nearest_physical_body_rounded_to_the_table_precision():
    """Default link 2 = the printed moments with the negative second moment set to zero (the nearest positive
    semi-definite second-moment matrix; I_yy, about the joint axis, unchanged), rounded up to five significant digits."""
    printed = np.array(_TABLE_3_2_INERTIA["link2"])
    nearest = nearest_physical_moments(printed)
    np.testing.assert_allclose(nearest, [2.50515e-5, 5.013e-5, 2.50785e-5], rtol=1e-12)
    assert second_moments(nearest) == pytest.approx([2.50785e-5, 0.0, 2.50515e-5], abs=1e-18)
    rounded_up = [math.ceil(x / 10 ** (math.floor(math.log10(x)) - 4) - 1e-9) * 10 ** (math.floor(math.log10(x)) - 4) for x in nearest]
    np.testing.assert_allclose(LINK2_INERTIA_PHYSICAL, rounded_up, rtol=1e-12)
    assert LINK2_INERTIA_PHYSICAL[1] == printed[1]
    # the correction leaves the in-plane second moments and adds a 5e-10 kg m^2 one across the arm's plane
    np.testing.assert_allclose(second_moments(LINK2_INERTIA_PHYSICAL), [2.50785e-5, 5e-10, 2.50515e-5], rtol=1e-9)
    assert thesis_params().links[1].inertia == (*LINK2_INERTIA_PHYSICAL, 0.0, 0.0, 0.0)


def test_printed_table_3_2_is_an_explicit_nonphysical_opt_in():
    printed = thesis_params(table_3_2="printed-nonphysical")
    assert printed.links[1].inertia[:3] == _TABLE_3_2_INERTIA["link2"]
    assert printed.nonphysical == ("link2",) and "nonphysical" in printed.variant
    assert printed != thesis_params()
    robot = qprr.thesis.load_qprr(printed)  # Pinocchio accepts it (it does not check); its link-2 inertia is the printed one
    assert robot.model.inertias[robot.model.getJointId("theta2")].inertia[1, 1] == pytest.approx(5.013e-5, rel=1e-12)
    with pytest.raises(NonPhysicalError, match=r"link2: .*I_yy <= I_xx \+ I_zz: 5\.013e-05 > 4\.5507e-05 by 4\.623e-06"):
        printed.with_changes(nonphysical=())
    with pytest.raises(UnknownNameError, match="printed-nonphysical"):
        thesis_params(table_3_2="printed")


_P = thesis_params()
_L2 = _P.links[1]


def _link2(**changes) -> tuple:
    from dataclasses import replace

    return (_P.links[0], replace(_L2, **changes), _P.links[2])


@pytest.mark.parametrize(
    "changes, pattern",
    [
        (dict(multirotor_mass=-1.0), r"multirotor: mass must be finite and > 0 kg, got -1.0"),
        (dict(multirotor_mass=float("nan")), r"multirotor: mass"),
        (dict(multirotor_inertia=(1e-2, 1e-2, 3e-2, 0.0, 0.0, 0.0)), r"multirotor: .*I_zz <= I_xx \+ I_yy"),
        (dict(multirotor_inertia=(1e-2, 1e-2, 1e-2, 2e-2, 0.0, 0.0)), r"multirotor: rotational inertia is not positive semi-definite, I_1 = -0.01"),
        (
            dict(multirotor_inertia=(1e-2, 1e-2, 1e-2, 0.0, 0.0)),
            r"multirotor inertia \(Ixx, .*\) \[kg m\^2\] must have shape \(6,\), got shape \(5,\)",
        ),
        (dict(links=_link2(mass=0.0)), r"link2: mass"),
        (dict(links=_link2(com=(0.0, math.inf, 0.0))), r"link2 com \(centre of mass, m\) must be finite, got \[0.0, inf, 0.0\]"),
        (dict(links=_link2(inertia=(-1e-5, 5e-5, 5e-5, 0.0, 0.0, 0.0))), r"link2: rotational inertia is not positive semi-definite, I_xx = -1e-05"),
        (dict(links=_link2(length=0.0)), r"link2: length"),
        (dict(d2=0.0), r"d2 must be a positive"),
        (dict(d0=-0.01), r"d0 must be a finite number >= 0"),
        (dict(arm_length=-0.2), r"arm_length must be a positive"),
        (dict(thrust_min=25.0), r"f_min <= f_max"),
        (dict(r0_limits=(0.04, -0.04)), r"r0_limits .* lower <= upper"),
        (dict(theta3_limits=(-1.0, math.nan)), r"theta3_limits"),
        (dict(effort_limits=(20.0, 0.0, 5.0)), r"effort_limits must be 3 positive"),
        (dict(g=-9.8), r"gravity g"),
        (dict(drag_factor=0.0), r"drag_factor must be a positive"),
    ],
)
def test_nonphysical_parameters_are_refused_with_the_body_and_the_inequality(changes, pattern):
    with pytest.raises(NonPhysicalError, match=pattern) as err:
        _P.with_changes(**changes)
    assert isinstance(err.value, InputError) and isinstance(err.value, ValueError)


def test_triangle_inequality_of_a_tensor_with_products_uses_principal_moments():
    """A rotated rod-like tensor that breaks the inequality only in its principal axes is refused, naming I_1..I_3."""
    R = pin.rpy.rpyToMatrix(0.3, -0.5, 1.1)
    I = R @ np.diag([1.0, 1.0, 2.2]) @ R.T * 1e-3  # 2.2 > 1 + 1
    six = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
    with pytest.raises(NonPhysicalError, match=r"rod: .*I_3 <= I_1 \+ I_2"):
        check_rigid_body("rod", 0.1, (0.0, 0.0, 0.0), six)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(1e-6, 1.0), min_size=3, max_size=3), st.lists(st.floats(-math.pi, math.pi), min_size=3, max_size=3), st.floats(0.01, 10.0))
def test_every_mass_distribution_is_accepted_and_a_negative_second_moment_is_not(sigma, rpy, mass):
    """I = tr(Sigma) 1 - Sigma for a positive second-moment matrix Sigma (any body) passes; making one principal second
    moment negative fails."""
    R = pin.rpy.rpyToMatrix(*rpy)
    for s, ok in ((np.array(sigma), True), (np.array([sigma[0], sigma[1], -0.05 * min(sigma[0], sigma[1])]), False)):
        S = R @ np.diag(s) @ R.T
        I = np.trace(S) * np.eye(3) - S
        six = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
        if ok:
            check_rigid_body("body", mass, (0.0, 0.0, 0.0), six)
        else:
            with pytest.raises(NonPhysicalError, match="negative second moment"):
                check_rigid_body("body", mass, (0.0, 0.0, 0.0), six)


def test_link_objects_in_a_parameter_set_are_checked():
    bad = Link("link3", 0.1, 0.1, (0.0, 0.0, 0.05), (1e-6, 1e-6, 3e-6, 0.0, 0.0, 0.0))
    with pytest.raises(NonPhysicalError, match="link3"):
        _P.with_changes(links=(_P.links[0], _P.links[1], bad))


def test_an_independent_engine_loads_the_default_urdf_and_refuses_the_printed_table():
    """MuJoCo checks A + B >= C on every body's principal moments when it compiles a model."""
    mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed: pip install 'qprr[mujoco]'")
    from qprr.thesis.urdf import URDF_PATH, build_urdf

    assert mujoco.MjModel.from_xml_path(str(URDF_PATH)).nbody == 4
    with pytest.raises(ValueError, match=r"A \+ B >= C"):
        mujoco.MjModel.from_xml_string(build_urdf(thesis_params(table_3_2="printed-nonphysical")))
