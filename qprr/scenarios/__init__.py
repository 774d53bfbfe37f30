"""Named, seeded simulation scenarios: one registry, the platform passed in.

A :class:`Scenario` bundles what a run needs (trajectory, controller, disturbances, contact
models) behind ``scenario.run(platform=None, controller=None, progress=False, **options)``.
:data:`SCENARIOS` (the registry :data:`qprr.registry.SCENARIOS`) holds the generic ones (any
platform), registered here, and those of plug-ins: the thesis's Chapter 6 ones
(:mod:`qprr.thesis.scenarios`, on the Q-PRR) arrive with the thesis plug-in the first time the
registry is listed or misses a name.  :func:`run` runs one by name.

=================  ===========================================================================
generic            what
=================  ===========================================================================
``hover-reach``    any platform: climb to 2 m, then move the arm to a reach posture; inverse
                   dynamics (or any controller of :mod:`qprr.control`)
``ee-impedance``   any platform: the end effector under operational-space impedance (Thesis
                   (6.72)-(6.73)) pressed into a compliant wall or pushed by a force step
                   (:mod:`qprr.scenarios.impedance`)
``takeoff-hover``  any platform, and the other missions of :mod:`qprr.scenarios.missions` (``fly-to``, ``mission``
``...``            given as data, ``grasp-drop``, ``ee-push``, ``hover-wind``, ``motor-lag``, ``hover-noise``,
                   ``hover-pulses``): gains derived from the platform (:mod:`qprr.control.gains`)
=================  ===========================================================================

The thesis's scenarios are listed by ``qprr simulate --help`` and :mod:`qprr.thesis.scenarios`.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from ..control import CONTROLLERS, make_controller
from ..errors import InputError, UnknownNameError
from ..model import Platform
from ..registry import SCENARIOS
from ..sim import INTEGRATORS, SimConfig, SimInputs, SimResult, simulate
from ..trajectory import DEFAULT_LAW, LAWS, hover_and_reach
from ..validation import as_bool


@dataclass(frozen=True)
class Option:
    """A scenario parameter settable by name (and from the command line): ``default`` gives its type.

    ``file``: the value may be a TOML file's path whose parsed content the scenario also takes (a campaign
    specification reads the file, relative to its own folder, and carries the content: its fingerprint then covers
    the file and its workers need no copy)."""

    default: object
    help: str
    file: bool = False


@dataclass(frozen=True)
class Scenario:
    """A named run: ``run(platform=None, controller=None, progress=False, **options) -> SimResult``.

    ``controllers``: its controller names (the first is the default; :meth:`controller_names` adds the registered
    controllers that name this scenario, :class:`qprr.control.ControllerEntry`); ``options``: the settable
    parameters with their defaults; ``platforms``: the platforms it runs on (None: any);
    ``plot``: ``(result, path) -> path`` drawing its figure; ``source``: the thesis section it
    reproduces ("" if none); ``summary``: extra report lines of a result; ``figures``: the
    thesis figure number of each panel of :func:`qprr.viz.plot_result` it reproduces (panel
    name -> "6.7"; the panel titles carry them); ``controller_in_data``: its data may name the controller (the
    mission file's ``[controller] name``): its runner gets ``controller=None`` when none is asked, and chooses.
    """

    name: str
    description: str
    runner: Callable[..., SimResult]
    controllers: tuple[str, ...]
    options: Mapping[str, Option] = field(default_factory=dict)
    platforms: tuple[str, ...] | None = None
    plot: Callable | None = None
    source: str = ""
    summary: Callable[[SimResult], list[str]] | None = None
    figures: Mapping[str, str] = field(default_factory=dict)
    controller_in_data: bool = False

    def controller_names(self) -> tuple[str, ...]:
        """The controllers it flies: its own :attr:`controllers` (the first the default), then every registered
        controller whose entry names this scenario (``ControllerEntry.scenarios``: a plug-in's controller flies a core
        scenario without an edit of it)."""
        more = tuple(n for n, e in CONTROLLERS.items() if self.name in e.scenarios and n not in self.controllers)
        return (*self.controllers, *more)

    @property
    def takes_plant(self) -> bool:
        """Whether the runner can fly a plant other than the controller's model (a ``plant`` argument)."""
        return "plant" in inspect.signature(self.runner).parameters

    @property
    def takes_settings(self) -> bool:
        """Whether the runner takes a settings object (``settings``: the generic missions' :class:`~qprr.scenarios.missions.MissionSettings`)."""
        return "settings" in inspect.signature(self.runner).parameters

    def run(
        self,
        platform: Platform | None = None,
        controller: str | None = None,
        progress: bool = False,
        plant: Platform | None = None,
        settings: object = None,
        **options,
    ) -> SimResult:
        """Run with ``options`` (unknown names raise :class:`UnknownNameError` listing the valid ones).

        ``plant``: fly another robot than the controller's model ``platform`` (model errors,
        :func:`qprr.sim.mismatch.perturbed`); only scenarios whose runner takes ``plant`` do
        (:attr:`takes_plant`).  ``settings``: what a Python caller sets beyond the options (the generic missions:
        a :class:`~qprr.scenarios.missions.MissionSettings`); only scenarios whose runner takes it do
        (:attr:`takes_settings`)."""
        for key in options:
            if key not in self.options:
                raise UnknownNameError(f"option of scenario {self.name!r}", key, tuple(self.options))
        if controller is not None and controller not in self.controller_names():
            raise UnknownNameError(f"controller of scenario {self.name!r}", controller, self.controller_names())
        if platform is not None and not isinstance(platform, Platform):
            raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
        values = {k: o.default for k, o in self.options.items()}
        values.update(options)
        for key in options:
            if isinstance(self.options[key].default, bool):  # a flag: "no", "false", 0 are False, never a truthy text
                values[key] = as_bool(options[key], f"option {key!r} of scenario {self.name!r}")
        if "law" in values and values["law"] not in LAWS:  # checked here: a trajectory may not use it (the spiral)
            raise UnknownNameError("transition law", values["law"], LAWS)
        if plant is not None:
            if not self.takes_plant:
                raise InputError(
                    f"scenario {self.name!r} flies its model: it takes no plant (model errors); "
                    f"scenarios that do: {', '.join(n for n, s in SCENARIOS.items() if s.takes_plant)}"
                )
            values["plant"] = plant
        if settings is not None:
            if not self.takes_settings:
                raise InputError(
                    f"scenario {self.name!r} takes no settings object; scenarios that do: "
                    f"{', '.join(n for n, s in SCENARIOS.items() if s.takes_settings)}"
                )
            values["settings"] = settings
        chosen = controller if self.controller_in_data else (controller or self.controllers[0])
        return self.runner(platform=platform, controller=chosen, progress=progress, **values)


# ------------------------------------------------------------------------- generic scenarios
COMMON_OPTIONS = {
    "duration": Option(10.0, "run length [s]"),
    "dt": Option(SimConfig.dt, "integration step [s]"),
    "integrator": Option(INTEGRATORS.default, "a name of qprr.sim.INTEGRATORS: midpoint (2nd order), rk4, euler (semi-implicit), a plug-in's"),
    "seed": Option(0, "noise seed"),
    "law": Option(DEFAULT_LAW, f"transition law: {', '.join(LAWS)}"),
}
"""Options every flight scenario takes."""


GAINS_OPTION = Option(
    "platform",
    "gain set: platform (derived from its mass, inertia and actuators: qprr.control.gains), "
    "class (the controller's own defaults), a registered gain table, FILE.toml, "
    "or its tables inline (a campaign's gains = { targets = { integral = true } })",
)
"""The ``gains`` option of the missions (:func:`qprr.scenarios.missions.controller_for`)."""


def _hover_reach(platform, controller, progress, plant=None, **o):
    from ..platforms import load
    from .missions import controller_for, reach_posture

    platform = load() if platform is None else platform
    q_arm = reach_posture(platform, o["reach_fraction"])
    trajectory = hover_and_reach(platform, (0.0, 0.0, o["z"]), q_arm, law=o["law"])
    # "platform": make_controller's own default (derived gains; a controller they do not cover, e.g. mpc, its class's)
    ctrl = make_controller(controller, platform) if o["gains"] == "platform" else controller_for(controller, platform, o["gains"])
    config = SimConfig(dt=o["dt"], integrator=o["integrator"], seed=o["seed"], progress=progress, scenario="hover-reach")
    return simulate(platform, ctrl, trajectory, o["duration"], config=config, inputs=SimInputs(plant=plant))


def _ee_impedance(platform, controller, progress, **options):
    from .impedance import run_ee_impedance

    return run_ee_impedance(platform, controller, progress, **options)


def _ee_impedance_plot(result, path):
    from .impedance import plot_ee_impedance

    return plot_ee_impedance(result, path)


def _ee_impedance_summary(result):
    from .impedance import ee_impedance_summary

    return ee_impedance_summary(result)


GENERIC = (
    Scenario(
        "hover-reach",
        "any platform: climb to z, then move every arm joint towards its upper limit",
        _hover_reach,
        ("idc", "dsid", "mfc", "decoupled", "mpc"),
        {
            **COMMON_OPTIONS,
            "gains": GAINS_OPTION,
            "z": Option(2.0, "hover height [m]"),
            "reach_fraction": Option(0.6, "fraction of the way from the neutral posture to the upper joint limits"),
        },
    ),
    Scenario(
        "ee-impedance",
        "any platform: end-effector impedance (6.72)-(6.73) against a compliant wall or a force step",
        _ee_impedance,
        ("opspace-impedance", "idc"),
        {
            "contact": Option("wall", "wall (reference pressed 'penetration' into a wall 'gap' ahead) or wrench (force step)"),
            "duration": Option(10.0, "run length [s]"),
            "dt": Option(SimConfig.dt, "integration step [s]"),
            "integrator": COMMON_OPTIONS["integrator"],
            "seed": Option(0, "seed"),
            "z": Option(2.0, "hover height [m]"),
            "reach_fraction": Option(0.3, "arm posture: fraction of the way from neutral to the upper joint limits"),
            "omega_n": Option(4.0, "impedance natural frequency [rad/s] (every axis)"),
            "zeta": Option(1.0, "impedance damping ratio"),
            "mass": Option(1.0, "impedance mass M_d [kg]"),
            "gap": Option(0.05, "wall: distance from the end effector to the wall at the start [m]"),
            "penetration": Option(0.05, "wall: how far the reference ends inside the wall [m]"),
            "wall_stiffness": Option(2000.0, "wall stiffness [N/m]"),
            "wall_damping": Option(20.0, "wall damping [N s/m]"),
            "force": Option((0.5, 0.0, 0.3), "wrench: force on the end effector [N], world x, y, z"),
            "t_on": Option(1.0, "wall: approach starts; wrench: force on [s]"),
            "t_off": Option(6.0, "wall: retreat starts; wrench: force off [s]"),
        },
        None,
        _ee_impedance_plot,
        "Sec. 6.4.3.3, (6.71)-(6.73)",
        _ee_impedance_summary,
    ),
)


def _mission_runner(name: str) -> Callable[..., SimResult]:
    """A runner of :mod:`qprr.scenarios.missions` (imported on first use); ``plant``: the robot flown when it differs from the
    controller's model (model errors of a campaign, :func:`qprr.sim.mismatch.perturbed`), on any platform; ``settings``:
    a :class:`~qprr.scenarios.missions.MissionSettings` (``scenarios.run(name, settings=...)``)."""

    def runner(platform, controller, progress, plant=None, settings=None, **options):
        from dataclasses import replace

        from . import missions

        if settings is None:
            settings = missions.MissionSettings(plant=plant)
        elif not isinstance(settings, missions.MissionSettings):
            raise InputError(f"settings of scenario {name!r} must be a qprr.scenarios.missions.MissionSettings, got {type(settings).__name__}")
        elif plant is not None:
            if settings.plant is not None:
                raise InputError("the plant is given twice (plant= and MissionSettings.plant): give it once")
            settings = replace(settings, plant=plant)
        return getattr(missions, name)(platform, controller, progress, settings=settings, **options)

    runner.__name__ = name
    return runner


def _mission_summary(result: SimResult) -> list[str]:
    from .missions import mission_summary

    return mission_summary(result)


_FLIGHT = ("idc", "dsid", "decoupled")
PAYLOAD_OPTION = Option(
    "unknown",
    "what the controller's model knows of a payload: unknown (integral action rejects it), announced (the mission's "
    "payload events), estimate (online mass estimate, Thesis Sec. 6.4.2); qprr.scenarios.missions.PAYLOAD_MODELS",
)
"""The ``payload_model`` option of the generic missions (:func:`qprr.scenarios.missions.payload_awareness`)."""
_HOVER = {
    **COMMON_OPTIONS,
    "gains": GAINS_OPTION,
    "payload_model": PAYLOAD_OPTION,
    "z": Option(2.0, "hover height [m]"),
    "reach_fraction": Option(0.3, "arm posture: fraction of the way from neutral to the upper joint limits"),
}
_MOVE = {
    **_HOVER,
    "target": Option((1.0, 0.5, 2.0), "base position to reach [m], world x, y, z"),
    "reach_fraction": Option(0.6, "arm target: fraction of the way from neutral to the upper joint limits"),
}
del _MOVE["z"]

MISSIONS = (
    Scenario(
        "takeoff-hover",
        "any platform: climb from the ground to z in the first 40 % of the run, hold",
        _mission_runner("takeoff_hover"),
        _FLIGHT,
        {k: v for k, v in _HOVER.items() if k != "reach_fraction"},
        summary=_mission_summary,
    ),
    Scenario(
        "fly-to",
        "any platform: climb, fly to target while the arm reaches out, hold",
        _mission_runner("fly_to"),
        _FLIGHT,
        _MOVE,
        summary=_mission_summary,
    ),
    Scenario(
        "mission",
        "any platform: phases of base and arm coordinates by name from a TOML file (payload grasp/release too)",
        _mission_runner("mission"),
        _FLIGHT,
        {
            **COMMON_OPTIONS,
            "gains": GAINS_OPTION,
            "payload_model": PAYLOAD_OPTION,
            "mission": Option(
                "",
                "FILE.toml of [[phase]] (coordinate, start, end, target) and [[payload]] (time, mass) tables, and optionally [wind], "
                "[[gust]], [drag], [motor], [controller] (qprr.scenarios.mission_file); empty: climb, fly 1 m, reach out",
                file=True,
            ),
        },
        summary=_mission_summary,
        controller_in_data=True,
    ),
    Scenario(
        "grasp-drop",
        "any platform: a mass grasped at the end effector at 25 % of the run, dropped at 55 %",
        _mission_runner("grasp_drop"),
        ("idc", "payload-idc"),
        {**_HOVER, "mass_fraction": Option(0.1, "payload mass as a fraction of the platform's mass")},
        summary=_mission_summary,
    ),
    Scenario(
        "ee-push",
        "any platform: the end effector pushed into a compliant wall under impedance, held",
        _mission_runner("push"),
        ("opspace-impedance", "idc"),
        {
            **{k: v for k, v in _HOVER.items() if k != "payload_model"},  # its controller reads the wall's sensor, not a payload
            "gap": Option(0.05, "distance from the end effector to the wall at the start [m]"),
            "penetration": Option(0.05, "how far the reference ends inside the wall [m]"),
            "wall_stiffness": Option(2000.0, "wall stiffness [N/m]"),
            "wall_damping": Option(20.0, "wall damping [N s/m]"),
        },
        summary=_mission_summary,
    ),
    Scenario(
        "hover-wind",
        "any platform: hover in a mean wind with a 1 - cos gust (base drag)",
        _mission_runner("hover_wind"),
        _FLIGHT,
        {
            **_HOVER,
            "mean_wind": Option((2.0, 0.0, 0.0), "mean wind [m/s], world x, y, z"),
            "gust": Option((3.0, 1.0, 0.0), "gust peak [m/s], world x, y, z"),
            "drag": Option(0.3, "linear drag coefficient of the base [N s/m]"),
        },
        summary=_mission_summary,
    ),
    Scenario(
        "motor-lag",
        "any platform: point-to-point at height through first-order rotor dynamics",
        _mission_runner("motor_lag"),
        _FLIGHT,
        {
            **_MOVE,
            "tau": Option(0.0, "rotor time constant [s]; 0: the rotor file's [motor] time_constant, else 0.005"),
            "thrust_factor": Option(0.0, "rotor thrust factor b [N s^2] (f = b w^2); 0: the rotor file's [motor] thrust_factor, else 1e-5"),
        },
        summary=_mission_summary,
    ),
    Scenario(
        "hover-noise",
        "any platform: hover under white noise on every generalised force (6.27)",
        _mission_runner("noise"),
        _FLIGHT,
        {**_HOVER, "fraction": Option(0.02, "noise amplitude: fraction of each coordinate's actuator authority")},
        summary=_mission_summary,
    ),
    Scenario(
        "hover-pulses",
        "any platform: hover hit by force pulses on z, x and y, then the arm (6.28)",
        _mission_runner("pulses"),
        _FLIGHT,
        {**_HOVER, "force": Option(2.0, "pulse on the base forces [N]"), "torque": Option(0.05, "pulse on the arm efforts [N m or N]")},
        summary=_mission_summary,
    ),
)
"""The generic missions of :mod:`qprr.scenarios.missions` (any platform, gains derived from it)."""


for _scenario in GENERIC + MISSIONS:
    SCENARIOS.register(_scenario.name, _scenario)
del _scenario


def get_scenario(name: str) -> Scenario:
    """The scenario called ``name``; :class:`UnknownNameError` lists the valid ones."""
    return SCENARIOS[name]


def run(
    name: str, controller: str | None = None, *, platform: Platform | None = None, progress: bool = False, settings: object = None, **options
) -> SimResult:
    """Run scenario ``name`` (optionally with another ``controller`` by name and on another ``platform``); ``settings``:
    its settings object (the generic missions: a :class:`~qprr.scenarios.missions.MissionSettings`), :meth:`Scenario.run`."""
    return get_scenario(name).run(platform=platform, controller=controller, progress=progress, settings=settings, **options)


__all__ = ["COMMON_OPTIONS", "GAINS_OPTION", "GENERIC", "MISSIONS", "PAYLOAD_OPTION", "SCENARIOS", "Option", "Scenario", "get_scenario", "run"]
