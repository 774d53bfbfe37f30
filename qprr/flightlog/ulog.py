"""The one reader of PX4 flight logs (ULog, read through pyulog, the ``flightlog`` extra).

:meth:`FlightLog.read` loads a ``.ulg`` file once; every other module of :mod:`qprr.flightlog` asks it for time
series (:meth:`FlightLog.series`, :meth:`FlightLog.vector`), parameters and the list of topics.

Time: every series is given in seconds since the log's start (the ``timestamp`` of the ULog file header, PX4's
``hrt_absolute_time`` in microseconds). Samples whose timestamp is 0 (a topic never published before the logger
subscribed writes its zero-initialised struct) are dropped; the arithmetic is done in signed 64-bit integers so no
unsigned wrap-around reaches a time. Samples published just before the header's timestamp keep a small negative time.

Frames: values are PX4's own, unconverted (body FRD, world NED); :mod:`qprr.flightstack.frames` converts them.

A missing topic raises :class:`~qprr.errors.MissingTopicError` naming the topic, what needed it and the logging
profile that adds it (PX4 ``src/modules/logger/logged_topics.cpp``, the ``SDLOG_PROFILE`` bits of
``logged_topics.h``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, MissingDependencyError, MissingTopicError

ULOG_MAGIC = b"ULog\x01\x12\x35"

# SDLOG_PROFILE bits (PX4 src/modules/logger/logged_topics.h, SDLogProfileMask)
_PROFILES = {
    0: "default",
    1: "estimator replay (EKF2)",
    2: "thermal calibration",
    3: "system identification",
    4: "high rate",
    5: "debug",
    6: "sensor comparison",
    7: "computer vision and collision avoidance",
}

# topic -> the SDLOG_PROFILE bits whose topic lists hold it (PX4 src/modules/logger/logged_topics.cpp; the
# older actuator_controls_0 from the PX4 1.13 version of that file)
_TOPIC_PROFILES: dict[str, tuple[int, ...]] = {
    "actuator_armed": (0,),
    "actuator_motors": (0, 3, 4),
    "actuator_outputs": (0,),
    "actuator_controls_0": (0, 3, 4),
    "battery_status": (0,),
    "control_allocator_status": (0,),
    "esc_status": (0, 4),
    "hover_thrust_estimate": (0,),
    "sensor_combined": (0, 1, 3, 4),
    "vehicle_acceleration": (0, 3),
    "vehicle_angular_acceleration": (3,),
    "vehicle_angular_velocity": (0, 3, 4),
    "vehicle_attitude": (0, 4),
    "vehicle_attitude_setpoint": (0, 4),
    "vehicle_control_mode": (0,),
    "vehicle_land_detected": (0, 1),
    "vehicle_local_position": (0,),
    "vehicle_rates_setpoint": (0, 4),
    "vehicle_status": (0, 1),
    "vehicle_thrust_setpoint": (0, 4),
    "vehicle_torque_setpoint": (0, 3, 4),
}


def logging_profile(topic: str) -> str:
    """Which PX4 logging profile logs ``topic``: the ``SDLOG_PROFILE`` bits (PX4 ``logged_topics.cpp``) or, for a
    topic no profile lists, the logger's topic file."""
    bits = _TOPIC_PROFILES.get(topic)
    if not bits:
        return "no standard SDLOG_PROFILE logs it: list it in the SD card's etc/logging/logger_topics.txt"
    names = [f"{_PROFILES[b]} (SDLOG_PROFILE bit {b}, value {1 << b})" for b in bits]
    return "logged by the " + " or the ".join(names) + " profile"


@dataclass(frozen=True)
class Series:
    """Samples of some fields of one topic.

    ``t_s``: (N,) seconds since the log start; ``t_us``: the same times in integer microseconds (exact, for matching
    samples); ``values``: (N, len(fields)) float64, PX4's units and frames; ``fields``: the field names;
    ``source``: where the values come from (the topic, or how they were derived from it).
    """

    t_s: np.ndarray
    values: np.ndarray
    fields: tuple[str, ...]
    t_us: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=np.int64))
    source: str = ""

    def column(self, name: str) -> np.ndarray:
        """The (N,) samples of field ``name``."""
        if name not in self.fields:
            raise InputError(f"column {name!r} is not in this series; its fields: {', '.join(self.fields)}")
        return self.values[:, self.fields.index(name)]

    def __len__(self) -> int:
        return len(self.t_s)


@dataclass(frozen=True)
class TopicInfo:
    """One logged topic instance: its name, ``multi_id``, sample count, mean rate [Hz] and field names."""

    name: str
    multi_id: int
    samples: int
    rate_hz: float
    fields: tuple[str, ...]


