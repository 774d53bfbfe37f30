"""The statistics identification rests on: zero-phase low-pass filtering, the first-order motor lag, least squares
with a residual-based covariance inflated for the autocorrelation of the residuals.

Why the inflation: a flight log's residuals are not white (the IMU is low-pass filtered to the band the motor
commands are logged in, the commands are interpolated between 10 Hz samples, unmodelled effects drift slowly), so the
textbook covariance s^2 (X^T X)^-1 would claim ~n independent samples where there are far fewer.  The effective
sample size is n / tau with tau the integrated autocorrelation time of the residual-times-regressor series, summed
over lags up to Sokal's automatic window (the smallest M with M >= 5 tau(M); A. Sokal, "Monte Carlo methods in
statistical mechanics", 1997, Sec. 3); the covariance is multiplied by tau (the Newey-West form with a rectangular
window of that width).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, filtfilt, lfilter

from ..errors import InputError
from ..validation import as_array, as_real

SOKAL_WINDOW = 5.0
"""Sokal's window constant c: the autocorrelation is summed over lags M with M >= c tau(M)."""


def lowpass(x: np.ndarray, rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """Zero-phase 4th-order Butterworth low-pass (scipy.signal.butter + filtfilt) of ``x`` (rows: samples at
    ``rate_hz``) at ``cutoff_hz``: the same filter applied to the measurement and to the regressor keeps a linear
    model linear, and shifts nothing in time."""
    if not 0.0 < cutoff_hz < 0.5 * rate_hz:
        raise InputError(f"cutoff_hz must lie in (0, {0.5 * rate_hz:g}) Hz (half the sample rate), got {cutoff_hz!r}")
    b, a = butter(4, cutoff_hz / (0.5 * rate_hz))
    return filtfilt(b, a, x, axis=0, padlen=min(3 * max(len(a), len(b)), x.shape[0] - 1))


def lag_response(u: np.ndarray, dt: float, time_constant: float) -> np.ndarray:
    """The output of the first-order lag T du_f/dt = u - u_f (jMAVSim's Rotor.java, qprr.sim.actuators) driven by
    ``u`` (rows: samples ``dt`` [s] apart, linear in between: the exact discrete update of a ramp), started at u[0];
    ``time_constant`` = 0: ``u`` itself."""
    u = as_array(u, "u", finite=True)
    if u.ndim not in (1, 2) or u.shape[0] == 0:
        raise InputError(f"u must be samples in rows (a 1-D or 2-D array with at least one row), got shape {u.shape}")
    dt = as_real(dt, "dt", positive=True, unit="s")
    time_constant = as_real(time_constant, "time_constant", nonnegative=True, unit="s")
    if time_constant == 0.0:
        return u.copy()
    e = math.exp(-dt / time_constant)
    c1 = 1.0 - time_constant / dt * (1.0 - e)  # weight of the new sample for a ramp between samples
    return lfilter([c1, 1.0 - e - c1], [1.0, -e], u - u[0], axis=0) + u[0]


def autocorrelation_time(z: np.ndarray) -> float:
    """tau = 1 + 2 sum_k rho(k) of the series ``z`` (rows: samples; columns summed: the series of x_j e), with Sokal's
    window (module docstring); 1 for white noise, >= 1 always."""
    z = np.atleast_2d(np.asarray(z, dtype=float).T).T
    z = z - z.mean(axis=0)
    n = z.shape[0]
    if n < 8:
        return 1.0
    nfft = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(z, nfft, axis=0)
    acov = np.fft.irfft(f * np.conj(f), nfft, axis=0)[:n].sum(axis=1)
    if acov[0] <= 0.0:
        return 1.0
    rho = acov / acov[0]
    tau = 1.0
    for m in range(1, n // 2):
        tau += 2.0 * rho[m]
        if m >= SOKAL_WINDOW * tau:
            break
    return float(min(max(tau, 1.0), n / 4.0))


@dataclass(frozen=True)
class LeastSquares:
    """The fit of y = X beta by least squares (numpy.linalg.lstsq) and its honest covariance (module docstring).

    beta (p,), cov (p, p) = s^2 (X^T X)^-1 tau; residual (n,); s2 the residual variance (n - p degrees of freedom);
    tau the autocorrelation time (the effective sample size is n / tau)."""

    beta: np.ndarray
    cov: np.ndarray
    residual: np.ndarray
    s2: float
    tau: float

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))

    @property
    def n_effective(self) -> float:
        return self.residual.shape[0] / self.tau


def least_squares(X: np.ndarray, y: np.ndarray) -> LeastSquares:
    """:class:`LeastSquares` of ``y`` (n,) on the columns of ``X`` (n, p), n > p, X of full column rank."""
    X = np.atleast_2d(np.asarray(X, dtype=float).T).T
    n, p = X.shape
    if n <= p + 2:
        raise InputError(f"least squares needs more samples than parameters: {n} samples for {p} parameters")
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ beta
    s2 = float(r @ r) / (n - p)
    XtX_inv = np.linalg.pinv(X.T @ X)
    tau = autocorrelation_time(X * r[:, None] / np.maximum(np.linalg.norm(X, axis=0), 1e-300))
    return LeastSquares(beta, XtX_inv * s2 * tau, r, s2, tau)
