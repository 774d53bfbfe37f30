"""Design search over the user's own robot (issue 35, item 5): a URDF and a rotor file with ``${name}`` placeholders,
the parameters that do not apply to a candidate left alone, and every design that is out said why."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.campaign import read_results
from qprr.design import DesignSpec, run_design
from qprr.design.report import rows_of
from qprr.design.template import evaluate_expression
from qprr.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "design" / "quad_rrr_arm.toml"
URDF = (ROOT / "examples" / "design" / "quad_rrr.urdf.template").read_text()
ROTORS = (ROOT / "examples" / "design" / "quad_rrr.rotors.toml.template").read_text()
DERIVED = DesignSpec.load(EXAMPLE).robot.derived


def study(tmp_path, urdf=URDF, rotors=ROTORS, **over) -> dict:
    """A study of the example's robot with its templates written in ``tmp_path`` (few samples)."""
    (tmp_path / "r.urdf").write_text(urdf)
    (tmp_path / "r.toml").write_text(rotors)
    d = {
        "name": "own",
        "objectives": ["hover_volume", "thrust_margin"],
        "robot": {"urdf": "r.urdf", "rotors": "r.toml", "derived": dict(DERIVED)},
        "parameters": {"upper_arm": 0.25, "rotor_arm": 0.2},
        "effort": {"samples": 200},
    }
    d.update(over)
    return d


def body(platform, joint: str) -> pin.Inertia:
    return platform.model.inertias[platform.model.getJointId(joint)]


# ------------------------------------------------------------------------------ the template is the robot
def test_the_template_is_the_users_robot_with_its_dimensions_free(tmp_path):
    """Instantiated, the template is examples/my_platform's quad_rrr with the closed forms in place of the file's rounded
    numbers: the upper arm a rod of length L (centre at L/2, m L^2 / 12), the elbow L below the shoulder, the motors at
    r / sqrt 2 on x and y, the body 1.20 + 0.40 (r - 0.20) kg; every other body and joint as in the file."""
    robot = DesignSpec.from_mapping(study(tmp_path), base=tmp_path).robot
    mine = qprr.from_urdf(ROOT / "examples/my_platform/quad_rrr.urdf", ROOT / "examples/my_platform/quad_rrr.rotors.toml")
    for L, r in ((0.25, 0.2), (0.31, 0.17)):
        p = robot.platform({"upper_arm": L, "rotor_arm": r})
        arm = body(p, "shoulder")
        assert arm.mass == 0.10 and np.array_equal(arm.lever, [0.0, 0.0, -L / 2])
        np.testing.assert_array_equal(np.diag(arm.inertia), [0.10 * L**2 / 12, 0.10 * L**2 / 12, 2.0e-6])
        assert np.array_equal(p.model.jointPlacements[p.model.getJointId("elbow")].translation, [0.0, 0.0, -L])
        m_body = 1.20 + 4 * 0.10 * (r - 0.20)
        assert body(p, "root_joint").mass == m_body
        assert math.isclose(body(p, "root_joint").inertia[2, 2], m_body * 0.18 / 12, rel_tol=1e-15)
        xy = np.abs([rot.position_body[:2] for rot in p.rotors])
        assert np.all(xy == r / math.sqrt(2)) and [rot.spin for rot in p.rotors] == [rot.spin for rot in mine.rotors]
        for j in ("yaw", "elbow"):  # the bodies the parameters do not touch
            assert body(p, j) == body(mine, j)
        assert math.isclose(pin.computeTotalMass(p.model), m_body + 0.30, rel_tol=1e-15)
    same = robot.platform({"upper_arm": 0.25, "rotor_arm": 0.2})  # the file's values: the file, to its 4 printed digits
    np.testing.assert_allclose(
        pin.crba(same.model, same.model.createData(), same.neutral_q()), pin.crba(mine.model, mine.model.createData(), mine.neutral_q()), atol=2e-6
    )
    np.testing.assert_allclose([rot.position_body for rot in same.rotors], [rot.position_body for rot in mine.rotors], atol=3e-5)


