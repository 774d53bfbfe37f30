"""Campaigns on any platform (issue 21 item 3): a platform by name or by its URDF and rotor file, columns named from
its coordinates, model errors drawn on it, a changed URDF a changed specification."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.campaign import CampaignSpec, read_results, run_campaign
from qprr.campaign.spec import platform_names
from qprr.campaign.worker import platform_of
from qprr.errors import InputError, UnknownNameError
from qprr.platforms import NAMES
from qprr.scenarios import SCENARIOS, run
from qprr.sim.mismatch import ModelError, check_plant, perturbed

MY_PLATFORM = Path(__file__).resolve().parents[1] / "examples" / "my_platform"
Q_PRR_ARM = ("r0", "theta2", "theta3")


def _user_robot(tmp_path: Path) -> tuple[Path, Path]:
    """The quad_rrr URDF and rotor file copied into tmp_path/robot; the specification goes into tmp_path/specs."""
    robot = tmp_path / "robot"
    robot.mkdir()
    for f in ("quad_rrr.urdf", "quad_rrr.rotors.toml"):
        shutil.copy(MY_PLATFORM / f, robot / f)
    specs = tmp_path / "specs"
    specs.mkdir()
    return robot, specs


def _write_spec(folder: Path, **over) -> Path:
    spec = {
        "name": "user",
        "scenario": "hover-reach",
        "seed": 4,
        "samples": 2,
        "platform": {"urdf": "../robot/quad_rrr.urdf", "rotors": "../robot/quad_rrr.rotors.toml", "ee_frame": "gripper"},
        "options": {"duration": 0.3},
        "grid": {"controller": ["idc", "mfc"]},
        "random": {"model.mass": {"dist": "uniform", "low": 0.9, "high": 1.1}, "model.payload": {"dist": "uniform", "low": 0.0, "high": 0.05}},
        **over,
    }
    path = folder / "user.json"
    path.write_text(json.dumps(spec))
    return path


def test_a_platform_table_is_read_relative_to_the_specification(tmp_path, monkeypatch):
    robot, specs = _user_robot(tmp_path)
    monkeypatch.chdir(robot.parent.parent)  # neither the specification's folder nor the robot's
    spec = CampaignSpec.load(_write_spec(specs))
    direct = qprr.from_urdf(robot / "quad_rrr.urdf", robot / "quad_rrr.rotors.toml", ee_frame="gripper")
    p = platform_of(spec)
    assert p.name == "quad_rrr" and p.xi_names == direct.xi_names and p.ee_frame == direct.ee_frame
    assert p.total_mass == pytest.approx(direct.total_mass, rel=1e-15) and p.n_rotors == 4
    np.testing.assert_array_equal(p.rotor_matrix, direct.rotor_matrix)
    # the table as the results' metadata keeps it: the paths as written, the files' hashes
    d = spec.to_dict()["platform"]
    assert d["urdf"] == "../robot/quad_rrr.urdf" and len(d["sha256"]["urdf"]) == 64
    assert CampaignSpec.from_mapping(spec.to_dict()).fingerprint == spec.fingerprint  # read back without the files
    with pytest.raises(InputError, match=r"platform\.urdf = 'quad\.urdf'.*no file.*relative to the specification's folder"):
        CampaignSpec.load(_write_spec(specs, platform={"urdf": "quad.urdf", "rotors": "../robot/quad_rrr.rotors.toml"}))
    with pytest.raises(UnknownNameError, match="key of the platform table 'rotor'.*'rotors'"):
        CampaignSpec.load(_write_spec(specs, platform={"urdf": "../robot/quad_rrr.urdf", "rotor": "x.toml"}))
    with pytest.raises(InputError, match=r"'static-idc' runs on q-prr, not on platform = 'urdf \.\./robot/quad_rrr\.urdf.*hover-reach"):
        CampaignSpec.load(_write_spec(specs, scenario="static-idc"))
    with pytest.raises(InputError, match=r"ee_frame = 'claw'.*claw"):
        platform_of(CampaignSpec.load(_write_spec(specs, platform={**spec.to_dict()["platform"], "ee_frame": "claw"})))


def test_columns_are_the_platform_s_coordinates_and_the_rows_its_flights(tmp_path):
    robot, specs = _user_robot(tmp_path)
    spec = CampaignSpec.load(_write_spec(specs))
    done = run_campaign(spec, tmp_path / "u.csv", backend="inline", progress=False)
    res = read_results(tmp_path / "u.csv")
    cols = res.table.dtype.names
    for n in ("x", "y", "z", "phi", "theta", "psi", "yaw", "shoulder", "elbow"):
        assert f"rmse_{n}" in cols
    assert not any(n in c for c in cols for n in Q_PRR_ARM), cols
    assert done.executed == 4 and set(res.table["status"]) == {"ok"}
    # each row is the flight of the perturbed user robot the run's parameters describe
    p = platform_of(spec)
    for i in (0, 3):
        r = spec.run(i)
        plant = perturbed(p, ModelError(mass=r.params["model.mass"], payload=r.params["model.payload"]))
        e = run("hover-reach", r.params["controller"], platform=p, plant=plant, duration=0.3, seed=r.seed).rmse()
        row = res.table[res.table["run"] == i][0]
        for n in p.xi_names:
            assert row[f"rmse_{n}"] == e[n], n
    # the payload and the mass reach the plant: four draws, four different climbs
    assert len(set(res.table["rmse_z"].tolist())) == 4


USER_TARGET = """
from qprr.scenarios import run
from qprr.platforms import load


