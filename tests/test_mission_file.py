"""Missions as complete data (issue 35, item 2): a mission file's wind, gusts, drag, motor stage and controller are
flown as written, from the command line and from Python (``scenarios.run(..., settings=MissionSettings(...))``), the
run records the wind it flew in and its figure draws it.  The refusals are cases of tests/catalogue.py
(:func:`tests.catalogue.mission_file_cases`), run here too."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from qprr import scenarios
from qprr.cli import main
from qprr.control.gains import load_gains
from qprr.errors import InputError, ScheduleWarning
from qprr.scenarios.missions import MissionSettings
from qprr.sim import Pulse, SimResult
from qprr.sim.wind import AerodynamicDrag, Dryden, Gust, Wind
from qprr.trajectory import Hold
from qprr.viz import plot_result
from tests import catalogue

ROOT = Path(__file__).resolve().parents[1]
MY = ROOT / "examples" / "my_platform"
OWN = ["--urdf", str(MY / "quad_rrr.urdf"), "--rotors", str(MY / "quad_rrr.rotors.toml"), "--ee-frame", "gripper"]
WIND_FILE = MY / "mission_wind.toml"

# the air and the motors of mission_wind.toml, typed here from the file's numbers (not read by qprr)
FILE_WIND = Wind(
    mean=(3.0, 1.0, 0.0),
    turbulence=Dryden((0.5, 0.5, 0.25), (30.0, 30.0, 5.0), math.hypot(3.0, 1.0)),
    gusts=(Gust(4.0, 1.0, (0.0, 2.0, 0.0)),),
)
FILE_SEED = 7
FILE_THRUST_FACTOR = 8.5e-6  # [N s^2]


def expected_wind(t: np.ndarray, period: float) -> np.ndarray:
    """The wind a run with ticks ``t`` flies in: FILE_WIND drawn from the file's seed on the tick grid (qprr.sim.wind)."""
    grid = t[0] + period * np.arange(t.shape[0] + 1)
    return FILE_WIND.sample(grid, np.random.default_rng(FILE_SEED))[:-1]


def simulate_cli(capsys, *argv: str) -> str:
    assert main(["simulate", "mission", *OWN, *argv, "-q"]) == 0, capsys.readouterr()
    out = capsys.readouterr()
    return out.out + out.err


@pytest.fixture(scope="module")
def quad():
    return catalogue.example_platform()


def test_the_wind_mission_flies_from_the_command_line_as_written(tmp_path, capsys):
    """examples/my_platform/mission_wind.toml, whole (8 s): the run is labelled by the file's name, its recorded wind is
    the file's (mean, Dryden turbulence of the file's seed, gust) at every tick, its rotors are the file's motor stage
    (f = b w^2 with the file's b), and its page has a wind panel and the mission's name in the title."""
    run, png = tmp_path / "wind.npz", tmp_path / "wind.png"
    out = simulate_cli(capsys, "--set", f"mission={WIND_FILE}", "--duration", "8", "--save", str(run), "--plot", str(png))
    assert "scenario mission pick-and-place in wind, platform quad_rrr, controller idc: ok" in out, out
    res = SimResult.load(run)
    np.testing.assert_array_equal(res.series["wind_velocity"], expected_wind(res.t, res.control_period))
    np.testing.assert_allclose(res.f, FILE_THRUST_FACTOR * res.series["rotor_speed"] ** 2, rtol=1e-12, atol=0.0)
    assert res.metrics["max_position_error"] < 0.3  # flown through the gust without diverging (no integral: an offset stays)
    fig = plot_result(res)
    assert "mission pick-and-place in wind / idc on quad_rrr" in fig.get_suptitle()
    wind_axes = [a for a in fig.axes if a.get_title() == "wind the base flew in"]
    assert len(wind_axes) == 1 and wind_axes[0].get_ylabel() == "wind velocity, world axes [m/s]"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the file's seed, not the run's: another run seed, a shorter run, the same air on the common ticks
    short = tmp_path / "short.npz"
    with pytest.warns(ScheduleWarning, match="gust 1"):  # the shorter run is warned about what it leaves out
        simulate_cli(capsys, "--set", f"mission={WIND_FILE}", "--duration", "0.5", "--seed", "5", "--save", str(short))
    w = SimResult.load(short).series["wind_velocity"]
    np.testing.assert_array_equal(w, res.series["wind_velocity"][: w.shape[0]])


def test_settings_objects_are_accepted_and_the_file_adds_to_them(quad):
    """``scenarios.run("mission", settings=MissionSettings(...))``: the given reference and name are flown, the caller's
    disturbance acts beside the file's wind (both in the run: the pulse in u_ext, the wind in its series)."""
    xi_hold = quad.neutral_xi()
    xi_hold[2] = 1.0
    gamma = np.zeros(quad.n_xi)
    gamma[0] = 0.8
    settings = MissionSettings(trajectory=Hold(tuple(xi_hold)), disturbance=Pulse(0.1, 0.2, tuple(gamma)), name="held in wind")
    data = {"wind": {"model": "mean", "mean_world": [2.0, 0.0, 0.0]}, "drag": {"linear": 0.3}, "payload": [{"time": 0.25, "mass": 0.1}]}
    res = scenarios.run("mission", platform=quad, duration=0.4, settings=settings, mission=data)
    assert res.scenario == "held in wind"
    np.testing.assert_array_equal(res.xi_d[:, 2], np.full(res.n, 1.0))
    on = (res.t > 0.1 + 1e-9) & (res.t < 0.2 - 1e-9)
    np.testing.assert_array_equal(res.u_ext[on], np.tile(gamma, (int(on.sum()), 1)))
    np.testing.assert_array_equal(res.series["wind_velocity"], np.tile([2.0, 0.0, 0.0], (res.n, 1)))
    with pytest.raises(InputError, match="plant is given twice"):
        scenarios.get_scenario("mission").run(platform=quad, plant=quad, settings=MissionSettings(plant=quad), duration=0.05)


