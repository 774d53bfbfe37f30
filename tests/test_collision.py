"""Self-collision model (qprr.analysis.collision): closed forms, the maps' collision-free numbers, the IK's collision-free option."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr.analysis import workspace
from qprr.analysis._common import COLLISION_AUDIT_TOLERANCE, collision_mask, make_grid
from qprr.analysis.collision import CONTACT_MARGIN, DISC_THICKNESS, collision_model, contacts, default_disc_radius
from qprr.analysis.hover import hover
from qprr.errors import InputError
from qprr.ik import IKSolver
from qprr.model import from_model
from qprr.rotors import Rotor, quadrotor, ring, rotors_from_mapping
from qprr.urdf import writer as ug

# A test robot with a closed-form collision set: a flat body box (top at z = H), a yaw joint at height A
# (no geometry), then a pitch joint at the same point carrying a cylinder of radius R and length L along its z.
H, A, R, L, LEAD = 0.02, 0.1, 0.01, 0.2, 0.1


def _test_urdf() -> str:
    box_inertia = (0.01, 0.01, 0.02, 0.0, 0.0, 0.0)
    small = (1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0)
    parts = [
        ug.link("body", ug.inertial(1.5, (0.0, 0.0, 0.0), box_inertia) + ug.box_visual((0.6, 0.6, 2 * H))),
        ug.link("yaw_link", ug.inertial(0.05, (0.0, 0.0, 0.0), small)),
        ug.joint("yaw", "revolute", "body", "yaw_link", (0.0, 0.0, A), (0, 0, 1), (-3.0, 3.0, 5.0, 6.0)),
        ug.link("pitch_link", ug.inertial(0.05, (0.0, 0.0, L / 2), small) + ug.cylinder_visual(R, L, (0.0, 0.0, L / 2))),
        ug.joint("pitch", "revolute", "yaw_link", "pitch_link", (0.0, 0.0, 0.0), (0, 1, 0), (-3.0, 3.0, 5.0, 6.0)),
        ug.link("tip"),
        ug.joint("tip_fixed", "fixed", "pitch_link", "tip", (0.0, 0.0, L)),
    ]
    return ug.robot("pendulum", parts, "tests/test_collision.py")


def _test_platform(radius=0.05):
    rotors = tuple(Rotor(r.position_body, r.axis_body, r.spin, 0.01, 0.0, 10.0, r.name, radius) for r in quadrotor(0.5, kappa=0.01, f_max=10.0))
    return qprr.from_urdf(_test_urdf(), rotors, ee_frame="tip")


def _closed_form_colliding(theta: np.ndarray) -> np.ndarray:
    """The cylinder (axis (sin t, 0, cos t) from z = A) dips below the body top H: its lowest point is
    A + min(0, L cos t) - R |sin t| (the rim of an end cap)."""
    return A + np.minimum(0.0, L * np.cos(theta)) - R * np.abs(np.sin(theta)) < H


@pytest.fixture(scope="module")
def pendulum():
    return _test_platform()


@pytest.fixture(scope="module")
def pendulum_cm(pendulum):
    return collision_model(pendulum)


# ------------------------------------------------------------------------------ the model
def test_pendulum_collision_matches_the_closed_form(pendulum_cm):
    theta = np.linspace(-3.0, 3.0, 2401)
    lowest = A + np.minimum(0.0, L * np.cos(theta)) - R * np.abs(np.sin(theta))
    keep = np.abs(lowest - H) > 1e-9  # off the contact boundary itself
    q_arm = np.column_stack([np.full(theta.size, 0.7), theta])[keep]
    got = pendulum_cm.colliding_arm(q_arm)
    assert np.array_equal(got, _closed_form_colliding(theta[keep]))
    assert got.any() and not got.all()


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR"])
def test_batched_check_answers_as_the_python_loop(name):
    """colliding_batch (Pinocchio's C++ loop, the pair screen on or off) gives colliding_arm's answers configuration
    for configuration, in grid order and shuffled, the configurations near contact included (both start from a
    fresh GeometryData and keep it through the batch)."""
    p = qprr.platforms.resolve(name)
    cm = collision_model(p)
    grid = make_grid(p, 200_000)
    rng = np.random.default_rng(5)
    for q in (grid.configurations(50_000, 58_000), grid.configurations_at(rng.choice(grid.size, 8000, replace=False))):
        ref = cm.colliding_arm(q)
        assert ref.any() and not ref.all()
        assert np.array_equal(cm.colliding_batch(q), ref)
        assert np.array_equal(cm.colliding_batch(q, screen=False), ref)
    with pytest.raises(InputError, match="q_arm"):
        cm.colliding_batch(np.zeros((4, p.n_arm + 1)))
    with pytest.raises(InputError, match="screen"):
        cm.colliding_batch(q, screen="yes")
    with pytest.raises(InputError, match="finite"):
        cm.colliding_batch(np.full((2, p.n_arm), np.nan))
    assert cm.colliding_batch(np.zeros((0, p.n_arm))).shape == (0,)


@pytest.mark.parametrize("name", ["q-prr", "borinot_flying_arm_2"])
def test_screened_check_of_the_default_map_answers_as_every_pair(name, monkeypatch):
    """The default workspace map (10^6 configurations per region, every region): each configuration the coarse-to-fine
    mask sends to the screened colliding_batch gets the answer of checking every pair one configuration at a time
    (colliding_arm), on a sample of 3000 of them, half from the later batches (the cells straddling the collision
    boundary), contacts included; so the map's masks are those of the unscreened check."""
    from qprr.analysis.collision import CollisionModel
    from qprr.analysis.workspace import default_variants

    p = qprr.platforms.resolve(name)
    cm = collision_model(p)
    screened = CollisionModel.colliding_batch
    seen: list[tuple[np.ndarray, np.ndarray]] = []

    def recorded(self, q_arm):
        out = screened(self, q_arm)
        seen.append((np.array(q_arm), out))
        return out

    monkeypatch.setattr(CollisionModel, "colliding_batch", recorded)
    for locked in [{}] + default_variants(p):
        collision_mask(cm, make_grid(p, 1_000_000, locked))
    rng = np.random.default_rng(3)
    Q, got = (np.concatenate(x) for x in zip(*seen[:1]))
    Q2, got2 = (np.concatenate(x) for x in zip(*seen[1:]))
    pick, pick2 = rng.choice(len(Q), 1500, replace=False), rng.choice(len(Q2), 1500, replace=False)
    Q, got = np.concatenate([Q[pick], Q2[pick2]]), np.concatenate([got[pick], got2[pick2]])
    assert got.any() and not got.all()
    np.testing.assert_array_equal(got, cm.colliding_arm(Q))


@pytest.fixture(scope="module")
def two_models(pendulum, pendulum_cm):
    """(platform, collision model) of the pendulum and of the Q-PRR."""
    p = qprr.load()
    return [(pendulum, pendulum_cm), (p, collision_model(p))]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), size=st.integers(1, 400), locked=st.booleans())
