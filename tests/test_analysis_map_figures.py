"""The design maps' figures show what was computed: no empty panel, no holes from the sampling lattice, the
collision-free region beside the whole one; on the Q-PRR and on a robot from files (examples/my_platform: a yaw
joint, so 3-D maps, and no slider)."""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np
import pytest
from scipy import ndimage

import qprr
from qprr.analysis import plots
from qprr.analysis.capacity import capacity
from qprr.analysis.cog import balance, cog_regions
from qprr.analysis.voxels import MAP_GAP_FRACTION, display_occupancy, map_cell
from qprr.analysis.workspace import workspace

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "my_platform"


@pytest.fixture(scope="module")
def own_robot():
    return qprr.from_urdf(EXAMPLE / "quad_rrr.urdf", rotors=EXAMPLE / "quad_rrr.rotors.toml", ee_frame="gripper")


def _pinholes(filled: np.ndarray) -> int:
    """Empty cells between two filled ones along x or along y (pinholes, lattice stripes), and filled cells with no
    filled face neighbour (dots)."""
    f = np.pad(filled, 1)
    gap = (f[:-2, 1:-1] & f[2:, 1:-1]) | (f[1:-1, :-2] & f[1:-1, 2:])
    alone = ~(f[:-2, 1:-1] | f[2:, 1:-1] | f[1:-1, :-2] | f[1:-1, 2:])
    return int(np.sum(~filled & gap) + np.sum(filled & alone))


def _image_holes(ax) -> tuple[int, int]:
    """(lattice holes, filled cells) of the first image drawn in ``ax``."""
    arr = np.ma.filled(np.ma.asarray(ax.get_images()[0].get_array(), dtype=float), np.nan)
    filled = np.isfinite(arr)
    return _pinholes(filled), int(filled.sum())


def test_capacity_map_has_no_lattice_holes_on_a_3d_workspace(own_robot):
    """At 2e4 samples of a 3-joint arm with a yaw joint the old map (cells of extent / 120, binned in 3-D, then the
    largest over y) was a checkerboard; the cells now come from the sample density, on the drawn plane."""
    res = capacity(own_robot, n_samples=20_000)
    fig = plots.capacity_figure(res)
    maps = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    assert len(maps) == 2
    for ax in maps:
        holes, cells = _image_holes(ax)
        assert cells > 150 and holes <= MAP_GAP_FRACTION * cells, (ax.get_title(), holes, cells)
    # the drawn axes are B's: the end effector reaches z_B = -0.55 m (straight down) and never above the body's 0.2 m
    im = fig.axes[0].get_images()[0]
    x0, x1, z0, z1 = im.get_extent()
    assert z0 <= res.ee_body[:, 2].min() and z1 >= res.ee_body[:, 2].max() and z0 > -0.7
    # the result's own 3-D cells are no finer than its samples fill
    cells3 = res.map_limiting >= 0
    structure = ndimage.generate_binary_structure(3, 1).astype(int)
    nb = ndimage.convolve(cells3.astype(int), structure, mode="constant") - cells3
    assert np.sum(cells3 & (nb == 0)) <= MAP_GAP_FRACTION * cells3.sum()


def test_map_cell_is_coarser_only_where_the_samples_are_sparse():
    """A dense square of points keeps extent / cells_across; a sparse lattice gets a cell it fills."""
    dense = np.random.default_rng(0).uniform(0.0, 1.0, (200_000, 2))
    ext = float((dense.max(axis=0) - dense.min(axis=0)).max())
    assert map_cell(dense, 100) == ext / 100
    lattice = np.stack(np.meshgrid(np.linspace(0, 1, 11), np.linspace(0, 1, 11)), axis=-1).reshape(-1, 2)
    h = map_cell(lattice, 100)
    assert h > 0.08  # about the lattice's spacing 0.1: finer cells leave stripes of empty cells between its points
    occ, _, _ = display_occupancy(lattice)
    assert _pinholes(occ) == 0


