"""A flight log replayed: PX4's mix rebuilt from the log's own ``CA_*`` parameters, and the IMU predicted from the
motor commands through a qprr platform.

1. The mix. PX4's control allocator (src/modules/control_allocator/ControlAllocator.cpp) turns the normalised
   ``vehicle_torque_setpoint.xyz`` and ``vehicle_thrust_setpoint.xyz`` (FRD) into ``actuator_motors.control`` with the
   normalised pseudo-inverse of the effectiveness matrix (:meth:`qprr.flightstack.px4.Px4Geometry.mix`), then
   desaturates (ControlAllocationSequentialDesaturation.cpp). ``actuator_motors.timestamp_sample`` is the
   ``timestamp_sample`` of the torque set point it was computed from, so the three topics are matched exactly on it.
   Where no motor saturates (every predicted and logged command strictly inside (0, 1), armed) the desaturation
   changes nothing and the prediction must equal the log to float32 round-off.
2. The IMU. Each rotor's thrust is ``f_max u`` (PX4's model: ``CA_ROTORi_CT`` is the thrust at full command, linear in
   the command its allocator outputs), applied on the platform (rigid, arm at its neutral pose, no drag, no motor lag):
   the specific force ``sum f_i a_i / m`` and the angular acceleration ``I^-1 (tau - w x I w)`` about the centre of
   gravity, both in FRD (:mod:`qprr.flightstack.frames`), compared with ``sensor_combined`` (accelerometer; the
   derivative of the gyro) while airborne, at the motor commands' times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..flightstack.frames import body_from_frd, frd_from_body
from ..flightstack.px4 import STANDARD_GRAVITY, Px4Geometry, rotors_from_geometry
from ..model import Platform, from_model
from ..platforms import multirotor_model
from ..viz.plots import new_figure
from .phases import Phases
from .ulog import FlightLog, Series, motor_commands

IMU_WINDOW_S = 0.02  # half-width of the window the IMU is averaged (and the gyro differentiated) over [s]


@dataclass(frozen=True)
class MixReplay:
    """PX4's mix against the log: ``t_s`` (N,) matched samples; ``predicted``/``logged`` (N, n) motor commands;
    ``unsaturated`` (N,) mask of the samples compared; ``max_residual`` over them (nan if none)."""

    t_s: np.ndarray
    predicted: np.ndarray
    logged: np.ndarray
    unsaturated: np.ndarray
    geometry: Px4Geometry

    @property
    def max_residual(self) -> float:
        if not self.unsaturated.any():
            return float("nan")
        return float(np.max(np.abs(self.predicted - self.logged)[self.unsaturated]))


def _matched(series: list[Series]) -> tuple[np.ndarray, list[np.ndarray]]:
    """The integer times common to every series and each series' row indices at them."""
    common = series[0].t_us
    for s in series[1:]:
        common = np.intersect1d(common, s.t_us)
    return common, [np.searchsorted(s.t_us, common) for s in series]


def _in(t: np.ndarray, intervals) -> np.ndarray:
    mask = np.zeros(len(t), dtype=bool)
    for a, b in intervals:
        mask |= (t >= a) & (t <= b)
    return mask


def replay_mix(log: FlightLog, phases: Phases) -> MixReplay:
    """Predict ``actuator_motors`` from the torque and thrust set points through PX4's mix of the log's ``CA_*``."""
    what = "replaying PX4's mix"
    geometry = Px4Geometry.from_parameters(log.parameters)
    n = geometry.n
    tq = log.vector("vehicle_torque_setpoint", "xyz", 3, needed_for=what, time_field="timestamp_sample")
    th = log.vector("vehicle_thrust_setpoint", "xyz", 3, needed_for=what, time_field="timestamp_sample")
    am = log.vector("actuator_motors", "control", n, needed_for=what, time_field="timestamp_sample")
    t_us, (iq, it, ia) = _matched([tq, th, am])
    if len(t_us) == 0:
        raise InputError(f"{log.path.name}: no actuator_motors sample shares its timestamp_sample with the torque and thrust set points")
    control = np.hstack([tq.values[iq], th.values[it]])
    predicted = geometry.allocate(control)
    logged = am.values[ia]
    t_s = t_us * 1e-6
    inside = np.all((logged > 0.0) & (logged < 1.0) & (predicted > 0.0) & (predicted < 1.0), axis=1)
    return MixReplay(t_s, predicted, logged, inside & _in(t_s, phases.armed), geometry)


