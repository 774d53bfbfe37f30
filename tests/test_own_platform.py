"""A user's own aerial manipulator (docs/platforms.md, examples/my_platform): physics of the loaded platform, every
mistake of the page's table ending in the error the page shows, and the command line with ``--urdf``.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr.actuation import Allocator
from qprr.cli import main

ROOT = Path(__file__).resolve().parents[1]
MY = ROOT / "examples" / "my_platform"
URDF = (MY / "quad_rrr.urdf").read_text()
TOML = (MY / "quad_rrr.rotors.toml").read_text()
OWN = ["--urdf", str(MY / "quad_rrr.urdf"), "--rotors", str(MY / "quad_rrr.rotors.toml"), "--ee-frame", "gripper"]


@pytest.fixture(scope="module")
def platform():
    return qprr.from_urdf(MY / "quad_rrr.urdf", MY / "quad_rrr.rotors.toml", ee_frame="gripper")


def test_mass_rotors_and_hover_of_the_example(platform):
    """Mass = the sum of the URDF's link masses; Omega of an X quadrotor in closed form ([0, 0, 1, y_i, -x_i, s_i kappa]);
    hover thrusts m g / 4 each (CoG on z_B: the arm hangs straight under the body)."""
    masses = [float(m.get("value")) for m in ET.fromstring(URDF).iter("mass")]
    assert platform.total_mass == pytest.approx(sum(masses), rel=1e-15) and len(masses) == 5
    a = 0.1414
    xy = np.array([[a, a], [-a, a], [-a, -a], [a, -a]])
    spins = np.array([1, -1, 1, -1])
    expected = np.vstack([np.zeros((2, 4)), np.ones(4), xy[:, 1], -xy[:, 0], 0.016 * spins])
    np.testing.assert_allclose(platform.rotor_matrix, expected, rtol=0, atol=1e-15)
    f = Allocator(platform).hover_thrusts()
    np.testing.assert_allclose(f, platform.total_mass * platform.g / 4, rtol=1e-14)
    assert (platform.arm_names, platform.wrench_rank, platform.fully_actuated) == (("yaw", "shoulder", "elbow"), 4, False)


# -------------------------------------------------------------------------------------- mistakes
_REV = """<?xml version="1.0"?>
<robot name="rev">
  <link name="gripper"><inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
  <joint name="elbow" type="revolute"><parent link="gripper"/><child link="forearm"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="forearm"><inertial><mass value="0.07"/><inertia ixx="2.33e-4" ixy="0" ixz="0" iyy="2.33e-4" iyz="0" izz="1e-6"/></inertial></link>
  <joint name="mount" type="fixed"><parent link="forearm"/><child link="base_link"/><origin xyz="0 0 0.3"/></joint>
  <link name="base_link"><inertial><mass value="1.2"/><inertia ixx="0.00964" ixy="0" ixz="0" iyy="0.00964" iyz="0" izz="0.018"/></inertial></link>