def test_hover_section_of_a_yaw_arm_is_filled_not_dots(own_robot):
    """The hover profile (rho, z) of an arm whose first joint turns about z repeats each point once per yaw value: the
    section is drawn on cells its distinct points fill (it was a few dots)."""
    res = workspace(own_robot, n_samples=100_000)
    r = res.regions[0]
    occ, _, h = r.hover_occupancy
    assert _pinholes(occ) <= 1e-3 * occ.sum() + 1
    # the figure draws the finer of the samples' cells and the cells the volume counted (filled by construction)
    ax = plots.plot_hover_workspace(res)
    drawn = [np.isfinite(np.ma.filled(np.ma.asarray(im.get_array(), dtype=float), np.nan)) for im in ax.get_images()]
    assert sum(int(d.sum()) for d in drawn) > 100
    assert all(_pinholes(d) <= 1e-3 * d.sum() + 1 for d in drawn)


def test_cog_figure_has_no_empty_panel_and_says_why_one_is_left_out(own_robot):
    """No slider: the CoG is on the thrust axis on a set without area (a few grid points), so the panel of balanced
    end-effector positions is left out and the figure says why; the offset map is over the end effector's cells."""
    res = cog_regions(own_robot, n_samples=20_000, payload_masses=(0.0, 0.5))
    bal = balance(own_robot, n_samples=20_000)
    assert bal.slider is None and bal.balanced_measure is None
    fig = plots.cog_figure(res, bal)
    axes = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    assert len(axes) == 2 and all(a.has_data() for a in axes)
    assert {a.get_subplotspec().get_geometry()[:2] for a in axes} == {(1, 2)}  # no blank slot in the grid
    assert "not drawn" in fig._supxlabel.get_text() and "no slider" in fig._supxlabel.get_text()
    offset = axes[1]
    holes, cells = _image_holes(offset)
    assert cells > 100 and holes <= MAP_GAP_FRACTION * cells
    for a in axes:  # regions drawn as filled cells, not as scattered points
        assert a.get_images() and not any(len(c.get_offsets()) for c in a.collections)


def test_cog_figure_of_the_q_prr_keeps_its_four_panels():
    p = qprr.load("q-prr")
    fig = plots.cog_figure(cog_regions(p, n_samples=20_000, payload_masses=(0.0, 0.5)), balance(p, n_samples=20_000))
    axes = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    assert len(axes) == 4 and all(a.has_data() for a in axes)
    assert fig._supxlabel is None
    labels = [t.get_text() for t in axes[3].get_legend().get_texts()]
    assert any(lab.startswith("CoG balanced:") and "% of the workspace" in lab for lab in labels)


def test_workspace_figure_draws_the_collision_free_region_beside_the_whole_one():
    """The Q-PRR's URDF has collision geometry: its regions in B and the hover section each show the whole region and
    its collision-free part, with both measures in the legend."""
    res = workspace(qprr.load("q-prr"), n_samples=20_000)
    assert res.regions[0].collision_free is not None
    fig = plots.workspace_figure(res)
    titled = {a.get_title(): a for a in fig.axes}
    for key in ("(a) all joints free", "(b) r0 locked at 0", "hover workspace: section through the yaw axis"):
        ax = titled[key]
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any("collision-free" in t and "±" in t for t in texts), (key, texts)
        images = ax.get_images()  # the whole region and its collision-free part (each as two halves: counted cells)
        assert len(images) in (2, 4, 8)
        step = len(images) // (2 if key.startswith("(") else 4)
        whole = np.isfinite(np.ma.filled(np.ma.asarray(images[0].get_array(), dtype=float), np.nan))
        free = np.isfinite(np.ma.filled(np.ma.asarray(images[step].get_array(), dtype=float), np.nan))
        assert whole.shape == free.shape and np.all(whole[free]) and free.sum() < whole.sum()
