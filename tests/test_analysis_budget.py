"""The sample count of a map chosen from a time budget (qprr.analysis.budget), driven by a fake clock: no test reads
a real one.  The fake clock advances only when a (fake or real) map runs, by a cost model the test knows, so the
choice can be checked against the count that model allows."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qprr.analysis import budget as bud
from qprr.analysis._common import make_grid
from qprr.analysis.budget import CostModel, Pilot, SampleChoice, choose_samples
from qprr.errors import InputError


@pytest.fixture(scope="module")
def qprr_platform():
    import qprr

    return qprr.load("q-prr")


class FakeClock:
    """A clock that reads ``now`` [s] and moves only when told."""

    def __init__(self) -> None:
        self.now = 0.0
        self.readings = 0

    def __call__(self) -> float:
        self.readings += 1
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += seconds


def fake_map(clock: FakeClock, overhead: float, per_sample: float, work=lambda n: n):
    """A map whose run at count n takes overhead + per_sample * work(n) seconds of the fake clock; returns (run, calls)."""
    calls = []

    def run(n: int):
        calls.append(n)
        clock.advance(overhead + per_sample * work(n))
        return ("result at", n)

    return run, calls


def expected_count(budget: float, pilots: tuple[Pilot, ...], overhead: float, per_sample: float) -> int:
    """The largest n (work(n) = n) whose exact cost fits in SAFETY times the budget left by the pilots."""
    left = bud.SAFETY * (budget - sum(p.seconds for p in pilots))
    return int(math.floor((left - overhead) / per_sample))


@pytest.mark.parametrize(
    "overhead, per_sample, budget", [(0.3, 2e-5, 10.0), (0.05, 1e-6, 10.0), (0.05, 3e-6, 10.0), (1.0, 1e-4, 30.0), (0.0, 5e-6, 2.0)]
)
def test_an_affine_cost_is_recovered_and_the_largest_count_that_fits_is_chosen(overhead, per_sample, budget):
    clock = FakeClock()
    run, calls = fake_map(clock, overhead, per_sample)
    choice, result = choose_samples(run, lambda n: n, budget, clock)
    assert result is None  # the map is still to be run at the chosen count
    assert choice.model.overhead == pytest.approx(overhead, abs=1e-9)
    assert choice.model.per_sample == pytest.approx(per_sample, rel=1e-9)
    n = min(expected_count(budget, choice.pilots, overhead, per_sample), bud.MAX_SAMPLES)
    assert abs(choice.n_samples - n) <= 1
    assert choice.predicted <= bud.SAFETY * (budget - choice.pilot_seconds) + 1e-9
    # pilots and the chosen map together within the budget, and the pilots a small part of it
    assert choice.pilot_seconds + overhead + per_sample * choice.n_samples <= budget
    assert choice.pilot_seconds <= bud.PILOT_CAP * budget + overhead + per_sample * calls[-1]
    # pilot counts: PILOT_FIRST growing by PILOT_GROWTH; the clock read twice per pilot
    assert calls == [bud.PILOT_FIRST * bud.PILOT_GROWTH**k for k in range(len(calls))]
    assert clock.readings == 2 * len(calls)


def test_the_count_scales_with_the_budget_and_inversely_with_the_cost():
    """n = (SAFETY (budget - pilots) - overhead) / per_sample: twice the cost per configuration, half the count; a
    budget whose usable part doubles, twice the count."""
    counts = {}
    for per_sample in (1e-5, 2e-5):
        for budget in (10.0, 20.0):
            clock = FakeClock()
            run, _ = fake_map(clock, 0.0, per_sample)
            choice, _ = choose_samples(run, lambda n: n, budget, clock)
            counts[per_sample, budget] = (choice.n_samples, bud.SAFETY * (budget - choice.pilot_seconds))
    for budget in (10.0, 20.0):
        (n1, left1), (n2, left2) = counts[1e-5, budget], counts[2e-5, budget]
        assert n1 / n2 == pytest.approx(2.0 * left1 / left2, rel=1e-4)
    (na, la), (nb, lb) = counts[1e-5, 10.0], counts[1e-5, 20.0]
    assert nb / na == pytest.approx(lb / la, rel=1e-4)
    assert nb > 1.6 * na  # the pilots take a smaller share of the larger budget: more than proportional is not asked


def test_grid_values_per_joint_follow_the_arm_dimension(qprr_platform):
    """The same budget and cost per configuration on a 3-joint and a 5-joint arm: about the same number of
    configurations, spread as its cube root over 3 joints and its fifth root over 5 (the balanced grid)."""
    import qprr

    arms = {3: qprr_platform, 5: qprr.load("hextilt_flying_arm_5")}
    for k, platform in arms.items():
        work = lambda n, p=platform: make_grid(p, n, None, None).size  # noqa: E731
        clock = FakeClock()
        run, _ = fake_map(clock, 0.1, 1e-5, work)
        choice, _ = choose_samples(run, work, 10.0, clock)
        shape = make_grid(platform, choice.n_samples).shape
        assert int(np.prod(shape)) == choice.work
        assert 0.1 + 1e-5 * choice.work <= bud.SAFETY * (10.0 - choice.pilot_seconds) + 1e-9
        # the next larger grid would not fit: the choice is the largest (within the grid's odd-count steps)
        assert 0.1 + 1e-5 * work(choice.n_samples + 1) > bud.SAFETY * (10.0 - choice.pilot_seconds) or choice.n_samples == bud.MAX_SAMPLES
        assert len(shape) == k
        geo = float(np.exp(np.mean(np.log(shape))))
        assert geo == pytest.approx(choice.work ** (1.0 / k), rel=1e-9)
        assert min(shape) >= 3


def test_noisy_pilots_fall_back_to_the_last_pilots_cost_per_configuration():
    """A second pilot faster than the first (load, caches) gives no usable line: the last pilot's t / w, no overhead."""
    pilots = (Pilot(256, 256, 0.8), Pilot(1024, 1024, 0.5))
    model = CostModel.fit(pilots)
    assert model == CostModel(0.0, 0.5 / 1024)
    assert CostModel.fit((Pilot(256, 256, 0.8),)) == CostModel(0.0, 0.8 / 256)
    assert CostModel.fit((Pilot(256, 300, 0.1), Pilot(1024, 1300, 0.3))) == CostModel(pytest.approx(0.04), pytest.approx(2e-4))
    # a slope from two nearly equal times (noise, or a fixed cost that dominates) is not trusted
    assert CostModel.fit((Pilot(256, 300, 0.30), Pilot(1024, 1300, 0.31))) == CostModel(0.0, 0.31 / 1300)


