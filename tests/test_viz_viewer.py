"""The browser viewer: its Python API (FK, IK, player, ports), Ctrl-C, and a real headless Chromium rendering it."""

from __future__ import annotations

import importlib
import io
import math
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr import kinematics
from qprr.charts import rot_y, xi_to_q
from qprr.viz import RunLog
from tests.polling import poll

pytest.importorskip("viser", reason="the viewer needs the 'viewer' extra: pip install 'qprr[viewer]'")
viewer_mod = importlib.import_module("qprr.viz.viewer")  # with viser installed, an import error is a failure
Viewer = viewer_mod.Viewer
ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def platform():
    return qprr.load()


@pytest.fixture()
def viewer(platform):
    v = Viewer(platform, port=0, verbose=False)
    yield v
    v.close()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_sliders_are_forward_kinematics(viewer, platform):
    viewer.set_joint("theta2", 0.7)
    viewer.sliders["r0"].value = -0.03  # as the browser's slider would
    xi = viewer.xi
    assert xi[7] == 0.7 and xi[6] == -0.03
    M = kinematics.ee_placement(platform, platform.data(), xi_to_q(xi))
    np.testing.assert_allclose(viewer.pose.ee_world, M.translation, atol=1e-14)
    np.testing.assert_allclose(viewer.pose.com_world, kinematics.com_world(platform, platform.data(), xi_to_q(xi)), atol=1e-14)
    assert viewer.hover_state.f.sum() == pytest.approx(platform.total_mass * platform.g, rel=1e-13)
    with pytest.raises(qprr.errors.UnknownNameError, match="theta2"):
        viewer.set_joint("theta9", 0.0)
    with pytest.raises(qprr.errors.LimitError, match="theta3"):
        viewer.set_xi(np.r_[xi[:8], 3.0])


@pytest.mark.parametrize(("hover", "cog"), [(True, True), (False, False)])
def test_target_is_solved_by_the_prioritised_ik(viewer, platform, hover, cog):
    viewer._hover_box.value, viewer._cog_box.value = hover, cog
    p_d = viewer.pose.ee_world + np.array([0.1, -0.05, 0.2])
    R_d = rot_y(0.8)
    res = viewer.solve_target(p_d, R_d)
    assert res.success, res.reason
    M = kinematics.ee_placement(platform, platform.data(), xi_to_q(viewer.xi))
    np.testing.assert_allclose(M.translation, p_d, atol=1e-8)
    assert np.linalg.norm(pin.log3(R_d.T @ M.rotation)) < 1e-8
    if hover and cog:
        assert abs(res.roll) < 1e-9 and abs(res.pitch) < 1e-9 and math.hypot(res.x_cm, res.y_cm) < 1e-6
        assert viewer.hover_state.feasible
    np.testing.assert_allclose(viewer.pose.ee_world, p_d, atol=1e-8)


def test_player_shows_the_logged_samples(viewer, platform, tmp_path):
    t = np.linspace(0.0, 1.0, 11)
    xi = np.tile(platform.neutral_xi(), (11, 1))
    xi[:, 8] = np.linspace(-0.5, 0.5, 11)
    f = np.tile([8.0, 9.0, 8.0, 9.0], (11, 1))
    viewer.load_run(RunLog(t, xi, f=f, platform=platform.name))
    viewer.show_time(0.55)  # the sample at 0.5 s
    np.testing.assert_array_equal(viewer.xi, xi[5])
    assert viewer.run_time == 0.5
    viewer.play()
    poll(lambda: viewer.run_time != 0.5, tries=200)  # the player's thread moved on
    viewer.stop_playing()
    k = int(np.flatnonzero(t == viewer.run_time)[0])  # the player moved on and shows a logged sample
    assert viewer.run_time != 0.5 and np.array_equal(viewer.xi, xi[k])
    with pytest.raises(qprr.errors.InputError, match="does not exist"):
        viewer.load_run(tmp_path / "missing.npz")
    with pytest.raises(qprr.errors.ShapeError, match="has 9"):
        viewer.load_run(RunLog(t, xi[:, :8]))


def test_port_in_use_is_a_clear_error(platform):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(qprr.errors.PortInUseError, match=f"port {port} on 127.0.0.1 is already in use"):
            Viewer(platform, port=port, verbose=False)


