"""Explicit contracts instead of hidden coupling (issue 33 item 5).

* An error raised during a run names the run's time through :meth:`QprrError.with_time`: the same object, its type
  and attributes kept (no rebuilding by ``type(err).__new__``, no decision on the message's text); an error that
  already names its time (:attr:`QprrError.time`, set by :meth:`DivergenceError.at`) is reported as is.
* Disturbances are told apart by their base class, :class:`Disturbance` or :class:`StateDisturbance`, whose
  defaults (``realize`` returns the disturbance itself, ``report`` no series) replace the ``hasattr`` and
  ``getattr`` probes of the loop.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr.control.base import Controller
from qprr.dynamics import dynamics_xi
from qprr.errors import DivergenceError, MissingDependencyError, QprrError, UnknownNameError
from qprr.sim import Disturbance, Disturbances, SimResult, StateDisturbance, Status, simulate
from qprr.trajectory import Hold
from qprr.validation import read_toml


class _RaisesAt(Controller):
    """Holds the hover force, then raises ``error`` at t >= ``t_error``."""

    name = "raises"

    def __init__(self, u, error: QprrError, t_error: float) -> None:
        self.u, self.error, self.t_error = u, error, t_error

    def step(self, t, state, ref):
        if t >= self.t_error:
            raise self.error
        return self.u


@pytest.fixture(scope="module")
def platform():
    return qprr.load("hextilt_flying_arm_5")


def _hover(platform):
    xi0 = platform.neutral_xi()
    xi0[2] = 2.0
    u = dynamics_xi(platform, platform.data(), xi0, np.zeros(platform.n_xi))[2]
    return xi0, u


@pytest.mark.parametrize(
    "error",
    [
        UnknownNameError("gain table", "typo", ("a", "b")),
        MissingDependencyError("somepkg", "a test", "pip install somepkg"),
        qprr.errors.InputError("a plain input error"),
    ],
    ids=["unknown-name", "missing-dependency", "input"],
)
def test_an_error_during_a_run_keeps_its_type_and_payload_and_names_the_time(platform, error):
    xi0, u = _hover(platform)
    before = str(error)
    with pytest.raises(type(error)) as info:
        simulate(platform, _RaisesAt(u, error, 0.0495), Hold(tuple(xi0)), 0.2, xi0=xi0)
    err = info.value
    assert err is error  # the same object: attributes (kind, name, valid; package, install) and traceback kept
    assert str(err) == f"at t = 0.050 s of the run: {before}" and err.time == pytest.approx(0.05)
    assert isinstance(err.result, SimResult) and err.result.status is Status.FAILED and err.result.n == 51
    if isinstance(err, UnknownNameError):
        assert (err.kind, err.name, err.valid) == ("gain table", "typo", ("a", "b"))


def test_with_time_names_the_time_once():
    err = DivergenceError("the attitude is NaN")
    assert err.with_time(1.25) is err and str(err) == "diverged at t = 1.250 s: the attitude is NaN" and err.time == 1.25
    err.with_time(2.0)  # already timed: unchanged
    assert str(err) == "diverged at t = 1.250 s: the attitude is NaN" and err.time == 1.25
    at = DivergenceError.at(0.5, "velocity v_x = 1e9")
    assert str(at) == "diverged at t = 0.500 s: velocity v_x = 1e9" and at.time == 0.5
    assert QprrError("x").time is None and str(QprrError("x").with_time(0.0)) == "at t = 0.000 s of the run: x"


class _Push(StateDisturbance):
    """A constant body force along x_B; no randomness, no series (the base class's defaults)."""

    def generalized_force(self, t, q, v):
        tau = np.zeros(v.shape[0])
        tau[0] = 0.1
        return tau


class _PushReported(_Push):
    def __init__(self) -> None:
        self.calls = 0

    def realize(self, t_ticks, rng, period):
        self.calls += 1
        return self

    def report(self):
        return {"push_calls": np.full(10_000, float(self.calls))}


class _Duck:
    """Has the method but not the base class: refused, the contract is the class."""

    def generalized_force(self, t, q, v):
        return np.zeros(v.shape[0])


def test_state_disturbances_use_the_base_class_defaults_and_overrides(platform):
    xi0, u = _hover(platform)
    assert _Push().realize(np.zeros(3), None, 1e-3) is not None and _Push().report() == {}
    res = simulate(platform, _RaisesAt(u, QprrError("never"), 1e9), Hold(tuple(xi0)), 0.05, xi0=xi0, disturbance=_Push())
    assert res.status is Status.OK and "push_calls" not in res.series
    assert res.xi_dot[-1, 0] != 0.0  # the push acted
    reported = _PushReported()
    res = simulate(platform, _RaisesAt(u, QprrError("never"), 1e9), Hold(tuple(xi0)), 0.05, xi0=xi0, disturbance=reported)
    assert reported.calls == 1 and res.series["push_calls"].shape == (res.n,) and np.all(res.series["push_calls"] == 1.0)


def test_a_disturbance_is_known_by_its_class():
    with pytest.raises(qprr.errors.InputError, match="subclass one of them"):
        Disturbances((_Duck(),))
    assert isinstance(Disturbances((_Push(),)), Disturbance)


def test_statuses_are_enums_equal_to_their_strings():
    """Statuses are Enums (``str`` Enums: comparisons with the strings, printing and JSON keep the strings)."""
    from qprr.actuation import AllocationStatus, Allocator
    from qprr.ik import BalanceStatus, IKOutcome, IKSolver, balance_prismatic
    from qprr.payload import CapacityStatus, HoldingStatus, holding_efforts, payload_capacity

    p = qprr.load()
    data = p.data()
    res = IKSolver(p, "qp").solve(data, np.array([0.3, 0.0, 1.0]))
    assert isinstance(res.status, IKOutcome) and res.status == "converged" == str(res.status)
    assert json.dumps({"status": res.status}) == '{"status": "converged"}' and f"{res.status}" == "converged"
    assert isinstance(Allocator(p).allocate(np.zeros(p.nv)).status, AllocationStatus)
    assert isinstance(balance_prismatic(p, data, [0.0, 0.4, -0.6]).status, BalanceStatus)
    assert isinstance(holding_efforts(p, [0.0, 0.0, 0.0], 0.1).status, HoldingStatus)
    assert isinstance(payload_capacity(p).status, CapacityStatus)
    with pytest.raises(ValueError):
        IKOutcome("convergd")  # a typo is not a status


# ------------------------------------------------------------------------------------------- SimResult.plot
_PLOT_WITHOUT_VIZ = """
import sys
import qprr
from qprr.scenarios import run
res = run("hover-reach", duration=0.2, progress=False)
assert "qprr.viz" not in sys.modules
fig = res.plot(panels="position")
print(type(fig).__module__, type(fig).__name__, "qprr.viz.plots" in sys.modules)
"""


def test_plot_returns_the_figure_of_plot_result(tmp_path):
    """``SimResult.plot()`` is ``qprr.viz.plot_result(result)``: a Figure, or the saved page with a path."""
    from matplotlib.figure import Figure

    from qprr.scenarios import run
    from qprr.sim.result import RUN_FIGURES
    from qprr.viz import plot_result

    res = run("hover-reach", duration=0.2, progress=False)
    assert RUN_FIGURES["run"] is plot_result
    fig = res.plot(panels=("position", "cog"))
    assert isinstance(fig, Figure) and len(fig.axes) >= 2
    assert res.plot(tmp_path / "run.png") == tmp_path / "run.png" and (tmp_path / "run.png").stat().st_size > 0


def test_plot_reaches_the_figures_through_the_entry_point_not_an_import(tmp_path):
    """The simulator never imports qprr.viz (the module map): ``result.plot()`` finds ``plot_result`` through the
    entry point of ``qprr.run_figures`` that qprr's pyproject.toml declares.  Here a stand-in distribution declares
    the same entry point (the installed metadata may predate it), and the run is plotted without importing qprr.viz."""
    root = Path(__file__).resolve().parents[1]
    declared = read_toml(root / "pyproject.toml", "pyproject", "qprr's own")["project"]["entry-points"]["qprr.run_figures"]
    assert declared == {"run": "qprr.viz.plots:plot_result"}
    dist = tmp_path / "qprr_run_figures_standin-0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: qprr-run-figures-standin\nVersion: 0\n")
    (dist / "entry_points.txt").write_text("[qprr.run_figures]\n" + "".join(f"{k} = {v}\n" for k, v in declared.items()))
    env = {**os.environ, "PYTHONPATH": f"{root}:{tmp_path}", "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-c", _PLOT_WITHOUT_VIZ], capture_output=True, text=True, cwd=root, env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["matplotlib.figure", "Figure", "True"], out.stdout
