"""The air a real vehicle flies in, and the friction a real arm has: wind, aerodynamic drag D and viscous friction F_v of (5.36).

Thesis (5.36) carries F_v xi_dot (viscous friction) and D(xi, xi_dot) (aerodynamic forces and
modelling uncertainties), then drops both (Sec. 5.3: "neglected for simplicity") and every
thesis scenario assumes still air.  These are :class:`~qprr.sim.disturbances.StateDisturbance`
objects (evaluated at every integration stage), off unless passed to :func:`qprr.sim.simulate`:

* :class:`ViscousFriction`: u_f = -F_v xi_dot in thesis coordinates (F_v diagonal, (5.36)),
  applied as tau = S^-T u_f; in practice on the arm joints (N s/m, N m s/rad);
* :class:`AerodynamicDrag`: D of (5.36) on the multirotor, a force at B from the velocity of
  the base relative to the air, v_r = v_B - R^T w(t) (body axes): F = -K_1 v_r - K_2 |v_r| v_r
  (rotor drag, linear, and form drag, quadratic; per body axis), moment -k_w omega_B;
* :class:`Wind` w(t) (world axes, m/s): a steady mean wind, discrete "1 - cosine" gusts
  (:class:`Gust`) and Dryden turbulence (:class:`Dryden`).

Time grid.  The turbulence is random: the simulator *realizes* a drag model once per run (its
``realize(t_ticks, rng, period)`` hook, seeded by the run's seed) by sampling w(t) at the
control ticks and interpolating linearly in between.  The wind is then continuous, smooth
inside every control period, with its knots on step boundaries: the integrators keep their
orders (tests/test_wind.py).

Dryden turbulence (MIL-F-8785C; MIL-HDBK-1797).  Three independent components in the axes of
the mean wind (u along its horizontal direction, v horizontal across it, w up) with the
one-sided power spectral densities, omega [rad/s] the temporal frequency, V the speed at which
the frozen turbulence field passes the vehicle (Taylor's hypothesis; the airspeed of an
aircraft, the mean wind speed for a hovering multirotor):

    Phi_u(omega) = sigma_u^2 (2 L_u / (pi V)) / (1 + (L_u omega / V)^2)
    Phi_v(omega) = sigma_v^2 (L_v / (pi V)) (1 + 3 (L_v omega / V)^2) / (1 + (L_v omega / V)^2)^2   (w alike)

(int_0^inf Phi d omega = sigma^2), i.e. the autocorrelations sigma_u^2 exp(-V tau / L_u) and
sigma_v^2 (1 - V tau / (2 L_v)) exp(-V tau / L_v).  They are the outputs of the shaping filters
H_u(s) = sigma_u sqrt(2 L_u / V) / (1 + (L_u / V) s) and
H_v(s) = sigma_v sqrt(L_v / V) (1 + sqrt(3) (L_v / V) s) / (1 + (L_v / V) s)^2 driven by white
noise of unit intensity (|H(j omega)|^2 = pi Phi).  :meth:`Dryden.sample` draws the *exact*
discretisation of these filters (state transition exp(A T_s), process covariance by Van Loan's
integral, the initial state from the stationary covariance): its samples have the model's
autocorrelation at every lag, whatever the sampling period.  (rotorpy, through the
wind-dynamics package, discretises the same second-order filter by Tustin's rule and drives it
with one uniform sample in [-1, 1] per step, without the 1 / sqrt(T_s) of a white-noise
density: its variance then depends on the step.)  :meth:`Dryden.low_altitude` gives the
scale lengths and intensities of the low-altitude model from the altitude and the wind speed
at 20 ft.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg import expm, solve_continuous_lyapunov

from .. import charts as ch
from ..errors import InputError, ShapeError
from ..validation import as_array, as_int, as_real, as_vector
from .disturbances import StateDisturbance

FT = 0.3048
"""One foot [m] (the MIL low-altitude formulas are in feet)."""


def _positive3(x, name: str) -> tuple[float, float, float]:
    a = as_vector(x, 3, name)
    if np.any(a <= 0.0):
        raise InputError(f"{name} must be > 0, got {a.tolist()}")
    return tuple(float(v) for v in a)


def _nonneg3(x, name: str) -> tuple[float, float, float]:
    a = as_vector(np.full(3, as_real(x, name)) if np.ndim(x) == 0 else x, 3, name)
    if np.any(a < 0.0):
        raise InputError(f"{name} must be >= 0, got {a.tolist()}")
    return tuple(float(v) for v in a)


def _samples(x, name: str) -> np.ndarray:
    """``x`` (a number or a 1-D array of finite numbers: times, lags, frequencies) as a 1-D float array."""
    a = np.atleast_1d(as_array(x, name, finite=True))
    if a.ndim != 1:
        raise ShapeError(f"{name} must be a number or a 1-D array, got shape {a.shape}")
    return a


def _check_rng(rng) -> np.random.Generator:
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"rng must be a numpy.random.Generator (np.random.default_rng(seed)), got {type(rng).__name__}")
    return rng


# ================================================================================ Dryden
@dataclass(frozen=True)
class Dryden:
    """Dryden turbulence (module docstring): intensities ``sigma`` (u, v, w) [m/s], scale lengths ``length`` [m],
    passing speed ``airspeed`` V [m/s]."""

    sigma: tuple[float, float, float]
    length: tuple[float, float, float]
    airspeed: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "sigma", _nonneg3(self.sigma, "Dryden sigma"))
        object.__setattr__(self, "length", _positive3(self.length, "Dryden length"))
        if not (isinstance(self.airspeed, (int, float)) and math.isfinite(self.airspeed) and self.airspeed > 0.0):
            raise InputError(f"Dryden airspeed must be > 0 m/s, got {self.airspeed!r}")

    @classmethod
    def low_altitude(cls, altitude: float, w20: float, airspeed: float) -> Dryden:
        """MIL-F-8785C low-altitude model (altitude h < 1000 ft): L_w = h, L_u = L_v = h / (0.177 + 0.000823 h)^1.2,
        sigma_w = 0.1 W_20, sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4 (h in ft).

        ``altitude`` [m] (> 0), ``w20`` the wind speed 20 ft above ground [m/s] (light turbulence 15 knots =
        7.7 m/s, moderate 30, severe 45), ``airspeed`` V [m/s].
        """
        if not (math.isfinite(altitude) and 0.0 < altitude < 1000 * FT):
            raise InputError(f"the low-altitude model needs 0 < altitude < 304.8 m, got {altitude!r}")
        if not (math.isfinite(w20) and w20 >= 0.0):
            raise InputError(f"w20 must be >= 0 m/s, got {w20!r}")
        h = altitude / FT
        k = 0.177 + 0.000823 * h
        L_uv = h / k**1.2 * FT
        s_w = 0.1 * w20
        s_uv = s_w / k**0.4
        return cls((s_uv, s_uv, s_w), (L_uv, L_uv, altitude), airspeed)

    # ------------------------------------------------------------------ the model
    def psd(self, omega) -> np.ndarray:
        """One-sided PSDs Phi_u, Phi_v, Phi_w (3, m) [(m/s)^2 / (rad/s)] at ``omega`` [rad/s] (module docstring)."""
        w = _samples(omega, "omega")
        V = self.airspeed
        out = np.empty((3, w.shape[0]))
        for i, (s, L) in enumerate(zip(self.sigma, self.length)):
            x2 = (L * w / V) ** 2
            out[i] = s * s * (2 * L / (math.pi * V)) / (1 + x2) if i == 0 else s * s * (L / (math.pi * V)) * (1 + 3 * x2) / (1 + x2) ** 2
        return out

    def autocorrelation(self, lag) -> np.ndarray:
        """R_u, R_v, R_w (3, m) [(m/s)^2] at time lags ``lag`` [s]: sigma^2 e^(-V|tau|/L), sigma^2 (1 - V|tau|/(2L)) e^(-V|tau|/L)."""
        tau = np.abs(_samples(lag, "lag"))
        V = self.airspeed
        out = np.empty((3, tau.shape[0]))
        for i, (s, L) in enumerate(zip(self.sigma, self.length)):
            x = V * tau / L
            out[i] = s * s * np.exp(-x) * (1.0 if i == 0 else (1.0 - 0.5 * x))
        return out

    def shaping_filter(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A (5, 5), B (5, 3), C (3, 5)): x_dot = A x + B eta, [u, v, w] = C x, eta unit-intensity white noise.

        u: one state, H_u = k_u / (1 + tau_u s); v, w: controllable canonical form of
        H = k (1 + sqrt(3) tau s) / (1 + tau s)^2 (tau = L / V).
        """
        V = self.airspeed
        A, B, C = np.zeros((5, 5)), np.zeros((5, 3)), np.zeros((3, 5))
        s, L = self.sigma[0], self.length[0]
        tau = L / V
        A[0, 0] = -1.0 / tau
        B[0, 0] = s * math.sqrt(2 * L / V) / tau
        C[0, 0] = 1.0
        for i, j in ((1, 1), (2, 3)):
            s, L = self.sigma[i], self.length[i]
            tau = L / V
            k = s * math.sqrt(L / V)
            A[j, j + 1] = 1.0
            A[j + 1, j] = -1.0 / tau**2
            A[j + 1, j + 1] = -2.0 / tau
            B[j + 1, i] = 1.0
            C[i, j] = k / tau**2
            C[i, j + 1] = k * math.sqrt(3.0) / tau
        return A, B, C

    def discretization(self, period: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A_d, L_d, C, P): x_{k+1} = A_d x_k + L_d n_k (n_k standard normal (5,)), [u, v, w]_k = C x_k, exact at
        sampling ``period`` [s]; P the stationary covariance (the initial state is drawn from N(0, P))."""
        period = as_real(period, "period", positive=True, unit="s")  # the sampling period
        A, B, C = self.shaping_filter()
        n = A.shape[0]
        Q = B @ B.T
        # Van Loan: expm([[-A, Q], [0, A^T]] T) = [[., F^-1 Q_d], [0, F^T]] with F = expm(A T)
        M = np.zeros((2 * n, 2 * n))
        M[:n, :n], M[:n, n:], M[n:, n:] = -A, Q, A.T
        E = expm(M * period)
        Ad = E[n:, n:].T
        Qd = Ad @ E[:n, n:]
        Qd = 0.5 * (Qd + Qd.T)
        P = solve_continuous_lyapunov(A, -Q)
        return Ad, _psd_sqrt(Qd), C, 0.5 * (P + P.T)

    def sample(self, n: int, period: float, rng: np.random.Generator) -> np.ndarray:
        """``n`` samples (n, 3) [m/s] of [u, v, w] at ``period`` [s], stationary from the first (exact discretisation)."""
        n = as_int(n, "n", lo=1)  # the number of samples
        _check_rng(rng)
        Ad, Ld, C, P = self.discretization(period)
        x = _psd_sqrt(P) @ rng.standard_normal(5)
        drive = rng.standard_normal((n, 5)) @ Ld.T
        out = np.empty((n, 3))
        for k in range(n):
            out[k] = C @ x
            x = Ad @ x + drive[k]
        return out

    def discrete_psd(self, f, period: float) -> np.ndarray:
        """One-sided PSD (3, m) [(m/s)^2 / Hz] of the *sampled* process at frequencies ``f`` [Hz] below 1 / (2 period):
        2 T_s C (e^{j theta} - A_d)^-1 Q_d (e^{-j theta} - A_d^T)^-1 C^T, theta = 2 pi f T_s (what a periodogram of
        :meth:`sample` estimates; it tends to 2 pi Phi(2 pi f) as T_s -> 0)."""
        Ad, Ld, C, _ = self.discretization(period)
        Qd = Ld @ Ld.T
        f = _samples(f, "f")
        out = np.empty((3, f.shape[0]))
        eye = np.eye(Ad.shape[0])
        for k, fk in enumerate(f):
            z = np.exp(1j * 2 * math.pi * fk * period)
            G = C @ np.linalg.inv(z * eye - Ad)
            out[:, k] = 2 * period * np.real(np.einsum("ij,jk,ik->i", G, Qd, G.conj()))
        return out


def _psd_sqrt(P: np.ndarray) -> np.ndarray:
    """A square root S S^T = P of a symmetric positive semi-definite matrix (eigenvalues clipped at 0)."""
    w, U = np.linalg.eigh(P)
    return U * np.sqrt(np.clip(w, 0.0, None))


# ================================================================================= wind
@dataclass(frozen=True)
class Gust:
    """Discrete "1 - cosine" gust (MIL-F-8785C shape, in time): w(t) = A / 2 (1 - cos(2 pi (t - t0) / d)) on [t0, t0 + d].

    ``amplitude`` A (3,) [m/s] world axes (the peak), ``start`` t0 and ``duration`` d [s]."""

    start: float
    duration: float
    amplitude: tuple[float, float, float]

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude", tuple(float(v) for v in as_vector(self.amplitude, 3, "gust amplitude")))
        object.__setattr__(self, "start", as_real(self.start, "gust start", unit="s"))
        object.__setattr__(self, "duration", as_real(self.duration, "gust duration", positive=True, unit="s"))

    def velocity(self, t) -> np.ndarray:
        t = _samples(t, "t")
        s = (t - self.start) / self.duration
        on = (s >= 0.0) & (s <= 1.0)
        shape = np.where(on, 0.5 * (1.0 - np.cos(2.0 * math.pi * s)), 0.0)
        return shape[:, None] * np.asarray(self.amplitude)[None, :]


@dataclass(frozen=True)
class Wind:
    """Wind velocity w(t) (world axes, m/s): ``mean`` (3,) + the ``gusts`` + Dryden ``turbulence`` (or None).

    The turbulence components (u, v, w) are along the mean wind's horizontal direction, across
    it (horizontal) and up (along x, y, z when the mean wind has no horizontal part).  ``seed``: the
    turbulence's own seed (an integer >= 0; None: drawn from the run's seed), so that one realisation of the
    air can be flown again under runs of other seeds.
    """

    mean: tuple[float, float, float] = (0.0, 0.0, 0.0)
    turbulence: Dryden | None = None
    gusts: tuple[Gust, ...] = ()
    seed: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", tuple(float(v) for v in as_vector(self.mean, 3, "mean wind")))
        if self.seed is not None:
            object.__setattr__(self, "seed", as_int(self.seed, "wind seed", lo=0))
        if self.turbulence is not None and not isinstance(self.turbulence, Dryden):
            raise InputError(f"turbulence must be a Dryden model or None, got {type(self.turbulence).__name__}")
        if any(not isinstance(g, Gust) for g in self.gusts):
            raise InputError("gusts must be Gust objects")

    def turbulence_axes(self) -> np.ndarray:
        """(3, 3): columns = the u, v, w directions of the turbulence in world axes."""
        h = np.array([self.mean[0], self.mean[1], 0.0])
        n = float(np.linalg.norm(h))
        e_u = h / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])
        e_w = np.array([0.0, 0.0, 1.0])
        return np.column_stack([e_u, np.cross(e_w, e_u), e_w])

    def deterministic(self, t) -> np.ndarray:
        """Mean wind + gusts at times ``t`` (m, 3) [m/s]."""
        t = _samples(t, "t")
        out = np.tile(np.asarray(self.mean), (t.shape[0], 1))
        for g in self.gusts:
            out += g.velocity(t)
        return out

    def sample(self, t, rng: np.random.Generator) -> np.ndarray:
        """A realisation (m, 3) [m/s] at the evenly spaced times ``t`` (turbulence sampled at their spacing)."""
        t = _samples(t, "t")
        _check_rng(rng)
        out = self.deterministic(t)
        if self.turbulence is not None:
            period = float(t[1] - t[0]) if t.shape[0] > 1 else 1.0
            if t.shape[0] > 2 and not np.allclose(np.diff(t), period, rtol=1e-9, atol=0.0):
                raise InputError("Wind.sample needs evenly spaced times")
            out += self.turbulence.sample(t.shape[0], period, rng) @ self.turbulence_axes().T
        return out


# ===================================================================== state disturbances
@dataclass(frozen=True)
class AerodynamicDrag(StateDisturbance):
    """D of Thesis (5.36) on the multirotor (module docstring): F_B = -K_1 v_r - K_2 |v_r| v_r, M_B = -k_w omega_B.

    ``linear`` K_1 (3,) [N s/m] and ``quadratic`` K_2 (3,) [N s^2/m^2] per body axis (one value: all three),
    ``angular`` k_w [N m s/rad]; ``wind`` a :class:`Wind` (None: still air).  v_r = v_B - R^T w(t).
    A :class:`~qprr.sim.disturbances.StateDisturbance`; the simulator realizes the turbulence per run.
    """

    linear: tuple[float, float, float] | float = 0.0
    quadratic: tuple[float, float, float] | float = 0.0
    angular: float = 0.0
    wind: Wind | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "linear", _nonneg3(self.linear, "drag linear"))
        object.__setattr__(self, "quadratic", _nonneg3(self.quadratic, "drag quadratic"))
        if not (isinstance(self.angular, (int, float)) and math.isfinite(self.angular) and self.angular >= 0.0):
            raise InputError(f"drag angular must be >= 0 N m s/rad, got {self.angular!r}")
        if self.wind is not None and not isinstance(self.wind, Wind):
            raise InputError(f"wind must be a Wind or None, got {type(self.wind).__name__}")

    def _force(self, q, v, w_world) -> np.ndarray:
        tau = np.zeros(v.shape[0])
        R = pin.XYZQUATToSE3(q[0:7]).rotation
        vr = v[0:3] - R.T @ w_world
        tau[0:3] = -np.asarray(self.linear) * vr - np.asarray(self.quadratic) * np.linalg.norm(vr) * vr
        tau[3:6] = -self.angular * v[3:6]
        return tau

    def wind_velocity(self, t: float) -> np.ndarray:
        """w(t) [m/s] without turbulence (mean + gusts): the drag's wind before the simulator realizes it."""
        t = as_real(t, "t", unit="s")
        return np.zeros(3) if self.wind is None else self.wind.deterministic([t])[0]

    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """tau (nv,): the drag wrench at B in B axes (mean wind and gusts; turbulence once realized by the simulator)."""
        return self._force(q, v, self.wind_velocity(t))

    def realize(self, t_ticks: np.ndarray, rng: np.random.Generator, period: float) -> _RealizedDrag:
        """The drag of one run: the wind sampled at the ticks (and one period after the last), interpolated linearly;
        the turbulence drawn from ``rng`` (the run's), or from the wind's own ``seed`` when it has one."""
        n = t_ticks.shape[0] + 1
        t = t_ticks[0] + period * np.arange(n)
        if self.wind is not None and self.wind.seed is not None:  # the wind's own realisation, whatever the run's seed
            rng = np.random.default_rng(self.wind.seed)
        w = np.zeros((n, 3)) if self.wind is None else self.wind.sample(t, rng)
        return _RealizedDrag(self, t[0], period, w)


