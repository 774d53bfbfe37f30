"""ArduPilot frame scripts (qprr.flightstack.ardupilot) and the fixed mixer's error map (qprr.flightstack.mixer):
factor signs against a hand-worked quad X, the scripts run in a Lua interpreter against mock bindings, the mixer's
error is zero at the export pose and grows with the centre of gravity's shift."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qprr
from qprr.errors import ActuationError, InputError
from qprr.flightstack import ardupilot as ap
from qprr.flightstack import px4
from qprr.flightstack.mixer import mixer_error
from qprr.rotors import Rotor

D = 0.2 / math.sqrt(2.0)


def quad_x() -> tuple[Rotor, ...]:
    """ArduPilot's QUAD X numbering, in qprr's FLU body frame (right = -y): motor 1 front right CCW, 2 back left CCW,
    3 front left CW, 4 back right CW.  A propeller turning CCW seen from above has its drag torque down: spin -1."""
    return (
        Rotor((D, -D, 0.0), (0, 0, 1), -1, 0.02, 0.0, 10.0),
        Rotor((-D, D, 0.0), (0, 0, 1), -1, 0.02, 0.0, 10.0),
        Rotor((D, D, 0.0), (0, 0, 1), 1, 0.02, 0.0, 10.0),
        Rotor((-D, -D, 0.0), (0, 0, 1), 1, 0.02, 0.0, 10.0),
    )


def test_quad_x_factors_by_hand():
    """AP_MotorsMatrix's QUAD X: add_motor(1, 45 deg, CCW, 1), (2, -135, CCW, 3), (3, -45, CW, 4), (4, 135, CW, 2),
    roll = cos(angle + 90), pitch = cos(angle), yaw +1 for CCW, then normalised to 0.5."""
    f = ap.motor_factors(px4.geometry_from_rotors(quad_x()))
    angles = np.radians([45.0, -135.0, -45.0, 135.0])
    np.testing.assert_allclose(f.roll, 0.5 * np.sign(np.round(np.cos(angles + np.pi / 2), 9)), atol=1e-12)
    np.testing.assert_allclose(f.pitch, 0.5 * np.sign(np.round(np.cos(angles), 9)), atol=1e-12)
    np.testing.assert_allclose(f.yaw, [0.5, 0.5, -0.5, -0.5], atol=1e-12)
    np.testing.assert_allclose(f.throttle, 1.0)
    assert f.testing_order == (1, 3, 4, 2)


def test_offset_cog_factors_put_no_torque_in_throttle():
    """CoG 3 cm forward: the throttle factors load the front motors more and produce no torque about the CoG."""
    c = np.array([0.03, 0.0, 0.0])
    g = px4.geometry_from_rotors(quad_x(), c)
    f = ap.motor_factors(g)
    assert f.throttle[0] > f.throttle[1] and f.throttle[2] > f.throttle[3]
    np.testing.assert_allclose(g.effectiveness()[0:3] @ f.throttle, 0.0, atol=1e-12)
    # roll and pitch factors give pure roll and pure pitch torque
    E = g.effectiveness()
    assert abs(E[1] @ f.roll) < 1e-12 and abs(E[0] @ f.pitch) < 1e-12 and E[0] @ f.roll > 0 and E[1] @ f.pitch > 0


def test_tilted_set_needs_six_dof():
    f = ap.motor_factors(px4.geometry_from_platform(qprr.load("hextilt_flying_arm_5")))
    assert f.forward is not None and f.right is not None
    assert max(np.abs(f.roll).max(), np.abs(f.pitch).max(), np.abs(f.yaw).max()) == pytest.approx(0.5)
    tilted = tuple(Rotor(r.position_body, (0.1, 0.0, 1.0), r.spin, r.kappa, 0.0, 10.0) for r in quad_x())
    with pytest.raises(ActuationError, match="six wrench directions"):
        ap.motor_factors(px4.geometry_from_rotors(tilted))


class _Recorder:
    def __init__(self):
        self.calls = []


def _run_lua(script: str, params: dict | None = None):
    """Run a generated script with mock ArduPilot bindings; returns the recorded calls and the script's results."""
    lupa = pytest.importorskip("lupa", reason="lupa is not installed: pip install lupa (a Lua interpreter to run the generated scripts)")
    lua = lupa.LuaRuntime(unpack_returned_tuples=True)
    rec = _Recorder()
    params = params or {}
    lua.execute(
        """
        calls = {}
        local function rec(...) table.insert(calls, {...}) end
        MotorsMatrix = {}
        function MotorsMatrix:add_motor_raw(i, r, p, y, o) rec("raw", i, r, p, y, o) end
        function MotorsMatrix:set_throttle_factor(i, t) rec("thr", i, t) end
        function MotorsMatrix:init(n) rec("init", n) return true end
        Motors_6DoF = {}
        function Motors_6DoF:add_motor(i, r, p, y, t, f, s, rev, o) rec("6dof", i, r, p, y, t, f, s, rev, o) end
        function Motors_6DoF:init(n) rec("init", n) return true end
        Motors_dynamic = {}
        function Motors_dynamic:add_motor(i, o) rec("dyn", i, o) end
        function Motors_dynamic:load_factors(ft) rec("load", ft) end
        function Motors_dynamic:init(n) rec("init", n) return true end
        function motor_factor_table()
          local t = {roll_ = {}, pitch_ = {}, yaw_ = {}, throttle_ = {}}
          function t:roll(i, v) self.roll_[i] = v end
          function t:pitch(i, v) self.pitch_[i] = v end
          function t:yaw(i, v) self.yaw_[i] = v end
          function t:throttle(i, v) self.throttle_[i] = v end
          return t
        end
        motors = {}
        function motors:set_frame_string(s) rec("name", s) end
        PARAMS = {}
        param = {}
        function param:get(name) return PARAMS[name] end
        """
    )
    for k, v in params.items():
        lua.globals().PARAMS[k] = v
    result = lua.execute(script)
    calls = [list(c.values()) for c in lua.globals().calls.values()]
    rec.calls = calls
    return rec, result, lua


