"""The scenarios of Thesis Chapter 6 on the Q-PRR, registered in :data:`qprr.scenarios.SCENARIOS`.

=================  =========================================================================
name               what it runs
=================  =========================================================================
``static-idc``     Sec. 6.3.1.4: xi_d = [3, 6, 10, psi = 0, 0.04, 0.2, 0.6], climb z 0-5 s,
                   x 5-10 s, y 10-15 s, arm 15-25 s, inverse-dynamics control (IDC)
``static-dsid``    the same with desired-state inverse dynamics (the thesis's "MPC", Annex A.2)
``static-mfc``     the same with model-free control (iPID, Sec. 6.3.3.2)
``spiral``         climb, then the spiral (6.25) from t_f = 5 s, IDC
``noise``          static mission + white noise on the generalised forces (6.27), IDC
``pulses``         static mission + finite pulses (6.28) in the three phases, IDC
``dynamic-bsg``    Sec. 6.3.3.3: same flight, theta2_d = -0.5, theta_e^d = 0, CoG stabiliser
                   (BSG) + MFC keeping x_cm near 0
``payload-drop``   Sec. 6.4.2.3: carry 0.1 kg, release it at 18 s (payload IDC)
``push-thrust``    Sec. 6.4.3.1: push an object with the thrust, arm locked
``push-prismatic`` Sec. 6.4.3.2: push an object with the slider
``impedance``      Sec. 6.4.3.4: interaction forces on a hovering Q-PRR, impedance control
=================  =========================================================================

Every scenario is reproducible (noise seeded); the Sec. 6.3 ones last 30 s at 1 kHz by
default.  The transition law is the minimum-snap septic (``law="septic"``): jerk-continuous
references, which a multirotor's tilt needs (docs/notes-spikes.md).  ``law="quintic"`` is the
order-5 polynomial the text names and ``law="thesis"`` the rational formula printed as (6.16)
(a 1.55 g deceleration on the 10 m climb: the rotors saturate at zero thrust).

Built on the generic missions of :mod:`qprr.scenarios.missions` (any platform) with the thesis's settings
(bit-identical to the scenarios' earlier own machinery; tests/test_thesis_thin.py):

==================  ==========================================================================
thesis scenario     generic scenario + the thesis's settings (:class:`Instance`)
==================  ==========================================================================
``static-*``        ``mission``: Sec. 6.3.1.4 as data (:data:`~qprr.thesis.missions.STATIC_MISSION`),
                    gains :func:`flight_gains` (``q-prr:idc``, ``q-prr:desired-state``, ``q-prr:mfc``)
``spiral``          ``mission`` flying the spiral (6.25) given as the reference
``noise``           ``hover-noise`` along the static mission, amplitudes :data:`NOISE_AMPLITUDE`
``pulses``          ``hover-pulses`` along the static mission, the train :data:`PULSES`
``dynamic-bsg``     ``mission``: Sec. 6.3.3.3 as data, the controller under the CoG stabiliser
``payload-drop``    ``mission``: the flight and the payload events (carry ``mass``, release) as data,
                    the payload controllers of Sec. 6.4.2, the noise and the plant
==================  ==========================================================================

No generic counterpart, on :func:`qprr.sim.simulate` directly: ``push-thrust`` and ``push-prismatic``
push a free object (a mass with Coulomb friction on its line, :class:`qprr.sim.PushedMass`; the contact
opens when the robot decelerates) under the layered IDC with wrist force feedback, where ``ee-push``
presses into a fixed compliant wall under operational-space impedance: another experiment.
``impedance`` applies prescribed wrenches on the base (x, y, z, psi) and at the end effector, measured
exactly, to the joint-space impedance filters (6.68)-(6.81); ``ee-impedance`` is the operational-space
law (6.72)-(6.73) with one end-effector wrench and no base wrench.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from enum import Enum
from pathlib import Path

import numpy as np

from .. import kinematics as kin
from ..charts import euler_to_rotation_batch, force_to_xi_batch
from ..control import (
    DecoupledController,
    InverseDynamicsController,
    LayeredIDC,
    PayloadIDC,
    make_controller,
)
from ..control.impedance import ImpedanceController, ImpedanceGains
from ..errors import InputError, QprrError, ScheduleWarning, UnknownNameError
from ..scenarios import COMMON_OPTIONS, Option, Scenario
from ..scenarios import missions as generic
from ..sim import (
    PrescribedWrench,
    Pulse,
    PushedMass,
    SimConfig,
    SimInputs,
    SimResult,
    Status,
    WhiteNoise,
    simulate,
)
from ..trajectory import DEFAULT_LAW, Hold, MultiPhase, Phase, Spiral
from ..validation import as_interval, as_name, as_real, as_settings, as_vector, check_fields, checked_module
from ..viz import plot_result
from ..viz.plots import REFERENCE_STYLE, Panel, applied_forces, legend, length_unit, robust_limits, time_axis
from . import gains
from .bsg import CogStabilizer
from .missions import DYNAMIC_MISSION, NAMES, STATIC_MISSION, static_mission
from .robot import load_qprr, params_of

SEED = 0

THESIS_NAMES = {"idc": "IDC", "dsid": "MPC", "mfc": "MFC"}
"""What the thesis calls each controller (Table 6.3 columns)."""

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


AS_PRINTED_UNSTABLE = (
    "Table 6.2's attitude PIDs fail Routh-Hurwitz as printed (k_D k_P < k_I on all three angles; flown as printed the "
    "static mission diverges at t = 29.4 s): there are no stable as-printed settings for {name}; run without "
    "--thesis-as-printed (its (s + 10)^3 attitude retuning, docs/control.md, 'Table 6.3 cell by cell')"
)


FLIGHT_GAINS = {"idc": gains.idc, "dsid": gains.desired_state, "mfc": gains.mfc, "decoupled": gains.idc}
"""The thesis's gain set of each Sec. 6.3 flight controller (:mod:`qprr.thesis.gains`): Table 6.2 retuned for IDC and
the decoupled scheme, (A.3) with the 6.2 attitude retuning for the desired-state controller, the iPID's for the MFC."""


def flight_gains(name: str, as_printed: bool = False):
    """The gains (:data:`FLIGHT_GAINS`, or the as-printed ones) the Sec. 6.3 flights give controller ``name``: a gains
    object for :func:`qprr.scenarios.missions.controller_for` ("class" for the MPC, not the thesis's: its own defaults).

    ``as_printed``: the thesis's settings as printed where they are stable: the desired-state controller with the
    position K_D = 18 of (A.3); the MFC's gains are those printed already.  IDC and the decoupled scheme have none
    (:data:`AS_PRINTED_UNSTABLE`), and the MPC is not the thesis's: both raise :class:`~qprr.errors.InputError`."""
    if as_printed:
        if name in ("idc", "decoupled"):
            raise InputError(AS_PRINTED_UNSTABLE.format(name=name))
        if name == "mpc":
            raise InputError("the receding-horizon MPC is not the thesis's controller (its 'MPC' is dsid): no as-printed settings")
        if name == "dsid":
            return gains.desired_state_as_printed()
    if name == "mpc":
        return "class"
    if name not in FLIGHT_GAINS:
        raise UnknownNameError("controller", name, _FLIGHT_CONTROLLERS)
    return FLIGHT_GAINS[name]()


