"""What identification reads from a flight, in qprr's frames: :class:`FlightRecord` (from a ULog through
:mod:`qprr.flightlog.ulog`, PX4's FRD turned into qprr's FLU body frame by :mod:`qprr.flightstack.frames`), and the
arm's joint angles from a CSV file (:func:`read_joint_csv`).

The IMU is taken at the origin of the base frame B (PX4's IMU at the vehicle's reference point).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, UnknownNameError
from ..flightstack.frames import body_from_frd
from ..flightstack.px4 import Px4Geometry
from ..model import Platform, check_platform
from ..validation import as_file
from .phases import find_phases
from .ulog import FlightLog, motor_commands

IDENTIFY = "the identification"


@dataclass(frozen=True)
class JointSeries:
    """Arm joint angles of a flight: ``t_s`` (k,) seconds since the log start, ``names`` the URDF's joint names,
    ``q`` (k, n_arm) [rad or m]."""

    t_s: np.ndarray
    names: tuple[str, ...]
    q: np.ndarray


@dataclass(frozen=True)
class FlightRecord:
    """The samples identification fits, body vectors in qprr's B (FLU).

    t_imu_s (n,) [s]; specific_force_body (n, 3) [m/s^2] (the accelerometer: acceleration minus gravity);
    gyro_body (n, 3) [rad/s]; t_command_s (m,) [s]; commands (m, n_rotors) normalised motor commands [0, 1];
    geometry: PX4's rotor geometry from the log's CA_* parameters (FRD; only its positions, axes and KM are used,
    never its CT); imu_position_body: the IMU relative to the centre of gravity PX4 was told [m] (PX4's
    EKF2_IMU_POS_X/Y/Z, FRD -> B); thr_mdl_fac: PX4's THR_MDL_FAC (thrust = ct (f u^2 + (1 - f) u)); airborne: (start, end) [s]
    intervals; joints: the arm's angles (None for a rigid multirotor); source: the file name.
    """

    t_imu_s: np.ndarray
    specific_force_body: np.ndarray
    gyro_body: np.ndarray
    t_command_s: np.ndarray
    commands: np.ndarray
    geometry: Px4Geometry
    thr_mdl_fac: float
    airborne: tuple[tuple[float, float], ...]
    joints: JointSeries | None = None
    source: str = ""
    imu_position_body: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def command_rate_hz(self) -> float:
        """The median rate the motor commands were logged at [Hz]."""
        return float(1.0 / np.median(np.diff(self.t_command_s)))


def record_from_log(log: FlightLog, joints: JointSeries | None = None) -> FlightRecord:
    """The :class:`FlightRecord` of ``log``: ``sensor_combined`` (accelerometer, gyro), the motor commands
    (:func:`qprr.flightlog.ulog.motor_commands`), the CA_* geometry, THR_MDL_FAC and the airborne intervals
    (:func:`qprr.flightlog.phases.find_phases`).  A log without a flight raises :class:`~qprr.errors.NoFlightError`,
    a missing topic :class:`~qprr.errors.MissingTopicError` naming it and the logging profile."""
    phases = find_phases(log)
    phases.require_flight(IDENTIFY)
    imu = log.series(
        "sensor_combined",
        [f"accelerometer_m_s2[{i}]" for i in range(3)] + [f"gyro_rad[{i}]" for i in range(3)],
        needed_for=f"{IDENTIFY} (the specific force and the body rates)",
    )
    cmd = motor_commands(log, f"{IDENTIFY} (the thrust model)")
    geometry = Px4Geometry.from_parameters(log.parameters)
    if cmd.values.shape[1] < geometry.n:
        raise InputError(f"{log.path.name}: {cmd.values.shape[1]} motor commands logged for CA_ROTOR_COUNT = {geometry.n} rotors")
    u = np.nan_to_num(cmd.values[:, : geometry.n], nan=0.0)
    return FlightRecord(
        imu.t_s,
        body_from_frd(imu.values[:, 0:3]),
        body_from_frd(imu.values[:, 3:6]),
        cmd.t_s,
        u,
        geometry,
        float(log.parameter("THR_MDL_FAC", 0.0)),
        phases.airborne,
        joints,
        log.path.name,
        tuple(float(x) for x in body_from_frd(np.array([float(log.parameter(f"EKF2_IMU_POS_{k}", 0.0)) for k in "XYZ"]))),
    )


def read_joint_csv(path: str | Path, platform: Platform) -> JointSeries:
    """Joint angles from a CSV file: a header ``time`` then joint names as in the platform's URDF (every arm joint
    once), one row per sample, time in seconds since the log start, angles in rad (m for prismatic joints).  Missing
    or unknown names raise :class:`~qprr.errors.UnknownNameError` naming them and the URDF's joints."""
    platform = check_platform(platform)
    path = as_file(path, "joints", what="joint-angle CSV file")
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows or not rows[0] or rows[0][0].strip() != "time":
        raise InputError(f"joints: {path.name} must start with a header 'time,<joint names>' (joints: {', '.join(platform.arm_names)})")
    header = [h.strip() for h in rows[0][1:]]
    unknown = [h for h in header if h not in platform.arm_names]
    if unknown:
        raise UnknownNameError(f"joint in {path.name}", unknown[0], platform.arm_names)
    missing = [n for n in platform.arm_names if n not in header]
    if missing or len(set(header)) != len(header):
        raise InputError(
            f"joints: {path.name} must give every arm joint once; missing {missing}, header {header}; "
            f"the URDF's joints: {', '.join(platform.arm_names)}"
        )
    try:
        data = np.array([[float(x) for x in r] for r in rows[1:] if r], dtype=float)
    except ValueError as exc:
        raise InputError(f"joints: {path.name} holds a value that is not a number ({exc})") from None
    if data.ndim != 2 or data.shape[0] < 4 or data.shape[1] != len(header) + 1 or not np.all(np.isfinite(data)):
        raise InputError(f"joints: {path.name} needs at least 4 rows of {len(header) + 1} finite numbers")
    if np.any(np.diff(data[:, 0]) <= 0.0):
        raise InputError(f"joints: the times of {path.name} must increase")
    order = [header.index(n) + 1 for n in platform.arm_names]
    return JointSeries(data[:, 0], platform.arm_names, data[:, order])


def write_joint_csv(path: str | Path, joints: JointSeries) -> Path:
    """Write ``joints`` in the format :func:`read_joint_csv` reads."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time", *joints.names])
        for t, q in zip(joints.t_s, joints.q):
            w.writerow([repr(float(t)), *(repr(float(x)) for x in q)])
    return path