def test_matrix_script_runs_and_matches_the_factors():
    p = qprr.load("q-prr")
    rec, _, _ = _run_lua(ap.frame_script(p))
    f = ap.motor_factors(px4.geometry_from_platform(p))
    raws = [c for c in rec.calls if c[0] == "raw"]
    assert len(raws) == 4 and ["init", 4] in rec.calls
    for c in raws:
        i = int(c[1])
        np.testing.assert_allclose(c[2:5], [f.roll[i], f.pitch[i], f.yaw[i]], atol=1e-6)


def test_6dof_script_runs():
    rec, _, _ = _run_lua(ap.frame_script(qprr.load("hextilt_flying_arm_5")))
    assert len([c for c in rec.calls if c[0] == "6dof"]) == 6 and ["init", 6] in rec.calls


def test_dynamic_script_interpolates_the_table():
    """The script's factors at a joint value between grid points equal the linear interpolation of qprr's table, and
    at a grid point the factors of that pose."""
    p = qprr.load("q-prr")
    t = ap.factor_table(p, joints=["r0"], resolution=5)
    q_mid = 0.5 * (t.axes[0][1] + t.axes[0][2])
    rec, result, lua = _run_lua(ap.dynamic_script(p, joints=["r0"], resolution=5), {"SCR_USER1": q_mid})
    assert ["init", 4] in rec.calls and len([c for c in rec.calls if c[0] == "dyn"]) == 4
    update, period = result
    assert period == ap.UPDATE_MS
    ft = [c for c in rec.calls if c[0] == "load"][-1][1]
    thr = [ft.throttle_[i] for i in range(4)]
    np.testing.assert_allclose(thr, 0.5 * (t.throttle[1] + t.throttle[2]), atol=1e-6)
    lua.globals().PARAMS["SCR_USER1"] = float(t.axes[0][3])
    update()
    calls = [list(c.values()) for c in lua.globals().calls.values()]
    ft = [c for c in calls if c[0] == "load"][-1][1]
    q = p.neutral_q()[7:].copy()
    q[0] = t.axes[0][3]
    f = ap.motor_factors(px4.geometry_from_platform(p, q))
    np.testing.assert_allclose([ft.throttle_[i] for i in range(4)], f.throttle, atol=1e-6)
    np.testing.assert_allclose([ft.roll_[i] for i in range(4)], f.roll, atol=1e-6)


def test_dynamic_refuses_tilted_sets():
    with pytest.raises(ActuationError, match="tilted"):
        ap.factor_table(qprr.load("hextilt_flying_arm_5"), resolution=2)


# ------------------------------------------------------------------ the fixed mixer's error
def test_mixer_error_zero_at_export_pose_and_grows():
    """Q-PRR, one joint (the slider r0) mapped: 0 at q0, and for parallel rotors the error is the CoG shift in the
    rotor plane over the span, so it grows linearly away from q0 on both sides."""
    p = qprr.load("q-prr")
    q0 = p.neutral_q()[7:]
    res = mixer_error(p, q0, joints=["r0"], resolution=21, samples=0)
    line = res.error_map
    k0 = int(np.argmin(np.abs(res.axes[0] - q0[0])))
    assert line[k0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.diff(line[k0:]) > 0) and np.all(np.diff(line[: k0 + 1]) < 0)
    # by hand: the CoG moves with the slider by (m_arm / m) dr along x; error = |dc| / L
    c = px4.coms_body_at(p, np.array([[0.04, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    span = max(math.hypot(*r.position_frd) for r in px4.geometry_from_platform(p, q0).rotors)
    assert line[-1] == pytest.approx(np.linalg.norm((c[0] - c[1])[:2]) / span, rel=1e-3)
    assert res.span == pytest.approx(span)


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR"])
def test_mixer_map_and_best_pose(name, tmp_path):
    p = qprr.load(name) if name == "q-prr" else qprr.build(name)
    res = mixer_error(p, resolution=15, samples=200)
    assert res.error_map.shape == (15, 15)
    assert res.worst_error >= res.error_map.max() - 1e-12 and res.worst_error > 0.01
    assert res.best_worst_error <= res.worst_error + 1e-12
    assert res.worst_hover_torque > 0.0
    assert "worst wrench error" in res.summary()
    fig = res.plot(tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 10_000
    assert fig.axes[0].get_xlabel().endswith("]")
    # exporting at the worst pose makes the original pose's error the same size (symmetric: |dc| both ways)
    other = mixer_error(p, res.worst_q, resolution=15, samples=0)
    assert other.worst_error >= res.best_worst_error - 1e-12


def test_mixer_error_arguments():
    p = qprr.load("q-prr")
    with pytest.raises(InputError, match="not an arm joint"):
        mixer_error(p, joints=["elbow"])
    with pytest.raises(InputError, match="not in"):
        mixer_error(p, [1.0, 0.0, 0.0])
