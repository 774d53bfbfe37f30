"""The phases of a flight found from the data: armed, take-off, airborne, landing.

PX4's land detector (``vehicle_land_detected.landed``, PX4 ``src/modules/land_detector/MulticopterLandDetector.cpp``)
is a state machine with hysteresis: it declares the take-off as soon as the take-off ramp starts (before the thrust
can carry the weight) and the landing only after its ground-contact and maybe-landed stages (seconds after the
touchdown). The phases here come from the physics instead:

- armed: ``actuator_armed.armed`` (else ``vehicle_status.arming_state`` = 2, ARMING_STATE_ARMED);
- certainly airborne: the height above the arming height (``vehicle_local_position.z``, NED, up = -z) above
  ``HEIGHT_AIRBORNE_M``;
- the hover level: the median collective command (the mean of the motor commands, else the thrust set point
  ``-vehicle_thrust_setpoint.xyz[2]``) while certainly airborne;
- take-off (lift-off): the last time before the first certainly-airborne sample that the collective command was
  below the hover level by ``HOVER_MARGIN`` of it: thrust below the weight cannot lift the vehicle;
- landing (touchdown): the first time after the last certainly-airborne sample that the command falls below that
  level and stays below until the disarm or the next take-off (the ground carries the rest of the weight).

The land detector's times are reported beside them, with its lag (positive: it declares the event later than the data
shows). The vertical specific force (``sensor_combined.accelerometer_m_s2[2]``, FRD) leaving its on-ground value is
a third, independent cue of the lift-off, reported as ``specific_force_liftoff_s``.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from ..errors import NoFlightError
from .ulog import FlightLog, Series, motor_commands

HEIGHT_AIRBORNE_M = 0.3  # height above the arming height [m] that only a flying multirotor reaches
HOVER_MARGIN = 0.03  # relative margin under the hover command that means "thrust below the weight"
ARMING_STATE_ARMED = 2  # PX4 msg/VehicleStatus.msg


class FlightStatus(enum.Enum):
    """What a log holds: no arming, arming without leaving the ground, or a flight."""

    NEVER_ARMED = "never armed"
    ARMED_NOT_AIRBORNE = "armed but never airborne"
    FLEW = "flew"


@dataclass(frozen=True)
class Phases:
    """The phases of a log (times in seconds since the log start).

    ``armed``/``airborne``: tuples of (start, end) intervals; ``takeoff_s``/``landing_s``: the first lift-off and
    the last touchdown (None without a flight); ``hover_command``: the median collective command while airborne
    (normalised, [0, 1]); ``land_detector_takeoff_s``/``land_detector_landing_s``: PX4's land detector's times
    (None if not logged); ``specific_force_liftoff_s``: the IMU's cue; ``evidence``: the signals used.
    """

    status: FlightStatus
    armed: tuple[tuple[float, float], ...]
    airborne: tuple[tuple[float, float], ...] = ()
    takeoff_s: float | None = None
    landing_s: float | None = None
    hover_command: float | None = None
    land_detector_takeoff_s: float | None = None
    land_detector_landing_s: float | None = None
    specific_force_liftoff_s: float | None = None
    evidence: str = ""

    @property
    def land_detector_takeoff_lag_s(self) -> float | None:
        """PX4's land detector's take-off time minus the lift-off found from the data (negative: it is early)."""
        if self.land_detector_takeoff_s is None or self.takeoff_s is None:
            return None
        return self.land_detector_takeoff_s - self.takeoff_s

    @property
    def land_detector_landing_lag_s(self) -> float | None:
        """PX4's land detector's landing time minus the touchdown found from the data (positive: it lags)."""
        if self.land_detector_landing_s is None or self.landing_s is None:
            return None
        return self.land_detector_landing_s - self.landing_s

    def require_flight(self, what: str) -> None:
        """Raise :class:`~qprr.errors.NoFlightError` (one line) unless the log holds a flight; ``what``: the
        computation that needs it."""
        if self.status is FlightStatus.NEVER_ARMED:
            raise NoFlightError(f"{what} needs a flight: this log never armed")
        if self.status is FlightStatus.ARMED_NOT_AIRBORNE:
            raise NoFlightError(f"{what} needs a flight: this log armed but never left the ground")

    def lines(self) -> list[str]:
        """The phases as text lines (``qprr log show``)."""
        out = [f"status: {self.status.value}"]
        out += [f"armed {a:.2f} s -> {b:.2f} s" for a, b in self.armed]
        out += [f"airborne {a:.2f} s -> {b:.2f} s ({b - a:.1f} s)" for a, b in self.airborne]
        if self.hover_command is not None:
            out.append(f"hover command {self.hover_command:.3f} (median of the collective command while airborne)")
        if self.specific_force_liftoff_s is not None:
            out.append(f"lift-off in the IMU's vertical specific force at {self.specific_force_liftoff_s:.2f} s")
        for event, t, lag in (
            ("take-off", self.land_detector_takeoff_s, self.land_detector_takeoff_lag_s),
            ("landing", self.land_detector_landing_s, self.land_detector_landing_lag_s),
        ):
            if t is not None:
                rel = f" ({lag:+.2f} s from the data)" if lag is not None else ""
                out.append(f"PX4 land detector {event} at {t:.2f} s{rel}")
        if self.evidence:
            out.append(f"from: {self.evidence}")
        return out


def _intervals(t: np.ndarray, on: np.ndarray, end_s: float) -> tuple[tuple[float, float], ...]:
    """(start, end) intervals where the step signal ``on`` (held between samples) is true."""
    out, start = [], None
    for ti, v in zip(t, on, strict=True):
        if v and start is None:
            start = float(ti)
        elif not v and start is not None:
            out.append((start, float(ti)))
            start = None
    if start is not None:
        out.append((start, float(max(end_s, start))))
    return tuple(out)


def armed_intervals(log: FlightLog) -> tuple[tuple[float, float], ...]:
    """The armed intervals: ``actuator_armed.armed``, else ``vehicle_status.arming_state == 2``; () if neither
    topic is logged or the vehicle never armed."""
    if log.has("actuator_armed"):
        s = log.series("actuator_armed", "armed")
        return _intervals(s.t_s, s.values[:, 0] > 0.5, log.duration_s)
    if log.has("vehicle_status") and "arming_state" in log.fields("vehicle_status"):
        s = log.series("vehicle_status", "arming_state")
        return _intervals(s.t_s, s.values[:, 0] == ARMING_STATE_ARMED, log.duration_s)
    return ()


def collective_command(log: FlightLog) -> Series:
    """The collective command in [0, 1], from the fastest source logged: the thrust set point
    ``-vehicle_thrust_setpoint.xyz[2]`` (FRD: thrust along -z; 50 Hz in PX4's default profile), else the mean of the
    motor commands (stopped motors count 0; 10 Hz), else ``actuator_controls_0.control[3]`` (PX4 <= 1.13)."""
    if log.has("vehicle_thrust_setpoint"):
        s = log.series("vehicle_thrust_setpoint", "xyz[2]")
        return Series(s.t_s, -s.values, ("collective",), s.t_us, "thrust set point (-vehicle_thrust_setpoint.xyz[2])")
    if log.has("actuator_controls_0"):
        s = log.series("actuator_controls_0", "control[3]")
        return Series(s.t_s, s.values, ("collective",), s.t_us, "thrust command (actuator_controls_0.control[3])")
    m = motor_commands(log, "finding the flight's phases")
    c = np.mean(np.where(np.isnan(m.values), 0.0, m.values), axis=1) if m.values.shape[1] else np.zeros(len(m))
    return Series(m.t_s, c[:, None], ("collective",), m.t_us, f"mean motor command ({m.source})")


def _held(t_query: np.ndarray, s: Series) -> np.ndarray:
    """The last sample of ``s`` at or before each query time (zero-order hold; the first sample before it)."""
    i = np.clip(np.searchsorted(s.t_s, t_query, side="right") - 1, 0, len(s) - 1)
    return s.values[i, 0]


def _land_detector(log: FlightLog) -> tuple[float | None, float | None]:
    """PX4's land detector's first take-off (landed 1 -> 0) and last landing (landed 0 -> 1)."""
    if not log.has("vehicle_land_detected"):
        return None, None
    s = log.series("vehicle_land_detected", "landed")
    landed = s.values[:, 0] > 0.5
    ups = np.flatnonzero(landed[:-1] & ~landed[1:]) + 1
    downs = np.flatnonzero(~landed[:-1] & landed[1:]) + 1
    takeoff = float(s.t_s[ups[0]]) if len(ups) else None
    landing = float(s.t_s[downs[-1]]) if len(downs) else None
    return takeoff, landing


def _certainly_airborne(log: FlightLog, armed, t: np.ndarray) -> tuple[np.ndarray, str]:
    """Mask over ``t``: armed and higher than HEIGHT_AIRBORNE_M above the height at the arming."""
    mask = np.zeros(len(t), dtype=bool)
    if not log.has("vehicle_local_position"):
        return mask, "no vehicle_local_position: no height, no flight found"
    lp = log.series("vehicle_local_position", "z")
    ok = np.isfinite(lp.values[:, 0])
    lp = Series(lp.t_s[ok], lp.values[ok], lp.fields, lp.t_us[ok])
    if len(lp) == 0:
        return mask, "vehicle_local_position.z never valid"
    for a, b in armed:
        z0 = _held(np.array([a]), lp)[0]
        inside = (t >= a) & (t <= b)
        mask |= inside & (z0 - _held(t, lp) > HEIGHT_AIRBORNE_M)
    return mask, f"height above the arming height > {HEIGHT_AIRBORNE_M} m (vehicle_local_position.z)"


def _flights(t: np.ndarray, c: np.ndarray, high: np.ndarray, level: float, armed) -> list[tuple[float, float]]:
    """Lift-off and touchdown around each certainly-airborne stretch: the collective command ``c`` at or above
    ``level`` (thrust carrying the weight) contiguous with it, within the armed interval."""
    carrying = c >= level
    out: list[tuple[float, float]] = []
    for a, b in armed:
        inside = np.flatnonzero((t >= a) & (t <= b))
        if len(inside) == 0:
            continue
        i = inside[0]
        while i <= inside[-1]:
            if not high[i]:
                i += 1
                continue
            lo = i
            while lo > inside[0] and carrying[lo - 1]:
                lo -= 1
            hi = i
            while hi < inside[-1] and (carrying[hi + 1] or high[hi + 1]):
                hi += 1
            out.append((float(t[lo]), float(t[min(hi + 1, inside[-1])])))
            i = hi + 1
    return out


def _specific_force_liftoff(log: FlightLog, armed_start: float, takeoff: float) -> float | None:
    """The first time after the arming that the vertical specific force (FRD z, 0.1 s mean) departs by more than
    0.3 m/s^2 from its mean over the first second of the arming (on the ground), searched up to 2 s after the
    take-off found from the commands."""
    if not log.has("sensor_combined"):
        return None
    s = log.series("sensor_combined", "accelerometer_m_s2[2]")
    ground = s.values[(s.t_s >= armed_start) & (s.t_s <= armed_start + 1.0), 0]
    window = (s.t_s >= armed_start) & (s.t_s <= takeoff + 2.0)
    if len(ground) < 10 or window.sum() < 10:
        return None
    tw = s.t_s[window]
    k = max(1, int(round(0.1 / np.median(np.diff(tw)))))
    smooth = np.convolve(s.values[window, 0], np.ones(k) / k, mode="valid")  # the mean of samples [i, i + k)
    away = np.flatnonzero(np.abs(smooth - ground.mean()) > 0.3)
    return float(tw[away[0] + k - 1]) if len(away) else None


def find_phases(log: FlightLog) -> Phases:
    """The phases of ``log`` (see the module docstring for how each is found)."""
    armed = armed_intervals(log)
    ld_takeoff, ld_landing = _land_detector(log)
    if not armed:
        return Phases(FlightStatus.NEVER_ARMED, (), land_detector_takeoff_s=ld_takeoff, land_detector_landing_s=ld_landing)
    cc = collective_command(log)
    t, c = cc.t_s, cc.values[:, 0]
    high, how = _certainly_airborne(log, armed, t)
    if not high.any():
        return Phases(FlightStatus.ARMED_NOT_AIRBORNE, armed, land_detector_takeoff_s=ld_takeoff, land_detector_landing_s=ld_landing, evidence=how)
    hover = float(np.median(c[high]))
    flights = _flights(t, c, high, (1.0 - HOVER_MARGIN) * hover, armed)
    takeoff, landing = flights[0][0], flights[-1][1]
    first_armed = next(a for a, b in armed if a <= takeoff <= b)
    return Phases(
        FlightStatus.FLEW,
        armed,
        tuple(flights),
        takeoff,
        landing,
        hover,
        ld_takeoff,
        ld_landing,
        _specific_force_liftoff(log, first_armed, takeoff),
        f"{how}; lift-off and touchdown where the {cc.source} crosses {1 - HOVER_MARGIN:.0%} of the hover command",
    )


__all__ = ["FlightStatus", "Phases", "armed_intervals", "collective_command", "find_phases"]