def flight_controller(name: str, platform, as_printed: bool = False):
    """The Sec. 6.3 controllers with the thesis's gains (:func:`flight_gains`), the decoupled scheme of Sec. 6.2.2
    at the IDC's gains, and the receding-horizon MPC (``mpc``, needs crocoddyl)."""
    return generic.controller_for(name, platform, flight_gains(name, as_printed))


def _q_prr(platform):
    platform = load_qprr() if platform is None else platform
    params_of(platform)  # a thesis scenario needs the Q-PRR
    return platform


@dataclass(frozen=True)
class Instance:
    """A thesis flight as an instance of a generic mission of :mod:`qprr.scenarios.missions`: ``generic`` (``mission``, ``noise``,
    ``pulses``) called with the thesis's ``settings`` (options and keywords: the mission as data, noise amplitudes,
    the pulse train) and, when not phases, the ``reference`` flown (law -> trajectory, :class:`~qprr.scenarios.missions.MissionSettings`)."""

    generic: Callable
    settings: Mapping[str, object]
    reference: Callable[[str], object] | None = None


@dataclass(frozen=True)
class FlightSettings:
    """The options of a Sec. 6.3 flight (defaults and help: the scenario's :attr:`~qprr.scenarios.Scenario.options`):
    run ``duration`` [s], integration step ``dt`` [s], ``integrator``, ``seed``, transition ``law`` and ``as_printed``
    (the ``static-*`` flights only; False for the others, which have no such option)."""

    duration: float
    dt: float
    integrator: str
    seed: int
    law: str
    as_printed: bool = False


def _flight(scenario: str, instance: Instance, bsg: bool = False):
    """The runner of a Sec. 6.3 flight: ``instance`` with the thesis's gains (:func:`flight_gains`), under the CoG
    stabiliser (BSG) if ``bsg``, named ``scenario``.  The options :meth:`Scenario.run <qprr.scenarios.Scenario.run>`
    passes by name are gathered into :class:`FlightSettings`; ``plant`` stays a parameter of the runner
    (:attr:`~qprr.scenarios.Scenario.takes_plant` reads it from the signature)."""

    def runner(platform, controller, progress, plant=None, **values):
        o = FlightSettings(**values)
        platform = _q_prr(platform)
        law = o.law
        if o.as_printed:  # the transition law (6.16) as printed: the quintic
            if law not in (DEFAULT_LAW, "quintic"):
                raise InputError(f"as_printed flies the quintic law (6.16) as printed; law = {law!r} contradicts it")
            law = "quintic"
        g = flight_gains(controller, o.as_printed)
        ctrl = CogStabilizer(platform, generic.controller_for(controller, platform, g), theta_e_d=0.0) if bsg else None
        reference = instance.reference(law) if instance.reference is not None else None
        settings = generic.MissionSettings(trajectory=reference, controller=ctrl, plant=plant, name=scenario)
        options = {"duration": o.duration, "dt": o.dt, "integrator": o.integrator, "seed": o.seed, "law": law, "gains": g}
        with warnings.catch_warnings():  # a thesis flight shorter than its mission flies its first seconds on purpose
            warnings.simplefilter("ignore", ScheduleWarning)
            return instance.generic(platform, controller, progress, settings, **options, **instance.settings)

    return runner


STATIC = Instance(generic.mission, {"mission": STATIC_MISSION})
"""``static-*``: the generic ``mission`` given the mission of Sec. 6.3.1.4 as data."""
SPIRAL = Instance(generic.mission, {"mission": ""}, lambda law: Spiral())
"""``spiral``: the generic ``mission`` flying the spiral (6.25) (not phases: the reference is given)."""
NOISE = Instance(generic.noise, {"amplitude": NOISE_AMPLITUDE}, lambda law: static_mission(law=law))
"""``noise``: the generic ``hover-noise`` with the amplitudes :data:`NOISE_AMPLITUDE`, along the static mission."""
PULSE_TRAIN = Instance(generic.pulses, {"train": PULSES}, lambda law: static_mission(law=law))
"""``pulses``: the generic ``hover-pulses`` with the pulses :data:`PULSES`, along the static mission."""
DYNAMIC = Instance(generic.mission, {"mission": DYNAMIC_MISSION})
"""``dynamic-bsg``: the generic ``mission`` given the mission of Sec. 6.3.3.3 as data (under the BSG)."""


_FLIGHT = {**COMMON_OPTIONS, "duration": Option(30.0, "run length [s]")}
_STATIC = {
    **_FLIGHT,
    "as_printed": Option(False, "the thesis's settings as printed where stable: quintic law (6.16), dsid K_D = 18 of (A.3) (idc: refused, unstable)"),
}
_FLIGHT_CONTROLLERS = ("idc", "dsid", "mfc", "decoupled", "mpc")
"""Controllers of the Sec. 6.3 flight scenarios: the thesis's three, the decoupled scheme (Sec. 6.2.2) and the MPC."""


def _reordered(first: str) -> tuple[str, ...]:
    return (first, *[c for c in _FLIGHT_CONTROLLERS if c != first])


_BSG_CONTROLLERS = ("mfc", "idc", "dsid", "decoupled")
"""Controllers under the CoG stabiliser (the MPC has its own CoG cost and previews the trajectory, not the BSG's references)."""


def _plot_flight(result: SimResult, path) -> Path:
    """The Chapter 6.3 page of a flight scenario (its panels titled with the thesis's figure numbers, :data:`FIGURES`)."""
    return plot_result(result, path)