def flies_given(params, seed, platform):
    return run("hover-reach", platform=platform, duration=0.1, seed=seed)


def flies_other(params, seed):
    return run("hover-reach", platform=load("borinot_flying_arm_2"), duration=0.1, seed=seed)
"""


def test_a_callable_target_gets_the_spec_s_platform_and_another_platform_is_an_error_row(tmp_path):
    robot, specs = _user_robot(tmp_path)
    (specs / "target.py").write_text(USER_TARGET)
    for fn, status in (("flies_given", "ok"), ("flies_other", "error")):
        path = _write_spec(specs, scenario=None, callable=f"target.py:{fn}", samples=1, options={}, grid={"k": [0]}, random={})
        data = json.loads(path.read_text())
        del data["scenario"]
        path.write_text(json.dumps(data))
        t = run_campaign(CampaignSpec.load(path), tmp_path / f"{fn}.csv", backend="inline", progress=False).results.table
        assert t["status"].tolist() == [status] and "rmse_shoulder" in t.dtype.names
        if status == "ok":
            assert np.isfinite(t["rmse_shoulder"][0])
        else:  # its errors would have no column: the row says so rather than writing NaN
            assert "flying_arm_2__j_bl_link1" in t["reason"][0] and "shoulder" in t["reason"][0]


def test_a_changed_urdf_is_a_changed_specification_and_resume_says_why(tmp_path):
    robot, specs = _user_robot(tmp_path)
    path = _write_spec(specs, samples=1, grid={"controller": ["idc"]})
    before = CampaignSpec.load(path)
    run_campaign(before, tmp_path / "u.csv", backend="inline", progress=False)
    urdf = robot / "quad_rrr.urdf"
    urdf.write_text(urdf.read_text().replace('<mass value="0.10"/>', '<mass value="0.11"/>', 1))
    # the specification read before the edit refuses to build the edited robot
    with pytest.raises(InputError, match=r"platform\.urdf = '\.\./robot/quad_rrr\.urdf': the file changed"):
        platform_of(before)
    after = CampaignSpec.load(path)
    assert (
        after.fingerprint != before.fingerprint
        and after.to_dict()["platform"]["sha256"]["rotors"] == before.to_dict()["platform"]["sha256"]["rotors"]
    )
    with pytest.raises(InputError, match=r"another specification.*the content of platform\.urdf = '\.\./robot/quad_rrr\.urdf'"):
        run_campaign(after, tmp_path / "u.csv", backend="inline", progress=False)
    original = qprr.from_urdf(MY_PLATFORM / "quad_rrr.urdf", MY_PLATFORM / "quad_rrr.rotors.toml")
    assert platform_of(after).total_mass == pytest.approx(original.total_mass + 0.01, rel=1e-14)  # the edited robot


def test_local_and_inline_tables_are_identical_on_borinot(tmp_path):
    spec = CampaignSpec.from_mapping(
        {
            "name": "borinot",
            "scenario": "hover-reach",
            "platform": "borinot_flying_arm_2",
            "seed": 5,
            "samples": 3,
            "options": {"duration": 0.2},
            "grid": {"controller": ["idc"]},
            "random": {
                "model.mass": {"dist": "uniform", "low": 0.9, "high": 1.1},
                "model.kappa": {"dist": "uniform", "low": 0.9, "high": 1.1},
                "model.payload": {"dist": "uniform", "low": 0.0, "high": 0.05},
            },
        }
    )
    a = run_campaign(spec, tmp_path / "a.csv", backend="inline", progress=False).results.table
    b = run_campaign(spec, tmp_path / "b.csv", backend="local", workers=2, progress=False).results.table
    assert a.dtype.names == b.dtype.names and "rmse_flying_arm_2__j_link1_link2" in a.dtype.names
    for n in a.dtype.names:
        if n != "wall_time":
            assert a[n].tolist() == b[n].tolist() or np.array_equal(a[n], b[n], equal_nan=True), n
    assert set(a["status"]) == {"ok"} and len(set(a["rmse_z"].tolist())) == 3


def test_the_unknown_platform_error_lists_each_name_once():
    with pytest.raises(UnknownNameError) as info:
        CampaignSpec(name="x", scenario="hover-reach", platform="x.urdf")
    msg = str(info.value)
    names = platform_names()
    assert set(names) == set(NAMES) and "q-prr" in names and "borinot_flying_arm_2" in names
    for n in names:
        assert msg.count(repr(n)) == 1, (n, msg)
    assert "urdf = " in msg and "HEX-RRR" in msg
    # a designation builds; a Q-PRR-only scenario names the ones for any platform
    assert CampaignSpec(name="x", scenario="hover-reach", platform="HEX-RRR").platform == "HEX-RRR"
    with pytest.raises(InputError, match="static-idc.*not on platform = 'borinot_flying_arm_2'.*hover-reach"):
        CampaignSpec(name="x", scenario="static-idc", platform="borinot_flying_arm_2")


@pytest.mark.parametrize("name", ["borinot_flying_arm_2", "HEX-RRR", "quad_rrr"])
def test_model_errors_perturb_any_platform(name):
    """perturbed on platforms other than the Q-PRR: total mass, centre of mass, inertia about each CoM, rotors."""
    if name == "quad_rrr":
        p = qprr.from_urdf(MY_PLATFORM / "quad_rrr.urdf", MY_PLATFORM / "quad_rrr.rotors.toml")
    else:
        p = qprr.load(name) if name in NAMES else qprr.build(name)
    e = ModelError(mass=1.1, arm_mass=1.2, inertia=0.9, kappa=1.05, f_max=0.95, payload=0.05)
    plant = check_plant(p, perturbed(p, e))
    m, mp = p.model, plant.model
    q = (
        pin.randomConfiguration(m, np.r_[-np.ones(3), -np.ones(4), m.lowerPositionLimit[7:]], np.r_[np.ones(3), np.ones(4), m.upperPositionLimit[7:]])
        if m.nq > 7
        else pin.neutral(m)
    )
    q[3:7] /= np.linalg.norm(q[3:7])
    d = m.createData()
    pin.framesForwardKinematics(m, d, q)
    factor = [0.0] + [1.1 * (1.2 if j >= 2 else 1.0) for j in range(1, m.njoints)]
    mass = sum(factor[j] * m.inertias[j].mass for j in range(1, m.njoints)) + 0.05
    first = sum(factor[j] * m.inertias[j].mass * d.oMi[j].act(m.inertias[j].lever) for j in range(1, m.njoints))
    com = (first + 0.05 * d.oMf[p.ee_frame].translation) / mass
    assert pin.computeTotalMass(mp) == pytest.approx(mass, rel=1e-14)
    np.testing.assert_allclose(pin.centerOfMass(mp, mp.createData(), q), com, rtol=0, atol=1e-14)
    parent = m.frames[p.ee_frame].parentJoint
    for j in range(1, m.njoints):
        if j != parent:  # the payload's link also carries the point mass
            np.testing.assert_allclose(mp.inertias[j].inertia, 0.9 * m.inertias[j].inertia, rtol=1e-14, atol=1e-16)
    assert [r.kappa for r in plant.rotors] == pytest.approx([1.05 * r.kappa for r in p.rotors], rel=1e-15)
    assert [r.f_max for r in plant.rotors] == pytest.approx([0.95 * r.f_max for r in p.rotors], rel=1e-15)


def test_campaign_show_names_the_platform_and_its_columns(tmp_path, capsys):
    from qprr.cli import main

    robot, specs = _user_robot(tmp_path)
    assert main(["campaign", "show", str(_write_spec(specs)), "--first", "1"]) == 0
    out = capsys.readouterr().out
    assert "hover-reach on quad_rrr (urdf ../robot/quad_rrr.urdf, rotors ../robot/quad_rrr.rotors.toml, ee_frame gripper)" in out
    assert "rmse_shoulder, rmse_elbow" in out and not any(f"rmse_{n}" in out for n in Q_PRR_ARM) and "q-prr" not in out
    spec = _write_spec(specs, platform="borinot_flying_arm_2")
    assert main(["campaign", "show", str(spec)]) == 0
    assert "on borinot_flying_arm_2;" in capsys.readouterr().out


def test_the_report_names_the_platform_it_flew_and_no_other(tmp_path):
    """A report on a URDF platform names it (its model name, the files as written and their SHA-256) in the header,
    summary.md and every figure's title, and holds no Q-PRR name anywhere."""
    import hashlib
    import re

    from qprr.campaign.report import box_plot, campaign_report, heat_map, metric_curve, platform_label, scatter_plot, success_curve

    robot, specs = _user_robot(tmp_path)
    path = _write_spec(specs, samples=1, grid={"controller": ["idc", "mfc"], "z": [1.0, 1.5]}, options={"duration": 0.1})
    run_campaign(CampaignSpec.load(path), tmp_path / "u.csv", backend="inline", progress=False)
    res = read_results(tmp_path / "u.csv")
    sha = {f: hashlib.sha256((robot / f"quad_rrr.{f}").read_bytes()).hexdigest()[:12] for f in ("urdf", "rotors.toml")}
    expected = (
        f"quad_rrr (URDF ../robot/quad_rrr.urdf sha256 {sha['urdf']}, rotors ../robot/quad_rrr.rotors.toml sha256 "
        f"{sha['rotors.toml']}, ee_frame gripper)"
    )
    assert platform_label(res) == expected
    text, figures = campaign_report(res, tmp_path / "rep", metrics=["rmse_position", "rmse_shoulder"], scatter=[("model.mass", "rmse_elbow")])
    md = (tmp_path / "rep" / "summary.md").read_text()
    assert f"4 runs of hover-reach on {expected}, " in text.splitlines()[0] and expected in md
    assert len(figures) >= 6
    for out in (text, md, *(f.name for f in figures)):
        assert not re.search("q-prr", out, re.IGNORECASE), out
    figs = [
        box_plot(res, "rmse_shoulder", None),
        success_curve(res, "z", None),
        metric_curve(res, "z", "rmse_elbow", None),
        scatter_plot(res, "model.mass", "rmse_elbow", None),
        heat_map(res, "z", "controller", None, by=None),
    ]
    for fig in figs:
        titles = [a.get_title() for a in fig.axes] + [t.get_text() for t in fig.texts]
        title = " ".join(t for t in titles if t).replace("\n", " ")
        assert title.startswith("user on quad_rrr: "), title
        assert not re.search("q-prr", title, re.IGNORECASE)
    # a registered platform says so; a (2.1) designation is named as one
    spec = CampaignSpec.load(_write_spec(specs, platform="borinot_flying_arm_2", samples=1, options={"duration": 0.05}))
    run_campaign(spec, tmp_path / "b.csv", backend="inline", progress=False)
    text, _ = campaign_report(tmp_path / "b.csv")
    assert "on borinot_flying_arm_2 (registered platform), " in text and not re.search("q-prr", text, re.IGNORECASE)


