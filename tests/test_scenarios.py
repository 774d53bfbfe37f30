"""Scenarios of Thesis Chapter 6: tracking vs Table 6.3, CoG stabiliser, disturbances, CLI."""

from __future__ import annotations

import numpy as np
import pytest

from qprr.cli import build_parser, main
from qprr.errors import UnknownNameError
from qprr.scenarios import SCENARIOS, get_scenario, run
from qprr.thesis.missions import NAMES as XI_NAMES
from qprr.thesis.scenarios import TABLE_6_3, compare


@pytest.fixture(scope="module")
def comparison(robot):
    return compare(platform=robot)


# Where ours may exceed Table 6.3, and why (the comparison is not like for like there):
#  * idc theta2, theta3: our controller is digital (1 kHz zero-order hold); the errors halve
#    with dt (test below), the thesis's Simulink controller ran in continuous time;
#  * mfc x, y, r0, theta2, theta3: our position loop must tilt the vehicle (underactuated
#    cascade through (6.17)), plus alpha / F-estimator settings the thesis does not print (see
#    MFCGains).  x and y scale with the reference's peak acceleration: the missions' septic law
#    (jerk-continuous, docs/notes-spikes.md) peaks 7.51 / 5.77 = 1.30 times higher than the
#    quintic, and the MFC's x, y errors grew by that factor (1.48e-3 -> 1.93e-3, 2.97e-3 -> 3.87e-3).
# (dsid needs no allowance since its position K_D is critically damped: x, y 3-6 times below the thesis.)
NOT_LIKE_FOR_LIKE = {
    ("idc", "theta2"): 2.0, ("idc", "theta3"): 7.0,
    ("mfc", "x"): 4.0, ("mfc", "y"): 5.0, ("mfc", "r0"): 2.5, ("mfc", "theta2"): 25.0, ("mfc", "theta3"): 25.0,
}


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
@pytest.mark.parametrize("ctrl", ["idc", "dsid", "mfc"])
def test_static_mission_rmse_against_table_6_3(comparison, ctrl):
    assert comparison.status[ctrl] == "ok"
    for i, var in enumerate(XI_NAMES):
        factor = NOT_LIKE_FOR_LIKE.get((ctrl, var), 1.0)
        assert comparison.rmse[ctrl][var] <= factor * TABLE_6_3[ctrl][i], (ctrl, var)


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
def test_idc_arm_error_is_the_zero_order_hold(robot):
    """The IDC arm errors above Table 6.3 halve with the control period: discretisation, not the law."""
    a = run("static-idc", platform=robot).rmse()
    b = run("static-idc", platform=robot, dt=5e-4).rmse()
    for var in ("theta2", "theta3"):
        assert a[var] / b[var] == pytest.approx(2.0, rel=0.1)
    assert b["theta2"] <= TABLE_6_3["idc"][7]


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
def test_compare_table_has_the_shape_of_table_6_3(comparison):
    text = comparison.table()
    lines = text.splitlines()
    assert all(any(line.startswith(v) for line in lines) for v in XI_NAMES)
    assert "IDC (thesis)" in lines[0] and "MPC (thesis)" in lines[0] and "MFC (thesis)" in lines[0]
    assert "2.2012e-03" in text and "14min" in text and "25min" in text and "11min" in text


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
def test_dynamic_bsg_keeps_the_cog_on_the_thrust_axis(robot):
    dyn = run("dynamic-bsg", platform=robot)
    static = run("static-mfc", platform=robot)
    assert dyn.status == "ok"
    assert np.abs(dyn.x_cm[:, 0]).max() < 5e-4  # measured 0.17 mm (r0 clamped at its 4 cm stroke)
    assert np.abs(static.x_cm[:, 0]).max() > 5e-3  # without the BSG the arm moves the CoG 8.9 mm
    after = dyn.t > 26.0
    theta_e = dyn.xi[after, 4] + dyn.xi[after, 7] + dyn.xi[after, 8]  # (6.34)
    assert np.abs(theta_e).max() < 5e-3
    assert dyn.xi[-1, 7] == pytest.approx(-0.5, abs=5e-3)


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
@pytest.mark.parametrize("name, bound", [("spiral", 0.1), ("noise", 0.1), ("pulses", 0.3)])
def test_disturbed_and_spiral_scenarios_fly(robot, name, bound):
    res = run(name, platform=robot)
    assert res.status == "ok"
    e = res.rmse()
    assert max(e["x"], e["y"], e["z"]) < bound


def test_noise_scenario_is_reproducible(robot):
    a = run("noise", platform=robot, duration=2.0, seed=3)
    b = run("noise", platform=robot, duration=2.0, seed=3)
    c = run("noise", platform=robot, duration=2.0, seed=4)
    np.testing.assert_array_equal(a.xi, b.xi)
    assert not np.array_equal(a.xi, c.xi)


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
def test_printed_transition_law_saturates_the_rotors(robot):
    """With (6.16) as printed the climb asks for 1.55 g of deceleration: thrust hits 0 and z overshoots."""
    res = run("static-idc", platform=robot, law="thesis")
    assert res.saturation_fraction() > 0.01
    assert res.f.min() == 0.0
    assert res.rmse()["z"] > 100 * run("static-idc", platform=robot, duration=8.0).rmse()["z"]


def test_unknown_names_list_the_valid_ones(robot, capsys):
    with pytest.raises(UnknownNameError, match="'static-idc'.*'dynamic-bsg'"):
        get_scenario("hover")
    with pytest.raises(UnknownNameError, match="'idc', 'dsid', 'mfc'"):
        run("spiral", "lqr", platform=robot)
    with pytest.raises(UnknownNameError, match="quintic"):
        run("spiral", platform=robot, law="cubic")
    assert main(["simulate", "hover"]) == 2
    assert "static-idc" in capsys.readouterr().err


def test_cli_simulate_help_lists_scenarios_and_writes_files(tmp_path, capsys):
    sub = build_parser()._subparsers._group_actions[0].choices
    helptext = sub["simulate"].format_help()
    for name in SCENARIOS:
        assert name in helptext
    png, npz = tmp_path / "s.png", tmp_path / "s.npz"
    assert main(["simulate", "static-idc", "--duration", "2", "--plot", str(png), "--save", str(npz), "-q"]) == 0
    out = capsys.readouterr().out
    assert "RMSE (6.26)" in out and png.stat().st_size > 10_000 and npz.exists()
