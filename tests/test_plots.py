"""Figures (qprr.viz.plots): panels on their own or in your Axes, figure numbers per scenario, units, robust limits.

Figures are drawn with matplotlib's object API (no pyplot), headless.
"""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr.errors import InputError, UnknownNameError
from qprr.scenarios import run
from qprr.viz import new_figure, plot_result
from qprr.viz.plots import DEFAULT_PANELS, PANELS, applied_forces, pretty, robust_limits

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def res():
    """3 s of hover-reach on the Q-PRR: climb, arm moving (every panel has something to show)."""
    return run("hover-reach", platform=qprr.load(), duration=3.0, z=1.0)


def time_axes(fig):
    return [a for a in fig.axes if getattr(a, "name", "") != "3d"]


def test_page_has_units_on_every_axis(res, tmp_path):
    fig = plot_result(res)
    assert len(time_axes(fig)) >= len(DEFAULT_PANELS) - 2  # the 3-D panel; no disturbance in this run
    for a in fig.axes:
        if getattr(a, "name", "") == "3d":
            labels = (a.get_xlabel(), a.get_ylabel(), a.get_zlabel())
        else:
            labels = (a.get_ylabel(),)
        for lab in labels:
            assert re.search(r"\[(m|mm|rad|N|N m|kg|s)\]", lab), (a.get_title(), lab)
    for a in fig.axes:  # twin axes share the host's x axis: only hosts carry the time label
        if getattr(a, "name", "") != "3d" and a.get_title():
            assert a.get_xlabel().startswith("t [s]")
    path = plot_result(res, tmp_path / "page.png")
    assert path == tmp_path / "page.png" and path.read_bytes()[:4] == b"\x89PNG"


def test_angles_in_radians_lengths_in_metres_or_millimetres(res):
    """One angle unit in every output (docs/guide.md): radians, as the CLI prints them."""
    fig = plot_result(res, panels=("attitude", "arm"))
    att, arm = fig.axes[0], fig.axes[1]
    assert att.get_ylabel() == "attitude [rad]"
    theta = next(line for line in att.get_lines() if line.get_label() == r"$\theta$")
    assert np.array_equal(theta.get_ydata(), res.xi[:, 4])
    # the Q-PRR's arm: a prismatic joint (mm, |r0| < 0.1 m) and two revolute ones (rad) on a labelled twin axis
    twins = [a for a in fig.axes[2:]]
    assert arm.get_ylabel() == "lengths [mm]" and twins and twins[0].get_ylabel() == "angles [rad]"
    assert arm.get_zorder() > twins[0].get_zorder()  # the lengths (r0) are drawn above the angles, never hidden
    r0 = next(line for line in arm.get_lines() if line.get_label().startswith("$r_{0}$"))
    assert np.allclose(r0.get_ydata(), 1e3 * res.xi[:, 6], rtol=0, atol=1e-15)


def test_references_are_drawn_above_the_measured_curves(res):
    fig = plot_result(res, panels="position")
    lines = fig.axes[0].get_lines()
    refs = [line for line in lines if line.get_linestyle() != "-" and line.get_color() == "k"]
    measured = [line for line in lines if line.get_linestyle() == "-" and line.get_label().startswith("$")]
    assert len(refs) == 3 and len(measured) == 3
    assert min(r.get_zorder() for r in refs) > max(m.get_zorder() for m in measured)
    assert [line.get_label() for line in refs].count("reference") == 1  # one legend entry


def test_single_panels_into_your_axes(res):
    fig = new_figure((8, 3))
    a1 = fig.add_subplot(1, 2, 1)
    a2 = fig.add_subplot(1, 2, 2, projection="3d")
    out = plot_result(res, panels=("cog", "path"), ax=(a1, a2))
    assert out is fig
    assert a1.get_ylabel() == "CoG offset in B [mm]"
    xcm = a1.get_lines()[0]
    assert np.array_equal(xcm.get_ydata(), 1e3 * res.x_cm[:, 0])
    with pytest.raises(InputError, match="3d"):
        plot_result(res, panels="path", ax=a1)
    with pytest.raises(InputError, match="2 Axes"):
        plot_result(res, panels="cog", ax=(a1, a2))
    with pytest.raises(InputError, match="not both"):
        plot_result(res, "x.png", panels="cog", ax=a1)
    with pytest.raises(UnknownNameError, match="cog"):
        plot_result(res, panels="x_cm")


def titles(fig) -> list[str]:
    return [a.get_title() for a in fig.axes if a.get_title()]