def test_screen_never_drops_a_pair_in_contact(two_models, seed, size, locked):
    """On random batches (a random sub-box of the joint limits, a joint locked or not) of the pendulum and the Q-PRR:
    the screen's lower bound never exceeds coal's distance, every pair in contact (and every pair coal finds within
    CONTACT_MARGIN) is among the screen's near pairs, and the screened batch answers as every pair checked."""
    rng = np.random.default_rng(seed)
    p, cm = two_models[seed % 2]
    lo, hi = np.maximum(p.arm_lower, -math.pi), np.minimum(p.arm_upper, math.pi)
    a, b = np.sort(rng.uniform(lo, hi, (2, lo.size)), axis=0)
    Q = rng.uniform(a, b, (size, lo.size))
    if locked:
        k = rng.integers(lo.size)
        Q[:, k] = rng.uniform(a[k], b[k])
    rows, near = cm.screen.near_pairs(Q)
    allowed = np.zeros((size, len(cm.pairs)), dtype=bool)
    allowed[rows] = near
    data = cm.new_data()
    for i in rng.choice(size, min(size, 40), replace=False):
        q = cm.neutral_q.copy()
        q[7:] = Q[i]
        pin.computeDistances(cm.model, data[0], cm.geometry, data[1], q)
        dist = np.array([r.min_distance for r in data[1].distanceResults])
        bound = cm.screen.lower_bounds(Q[i : i + 1], np.zeros(dist.size, dtype=np.int64), np.arange(dist.size))
        assert np.all(bound <= np.maximum(dist, 0.0) + 1e-6)
        assert np.all(allowed[i][dist <= CONTACT_MARGIN])
        assert np.all(allowed[i][contacts(cm.model, cm.geometry, data, q, first=False)])
    np.testing.assert_array_equal(cm.colliding_batch(Q), cm.colliding_arm(Q))


