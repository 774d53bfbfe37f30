"""Identification from flight logs: the SITL log against jMAVSim's sources, simulated logs against their truth."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyulog", reason="pyulog is not installed: pip install 'qprr[flightlog]'")

import qprr
from qprr.cli import main
from qprr.errors import InputError, NoFlightError, NonPhysicalError, UnknownNameError
from qprr.flightlog.identify import IdentifyOptions, identify_log
from qprr.flightlog.record import read_joint_csv
from qprr.flightlog.synth import SynthOptions, synth_log
from qprr.rotors import rotors_to_toml

LOGS = Path(__file__).resolve().parents[2] / "shared/data/flightlogs"
SITL = LOGS / "sample_px4_events.ulg"

# jMAVSim's iris, github:PX4/jMAVSim at commit 665b26d62d36a33b6bf01c5931c589beb812c6a2:
# src/me/drton/jmavsim/Simulator.java buildMulticopter(): new Quadcopter(..., "x", "default", 0.33 / 2, 4.0, 0.05,
# 0.005, ...), setMass(0.8), inertia diag(0.005, 0.005, 0.009); Rotor.java: thrust = (control filtered by the time
# constant) * fullThrust, linear in the command; SimpleEnvironment.java: G = 9.80665.
JMAVSIM_MASS, JMAVSIM_CT, JMAVSIM_G = 0.8, 4.0, 9.80665
JMAVSIM_HOVER = JMAVSIM_MASS * JMAVSIM_G / (4 * JMAVSIM_CT)


@pytest.fixture(scope="module")
def sitl():
    if not SITL.exists():
        pytest.skip(f"the shared SITL log is absent: {SITL}")
    return identify_log(SITL, IdentifyOptions(mass=JMAVSIM_MASS, folds=5))


def test_sitl_ct_and_hover_within_one_percent_on_every_fold(sitl):
    assert abs(sitl["ct"].value - JMAVSIM_CT) <= 3 * sitl["ct"].std
    assert abs(sitl["hover_command"].value - JMAVSIM_HOVER) <= 3 * sitl["hover_command"].std
    assert sitl["ct"].std < 0.005 * JMAVSIM_CT
    assert len(sitl.folds) == 5
    for fold in sitl.folds:
        assert abs(fold.values["ct"] / JMAVSIM_CT - 1.0) < 0.01
        assert abs(fold.values["hover_command"] / JMAVSIM_HOVER - 1.0) < 0.01
        assert fold.rms_held_out < 0.2


def test_sitl_angular_values_covered_or_not_identifiable(sitl):
    # jMAVSim's centre of gravity is at the rotors' centre (gc = 0); its time constant 5 ms is far below what 10 Hz
    # motor commands resolve
    for key in ("cog_x", "cog_y", "cog_z"):
        e = sitl[key]
        assert not e.identified or abs(e.value) <= 3 * e.std
    assert not sitl["motor_time_constant"].identified
    assert "10 Hz" in sitl["motor_time_constant"].reason
    for key in ("inertia_xx", "inertia_yy", "inertia_zz", "inertia_ratio_yy_xx", "inertia_ratio_zz_xx"):
        e = sitl[key]
        truth = {"inertia_xx": 0.005, "inertia_yy": 0.005, "inertia_zz": 0.009, "inertia_ratio_yy_xx": 1.0, "inertia_ratio_zz_xx": 1.8}[key]
        assert not e.identified or abs(e.value - truth) <= 3 * e.std, (key, e)


def test_sitl_json_and_summary(sitl, tmp_path):
    out = json.loads(sitl.to_json(tmp_path / "out.json").read_text())
    assert set(out["ct"]) >= {"value", "std"} and out["hover_command"]["value"] == pytest.approx(sitl["hover_command"].value)
    assert out["motor_time_constant"]["value"] is None
    text = sitl.summary()
    assert "ct: 4.00" in text and "not identifiable:" in text


def test_no_flight_refused():
    log = LOGS / "sample_logging_tagged_and_default_params.ulg"
    if not log.exists():
        pytest.skip(f"the shared log is absent: {log}")
    with pytest.raises(NoFlightError, match="needs a flight"):
        identify_log(log, IdentifyOptions(mass=0.8))


def test_options_refused_by_name():
    with pytest.raises(InputError, match="mass or ct"):
        IdentifyOptions(mass=1.0, ct=4.0)
    with pytest.raises(InputError, match="folds"):
        IdentifyOptions(folds=1)


def locked_hexarotor(folder: Path):
    """HEX-RRR with its arm joints fixed in the URDF: a plain (arm-less) hexarotor, its URDF and rotor file."""
    built = qprr.build("HEX-RRR")
    urdf, rotors = folder / "hex.urdf", folder / "hex.rotors.toml"
    urdf.write_text(re.sub(r'type="(revolute|prismatic)"', 'type="fixed"', built.urdf))
    rotors.write_text(rotors_to_toml(list(built.rotors)))
    ee = built.model.frames[built.ee_frame].name
    return qprr.from_urdf(urdf, rotors, ee_frame=ee), urdf, rotors, ee


@pytest.fixture(scope="module")
def hexa(tmp_path_factory):
    """The arm-less hexarotor flown through steps of x, y and yaw (the attitude excited), identified from the log
    alone and with its URDF."""
    folder = tmp_path_factory.mktemp("hex")
    platform, urdf, rotors, ee = locked_hexarotor(folder)
    s = synth_log(platform, folder / "hex.ulg", SynthOptions(duration_s=10.0, seed=2))
    options = IdentifyOptions(mass=s.truth["mass"], gravity=s.truth["gravity"], folds=3)
    return s, identify_log(s.path, options), (platform, urdf, rotors, ee)


def test_simulated_hexarotor_identified_and_written_back(hexa, tmp_path):
    s, r, _ = hexa
    truth = s.truth
    for key in ("ct", "hover_command"):
        e = r[key]
        assert abs(e.value - truth[key]) <= 3 * e.std, (key, e, truth[key])
        assert e.std < 0.005 * truth[key]
    r2 = identify_log(s.path, IdentifyOptions(ct=truth["ct"], gravity=truth["gravity"], folds=3))
    assert abs(r2["mass"].value - truth["mass"]) <= 3 * r2["mass"].std
    for k, key in enumerate(("cog_x", "cog_y", "cog_z")):
        e = r[key]
        assert e.identified and abs(e.value - truth["rigid"]["cog"][k]) <= 3 * e.std, (key, e)
    I = truth["rigid"]["inertia"]
    for key, value in (("inertia_ratio_yy_xx", I[1] / I[0]), ("inertia_ratio_zz_xx", I[2] / I[0]), ("inertia_xx", I[0]), ("inertia_yy", I[1])):
        e = r[key]
        assert e.identified and abs(e.value - value) <= 3 * e.std and e.std < 0.3 * value, (key, e, value)
    # the write-back round trip (the same flight: the fixture is built once per worker)
    platform, urdf, rotors, ee = hexa[2]
    rot_out, inert_out, js = tmp_path / "identified.rotors.toml", tmp_path / "identified.inertials.toml", tmp_path / "id.json"
    argv = [
        "log",
        "identify",
        str(s.path),
        "--mass",
        repr(s.truth["mass"]),
        "--folds",
        "3",
        "--urdf",
        str(urdf),
        "--rotors",
        str(rotors),
        "--ee-frame",
        ee,
    ]
    argv += ["--json", str(js), "--write-rotors", str(rot_out), "--write-inertials", str(inert_out)]
    assert main(argv) == 0
    est = json.loads(js.read_text())
    text = inert_out.read_text()
    assert "# ±" in text and "[link." in text
    flown = qprr.from_urdf(urdf, rot_out, ee_frame=ee, inertials=inert_out)
    assert [r.f_max for r in flown.rotors] == [est["ct"]["value"]] * platform.n_rotors
    body = flown.model.inertias[1]
    np.testing.assert_allclose(np.array(body.lever), [est[f"base.cog_{k}"]["value"] for k in "xyz"], rtol=1e-12)
    I = np.array(body.inertia)
    got = [I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]]
    np.testing.assert_allclose(got, [est[f"base.inertia_{k}"]["value"] for k in ("xx", "xy", "xz", "yy", "yz", "zz")], rtol=1e-12)
    assert body.mass == pytest.approx(s.truth["mass"])  # given, not identified: the URDF's mass kept
    sim = ["simulate", "hover-reach", "--urdf", str(urdf), "--rotors", str(rot_out), "--inertials", str(inert_out), "--ee-frame", ee]
    assert main([*sim, "--set", "duration=1.0"]) == 0


def test_hover_only_inertia_not_identifiable(tmp_path):
    platform, *_ = locked_hexarotor(tmp_path)
    s = synth_log(platform, tmp_path / "hover.ulg", SynthOptions(duration_s=6.0, steps=0.0, seed=4))
    r = identify_log(s.path, IdentifyOptions(mass=s.truth["mass"], gravity=s.truth["gravity"], folds=3))
    for key in ("inertia_xx", "inertia_ratio_yy_xx", "inertia_ratio_zz_xx"):
        assert not r[key].identified and "too little excitation" in r[key].reason, (key, r[key])
    assert abs(r["ct"].value - s.truth["ct"]) <= 3 * r["ct"].std


def test_inertials_refused_by_link_and_value(tmp_path):
    platform, urdf, rotors, ee = locked_hexarotor(tmp_path)
    bad = tmp_path / "bad.toml"
    bad.write_text("[link.no_such_link]\nmass = 1.0\n")
    with pytest.raises(UnknownNameError, match="no_such_link"):
        qprr.from_urdf(urdf, rotors, ee_frame=ee, inertials=bad)
    root = platform.model.frames[platform.base_frame].name
    bad.write_text(f"[link.{root}]\ninertia = [0.01, 0.0, 0.0, 0.01, 0.0, 0.05]\n")
    with pytest.raises(NonPhysicalError, match=root):
        qprr.from_urdf(urdf, rotors, ee_frame=ee, inertials=bad)
    bad.write_text(f"[link.{root}]\nmass = -2.0\n")
    with pytest.raises(NonPhysicalError, match="-2.0"):
        qprr.from_urdf(urdf, rotors, ee_frame=ee, inertials=bad)


@pytest.fixture(scope="module")
def manipulator(tmp_path_factory):
    """A Q-PRR flight sweeping its arm, and its identification with the joint angles and the URDF."""
    platform = qprr.load("q-prr")
    s = synth_log(platform, tmp_path_factory.mktemp("qprr") / "qprr.ulg", SynthOptions(duration_s=12.0, arm_sweep=0.5, seed=5))
    options = IdentifyOptions(mass=s.truth["mass"], gravity=s.truth["gravity"], folds=3)
    return platform, s, identify_log(s.path, options, platform, s.joints_csv)


def test_simulated_manipulator_ct_jointly_and_identifiable_combinations(manipulator):
    # ct from the full regressor, jointly with the inertial parameters: the arm's reaction on the base is modelled
    _, s, r = manipulator
    truth = s.truth
    for key in ("ct", "hover_command"):
        assert abs(r[key].value - truth[key]) <= 3 * r[key].std, (key, r[key], truth[key])
    assert 0.0 < r["ct"].std < 0.001 * truth["ct"]
    # the identifiable combinations (one flight: the fixture is built once per worker)
    truth = s.truth["parameters"]
    identified = [c for c in r.combinations if c.estimate.identified]
    for c in identified:
        assert 0.0 < c.estimate.std < math.inf
        assert abs(c.estimate.value - c.value_of(truth)) <= 3 * c.estimate.std, (c.label, c.estimate, c.value_of(truth))
    labels = [c.label for c in identified]
    # the thrust, the whole robot's yaw inertia about B's z, the arm's first moment along the link2-link3 chain
    assert "ct" in labels and "base.Izz + link1.Izz + link2.Izz + link3.Izz" in labels and "link2.mcz + 0.18 link3.m" in labels
    assert len(identified) >= 6
    # the individual link parameters the base rows cannot separate are named, with the reason
    for key in ("link1.mass", "link2.mass", "link3.mass", "link1.inertia_xx"):
        assert not r[key].identified and "joint torques" in r[key].reason
    out = r.summary()
    assert "the combinations of the inertial parameters this flight determines" in out and "link2.mcz + 0.18 link3.m:" in out


def test_joint_csv_names_checked(tmp_path):
    platform = qprr.load("q-prr")
    bad = tmp_path / "bad.csv"
    bad.write_text("time,shoulder," + ",".join(platform.arm_names[1:]) + "\n0,0,0,0\n0.1,0,0,0\n0.2,0,0,0\n0.3,0,0,0\n")
    with pytest.raises(UnknownNameError, match="shoulder"):
        read_joint_csv(bad, platform)
    short = tmp_path / "short.csv"
    short.write_text("time," + platform.arm_names[0] + "\n0,0\n0.1,0\n0.2,0\n0.3,0\n")
    with pytest.raises(InputError, match="missing"):
        read_joint_csv(short, platform)
    good = tmp_path / "good.csv"
    good.write_text("time," + ",".join(platform.arm_names) + "\n" + "\n".join(f"{t},0,0.1,0.2" for t in np.arange(5) * 0.1))
    assert read_joint_csv(good, platform).q.shape == (5, 3)