FLIGHT_SCENARIOS = (
    Scenario(
        "static-idc",
        "static manipulator mission, inverse-dynamics control",
        _flight("static-idc", STATIC),
        _reordered("idc"),
        _STATIC,
        ("q-prr",),
        _plot_flight,
        "Sec. 6.3.1.4, Table 6.3 IDC, Fig. 6.7-6.13",
    ),
    Scenario(
        "static-dsid",
        "static manipulator mission, desired-state inverse dynamics (thesis: MPC)",
        _flight("static-dsid", STATIC),
        _reordered("dsid"),
        _STATIC,
        ("q-prr",),
        _plot_flight,
        "Annex A.2, Table 6.3 MPC, Fig. 6.19-6.21",
    ),
    Scenario(
        "static-mfc",
        "static manipulator mission, model-free control (iPID)",
        _flight("static-mfc", STATIC),
        _reordered("mfc"),
        _STATIC,
        ("q-prr",),
        _plot_flight,
        "Sec. 6.3.3.2, Table 6.3 MFC, Fig. 6.19-6.21",
    ),
    Scenario(
        "spiral",
        "climb then spiral (6.25) from t_f = 5 s, IDC",
        _flight("spiral", SPIRAL),
        _reordered("idc"),
        _FLIGHT,
        ("q-prr",),
        _plot_flight,
        "Sec. 6.3.1.4, (6.25), Fig. 6.14-6.18",
    ),
    Scenario(
        "noise",
        "static mission with white noise on the generalised forces, IDC",
        _flight("noise", NOISE),
        _reordered("idc"),
        _FLIGHT,
        ("q-prr",),
        _plot_flight,
        "Sec. 6.3.2.1, (6.27), Fig. 6.23-6.27",
    ),
    Scenario(
        "pulses",
        "static mission with finite pulses in the three phases, IDC",
        _flight("pulses", PULSE_TRAIN),
        _reordered("idc"),
        _FLIGHT,
        ("q-prr",),
        _plot_flight,
        "Sec. 6.3.2.2, (6.28), Fig. 6.28-6.29",
    ),
    Scenario(
        "dynamic-bsg",
        "dynamic manipulator: theta2_d = -0.5, theta_e^d = 0, BSG + MFC keep x_cm near 0",
        _flight("dynamic-bsg", DYNAMIC, bsg=True),
        _BSG_CONTROLLERS,
        _FLIGHT,
        ("q-prr",),
        _plot_flight,
        "Sec. 6.3.3.3, Fig. 6.37-6.45",
    ),
)


# ======================================================================= Sec. 6.4: helpers
def _ee_world(platform, xi) -> np.ndarray:
    p, _ = kin.ee_pose_xi(platform, platform.data(), xi)
    return p


class RecoveryStatus(str, Enum):
    """Whether the robot returned to the no-payload hover within the run (:attr:`Recovery.status`, equal to its string)."""

    RECOVERED = "recovered"
    NOT_RECOVERED = "not recovered"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Recovery:
    """Time to return to the no-payload hover after a release.

    ``time`` [s] after ``release_time``: from then on every |p_d - p| <= ``tol_position``
    (x, y, z and r0, m), every |q_d - q| <= ``tol_angle`` (theta2, theta3, psi, rad) and the
    total thrust is within ``tol_thrust`` (relative) of the no-payload weight m g / (c_phi c_theta).
    ``status`` (:class:`RecoveryStatus`) "recovered" or "not recovered" (within the run); ``peak_*`` the largest
    deviations after the release.
    """

    release_time: float
    time: float
    tol_position: float
    tol_angle: float
    tol_thrust: float
    peak_position: float
    peak_angle: float
    peak_thrust: float
    status: RecoveryStatus
    reason: str


def recovery(
    result: SimResult,
    release_time: float,
    total_mass: float,
    g: float,
    *,
    tol_position: float = 1e-3,
    tol_angle: float = 1e-3,
    tol_thrust: float = 0.01,
) -> Recovery:
    """Measure :class:`Recovery` on a logged run (no-payload weight ``total_mass`` g)."""
    t = result.t
    after = t >= release_time
    e = np.abs(result.xi_d - result.xi)
    pos = e[:, [0, 1, 2, 6]].max(axis=1)
    ang = e[:, [5, 7, 8]].max(axis=1)
    tilt = np.cos(result.xi[:, 3]) * np.cos(result.xi[:, 4])
    thrust = np.abs(result.f.sum(axis=1) * tilt / (total_mass * g) - 1.0)
    ok = (pos <= tol_position) & (ang <= tol_angle) & (thrust <= tol_thrust)
    idx = np.nonzero(after)[0]
    bad = idx[~ok[idx]]
    peaks = (float(pos[after].max()), float(ang[after].max()), float(thrust[after].max()))
    if bad.size == 0:
        return Recovery(release_time, 0.0, tol_position, tol_angle, tol_thrust, *peaks, RecoveryStatus.RECOVERED, "within tolerance at the release")
    last = bad[-1]
    if last == idx[-1]:
        return Recovery(
            release_time,
            math.inf,
            tol_position,
            tol_angle,
            tol_thrust,
            *peaks,
            RecoveryStatus.NOT_RECOVERED,
            f"still out of tolerance at the end of the run (t = {t[last]:.3f} s)",
        )
    return Recovery(
        release_time,
        float(t[last + 1] - release_time),
        tol_position,
        tol_angle,
        tol_thrust,
        *peaks,
        RecoveryStatus.RECOVERED,
        "every tolerance holds from then to the end of the run",
    )


def applied_generalized_forces(result: SimResult, platform=None) -> np.ndarray:
    """u = S^T N f (m, 9) actually applied (thesis coordinates): u_fb world thrust, u_tau Euler torques, arm efforts."""
    platform = _q_prr(platform)
    tau = np.hstack([result.f @ np.asarray(platform.rotor_matrix).T, result.arm_effort])
    return force_to_xi_batch(euler_to_rotation_batch(result.xi[:, 3:6]), result.xi, tau)


def _contact_series(res: SimResult, obj) -> None:
    c = obj.history()
    res.series.update(
        {
            "contact_t": c.t,
            "contact_force": c.force,
            "contact_wrench": c.wrench,
            "contact_position": c.position,
            "contact_velocity": c.velocity,
            "contact_penetration": c.penetration,
        }
    )


def contact_history(result: SimResult):
    """The :class:`qprr.sim.ContactHistory` a push scenario logged in ``result.series``."""
    from ..sim import ContactHistory

    s = result.series
    return ContactHistory(
        s["contact_t"], s["contact_force"], s["contact_wrench"], s["contact_position"], s["contact_velocity"], s["contact_penetration"]
    )


# ============================================================================ payload-drop
PAYLOAD_CONTROLLERS = ("payload-idc", "payload-idc-known", "payload-idc-none", "idc", "decoupled", "mpc")


def _payload_controller(name: str, platform, mass: float, release_time: float):
    """The controller ``name`` of :data:`PAYLOAD_CONTROLLERS` with the thesis's gains (:func:`payload_drop`)."""

    class _Told(PayloadIDC):
        def step(self, t, state, ref):
            if t >= release_time:
                self.set_known_mass(0.0)
            return super().step(t, state, ref)

    g = gains.payload_idc()
    builders = {
        "payload-idc": lambda: PayloadIDC(platform, g, payload="estimate"),
        "payload-idc-known": lambda: _Told(platform, g, payload="known", known_mass=mass),
        "payload-idc-none": lambda: PayloadIDC(platform, g, payload="none"),
        "idc": lambda: InverseDynamicsController(platform, gains.idc()),
        "decoupled": lambda: DecoupledController(platform, gains.idc()),
        "mpc": lambda: make_controller("mpc", platform),
    }
    if name not in builders:
        raise UnknownNameError("controller", name, PAYLOAD_CONTROLLERS)
    return builders[name]()


