"""ULog files written from simulated flights of any platform, with the truth beside them (the tests and the docs).

A flight is :func:`qprr.sim.simulate` of a mission (a climb, steps of x, y and yaw, the arm swept through its range,
a descent) under qprr's IDC controller with gains for the motor lag (:func:`qprr.scenarios.missions.lag_gains`), the rotors
behind the first-order motor lag of :class:`qprr.sim.actuators.RotorDynamics`.  The log holds what PX4 logs
(topics and fields of PX4 1.15's msg/ definitions), in PX4's frames (:mod:`qprr.flightstack.frames`):

* ``vehicle_status`` (arming_state 2 while armed), ``actuator_motors`` at 10 Hz (PX4's default logging profile;
  command = thrust / f_max: CT = f_max, THR_MDL_FAC = 0), ``sensor_combined`` at 250 Hz (specific force and body
  rates in FRD, white noise added), ``vehicle_attitude``, ``vehicle_local_position``, ``vehicle_thrust_setpoint``
  and ``vehicle_torque_setpoint`` at 50 Hz;
* the CA_* parameters of :func:`qprr.flightstack.px4.geometry_from_platform` (positions from the centre of gravity at
  the neutral pose);
* two seconds armed on the ground before the flight and after it.

The specific force is the classical acceleration of B's origin minus gravity, from Pinocchio's ``aba`` at each tick
with the thrusts the rotors produce there.

The ULog bytes are written here (:func:`write_ulog`), not by pyulog: pyulog's writer (``ULog.write_ulog``) only
re-writes a log it has read (it serialises a parsed ``ULog`` object), it cannot make one from arrays.  The format is
PX4's ULog specification (docs.px4.io/main/en/dev_log/ulog_file_format.html, "ULog File Format": the 16-byte
header with magic ``ULog\x01\x12\x35``, version and start time; the 'B' flag bits; 'F' formats; 'P' parameters;
'A' subscriptions; 'D' data, each message a uint16 size and a uint8 type before its payload, little-endian).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..charts import euler_to_rotation_batch, xi_to_qv
from ..control import make_controller
from ..errors import InputError
from ..flightstack.frames import R_ned_frd_from_world_body, frd_from_body, ned_from_world
from ..flightstack.px4 import com_body_at, geometry_from_platform
from ..model import Platform, check_platform
from ..scenarios.missions import lag_gains
from ..sim import SimConfig, SimInputs, simulate
from ..sim.actuators import RotorDynamics
from ..trajectory import MultiPhase, Phase
from ..validation import as_int, as_real
from .inertial import parameter_values
from .record import JointSeries, write_joint_csv


@dataclass(frozen=True)
class SynthOptions:
    """duration_s of the flight; motor_time_constant [s]; accel_noise [m/s^2] and gyro_noise [rad/s]: std of the white
    noise on each IMU sample; command_rate_hz (PX4's default profile: 10); imu_rate_hz (250); arm_sweep: the fraction
    of the arm's range the mission sweeps; seed; steps: the largest step of x, y [m] and yaw [rad] (0: a hover, no
    excitation)."""

    duration_s: float = 20.0
    motor_time_constant: float = 0.005
    accel_noise: float = 0.05
    gyro_noise: float = 0.01
    command_rate_hz: float = 10.0
    imu_rate_hz: float = 250.0
    arm_sweep: float = 0.6
    seed: int = 0
    steps: float = 0.6

    def __post_init__(self) -> None:
        object.__setattr__(self, "duration_s", as_real(self.duration_s, "duration_s", positive=True, unit="s"))
        object.__setattr__(self, "motor_time_constant", as_real(self.motor_time_constant, "motor_time_constant", positive=True, unit="s"))
        for name in ("accel_noise", "gyro_noise", "arm_sweep", "steps"):
            object.__setattr__(self, name, as_real(getattr(self, name), name, nonnegative=True))
        for name in ("command_rate_hz", "imu_rate_hz"):
            object.__setattr__(self, name, as_real(getattr(self, name), name, positive=True, unit="Hz"))
        object.__setattr__(self, "seed", as_int(self.seed, "seed", lo=0))


@dataclass(frozen=True)
class SynthLog:
    """A written log and its truth: ``path`` (the .ulg), ``joints_csv`` (None for a rigid multirotor), ``truth``:
    ct [N] (f_max), mass [kg], hover_command, motor_time_constant [s], gravity [m/s^2], and per moving body
    (``base``, then the link of each arm joint) its mass, centre of gravity in its frame and inertia about it;
    ``rigid``: the whole robot at the neutral pose, its centre of gravity in B and its inertia about it (B's axes)."""

    path: Path
    joints_csv: Path | None
    truth: dict = field(default_factory=dict)


def excitation_mission(platform: Platform, duration: float, sweep: float, seed: int, steps: float = 0.6) -> MultiPhase:
    """Climb to 1.5 m (first 12 %), steps of x, y and yaw of random sizes up to ``steps`` [m, rad], the arm swept
    ``sweep`` of its range back and forth, a descent to 0.2 m (last 12 %)."""
    rng = np.random.default_rng(seed)
    D = duration
    phases = [Phase("z", 0.0, 0.12 * D, 1.5)]
    n = 8
    edges = np.linspace(0.15 * D, 0.85 * D, n + 1)
    for k in range(n):
        a, b = float(edges[k]), float(edges[k + 1])
        phases.append(Phase("xyz"[k % 2] if k % 3 else "psi", a, b, float(rng.uniform(-steps, steps))))
    lo, hi = platform.arm_lower, platform.arm_upper
    q0 = platform.neutral_q()[7:]
    for j, name in enumerate(platform.arm_names):
        span = (hi[j] - lo[j]) if np.isfinite(hi[j] - lo[j]) else 2.0
        mid = 0.5 * (hi[j] + lo[j]) if np.isfinite(hi[j] + lo[j]) else q0[j]
        for k in range(4):
            a, b = 0.15 * D + k * 0.175 * D, 0.15 * D + (k + 1) * 0.175 * D
            phases.append(Phase(name, a, b, float(mid + (0.5 if k % 2 == 0 else -0.5) * sweep * span * (1 if j % 2 == 0 else -1))))
    phases.append(Phase("z", 0.88 * D, D, 0.2))
    return MultiPhase(tuple(phases), tuple(platform.neutral_xi()), name="identification", names=platform.xi_names)


def fly_excitation(platform: Platform, options: SynthOptions):
    """The simulated flight (module docstring): the SimResult, dt 1 ms, control period 2 ms."""
    T = options.motor_time_constant
    rotors = RotorDynamics.for_rotors(platform.rotors, 1e-5, T, initial="hover")
    ctrl = make_controller("idc", platform, **lag_gains("idc", platform, T))
    traj = excitation_mission(platform, options.duration_s, options.arm_sweep, options.seed, options.steps)
    config = SimConfig(dt=1e-3, control_period=2e-3, seed=options.seed)
    return simulate(platform, ctrl, traj, options.duration_s, config=config, inputs=SimInputs(actuators=rotors))


def imu(platform: Platform, res) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(specific force (m, 3) in B [m/s^2], body rates (m, 3) [rad/s], R_world_body (m, 3, 3)) at every tick of ``res``:
    Pinocchio's aba with the produced thrusts and the arm efforts, a_B = dv/dt + omega x v - R^T g."""
    model = platform.model
    data = model.createData()
    Omega = np.array(platform.rotor_matrix)
    g_world = np.array(model.gravity.linear)
    R = euler_to_rotation_batch(res.xi[:, 3:6])
    f_spec = np.empty((res.n, 3))
    omega = np.empty((res.n, 3))
    for k in range(res.n):
        q, v = xi_to_qv(res.xi[k], res.xi_dot[k])
        tau = np.concatenate([Omega @ res.f[k], res.arm_effort[k]])
        a = pin.aba(model, data, q, v, tau)
        f_spec[k] = a[0:3] + np.cross(v[3:6], v[0:3]) - R[k].T @ g_world
        omega[k] = v[3:6]
    return f_spec, omega, R


def _quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Hamilton quaternion (w, x, y, z) of a rotation matrix (Pinocchio's Quaternion, coefficients x, y, z, w)."""
    c = pin.Quaternion(R).coeffs()
    return np.array([c[3], c[0], c[1], c[2]])


def synth_log(platform: Platform, path, options: SynthOptions | None = None) -> SynthLog:
    """Fly ``platform`` (module docstring) and write the ULog to ``path`` (and the joint angles beside it,
    ``<stem>.joints.csv``, for an aerial manipulator); returns the :class:`SynthLog` with the truth."""
    platform = check_platform(platform)
    options = SynthOptions() if options is None else options
    if not isinstance(options, SynthOptions):
        raise InputError(f"options must be a SynthOptions, got {type(options).__name__}")
    path = Path(path)
    res = fly_excitation(platform, options)
    f_max = np.array([r.f_max for r in platform.rotors])
    rng = np.random.default_rng(options.seed + 1)
    f_spec, omega, R = imu(platform, res)
    t0 = 2.0  # seconds armed on the ground before the flight
    topics = _topics(platform, res, options, (f_spec, omega, R), f_max, rng, t0)
    params = {**geometry_from_platform(platform).parameters(), "THR_MDL_FAC": 0.0, "SDLOG_PROFILE": 1, "MPC_THR_HOVER": 0.5}
    imu_pos = frd_from_body(-com_body_at(platform))  # the IMU at B's origin, relative to the centre of gravity
    params.update({f"EKF2_IMU_POS_{k}": float(x) for k, x in zip("XYZ", imu_pos)})
    write_ulog(path, topics, params)
    joints_csv = None
    if platform.n_arm:
        joints_csv = write_joint_csv(path.with_suffix(".joints.csv"), JointSeries(res.t + t0, platform.arm_names, res.xi[:, 6:]))
    return SynthLog(path, joints_csv, truth(platform, options))


def truth(platform: Platform, options: SynthOptions) -> dict:
    """The simulated values identification should find (:class:`SynthLog`)."""
    f_max = np.array([r.f_max for r in platform.rotors])
    a_z = np.array([r.axis_body[2] for r in platform.rotors])
    g = platform.g
    out = {
        "ct": float(f_max[0]),
        "mass": platform.total_mass,
        "hover_command": float(platform.total_mass * g / (f_max @ a_z)),
        "motor_time_constant": options.motor_time_constant,
        "gravity": g,
    }
    model = platform.model
    for j in range(1, model.njoints):
        links = [f.name for f in model.frames if f.parentJoint == j and f.type == pin.FrameType.BODY]
        name = "base" if j == 1 else (links[0] if links else model.names[j])
        Y = model.inertias[j]
        I_c = np.array(Y.inertia)
        out[name] = {"mass": float(Y.mass), "com": np.array(Y.lever).tolist(), "inertia": np.diag(I_c).tolist()}
    data = model.createData()
    pin.ccrba(model, data, platform.neutral_q(), np.zeros(model.nv))
    out["parameters"] = parameter_values(model, out["ct"])
    out["rigid"] = {"cog": com_body_at(platform).tolist(), "inertia": np.diag(data.Ig.inertia).tolist()}
    return out


def _every(res, rate_hz: float) -> np.ndarray:
    """Indices of the ticks of ``res`` at ``rate_hz``."""
    step = max(1, int(round(1.0 / (rate_hz * res.control_period))))
    return np.arange(0, res.n, step)


def _ground(t0: float, t_end: float, rate: float) -> np.ndarray:
    return np.arange(t0, t_end, 1.0 / rate)


def _topics(platform: Platform, res, options: SynthOptions, imu_data, f_max: np.ndarray, rng, t0: float) -> dict:
    """topic -> (fields [(type, name)], columns {name: array}) of the log (module docstring); times in s since the start."""
    f_spec, omega, R = imu_data
    t_end = t0 + res.t[-1] + 2.0
    n_r = platform.n_rotors
    # the IMU: on the ground before and after (1 g up, at rest), the flight between
    k = _every(res, options.imu_rate_hz)
    g_pre, g_post = _ground(0.0, t0, options.imu_rate_hz), _ground(t0 + res.t[-1] + 1e-3, t_end, options.imu_rate_hz)
    rest = np.array([0.0, 0.0, platform.g])  # at rest on the ground: 1 g up, the plant's own g
    t_imu = np.concatenate([g_pre, t0 + res.t[k], g_post])
    acc = np.vstack([np.tile(rest, (g_pre.size, 1)), f_spec[k], np.tile(rest, (g_post.size, 1))])
    gyr = np.vstack([np.zeros((g_pre.size, 3)), omega[k], np.zeros((g_post.size, 3))])
    acc = frd_from_body(acc + options.accel_noise * rng.standard_normal(acc.shape))
    gyr = frd_from_body(gyr + options.gyro_noise * rng.standard_normal(gyr.shape))
    sensor = {"timestamp": t_imu, "gyro_rad": gyr, "gyro_integral_dt": np.full(t_imu.size, 1e6 / options.imu_rate_hz), "accelerometer_m_s2": acc}
    # the motor commands at the logging rate: idle on the ground
    k = _every(res, options.command_rate_hz)
    c_pre, c_post = _ground(0.0, t0, options.command_rate_hz), _ground(t0 + res.t[-1] + 1e-3, t_end, options.command_rate_hz)
    u = np.clip(res.series["thrust_command"] / f_max, 0.0, 1.0)
    u_all = np.vstack([np.full((c_pre.size, n_r), 0.05), u[k], np.full((c_post.size, n_r), 0.05)])
    control = np.full((u_all.shape[0], 12), np.nan)
    control[:, :n_r] = u_all
    t_cmd = np.concatenate([c_pre, t0 + res.t[k], c_post])
    motors = {"timestamp": t_cmd, "timestamp_sample": t_cmd, "control": control}
    # attitude, position, set points at 50 Hz
    k = _every(res, 50.0)
    t50 = t0 + res.t[k]
    q = np.array([_quat_wxyz(Rn) for Rn in R_ned_frd_from_world_body(R[k])])
    attitude = {"timestamp": t50, "timestamp_sample": t50, "q": q}
    p, v = ned_from_world(res.xi[k, 0:3]), ned_from_world(res.xi_dot[k, 0:3])
    position = {
        "timestamp": t50,
        "timestamp_sample": t50,
        **{n: p[:, i] for i, n in enumerate("xyz")},
        **{f"v{n}": v[:, i] for i, n in enumerate("xyz")},
    }
    mix = geometry_from_platform(platform).mix()
    sp = np.clip(res.series["thrust_command"][k] / f_max, 0.0, 1.0) @ np.linalg.pinv(mix).T
    torque = {"timestamp": t50, "timestamp_sample": t50, "xyz": sp[:, 0:3]}
    thrust = {"timestamp": t50, "timestamp_sample": t50, "xyz": sp[:, 3:6]}
    status = {"timestamp": np.array([0.0, 1.0, t_end - 1.0]), "arming_state": np.array([1, 2, 1]), "nav_state": np.array([4, 4, 4])}
    f3, u64 = "float", "uint64_t"
    return {
        "vehicle_status": ([("uint8_t", "arming_state"), ("uint8_t", "nav_state")], status),
        "sensor_combined": ([(f"{f3}[3]", "gyro_rad"), ("uint32_t", "gyro_integral_dt"), (f"{f3}[3]", "accelerometer_m_s2")], sensor),
        "actuator_motors": ([(u64, "timestamp_sample"), (f"{f3}[12]", "control")], motors),
        "vehicle_attitude": ([(u64, "timestamp_sample"), (f"{f3}[4]", "q")], attitude),
        "vehicle_local_position": ([(u64, "timestamp_sample")] + [(f3, n) for n in ("x", "y", "z", "vx", "vy", "vz")], position),
        "vehicle_torque_setpoint": ([(u64, "timestamp_sample"), (f"{f3}[3]", "xyz")], torque),
        "vehicle_thrust_setpoint": ([(u64, "timestamp_sample"), (f"{f3}[3]", "xyz")], thrust),
    }


_DTYPE = {"uint64_t": "<u8", "uint32_t": "<u4", "uint8_t": "u1", "int32_t": "<i4", "float": "<f4"}


def _message(kind: bytes, payload: bytes) -> bytes:
    """One ULog message: uint16 size, uint8 type, payload (PX4's ULog specification)."""
    return np.array([len(payload)], "<u2").tobytes() + kind[:1] + payload


def _field_dtype(t: str) -> tuple:
    base = _DTYPE[t.split("[")[0]]
    return (base, (int(t.split("[")[1][:-1]),)) if "[" in t else (base,)


def write_ulog(path, topics: dict, parameters: dict) -> Path:
    """Write a ULog file: header (magic, version 1, start time 0), flag bits, one 'F' format and one 'A' subscription per
    topic, the parameters ('P': int32_t for ints, float otherwise), then the 'D' samples in time order.  Times in
    ``topics`` are seconds (written as microseconds); every topic's format starts with ``uint64_t timestamp``."""
    path = Path(path)
    out = bytearray(b"ULog\x01\x12\x35" + bytes([1]) + bytes(8))
    out += _message(b"B", bytes(16 + 24))
    data = []
    for msg_id, (name, (fields, cols)) in enumerate(topics.items()):
        spec = [("uint64_t", "timestamp"), *fields]
        out += _message(b"F", f"{name}:{''.join(f'{t} {n};' for t, n in spec)}".encode())
        dtype = np.dtype([("msg_id", "<u2")] + [(n, *_field_dtype(t)) for t, n in spec])
        t_us = np.round(np.asarray(cols["timestamp"]) * 1e6).astype(np.int64)
        rows = np.zeros(t_us.size, dtype)
        rows["msg_id"] = msg_id
        rows["timestamp"] = t_us
        for t, n in fields:
            rows[n] = np.round(np.asarray(cols[n]) * 1e6) if t == "uint64_t" else np.asarray(cols[n])
        data += [(int(t_us[i]), msg_id, rows[i : i + 1].tobytes()) for i in range(t_us.size)]
    for key, value in parameters.items():
        kind = "int32_t" if isinstance(value, (int, np.integer)) and not isinstance(value, bool) else "float"
        k = f"{kind} {key}".encode()
        out += _message(b"P", bytes([len(k)]) + k + np.array([value], _DTYPE[kind]).tobytes())
    for msg_id, name in enumerate(topics):
        out += _message(b"A", bytes([0]) + np.array([msg_id], "<u2").tobytes() + name.encode())
    for _, _, payload in sorted(data, key=lambda d: (d[0], d[1])):
        out += _message(b"D", payload)
    path.write_bytes(bytes(out))
    return path
