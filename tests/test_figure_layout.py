"""Layout of the figures, checked on the rendered page (issue 23 item 4, issue 21 item 4).

Each figure is drawn with matplotlib's Agg canvas and measured with its renderer: every text
(titles, axis labels, tick labels, legends) lies inside the page, no two titles overlap, no legend
covers a data point or an image of any axes, every axis label names its unit in brackets or
parentheses (or is dimensionless by name).  Figures: :func:`qprr.viz.plot_result` (the whole page
and every panel alone) on the Q-PRR and on borinot_flying_arm_2 (URDF joint names, revolute joints
only), a platform whose joint names hold mathtext specials, the hover and workspace maps, and a
wheeled figure with a straight-line path.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import qprr
from qprr.analysis import hover, singularity, workspace
from qprr.analysis import plots as analysis_plots
from qprr.scenarios import run
from qprr.viz import new_figure, plot_result
from qprr.viz.plots import DEFAULT_PANELS
from qprr.wheeled import plots as wheeled_plots
from qprr.wheeled.robots import get_robot, tricycle_exercise

UNIT = re.compile(r"\[[^\]]+\]|\([^)]*(m|N|rad|s|kg|%)[^)]*\)")
DIMENSIONLESS = ("log10", "det(J J^T)", "share", "count", "fraction")
"""Axis labels of quantities without a unit, recognised by a word they contain."""
CATEGORICAL = ("controller", "success rate")
"""Whole axis labels without a unit (a category axis, a ratio): matched exactly, so "controller gain" still needs one."""
SLACK = 1.0  # [px] rounding of the renderer's extents


@pytest.fixture(scope="module")
def qprr_run():
    """1.5 s of hover-reach on the Q-PRR: a prismatic and two revolute joints (twin axes in the arm panels)."""
    return run("hover-reach", platform=qprr.load(), duration=1.5, z=1.0)


@pytest.fixture(scope="module")
def borinot_run():
    """1.5 s of hover-reach on borinot_flying_arm_2: joints named by its URDF (flying_arm_2__j_bl_link1, ...)."""
    return run("hover-reach", platform=qprr.load("borinot_flying_arm_2"), duration=1.5)


def render(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def inside(bb, page) -> bool:
    return bb.x0 >= page.x0 - SLACK and bb.x1 <= page.x1 + SLACK and bb.y0 >= page.y0 - SLACK and bb.y1 <= page.y1 + SLACK


def check_layout(fig, what: str) -> None:
    renderer = render(fig)
    page = fig.bbox
    for t in fig.texts + ([fig._suptitle] if fig._suptitle is not None else []):
        assert inside(t.get_window_extent(renderer), page), f"{what}: text {t.get_text()!r} leaves the page"
    for a in fig.axes:  # everything an axes draws: title, labels, the tick labels it shows, its legend
        bb = a.get_tightbbox(renderer)
        assert inside(bb, page), f"{what}: {a.get_title()!r} ({a.get_ylabel()!r}) leaves the page: {bb} outside {page}"
    titles = [a.title for a in fig.axes if a.title.get_text()] + ([fig._suptitle] if fig._suptitle is not None else [])
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in titles]
    for i, (ti, bi) in enumerate(boxes):
        for tj, bj in boxes[i + 1 :]:
            assert not bi.overlaps(bj), f"{what}: titles {ti!r} and {tj!r} overlap"
    for a in fig.axes:
        leg = a.get_legend()
        if leg is not None:
            check_legend(fig, leg.get_window_extent(renderer), what)
        check_units(a, what)


def check_legend(fig, box, what: str) -> None:
    """No data point of any 2-D axes (line vertices, image extents) inside the legend ``box``."""
    for a in fig.axes:
        if getattr(a, "name", "") == "3d":
            continue
        for line in a.get_lines():
            xy = np.column_stack([np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)])
            xy = xy[np.all(np.isfinite(xy), axis=1)]
            if not len(xy):
                continue
            d = line.get_transform().transform(xy)
            inside = (d[:, 0] > box.x0) & (d[:, 0] < box.x1) & (d[:, 1] > box.y0) & (d[:, 1] < box.y1)
            axes_box = a.bbox
            visible = (d[:, 0] >= axes_box.x0) & (d[:, 0] <= axes_box.x1) & (d[:, 1] >= axes_box.y0) & (d[:, 1] <= axes_box.y1)
            assert not np.any(inside & visible), f"{what}: the legend covers data of {a.get_title()!r} ({line.get_label()!r})"
        for im in a.get_images():
            assert not im.get_window_extent().overlaps(box), f"{what}: the legend covers the map of {a.get_title()!r}"


def check_units(a, what: str) -> None:
    labels = [a.get_xlabel(), a.get_ylabel()] + ([a.get_zlabel()] if getattr(a, "name", "") == "3d" else [])
    for lab in labels:
        if lab.strip() and lab.strip() not in CATEGORICAL and not any(w in lab for w in DIMENSIONLESS):
            assert UNIT.search(lab), f"{what}: axis label {lab!r} of {a.get_title()!r} has no unit"


# ============================================================================ simulation pages
def test_page_and_every_panel_alone_on_the_q_prr(qprr_run):
    check_layout(plot_result(qprr_run), "Q-PRR page")
    for name in DEFAULT_PANELS:
        check_layout(plot_result(qprr_run, panels=name), f"Q-PRR panel {name}")


def test_page_and_panels_on_borinot(borinot_run):
    fig = plot_result(borinot_run)
    check_layout(fig, "borinot page")
    arm = next(a for a in fig.axes if a.get_title().startswith("arm joints"))
    assert arm.get_ylabel() == "arm joints [rad]"  # revolute joints: radians, from the platform's joint types
    efforts = next(a for a in fig.axes if a.get_title().startswith("arm efforts"))
    assert efforts.get_ylabel() == "arm efforts [N m]"
    labels = [t.get_text() for t in efforts.get_legend().get_texts()]
    assert labels == [f"$u_\\mu$ ({n})" for n in borinot_run.names[6:]]  # the joint's own name, no raw "u_mu,"
    for name in ("arm", "arm_efforts", "cog"):
        check_layout(plot_result(borinot_run, panels=name), f"borinot panel {name}")


def test_any_joint_name_renders(qprr_run):
    """Joint names holding mathtext specials ($, ^, _, {, \\) render as written, in legends and titles."""
    odd = ("r$0", "theta_2^x", "{elbow}\\")
    res = dataclasses.replace(qprr_run, names=qprr_run.names[:6] + odd)
    fig = plot_result(res, panels=("arm", "arm_efforts", "errors_angle"))
    check_layout(fig, "odd names")  # a mathtext parse error would raise while drawing
    legend_texts = [t.get_text() for a in fig.axes if a.get_legend() for t in a.get_legend().get_texts()]
    assert any("r\\$0" in t for t in legend_texts)


def test_units_follow_the_joint_types(qprr_run):
    fig = plot_result(qprr_run, panels=("arm_efforts",))
    host, twin = fig.axes[0], fig.axes[1]
    assert (host.get_ylabel(), twin.get_ylabel()) == ("forces [N]", "torques [N m]")  # prismatic r0; revolute theta2, theta3
    assert host.get_zorder() > twin.get_zorder()


def test_single_panel_title_fits(qprr_run):
    fig = plot_result(qprr_run, panels="cog")
    check_layout(fig, "cog alone")
    assert fig._suptitle.get_text().count("\n") >= 2  # the RMSE line is wrapped to the page, not clipped


# ============================================================================ the X8 of issue 35: 4 joints, 8 named rotors
@pytest.fixture(scope="module")
def x8_run():
    """tests/robots/x8_arm4/mission.toml (a payload grasped at 2 s, released at 4 s) on the X8, 4.5 s at 2 ms."""
    from tests import x8_robot

    return run("mission", platform=x8_robot.load(), duration=4.5, dt=0.002, mission=str(x8_robot.DIR / "mission.toml"))


def column_of(a, page) -> tuple[float, float]:
    """(left, right) [px] of the columns of the page's grid that the axes ``a`` spans."""
    spec = a.get_subplotspec()
    n, cols = spec.get_gridspec().ncols, spec.colspan
    return page.x0 + page.width * cols.start / n, page.x0 + page.width * cols.stop / n


def check_page(fig, what: str) -> None:
    """:func:`check_layout`, and: every legend within its panel's column of the page (a legend under a panel that is
    wider runs into its neighbour's), no two legends overlapping, no empty axes (each draws some finite data)."""
    check_layout(fig, what)
    renderer = render(fig)
    page = fig.bbox
    boxes = []
    for a in fig.axes:
        leg = a.get_legend()
        if leg is not None:
            bb = leg.get_window_extent(renderer)
            lo, hi = column_of(a, page)
            assert lo - SLACK <= bb.x0 and bb.x1 <= hi + SLACK, f"{what}: the legend of {a.get_title()!r} leaves its column"
            boxes.append((a.get_title(), bb))
        finite = [line for line in a.get_lines() if np.isfinite(np.asarray(line.get_ydata(), float)).any()]
        assert finite or a.collections or a.get_images(), f"{what}: {a.get_title()!r} ({a.get_ylabel()!r}) is empty"
    for i, (ti, bi) in enumerate(boxes):
        for tj, bj in boxes[i + 1 :]:
            assert not bi.overlaps(bj), f"{what}: the legends of {ti!r} and {tj!r} overlap"


def test_x8_page_names_its_rotors_and_cites_no_thesis_equation(x8_run):
    """The X8's page: nothing clipped or empty, the rotor legend in the rotor file's names, and a generic run's titles
    without the thesis's equation numbers ((6.17) for the attitude references, (6.26) for the RMSE)."""
    from tests.x8_robot import ROTOR_NAMES

    assert x8_run.rotor_names == ROTOR_NAMES
    fig = plot_result(x8_run)
    check_page(fig, "X8 page")
    rotors = next(a for a in fig.axes if a.get_title().startswith("rotor thrusts"))
    labels = [t.get_text() for t in rotors.get_legend().get_texts()]
    assert labels[:8] == list(ROTOR_NAMES) and not any(lab.startswith("$f_") for lab in labels)
    titles = [a.get_title() for a in fig.axes] + [fig._suptitle.get_text()]
    assert not any(re.search(r"\([3-6]\.\d+\)", t) for t in titles), titles
    assert "\nRMSE: x " in fig._suptitle.get_text()
    for name in DEFAULT_PANELS:
        if name != "disturbance":
            check_layout(plot_result(x8_run, panels=name), f"X8 panel {name}")


def test_x8_page_with_every_legend_entry_fits(x8_run):
    """The same run as if every command had been clipped (1 N or N m of every generalised force not produced, every tick
    saturated): the longest
    legends a page draws (dotted commands on the thrust, torque and effort panels, the 8 rotor names, the bounds, the
    saturation marks) wrap to their column instead of running into their neighbours or off the page."""
    from qprr.actuation import AllocationFlag

    clipped = dataclasses.replace(x8_run, unallocated=x8_run.unallocated + 1.0, flags=np.full_like(x8_run.flags, int(AllocationFlag.ROTOR_SATURATED)))
    fig = plot_result(clipped)
    check_page(fig, "X8 page, every command clipped")
    efforts = next(a for a in fig.axes if a.get_title().startswith("arm efforts") and a.get_legend() is not None)
    labels = [t.get_text() for t in efforts.get_legend().get_texts()]
    assert labels.count("commanded (where not produced)") == 1 and len(labels) == 5  # four joints, one explanation


def test_thesis_run_keeps_its_equation_numbers(qprr_run):
    """hover-reach on the Q-PRR is a generic run too; a result named after a thesis scenario cites (6.17) and (6.26)."""
    fig = plot_result(dataclasses.replace(qprr_run, scenario="static-idc"), panels=("attitude", "rotors"))
    assert fig.axes[0].get_title().startswith("attitude (roll, pitch references from (6.17))")
    assert "RMSE (6.26): " in fig._suptitle.get_text()
    generic = plot_result(qprr_run, panels=("attitude",))
    assert generic.axes[0].get_title() == "attitude (roll, pitch references from the controller)"


# ============================================================================ maps and wheeled
def test_hover_and_workspace_maps():
    platform = qprr.load()
    check_layout(analysis_plots.hover_figure(hover(platform, n_samples=1500)), "hover map")
    check_layout(analysis_plots.workspace_figure(workspace(platform, n_samples=2000)), "workspace map")
    check_layout(analysis_plots.singularity_figure(singularity(platform, n_samples=2000)), "singularity map")  # joints in rad / m


def test_hover_map_constant_field_and_yes_no_map():
    fig = analysis_plots.hover_figure(hover(qprr.load(), n_samples=1500))
    render(fig)
    roll = next(a for a in fig.axes if "roll" in a.get_title())
    assert "constant" in roll.get_legend().get_texts()[0].get_text()  # one colour, its value named: not a grey "no data"
    yes_no = next(a for a in fig.axes if a.get_title().startswith("where hovering"))
    assert [t.get_text().split(" (")[0] for t in yes_no.get_legend().get_texts()] == ["hover possible", "impossible"]
    assert not any(a.get_ylabel().startswith("hover-feasible") for a in fig.axes)  # no continuous colour bar


def test_wheeled_straight_line_shows_the_robot():
    res = tricycle_exercise("b", "rear", duration=10.0)
    model = get_robot("tricycle-rear", D=0.3)
    fig = new_figure((9, 4))
    axs = fig.subplots(1, 2)
    wheeled_plots.plot_path(axs[0], res, model, n_robots=3)
    wheeled_plots.plot_states(axs[1], res)
    check_layout(fig, "wheeled")
    labels = [t.get_text() for t in axs[0].get_legend().get_texts()]
    assert any(lab.startswith("robot, drawn x") for lab in labels)  # enlarged, and says so
    assert {"fixed wheel", "centred steerable wheel"} <= set(labels)


# ============================================================================ campaign reports
@pytest.fixture(scope="module")
def borinot_campaign(tmp_path_factory):
    """A tiny campaign on borinot_flying_arm_2, whose arm columns are long (``rmse_flying_arm_2__j_link1_link2``)."""
    from qprr.campaign import CampaignSpec, run_campaign

    spec = CampaignSpec.from_mapping(
        {
            "name": "borinot-layout",
            "scenario": "hover-reach",
            "platform": "borinot_flying_arm_2",
            "seed": 3,
            "samples": 2,
            "options": {"duration": 0.1},
            "grid": {"controller": ["idc", "mfc"], "z": [1.0, 1.5], "reach_fraction": [0.3, 0.6]},
            "random": {"model.mass": {"dist": "uniform", "low": 0.9, "high": 1.1}},
        }
    )
    return run_campaign(spec, tmp_path_factory.mktemp("campaign") / "b.csv", backend="inline", progress=False).results


def test_campaign_report_figures_with_long_column_names(borinot_campaign):
    """Every report figure on the page: titles naming the campaign, its platform and a long column are wrapped, not cut."""
    from qprr.campaign import report as rep

    res = borinot_campaign
    long = "rmse_flying_arm_2__j_link1_link2"
    figs = {
        "box": rep.box_plot(res, long, None),
        "success": rep.success_curve(res, "model.mass", None),
        "curve": rep.metric_curve(res, "z", long, None),
        "scatter": rep.scatter_plot(res, "model.mass", long, None),
        "heat success": rep.heat_map(res, "z", "reach_fraction", None),
        "heat metric": rep.heat_map(res, "z", "reach_fraction", None, metric=long),
    }
    for what, fig in figs.items():
        check_layout(fig, f"campaign {what}")
        titles = " ".join(a.get_title() for a in fig.axes) + " ".join(t.get_text() for t in fig.texts)
        assert "borinot_flying_arm_2" in titles.replace("\n", ""), what
    box_title = figs["box"].axes[0].get_title()
    assert "\n" in box_title and box_title.replace("\n", " ").replace("_ ", "_") == (
        f"borinot-layout on borinot_flying_arm_2: {long} per controller (completed runs)"
    )  # wrapped at spaces (and, for a word too long for the page, after underscores): nothing lost


def test_fit_texts_wraps_a_long_word_after_its_underscores():
    from qprr.viz import fit_texts

    fig = new_figure((2.5, 2.0))
    ax = fig.subplots()
    ax.set_title("rmse_a_very_long_shoulder_pitch_joint_name_of_some_robot")
    ax.set_ylabel("median rmse_a_very_long_shoulder_pitch_joint_name [rad]")
    fit_texts(fig)
    check_layout(fig, "narrow page")
    lines = ax.get_title().split("\n")
    assert len(lines) > 1 and all(line.endswith("_") for line in lines[:-1])
    assert "".join(lines) == "rmse_a_very_long_shoulder_pitch_joint_name_of_some_robot"


# ============================================================================ the viewer's camera
@pytest.mark.parametrize("name", ["q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5"])
def test_viewer_camera_frames_any_platform(name):
    """Every point of the robot (rotor discs, arm, end effector) lies inside the initial camera's cone, with room to spare."""
    viewer = pytest.importorskip("qprr.viz.viewer", reason="pip install 'qprr[viewer]'", exc_type=qprr.errors.MissingDependencyError)
    from qprr.charts import xi_to_q
    from qprr.viz.geometry import rotor_radius
    from qprr.viz.scene import robot_pose

    platform = qprr.load(name)
    xi = np.zeros(platform.n_xi)
    xi[2] = 1.0
    pose = robot_pose(platform, platform.data(), xi_to_q(xi))
    look_at, position = viewer.camera_framing(pose, rotor_radius(platform))
    axis = (look_at - position) / np.linalg.norm(look_at - position)
    r = rotor_radius(platform)
    pts = np.vstack(
        [pose.rotor_world + r * s for s in np.eye(3)]
        + [pose.rotor_world - r * s for s in np.eye(3)]
        + [pose.arm_world, pose.ee_world[None, :], pose.com_world[None, :]]
    )
    rel = pts - position
    angle = np.arccos(np.clip(rel @ axis / np.linalg.norm(rel, axis=1), -1.0, 1.0))
    assert 0.3 * viewer.CAMERA_FOV / 2 < angle.max() < 0.9 * viewer.CAMERA_FOV / 2, (name, np.degrees(angle.max()))  # fills the view
    centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0)) - position
    assert np.arccos(min(1.0, centre @ axis / np.linalg.norm(centre))) < np.radians(1.0)  # the box's centre in the middle of the view
    assert np.linalg.norm(look_at - pose.p_base_world) < 2.0 * np.ptp(pts, axis=0).max()  # aimed at the robot, not the origin


def test_viewer_camera_frames_a_run_path():
    """With a run's path (extra points far from the robot's start) every path point is inside the camera's cone too."""
    viewer = pytest.importorskip("qprr.viz.viewer", reason="pip install 'qprr[viewer]'", exc_type=qprr.errors.MissingDependencyError)
    from qprr.charts import xi_to_q
    from qprr.viz.geometry import rotor_radius
    from qprr.viz.scene import robot_pose

    platform = qprr.load("borinot_flying_arm_2")
    xi = np.zeros(platform.n_xi)
    pose = robot_pose(platform, platform.data(), xi_to_q(xi))
    path = np.column_stack([np.linspace(0.0, 3.0, 50), np.linspace(0.0, -1.0, 50), np.linspace(0.0, 2.0, 50)])
    look_at, position = viewer.camera_framing(pose, rotor_radius(platform), extra_world=path)
    axis = (look_at - position) / np.linalg.norm(look_at - position)
    rel = np.vstack([path, pose.ee_world[None, :]]) - position
    angle = np.arccos(np.clip(rel @ axis / np.linalg.norm(rel, axis=1), -1.0, 1.0))
    assert angle.max() < 0.9 * viewer.CAMERA_FOV / 2