@dataclass(frozen=True)
class PayloadDropSettings:
    """The options of ``payload-drop`` (:func:`payload_drop`): the payload ``mass`` [kg], its ``release_time`` [s],
    the run's ``duration`` [s], the ``mission`` ("thesis" or "hover"), the arm's ``arm_target`` (r0, theta2, theta3)
    reached during ``arm_phase`` (start, end) [s], the white-``noise`` amplitude [N] and the ``seed``."""

    mass: float = 0.1
    release_time: float = 18.0
    duration: float = 25.0
    mission: str = "thesis"
    arm_target: tuple[float, float, float] = (-0.04, 0.3, 0.5)
    arm_phase: tuple[float, float] = (15.0, 17.0)
    noise: float = 0.0
    seed: int = SEED

    def __post_init__(self) -> None:
        check_fields(self)
        as_real(self.duration, "duration", positive=True, unit="s")
        as_real(self.mass, "mass", nonnegative=True, unit="kg")
        as_name(self.mission, "mission", ("thesis", "hover"))
        object.__setattr__(self, "arm_target", tuple(as_vector(self.arm_target, 3, "arm_target").tolist()))
        object.__setattr__(self, "arm_phase", as_interval(self.arm_phase, "arm_phase", lo=0.0))


def payload_drop(
    platform=None, controller: str = "payload-idc", progress: bool = False, settings: PayloadDropSettings | None = None, plant=None
) -> SimResult:
    """Carry ``mass`` at the end effector and release it at ``release_time`` (Thesis Sec. 6.4.2.3; the fields of
    ``settings``, a :class:`PayloadDropSettings`).

    ``mission="thesis"``: climb/x/y flight of Sec. 6.3.1.4 to (3, 6, 10) m, arm to ``arm_target``
    during ``arm_phase``; ``mission="hover"``: start hovering at (0, 0, 1) m with the arm already
    at ``arm_target`` (short runs for tests).  Controllers: "payload-idc" (mass estimated,
    default), "payload-idc-known" (known mass, told of the release), "payload-idc-none",
    "idc" (Sec. 6.3.1, nominal model), "decoupled" (Sec. 6.2.2, nominal model) and "mpc" (receding horizon,
    nominal model: the payload is a disturbance to all three).  ``noise`` > 0 adds the white noise of Thesis (6.27),
    uniform in [-noise, noise] N, on the three forces (seeded by ``seed``).  The result's
    ``series`` hold ``payload_mass`` and ``mass_estimate``; its ``metrics`` the ``release_time``,
    the ``recovery_time`` (:class:`Recovery`) and ``mass_estimate_error``.  ``plant``: the robot
    flown when it differs from the controllers' model ``platform`` (:func:`qprr.sim.simulate`).
    """
    o = as_settings(settings, PayloadDropSettings)
    mass, release_time, duration, mission, noise, seed = o.mass, o.release_time, o.duration, o.mission, o.noise, o.seed
    platform = _q_prr(platform)
    missions = ("thesis", "hover")
    if mission not in missions:
        raise UnknownNameError("mission", mission, missions)
    r0, t2, t3 = platform.check_arm_limits(o.arm_target, "arm_target")
    if not 0.0 < release_time < duration:
        raise InputError(f"release_time must lie inside the run, 0 < release_time < duration = {duration!r} s, got {release_time!r}")
    arm_phase = as_interval(o.arm_phase, "arm_phase", lo=0.0)
    data = {"payload": ({"time": 0.0, "mass": mass}, {"time": release_time, "mass": 0.0})}
    trajectory = None
    if mission == "thesis":
        phases = (Phase("z", 0.0, 5.0, 10.0), Phase("x", 5.0, 10.0, 3.0), Phase("y", 10.0, 15.0, 6.0))
        phases += tuple(Phase(c, *arm_phase, v) for c, v in (("r0", r0), ("theta2", t2), ("theta3", t3)) if v != 0.0)
        data["phase"] = tuple(generic.phase_tables(phases))
    else:
        trajectory = Hold((0.0, 0.0, 1.0, 0.0, 0.0, 0.0, r0, t2, t3))
    ctrl = _payload_controller(controller, platform, mass, release_time)
    disturbance = WhiteNoise(noise, components=(0, 1, 2)) if noise > 0.0 else None
    settings = generic.MissionSettings(trajectory=trajectory, controller=ctrl, disturbance=disturbance, plant=plant, name="payload-drop")
    options = {"duration": duration, "dt": SimConfig.dt, "integrator": SimConfig.integrator, "seed": seed, "law": DEFAULT_LAW}
    res = generic.mission(platform, controller, progress, settings, mission=data, **options)
    res.series["payload_mass"] = np.where(res.t < release_time, mass, 0.0)
    if isinstance(ctrl, PayloadIDC) and ctrl.mode == "estimate":
        res.series["mass_estimate"] = np.asarray(ctrl.mass_log)
        window = min(1.0, 0.5 * release_time)  # the last second before the release (half the carry time if shorter)
        before = (res.t >= release_time - window) & (res.t < release_time)
        res.metrics["mass_estimate_error"] = float(np.max(np.abs(res.series["mass_estimate"][before] - mass))) if before.any() else math.nan
    res.metrics["release_time"] = float(release_time)
    rec = recovery(res, release_time, (platform if plant is None else plant).total_mass, platform.g)  # the real robot's weight
    res.metrics.update(
        {
            "recovery_time": rec.time,
            "recovery_peak_position": rec.peak_position,
            "recovery_peak_angle": rec.peak_angle,
            "recovery_peak_thrust": rec.peak_thrust,
        }
    )
    return res


def recovery_of(result: SimResult, platform=None) -> Recovery:
    """:class:`Recovery` of a payload-drop result (recomputed from the logs)."""
    platform = _q_prr(platform)
    return recovery(result, result.metrics["release_time"], platform.total_mass, platform.g)


# ============================================================================ pushing
ARM_PUSH = (0.0, math.pi / 2, 0.0)
"""Links 2 and 3 horizontal along x_B: the last segment parallel to the pushing direction (Sec. 6.4.3.1)."""

PUSH_CONTROLLERS = ("layered-idc-ft", "layered-idc", "idc")
SENSOR_FILTER = 50.0
"""Bandwidth [rad/s] of the first-order filter on the wrist-sensor reading (see :class:`LayeredIDC`)."""

PUSH_STIFFNESS = 300.0
"""Contact stiffness [N/m] of the push scenarios (not a thesis value).  Cancelling the contact force F
through the thrust needs a pitch F / (m g); pitching about the CoM moves the end effector, h = 8.3 cm
above it, into the object: a loop of gain k h / (m g), unstable above k* = m g / h = 417 N/m.  The
500 N/m first chosen (gain 1.2) bounced, then opened, once the object stuck; 300 N/m (gain 0.72)
holds a steady force (docs/notes-spikes.md, tests/test_phase_switches.py)."""