def test_the_rotor_count_is_a_variable_of_a_rotor_ring(tmp_path):
    """[robot.rotor_ring]: count rotors on a circle of the given radius, the total thrust shared between them."""
    ring = {"count": "rotor_count", "radius": "rotor_arm", "height": 0.03, "start_angle": "pi / 4", "kappa": 0.016, "f_max": "32 / rotor_count"}
    d = study(tmp_path, parameters={"upper_arm": 0.25, "rotor_arm": 0.2, "rotor_count": [4, 6, 8]})
    d["robot"] = {"urdf": "r.urdf", "rotor_ring": ring, "derived": {k: v for k, v in DERIVED.items() if k != "rotor_xy"}}
    spec = DesignSpec.from_mapping(d, base=tmp_path)
    for n in (4, 6, 8):
        p = spec.robot.platform({"upper_arm": 0.25, "rotor_arm": 0.2, "rotor_count": float(n)})
        assert len(p.rotors) == n and math.isclose(sum(r.f_max for r in p.rotors), 32.0, rel_tol=1e-15)
        assert np.allclose([math.hypot(*r.position_body[:2]) for r in p.rotors], 0.2, rtol=0, atol=1e-15)
        assert sorted({r.spin for r in p.rotors}) == [-1, 1]
    rows = rows_of(run_design(spec, tmp_path / "n.csv", backend="inline", progress=False).results.table)
    assert [r["rotor_count"] for r in rows] == [4.0, 6.0, 8.0] and all(r["status"] == "ok" for r in rows)
    # at equal total thrust and mass, more rotors split the same hover thrust: the smallest margin falls with the count
    assert rows[0]["thrust_margin"] > rows[1]["thrust_margin"] > rows[2]["thrust_margin"]


# ------------------------------------------------------------------------------ variables that do not apply
JOINT_TYPE_URDF = URDF.replace('<joint name="elbow" type="revolute">', '<joint name="elbow" type="${elbow_type}">')
JOINT_TYPE_URDF = JOINT_TYPE_URDF.replace(
    '<origin xyz="0 0 -${upper_arm}"/>\n    <axis xyz="0 1 0"/>', '<origin xyz="0 0 -${upper_arm}"/>\n    <axis xyz="${elbow_axis}"/>'
)
JOINT_TYPE_URDF = JOINT_TYPE_URDF.replace(
    '<limit lower="-2.5" upper="2.5" effort="1.5" velocity="3.0"/>',
    '<limit lower="-${elbow_range}" upper="${elbow_range}" effort="${elbow_effort}" velocity="3.0"/>',
)


def test_a_joint_type_and_its_stroke_vary_only_where_they_apply(tmp_path):
    """The elbow revolute or prismatic; its stroke is varied for the prismatic one only (3 designs, not 4), and the
    revolute design's stroke cell is empty; each design is the joint its file says."""
    params = {
        "upper_arm": 0.25,
        "rotor_arm": 0.2,
        "elbow_type": ["revolute", "prismatic"],
        "elbow_range": {"values": [0.05, 0.10], "when": {"elbow_type": "prismatic"}, "otherwise": 2.5},
        "elbow_effort": {"values": 20.0, "when": {"elbow_type": "prismatic"}, "otherwise": 1.5},
        "elbow_axis": "0 1 0",
    }
    spec = DesignSpec.from_mapping(study(tmp_path, urdf=JOINT_TYPE_URDF, parameters=params), base=tmp_path)
    rows = rows_of(run_design(spec, tmp_path / "j.csv", backend="inline", progress=False).results.table)
    assert [(r["elbow_type"], r["elbow_range"]) for r in rows][1:] == [("prismatic", 0.05), ("prismatic", 0.10)]
    assert rows[0]["elbow_type"] == "revolute" and math.isnan(rows[0]["elbow_range"]) and all(r["status"] == "ok" for r in rows), rows
    chosen = {"upper_arm": 0.25, "rotor_arm": 0.2, "elbow_type": "prismatic", "elbow_range": 0.05, "elbow_effort": 20.0, "elbow_axis": "0 1 0"}
    p = spec.robot.platform(chosen)
    elbow = p.arm[-1]
    assert elbow.kind == "prismatic" and (elbow.lower, elbow.upper) == (-0.05, 0.05) and elbow.effort == 20.0
    assert p.model.joints[elbow.joint_id].shortname() == "JointModelPY"
    about_x = spec.robot.platform({**chosen, "elbow_type": "revolute", "elbow_range": 2.5, "elbow_effort": 1.5, "elbow_axis": "1 0 0"})
    assert about_x.model.joints[about_x.arm[-1].joint_id].shortname() == "JointModelRX" and about_x.arm[-1].upper == 2.5


def test_the_nomenclature_varies_a_slider_only_on_arms_with_a_slider(tmp_path):
    """RRR is evaluated once, not once per stroke; a single revolute joint has no taper to vary."""
    d = {
        "name": "strokes",
        "architectures": ["Q-PRR", "Q-RRR", "Q-PR"],
        "objectives": ["hover_volume", "arm_mass"],
        "parameters": {"slider_stroke": [0.04, 0.08, 0.12], "taper": [0.6, 1.0]},
        "effort": {"samples": 100},
    }
    spec = DesignSpec.from_mapping(d)
    rows = rows_of(run_design(spec, tmp_path / "s.csv", backend="inline", progress=False).results.table)
    count = {a: sum(r["architecture"] == a for r in rows) for a in spec.architectures}
    assert count == {"Q-PRR": 6, "Q-RRR": 2, "Q-PR": 3}, count
    rrr = [r for r in rows if r["architecture"] == "Q-RRR"]
    assert all(math.isnan(r["slider_stroke"]) and math.isnan(r["slider_link"]) for r in rrr)
    assert all(math.isnan(r["taper"]) for r in rows if r["architecture"] == "Q-PR")
    prr = {(r["slider_stroke"], r["taper"]): r["arm_mass"] for r in rows if r["architecture"] == "Q-PRR"}
    assert math.isclose(prr[(0.12, 0.6)] - prr[(0.04, 0.6)], 0.40 * 0.08, rel_tol=1e-12)  # the rail, 0.40 kg/m of stroke


