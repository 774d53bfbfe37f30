"""Visual geometry: the Q-PRR URDF's shapes leave the dynamics untouched and sit where the kinematics says; any platform gets shapes."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.thesis import cad_params, thesis_params
from qprr.thesis.urdf import PROPELLER_RADIUS, URDF_PATH, build_urdf
from qprr.viz import primitive_visual_model, visual_model

RNG = np.random.default_rng(14)


def _model(text: str) -> pin.Model:
    return pin.buildModelFromXML(text, pin.JointModelFreeFlyer())


def _random_q(model: pin.Model) -> np.ndarray:
    q = np.empty(model.nq)
    q[0:3] = RNG.uniform(-2.0, 2.0, 3)
    q[3:7] = pin.Quaternion(pin.exp3(RNG.normal(size=3))).coeffs()
    q[7:] = RNG.uniform(model.lowerPositionLimit[7:], model.upperPositionLimit[7:])
    return q


def _strip_visuals(text: str) -> str:
    root = ET.fromstring(text)
    for link in root.iter("link"):
        for vis in link.findall("visual"):
            link.remove(vis)
    return ET.tostring(root, encoding="unicode")


def test_committed_urdf_is_the_generated_one():
    assert URDF_PATH.read_text() == build_urdf(), "regenerate with `python -m qprr.thesis.urdf`"


@pytest.mark.parametrize("params", [thesis_params(), cad_params()], ids=["thesis", "cad"])
@pytest.mark.parametrize("layout", ["plus", "x"])
def test_visual_shapes_do_not_change_the_dynamics(params, layout):
    """M(q) and RNEA are bit-identical with and without the <visual> elements (and with them stripped by XML)."""
    text = build_urdf(params, layout=layout)
    models = [_model(text), _model(build_urdf(params, layout=layout, visuals=False)), _model(_strip_visuals(text))]
    assert "<visual>" in text and "<visual>" not in build_urdf(params, layout=layout, visuals=False)
    datas = [m.createData() for m in models]
    for _ in range(20):
        q = _random_q(models[0])
        v, a = RNG.normal(size=models[0].nv), RNG.normal(size=models[0].nv)
        M = [pin.crba(m, d, q).copy() for m, d in zip(models, datas)]
        tau = [pin.rnea(m, d, q, v, a).copy() for m, d in zip(models, datas)]
        for k in (1, 2):
            np.testing.assert_array_equal(M[0], M[k])
            np.testing.assert_array_equal(tau[0], tau[k])
    assert [f.name for f in models[0].frames] == [f.name for f in models[1].frames]


@pytest.mark.parametrize("layout", ["plus", "x"])
def test_propeller_discs_sit_on_the_rotors_of_the_layout(layout):
    """One disc per rotor of the platform, centred 17 mm above the rotor on its thrust axis, radius 0.127 m; none elsewhere."""
    platform = qprr.load("q-prr", layout=layout)
    geom = visual_model(platform)
    model = platform.model
    discs = [o for o in geom.geometryObjects if o.geometry.__class__.__name__ == "Cylinder" and o.geometry.radius > 0.1]
    assert len(discs) == platform.n_rotors
    data, gdata = model.createData(), geom.createData()
    q = platform.neutral_q()
    pin.updateGeometryPlacements(model, data, geom, gdata, q)
    centres = {tuple(np.round(gdata.oMg[geom.getGeometryId(o.name)].translation, 12)) for o in discs}
    expected = {tuple(np.round(np.array(r.position_body) + [0.0, 0.0, 0.017], 12)) for r in platform.rotors}
    assert centres == expected
    for o in discs:
        assert o.geometry.radius == PROPELLER_RADIUS
        np.testing.assert_allclose(gdata.oMg[geom.getGeometryId(o.name)].rotation[:, 2], [0.0, 0.0, 1.0], atol=1e-15)
        assert model.frames[o.parentFrame].name.startswith(f"rotor_{layout}_")


def _cylinder_ends(gdata, geom, name):
    gid = geom.getGeometryId(name)
    M, h = gdata.oMg[gid], geom.geometryObjects[gid].geometry.halfLength
    return M.act(np.array([0.0, 0.0, -h])), M.act(np.array([0.0, 0.0, h]))


def test_qprr_links_join_the_joint_origins_at_any_configuration():
    """Each arm cylinder spans its link: theta2 -> theta3 (length d2), theta3 -> end effector (d3), from FK at random q."""
    platform = qprr.load()
    p = platform.params
    model, geom = platform.model, visual_model(platform)
    data, gdata = model.createData(), geom.createData()
    ee = platform.ee_frame
    for _ in range(10):
        q = _random_q(model)
        pin.updateGeometryPlacements(model, data, geom, gdata, q)
        pin.updateFramePlacements(model, data)
        lo, hi = _cylinder_ends(gdata, geom, "link2_1")
        np.testing.assert_allclose(lo, data.oMi[model.getJointId("theta2")].translation, atol=1e-14)
        np.testing.assert_allclose(hi, data.oMi[model.getJointId("theta3")].translation, atol=1e-14)
        assert np.linalg.norm(hi - lo) == pytest.approx(p.d2, abs=1e-14)
        lo, hi = _cylinder_ends(gdata, geom, "link3_1")
        np.testing.assert_allclose(hi, data.oMf[ee].translation, atol=1e-14)
        assert np.linalg.norm(hi - lo) == pytest.approx(p.d3, abs=1e-14)


def test_booms_run_from_the_hub_to_each_rotor():
    platform = qprr.load("q-prr", layout="x")
    model, geom = platform.model, visual_model(platform)
    data, gdata = model.createData(), geom.createData()
    pin.updateGeometryPlacements(model, data, geom, gdata, platform.neutral_q())
    hub = geom.geometryObjects[geom.getGeometryId("multirotor_0")].geometry.radius
    for i, r in enumerate(platform.rotors, start=1):
        a, b = _cylinder_ends(gdata, geom, f"rotor_x_{i}_0")
        ends = sorted([a, b], key=np.linalg.norm)
        assert np.linalg.norm(ends[0][0:2]) == pytest.approx(hub, abs=1e-14)
        np.testing.assert_allclose(ends[1], r.position_body, atol=1e-14)


def test_example_robot_data_platforms_use_their_meshes():
    platform = qprr.load("borinot_flying_arm_2")
    geom = visual_model(platform)
    paths = [o.meshPath for o in geom.geometryObjects]
    assert geom.ngeoms >= 3 and all(p.endswith(".dae") for p in paths)
    assert all(__import__("os").path.isfile(p) for p in paths)


@pytest.mark.parametrize("name", ["hextilt_flying_arm_5", "HEX-RRR"])
def test_primitive_shapes_follow_the_model(name):
    """Without a URDF: a disc per rotor normal to its (possibly tilted) axis, arm cylinders joining consecutive joints."""
    platform = qprr.load(name) if "_" in name else qprr.build(name)
    bare = qprr.model.from_model(platform.model, platform.rotors, ee_frame=platform.ee_frame, name="bare")
    assert bare.urdf is None
    geom = visual_model(bare)
    assert geom.ngeoms == len(primitive_visual_model(bare).geometryObjects)
    model = bare.model
    data, gdata = model.createData(), geom.createData()
    q = _random_q(model)
    pin.updateGeometryPlacements(model, data, geom, gdata, q)
    pin.updateFramePlacements(model, data)
    R, p = data.oMi[1].rotation, data.oMi[1].translation
    for k, r in enumerate(bare.rotors):
        M = gdata.oMg[geom.getGeometryId(f"rotor_{k}_disc")]
        np.testing.assert_allclose(M.translation, p + R @ np.array(r.position_body), atol=1e-13)
        np.testing.assert_allclose(M.rotation[:, 2], R @ np.array(r.axis_body), atol=1e-13)
    chain = [j for j in model.supports[model.frames[bare.ee_frame].parentJoint] if j >= 2]
    ends = [data.oMi[j].translation for j in chain[1:]] + [data.oMf[bare.ee_frame].translation]
    for j, end in zip(chain, ends):
        name_j = f"{model.names[j]}_link"
        if geom.existGeometryName(name_j):
            a, b = _cylinder_ends(gdata, geom, name_j)
            np.testing.assert_allclose(a, data.oMi[j].translation, atol=1e-13)
            np.testing.assert_allclose(b, end, atol=1e-13)


def test_visual_model_rejects_a_missing_urdf_file(tmp_path):
    with pytest.raises(qprr.errors.InputError, match="does not exist"):
        visual_model(qprr.load(), tmp_path / "nope.urdf")
