"""The summary figure of a flight log (``qprr log show --plot``): position, attitude, motor commands, battery.

Four panels against the time since the log start [s], the airborne intervals shaded and the armed ones marked by
dashed lines. Position: ``vehicle_local_position`` x, y, z in PX4's local NED frame [m]. Attitude:
``vehicle_attitude.q`` (Hamilton, w first; body FRD -> world NED) as ZYX Euler angles roll, pitch, yaw [deg]
(PX4 ``matrix::Eulerf``). Motor commands: :func:`qprr.flightlog.ulog.motor_commands` (normalised, [0, 1]).
Battery: ``battery_status.voltage_v`` [V]. A topic the log lacks is noted on its axes instead of an empty panel.
"""

from __future__ import annotations

import numpy as np

from ..errors import MissingTopicError
from ..viz.plots import new_figure
from .phases import Phases
from .ulog import FlightLog, motor_commands


def euler_zyx_deg(q_wxyz: np.ndarray) -> np.ndarray:
    """(N, 3) roll, pitch, yaw [deg] (ZYX, intrinsic) of (N, 4) unit quaternions w, x, y, z rotating body vectors to
    world ones (PX4 ``matrix::Euler(const Quaternion&)`` through the rotation matrix)."""
    w, x, y, z = (q_wxyz[:, i] for i in range(4))
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return np.degrees(np.column_stack([roll, pitch, yaw]))


def _missing(ax, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.4", wrap=True)


def _panel(ax, log: FlightLog, spec) -> None:
    """Draw one panel: ``spec`` = (title, ylabel, loader returning (t, values, labels))."""
    title, ylabel, load = spec
    ax.set_title(title, fontsize=10, loc="left")
    ax.set_ylabel(ylabel)
    try:
        t, values, labels = load(log)
    except MissingTopicError as exc:
        _missing(ax, f"not in this log: {exc.topic}")
        return
    if len(t) == 0 or values.shape[1] == 0:
        _missing(ax, "no samples in this log")
        return
    if not np.isfinite(values).any():
        _missing(ax, "every sample is NaN (motors stopped: never armed)")
        return
    for i, label in enumerate(labels):
        ax.plot(t, values[:, i], lw=1.0, label=label)
    ax.legend(loc="upper left", fontsize=8, ncols=min(len(labels), 6))


def _position(log: FlightLog):
    s = log.series("vehicle_local_position", ["x", "y", "z"], needed_for="the position panel")
    return s.t_s, s.values, ("x (north)", "y (east)", "z (down)")


def _attitude(log: FlightLog):
    s = log.vector("vehicle_attitude", "q", 4, needed_for="the attitude panel")
    return s.t_s, euler_zyx_deg(s.values), ("roll", "pitch", "yaw")


def _motors(log: FlightLog):
    s = motor_commands(log, "the motor panel")
    return s.t_s, s.values, tuple(f"motor {i + 1}" for i in range(s.values.shape[1]))


def _battery(log: FlightLog):
    s = log.series("battery_status", "voltage_v", needed_for="the battery panel")
    v = s.values.copy()
    v[v <= 0.0] = np.nan  # 0 V: no battery reading
    return s.t_s, v, ("voltage",)


PANELS = (
    ("position (local NED)", "position [m]", _position),
    ("attitude (FRD body in NED, ZYX Euler)", "angle [deg]", _attitude),
    ("motor commands", "command [0-1]", _motors),
    ("battery", "voltage [V]", _battery),
)


def _shade(ax, phases: Phases) -> None:
    for a, b in phases.airborne:
        ax.axvspan(a, b, color="tab:blue", alpha=0.08, lw=0)
    for a, b in phases.armed:
        ax.axvline(a, color="0.3", ls="--", lw=0.8)
        ax.axvline(b, color="0.3", ls="--", lw=0.8)


def summary_figure(log: FlightLog, phases: Phases):
    """The summary figure of ``log`` (a matplotlib Figure, not attached to pyplot)."""
    fig = new_figure((11, 10))
    axes = fig.subplots(len(PANELS), 1, sharex=True)
    for ax, spec in zip(axes, PANELS, strict=True):
        _panel(ax, log, spec)
        _shade(ax, phases)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time since the log start [s]")
    vehicle = log.info.get("sys_name", "vehicle")
    fig.suptitle(
        f"{log.path.name}: {vehicle} {log.info.get('ver_hw', '')}, airframe {log.airframe}, {phases.status.value}\n"
        "(shaded: airborne; dashed: armed, disarmed)",
        fontsize=11,
    )
    return fig


__all__ = ["PANELS", "euler_zyx_deg", "summary_figure"]
