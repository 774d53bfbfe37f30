"""Drive a headless Chromium over the DevTools protocol: load the viewer's page, evaluate JavaScript, take screenshots.

Used by the browser test of the viewer and to make the README's screenshot
(``python -m qprr.viz.browser OUT.png``).  Needs a ``chromium`` executable (Debian:
``apt-get install chromium``) and ``websockets`` (installed with viser, the ``viewer`` extra).
Chromium runs with a fresh profile, without sandbox, GPU, QUIC, first-run, background networking,
component updates or sync; WebGL falls back to SwiftShader (``--enable-unsafe-swiftshader``).
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request

from ..errors import MissingDependencyError, QprrError
from ..platforms import DEFAULT_PLATFORM

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
    "--remote-allow-origins=*",
    "--remote-debugging-port=0",
)
"""Command-line flags of the headless browser (plus ``--user-data-dir`` and ``--window-size``)."""


def find_chromium() -> str | None:
    """Path of a Chromium (or Chrome) executable, or None: ``$CHROMIUM``, then chromium, chromium-browser, google-chrome."""
    env = os.environ.get("CHROMIUM")
    if env and shutil.which(env):
        return shutil.which(env)
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    return None


class HeadlessChromium:
    """A headless Chromium showing ``url`` in a ``width`` x ``height`` viewport; close it (or use ``with``)."""

    def __init__(self, url: str, *, width: int = 1280, height: int = 800, timeout: float = 30.0, executable: str | None = None):
        exe = executable or find_chromium()
        if exe is None:
            raise MissingDependencyError("chromium", "the headless browser", "apt-get install chromium")
        try:
            from websockets.sync.client import connect
        except ImportError as exc:
            raise MissingDependencyError("websockets", "the headless browser", "pip install 'qprr[viewer]'") from exc
        self._profile = tempfile.mkdtemp(prefix="qprr-chromium-")
        args = [exe, *FLAGS, f"--user-data-dir={self._profile}", f"--window-size={width},{height}", url]
        self.proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self._id = 0
        self.ws = None
        try:
            port = self._devtools_port(timeout)
            deadline = time.monotonic() + timeout
            while True:
                pages = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5))
                pages = [p for p in pages if p.get("type") == "page"]
                if pages or time.monotonic() > deadline:
                    break
                time.sleep(0.1)
            if not pages:
                raise QprrError("headless Chromium opened no page")
            self.ws = connect(pages[0]["webSocketDebuggerUrl"], max_size=64 * 1024 * 1024, open_timeout=timeout)
            self.call("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1, mobile=False)
        except BaseException:
            self.close()
            raise

    def _devtools_port(self, timeout: float) -> int:
        path = os.path.join(self._profile, "DevToolsActivePort")
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise QprrError(f"Chromium exited with code {self.proc.returncode} before opening its DevTools port")
            if os.path.exists(path):
                text = open(path).read().split()
                if text:
                    return int(text[0])
            time.sleep(0.05)
        raise QprrError(f"Chromium opened no DevTools port within {timeout} s")

    def call(self, method: str, **params) -> dict:
        """Send one DevTools command and return its ``result`` (raises QprrError on a protocol error)."""
        self._id += 1
        self.ws.send(json.dumps({"id": self._id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv(timeout=60))
            if msg.get("id") == self._id:
                if "error" in msg:
                    raise QprrError(f"DevTools {method}: {msg['error']}")
                return msg.get("result", {})

    def evaluate(self, expression: str):
        """Value of a JavaScript expression in the page."""
        res = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        return res.get("result", {}).get("value")

    def screenshot(self, path: str | os.PathLike | None = None) -> bytes:
        """PNG of the viewport (written to ``path`` when given)."""
        data = base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])
        if path is not None:
            with open(path, "wb") as f:
                f.write(data)
        return data

    def close(self) -> None:
        """Quit the browser and delete its profile."""
        if self.ws is not None:
            try:
                self.ws.close()
            except Exception:
                pass
            self.ws = None
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> HeadlessChromium:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


DISMISS_NOTIFICATIONS = "document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click())"
"""JavaScript closing viser's notifications (e.g. "software WebGL rendering detected")."""


def viewer_screenshot(path: str, platform_name: str = DEFAULT_PLATFORM, *, width: int = 1280, height: int = 800, settle: float = 3.0) -> str:
    """Start a viewer of ``platform_name`` on a free port, solve an end-effector target, and save the page as a PNG."""
    import numpy as np

    from ..platforms import resolve
    from .viewer import Viewer

    platform = resolve(platform_name)
    with Viewer(platform, port=0, verbose=False) as viewer, HeadlessChromium(viewer.url, width=width, height=height) as browser:
        deadline = time.monotonic() + 30.0
        while viewer.clients() == 0 and time.monotonic() < deadline:
            time.sleep(0.1)
        from ..charts import rot_y

        ee = viewer.pose.ee_world
        R = platform.model.frames[platform.ee_frame].placement.rotation  # at the neutral arm, level base
        viewer.solve_target(ee + np.array([0.15, 0.0, -0.12]), R @ rot_y(1.0))
        time.sleep(settle)
        browser.evaluate(DISMISS_NOTIFICATIONS)
        time.sleep(0.5)
        browser.screenshot(path)
    return path


if __name__ == "__main__":  # python -m qprr.viz.browser docs/figures/viewer.png
    import sys

    print(viewer_screenshot(sys.argv[1] if len(sys.argv) > 1 else "docs/figures/viewer.png"))
