"""The generic missions of qprr.scenarios.missions on four platforms: each reaches its physical check, names its own coordinates.

Runs are short (5 s at 1 kHz, targets scaled down): the missions scale their timing with the duration.  At 3 s the
fly-to's climb decelerates close to free fall (HEX-RRR's rotors at 0.25 N of 9.2), where the attitude has no authority
left: with the default gains' integral action HEX-RRR then tilts 0.35 rad and strays 35 cm (the PD gains: 7 mm), and the
arm integrals still unwind at the end of the 3 s missions with a payload event (docs/simulation.md, "Integral action").
"""

from __future__ import annotations

import numpy as np
import pytest

import qprr
from qprr.scenarios import MISSIONS, SCENARIOS, run
from qprr.scenarios.missions import read_mission

PLATFORMS = ("q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")
QPRR_WORDS = ("r0", "theta2", "theta3", "q-prr", "Q-PRR")


@pytest.fixture(scope="module", params=PLATFORMS)
def platform(request):
    return qprr.build(request.param) if request.param == "HEX-RRR" else qprr.load(request.param)


def small_mission(platform) -> dict:
    """Climb to 1 m, fly 0.3 m along x, reach the first arm joint out; grasp 10 % of the mass at 1.3 s, release at 1.8 s."""
    q = platform.neutral_q()[7:]
    hi = np.where(np.isfinite(platform.arm_upper), platform.arm_upper, q + 1.0)
    return {
        "phase": [
            {"coordinate": "z", "start": 0.0, "end": 1.2, "target": 1.0},
            {"coordinate": "x", "start": 1.2, "end": 2.0, "target": 0.3},
            {"coordinate": platform.arm_names[0], "start": 1.0, "end": 2.2, "target": float(q[0] + 0.4 * (hi[0] - q[0]))},
        ],
        "payload": [{"time": 1.3, "mass": 0.1 * platform.total_mass}, {"time": 1.8, "mass": 0.0}],
    }


OPTIONS = {"fly-to": {"target": (0.3, 0.2, 1.0)}, "motor-lag": {"target": (0.3, 0.2, 1.0)}}


def check(name: str, m: dict) -> None:
    """The physical check of each mission (metrics recorded by qprr.scenarios.missions)."""
    if name in ("takeoff-hover", "fly-to", "motor-lag"):  # reaches the target
        assert m["final_position_error"] < 0.01 and m["final_arm_error"] < 0.02
    elif name == "mission":
        assert m["final_position_error"] < 0.05 and m["final_arm_error"] < 0.05
    elif name in ("grasp-drop", "hover-pulses"):  # disturbed, then recovers
        assert m["max_position_error"] > 0.005 and m["final_position_error"] < 0.5 * m["max_position_error"]
    elif name == "ee-push":  # impedance and wall in series: F = penetration K k / (K + k)
        assert m["contact_force"] == pytest.approx(m["predicted_force"], rel=0.05)
    elif name == "hover-wind":
        assert 1e-3 < m["max_position_error"] < 0.2
    elif name == "hover-noise":
        assert m["max_position_error"] < 0.02
    else:
        raise AssertionError(f"no check for {name}")


@pytest.mark.parametrize("name", [s.name for s in MISSIONS])
def test_mission_reaches_its_check(platform, name):
    options = {"mission": small_mission(platform)} if name == "mission" else OPTIONS.get(name, {})
    res = run(name, platform=platform, duration=5.0, **options)
    assert res.status == "ok" and res.platform == platform.name
    check(name, res.metrics)
    assert tuple(res.names) == platform.xi_names and tuple(res.rmse()) == platform.xi_names
    if "theta2" not in platform.xi_names:  # not the Q-PRR
        text = "\n".join([*SCENARIOS[name].summary(res), " ".join(res.rmse()), res.platform, res.scenario])
        assert not any(w in text for w in QPRR_WORDS), text