def test_report_units_follow_the_arm_joint_types(tmp_path):
    """On a built HEX-PRR (a prismatic, then two revolute joints) the joints' RMSE columns are in m, rad, rad, from the
    joint types the campaign recorded; the header names the (2.1) designation."""
    from qprr.campaign.report import box_plot, campaign_report, column_units, format_table, summarize

    spec = {"name": "pr", "scenario": "hover-reach", "platform": "HEX-PRR", "seed": 1, "samples": 1, "options": {"duration": 0.05}}
    spec = CampaignSpec.from_mapping({**spec, "grid": {"controller": ["idc", "mfc"]}})
    res = run_campaign(spec, tmp_path / "pr.csv", backend="inline", progress=False).results
    kinds = [j.kind for j in platform_of(spec).arm]
    assert kinds == ["prismatic", "revolute", "revolute"] and res.meta["arm_kinds"] == kinds
    arm = res.names[6:]
    assert column_units(res) == {f"rmse_{arm[0]}": "m", f"rmse_{arm[1]}": "rad", f"rmse_{arm[2]}": "rad"}
    table = format_table(summarize(res, metrics=[f"rmse_{n}" for n in arm]))
    assert f"rmse_{arm[0]} median [m]" in table and f"rmse_{arm[1]} median [rad]" in table
    assert box_plot(res, f"rmse_{arm[0]}", None).axes[0].get_ylabel() == f"rmse_{arm[0]} [m]"
    text, _ = campaign_report(res)
    assert "on HEX-PRR ((2.1) designation), " in text