def test_gains_in_the_file_are_the_gains_flown(quad, tmp_path, capsys):
    """[controller] gains = "gains.toml" (relative to the mission file), the same tables written in [controller], and
    the option gains=FILE fly the same run bit for bit, and ``--print-gains`` shows them; the derived gains fly another."""
    shutil.copy(MY / "gains.toml", tmp_path / "gains.toml")
    climb = '[[phase]]\ncoordinate = "z"\nstart = 0.0\nend = 0.3\ntarget = 0.5\n'
    (tmp_path / "by_file.toml").write_text(climb + '[controller]\nname = "idc"\ngains = "gains.toml"\n')
    (tmp_path / "inline.toml").write_text(climb + "[controller.targets]\nratio = 3.0\n")
    (tmp_path / "plain.toml").write_text(climb)
    runs = {
        name: scenarios.run("mission", platform=quad, duration=0.3, mission=str(tmp_path / f"{name}.toml"), **extra)
        for name, extra in (("by_file", {}), ("inline", {}), ("plain", {"gains": str(MY / "gains.toml")}))
    }
    for name in ("by_file", "inline"):
        np.testing.assert_array_equal(runs[name].xi, runs["plain"].xi)
    derived = scenarios.run("mission", platform=quad, duration=0.3, mission=str(tmp_path / "plain.toml"))
    assert np.max(np.abs(derived.xi[:, 2] - runs["plain"].xi[:, 2])) > 1e-4
    assert runs["by_file"].scenario == "mission by_file" and derived.scenario == "mission plain"
    printed = [
        simulate_cli(capsys, *extra, "--print-gains")
        for extra in (["--set", f"mission={tmp_path / 'inline.toml'}"], ["--gains", str(MY / "gains.toml")])
    ]
    kp_x = load_gains(MY / "gains.toml", "idc", quad)["gains"].kp[0]  # the file's re-derived gains (ratio 3)
    assert "gains of idc in mission on quad_rrr ([controller] of mission 'inline')" in printed[0] and f"{kp_x:.5g}" in printed[0]
    assert printed[0].split("\n", 1)[1] == printed[1].split("\n", 1)[1]  # the same table


def test_the_wind_seed_is_the_winds_own():
    """Wind(seed=...) realizes the same air whatever the run's generator; without a seed, the run's generator draws it."""
    t = np.arange(200) * 1e-3
    own = AerodynamicDrag(linear=0.3, wind=Wind(mean=(3.0, 0.0, 0.0), turbulence=FILE_WIND.turbulence, seed=11))
    a = own.realize(t, np.random.default_rng(1), 1e-3).report()["wind_velocity"]
    b = own.realize(t, np.random.default_rng(2), 1e-3).report()["wind_velocity"]
    np.testing.assert_array_equal(a, b)
    run = AerodynamicDrag(linear=0.3, wind=Wind(mean=(3.0, 0.0, 0.0), turbulence=FILE_WIND.turbulence))
    c = run.realize(t, np.random.default_rng(11), 1e-3).report()["wind_velocity"]
    d = run.realize(t, np.random.default_rng(2), 1e-3).report()["wind_velocity"]
    np.testing.assert_array_equal(a, c)
    assert np.max(np.abs(c - d)) > 1e-3
    with pytest.raises(InputError, match="wind seed"):
        Wind(seed=-1)


def test_a_run_in_still_air_has_no_wind_panel(quad):
    res = scenarios.run("mission", platform=quad, duration=0.05, mission={"phase": [{"coordinate": "z", "start": 0.0, "end": 0.02, "target": 1.0}]})
    assert "wind_velocity" not in res.series
    assert "wind the base flew in" not in [a.get_title() for a in plot_result(res).axes]
    with pytest.raises(InputError, match="recorded no wind"):
        plot_result(res, panels="wind")


def test_every_mission_file_refusal_names_the_input():
    outcomes = catalogue.run_cases(catalogue.mission_file_cases())
    bad = [o for o in outcomes if o.verdict != "good"]
    assert len(outcomes) >= 20 and not bad, "\n".join(f"{o.verdict:8s} {o.target}: {o.detail}" for o in bad)


def test_a_campaign_names_the_controller_its_mission_file_flies(tmp_path):
    """A campaign of the mission scenario that names no controller: its table's controller column is the one the
    mission file names (the runs fly it), not the scenario's first."""
    from qprr.campaign import CampaignSpec
    from qprr.campaign.worker import default_controller

    (tmp_path / "m.toml").write_text('[[phase]]\ncoordinate = "z"\nstart = 0.0\nend = 1.0\ntarget = 1.0\n[controller]\nname = "dsid"\n')
    (tmp_path / "spec.toml").write_text('name = "m"\nscenario = "mission"\nplatform = "HEX-RRR"\n[options]\nmission = "m.toml"\nduration = 1.5\n')
    assert default_controller(CampaignSpec.load(tmp_path / "spec.toml")) == "dsid"