def test_listens_on_loopback_only(viewer):
    addresses = {a[4][0] for a in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)} - {"127.0.0.1", "127.0.1.1"}
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.connect(("192.0.2.1", 9))  # no packet is sent: finds the outgoing interface
        addresses.add(probe.getsockname()[0])
    except OSError:
        pass
    finally:
        probe.close()
    addresses.discard("0.0.0.0")
    addresses = {a for a in addresses if not a.startswith("127.")}
    if not addresses:
        pytest.skip("no non-loopback IPv4 interface to probe")
    with socket.create_connection(("127.0.0.1", viewer.port), timeout=2):
        pass
    for address in addresses:
        with pytest.raises(OSError):
            socket.create_connection((address, viewer.port), timeout=2).close()


def test_ctrl_c_stops_the_server():
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "qprr", "view", "--port", str(port)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        line = proc.stdout.readline()
        assert f"http://127.0.0.1:{port}" in line, line + proc.stderr.read()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0 and "stopping the viewer" in err and "Traceback" not in err
    with socket.socket() as s:  # the port is free again
        s.bind(("127.0.0.1", port))


# ------------------------------------------------------------------------------------------- real browser
browser_mod = importlib.import_module("qprr.viz.browser")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _png(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=np.int16)


def _wait_for_change(browser, before: np.ndarray, region, pixels: int = 200, tries: int = 40) -> tuple[np.ndarray, int]:
    """Screenshot until the 3-D region differs from ``before`` in more than ``pixels`` pixels (at most ``tries`` shots,
    0.5 s apart: a loaded machine renders in several frames)."""
    last = {"shot": before, "changed": 0}

    def differs() -> bool:
        last["shot"] = _png(browser.screenshot())
        last["changed"] = int((np.abs(last["shot"][region] - before[region]).max(axis=2) > 30).sum())
        return last["changed"] > pixels

    poll(differs, tries, pause=0.5)
    return last["shot"], last["changed"]


@pytest.mark.slow
@pytest.mark.skipif(browser_mod.find_chromium() is None, reason="Chromium is not installed (Debian: apt-get install chromium)")
def test_headless_chromium_renders_the_viewer_and_its_ik(platform):
    """Chromium loads the page and renders the robot with WebGL; moving a slider and solving a target change the picture;
    the page shows the IK outcome the viewer reports, and that outcome is right (FK at the target, hover, CoG on the axis)."""
    with Viewer(platform, port=0, verbose=False) as viewer, browser_mod.HeadlessChromium(viewer.url, width=1280, height=800) as browser:
        poll(lambda: viewer.clients() > 0, tries=300, pause=0.1)
        assert viewer.clients() == 1, "the page did not connect to the viewer"
        assert browser.evaluate("!!document.createElement('canvas').getContext('webgl2')"), "no WebGL in headless Chromium"
        browser.evaluate(browser_mod.DISMISS_NOTIFICATIONS)
        scene = (slice(0, 800), slice(0, 860))  # the 3-D view, left of the control panel
        blank = _png(browser.screenshot())
        first, drawn = _wait_for_change(browser, np.full_like(blank, 255), scene, pixels=2000)
        assert drawn > 2000, "nothing rendered in the 3-D view"

        viewer.set_joint("theta2", 1.2)  # a slider move through the viewer's API
        after_slider, changed = _wait_for_change(browser, first, scene)
        assert changed > 200, "the picture did not change when theta2 moved"
        values = browser.evaluate("Array.from(document.querySelectorAll('input')).map(i => i.value)")
        assert any(_is_number(v) and float(v) == 1.2 for v in values), values  # the page's theta2 slider followed

        p_d = viewer.pose.ee_world + np.array([0.05, 0.1, 0.15])
        res = viewer.solve_target(p_d)
        _, changed = _wait_for_change(browser, after_slider, scene)
        assert changed > 200, "the picture did not change when the IK moved the robot"
        assert res.status == "converged" and res.success
        M = kinematics.ee_placement(platform, platform.data(), xi_to_q(viewer.xi))
        np.testing.assert_allclose(M.translation, p_d, atol=1e-8)
        assert abs(res.roll) < 1e-9 and abs(res.pitch) < 1e-9 and math.hypot(res.x_cm, res.y_cm) < 1e-6
        poll(lambda: "IK converged" in browser.evaluate("document.body.innerText"), tries=50, pause=0.2)
        text = browser.evaluate("document.body.innerText")
        assert "IK converged" in text and f"position error {res.position_error:.2e} m" in text
        assert "can hover" in text
