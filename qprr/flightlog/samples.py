"""The samples identification fits and the estimates it gives: :class:`Estimate` (value, std, unit, status,
reason), :class:`Samples` (the airborne part of a flight, low-passed and on a common grid, :func:`prepare_samples`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..errors import InputError
from .record import FlightRecord
from .stats import lag_response, lowpass

GRID_RATE_HZ = 50.0
"""The rate the filtered signals are fitted at [Hz]."""

RELATIVE_STD_MAX = 0.3
"""An estimate whose std exceeds this fraction of its value (or of its physical scale) is not identifiable."""


class EstimateStatus(Enum):
    IDENTIFIED = "identified"
    NOT_IDENTIFIABLE = "not identifiable"


@dataclass(frozen=True)
class Estimate:
    """One identified value: ``value`` ± ``std`` [``unit``], or ``status`` NOT_IDENTIFIABLE with the ``reason``."""

    value: float
    std: float
    unit: str
    status: EstimateStatus = EstimateStatus.IDENTIFIED
    reason: str = ""

    @property
    def identified(self) -> bool:
        return self.status is EstimateStatus.IDENTIFIED

    def line(self, key: str) -> str:
        if not self.identified:
            return f"{key}: not identifiable: {self.reason}"
        unit = f" {self.unit}" if self.unit else ""
        return f"{key}: {self.value:.6g} ± {self.std:.2g}{unit}"


def not_identifiable(unit: str, reason: str) -> Estimate:
    return Estimate(math.nan, math.nan, unit, EstimateStatus.NOT_IDENTIFIABLE, reason)


@dataclass(frozen=True)
class Samples:
    """The airborne samples on a GRID_RATE_HZ grid, low-passed: t_s (n,), segment (n,) the airborne interval index,
    specific_force_body (n, 3), gyro_body (n, 3), omega_dot_body (n, 3) [rad/s^2]; ``commands(T)`` (n, n_rotors) the
    thrust-model outputs g(lag_T(u)) filtered alike; cutoff_hz; joints q, qd, qdd (n, n_arm) or None."""

    t_s: np.ndarray
    segment: np.ndarray
    specific_force_body: np.ndarray
    gyro_body: np.ndarray
    omega_dot_body: np.ndarray
    cutoff_hz: float
    pieces: tuple = field(repr=False, default=())
    joints: tuple | None = None

    def commands(self, time_constant: float) -> np.ndarray:
        """g(lag_T(u)) low-passed and sampled on the grid (n, n_rotors)."""
        out = []
        for _t, u_imu, dt, rate, fac, pick in self.pieces:
            lagged = lag_response(u_imu, dt, time_constant)
            thrust = fac * lagged**2 + (1.0 - fac) * lagged
            out.append(lowpass(thrust, rate, self.cutoff_hz)[pick])
        return np.concatenate(out)


def prepare_samples(record: FlightRecord, options) -> Samples:
    """:class:`Samples` of ``record``: each airborne interval (less ``margin_s`` at both ends) on the IMU's grid, the
    commands interpolated to it, the IMU's signals through the same sampling and interpolation (:func:`_as_commands`),
    everything low-passed (module docstring) and sampled at GRID_RATE_HZ."""
    t = record.t_imu_s
    dt = float(np.median(np.diff(t)))
    rate = 1.0 / dt
    cmd_rate = record.command_rate_hz
    cutoff = options.cutoff_hz if options.cutoff_hz is not None else min(0.25 * cmd_rate, 5.0)
    step = max(1, int(round(rate / GRID_RATE_HZ)))
    cols = {k: [] for k in ("t", "seg", "f", "w", "wd", "q", "qd", "qdd")}
    pieces = []
    for k, (a, b) in enumerate(record.airborne):
        a, b = max(a + options.margin_s, record.t_command_s[0]), min(b - options.margin_s, record.t_command_s[-1])
        sel = np.flatnonzero((t >= a) & (t <= b))
        if sel.size * dt < max(3.0 / cutoff, 2.0):
            continue  # too short to filter
        ts = t[sel]
        tg = ts[0] + dt * np.arange(ts.size)  # a uniform grid (the IMU's jitter removed)
        f = lowpass(_as_commands(_resample(ts, record.specific_force_body[sel], tg), rate, cmd_rate), rate, cutoff)
        w = lowpass(_as_commands(_resample(ts, record.gyro_body[sel], tg), rate, cmd_rate), rate, cutoff)
        wd = np.gradient(w, dt, axis=0)
        pick = np.arange(0, tg.size, step)
        u = np.column_stack([np.interp(tg, record.t_command_s, record.commands[:, i]) for i in range(record.commands.shape[1])])
        pieces.append((tg, u, dt, rate, record.thr_mdl_fac, pick))
        cols["t"].append(tg[pick])
        cols["seg"].append(np.full(pick.size, k))
        cols["f"].append(f[pick])
        cols["w"].append(w[pick])
        cols["wd"].append(wd[pick])
        if record.joints is not None:
            q = lowpass(_resample(record.joints.t_s, record.joints.q, tg), rate, cutoff)
            qd = np.gradient(q, dt, axis=0)
            cols["q"].append(q[pick])
            cols["qd"].append(qd[pick])
            cols["qdd"].append(np.gradient(qd, dt, axis=0)[pick])
    if not cols["t"]:
        raise InputError(f"{record.source}: no airborne interval longer than {max(3.0 / cutoff, 2.0) + 2 * options.margin_s:.1f} s to identify from")
    cat = {k: np.concatenate(v) for k, v in cols.items() if v}
    joints = (cat["q"], cat["qd"], cat["qdd"]) if record.joints is not None else None
    return Samples(cat["t"], cat["seg"], cat["f"], cat["w"], cat["wd"], cutoff, tuple(pieces), joints)


def _as_commands(x: np.ndarray, rate_hz: float, command_rate_hz: float) -> np.ndarray:
    """``x`` (rows: samples at ``rate_hz``) through the filter that linear interpolation between commands logged at
    ``command_rate_hz`` applies to the commands: the triangle of half-width 1 / command_rate_hz (zero phase, gain
    sinc^2(f / command_rate_hz), 0.87 at 2 Hz for 10 Hz commands, which would otherwise read as a 13 % smaller
    inertia).  Convolving, not sampling the IMU at the command times: its wide-band noise is not aliased."""
    h = int(round(rate_hz / command_rate_hz))
    if h < 2:
        return x
    kernel = 1.0 - np.abs(np.arange(-h + 1, h)) / h
    kernel /= kernel.sum()
    padded = np.concatenate([np.repeat(x[:1], h, axis=0), x, np.repeat(x[-1:], h, axis=0)])
    out = np.apply_along_axis(lambda c: np.convolve(c, kernel, mode="same"), 0, padded)
    return out[h:-h]


def _resample(t: np.ndarray, x: np.ndarray, t_new: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float).reshape(len(t), -1)
    return np.column_stack([np.interp(t_new, t, x[:, j]) for j in range(x.shape[1])])
