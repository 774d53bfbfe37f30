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


# Every cell of Table 6.3 where ours departs from the printed value by more than 2x, either way, with the band of
# the ratio ours / printed it must stay in and the cause (docs/control.md, section "Table 6.3 cell by cell").  A cell
# not listed must be within [0.5, 2].  Causes:
EXACT = "the plant is the model the controller inverts; the thesis flew a SimMechanics prototype from its CAD (Annex A)"
YAW = "yaw is held constant and decoupled in the exact model: nothing excites it"
ZOH = "digital controller (1 kHz zero-order hold): halves with dt (test below); the thesis's ran in continuous time"
KD = "desired-state ID: position K_D = 2 sqrt(30) (critical damping) instead of the printed 18 (3 Hz roll/pitch ringing)"
ARM = "desired-state ID: arm loops at w = 50 rad/s (w <= 25 diverges: G(xi_d) acts as a negative stiffness)"
CASCADE = "MFC position loop through the thrust direction (6.17); septic reference peaks 1.30x the printed quintic's"
MFC_ARM = "MFC: alpha = 3 (B^-1)_ii and the F estimator's filter, which the thesis does not print (naive 1/B_ii diverges)"
DEPARTURES = {
    ("idc", "z"): (0.05, 0.5, EXACT),
    ("idc", "phi"): (0.05, 0.5, EXACT),
    ("idc", "theta"): (0.01, 0.3, EXACT),
    ("idc", "psi"): (1e-7, 1e-4, YAW),
    ("idc", "theta3"): (2.0, 7.0, ZOH),
    ("dsid", "x"): (0.1, 0.5, KD),
    ("dsid", "y"): (0.07, 0.5, KD),
    ("dsid", "z"): (0.01, 0.1, EXACT),
    ("dsid", "phi"): (0.002, 0.03, KD),
    ("dsid", "theta"): (0.002, 0.03, KD),
    ("dsid", "psi"): (0.01, 0.1, YAW),
    ("dsid", "r0"): (1e-4, 2e-3, ARM),
    ("dsid", "theta2"): (5e-4, 1e-2, ARM),
    ("dsid", "theta3"): (3e-3, 0.05, ARM),
    ("mfc", "x"): (2.0, 4.0, CASCADE),
    ("mfc", "y"): (2.0, 5.0, CASCADE),
    ("mfc", "z"): (0.03, 0.3, EXACT),
    ("mfc", "phi"): (0.015, 0.2, EXACT),
    ("mfc", "theta"): (0.03, 0.3, EXACT),
    ("mfc", "psi"): (0.004, 0.04, YAW),
    ("mfc", "theta2"): (6.0, 25.0, MFC_ARM),
    ("mfc", "theta3"): (7.0, 25.0, MFC_ARM),
}


@pytest.mark.slow  # 30 s thesis missions (issue 9: marked slow, run by .ci/run)
@pytest.mark.parametrize("ctrl", ["idc", "dsid", "mfc"])
def test_static_mission_rmse_against_table_6_3(comparison, ctrl):
    """Both directions: a cell far above or far below the printed value fails unless it is listed with its cause."""
    assert comparison.status[ctrl] == "ok"
    for i, var in enumerate(XI_NAMES):
        lo, hi, why = DEPARTURES.get((ctrl, var), (0.5, 2.0, "within 2x of the printed value"))
        ratio = comparison.rmse[ctrl][var] / TABLE_6_3[ctrl][i]
        assert lo <= ratio <= hi, f"{ctrl} {var}: ours / Table 6.3 = {ratio:.3g}, outside [{lo}, {hi}] ({why})"


def test_every_listed_departure_is_one():
    """A band inside [0.5, 2] would hide nothing: each listed cell departs by more than 2x."""
    for (ctrl, var), (lo, hi, why) in DEPARTURES.items():
        assert hi <= 0.5 or lo >= 2.0 or (lo < 0.5 and hi > 2.0), (ctrl, var)
        assert why and ctrl in TABLE_6_3 and var in XI_NAMES


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


def test_as_printed_flies_the_printed_law_and_gains_bit_for_bit(robot):
    """static-dsid with as_printed is the quintic law (6.16) with the printed position K_D = 18 of (A.3), nothing else;
    it departs from the default (septic law, critically damped K_D)."""
    from qprr.control import DesiredStateInverseDynamics
    from qprr.sim import simulate
    from qprr.thesis import gains
    from qprr.thesis.missions import static_mission

    res = run("static-dsid", platform=robot, duration=6.0, as_printed=True)
    ref = simulate(robot, DesiredStateInverseDynamics(robot, gains.desired_state_as_printed()), static_mission(law="quintic"), 6.0)
    assert np.array_equal(res.xi, ref.xi) and np.array_equal(res.u, ref.u)
    assert gains.desired_state_as_printed().kd[0:3] == (18.0, 18.0, 18.0)
    default = run("static-dsid", platform=robot, duration=6.0)
    assert np.abs(default.xi - res.xi).max() > 1e-6


def test_as_printed_refuses_what_is_unstable_as_printed(robot):
    from qprr.errors import InputError

    with pytest.raises(InputError, match="Routh-Hurwitz"):
        run("static-idc", platform=robot, duration=1.0, as_printed=True)
    with pytest.raises(InputError, match="quintic"):
        run("static-mfc", platform=robot, duration=1.0, as_printed=True, law="thesis")