def _push_controller(name: str, platform, contact):
    """ "layered-idc-ft": layered IDC cancelling the contact wrench its wrist sensor read at the previous step
    ((6.76)), filtered at :data:`SENSOR_FILTER`; "layered-idc": the same without force feedback (the arm
    buckles under the compressive contact force); "idc": Sec. 6.3.1's controller."""
    g = gains.payload_idc()
    builders = {
        "layered-idc-ft": lambda: LayeredIDC(platform, g, ee_sensor=contact.measured, sensor_filter=SENSOR_FILTER),
        "layered-idc": lambda: LayeredIDC(platform, g),
        "idc": lambda: InverseDynamicsController(platform, gains.idc()),
    }
    if name not in builders:
        raise UnknownNameError("controller", name, PUSH_CONTROLLERS)
    return builders[name]()


@dataclass(frozen=True)
class PushSettings:
    """The options of a pushing scenario (:func:`push_thrust`, :func:`push_prismatic`): the push ``distance`` [m] (the
    thrust's; the slider goes from its lower to its upper limit), the pushing phase ``push`` (start, end) [s], the run's
    ``duration`` [s], the object's ``object_mass`` [kg] and Coulomb ``friction``, the contact's ``stiffness`` [N/m] and
    ``damping`` [N s/m], the ``seed``.  Defaults: push-thrust's (:meth:`prismatic` gives push-prismatic's)."""

    distance: float = 0.5
    push: tuple[float, float] = (2.0, 7.0)
    duration: float = 12.0
    object_mass: float = 0.5
    friction: float = 0.3
    stiffness: float = PUSH_STIFFNESS
    damping: float = 20.0
    seed: int = SEED

    def __post_init__(self) -> None:
        check_fields(self)
        as_real(self.duration, "duration", positive=True, unit="s")
        object.__setattr__(self, "push", as_interval(self.push, "push", lo=0.0))

    @classmethod
    def prismatic(cls, **fields) -> PushSettings:
        """push-prismatic's defaults (a 10 s run, a 0.2 kg object), with ``fields`` replacing them."""
        return cls(**{"duration": 10.0, "object_mass": 0.2, **fields})


def push_thrust(platform=None, controller: str = "layered-idc-ft", progress: bool = False, settings: PushSettings | None = None) -> SimResult:
    """Push an object along x with the thrust, arm locked (Thesis Sec. 6.4.3.1; ``settings``: :class:`PushSettings`).

    The Q-PRR hovers at (0, 0, 1) m with the arm at :data:`ARM_PUSH`, its end effector
    touching the object's face; x_d goes 0 -> ``distance`` during ``push`` ((6.16), septic law).
    The object (``object_mass`` kg, Coulomb ``friction`` on its line) is pushed through a
    compliant contact (``stiffness`` N/m, ``damping`` N s/m).  The thesis assumes a
    frictionless line (``friction=0``): the object then only resists its acceleration
    and slides on when the robot decelerates, the contact opening.
    """
    o = as_settings(settings, PushSettings)
    platform = _q_prr(platform)
    push = as_interval(o.push, "push", lo=0.0)
    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, *ARM_PUSH])
    trajectory = MultiPhase((Phase("x", push[0], push[1], o.distance),), tuple(xi0), name="push-thrust", names=NAMES)
    experiment = PushExperiment(xi0, trajectory, push, o.duration, o.object_mass, o.friction, o.stiffness, o.damping, o.seed)
    return _push(platform, controller, progress, experiment)


def push_prismatic(platform=None, controller: str = "layered-idc-ft", progress: bool = False, settings: PushSettings | None = None) -> SimResult:
    """Push an object with the slider from r0 = -0.04 m to +0.04 m while the rotors hold the pose (Thesis Sec. 6.4.3.2;
    ``settings``: :class:`PushSettings`, default :meth:`PushSettings.prismatic`; its ``distance`` is not used)."""
    o = PushSettings.prismatic() if settings is None else as_settings(settings, PushSettings)
    platform = _q_prr(platform)
    push = as_interval(o.push, "push", lo=0.0)
    lo, hi = params_of(platform).r0_limits
    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, lo, ARM_PUSH[1], ARM_PUSH[2]])
    trajectory = MultiPhase((Phase("r0", push[0], push[1], hi),), tuple(xi0), name="push-prismatic", names=NAMES)
    experiment = PushExperiment(xi0, trajectory, push, o.duration, o.object_mass, o.friction, o.stiffness, o.damping, o.seed)
    return _push(platform, controller, progress, experiment)


@dataclass(frozen=True)
class PushExperiment:
    """The settings of one pushing flight of Thesis Sec. 6.4.3 (:func:`push_thrust`, :func:`push_prismatic`).

    The robot starts at rest at ``xi0`` (thesis coordinates) and follows ``trajectory`` (named after the scenario) for
    ``duration`` [s]; ``push`` = (start, end) [s] of the pushing phase.  The object touches the end effector at the
    start: ``object_mass`` [kg], Coulomb ``friction`` coefficient on its line, contact ``stiffness`` [N/m] and
    ``damping`` [N s/m] (:class:`qprr.sim.PushedMass`).  ``seed``: the run's seed."""

    xi0: np.ndarray
    trajectory: MultiPhase
    push: tuple[float, float]
    duration: float
    object_mass: float
    friction: float
    stiffness: float
    damping: float
    seed: int


def _push(platform, controller, progress, experiment: PushExperiment) -> SimResult:
    """The pushing flight of Thesis Sec. 6.4.3 set by ``experiment``, the object at the end effector."""
    e = experiment
    obj = PushedMass(platform, mass=e.object_mass, origin=_ee_world(platform, e.xi0), stiffness=e.stiffness, damping=e.damping, friction=e.friction)
    ctrl = _push_controller(controller, platform, obj)
    config = SimConfig(seed=e.seed, progress=progress, scenario=e.trajectory.name)
    res = simulate(platform, ctrl, e.trajectory, e.duration, config=config, inputs=SimInputs(external_wrench=obj))
    _contact_series(res, obj)
    res.metrics.update({"object_mass": float(e.object_mass), "push_start": float(e.push[0]), "push_end": float(e.push[1])})
    return res


# ============================================================================ impedance
IMPEDANCE_CONTROLLERS = ("impedance", "impedance-table-6.7", "idc")


@dataclass(frozen=True)
class ImpedanceSettings:
    """The options of ``impedance`` (:func:`impedance`): the base force ``h_b`` on [x, y, z, psi] (N, N, N, N m) and
    the end-effector force ``h_q`` [N], applied from ``t_on`` to ``t_off`` [s]; the run's ``duration`` [s]; the
    hovering ``arm`` posture; ``impedance_gains`` (:class:`~qprr.control.impedance.ImpedanceGains`; None: the
    thesis's filters) and the ``seed``."""

    h_b: tuple[float, float, float, float] = (0.2, 0.0, 0.0, 0.0)
    h_q: tuple[float, float, float] = (0.05, 0.01, 0.05)
    t_on: float = 0.0
    t_off: float = 18.0
    duration: float = 25.0
    arm: tuple[float, float, float] = ARM_PUSH
    impedance_gains: ImpedanceGains | None = None
    seed: int = SEED

    def __post_init__(self) -> None:
        check_fields(self)
        as_real(self.duration, "duration", positive=True, unit="s")
        for key, n in (("h_b", 4), ("h_q", 3), ("arm", 3)):
            object.__setattr__(self, key, tuple(as_vector(self.__dict__[key], n, key).tolist()))