def test_a_pilot_that_spends_the_budget_is_the_map():
    clock = FakeClock()
    run, calls = fake_map(clock, 0.0, 1.0)  # 256 s for the first pilot
    choice, result = choose_samples(run, lambda n: n, 10.0, clock)
    assert calls == [bud.PILOT_FIRST] and result == ("result at", bud.PILOT_FIRST)
    assert choice.n_samples == bud.PILOT_FIRST and "the last pilot is the map" in choice.note


def test_a_cheap_map_stops_at_the_memory_cap():
    clock = FakeClock()
    run, _ = fake_map(clock, 0.01, 1e-12)
    choice, _ = choose_samples(run, lambda n: n, 10.0, clock)
    assert choice.n_samples == bud.MAX_SAMPLES and "capped" in choice.note


def test_budget_and_clock_are_checked():
    with pytest.raises(InputError, match="budget"):
        choose_samples(lambda n: None, lambda n: n, -1.0, FakeClock())
    with pytest.raises(InputError, match="budget"):
        choose_samples(lambda n: None, lambda n: n, None, FakeClock())
    with pytest.raises(InputError, match="clock"):
        choose_samples(lambda n: None, lambda n: n, 1.0, 3.0)
    from qprr.analysis.workspace import WorkspaceOptions

    with pytest.raises(InputError, match="budget"):
        WorkspaceOptions(budget=0.0)
    with pytest.raises(InputError, match="clock"):
        WorkspaceOptions(budget=1.0, clock="now")


def _largest_work(choice: SampleChoice, most: float) -> int:
    """The work of the chosen count, checked to be at most ``most`` configurations (the count itself came from the
    bisection over the grid's work)."""
    assert choice.work <= most + 1e-9
    return choice.work


class StepClock(FakeClock):
    """A fake clock for a real map: every reading after the first of a pair advances by ``step`` (each pilot seems to
    take ``step`` seconds whatever its size)."""

    def __init__(self, step: float) -> None:
        super().__init__()
        self.step = step

    def __call__(self) -> float:
        self.readings += 1
        if self.readings % 2 == 0:
            self.now += self.step
        return self.now


@pytest.mark.parametrize("map_name", ["workspace", "hover", "capacity", "singularity", "cog", "balance", "opspace"])
def test_every_map_takes_a_budget_option(qprr_platform, map_name):
    """Each map's options take ``budget`` and ``clock``: pilots of equal (fake) duration step / pilot give no slope, so
    they run until they took PILOT_CAP of the budget and the last one's t / w is the cost; the map then holds the
    count chosen, and says so in its summary."""
    from qprr.analysis.capacity import capacity
    from qprr.analysis.cog import balance, cog_regions
    from qprr.analysis.hover import hover
    from qprr.analysis.opspace import opspace_map
    from qprr.analysis.singularity import singularity
    from qprr.analysis.workspace import workspace

    fn = {
        "workspace": workspace,
        "hover": hover,
        "capacity": capacity,
        "singularity": singularity,
        "cog": cog_regions,
        "balance": balance,
        "opspace": opspace_map,
    }[map_name]
    budget, step = 1.0, 0.125  # three pilots reach PILOT_CAP = 0.3 of the budget (binary fractions: exact sums)
    res = fn(qprr_platform, budget=budget, clock=StepClock(step))
    s = res.sampling
    assert isinstance(s, SampleChoice) and s.budget == budget
    assert [p.requested for p in s.pilots] == [bud.PILOT_FIRST * bud.PILOT_GROWTH**k for k in range(3)]
    assert s.model == CostModel(0.0, step / s.pilots[-1].work)
    assert s.predicted <= bud.SAFETY * (budget - 3 * step) + 1e-12
    assert s.work == _largest_work(s, bud.SAFETY * (budget - 3 * step) / s.model.per_sample)
    assert s.work > s.pilots[-1].work
    if map_name == "workspace":
        assert s.work == sum(r.grid.size for r in res.regions)
    elif map_name == "cog":  # one grid per locked-joint variant, shared by the payload masses
        assert s.work == sum(r.grid.size for (v, k), r in res.regions.items() if k == 0)
    elif map_name != "balance":  # balance: its grid over the other joints, and the whole workspace's
        assert s.work == res.grid.size
    assert "samples:" in res.summary() and f"budget of {budget:g} s" in res.summary()
    fixed = fn(qprr_platform, n_samples=500)
    assert fixed.sampling.budget is None and "no time budget" in fixed.summary()