def test_pendulum_distance_is_the_closed_form_gap(pendulum_cm):
    for theta in (1.0, 1.6, 2.0):  # the cylinder above the body top: the gap is the lowest point's height above H
        gap = A + min(0.0, L * math.cos(theta)) - R * abs(math.sin(theta)) - H
        dist, pair = pendulum_cm.min_distance(np.array([0.0, theta]))
        assert dist == pytest.approx(gap, abs=1e-9)
        assert set(pair) == {"body_0", "pitch_link_0"}


def test_pairs_exclude_adjacent_bodies_and_report_them(pendulum_cm):
    names = {g.name for g in pendulum_cm.geometry.geometryObjects}
    assert names == {"body_0", "pitch_link_0", *(f"disc_rotor_{i}" for i in range(1, 5))}
    # the pitch link is two joints from the body: checked against the body and every disc; no pair on one body
    assert {frozenset(p) for p in pendulum_cm.pairs} == {frozenset(("pitch_link_0", n)) for n in names - {"pitch_link_0"}}
    assert pendulum_cm.adjacent == () and pendulum_cm.neutral_contacts == ()


def test_discs_take_the_rotor_radius_and_axis(pendulum_cm, pendulum):
    discs = {g.name: g for g in pendulum_cm.geometry.geometryObjects if g.name.startswith("disc_")}
    for r in pendulum.rotors:
        g = discs[f"disc_{r.name}"]
        assert g.geometry.radius == 0.05 and 2.0 * g.geometry.halfLength == pytest.approx(DISC_THICKNESS, abs=1e-15)
        assert np.allclose(g.placement.rotation[:, 2], r.axis_body, atol=1e-15)
        assert np.allclose(g.placement.translation, r.position_body, atol=1e-15)
    assert all(src == "rotor file" for _, _, src in pendulum_cm.discs)


def test_default_disc_radius_is_half_the_nearest_spacing():
    for n in (4, 6, 8):
        rotors = ring(n, 0.3)
        assert default_disc_radius(rotors) == pytest.approx(0.3 * math.sin(math.pi / n), rel=1e-14)
    coaxial = (Rotor((0.0, 0.0, 0.0)), Rotor((0.0, 0.0, 0.1)), Rotor((0.5, 0.0, 0.0)))
    assert default_disc_radius(coaxial) == pytest.approx(0.25, rel=1e-14)  # the coaxial pair shares a disc
    with pytest.raises(InputError, match="radius"):
        default_disc_radius((Rotor((0.0, 0.0, 0.0)), Rotor((0.0, 0.0, 0.2))))


def test_rotor_file_radius_key():
    desc = {
        "defaults": {"radius": 0.1, "f_max": 10.0},
        "rotor": [{"position": [0.3, 0.0, 0.0], "spin": "cw"}, {"position": [-0.3, 0.0, 0.0], "spin": "ccw", "radius": 0.12}],
    }
    assert [r.radius for r in rotors_from_mapping(desc)] == [0.1, 0.12]
    with pytest.raises(InputError, match="radius"):
        Rotor((0.0, 0.0, 0.0), radius=-0.1)


def test_without_collision_geometry(pendulum):
    bare = from_model(pendulum.model, pendulum.rotors, ee_frame="tip")
    with pytest.raises(InputError, match="no URDF"):
        collision_model(bare)
    r = hover(bare, n_samples=50)
    assert r.collision_free is None and "not checked" in r.collision_note and "not checked" in r.summary()
    with pytest.raises(InputError, match="no URDF"):
        hover(bare, n_samples=50, collision=True)
    with pytest.raises(InputError, match="collision must be"):
        hover(bare, n_samples=50, collision="yes")


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR"])
def test_generated_urdfs_carry_collision_geometry_on_every_arm_link(name):
    p = qprr.platforms.resolve(name)
    cm = collision_model(p)
    moving = {g.parentJoint for g in cm.geometry.geometryObjects}
    assert all(j.joint_id in moving for j in p.arm)
    assert cm.discs == ()  # the propeller discs are in the URDF: none added
    assert cm.pairs and not cm.colliding(p.neutral_q())


# ------------------------------------------------------------------------------ the maps
def test_hover_map_collision_fraction_is_the_closed_form(pendulum):
    r = hover(pendulum, n_samples=3000)
    q = r.grid.configurations()
    expect = ~_closed_form_colliding(q[:, 1])
    assert np.array_equal(r.collision_free, expect)
    assert r.feasible_free_fraction[0] == pytest.approx(float((r.feasible[0] & expect).mean()), abs=0.0)
    assert "collision-free" in r.summary()
    assert hover(pendulum, n_samples=3000, collision=False).collision_free is None