def platform_from_log(log: FlightLog, hover_command: float) -> Platform:
    """A rigid multirotor with the log's ``CA_*`` rotors (thrust at full command CT): its mass from the hover balance
    ``m g = sum CT_i u_hover`` (so it cannot test the mean thrust), its inertia example-robot-data's 3DR Iris
    (``iris_simple.urdf``) scaled to that mass. The ``CA_*`` of a SITL log are the airframe's parameters, not
    necessarily the simulated plant's."""
    geometry = Px4Geometry.from_parameters(log.parameters)
    rotors = rotors_from_geometry(geometry)
    mass = float(sum(r.ct for r in geometry.rotors) * hover_command / STANDARD_GRAVITY)
    model = multirotor_model("iris")
    body = model.inertias[1]
    model.inertias[1] = pin.Inertia(mass, np.zeros(3), body.inertia * (mass / body.mass))
    model.gravity.linear = np.array([0.0, 0.0, -STANDARD_GRAVITY])
    return from_model(
        model, rotors, ee_frame="iris__base_link", name=f"{log.path.name} CA_* rotors", rotor_source=f"{log.path.name} (CA_* parameters)"
    )


def _predict(platform: Platform, u: np.ndarray, gyro_frd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Specific force [m/s^2] and angular acceleration [rad/s^2] (N, 3), FRD, for commands ``u`` (N, n)."""
    q = platform.neutral_q()
    data = platform.model.createData()
    pin.ccrba(platform.model, data, q, np.zeros(platform.model.nv))
    mass, com = data.Ig.mass, np.array(pin.centerOfMass(platform.model, data, q))
    inertia = data.Ig.inertia  # about the centre of gravity, B axes (the base is level at the neutral pose)
    f = np.nan_to_num(u, nan=0.0) * platform.thrust_max  # thrust of each rotor [N]
    force_b = np.zeros((len(u), 3))
    torque_b = np.zeros((len(u), 3))
    for i, r in enumerate(platform.rotors):
        a, p = np.array(r.axis_body), np.array(r.position_body) - com
        force_b += np.outer(f[:, i], a)
        torque_b += np.outer(f[:, i], np.cross(p, a) + r.spin * r.kappa * a)
    w_b = body_from_frd(gyro_frd)
    alpha_b = np.linalg.solve(inertia, (torque_b - np.cross(w_b, w_b @ inertia.T)).T).T
    return frd_from_body(force_b / mass), frd_from_body(alpha_b)


def _imu_at(log: FlightLog, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Accelerometer mean, gyro mean and gyro slope (FRD) over +-IMU_WINDOW_S around each time of ``t``."""
    what = "comparing with the IMU"
    acc = log.vector("sensor_combined", "accelerometer_m_s2", 3, needed_for=what)
    gyr = log.vector("sensor_combined", "gyro_rad", 3, needed_for=what)
    out = np.full((3, len(t), 3), np.nan)
    for k, tk in enumerate(t):
        w = np.abs(gyr.t_s - tk) <= IMU_WINDOW_S
        if w.sum() >= 3:
            out[0, k] = acc.values[w].mean(axis=0)
            out[1, k] = gyr.values[w].mean(axis=0)
            out[2, k] = np.polyfit(gyr.t_s[w] - tk, gyr.values[w], 1)[0]
    return out[0], out[1], out[2]


@dataclass(frozen=True)
class ImuReplay:
    """The IMU predicted from the motor commands: ``t_s`` (N,) airborne motor-command times; specific force and
    angular acceleration predicted and measured (N, 3), FRD; ``platform``: the platform used and ``platform_note``."""

    t_s: np.ndarray
    force_predicted: np.ndarray
    force_measured: np.ndarray
    alpha_predicted: np.ndarray
    alpha_measured: np.ndarray
    platform_note: str

    def rms(self) -> tuple[np.ndarray, np.ndarray]:
        """(3,) RMS errors of the specific force [m/s^2] and of the angular acceleration [rad/s^2], FRD x, y, z."""
        ok = np.all(np.isfinite(self.force_measured), axis=1)
        ef = self.force_predicted[ok] - self.force_measured[ok]
        ea = self.alpha_predicted[ok] - self.alpha_measured[ok]
        return np.sqrt(np.mean(ef**2, axis=0)), np.sqrt(np.mean(ea**2, axis=0))


def replay_imu(log: FlightLog, phases: Phases, platform: Platform | None = None) -> ImuReplay:
    """Predict the IMU while airborne from the motor commands through ``platform`` (default
    :func:`platform_from_log`)."""
    phases.require_flight("replaying the IMU")
    if platform is None:
        platform = platform_from_log(log, phases.hover_command)
        note = f"{platform.name}: mass {platform.total_mass:.3f} kg from the hover balance, inertia of a 3DR Iris scaled to it"
    else:
        note = f"platform {platform.name}: mass {platform.total_mass:.3f} kg, its rotors' f_max as the thrust at full command"
    u = motor_commands(log, "replaying the IMU")
    if u.values.shape[1] != platform.n_rotors:
        raise InputError(
            f"the log has {u.values.shape[1]} motors ({u.source}) but platform {platform.name!r} has "
            f"{platform.n_rotors} rotors: give a platform with as many"
        )
    airborne = _in(u.t_s, phases.airborne)
    t = u.t_s[airborne]
    acc, gyro, alpha = _imu_at(log, t)
    force_p, alpha_p = _predict(platform, u.values[airborne], np.nan_to_num(gyro))
    return ImuReplay(t, force_p, acc, alpha_p, alpha, note)


@dataclass(frozen=True)
class ReplayResult:
    """The replay of a log: PX4's mix (:class:`MixReplay`) and the IMU (:class:`ImuReplay`)."""

    log_name: str
    mix: MixReplay
    imu: ImuReplay

    def summary(self) -> str:
        m, i = self.mix, self.imu
        rf, ra = i.rms()
        lines = [
            f"{self.log_name}: PX4's mix rebuilt from the log's CA_* ({m.geometry.n} rotors)",
            f"  {len(m.t_s)} actuator_motors samples matched on timestamp_sample, {int(m.unsaturated.sum())} unsaturated",
            f"max residual {m.max_residual:.3e}",
            f"IMU from the motor commands ({len(i.t_s)} airborne samples) through {i.platform_note}",
            "  specific force RMS error (FRD x, y, z): " + ", ".join(f"{x:.3f}" for x in rf) + " m/s^2",
            "  angular acceleration RMS error (FRD x, y, z): " + ", ".join(f"{x:.3f}" for x in ra) + " rad/s^2",
        ]
        return "\n".join(lines)

    def plot(self, path) -> None:
        """Save the figure: the logged and predicted motor commands; specific force z and angular accelerations."""
        fig = new_figure((11, 9))
        axes = fig.subplots(3, 1, sharex=True)
        m, i = self.mix, self.imu
        for k in range(m.logged.shape[1]):
            axes[0].plot(m.t_s, m.logged[:, k], lw=1.0, label=f"motor {k + 1} logged")
            axes[0].plot(m.t_s, m.predicted[:, k], "k:", lw=0.8)
        axes[0].set_ylabel("command [0-1]")
        axes[0].set_title(
            f"actuator_motors logged (colours) and PX4's mix replayed (dotted): max residual {m.max_residual:.2e}", loc="left", fontsize=10
        )
        axes[1].plot(i.t_s, i.force_measured[:, 2], label="IMU")
        axes[1].plot(i.t_s, i.force_predicted[:, 2], label="predicted")
        axes[1].set_ylabel("specific force z (FRD) [m/s^2]")
        for k, name in enumerate("xyz"):
            axes[2].plot(i.t_s, i.alpha_measured[:, k], lw=1.0, label=f"{name} gyro derivative")
            axes[2].plot(i.t_s, i.alpha_predicted[:, k], ":", lw=1.0, label=f"{name} predicted")
        axes[2].set_ylabel("angular acceleration (FRD) [rad/s^2]")
        axes[2].set_xlabel("time since the log start [s]")
        for ax in axes:
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper left", fontsize=7, ncols=4)
        fig.suptitle(f"{self.log_name}: replay through {i.platform_note}", fontsize=10)
        fig.savefig(path, dpi=110)


def replay(log: FlightLog, phases: Phases, platform: Platform | None = None) -> ReplayResult:
    """PX4's mix and the IMU replayed (:func:`replay_mix`, :func:`replay_imu`); needs a flight."""
    phases.require_flight("replaying PX4's mix")
    return ReplayResult(log.path.name, replay_mix(log, phases), replay_imu(log, phases, platform))


__all__ = ["ImuReplay", "MixReplay", "ReplayResult", "platform_from_log", "replay", "replay_imu", "replay_mix"]