def impedance(platform=None, controller: str = "impedance", progress: bool = False, settings: ImpedanceSettings | None = None) -> SimResult:
    """Interaction forces from ``t_on`` to ``t_off`` on a hovering Q-PRR under impedance control (Thesis Sec. 6.4.3.4;
    the fields of ``settings``, an :class:`ImpedanceSettings`).

    ``h_b`` = generalised force on [x, y, z, psi] of the base (N, N, N, N m), applied as the
    disturbance (6.28) pulse; ``h_q`` = force on the end effector [N, world axes] (the moments
    are neglected, as the thesis states), applied through the end-effector wrench hook.  The
    controller measures both exactly.  Controllers: "impedance" (stable gains), "impedance-
    table-6.7" (printed impedance gains: the slider reference saturates), "idc" (no compliance).
    """
    o = as_settings(settings, ImpedanceSettings)
    t_on, t_off, impedance_gains = o.t_on, o.t_off, o.impedance_gains
    platform = _q_prr(platform)
    arm = tuple(params_of(platform).lower_limits * 0.0 + platform.check_arm_limits(o.arm, "arm"))
    hb = as_vector(o.h_b, 4, "h_b").copy()
    hq = np.concatenate([as_vector(o.h_q, 3, "h_q"), np.zeros(3)])
    ee = PrescribedWrench(hq, t_on, t_off)

    def base_sensor(t: float) -> np.ndarray:
        return hb if t_on <= t < t_off else np.zeros(4)

    gamma = np.zeros(9)
    gamma[[0, 1, 2, 5]] = hb
    pulse = Pulse(t_on, t_off, tuple(gamma))
    xi0 = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0, *arm)
    imp = gains.impedance_filters() if impedance_gains is None else impedance_gains
    builders = {
        "impedance": lambda: ImpedanceController(platform, gains.impedance_idc(), imp, ee_sensor=ee.measured, base_sensor=base_sensor),
        "impedance-table-6.7": lambda: ImpedanceController(
            platform, gains.impedance_idc(), gains.impedance_table_6_7(), ee_sensor=ee.measured, base_sensor=base_sensor
        ),
        "idc": lambda: InverseDynamicsController(platform, gains.idc()),
    }
    if controller not in builders:
        raise UnknownNameError("controller", controller, IMPEDANCE_CONTROLLERS)
    ctrl = builders[controller]()
    config = SimConfig(seed=o.seed, progress=progress, scenario="impedance")
    res = simulate(platform, ctrl, Hold(xi0), o.duration, config=config, inputs=SimInputs(external_wrench=ee, disturbance=pulse))
    res.series["ee_wrench"] = np.array([ee.measured(t) for t in res.t])
    res.series["base_wrench"] = np.array([base_sensor(t) for t in res.t])
    res.metrics["t_off"] = float(t_off)
    if isinstance(ctrl, ImpedanceController):
        h = ctrl.history()
        res.series.update(
            {"impedance_t": h["t"], "impedance_delta_eta": h["delta_eta"], "impedance_delta_q": h["delta_q"], "impedance_u_e": h["u_e"]}
        )
        K_arm = ctrl.impedance.arm(platform.n_arm)[2]
        res.series["impedance_K"] = np.concatenate([np.asarray(ctrl.impedance.K_base, dtype=float), K_arm])
        res.metrics["saturated_steps"] = float(ctrl.saturated_steps)
    return res


def impedance_steady_state(result: SimResult, at: float) -> dict[str, np.ndarray]:
    """Deflection of the measured state from the unperturbed reference at time ``at`` vs the filter's K^-1 h.

    Returns ``measured`` ([x, y, z, psi, r0, theta2, theta3] - their constant set points),
    ``filter`` (the impedance filters' Delta at that step: what the inner loop tracks) and
    ``predicted`` = [K_base^-1 h_b, K_arm^-1 u_e,mu] from the logged wrench.
    """
    k = int(np.searchsorted(result.t, at))
    k = min(k, result.n - 1)
    s = result.series
    K = s["impedance_K"]
    u_e = s["impedance_u_e"][k]
    hb = s["base_wrench"][k]
    predicted = np.concatenate([hb / K[0:4], u_e[6:9] / K[4:7]])
    set_point = result.xi[0]  # the run starts at rest on its set point
    idx = [0, 1, 2, 5, 6, 7, 8]
    filt = np.concatenate([s["impedance_delta_eta"][k], s["impedance_delta_q"][k]])
    return {"measured": result.xi[k, idx] - set_point[idx], "filter": filt, "predicted": predicted, "t": result.t[k]}


# ============================================================================ figures
FIGURES = {
    "static-idc": {
        "position": "6.7",
        "attitude": "6.8",
        "arm": "6.9",
        "errors_position": "6.10",
        "errors_angle": "6.10",
        "thrust": "6.11",
        "torques": "6.12",
        "arm_efforts": "6.12",
        "path": "6.13",
    },
    "static-dsid": {"position": "6.19", "errors_position": "6.20", "errors_angle": "6.21"},
    "static-mfc": {"position": "6.19", "errors_position": "6.20", "errors_angle": "6.21"},
    "spiral": {"path": "6.14", "position": "6.15", "attitude": "6.16", "arm": "6.17", "errors_position": "6.18", "errors_angle": "6.18"},
    "noise": {
        "disturbance": "6.23",
        "position": "6.24",
        "attitude": "6.25",
        "arm": "6.26",
        "thrust": "6.27a",
        "torques": "6.27b",
        "arm_efforts": "6.27c",
    },
    "pulses": {"thrust": "6.28a", "torques": "6.28b", "arm_efforts": "6.28c", "position": "6.29", "attitude": "6.29", "arm": "6.29"},
    "dynamic-bsg": {
        "position": "6.37",
        "attitude": "6.38",
        "arm": "6.39",
        "thrust": "6.40a",
        "torques": "6.40b",
        "arm_efforts": "6.40c",
        "errors_position": "6.41",
        "errors_angle": "6.41",
        "cog": "6.42-6.43",
    },
    "payload-drop": {"attitude": "6.49", "arm": "6.50", "thrust": "6.51a", "torques": "6.51b", "arm_efforts": "6.51c"},
    "push-thrust": {"attitude": "6.54", "arm": "6.55", "thrust": "6.56", "torques": "6.57", "arm_efforts": "6.58"},
    "push-prismatic": {"attitude": "6.60", "arm": "6.61", "thrust": "6.62", "torques": "6.63", "arm_efforts": "6.64"},
    "impedance": {"attitude": "6.66", "arm": "6.67", "thrust": "6.68", "torques": "6.69", "arm_efforts": "6.70"},
}
"""Thesis figure number of each panel of :func:`qprr.viz.plot_result`, per scenario (the thesis's own
captions: Sec. 6.3.1.4 Fig. 6.7-6.21, Sec. 6.3.2 Fig. 6.23-6.29, Sec. 6.3.3.3 Fig. 6.37-6.43, Sec. 6.4
Fig. 6.49-6.70).  Fig. 6.19-6.21 and 6.42-6.43 compare several runs: one run gives one of their curves."""