def _load_pyulog():
    try:
        from pyulog import ULog
    except ImportError:
        raise MissingDependencyError("pyulog", "reading PX4 flight logs (ULog)", 'pip install "qprr[flightlog]"') from None
    return ULog


def _open_ulog(path: Path):
    """pyulog's ULog of ``path``; InputError naming the path when it is missing, unreadable or not a ULog file."""
    if not path.is_file():
        raise InputError(f"flight log {str(path)!r} does not exist or is not a file: give the path of a .ulg file")
    try:
        with path.open("rb") as f:
            head = f.read(len(ULOG_MAGIC))
    except OSError as exc:
        raise InputError(f"flight log {str(path)!r} cannot be read ({exc.strerror or exc})") from None
    if head != ULOG_MAGIC:
        raise InputError(f"flight log {str(path)!r} is not a ULog file (it does not start with the ULog header): give a PX4 .ulg file")
    ULog = _load_pyulog()
    try:
        return ULog(str(path))
    except Exception as exc:  # pyulog raises bare exceptions on truncated or corrupt files
        raise InputError(f"flight log {str(path)!r} is not a readable ULog file ({type(exc).__name__}: {exc})") from None


def _number(value):
    return int(value) if isinstance(value, (int, np.integer)) else float(value)


class FlightLog:
    """A PX4 flight log read once (build it with :meth:`read`).

    Attributes: ``path``; ``parameters`` (name -> value, as at the log start); ``changed_parameters`` (list of
    ``(t_s, name, value)``); ``info`` (the ULog information messages as text: ``sys_name``, ``ver_hw``, ``ver_sw``...);
    ``duration_s``; ``airframe`` (``SYS_AUTOSTART``, None if not logged).
    """

    def __init__(self, path: Path, data: dict, start_us: int, last_us: int, parameters: dict, changed: list, info: dict) -> None:
        self.path = path
        self._data = data  # (name, multi_id) -> {field: ndarray}
        self._start_us = int(start_us)
        self.duration_s = (int(last_us) - int(start_us)) * 1e-6
        self.parameters = parameters
        self.changed_parameters = changed
        self.info = info
        autostart = parameters.get("SYS_AUTOSTART")
        self.airframe = int(autostart) if autostart is not None else None

    @classmethod
    def read(cls, path: str | Path) -> FlightLog:
        """Read a ``.ulg`` file; :class:`~qprr.errors.InputError` naming the path if it is missing, unreadable or
        not a ULog; :class:`~qprr.errors.MissingDependencyError` without pyulog."""
        p = Path(path)
        ulog = _open_ulog(p)
        start = int(ulog.start_timestamp)
        data = {(d.name, int(d.multi_id)): dict(d.data) for d in ulog.data_list}
        params = {k: _number(v) for k, v in ulog.initial_parameters.items()}
        changed = [((int(t) - start) * 1e-6, name, _number(v)) for t, name, v in ulog.changed_parameters]
        info = {k: str(v) for k, v in ulog.msg_info_dict.items()}
        return cls(p, data, start, int(ulog.last_timestamp), params, changed, info)

    def __repr__(self) -> str:
        return f"FlightLog({str(self.path)!r}, {self.duration_s:.1f} s, {len(self._data)} topic instances)"

    # -------------------------------------------------------------------------------------------- topics
    def _times_us(self, topic: str, multi_id: int, time_field: str = "timestamp") -> tuple[np.ndarray, np.ndarray]:
        """(mask of kept samples, int64 microseconds since the start of the kept samples)."""
        raw = self._data[(topic, multi_id)][time_field]
        ts = np.asarray(raw).astype(np.uint64)
        keep = ts != 0
        return keep, ts[keep].astype(np.int64) - np.int64(self._start_us)

    def topics(self) -> tuple[TopicInfo, ...]:
        """Every logged topic instance, sorted by name and ``multi_id``; the rate over its non-zero timestamps."""
        out = []
        for (name, mid), d in sorted(self._data.items()):
            _, t = self._times_us(name, mid)
            span = (t[-1] - t[0]) * 1e-6 if len(t) > 1 else 0.0
            rate = (len(t) - 1) / span if span > 0 else 0.0
            fields = tuple(k for k in d if k != "timestamp")
            out.append(TopicInfo(name, mid, len(t), float(rate), fields))
        return tuple(out)

    def has(self, topic: str, multi_id: int = 0) -> bool:
        """True if the log holds samples of ``topic`` instance ``multi_id``."""
        return (topic, multi_id) in self._data

    def fields(self, topic: str, multi_id: int = 0) -> tuple[str, ...]:
        """The field names of a topic (empty if the log lacks it)."""
        return tuple(self._data.get((topic, multi_id), {}))

    def missing(self, topic: str, needed_for: str) -> MissingTopicError:
        """The error for a topic this log lacks: its name, what needs it, the profile that logs it."""
        profile = self.parameters.get("SDLOG_PROFILE")
        this = f"; this log's SDLOG_PROFILE is {profile}" if profile is not None else ""
        return MissingTopicError(
            f"{self.path.name}: topic {topic!r} is not in the log; {needed_for} needs it ({logging_profile(topic)}{this})",
            topic,
        )

    def series(self, topic: str, fields, multi_id: int = 0, *, needed_for: str = "this computation", time_field: str = "timestamp") -> Series:
        """Fields of ``topic`` as float64 (NaN kept) against time; ``time_field``: the field giving the time
        (``timestamp``, or ``timestamp_sample`` where PX4 logs when the data was sampled). Raises
        :class:`~qprr.errors.MissingTopicError` when the topic or a field is missing."""
        names = (fields,) if isinstance(fields, str) else tuple(fields)
        if (topic, multi_id) not in self._data:
            raise self.missing(topic if multi_id == 0 else f"{topic} (instance {multi_id})", needed_for)
        d = self._data[(topic, multi_id)]
        absent = [f for f in (*names, time_field) if f not in d]
        if absent:
            raise MissingTopicError(
                f"{self.path.name}: topic {topic!r} has no field {', '.join(map(repr, absent))} "
                f"(a PX4 version with other message definitions); {needed_for} needs it; its fields: {', '.join(d)}",
                topic,
            )
        keep, t_us = self._times_us(topic, multi_id, time_field)
        values = np.column_stack([np.asarray(d[f], dtype=np.float64)[keep] for f in names]) if names else np.zeros((len(t_us), 0))
        order = np.argsort(t_us, kind="stable")
        return Series(t_us[order] * 1e-6, values[order], names, t_us[order], topic)

    def vector(
        self, topic: str, prefix: str, n: int, multi_id: int = 0, *, needed_for: str = "this computation", time_field: str = "timestamp"
    ) -> Series:
        """The array field ``prefix[0] .. prefix[n-1]`` of ``topic`` (e.g. ``xyz`` of ``vehicle_torque_setpoint``)."""
        return self.series(topic, [f"{prefix}[{i}]" for i in range(n)], multi_id, needed_for=needed_for, time_field=time_field)

    def parameter(self, name: str, default=None):
        """A parameter's value at the log start, ``default`` if the log does not hold it."""
        return self.parameters.get(name, default)