def test_mission_as_data_is_read_and_checked(tmp_path):
    """A mission file of [[phase]] and [[payload]] tables; a phase with a missing key, an unknown table, a missing file raise."""
    f = tmp_path / "m.toml"
    f.write_text('[[phase]]\ncoordinate = "z"\nstart = 0.0\nend = 2.0\ntarget = 1.5\n[[payload]]\ntime = 1.0\nmass = 0.2\n')
    phases, payload = read_mission(f)
    assert phases[0].coordinate == "z" and phases[0].value == 1.5 and payload.mass_at(1.5) == 0.2
    with pytest.raises(qprr.QprrError, match="needs exactly"):
        read_mission({"phase": [{"coordinate": "z", "start": 0.0, "end": 1.0}]})
    with pytest.raises(qprr.QprrError, match="mission table"):
        read_mission({"phase": [], "phases": []})
    with pytest.raises(qprr.QprrError, match="does not exist"):
        read_mission(tmp_path / "none.toml")


def test_mission_unknown_coordinate_names_the_platforms_own():
    p = qprr.load("borinot_flying_arm_2")
    with pytest.raises(qprr.QprrError, match="flying_arm_2__j_bl_link1"):
        run("mission", platform=p, duration=1.0, mission={"phase": [{"coordinate": "theta2", "start": 0.0, "end": 1.0, "target": 0.1}]})


def test_every_mission_takes_any_platform_and_the_gains_option():
    for s in MISSIONS:
        assert s.platforms is None and "gains" in s.options and s.options["gains"].default == "platform"


def test_heavier_plant_sags_below_the_hover_height():
    """borinot under IDC (no integral action) flying a plant 10 % heavier than its model: the thrust feedforward is 10 %
    short, so the base settles below the reference, by far more than the nominal run's error; the nominal run reaches it."""
    from qprr.sim.mismatch import ModelError, perturbed

    p = qprr.load("borinot_flying_arm_2")
    sc = SCENARIOS["takeoff-hover"]
    nominal = sc.run(platform=p, controller="idc", duration=4.0)
    heavy = sc.run(platform=p, controller="idc", duration=4.0, plant=perturbed(p, ModelError(mass=1.1)))
    dz_nominal = nominal.xi[-1, 2] - nominal.xi_d[-1, 2]
    dz_heavy = heavy.xi[-1, 2] - heavy.xi_d[-1, 2]
    assert abs(dz_nominal) < 1e-3
    assert dz_heavy < -10.0 * max(abs(dz_nominal), 1e-4)


def test_a_run_whose_rotors_saturate_completes_with_a_warning():
    """The Q-PRR's plant with 90 % of the rotor thrust hover takes (m g / sum f_max of the nominal maximum) cannot climb:
    the run completes, sinking, but its reason says the rotor bounds were active on most ticks; the nominal run's reason
    is plain "completed"."""
    from qprr.sim.loop import SATURATION_WARNING
    from qprr.sim.mismatch import ModelError, perturbed

    p = qprr.load()
    share = p.total_mass * p.g / float(np.sum(p.thrust_max))  # the fraction of the maximum thrust hover takes
    sc = SCENARIOS["takeoff-hover"]
    nominal = sc.run(platform=p, controller="idc", duration=3.0)
    weak = sc.run(platform=p, controller="idc", duration=3.0, plant=perturbed(p, ModelError(f_max=0.9 * share)))
    assert nominal.reason == "completed" and nominal.saturation_fraction() <= SATURATION_WARNING
    assert str(weak.status) == "ok" and weak.saturation_fraction() > SATURATION_WARNING
    assert weak.reason.startswith("completed with warnings: a rotor thrust bound was active on ")
    assert f"{100 * weak.saturation_fraction():.0f} % of the ticks" in weak.reason
    assert weak.xi[-1, 2] < weak.xi[0, 2] - 1.0  # it sank