def test_nsga2_optimises_only_the_ranges_that_apply(tmp_path):
    pytest.importorskip("pymoo", reason="pymoo is not installed: pip install 'qprr[design]'")
    d = {
        "name": "ranges",
        "architectures": ["Q-RR", "Q-PRR"],
        "objectives": ["hover_volume", "arm_mass"],
        "parameters": {"slider_stroke": {"low": 0.02, "high": 0.12}},
        "search": {"method": "nsga2", "population": 4, "generations": 2},
        "effort": {"samples": 100},
    }
    rows = rows_of(run_design(DesignSpec.from_mapping(d), tmp_path / "n.csv", backend="inline", progress=False).results.table)
    assert [r["architecture"] for r in rows] == ["Q-RR"] + ["Q-PRR"] * 8 and [r["run"] for r in rows] == list(range(9))
    assert math.isnan(rows[0]["slider_stroke"]) and all(0.02 <= r["slider_stroke"] <= 0.12 for r in rows[1:])


# ------------------------------------------------------------------------------ the command line says why
def test_the_example_study_from_the_cli(tmp_path, capsys):
    from qprr.cli import main

    out = tmp_path / "rep"
    assert main(["design", "run", str(EXAMPLE), "-o", str(tmp_path / "q.csv"), "--backend", "inline", "--report", str(out), "--top", "1"]) == 0
    text = capsys.readouterr().out
    rows = rows_of(read_results(tmp_path / "q.csv").table)
    assert len(rows) == 9 and all(r["status"] == "ok" for r in rows)
    for r in rows:  # the take-off mass of the file's closed form; the budget of 1.51 kg rules out the 0.23 m rotor arms
        assert math.isclose(r["mass"], 1.20 + 0.40 * (r["rotor_arm"] - 0.20) + 0.30, rel_tol=1e-14)
        assert r["feasible"] == (r["rotor_arm"] < 0.23)
    assert "constraint mass <= 1.51 excludes 3 of the 9 evaluated design(s)" in text, text
    assert "design 8 quad_rrr (upper_arm=0.3, rotor_arm=0.23): infeasible: mass = 1.512 kg, above its max 1.51" in text, text
    by = {(r["upper_arm"], r["rotor_arm"]): r for r in rows}
    for L in (0.20, 0.25, 0.30):  # the rotors do not move the arm: one workspace per arm; longer rotor arms, more margin
        assert by[(L, 0.17)]["hover_volume"] == by[(L, 0.20)]["hover_volume"] == by[(L, 0.23)]["hover_volume"]
        assert by[(L, 0.17)]["thrust_margin"] < by[(L, 0.20)]["thrust_margin"] < by[(L, 0.23)]["thrust_margin"]
    assert by[(0.20, 0.2)]["hover_volume"] < by[(0.30, 0.2)]["hover_volume"]
    assert (out / "pareto.png").read_bytes()[:4] == b"\x89PNG" and "quad_rrr" in (out / "summary.md").read_text()
    with (out / "closed_loop.csv").open() as fh:
        flown = list(csv.DictReader(fh))
    assert len(flown) == 1 and flown[0]["status"] == "ok" and float(flown[0]["rmse_position"]) < 1e-2


def test_a_study_with_nothing_feasible_exits_non_zero_and_says_why(tmp_path, capsys):
    """A design that cannot be built (rotors on top of each other) says the loader's reason; the others the bound they
    miss; the study exits 3 with the count per constraint."""
    from qprr.cli import main

    d = study(tmp_path, parameters={"upper_arm": 0.25, "rotor_arm": [0.0, 0.2]}, constraints={"mass": {"max": 1.0}})
    spec = tmp_path / "s.json"
    spec.write_text(__import__("json").dumps(d))
    assert main(["design", "run", str(spec), "-o", str(tmp_path / "r.csv"), "--backend", "inline", "--quiet"]) == 3
    cap = capsys.readouterr()
    assert "not feasible: 2 of 2 design(s)" in cap.out and "constraint mass <= 1 excludes 1 of the 1 evaluated design(s)" in cap.out, cap.out
    assert "design 0 r (rotor_arm=0): failed: " in cap.out and "design 1 r (rotor_arm=0.2): infeasible: mass = 1.5 kg, above its max 1" in cap.out
    assert "no feasible design" in cap.err


