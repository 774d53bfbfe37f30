"""Named, seeded flight scenarios of Thesis Chapter 6, and the ``simulate`` / ``compare`` commands.

=================  =========================================================================
name               what it runs
=================  =========================================================================
``static-idc``     Sec. 6.3.1.4: xi_d = [3, 6, 10, psi = 0, 0.04, 0.2, 0.6], climb z 0-5 s,
                   x 5-10 s, y 10-15 s, arm 15-25 s, inverse-dynamics control (IDC)
``static-dsid``    the same with desired-state inverse dynamics (the thesis's "MPC", Annex A.2)
``static-mfc``     the same with model-free control (iPID, Sec. 6.3.3.2)
``spiral``         climb, then the spiral (6.25) from t_f = 5 s (faded in over 2 s), IDC
``noise``          static mission + white noise on the generalised forces (6.27), IDC
``pulses``         static mission + finite pulses (6.28) in the three phases, IDC
``dynamic-bsg``    Sec. 6.3.3.3: same flight, theta2_d = -0.5, theta_e^d = 0, CoG stabiliser
                   (BSG) + MFC keeping x_cm near 0
=================  =========================================================================

Every scenario lasts 30 s at 1 kHz by default and is reproducible (noise seeded).  The
transition law is the minimum-snap septic polynomial (``law="septic"``: jerk zero at both
ends of a phase, so the thrust direction (6.17) starts and stops turning smoothly);
``law="quintic"`` uses the order-5 polynomial the text names (its jerk steps at every phase
switch: a step of the tilt rate, see docs/notes-spikes.md) and ``law="thesis"`` the rational
formula printed as (6.16), whose 10 m climb in 5 s asks for a 1.55 g deceleration (see
:mod:`qprr.trajectory`): the rotors saturate at zero thrust.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .control import CONTROLLERS, THESIS_NAMES, CogStabilizer, make_controller
from .errors import UnknownNameError
from .model import Robot, load
from .sim import Disturbances, Pulse, SimResult, WhiteNoise, simulate
from .trajectory import DEFAULT_LAW, LAWS, XI_NAMES, Spiral, dynamic_mission, static_mission

# ------------------------------------------------------------------------------ scenarios
NOISE_AMPLITUDE = (0.3,) * 7 + (0.01, 0.01)
"""White-noise amplitude per generalised force (N or N m), a new value every step.  The thesis
applies [-0.3, 0.3] to all nine; on the revolute joints that is 6 to 60 times the links' own
gravity torque and, on the 2.5e-4 kg m^2 wrist, up to 1200 rad/s^2.  Measured with +-0.3 on
all nine (static mission, 30 s): the IDC loses the wrist (theta3 RMSE 4.2 rad: it spins), the
desired-state controller keeps it within 0.17 rad RMSE, the MFC within 0.036 rad (the thesis's
remark that the MFC is the most robust to disturbances holds).  The scenario keeps +-0.3 on
x, y, z, phi, theta, psi, r0 and gives the two revolute joints +-0.01 N m."""

PULSES = (
    Pulse(2.0, 2.5, (0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
    Pulse(12.0, 12.5, (2.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
    Pulse(26.0, 26.5, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.005, 0.0)),
)
"""(6.28) pulses Gamma [H(t - t1) - H(t - t2)] in the three phases of Sec. 6.3.2.2: during the
climb in z (5 N on z), during the x-y transition (2 N on x and y) and after the arm task
("t > 25 s": 0.1 N on r0, 0.005 N m on theta2).  The thesis does not print Gamma ("chosen so
that the system does not diverge"); these values displace the arm by a few centimetres or
hundredths of a radian with the Table 6.2 arm gains."""


@dataclass(frozen=True)
class Scenario:
    """A named simulation: trajectory factory (takes the transition law), default controller, disturbance."""

    name: str
    description: str
    thesis: str
    controller: str
    trajectory: Callable[[str], object]
    duration: float = 30.0
    disturbance: Callable[[], object] | None = None
    bsg: bool = False
    theta_e_d: float = 0.0
    controller_kwargs: dict = field(default_factory=dict)


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario("static-idc", "static manipulator mission, inverse-dynamics control", "Sec. 6.3.1.4, Table 6.3 IDC",
                 "idc", lambda law: static_mission(law=law)),
        Scenario("static-dsid", "static manipulator mission, desired-state inverse dynamics (thesis: MPC)",
                 "Annex A.2, Table 6.3 MPC", "dsid", lambda law: static_mission(law=law)),
        Scenario("static-mfc", "static manipulator mission, model-free control (iPID)", "Sec. 6.3.3.2, Table 6.3 MFC",
                 "mfc", lambda law: static_mission(law=law)),
        Scenario("spiral", "climb then spiral (6.25) from t_f = 5 s (faded in over 2 s), IDC", "Sec. 6.3.1.4, (6.25), Fig. 6.14-6.18",
                 "idc", lambda law: Spiral()),
        Scenario("noise", "static mission with white noise on the generalised forces, IDC",
                 "Sec. 6.3.2.1, (6.27), Fig. 6.23-6.27", "idc", lambda law: static_mission(law=law),
                 disturbance=lambda: WhiteNoise(NOISE_AMPLITUDE)),
        Scenario("pulses", "static mission with finite pulses in the three phases, IDC", "Sec. 6.3.2.2, (6.28), Fig. 6.28-6.29",
                 "idc", lambda law: static_mission(law=law), disturbance=lambda: Disturbances(PULSES)),
        Scenario("dynamic-bsg", "dynamic manipulator: theta2_d = -0.5, theta_e^d = 0, BSG + MFC keep x_cm near 0",
                 "Sec. 6.3.3.3, Fig. 6.37-6.45", "mfc", lambda law: dynamic_mission(law=law), bsg=True),
    )
}
"""Scenarios by name."""


def get_scenario(name: str) -> Scenario:
    """The scenario called ``name``; UnknownNameError lists the valid ones."""
    if name not in SCENARIOS:
        raise UnknownNameError("scenario", name, tuple(SCENARIOS))
    return SCENARIOS[name]


def run(name: str, controller: str | None = None, *, robot: Robot | None = None, duration: float | None = None,
        dt: float = 1e-3, integrator: str = "midpoint", seed: int = 0, law: str = DEFAULT_LAW,
        progress: bool = False) -> SimResult:
    """Run scenario ``name`` (optionally with another ``controller`` by name); returns the :class:`SimResult`."""
    sc = get_scenario(name)
    if controller is not None and controller not in CONTROLLERS:
        raise UnknownNameError("controller", controller, tuple(CONTROLLERS))
    if law not in LAWS:
        raise UnknownNameError("transition law", law, LAWS)
    robot = load() if robot is None else robot
    cname = controller or sc.controller
    ctrl = make_controller(cname, robot, **(sc.controller_kwargs if controller is None else {}))
    if sc.bsg:
        ctrl = CogStabilizer(robot, ctrl, theta_e_d=sc.theta_e_d)
    dist = sc.disturbance() if sc.disturbance is not None else None
    return simulate(robot, ctrl, sc.trajectory(law), sc.duration if duration is None else duration, dt=dt,
                    integrator=integrator, disturbance=dist, seed=seed, progress=progress, scenario=name)


# ------------------------------------------------------------------------------ compare
TABLE_6_3 = {
    "idc": (2.2012e-3, 4.1015e-3, 4.2852e-3, 2.6788e-05, 5.5766e-05, 8.6008e-04, 1.0759e-05, 2.9757e-05, 5.5746e-05),
    "dsid": (1.4294e-04, 4.3873e-04, 6.2974e-04, 6.9541e-04, 4.1160e-04, 1.6472e-07, 1.0466e-04, 2.3679e-04, 2.5635e-04),
    "mfc": (4.9975e-04, 8.0141e-04, 1.2238e-3, 5.2551e-04, 1.3367e-3, 3.2451e-5, 5.9445e-06, 2.9722e-05, 8.9167e-05),
}
"""Thesis Table 6.3: RMSE (6.26) per variable (x, y, z [m], phi, theta, psi [rad], r0 [m],
theta2, theta3 [rad]) for IDC, "MPC" (our dsid) and MFC."""

THESIS_RUN_TIME_S = {"idc": 14 * 60.0, "dsid": 25 * 60.0, "mfc": 11 * 60.0}
"""Thesis run times T_x (Table 6.3 text: Matlab 2018, Intel Core i7 3.4 GHz): 14, 25, 11 min."""


@dataclass
class Comparison:
    """RMSE (6.26) of each controller on the static mission, with wall times, next to Table 6.3."""

    rmse: dict[str, dict[str, float]]
    wall_time: dict[str, float]
    status: dict[str, str]
    reason: dict[str, str]

    def table(self) -> str:
        """Text table shaped like Table 6.3 (rows: variables; columns: ours and the thesis's, per controller)."""
        ctrls = list(self.rmse)
        head = f"{'variable':<9}" + "".join(f"{c + ' (ours)':>13}{THESIS_NAMES[c] + ' (thesis)':>15}" for c in ctrls)
        lines = [head, "-" * len(head)]
        for i, var in enumerate(XI_NAMES):
            row = f"{var:<9}"
            for c in ctrls:
                ours = self.rmse[c].get(var, float("nan"))
                row += f"{ours:>13.3e}{TABLE_6_3[c][i]:>15.4e}"
            lines.append(row)
        lines.append("-" * len(head))
        row = f"{'time':<9}"
        for c in ctrls:
            row += f"{self.wall_time[c]:>12.3f}s{THESIS_RUN_TIME_S[c] / 60:>12.0f}min"
        lines.append(row)
        row = f"{'ratio':<9}"
        for c in ctrls:
            row += f"{'':>13}{THESIS_RUN_TIME_S[c] / self.wall_time[c]:>14.0f}x"
        lines.append(row)
        for c in ctrls:
            if self.status[c] != "ok":
                lines.append(f"{c}: {self.status[c]}: {self.reason[c]}")
        return "\n".join(lines)


def compare(*, robot: Robot | None = None, controllers=("idc", "dsid", "mfc"), duration: float = 30.0,
            dt: float = 1e-3, progress: bool = False) -> Comparison:
    """Run the three controllers on the static mission (Sec. 6.3.1.4) and collect RMSE and wall times."""
    from .errors import QprrError

    robot = load() if robot is None else robot
    rmse, wall, status, reason = {}, {}, {}, {}
    for c in controllers:
        if c not in CONTROLLERS:
            raise UnknownNameError("controller", c, tuple(CONTROLLERS))
        try:
            res = run(f"static-{c}", c, robot=robot, duration=duration, dt=dt, progress=progress)
        except QprrError as err:
            res = getattr(err, "result", None)
            if res is None:
                raise
        rmse[c], wall[c], status[c], reason[c] = res.rmse(), res.wall_time, res.status, res.reason
    return Comparison(rmse, wall, status, reason)


# ------------------------------------------------------------------------------ CLI
def _summary(res: SimResult) -> str:
    e = res.rmse()
    lines = [f"scenario {res.scenario}, controller {res.controller}: {res.status} ({res.reason}); "
             f"{res.n} steps of {res.dt * 1e3:g} ms in {res.wall_time:.3f} s",
             "RMSE (6.26): " + ", ".join(f"{k} {v:.3e}" for k, v in e.items()),
             f"rotor saturation on {100 * res.saturation_fraction():.2f} % of the steps; "
             f"max |x_cm| = {1e3 * np.max(np.abs(res.x_cm[:, 0])):.2f} mm"]
    return "\n".join(lines)


_RUN_OPTIONS = {"duration": None, "dt": 1e-3, "integrator": "midpoint", "seed": 0, "law": DEFAULT_LAW}


def _cmd_simulate(args: argparse.Namespace) -> int:
    from .errors import QprrError

    inter = _interaction()
    progress = not args.quiet and sys.stderr.isatty()
    given = {k: getattr(args, k) for k in _RUN_OPTIONS if getattr(args, k) is not None}
    try:
        if args.scenario in inter.SCENARIOS:
            valid = inter.CONTROLLERS[args.scenario]
            if args.controller is not None and args.controller not in valid:
                raise UnknownNameError("controller", args.controller, valid)
            if given:
                raise UnknownNameError("option for the Sec. 6.4 scenarios", "--" + next(iter(given)), ("--controller", "--plot", "--save"))
        else:
            get_scenario(args.scenario)
            if args.controller is not None and args.controller not in CONTROLLERS:
                raise UnknownNameError("controller", args.controller, tuple(CONTROLLERS))
    except UnknownNameError as err:
        if "scenario" == err.kind:
            err = UnknownNameError("scenario", args.scenario, tuple(SCENARIOS) + tuple(inter.SCENARIOS))
        print(f"qprr simulate: error: {err}", file=sys.stderr)
        return 2
    try:
        if args.scenario in inter.SCENARIOS:
            res = inter.SCENARIOS[args.scenario](args.controller, progress)
        else:
            res = run(args.scenario, args.controller, progress=progress, **{**_RUN_OPTIONS, **given})
        code = 0
    except QprrError as err:
        res = getattr(err, "result", None)
        if res is None:
            raise
        print(f"qprr simulate: {type(err).__name__}: {err}", file=sys.stderr)
        code = 1
    print(_summary(res))
    if args.scenario in inter.SCENARIOS and code == 0:
        print("\n".join(inter.summary(res)[1:]))
    if args.save:
        print(f"saved {res.save(args.save)}")
    if args.plot:
        if args.scenario in inter.SCENARIOS and code == 0:
            print(f"figure {inter.PLOTS[args.scenario](res, args.plot)}")
        else:
            from .plots import plot_result

            print(f"figure {plot_result(res, args.plot)}")
    return code


def _cmd_compare(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    cmp = compare(duration=args.duration, progress=not args.quiet and sys.stderr.isatty())
    print("RMSE (6.26) on the static-manipulator mission (Sec. 6.3.1.4), ours vs Thesis Table 6.3;")
    print("thesis columns: IDC, MPC (= our dsid), MFC; times: our wall time vs the thesis's T_x")
    print(cmp.table())
    print(f"total {time.perf_counter() - t0:.2f} s")
    return 0 if all(s == "ok" for s in cmp.status.values()) else 1


def _interaction():
    """The payload and interaction scenarios of Sec. 6.4 (qprr.interaction_scenarios)."""
    from . import interaction_scenarios

    return interaction_scenarios


def register_cli(subparsers) -> None:
    """Add ``simulate`` and ``compare`` to the ``qprr`` command line."""
    inter = _interaction()
    lines = [f"  {n:<15} {s.description} [{s.thesis}]" for n, s in SCENARIOS.items()]
    lines += [f"  {n:<15} {(fn.__doc__ or '').strip().splitlines()[0]} [Sec. 6.4; controllers: {', '.join(inter.CONTROLLERS[n])}]"
              for n, fn in inter.SCENARIOS.items()]
    names = list(SCENARIOS) + list(inter.SCENARIOS)
    p = subparsers.add_parser(
        "simulate", help="run a thesis flight scenario (prints RMSE; optional figure and .npz)",
        description="Run a named scenario of Thesis Chapter 6.\n\nscenarios:\n" + "\n".join(lines)
        + "\n\ncontrollers (Sec. 6.3 scenarios): " + ", ".join(f"{c} ({THESIS_NAMES[c]})" for c in CONTROLLERS),
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", help="one of: " + ", ".join(names))
    p.add_argument("--controller", default=None, help="override the scenario's controller (see the list above)")
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save a figure of the run")
    p.add_argument("--save", default=None, metavar="FILE.npz", help="save the logged run")
    p.add_argument("--duration", type=float, default=None, help="seconds (default: the scenario's, 30 s)")
    p.add_argument("--dt", type=float, default=None, help="step [s] (default 1e-3)")
    p.add_argument("--integrator", default=None, help="midpoint (default, 2nd order), rk4 or euler (semi-implicit)")
    p.add_argument("--seed", type=int, default=None, help="noise seed (default 0)")
    p.add_argument("--law", default=None, help="transition law: septic (default, minimum snap), quintic or thesis (printed (6.16))")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_simulate)
    p = subparsers.add_parser("compare", help="IDC vs desired-state ID ('MPC') vs MFC on the static mission: Table 6.3")
    p.add_argument("--duration", type=float, default=30.0, help="seconds (default 30)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_compare)


__all__ = ["Comparison", "SCENARIOS", "Scenario", "TABLE_6_3", "THESIS_RUN_TIME_S", "compare", "get_scenario",
           "register_cli", "run"]
