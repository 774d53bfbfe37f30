"""Campaign target: the flight of Thesis Sec. 6.3 with its parameters exposed.

:func:`flight` is the flight of the ``static-*``, ``noise``, ``pulses`` and ``dynamic-bsg``
scenarios (:mod:`qprr.thesis.scenarios`) with its mission, controller gains, disturbance
amplitudes and model errors as parameters, for a campaign specification's
``callable = "qprr.thesis.flight:flight"``.  Its pieces are the scenarios' own:
:func:`qprr.thesis.scenarios.flight_controller`, :func:`qprr.thesis.missions.static_mission` /
:func:`~qprr.thesis.missions.dynamic_mission`, :data:`~qprr.thesis.scenarios.NOISE_AMPLITUDE`,
:data:`~qprr.thesis.scenarios.PULSES`, :class:`~qprr.thesis.bsg.CogStabilizer`; the gains are
scaled by :func:`qprr.campaign.targets.scale_bandwidth`.
"""

from __future__ import annotations

from collections.abc import Mapping

from ..campaign.spec import MODEL_PREFIX, model_error
from ..campaign.targets import scale_bandwidth
from ..errors import InputError, UnknownNameError
from ..model import check_platform
from ..sim import Disturbances, Pulse, SimConfig, SimInputs, SimResult, WhiteNoise, simulate
from ..sim.mismatch import perturbed
from .bsg import CogStabilizer
from .missions import dynamic_mission, static_mission
from .robot import load_qprr
from .scenarios import NOISE_AMPLITUDE, PULSES, flight_controller

__all__ = ["FLIGHT_DEFAULTS", "flight"]

FLIGHT_DEFAULTS = {
    "mission": "static",
    "controller": "idc",
    "bsg": None,
    "duration": 30.0,
    "time_scale": 1.0,
    "law": "septic",
    "x": 3.0,
    "y": 6.0,
    "z": 10.0,
    "psi": 0.0,
    "r0": 0.04,
    "theta2": 0.2,
    "theta3": 0.6,
    "theta2_d": -0.5,
    "noise": 0.0,
    "pulses": 0.0,
    "dt": 1e-3,
    "bandwidth.position": 1.0,
    "bandwidth.attitude": 1.0,
    "bandwidth.arm": 1.0,
}
"""Parameters of :func:`flight` and their defaults (the Sec. 6.3.1.4 static mission with IDC)."""


def flight(params: Mapping[str, object], seed: int, platform=None) -> SimResult:
    """The Sec. 6.3 flight with its parameters (:data:`FLIGHT_DEFAULTS`; unknown names raise).

    * ``mission``: "static" (targets ``x, y, z, psi, r0, theta2, theta3``) or "dynamic"
      (targets ``x, y, z`` and ``theta2_d``; the BSG computes r0 and theta3);
      ``time_scale``: the static mission's phase times times this factor (0.5: a 15 s mission;
      ``duration`` is not scaled); ``law``: the transition law.
    * ``controller``: idc, dsid or mfc (:func:`qprr.thesis.scenarios.flight_controller`);
      ``bsg``: wrap it in the CoG stabiliser (default: with the dynamic mission);
      ``bandwidth.position|attitude|arm``: loop-bandwidth factors (:func:`scale_bandwidth`).
    * ``noise``: factor on :data:`~qprr.thesis.scenarios.NOISE_AMPLITUDE` (white noise (6.27));
      ``pulses``: factor on :data:`~qprr.thesis.scenarios.PULSES` (6.28); seeded by ``seed``.
    * ``model.*``: model errors of the plant (:class:`qprr.sim.mismatch.ModelError`).
    """
    if not isinstance(params, Mapping):
        raise InputError(f"params must be a mapping of parameter name -> value (qprr.thesis.flight.FLIGHT_DEFAULTS), got {type(params).__name__}")
    for k in params:
        if k not in FLIGHT_DEFAULTS and not k.startswith(MODEL_PREFIX):
            raise UnknownNameError("parameter of qprr.thesis.flight.flight", k, tuple(FLIGHT_DEFAULTS))
    p = {**FLIGHT_DEFAULTS, **{k: v for k, v in params.items() if not k.startswith(MODEL_PREFIX)}}
    platform = load_qprr() if platform is None else check_platform(platform)
    ts = float(p["time_scale"])
    if not ts > 0:
        raise InputError(f"time_scale must be > 0, got {ts!r}")
    if p["mission"] == "static":
        phases = {
            k: (a * ts, b * ts)
            for k, (a, b) in {"z_phase": (0.0, 5.0), "x_phase": (5.0, 10.0), "y_phase": (10.0, 15.0), "arm_phase": (15.0, 25.0)}.items()
        }
        target = tuple(float(p[k]) for k in ("x", "y", "z", "psi", "r0", "theta2", "theta3"))
        trajectory = static_mission(target, law=p["law"], **phases)
    elif p["mission"] == "dynamic":
        if ts != 1.0:
            raise InputError("time_scale applies to the static mission only")
        trajectory = dynamic_mission((float(p["x"]), float(p["y"]), float(p["z"])), float(p["theta2_d"]), law=p["law"])
    else:
        raise UnknownNameError("mission", p["mission"], ("static", "dynamic"))
    ctrl = flight_controller(p["controller"], platform)  # the thesis's gains
    g = ctrl.gains
    for group in ("position", "attitude", "arm"):
        if p[f"bandwidth.{group}"] != 1.0:
            g = scale_bandwidth(g, group, float(p[f"bandwidth.{group}"]), platform.n_xi)
    if g is not ctrl.gains:
        ctrl = type(ctrl)(platform, g)  # the same controller class with the scaled gains
    bsg = (p["mission"] == "dynamic") if p["bsg"] is None else bool(p["bsg"])
    if bsg:
        ctrl = CogStabilizer(platform, ctrl, theta_e_d=0.0)
    parts = []
    if p["noise"]:
        parts.append(WhiteNoise(tuple(float(p["noise"]) * a for a in NOISE_AMPLITUDE)))
    if p["pulses"]:
        parts += [Pulse(q.t1, q.t2, tuple(float(p["pulses"]) * g for g in q.gamma)) for q in PULSES]
    disturbance = Disturbances(tuple(parts)) if parts else None
    err = model_error(params)
    plant = None if err is None or err.is_nominal else perturbed(platform, err)
    config = SimConfig(dt=float(p["dt"]), seed=seed, scenario=f"flight-{p['mission']}")
    return simulate(platform, ctrl, trajectory, float(p["duration"]), config=config, inputs=SimInputs(disturbance=disturbance, plant=plant))