# ------------------------------------------------------------------------------------------------ motor commands
MAX_MOTORS = 12
PWM_DEFAULT_MIN_US, PWM_DEFAULT_MAX_US, PWM_DEFAULT_DISARMED_US = 1000.0, 2000.0, 900.0


def _rotor_count_param(log: FlightLog) -> int | None:
    n = log.parameter("CA_ROTOR_COUNT")
    return int(n) if n is not None and int(n) > 0 else None


def _from_actuator_motors(log: FlightLog, needed_for: str) -> Series:
    """actuator_motors.control[i]: PX4's normalised motor commands in [0, 1], NaN for a stopped motor
    (PX4 msg/ActuatorMotors.msg)."""
    fields = [f for f in log.fields("actuator_motors") if f.startswith("control[")]
    raw = log.series("actuator_motors", fields, needed_for=needed_for)
    n = _rotor_count_param(log)
    how = "CA_ROTOR_COUNT"
    if n is None:
        n = int(np.sum(np.any(np.isfinite(raw.values), axis=0)))
        how = "the channels that are not always NaN"
    values = raw.values[:, :n]
    return Series(raw.t_s, values, tuple(f"motor{i}" for i in range(n)), raw.t_us, f"actuator_motors ({n} rotors from {how})")


def _pwm_limits(log: FlightLog, channel: int) -> tuple[float, float, str]:
    """PWM range [us] of output ``channel`` (0-based): PWM_MAIN_MINn/MAXn (PX4 >= 1.13), else PWM_MAIN_MIN/MAX
    (older), else PX4's defaults 1000/2000 us."""
    k = channel + 1
    lo, hi = log.parameter(f"PWM_MAIN_MIN{k}"), log.parameter(f"PWM_MAIN_MAX{k}")
    if lo is not None and hi is not None:
        return float(lo), float(hi), "PWM_MAIN_MINn/MAXn"
    lo, hi = log.parameter("PWM_MAIN_MIN"), log.parameter("PWM_MAIN_MAX")
    if lo is not None and hi is not None:
        return float(lo), float(hi), "PWM_MAIN_MIN/MAX"
    return PWM_DEFAULT_MIN_US, PWM_DEFAULT_MAX_US, "PX4's default range 1000-2000 us (no PWM_MAIN_MIN/MAX in the log)"