</robot>"""


def _grams(text: str) -> str:
    return re.sub(r'<mass value="([\d.]+)"/>', lambda m: f'<mass value="{round(float(m.group(1)) * 1000)}"/>', text)


def _no_inertial(link: str):
    return lambda text: re.sub(rf'(<link name="{link}">)\s*<inertial>.*?</inertial>', r"\1", text, flags=re.S)


def _joint_type(kind: str):
    return lambda text: text.replace('name="elbow" type="revolute"', f'name="elbow" type="{kind}"')


_FIRST_ROTOR = "position = [0.1414, 0.1414, 0.03]\naxis = [0.0, 0.0, 1.0]"
# table row of docs/platforms.md -> (URDF edit, rotor-file edit, from_urdf keywords, rotor file name)
MISTAKES = {
    '`ee_frame="grippr"`': (None, None, {"ee_frame": "grippr"}, None),
    "a misspelt key (`spn`, `fmax`, `[[rotors]]`)": (None, lambda t: t.replace('spin = "ccw"', 'spn = "ccw"', 1), {}, None),
    "no `spin`": (None, lambda t: t.replace('spin = "ccw"\n', "\n", 1), {}, None),
    "`axis = [0, 0, 2]`": (None, lambda t: t.replace("axis = [0.0, 0.0, 1.0]", "axis = [0, 0, 2]"), {}, None),
    "positions in millimetres": (None, lambda t: t.replace("0.1414", "141.4").replace("0.03]", "30.0]"), {}, None),
    "masses in grams (or thrusts too small)": (_grams, None, {}, None),
    "a non-physical inertia, a negative mass": (lambda t: t.replace('izz="0.018"', 'izz="0.03"'), None, {}, None),
    "a moving link without `<inertial>`": (_no_inertial("upper_arm"), None, {}, None),
    "a `continuous` joint": (_joint_type("continuous"), None, {}, None),
    "a revolute joint without `<limit>`": (
        lambda t: re.sub(r'(name="elbow" type="revolute">.*?)<limit[^>]*/>', r"\1", t, flags=re.S),
        None,
        {},
        None,
    ),
    "a `world` link with a `floating` joint": (
        lambda t: t.replace(
            '<robot name="quad_rrr">',
            '<robot name="quad_rrr">\n<link name="world"/>\n'
            '<joint name="float" type="floating"><parent link="world"/><child link="base_link"/></joint>',
        ),
        None,
        {},
        None,
    ),
    "a `planar` or `floating` arm joint": (_joint_type("planar"), None, {}, None),
    "the body is not the URDF's root (with `base_link` in the rotor file)": (lambda t: _REV, None, {"ee_frame": "gripper"}, None),
    "a rotor `frame` on an arm link": (None, lambda t: t.replace(_FIRST_ROTOR, 'frame = "forearm"'), {}, None),
    "a rotor file that is not `.toml`": (None, None, {}, "rotors.yaml"),
}


def _doc_rows() -> dict[str, str]:
    text = (ROOT / "docs" / "platforms.md").read_text()
    section = text[text.index("## When something is wrong") : text.index("## What the core assumes")]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")] if line.startswith("| ") else []
        if len(cells) == 2 and cells[0] not in ("mistake",) and not set(cells[0]) <= {"-"}:
            rows[cells[0]] = cells[1]
    return rows


def _pattern(cell: str) -> str:
    """The error shown in the page as a regex: the text between backticks, each "..." standing for any text."""
    shown = cell.strip("`")
    return ".*".join(re.escape(part.strip()) for part in shown.split("..."))


def test_every_row_of_the_page_is_tested():
    assert set(_doc_rows()) == set(MISTAKES)


@pytest.mark.parametrize("row", list(MISTAKES))
def test_mistake_ends_in_the_error_the_page_shows(row, tmp_path):
    edit_urdf, edit_toml, kwargs, rotor_name = MISTAKES[row]
    urdf = tmp_path / "quad_rrr.urdf"
    urdf.write_text(edit_urdf(URDF) if edit_urdf else URDF)
    rotors = tmp_path / (rotor_name or "quad_rrr.rotors.toml")
    rotors.write_text(edit_toml(TOML) if edit_toml else TOML)
    with pytest.raises(qprr.QprrError) as exc:
        qprr.from_urdf(urdf, rotors, **kwargs)
    message = f"{type(exc.value).__name__}: {exc.value}".replace(f"{tmp_path}/", "")  # the page shows file names
    assert re.search(_pattern(_doc_rows()[row]), message, flags=re.S), f"{row}:\n{message}"


def test_the_rotor_file_of_the_page_is_the_example_file(tmp_path):
    from qprr.rotors import read_rotor_file, rotors_from_mapping

    text = (ROOT / "docs" / "platforms.md").read_text()
    (block,) = re.findall(r"```toml\n(.*?)```", text, flags=re.S)
    (tmp_path / "page.toml").write_text(block)
    page = read_rotor_file(tmp_path / "page.toml")
    assert page["base_link"] == "base_link"
    assert rotors_from_mapping(page) == rotors_from_mapping(read_rotor_file(MY / "quad_rrr.rotors.toml"))


# ---------------------------------------------------------------------------------- command line
def test_cli_simulate_analyze_animate_with_a_urdf(tmp_path, capsys):
    run = tmp_path / "reach.npz"
    assert main(["simulate", "hover-reach", *OWN, "--duration", "4", "--save", str(run), "-q"]) == 0
    out = capsys.readouterr().out
    assert "platform quad_rrr, controller idc: ok" in out
    assert main(["analyze", "capacity", *OWN, "--samples", "2000"]) == 0
    assert "payload capacity of quad_rrr" in capsys.readouterr().out
    gif = tmp_path / "reach.gif"
    assert main(["animate", str(run), *OWN, "-o", str(gif), "--fps", "2", "-q"]) == 0
    assert gif.read_bytes()[:6] == b"GIF89a"
    # the same run drawn on the default Q-PRR is refused, naming both platforms
    assert main(["animate", str(run), "-o", str(tmp_path / "wrong.gif"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "recorded on platform 'quad_rrr', not on 'Q-PRR (thesis, plus)'" in err
    assert not (tmp_path / "wrong.gif").exists()


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["simulate", "hover-reach", "--urdf", str(MY / "quad_rrr.urdf")], "needs --rotors FILE.toml"),
        (["simulate", "hover-reach", "--rotors", str(MY / "quad_rrr.rotors.toml")], "give its --urdf too"),
        (["simulate", "hover-reach", "--platform", "HEX-RRR", *OWN], "leave out --platform and --layout"),
        (["simulate", "static-idc", *OWN], "runs on q-prr"),
        (["simulate", "hover-reach", "--urdf", "nope.urdf", "--rotors", str(MY / "quad_rrr.rotors.toml")], "'nope.urdf' does not exist"),
        (["simulate", "hover-reach", *OWN[:4], "--ee-frame", "grippr"], "unknown ee_frame 'grippr'"),
        (["analyze", "hover", "--ee-frame", "gripper"], "give its --urdf too"),
        (["analyze", "hover", "--platform", "quad"], "--urdf FILE --rotors FILE.toml"),
        (["animate", "--platform", "borinot_flying_arm_2", "--layout", "x"], "unknown option of platform 'borinot_flying_arm_2' 'layout'"),
    ],
)
def test_cli_platform_errors(argv, fragment, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert fragment in err and err.count("\n") == 1, err