_SEC_6_4_PANELS = ("position", "attitude", "arm", "thrust", "torques", "arm_efforts")


def _payload_panel(ax, result: SimResult) -> None:
    s, t = result.series, result.t
    if "mass_estimate" in s:
        ax.plot(t, s["mass_estimate"], color="C3", lw=1.4, label="estimate [kg]", zorder=2)
    ax.plot(t, s["payload_mass"], label="carried mass [kg]", **REFERENCE_STYLE)
    ax.set_ylabel("payload mass [kg]")
    robust_limits(ax, [s["payload_mass"], s.get("mass_estimate")], min_span=0.01, t=t)
    e = np.linalg.norm((result.xi_d - result.xi)[:, 0:3], axis=1)
    ax2 = ax.twinx()
    ax2.semilogy(t, np.maximum(1e3 * e, 1e-6), color="C0", lw=0.9, label="$|p_d - p|$ [mm]")
    ax2.set_ylabel("position error of B [mm]")
    time_axis(ax, result)
    legend(ax, ax2)


def _contact_panel(ax, result: SimResult) -> None:
    c = contact_history(result)
    u = applied_forces(result)
    ax.plot(c.t, c.force, color="C3", lw=1.3, label="contact force [N]", zorder=3)
    ax.plot(result.t, u[:, 0], color="C0", lw=1.0, label="$u_{f_b,x}$ [N]", zorder=2)
    ax.set_ylabel("force [N]")
    robust_limits(ax, [c.force, u[:, 0]], min_span=0.01, t=c.t)
    ax2 = ax.twinx()
    unit, scale = length_unit([c.position - c.position[0]])
    ax2.plot(c.t, scale * (c.position - c.position[0]), color="C2", lw=1.2, ls="--", label=f"object displacement [{unit}]")
    ax2.set_ylabel(f"object displacement [{unit}]")
    time_axis(ax, result)
    legend(ax, ax2)


def _deflection_panel(ax, result: SimResult) -> None:
    s, t = result.series, result.t
    x0 = result.xi[0]
    raw = [result.xi[:, 0] - x0[0], result.xi[:, 6] - x0[6]]
    unit, scale = length_unit(raw)
    for k, (y, lab) in enumerate(zip(raw, ("$x - x_d$", "$r_0 - r_{0d}$"))):
        ax.plot(t, scale * y, color=f"C{k}", lw=1.3, label=f"{lab} [{unit}]", zorder=2)
    if "impedance_t" in s:
        ax.plot(s["impedance_t"], scale * s["impedance_delta_eta"][:, 0], color="C0", ls=":", lw=1.2, label=r"filter $\Delta x$")
        ax.plot(s["impedance_t"], scale * s["impedance_delta_q"][:, 0], color="C1", ls=":", lw=1.2, label=r"filter $\Delta r_0$")
    ax.set_ylabel(f"lengths [{unit}]")
    robust_limits(ax, [scale * y for y in raw], min_span=1e-3, t=t)
    ax2 = ax.twinx()
    ax2.plot(t, result.xi[:, 7] - x0[7], color="C2", lw=1.3, label=r"$\theta_2 - \theta_{2d}$ [rad]")
    if "impedance_t" in s:
        ax2.plot(s["impedance_t"], s["impedance_delta_q"][:, 1], color="C2", ls=":", lw=1.2, label=r"filter $\Delta\theta_2$")
    ax2.set_ylabel("angles [rad]")
    robust_limits(ax2, [result.xi[:, 7] - x0[7]], min_span=2e-5, t=t)
    time_axis(ax, result)
    legend(ax, ax2)


def _interaction_panel(ax, result: SimResult) -> None:
    s, t = result.series, result.t
    w, hb = s["ee_wrench"], s["base_wrench"]
    for k, (y, lab) in enumerate(
        ((hb[:, 0], "$h_{b,x}$ on the base"), (w[:, 0], "$h_{q,x}$ at the end effector"), (w[:, 1], "$h_{q,y}$"), (w[:, 2], "$h_{q,z}$"))
    ):
        ax.plot(t, y, color=f"C{k}", lw=1.2, label=lab)
    ax.set_ylabel("interaction force [N]")
    robust_limits(ax, [hb[:, 0], w[:, 0:3]], min_span=0.01, mark=False)
    time_axis(ax, result)
    legend(ax)


PAYLOAD_PANEL = Panel("payload", "payload mass and position error", _payload_panel)
CONTACT_PANEL = Panel("contact", "contact force and object motion", _contact_panel)
DEFLECTION_PANEL = Panel("deflection", "compliant deflections (dotted: impedance filter)", _deflection_panel)
INTERACTION_PANEL = Panel("interaction", "interaction forces (world x, y, z)", _interaction_panel)


def plot_payload_drop(result: SimResult, path) -> Path:
    """The Sec. 6.4.2.3 figures of ``payload-drop`` (Fig. 6.49-6.51) with the payload mass (true, estimated) and the release."""
    return plot_result(result, path, panels=_SEC_6_4_PANELS + (PAYLOAD_PANEL, "rotors", "cog"), events=((result.metrics["release_time"], "release"),))


def plot_push(result: SimResult, path) -> Path:
    """The Sec. 6.4.3 figures of a push scenario (Fig. 6.54-6.58 or 6.60-6.64) with the contact force and the object's motion."""
    m = result.metrics
    events = tuple((m[k], k.replace("_", " ")) for k in ("push_start", "push_end") if k in m)
    return plot_result(result, path, panels=_SEC_6_4_PANELS + (CONTACT_PANEL, "rotors", "cog"), events=events)


def plot_impedance(result: SimResult, path) -> Path:
    """The Sec. 6.4.3.4 figures of ``impedance`` (Fig. 6.66-6.70) with the interaction forces and the compliant deflections."""
    return plot_result(
        result, path, panels=_SEC_6_4_PANELS + (INTERACTION_PANEL, DEFLECTION_PANEL, "rotors"), events=((result.metrics["t_off"], "forces off"),)
    )