def test_workspace_collision_free_part(pendulum_cm):
    p = qprr.build("HEX-RRR")
    cm = collision_model(p)
    r = workspace(p, n_samples=3000, hover=True)  # below COLLISION_EXACT_BELOW: every configuration checked
    reg = r.regions[0]
    q = reg.grid.configurations()
    assert np.array_equal(reg.collision_free, ~cm.colliding_arm(q))
    assert 0.0 < reg.collision_free.mean() < 1.0
    assert reg.free_measure.measure < reg.measure.measure
    assert reg.free_hover_volume.measure < reg.hover_volume.measure
    assert "collision-free" in r.summary()
    q_prr = workspace(qprr.load("q-prr"), n_samples=3000, hover=False)  # two regions: with and without the slider
    g = q_prr.gain_free[1][0]
    assert g.value == q_prr.regions[0].free_measure.measure / q_prr.regions[1].free_measure.measure and q_prr.gain_free[1][1] is None
    assert "collision-free parts: in B" in q_prr.summary()
    off = workspace(p, n_samples=3000, hover=False, collision=False)
    assert off.regions[0].collision_free is None and off.regions[0].measure.measure == reg.measure.measure


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR"])
def test_coarse_to_fine_mask_against_every_configuration(name):
    p = qprr.platforms.resolve(name)
    cm = collision_model(p)
    grid = make_grid(p, 40_000)
    mask = collision_mask(cm, grid)
    exact = ~cm.colliding_arm(grid.configurations())
    wrong = np.count_nonzero(mask.free != exact)
    assert mask.evaluated < grid.size and mask.audited == 1000
    assert mask.mismatches <= COLLISION_AUDIT_TOLERANCE * mask.audited
    assert wrong <= 0.005 * grid.size  # the audit's promise, measured on the whole grid
    assert "inferred" in mask.describe()


def test_failed_audit_checks_every_configuration(pendulum_cm, monkeypatch):
    import qprr.analysis._common as common

    p = qprr.build("HEX-RRR")
    cm = collision_model(p)
    grid = make_grid(p, 40_000)
    monkeypatch.setattr(common, "COLLISION_AUDIT_TOLERANCE", -1.0)  # any audit fails
    mask = common.collision_mask(cm, grid)
    assert mask.evaluated == grid.size and "every one" in mask.describe()
    assert np.array_equal(mask.free, ~cm.colliding_arm(grid.configurations()))


# ------------------------------------------------------------------------------ the IK
def _colliding_targets(p, cm, n, seed):
    """End-effector placements of colliding arm configurations (base at the origin): targets the plain IK may
    reach in collision."""
    rng = np.random.default_rng(seed)
    data = p.data()
    lo, hi = np.maximum(p.arm_lower, -3.0), np.minimum(p.arm_upper, 3.0)
    out = []
    while len(out) < n:
        qa = rng.uniform(lo, hi)
        if cm.colliding(qa):
            q = p.neutral_q()
            q[7:] = qa
            pin.framesForwardKinematics(p.model, data, q)
            out.append(data.oMf[p.ee_frame].copy())
    return out


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR", "borinot_flying_arm_2"])
@pytest.mark.parametrize("method", ["qp", "dls"])
def test_collision_free_ik_never_returns_a_colliding_success(name, method):
    p = qprr.platforms.resolve(name)
    cm = collision_model(p)
    data = p.data()
    plain, safe = IKSolver(p, method), IKSolver(p, method, {"collision_free": True})
    plain_hits = recovered = successes = 0
    for target in _colliding_targets(p, cm, 15, seed=3):
        r0, r1 = plain.solve(data, target), safe.solve(data, target)
        hit = r0.success and cm.colliding(r0.q)
        plain_hits += hit
        assert not (r1.success and cm.colliding(r1.q))
        if r1.success:
            assert r1.position_error < 1e-6 and r1.orientation_error < 1e-6
            recovered += hit
            successes += 1
        else:  # the only reason to fail a target the plain IK reaches: every answer found collides
            assert r1.status == "collision" and " / " in r1.reason and r0.success, (r1.status, r1.reason)
    assert successes > 0  # the option is exercised: collision-free answers are returned, not only refusals
    if method == "dls" and name != "borinot_flying_arm_2":
        assert plain_hits > 0 and recovered > 0  # the plain IK does end in collision; the restarts find another answer