class _RealizedDrag(StateDisturbance):
    """:class:`AerodynamicDrag` with one realisation of the wind on the tick grid (linear in between)."""

    def __init__(self, drag: AerodynamicDrag, t0: float, period: float, w: np.ndarray) -> None:
        self.drag, self.t0, self.period, self.w = drag, t0, period, w
        self._last = w.shape[0] - 2

    def wind_velocity(self, t: float) -> np.ndarray:
        s = (t - self.t0) / self.period
        k = min(max(int(math.floor(s)), 0), self._last)
        a = s - k
        return (1.0 - a) * self.w[k] + a * self.w[k + 1]

    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.drag._force(q, v, self.wind_velocity(t))

    def report(self) -> dict[str, np.ndarray]:
        """The realized wind at the ticks (m, 3) [m/s], world axes."""
        return {"wind_velocity": self.w[:-1].copy()}


@dataclass(frozen=True)
class ViscousFriction(StateDisturbance):
    """F_v xi_dot of Thesis (5.36): the generalised force u_f = -F_v xi_dot (thesis coordinates), tau = S^-T u_f.

    ``coefficients`` (6 + n_arm,): N s/m on x, y, z and prismatic joints, N m s/rad on the Euler
    angles and revolute joints (the base entries are usually 0: its air drag is :class:`AerodynamicDrag`).
    """

    coefficients: tuple[float, ...]

    def __post_init__(self) -> None:
        c = np.atleast_1d(as_array(self.coefficients, "friction coefficients"))
        if c.ndim != 1 or c.shape[0] < 6 or not np.all(np.isfinite(c)) or np.any(c < 0.0):
            raise InputError(f"friction coefficients must be 6 + n_arm finite values >= 0, got {self.coefficients!r}")
        object.__setattr__(self, "coefficients", tuple(float(x) for x in c))

    def generalized_force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        F = np.asarray(self.coefficients)
        if F.shape[0] != v.shape[0]:
            raise ShapeError(f"friction has {F.shape[0]} coefficients, the platform's xi has {v.shape[0]}")
        if not np.any(F[0:6]):  # arm joints only: xi_dot = v there and S^-T is the identity
            tau = np.zeros(v.shape[0])
            tau[6:] = -F[6:] * v[6:]
            return tau
        xi, xi_dot = ch.qv_to_xi(q, v)
        return ch.force_from_xi(xi, -F * xi_dot)


__all__ = ["FT", "AerodynamicDrag", "Dryden", "Gust", "ViscousFriction", "Wind"]