def summary(result: SimResult) -> list[str]:
    """The numbers a Sec. 6.4 scenario reports, one per line."""
    lines = []
    m, s = result.metrics, result.series
    if "recovery_time" in m:
        r = recovery_of(result)
        lines.append(
            f"recovery after release at {r.release_time:g} s: {r.time:.3f} s ({r.status}; |p_d - p| <= {r.tol_position:g} m, "
            f"|q_d - q| <= {r.tol_angle:g} rad, thrust within {100 * r.tol_thrust:g} % of m g); peaks after release: "
            f"position {r.peak_position:.4f} m, angle {r.peak_angle:.4f} rad, thrust {100 * r.peak_thrust:.2f} %"
        )
    if "mass_estimate_error" in m:
        lines.append(f"mass estimate: max |m_hat - m| over the last second before the release = {m['mass_estimate_error']:.3e} kg")
    if "contact_force" in s:
        c = contact_history(result)
        lines.append(f"contact force: max {c.force.max():.3f} N, min {c.force.min():.3f} N; object moved {c.position[-1] - c.position[0]:.4f} m")
    if "impedance_K" in s:
        d = impedance_steady_state(result, min(result.t[-1], m["t_off"] - result.dt))
        names = ("x", "y", "z", "psi", "r0", "theta2", "theta3")
        parts = [
            f"{n} {v:+.5f} (filter {f:+.5f}, h/K {p:+.5f})"
            for n, v, f, p in zip(names, d["measured"], d["filter"], d["predicted"])
            if abs(p) > 0 or abs(v) > 1e-6
        ]
        lines.append(f"deflection at t = {d['t']:.3f} s: " + ", ".join(parts))
        lines.append(f"arm reference saturated on {int(m['saturated_steps'])} steps")
    return lines


def _interaction(fn: Callable, settings_of: Callable) -> Callable:
    """The registry's runner of ``fn(platform, controller, progress, settings)``: the options :meth:`Scenario.run
    <qprr.scenarios.Scenario.run>` passes by name, gathered by ``settings_of`` (a settings class or constructor)."""

    def runner(platform, controller, progress, **options):
        return fn(platform, controller, progress, settings_of(**options))

    return runner


def _payload_drop_runner(platform, controller, progress, plant=None, **options):
    """The registry's runner of :func:`payload_drop`; its ``plant`` argument tells :attr:`Scenario.takes_plant`."""
    return payload_drop(platform, controller, progress, PayloadDropSettings(**options), plant)


INTERACTION_SCENARIOS = (
    Scenario(
        "payload-drop",
        "carry 0.1 kg at the end effector, release it at 18 s (payload IDC)",
        _payload_drop_runner,
        PAYLOAD_CONTROLLERS,
        {
            "mass": Option(0.1, "payload mass [kg]"),
            "release_time": Option(18.0, "release time [s]"),
            "duration": Option(25.0, "run length [s]"),
            "mission": Option("thesis", "thesis (the flight of Sec. 6.3.1.4) or hover"),
            "noise": Option(0.0, "white-noise amplitude on x, y, z [N] (6.27)"),
            "seed": Option(SEED, "noise seed"),
        },
        ("q-prr",),
        plot_payload_drop,
        "Sec. 6.4.2.3, Fig. 6.49-6.51",
        summary,
    ),
    Scenario(
        "push-thrust",
        "push a 0.5 kg object 0.5 m with the thrust, arm locked",
        _interaction(push_thrust, PushSettings),
        PUSH_CONTROLLERS,
        {
            "distance": Option(0.5, "push distance [m]"),
            "duration": Option(12.0, "run length [s]"),
            "object_mass": Option(0.5, "object mass [kg]"),
            "friction": Option(0.3, "Coulomb friction coefficient"),
            "stiffness": Option(PUSH_STIFFNESS, "contact stiffness [N/m]"),
            "damping": Option(20.0, "contact damping [N s/m]"),
            "seed": Option(SEED, "seed"),
        },
        ("q-prr",),
        plot_push,
        "Sec. 6.4.3.1, (6.65)-(6.67), Fig. 6.52-6.58",
        summary,
    ),
    Scenario(
        "push-prismatic",
        "push a 0.2 kg object with the slider while hovering",
        _interaction(push_prismatic, PushSettings.prismatic),
        PUSH_CONTROLLERS,
        {
            "duration": Option(10.0, "run length [s]"),
            "object_mass": Option(0.2, "object mass [kg]"),
            "friction": Option(0.3, "Coulomb friction coefficient"),
            "stiffness": Option(PUSH_STIFFNESS, "contact stiffness [N/m]"),
            "damping": Option(20.0, "contact damping [N s/m]"),
            "seed": Option(SEED, "seed"),
        },
        ("q-prr",),
        plot_push,
        "Sec. 6.4.3.2, Fig. 6.59-6.64",
        summary,
    ),
    Scenario(
        "impedance",
        "interaction forces on a hovering Q-PRR under impedance control",
        _interaction(impedance, ImpedanceSettings),
        IMPEDANCE_CONTROLLERS,
        {
            "t_on": Option(0.0, "forces on [s]"),
            "t_off": Option(18.0, "forces off [s]"),
            "duration": Option(25.0, "run length [s]"),
            "seed": Option(SEED, "seed"),
        },
        ("q-prr",),
        plot_impedance,
        "Sec. 6.4.3.4, (6.68)-(6.81), Table 6.7, Fig. 6.65-6.70",
        summary,
    ),
)

FLIGHT_SCENARIOS, INTERACTION_SCENARIOS = (
    tuple(replace(s, figures=FIGURES[s.name]) if s.name in FIGURES else s for s in group) for group in (FLIGHT_SCENARIOS, INTERACTION_SCENARIOS)
)
SCENARIOS = FLIGHT_SCENARIOS + INTERACTION_SCENARIOS
"""The thesis's scenarios (registered in :data:`qprr.scenarios.SCENARIOS`), with their figure numbers (:data:`FIGURES`)."""


# ============================================================================ Table 6.3
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
    status: dict[str, Status]
    reason: dict[str, str]

    def table(self) -> str:
        """Text table shaped like Table 6.3 (rows: variables; columns: ours and the thesis's, per controller)."""
        ctrls = list(self.rmse)
        head = f"{'variable':<9}" + "".join(f"{c + ' (ours)':>13}{THESIS_NAMES[c] + ' (thesis)':>15}" for c in ctrls)
        lines = [head, "-" * len(head)]
        for i, var in enumerate(NAMES):
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
            if self.status[c] is not Status.OK:
                lines.append(f"{c}: {self.status[c]}: {self.reason[c]}")
        return "\n".join(lines)


def compare(
    *, platform=None, controllers=("idc", "dsid", "mfc"), duration: float = 30.0, dt: float = SimConfig.dt, progress: bool = False
) -> Comparison:
    """Run the three controllers on the static mission (Sec. 6.3.1.4) and collect RMSE and wall times."""
    platform = _q_prr(platform)
    by_name = {s.name: s for s in FLIGHT_SCENARIOS}
    rmse, wall, status, reason = {}, {}, {}, {}
    for c in controllers:
        if c not in THESIS_NAMES:
            raise UnknownNameError("controller", c, tuple(THESIS_NAMES))
        try:
            res = by_name[f"static-{c}"].run(platform=platform, controller=c, progress=progress, duration=duration, dt=dt)
        except QprrError as err:
            res = err.result
            if res is None:
                raise
        rmse[c], wall[c], status[c], reason[c] = res.rmse(), res.wall_time, res.status, res.reason
    return Comparison(rmse, wall, status, reason)


checked_module(globals())  # scenario options (annotated floats and ints) are checked before a run starts