def test_figure_numbers_come_from_the_scenario(res):
    custom = plot_result(dataclasses.replace(res, scenario="custom"), panels=("position", "path"))
    assert not any("Fig." in t for t in titles(custom))
    static = titles(plot_result(dataclasses.replace(res, scenario="static-idc"), panels=("position", "path")))
    assert static == ["position of B (Fig. 6.7)", "3-D path of B (Fig. 6.13)"]
    spiral = titles(plot_result(dataclasses.replace(res, scenario="spiral"), panels=("position", "path", "thrust")))
    assert spiral == ["position of B (Fig. 6.15)", "3-D path of B (Fig. 6.14)", "thrust force $u_{f_b}$"]
    for name, fig_no in (("noise", "6.24"), ("pulses", "6.29"), ("dynamic-bsg", "6.37")):
        t = titles(plot_result(dataclasses.replace(res, scenario=name), panels="position"))
        assert t == [f"position of B (Fig. {fig_no})"], name
    none = titles(plot_result(dataclasses.replace(res, scenario="static-idc"), panels="position", figures={}))
    assert none == ["position of B"]


def test_robust_limits_ignore_short_spikes_and_mark_them():
    t = np.linspace(0.0, 30.0, 30001)
    y = np.sin(t)
    y[15000:15003] = 1000.0  # a 3 ms spike
    fig = new_figure()
    ax = fig.add_subplot()
    ax.plot(t, y)
    lo, hi = robust_limits(ax, [y], min_span=1e-3, t=t)
    assert -1.3 < lo < -1.0 and 1.0 < hi < 1.3
    assert any("clipped spike (peak |1e+03|)" == line.get_label() for line in ax.get_lines())
    # no spike: the whole curve is inside, nothing marked
    fig2 = new_figure()
    ax2 = fig2.add_subplot()
    lo, hi = robust_limits(ax2, [np.sin(t)], min_span=1e-3, t=t)
    assert lo < -1.0 and hi > 1.0 and not any("clipped" in line.get_label() for line in ax2.get_lines())
    # a flat curve is shown flat over the minimum span, not as rounding noise
    lo, hi = robust_limits(ax2, [1e-12 * np.sin(t)], min_span=0.01)
    assert hi - lo == pytest.approx(0.01)


def test_small_motion_path_in_millimetres_with_equal_axes(res):
    moved = dataclasses.replace(res, xi=res.xi.copy(), xi_d=res.xi_d.copy())
    base = np.array([0.3, -0.2, 1.5])
    wiggle = 1e-3 * np.c_[np.sin(res.t), np.cos(res.t) - 1.0, 0.5 * res.t / res.t[-1]]
    moved.xi[:, 0:3] = base + wiggle
    moved.xi_d[:, 0:3] = base
    fig = plot_result(moved, panels="path")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x - x0 [mm]" and ax.get_zlabel() == "z - z0 [mm]"
    spans = [np.diff(lim)[0] for lim in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
    assert np.allclose(spans, spans[0]) and 1.0 < spans[0] < 3.0  # equal axes, a few millimetres
    text = " ".join(t.get_text() for t in ax.texts)
    assert "(0.300, -0.200, 1.500) m" in text


def test_applied_forces_are_s_transpose_n_f(res):
    """The force panels show S^T N f (what the rotors and joints produced), from the logs, two ways."""
    from qprr.charts import euler_to_rotation_batch, force_to_xi_batch

    p = qprr.load()
    tau = np.hstack([res.f @ np.asarray(p.rotor_matrix).T, res.arm_effort])
    direct = force_to_xi_batch(euler_to_rotation_batch(res.xi[:, 3:6]), res.xi, tau)
    assert np.max(np.abs(applied_forces(res) - direct)) < 1e-10 * max(1.0, np.max(np.abs(direct)))


def test_pretty_names():
    assert pretty("theta2") == r"$\theta_{2}$" and pretty("r0") == "$r_{0}$" and pretty("phi") == r"$\phi$"
    assert pretty("flying_arm_2__j_bl_link1") == "flying_arm_2__j_bl_link1"
    assert set(DEFAULT_PANELS) <= set(PANELS)


def test_sec_6_4_figures_share_the_style(tmp_path):
    from qprr.thesis.scenarios import plot_impedance, plot_payload_drop

    pay = run("payload-drop", mission="hover", duration=1.0, release_time=0.5)
    path = plot_payload_drop(pay, tmp_path / "payload.png")
    assert path.is_file()
    imp = run("impedance", duration=1.0, t_off=0.5)
    assert plot_impedance(imp, tmp_path / "imp.png").is_file()
    fig = plot_result(pay, panels=("attitude", "thrust"))
    assert titles(fig) == ["attitude (roll, pitch references from (6.17)) (Fig. 6.49)", "thrust force $u_{f_b}$ (Fig. 6.51a)"]


def test_library_never_selects_a_backend_nor_imports_pyplot(tmp_path):
    code = (
        "import sys, qprr, qprr.viz, qprr.thesis.scenarios\n"
        "from qprr.scenarios import run\n"
        "r = run('hover-reach', duration=0.5)\n"
        "qprr.viz.plot_result(r, sys.argv[1])\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'\n"
    )
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / "f.png")], env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    for f in (ROOT / "qprr").rglob("*.py"):
        text = f.read_text()
        assert "matplotlib.use(" not in text and "import matplotlib.pyplot" not in text, f
