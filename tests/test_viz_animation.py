"""Headless animation: decimation of the run, the files written (GIF by Pillow, MP4 by ffmpeg), the errors."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image, ImageChops

import qprr
from qprr.viz import RunLog, animate, animate_result
from qprr.viz import animation as anim
from qprr.viz.animation import frame_indices

SMALL = dict(size=(160, 120), fps=10.0)


@pytest.fixture(scope="module")
def platform():
    return qprr.load()


def _run(platform, duration=1.0, rate=100.0, wave=True):
    t = np.arange(int(round(duration * rate)) + 1) / rate
    xi = np.tile(platform.neutral_xi(), (t.size, 1))
    xi[:, 2] = 1.0
    if wave:
        xi[:, 7] = 0.8 * np.sin(2.0 * np.pi * t / duration)
    f = np.full((t.size, 4), platform.total_mass * platform.g / 4.0)
    return t, xi, f


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.0, 0.3), min_size=1, max_size=40), st.floats(1.0, 60.0), st.floats(0.25, 4.0))
def test_each_frame_shows_the_last_sample_before_its_time(steps, fps, speed):
    t = np.cumsum(np.array(steps))
    times, idx = frame_indices(t, fps, speed)
    assert times.size == math.floor((t[-1] - t[0]) * fps / speed + 1e-9) + 1
    np.testing.assert_allclose(np.diff(times), speed / fps, rtol=1e-9)
    assert times[0] == t[0] and times[-1] <= t[-1] + 1e-9
    assert np.all(t[idx] <= times + 1e-12)
    later = np.minimum(idx + 1, t.size - 1)
    assert np.all((idx == t.size - 1) | (t[later] > times))


def test_gif_has_one_frame_per_decimated_time(platform, tmp_path):
    t, xi, f = _run(platform, duration=2.0, rate=1000.0)  # 2001 samples -> 21 frames at 10 fps
    info = animate(platform, t, xi, tmp_path / "a.gif", f=f, contact_force_world=np.tile([0.0, 0.0, -3.0], (t.size, 1)), **SMALL)
    assert info.frames == 21 and info.duration == pytest.approx(2.0) and info.writer.startswith("gif")
    with Image.open(info.path) as im:
        assert im.size == (160, 120) and im.n_frames == 21
        assert im.info["duration"] == 100 and im.info.get("loop") == 0
        im.seek(0)
        first = im.convert("RGB")
        im.seek(5)
        moved = im.convert("RGB")
    assert ImageChops.difference(first, moved).getbbox() is not None  # the arm moved between the frames
    assert not (tmp_path / "a.partial.gif").exists()


def test_same_configuration_same_picture(platform, tmp_path):
    """A still run gives identical frames: the picture depends on the configuration only."""
    t, xi, f = _run(platform, wave=False)
    info = animate(platform, t, xi, tmp_path / "still.gif", f=f, trail=0.0, **SMALL)
    with Image.open(info.path) as im:
        frames = []
        for k in (0, info.frames - 1):
            im.seek(k)
            frames.append(im.convert("RGB"))
    # the text line (time) changes; the 3-D scene below it must not
    h = frames[0].size[1]
    box = (0, int(0.2 * h), frames[0].size[0], int(0.9 * h))
    assert ImageChops.difference(frames[0].crop(box), frames[1].crop(box)).getbbox() is None


def test_animate_result_reads_a_run(platform, tmp_path):
    t, xi, f = _run(platform)
    wrench = np.zeros((t.size, 6))
    wrench[:, 0] = 2.0
    info = animate_result(
        platform, RunLog(t, xi, f=f, contact_wrench_world=wrench, platform=platform.name), tmp_path / "r.gif", view="fixed", **SMALL
    )
    assert info.frames == 11
    with pytest.raises(qprr.errors.ShapeError, match="4 rotors"):
        animate_result(platform, RunLog(t, xi, f=np.zeros((t.size, 6))), tmp_path / "bad.gif", **SMALL)
    with pytest.raises(qprr.errors.ShapeError, match="has 9"):
        animate_result(platform, RunLog(t, xi[:, :8]), tmp_path / "bad.gif", **SMALL)


def test_mp4_needs_ffmpeg(platform, tmp_path, monkeypatch):
    t, xi, _ = _run(platform)
    if shutil.which("ffmpeg"):
        info = animate(platform, t, xi, tmp_path / "a.mp4", **SMALL)
        assert info.path.stat().st_size > 0
    monkeypatch.setattr(anim.shutil, "which", lambda name: None)
    with pytest.raises(qprr.errors.MissingDependencyError, match="apt-get install ffmpeg"):
        animate(platform, t, xi, tmp_path / "b.mp4", **SMALL)


def test_bad_inputs_are_named(platform, tmp_path):
    t, xi, f = _run(platform)
    with pytest.raises(qprr.errors.ShapeError, match=r"xi must have shape \(101, 9\)"):
        animate(platform, t, xi[:, :7], tmp_path / "a.gif")
    with pytest.raises(qprr.errors.ShapeError, match=r"f must have shape \(101, 4\)"):
        animate(platform, t, xi, tmp_path / "a.gif", f=f[:, :3])
    with pytest.raises(qprr.errors.InputError, match="non-decreasing"):
        animate(platform, t[::-1], xi, tmp_path / "a.gif")
    with pytest.raises(qprr.errors.InputError, match=r"\.gif or \.mp4"):
        animate(platform, t, xi, tmp_path / "a.avi")
    with pytest.raises(qprr.errors.UnknownNameError, match="follow"):
        animate(platform, t, xi, tmp_path / "a.gif", view="orbit")
    with pytest.raises(qprr.errors.InputError, match="fps"):
        animate(platform, t, xi, tmp_path / "a.gif", fps=0)


def test_a_failed_animation_leaves_no_file(platform, tmp_path, monkeypatch):
    t, xi, _ = _run(platform)
    calls, original = [], anim._GifWriter.add

    def boom(self, rgba):
        calls.append(1)
        if len(calls) == 3:
            assert (tmp_path / "a.partial.gif").stat().st_size > 0  # two frames were written
            raise RuntimeError("disk full")
        original(self, rgba)

    monkeypatch.setattr(anim._GifWriter, "add", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        animate(platform, t, xi, tmp_path / "a.gif", **SMALL)
    assert list(tmp_path.iterdir()) == []