def test_mission_file_of_a_campaign_is_read_from_the_spec_folder(tmp_path, monkeypatch):
    """options.mission = "FILE.toml" is read relative to the specification's folder (whatever the working directory),
    carried as data (the fingerprint follows the file's content) and a missing file is refused at load, naming it."""
    from qprr.campaign import CampaignSpec

    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "m.toml").write_text('[[phase]]\ncoordinate = "z"\nstart = 0.0\nend = 1.0\ntarget = 1.0\n')
    (folder / "spec.toml").write_text('name = "m"\nscenario = "mission"\nplatform = "HEX-RRR"\n[options]\nmission = "m.toml"\nduration = 1.5\n')
    monkeypatch.chdir(tmp_path)
    spec = CampaignSpec.load(folder / "spec.toml")
    assert spec.options["mission"] == {"phase": [{"coordinate": "z", "start": 0.0, "end": 1.0, "target": 1.0}]}
    before = spec.fingerprint
    (folder / "m.toml").write_text('[[phase]]\ncoordinate = "z"\nstart = 0.0\nend = 1.0\ntarget = 2.0\n')
    assert CampaignSpec.load(folder / "spec.toml").fingerprint != before
    assert CampaignSpec.from_mapping(spec.to_dict()).options == spec.options  # the data reads back
    res = SCENARIOS["mission"].run(platform=qprr.build("HEX-RRR"), **spec.options)
    assert res.xi_d[-1, 2] == pytest.approx(1.0)  # the file's phase was flown
    (folder / "m.toml").unlink()
    with pytest.raises(InputError, match="m.toml"):
        CampaignSpec.load(folder / "spec.toml")