def _motor_channels(log: FlightLog, pwm: np.ndarray, disarmed: float) -> tuple[list[int], str]:
    """Output channels of the motors: PWM_MAIN_FUNCn = 101..112 (Motor 1..12, PX4 >= 1.13), else the first
    CA_ROTOR_COUNT channels, else the channels that ever leave the disarmed value, else those sitting at it."""
    funcs = {int(log.parameter(f"PWM_MAIN_FUNC{k}", 0)) - 101: k - 1 for k in range(1, pwm.shape[1] + 1)}
    by_func = [funcs[i] for i in range(MAX_MOTORS) if i in funcs]
    n = _rotor_count_param(log)
    if by_func and (n is None or len(by_func) >= n):
        chans = by_func[: n or len(by_func)]
        return chans, f"{len(chans)} rotors, channels from PWM_MAIN_FUNCn"
    if n is not None:
        return list(range(min(n, pwm.shape[1]))), f"{n} rotors from CA_ROTOR_COUNT"
    moving = [i for i in range(pwm.shape[1]) if np.any(np.abs(pwm[:, i] - disarmed) > 1.0) and np.any(pwm[:, i] > 0)]
    if moving:
        return moving, f"{len(moving)} rotors: the channels that leave the disarmed value {disarmed:g} us"
    idle = [i for i in range(pwm.shape[1]) if np.all(np.abs(pwm[:, i] - disarmed) <= 1.0)]
    return idle, f"{len(idle)} rotors: the channels at the disarmed value {disarmed:g} us (no motor ever ran)"


def _from_actuator_outputs(log: FlightLog, needed_for: str) -> Series:
    """actuator_outputs.output[i] in PWM microseconds, normalised to [0, 1] as (pwm - min) / (max - min) with the
    log's PWM range (PX4 src/lib/mixer_module/mixer_module.cpp maps [0, 1] linearly onto [min, max]); the disarmed
    value (PWM_MAIN_DISARM, default 900 us) and anything below min - 1 us becomes NaN (stopped)."""
    fields = [f for f in log.fields("actuator_outputs") if f.startswith("output[")]
    raw = log.series("actuator_outputs", fields, needed_for=needed_for)
    disarmed = float(log.parameter("PWM_MAIN_DISARM", log.parameter("PWM_MAIN_DISARMED", PWM_DEFAULT_DISARMED_US)))
    chans, how = _motor_channels(log, raw.values, disarmed)
    cols, ranges = [], set()
    for c in chans:
        lo, hi, src = _pwm_limits(log, c)
        ranges.add(f"{lo:g}-{hi:g} us from {src}")
        u = (raw.values[:, c] - lo) / (hi - lo)
        u[raw.values[:, c] < lo - 1.0] = np.nan
        cols.append(np.clip(u, 0.0, 1.0))
    values = np.column_stack(cols) if cols else np.zeros((len(raw), 0))
    source = f"actuator_outputs in PWM normalised with {'; '.join(sorted(ranges)) or 'no channel'} ({how})"
    return Series(raw.t_s, values, tuple(f"motor{i}" for i in range(len(chans))), raw.t_us, source)


def motor_commands(log: FlightLog, needed_for: str = "the motor commands") -> Series:
    """Normalised motor commands in [0, 1] (NaN while a motor is stopped), one column per rotor (``motor0``...).

    From ``actuator_motors`` (PX4 >= 1.13's control allocator), else from ``actuator_outputs`` in PWM (older logs);
    ``Series.source`` says which and how the rotor count and PWM range were found."""
    if log.has("actuator_motors"):
        return _from_actuator_motors(log, needed_for)
    if log.has("actuator_outputs"):
        return _from_actuator_outputs(log, needed_for)
    raise MissingTopicError(
        f"{log.path.name}: neither 'actuator_motors' nor 'actuator_outputs' is in the log; {needed_for} needs one "
        f"({logging_profile('actuator_motors')})",
        "actuator_motors",
    )


__all__ = ["FlightLog", "Series", "TopicInfo", "logging_profile", "motor_commands"]