# ------------------------------------------------------------------------------ what a study file may say
@pytest.mark.parametrize(
    "change, key, fix",
    [
        ({"parameters": {"upper_arm": 0.25}}, "parameters", "give rotor_arm a value"),
        ({"parameters": {"upper_arm": 0.25, "rotor_arm": 0.2, "colour": 1.0}}, "parameters.colour", "appears in none"),
        ({"parameters": {"upper_arm": 0.25, "rotor_arm": 0.2, "mass": 1.0}}, "parameters.mass", "not a column"),
        ({"parameters": {"upper_arm": [0.2, "x"], "rotor_arm": 0.2}}, "parameters.upper_arm", "all numbers or all words"),
        (
            {"parameters": {"rotor_arm": [0.2, 0.3], "upper_arm": {"low": 0.2, "high": 0.3, "when": {"rotor_arm": 0.2}, "otherwise": 0.25}}},
            "parameters.upper_arm.when",
            "listed parameter only",
        ),
        (
            {"parameters": {"upper_arm": {"values": 0.25, "when": {"rotor_arm": 0.3}, "otherwise": 0.2}, "rotor_arm": 0.2}},
            "parameters.upper_arm.when.rotor_arm",
            "remove it",
        ),
        (
            {"parameters": {"rotor_arm": [0.2, 0.3], "upper_arm": {"values": 0.25, "when": {"rotor_arm": 0.2}}}},
            "parameters.upper_arm.otherwise",
            "where it does not apply",
        ),
        (
            {"parameters": {"rotor_arm": 0.2, "upper_arm": {"values": 0.25, "when": {"rotor_arm": 0.3}, "otherwise": 0.2}}},
            "parameters.upper_arm.when.rotor_arm",
            "values among",
        ),
        ({"architectures": ["Q-RR"]}, "architectures", "remove it"),
        (
            {"robot": {"urdf": "r.urdf", "rotors": "r.toml", "derived": {**DERIVED, "upper_arm_com": "__import__('os')"}}},
            "robot.derived.upper_arm_com",
            "only numbers",
        ),
        ({"robot": {"urdf": "missing.urdf", "rotors": "r.toml"}}, "robot.urdf", "an existing file"),
        ({"robot": {"urdf": "r.urdf", "derived": dict(DERIVED)}}, "robot", "rotors as a file"),
    ],
)
def test_a_robot_studys_errors_name_key_value_and_fix(tmp_path, change, key, fix):
    with pytest.raises(InputError) as err:
        DesignSpec.from_mapping(study(tmp_path, **change), base=tmp_path)
    msg = str(err.value)
    assert f"{key} = " in msg and "fix:" in msg and fix in msg, msg


def test_a_placeholder_nobody_gives_and_a_lone_dollar_are_refused(tmp_path):
    with pytest.raises(InputError, match=r"give upper_arm_mass a value: the URDF r.urdf uses it"):
        DesignSpec.from_mapping(study(tmp_path, urdf=URDF.replace('value="0.10"', 'value="${upper_arm_mass}"')), base=tmp_path)
    with pytest.raises(InputError, match=r"line 12: .*\$ 1.*fix: a placeholder"):
        DesignSpec.from_mapping(study(tmp_path, urdf=URDF.replace("<robot", "<!-- $ 1 -->\n<robot", 1)), base=tmp_path)


def test_a_saved_study_is_complete_and_round_trips(tmp_path):
    """The results file's study carries the files' texts: the report rebuilds the designs with the templates gone."""
    spec = DesignSpec.from_mapping(study(tmp_path), base=tmp_path)
    again = DesignSpec.from_mapping(spec.to_dict())
    assert again == spec and again.fingerprint == spec.fingerprint and "${upper_arm}" in again.to_dict()["robot"]["urdf_text"]


def test_expressions_are_arithmetic_only():
    v = {"a": 0.3, "n": 4.0}
    assert evaluate_expression("-a / 2", v, "k") == -0.15 and evaluate_expression("a**2 * 0.1 / 12", v, "k") == 0.3**2 * 0.1 / 12
    assert evaluate_expression("32 / n + sqrt(4) - cos(pi)", v, "k") == 32 / 4 + 2.0 + 1.0
    for bad in ("a.real", "open('f')", "[a]", "a if n else 1", "sqrt(a, n)", "True + a", "'x'"):
        with pytest.raises(InputError, match="fix: only numbers"):
            evaluate_expression(bad, v, "k")
    with pytest.raises(InputError, match="'b' is not"):
        evaluate_expression("b + 1", v, "k")
    with pytest.raises(InputError, match="finite real value"):
        evaluate_expression("(-a) ** 0.5", v, "k")