def test_ik_collision_option_is_checked():
    p = qprr.build("HEX-RRR")
    with pytest.raises(InputError, match="collision_free"):
        IKSolver(p, "qp", {"collision_free": 1})
    with pytest.raises(InputError, match="collision_restarts"):
        IKSolver(p, "qp", {"collision_free": True, "collision_restarts": -1})


# Q-PRR arm configurations (r0 [m], theta2, theta3 [rad]) where coal's GJK alone (collision mode, default guess)
# calls the last link and a propeller disc apart although the link reaches 0.5-2.6 mm into the disc
GJK_MISSES = ((0.007885441985879739, 1.9256624217308995, -1.9942442761016572), (-0.03538405342134774, 1.938090894693676, -1.9833160617986358))


def _sampled_penetration(cm, q, pair_names, rng, n=400000):
    """Deepest point [m] of the first geometry's cylinder inside the second's, by sampling its volume (independent of
    coal); 0 when no sample is inside."""
    data, gdata = cm.model.createData(), pin.GeometryData(cm.geometry)
    pin.updateGeometryPlacements(cm.model, data, cm.geometry, gdata, q)
    ia, ib = (cm.geometry.getGeometryId(name) for name in pair_names)
    A, B = cm.geometry.geometryObjects[ia].geometry, cm.geometry.geometryObjects[ib].geometry
    MA, MB = gdata.oMg[ia], gdata.oMg[ib]
    rho, th = A.radius * np.sqrt(rng.uniform(0, 1, n)), rng.uniform(0, 2 * np.pi, n)
    P = np.column_stack([rho * np.cos(th), rho * np.sin(th), rng.uniform(-A.halfLength, A.halfLength, n)])
    L = (P @ MA.rotation.T + MA.translation - MB.translation) @ MB.rotation
    depth = np.minimum(B.halfLength - np.abs(L[:, 2]), B.radius - np.hypot(L[:, 0], L[:, 1]))
    return float(max(depth.max(), 0.0))


@pytest.mark.parametrize("q_arm", GJK_MISSES)
def test_penetration_that_gjk_misses_is_found(q_arm):
    """Every check (one configuration, the Python loop, the C++ batch, the pairs) finds the contact, and the pair it
    names really interpenetrates: a volume sampling of the link finds points inside the disc."""
    cm = collision_model(qprr.load())
    q = cm.neutral_q.copy()
    q[7:] = q_arm
    assert cm.colliding(q)
    assert cm.colliding_arm(np.array([q_arm]))[0] and cm.colliding_batch(np.array([q_arm]))[0]
    pairs = cm.colliding_pairs(q)
    assert pairs
    assert _sampled_penetration(cm, q, pairs[0], np.random.default_rng(0)) > 1e-4


def test_check_does_not_depend_on_what_was_checked_before():
    """The answers near contact are the configuration's own: checked alone, in a batch, in reverse order, all agree,
    and agree with the sign of the smallest signed distance wherever it is clear of rounding (|d| > 1e-6 m)."""
    p = qprr.load()
    cm = collision_model(p)
    rng = np.random.default_rng(1)
    Q = rng.uniform(p.arm_lower, p.arm_upper, (3000, p.n_arm))
    Q[:2] = GJK_MISSES
    batch = cm.colliding_batch(Q)
    np.testing.assert_array_equal(batch, cm.colliding_batch(Q[::-1])[::-1])
    np.testing.assert_array_equal(batch, [cm.colliding(q) for q in Q])
    dist = np.array([cm.min_distance(q)[0] for q in Q])
    clear = np.abs(dist) > 1e-6
    np.testing.assert_array_equal(batch[clear], dist[clear] < 0.0)


def test_screen_of_an_eight_joint_arm_on_a_dense_batch():
    """A straight joint-space path over the whole box of an 8-revolute arm: the finest screening level has more cells
    than int64 counts (about 1e19); the screened answers are those of checking every pair."""
    p = qprr.build("Q-RRRRRRRR")
    cm = collision_model(p)
    lo, hi = np.maximum(p.arm_lower, -math.pi), np.minimum(p.arm_upper, math.pi)
    Q = lo + (hi - lo) * np.linspace(0.0, 1.0, 20_000)[:, None]
    assert np.array_equal(cm.colliding_batch(Q), cm.colliding_batch(Q, screen=False))
