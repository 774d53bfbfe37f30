"""Control scenarios on the Q-PRR beyond Sec. 6.3's missions: the thesis's point-to-point regulation and Annex run,
and the scenarios qprr adds (aggressive reach for rotor bounds; realistic actuators and wind).

==================  ==============================================================================================
name                what
==================  ==============================================================================================
``point-to-point``  Sec. 6.3.1.1, Fig. 6.4: regulation to p_b = [5, 5, 10] m without a trajectory (a step),
                    IDC with K_P = 30 I_9, K_D = 18 I_9 on all nine coordinates and no (6.17) attitude loop.
                    The thesis drives its model with u directly: ``actuation="ideal"`` (default) reproduces
                    that with a fully actuated, unbounded idealisation of the rotors
                    (:func:`qprr.rotors.ideal_wrench_set`, :class:`qprr.actuation.IdealAllocator`; arm efforts
                    unclipped); ``actuation="rotors"`` tries the same step on the Q-PRR's four bounded rotors
                    with (6.17) tilt references (the demand saturates every rotor: it diverges)
``annex-a``         Annex A, Figs. A.9-A.13: the dynamic-manipulator mission (CoG stabiliser BSG + MFC) to
                    p_b = [10, 6, 10] m
``aggressive-reach`` not in the thesis: climb 2 m and reach 0.6 m forward in 1 s with the arm out
                    (:func:`qprr.thesis.missions.aggressive_reach`): the IDC asks the rotors for more than
                    [0, 20] N, the MPC plans inside the bounds
``realistic``       not in the thesis: a mission (static, spiral or hover) with motor lag, air drag with wind
                    (mean + Dryden turbulence + a gust) and joint friction (:mod:`qprr.thesis.realistic`)
==================  ==============================================================================================

Registered in :data:`qprr.scenarios.SCENARIOS`.  Results carry ``metrics`` on the rotor bounds
(:func:`thrust_margins`) and, for the MPC, its solve statistics (``mpc_*``).

Built on the generic missions of :mod:`qprr.scenarios.missions` (bit-identical to their earlier own machinery):
``annex-a`` is ``mission`` with the dynamic mission to :data:`ANNEX_TARGET` as data under the CoG
stabiliser; ``aggressive-reach`` is ``mission`` flying :func:`~qprr.thesis.missions.aggressive_reach`;
``realistic`` is ``motor-lag`` with the Q-PRR's rotor stage (thrust factor of its parameters, time constant
``time_constant``), its mission as the reference and drag in wind and joint friction as the disturbance
(``mission`` when ``motors=False``).  ``point-to-point`` has no generic counterpart: a step of the set point
(no trajectory) flown by idealised, unbounded actuators (:class:`qprr.actuation.IdealAllocator`, arm efforts
unclipped) from rest at the origin, where ``fly-to`` flies a smooth reference through the platform's rotors.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..actuation import IdealAllocator
from ..control import IDCGains, InverseDynamicsController
from ..errors import QprrError, UnknownNameError
from ..rotors import ideal_wrench_set
from ..scenarios import Option, Scenario
from ..scenarios import missions as generic
from ..sim import INTEGRATORS, SimConfig, SimInputs, SimResult, simulate
from ..trajectory import Hold, Spiral
from ..validation import as_name, as_real, as_settings, as_vector, check_fields
from ..viz import plot_result
from .missions import aggressive_reach, dynamic_mission, static_mission
from .realistic import MEAN_WIND, TIME_CONSTANT, W20, realistic
from .robot import load_qprr, params_of
from .scenarios import _BSG_CONTROLLERS, _FLIGHT, _FLIGHT_CONTROLLERS, Instance, _flight, _plot_flight, flight_gains

POINT_TARGET = (5.0, 5.0, 10.0)
"""p_b of Sec. 6.3.1.1 [m]."""
POINT_GAINS = IDCGains((30.0,) * 9, (18.0,) * 9, (0.0,) * 9)
"""K_P = 30 I_9, K_D = 18 I_9 (Sec. 6.3.1.1), no integral action."""
ANNEX_TARGET = (10.0, 6.0, 10.0)
"""p_b of Annex A, Fig. A.11 [m]."""
ANNEX_MISSION = Instance(generic.mission, {"mission": {"phase": tuple(generic.phase_tables(dynamic_mission(ANNEX_TARGET).phases))}})
"""``annex-a``: the generic ``mission`` given the dynamic mission of Sec. 6.3.3.3 to :data:`ANNEX_TARGET` as data (under the BSG)."""
IDEAL_FORCE_MAX, IDEAL_TORQUE_MAX = 1e4, 1e3
"""Bounds of the idealised actuation [N], [N m]: far above what the step asks (1.1 kN at t = 0)."""


def _q_prr(platform):
    platform = load_qprr() if platform is None else platform
    params_of(platform)
    return platform


# ------------------------------------------------------------------------------- margins
def thrust_margins(result: SimResult, platform) -> dict[str, float]:
    """How close a run came to the rotor bounds [N] (negative: beyond).

    ``applied_margin``: min over the run of min(f - f_min, f_max - f) of the applied thrusts;
    ``asked_margin``: the same for the thrusts the controller *asked* for, Omega_P^-1 of the producible rows of
    the desired base wrench tau_d = N f + unallocated (what the allocator would have had to apply exactly);
    ``saturated_fraction``: fraction of control ticks with a rotor bound active.
    """
    f_lo, f_hi = np.array(platform.thrust_min), np.array(platform.thrust_max)
    f = result.f
    applied = float(np.min(np.minimum(f - f_lo, f_hi - f))) if f.size else float("nan")
    Omega = np.array(platform.rotor_matrix)
    rows = [i for i in range(6) if np.abs(Omega[i]).max() > 1e-12]
    tau_d = np.hstack([f, result.arm_effort]) @ np.array(platform.actuation_matrix).T + result.unallocated
    asked = tau_d[:, rows] @ np.linalg.pinv(Omega[rows]).T
    asked_margin = float(np.min(np.minimum(asked - f_lo, f_hi - asked))) if asked.size else float("nan")
    return {
        "applied_margin_N": applied,
        "asked_margin_N": asked_margin,
        "saturated_fraction": result.saturation_fraction(),
        "asked_min_N": float(asked.min()),
        "asked_max_N": float(asked.max()),
    }


def _with_margins(res: SimResult, platform) -> SimResult:
    res.metrics.update({f"thrust_{k}": v for k, v in thrust_margins(res, platform).items()})
    return res


def margin_summary(res: SimResult) -> list[str]:
    """Report lines: thrust margins (and the MPC's solve statistics when present)."""
    m = res.metrics
    lines = []
    if "thrust_applied_margin_N" in m:
        lines.append(
            f"rotor bounds: applied thrust margin {m['thrust_applied_margin_N']:.3g} N, asked-for thrusts "
            f"[{m['thrust_asked_min_N']:.3g}, {m['thrust_asked_max_N']:.3g}] N (margin {m['thrust_asked_margin_N']:.3g} N), "
            f"a bound active on {100 * m['thrust_saturated_fraction']:.2f} % of the ticks"
        )
    if "mpc_solves" in m:
        lines.append(
            f"mpc: {m['mpc_solves']:.0f} solves, wall median {1e3 * m['mpc_median_solve_s']:.1f} ms, p95 "
            f"{1e3 * m['mpc_p95_solve_s']:.1f} ms (CPU median {1e3 * m['mpc_median_solve_cpu_s']:.1f} ms, p95 "
            f"{1e3 * m['mpc_p95_solve_cpu_s']:.1f} ms); {m['mpc_converged']:.0f} converged, {m['mpc_iteration_limit']:.0f} "
            f"at the iteration limit, {m['mpc_failed']:.0f} failed ({m['mpc_fallbacks']:.0f} fallbacks); smallest planned "
            f"thrust margin {m['mpc_min_plan_thrust_margin_N']:.3g} N"
        )
    if "wind_speed_mean" in m:
        lines.append(
            f"wind: mean speed {m['wind_speed_mean']:.2f} m/s, turbulence std {m['wind_turbulence_std']:.2f} m/s; rotor "
            f"speeds {m['rotor_speed_min']:.0f}..{m['rotor_speed_max']:.0f} rad/s"
        )
    if "settling_x" in m:  # point-to-point (the generic missions' final_position_error has no settling times)
        lines.append(
            f"final |p_b - p_b^d| = {m['final_position_error']:.3g} m; 2 % settling times x, y, z: "
            f"{m['settling_x']:.2f}, {m['settling_y']:.2f}, {m['settling_z']:.2f} s"
        )
    return lines


# ------------------------------------------------------------------------ point-to-point
def _settling_time(t: np.ndarray, x: np.ndarray, target: float, start: float, tol: float = 0.02) -> float:
    """First time after which |x - target| <= tol |target - start| for good."""
    band = tol * abs(target - start) if target != start else tol
    out = np.abs(x - target) > band
    if not out.any():
        return 0.0
    k = int(np.nonzero(out)[0][-1])
    return float(t[k + 1]) if k + 1 < t.shape[0] else float("inf")


@dataclass(frozen=True)
class PointToPointSettings:
    """The options of ``point-to-point`` (help: the scenario's :attr:`~qprr.scenarios.Scenario.options`): the set point
    ``target`` p_b [m], run ``duration`` [s], ``actuation`` ("ideal" or "rotors", module docstring), integration step
    ``dt`` [s], ``integrator``, ``seed``."""

    target: tuple[float, float, float] = POINT_TARGET
    duration: float = 10.0
    actuation: str = "ideal"
    dt: float = SimConfig.dt
    integrator: str = "midpoint"
    seed: int = 0

    def __post_init__(self) -> None:
        check_fields(self)
        object.__setattr__(self, "target", tuple(as_vector(self.target, 3, "target").tolist()))
        as_real(self.duration, "duration", positive=True, unit="s")
        as_real(self.dt, "dt", positive=True, unit="s")
        as_name(self.actuation, "actuation", ("ideal", "rotors"))
        as_name(self.integrator, "integrator", INTEGRATORS)


def point_to_point(platform=None, controller: str = "idc", progress: bool = False, settings: PointToPointSettings | None = None) -> SimResult:
    """Sec. 6.3.1.1 (Fig. 6.4): a step of the base reference from the origin to ``settings.target`` [m], IDC with
    K_P = 30 I_9, K_D = 18 I_9 (:class:`PointToPointSettings`; module docstring for ``actuation``)."""
    o = as_settings(settings, PointToPointSettings)
    target, duration, actuation, dt, integrator, seed = o.target, o.duration, o.actuation, o.dt, o.integrator, o.seed
    platform = _q_prr(platform)
    if controller != "idc":
        raise UnknownNameError("controller", controller, ("idc",))
    target = tuple(as_vector(target, 3, "target").tolist())  # p_b = (x, y, z) [m]
    allocator = None
    if actuation == "ideal":
        platform = platform.replace(rotors=ideal_wrench_set(IDEAL_FORCE_MAX, IDEAL_TORQUE_MAX), name=f"{platform.name}, ideal actuation")
        allocator = IdealAllocator(platform, clip_arm=False)
    elif actuation != "rotors":
        raise UnknownNameError("actuation", actuation, ("ideal", "rotors"))
    ctrl = InverseDynamicsController(platform, POINT_GAINS)
    config = SimConfig(dt=dt, integrator=integrator, seed=seed, progress=progress, scenario="point-to-point")
    inputs = SimInputs(xi0=np.zeros(9), allocator=allocator)
    res = simulate(platform, ctrl, Hold((*target, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)), duration, config=config, inputs=inputs)
    res.metrics["final_position_error"] = float(np.linalg.norm(res.xi[-1, 0:3] - np.array(target)))
    for i, name in enumerate("xyz"):
        res.metrics[f"settling_{name}"] = _settling_time(res.t, res.xi[:, i], target[i], 0.0)
    return res


def plot_point_to_point(result: SimResult, path) -> Path:
    """Fig. 6.4: x_b, y_b, z_b against time, with the set points."""
    from ..viz import figure_path, new_figure

    path = figure_path(path)
    fig = new_figure((12, 3.8))
    ax = fig.subplots(1, 3)
    for i, (a, n) in enumerate(zip(ax, ("x_b", "y_b", "z_b"))):
        a.plot(result.t, result.xi[:, i], "C0", lw=1.5, label="measured")
        a.plot(result.t, result.xi_d[:, i], "k--", lw=1.0, label="set point")
        a.set_xlabel("t [s]")
        a.set_ylabel(f"{n} [m]")
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle(f"point-to-point regulation (Sec. 6.3.1.1, Fig. 6.4): IDC K_P = 30 I, K_D = 18 I; {result.platform}", fontsize=10)
    fig.savefig(path, dpi=90)
    return path


# ------------------------------------------------------------------------ aggressive reach
@dataclass(frozen=True)
class AggressiveReachSettings:
    """The options of ``aggressive-reach`` (defaults and help: the scenario's :attr:`~qprr.scenarios.Scenario.options`):
    run ``duration`` [s], ``climb`` [m] and ``forward`` reach along x [m] in 1 s
    (:func:`~qprr.thesis.missions.aggressive_reach`), integration step ``dt`` [s], ``integrator``, ``seed``."""

    duration: float
    climb: float
    forward: float
    dt: float
    integrator: str
    seed: int


def _aggressive(platform, controller, progress, settings: AggressiveReachSettings):
    platform = _q_prr(platform)
    o = settings
    mission = generic.MissionSettings(trajectory=aggressive_reach(climb=o.climb, forward=o.forward), name="aggressive-reach")
    options = {"duration": o.duration, "dt": o.dt, "integrator": o.integrator, "seed": o.seed, "gains": flight_gains(controller), "mission": ""}
    try:
        res = generic.mission(platform, controller, progress, mission, **options)
    except QprrError as err:  # a diverged run still reports its margins
        res = err.result
        if res is None:
            raise
        _with_margins(res, platform)
        raise
    return _with_margins(res, platform)


# ------------------------------------------------------------------------------ realistic
MISSIONS = ("static", "spiral", "hover")


@dataclass(frozen=True)
class RealisticSettings:
    """The options of ``realistic`` (defaults and help: the scenario's :attr:`~qprr.scenarios.Scenario.options`).

    The flight: run ``duration`` [s], integration step ``dt`` [s], ``integrator``, ``seed``, transition ``law`` and
    ``mission`` (one of :data:`MISSIONS`).  The stages of :func:`qprr.thesis.realistic.realistic`, each switchable:
    ``motors`` (first-order lag, time constant ``time_constant`` [s]), ``drag`` in the wind (mean ``mean_wind``, world
    axes [m/s]; Dryden turbulence of wind speed ``w20`` at 20 ft [m/s]; the ``gust``) and joint ``friction``."""

    duration: float
    dt: float
    integrator: str
    seed: int
    law: str
    mission: str
    motors: bool
    drag: bool
    friction: bool
    mean_wind: tuple[float, float, float]
    w20: float
    gust: bool
    time_constant: float


def _realistic(platform, controller, progress, settings: RealisticSettings):
    platform = _q_prr(platform)
    o = settings
    if o.mission not in MISSIONS:
        raise UnknownNameError("mission", o.mission, MISSIONS)
    trajectory = {
        "static": lambda: static_mission(law=o.law),
        "spiral": lambda: Spiral(),
        "hover": lambda: Hold((0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
    }[o.mission]()
    env = realistic(
        platform, motors=o.motors, drag=o.drag, friction=o.friction, mean_wind=o.mean_wind, w20=o.w20, gust=o.gust, time_constant=o.time_constant
    )
    mission = generic.MissionSettings(trajectory=trajectory, disturbance=env.disturbance, name="realistic")
    options = {"duration": o.duration, "dt": o.dt, "integrator": o.integrator, "seed": o.seed, "law": o.law, "gains": flight_gains(controller)}
    try:
        if o.motors:  # the generic motor-lag with the Q-PRR's rotor stage (thrust factor of its parameters, time constant)
            b = params_of(platform).thrust_factor
            res = generic.motor_lag(platform, controller, progress, mission, tau=o.time_constant, thrust_factor=b, **options)
        else:
            res = generic.mission(platform, controller, progress, mission, mission="", **options)
    except QprrError as err:
        if err.result is not None:
            _realistic_metrics(err.result, platform)
        raise
    return _realistic_metrics(res, platform)


def _realistic_metrics(res: SimResult, platform) -> SimResult:
    _with_margins(res, platform)
    s = res.series
    if "wind_velocity" in s:
        w = s["wind_velocity"]
        res.metrics["wind_speed_mean"] = float(np.linalg.norm(w.mean(axis=0)))
        res.metrics["wind_turbulence_std"] = float(np.sqrt(np.mean(np.sum((w - w.mean(axis=0)) ** 2, axis=1))))
    if "rotor_speed" in s:
        res.metrics["rotor_speed_min"] = float(s["rotor_speed"].min())
        res.metrics["rotor_speed_max"] = float(s["rotor_speed"].max())
    return res


def plot_realistic(result: SimResult, path) -> Path:
    """The run's page (:func:`qprr.viz.plot_result`) and, next to it (``<stem>-wind<suffix>``), the wind and rotor speeds."""
    from ..viz import figure_path, new_figure

    out = plot_result(result, path)
    s = result.series
    if "wind_velocity" not in s and "rotor_speed" not in s:
        return out
    p2 = figure_path(Path(path).with_name(Path(path).stem + "-wind" + Path(path).suffix))
    fig = new_figure((12, 6))
    ax = fig.subplots(2, 1, sharex=True)
    if "wind_velocity" in s:
        for i, c in enumerate("xyz"):
            ax[0].plot(result.t, s["wind_velocity"][:, i], lw=0.8, label=f"w_{c}")
        ax[0].set_ylabel("wind, world axes [m/s]")
        ax[0].legend(fontsize=8)
    if "rotor_speed" in s:
        for i in range(s["rotor_speed"].shape[1]):
            ax[1].plot(result.t, s["rotor_speed"][:, i], lw=0.8, label=f"rotor {i + 1}")
        ax[1].set_ylabel("rotor speed [rad/s]")
        ax[1].legend(fontsize=8)
    ax[1].set_xlabel("t [s]")
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(f"{result.scenario} / {result.controller}: wind (mean + Dryden + gust) and rotor speeds", fontsize=10)
    fig.savefig(p2, dpi=80)
    return out


# ------------------------------------------------------------------------------ registry
def _settings_runner(fn, settings_type):
    """The registry's runner of ``fn(platform, controller, progress, settings)``: the options :meth:`Scenario.run
    <qprr.scenarios.Scenario.run>` passes by name, gathered into ``settings_type`` (a field per option)."""

    def run(platform, controller, progress, **options):
        return fn(platform, controller, progress, settings_type(**options))

    return run


_REALISTIC = {
    **_FLIGHT,
    "mission": Option("static", "static (Sec. 6.3.1.4), spiral (6.25) or hover (at 10 m)"),
    "motors": Option(True, "rotor speeds with a first-order lag (qprr.sim.actuators)"),
    "drag": Option(True, "aerodynamic drag D of (5.36) with the wind"),
    "friction": Option(True, "arm joint friction F_v of (5.36)"),
    "mean_wind": Option(MEAN_WIND, "mean wind, world axes [m/s]"),
    "w20": Option(W20, "wind speed at 20 ft for the Dryden intensities [m/s] (0: no turbulence)"),
    "gust": Option(True, "a 1 - cosine gust of 2 m/s along y at 18-21 s"),
    "time_constant": Option(TIME_CONSTANT, "motor time constant [s]"),
}

SCENARIOS = (
    Scenario(
        "point-to-point",
        "regulation to p_b = [5, 5, 10] without trajectory, IDC K_P = 30 I, K_D = 18 I",
        _settings_runner(point_to_point, PointToPointSettings),
        ("idc",),
        {
            "target": Option(POINT_TARGET, "p_b set point [m]"),
            "duration": Option(10.0, "run length [s]"),
            "actuation": Option("ideal", "ideal (the thesis's u applied as is) or rotors (the Q-PRR's four bounded rotors)"),
            "dt": Option(SimConfig.dt, "integration step [s]"),
            "integrator": Option("midpoint", "midpoint, rk4 or euler"),
            "seed": Option(0, "seed"),
        },
        ("q-prr",),
        plot_point_to_point,
        "Sec. 6.3.1.1, Fig. 6.4",
        margin_summary,
    ),
    Scenario(
        "annex-a",
        "dynamic-manipulator mission (BSG + MFC) to p_b = [10, 6, 10]",
        _flight("annex-a", ANNEX_MISSION, bsg=True),
        _BSG_CONTROLLERS,
        _FLIGHT,
        ("q-prr",),
        _plot_flight,
        "Annex A, Figs. A.9-A.13",
    ),
    Scenario(
        "aggressive-reach",
        "climb 2 m and reach 0.6 m forward in 1 s: the IDC saturates the rotors, the MPC plans within them",
        _settings_runner(_aggressive, AggressiveReachSettings),
        ("mpc", *[c for c in _FLIGHT_CONTROLLERS if c != "mpc"]),
        {
            "duration": Option(3.0, "run length [s]"),
            "climb": Option(2.0, "climb [m] in 1 s"),
            "forward": Option(0.6, "reach along x [m]"),
            "dt": Option(SimConfig.dt, "integration step [s]"),
            "integrator": Option("midpoint", "midpoint, rk4 or euler"),
            "seed": Option(0, "seed"),
        },
        ("q-prr",),
        _plot_flight,
        "",
        margin_summary,
    ),
    Scenario(
        "realistic",
        "a mission with motor lag, air drag in wind (mean + Dryden + gust) and joint friction",
        _settings_runner(_realistic, RealisticSettings),
        _FLIGHT_CONTROLLERS,
        _REALISTIC,
        ("q-prr",),
        plot_realistic,
        "(5.36) F_v and D, not simulated in the thesis",
        margin_summary,
    ),
)
"""The scenarios of this module (registered in :data:`qprr.scenarios.SCENARIOS`)."""

__all__ = [
    "ANNEX_TARGET",
    "POINT_GAINS",
    "POINT_TARGET",
    "PointToPointSettings",
    "SCENARIOS",
    "margin_summary",
    "plot_point_to_point",
    "plot_realistic",
    "point_to_point",
    "thrust_margins",
]
