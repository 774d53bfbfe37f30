"""Campaign targets with more parameters than the registered scenarios expose.

:func:`flight` is the flight of Thesis Sec. 6.3 (the ``static-*``, ``noise``, ``pulses`` and
``dynamic-bsg`` scenarios of :mod:`qprr.thesis.scenarios`) with its mission, controller gains,
disturbance amplitudes and model errors as parameters, for a specification's
``callable = "qprr.campaign.targets:flight"``.  Its pieces are the scenarios' own:
:func:`qprr.thesis.scenarios.flight_controller`, :func:`qprr.thesis.missions.static_mission` /
:func:`~qprr.thesis.missions.dynamic_mission`, :data:`~qprr.thesis.scenarios.NOISE_AMPLITUDE`,
:data:`~qprr.thesis.scenarios.PULSES`, :class:`~qprr.thesis.bsg.CogStabilizer`.

A callable target takes ``(params, seed)`` or ``(params, seed, platform)``: the three-argument
form receives the campaign's platform, built once per worker.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from ..charts import as_int, as_name, as_real
from ..errors import InputError, UnknownNameError
from ..platform import check_platform
from ..sim import Disturbances, Pulse, SimResult, WhiteNoise, simulate
from ..sim.mismatch import perturbed
from .spec import MODEL_PREFIX, model_error

FLIGHT_DEFAULTS = {
    "mission": "static", "controller": "idc", "bsg": None, "duration": 30.0, "time_scale": 1.0, "law": "septic",
    "x": 3.0, "y": 6.0, "z": 10.0, "psi": 0.0, "r0": 0.04, "theta2": 0.2, "theta3": 0.6, "theta2_d": -0.5,
    "noise": 0.0, "pulses": 0.0, "dt": 1e-3,
    "bandwidth.position": 1.0, "bandwidth.attitude": 1.0, "bandwidth.arm": 1.0,
}
"""Parameters of :func:`flight` and their defaults (the Sec. 6.3.1.4 static mission with IDC)."""

_GROUPS = {"position": (0, 1, 2), "attitude": (3, 4, 5), "arm": None}


def scale_bandwidth(gains, group: str, s: float, n_xi: int):
    """Gains with the loop bandwidth of ``group`` (position, attitude, arm) times ``s``: k_P s^2, k_D s, k_I s^3.

    The error polynomial e''' + k_D e'' + k_P e' + k_I e of every loop of the group has its
    roots multiplied by ``s`` (same damping, same stability: Routh-Hurwitz is scale-free).
    Works on :class:`~qprr.control.IDCGains` and :class:`~qprr.control.MFCGains` (explicit vectors).
    """
    group = as_name(group, "group", tuple(_GROUPS), kind="bandwidth group")
    s = as_real(s, f"bandwidth.{group}", positive=True)
    n_xi = as_int(n_xi, "n_xi", lo=6)
    if not all(len(getattr(gains, k, ())) == n_xi for k in ("kp", "kd", "ki")) or not dataclasses.is_dataclass(gains):
        raise InputError(f"gains must be IDCGains or MFCGains with explicit vectors kp, kd, ki of n_xi = {n_xi} entries, "
                         f"got {type(gains).__name__}")
    idx = _GROUPS[group] if _GROUPS[group] is not None else tuple(range(6, n_xi))
    changes = {}
    for name, power in (("kp", 2), ("kd", 1), ("ki", 3)):
        k = list(getattr(gains, name))
        for i in idx:
            k[i] *= s**power
        changes[name] = tuple(k)
    return dataclasses.replace(gains, **changes)


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
    from ..thesis import load
    from ..thesis.bsg import CogStabilizer
    from ..thesis.missions import dynamic_mission, static_mission
    from ..thesis.scenarios import NOISE_AMPLITUDE, PULSES, flight_controller

    if not isinstance(params, Mapping):
        raise InputError(f"params must be a mapping of parameter name -> value (qprr.campaign.targets.FLIGHT_DEFAULTS), "
                         f"got {type(params).__name__}")
    for k in params:
        if k not in FLIGHT_DEFAULTS and not k.startswith(MODEL_PREFIX):
            raise UnknownNameError("parameter of qprr.campaign.targets.flight", k, tuple(FLIGHT_DEFAULTS))
    p = {**FLIGHT_DEFAULTS, **{k: v for k, v in params.items() if not k.startswith(MODEL_PREFIX)}}
    platform = load() if platform is None else check_platform(platform)
    ts = float(p["time_scale"])
    if not ts > 0:
        raise InputError(f"time_scale must be > 0, got {ts!r}")
    if p["mission"] == "static":
        phases = {k: (a * ts, b * ts) for k, (a, b) in
                  {"z_phase": (0.0, 5.0), "x_phase": (5.0, 10.0), "y_phase": (10.0, 15.0), "arm_phase": (15.0, 25.0)}.items()}
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
    return simulate(platform, ctrl, trajectory, float(p["duration"]), dt=float(p["dt"]), disturbance=disturbance, seed=seed,
                    plant=plant, scenario=f"flight-{p['mission']}")
