"""Model-free control (MFC) with intelligent PIDs, Thesis Sec. 6.3.3.2, (6.36)-(6.39).

Each coordinate y = xi_i gets the ultra-local model (6.36) with nu = 2:

    y_ddot = F + alpha u

where u is the generalised force on that coordinate (thesis coordinates: the world force
u_fb for x, y, z, the Euler-angle torques, the arm efforts) and F lumps everything else
(coupling, gravity, disturbances).  F is estimated at each step from measured outputs and
the last input, F_est = y_ddot_meas - alpha u_prev, with y_ddot_meas the backward difference
of the measured rate (optionally low-passed).  The iPID closes the loop:

    u = (-F_est + y*_ddot + K_P e + K_I int e + K_D e_dot) / alpha,   e = y* - y,

so that e_ddot + K_D e_dot + K_P e + K_I int e = F_est - F (6.38).  The thesis prints (6.37)
with the opposite sign, which gives a tracking error with negative damping
(:func:`qprr.thesis.printed.ipid_thesis_printed`, disproved in tests/test_control.py).

As in the IDC, roll and pitch references come from u_fb through (6.17) and a command filter;
the MFC needs no model: alpha_i = 1 / B_ii is evaluated once at the initial configuration
("alpha is chosen so that the three terms of (6.36) have the same magnitude").
Gains: K_P = 60, K_I = 8, K_D = 35 for every coordinate (Sec. 6.3.3.2), for any platform.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..charts import State, rate_map
from ..errors import InputError
from ..model import Platform, check_platform
from ..validation import as_array, as_int, as_real
from .base import Controller, Reference, check_reset, not_reset
from .filters import TiltReference

_PI = math.pi
_TWO_PI = 2.0 * math.pi


def ipid(F_est: float, y_ddot_ref: float, e: float, e_int: float, e_dot: float, alpha: float, gains: tuple[float, float, float]) -> float:
    """Intelligent PID (6.37), sign corrected: u = (-F_est + y*_ddot + K_P e + K_I int e + K_D e_dot) / alpha, e = y* - y.

    ``gains`` = (K_P, K_I, K_D) of the coordinate.
    """
    kp, ki, kd = gains
    return (-F_est + y_ddot_ref + kp * e + ki * e_int + kd * e_dot) / alpha


@dataclass(frozen=True)
class MFCGains:
    """iPID gains per coordinate (x, y, z, phi, theta, psi, then the arm joints) and estimator settings.

    ``kp``, ``ki``, ``kd``: 60, 8, 35 for all (Sec. 6.3.3.2, printed); None: those for every
    coordinate of the platform.  The rest is not printed; chosen values and why (Q-PRR, static
    mission, measured):

    * ``alpha`` (None: ``alpha_scale`` (B^-1)_ii at the initial state, scale 3, one common
      value for x, y, z).  F_est uses the previous step's inputs, so the coupled channels
      update as u_k = (I - diag(1/alpha) B^-1) u_(k-1) + ...; the natural guess
      alpha = 1 / B_ii gives spectral radius 16 at hover (diverges in milliseconds);
      c (B^-1)_ii contracts for c > 1.2 (eigenvalues of diag(1/(B^-1)_ii) B^-1 lie in
      [0.05, 2.34] at hover).  Measured on the static mission: c = 2 tracks the arm ten
      times worse than c = 3; c = 4 and 6 are worse again.
    * ``f_filter`` [s]: first-order low-pass on F_est per coordinate (0.2 s on x, y, none
      elsewhere; None: that for any platform).  B sits 2.5 cm below the CoG, so a pitch acceleration moves B sideways at
      once; unfiltered, F_x feeds that straight back into the pitch reference.
    * ``filter_omega`` (15 rad/s): bandwidth of the feedback part of the roll/pitch reference
      (:class:`~qprr.control.base.TiltReference`).  With K_D = 35 on the velocity of B the
      reference feeds back its own rate with gain ~K_D z_cm / (alpha m g); the filter's
      damping must exceed it: 50 rad/s diverges, 30 tracks poorly, 12-20 are best, 8 lags.
    """

    kp: tuple[float, ...] | None = None
    ki: tuple[float, ...] | None = None
    kd: tuple[float, ...] | None = None
    alpha: tuple[float, ...] | None = None
    alpha_scale: float = 3.0
    f_filter: tuple[float, ...] | None = None
    filter_omega: float = 15.0
    max_tilt: float = 0.8

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha_scale", as_real(self.alpha_scale, "alpha_scale", positive=True))
        object.__setattr__(self, "filter_omega", as_real(self.filter_omega, "filter_omega", positive=True, unit="rad/s"))
        object.__setattr__(self, "max_tilt", as_real(self.max_tilt, "max_tilt", positive=True, unit="rad"))
        if not self.max_tilt < math.pi / 2:
            raise InputError(f"max_tilt must be < pi/2 rad, got {self.max_tilt!r}")
        for name in ("kp", "ki", "kd", "alpha", "f_filter"):
            v = getattr(self, name)
            if v is not None:
                a = as_array(v, name)
                if a.ndim != 1 or a.shape[0] < 6 or not np.all(np.isfinite(a)) or np.any(a < 0) or (name == "alpha" and np.any(a <= 0)):
                    raise InputError(f"{name} must be 6 + n_arm finite values {'> 0' if name == 'alpha' else '>= 0'}, got {v!r}")
                object.__setattr__(self, name, tuple(float(x) for x in a))

    def resolved(self, n_xi: int) -> MFCGains:
        """The gains with every per-coordinate vector of length ``n_xi`` (defaults filled in, sizes checked)."""
        from dataclasses import replace

        n_xi = as_int(n_xi, "n_xi", lo=6)

        def fill(v, default, name):
            if v is None:
                return tuple(default)
            if len(v) != n_xi:
                raise InputError(f"MFC gains {name} have {len(v)} entries, the platform's xi has {n_xi}")
            return v

        return replace(
            self,
            kp=fill(self.kp, (60.0,) * n_xi, "kp"),
            ki=fill(self.ki, (8.0,) * n_xi, "ki"),
            kd=fill(self.kd, (35.0,) * n_xi, "kd"),
            f_filter=fill(self.f_filter, (0.2, 0.2) + (0.0,) * (n_xi - 2), "f_filter"),
            alpha=None if self.alpha is None else fill(self.alpha, (), "alpha"),
        )


class ModelFreeController(Controller):
    """iPID model-free control of every coordinate, with (6.17) roll/pitch references (Sec. 6.3.3.2)."""

    name = "mfc"
    uses_applied_force = True

    def __init__(self, platform: Platform, gains: MFCGains | None = None) -> None:
        self.platform = check_platform(platform)
        gains = MFCGains() if gains is None else gains
        if not isinstance(gains, MFCGains):
            raise InputError(f"gains must be an MFCGains, got {type(gains).__name__}")
        self.gains = gains.resolved(platform.n_xi)
        self.dt = None  # the control period: set by reset(state, ref, dt), called by the simulator
        self.alpha = None  # alpha_i of (6.36): set by reset (from the initial state unless the gains give it)
        self._kf = None  # gains of the F_est low-pass: set by reset (they depend on dt)
        self._new_run()

    def _alpha_from_inertia(self, state: State) -> list[float]:
        """alpha_i = c (B^-1)_ii with B = S^T M S at the given state (computed once, not in the loop)."""
        data = self.platform.model.createData()
        M = pin.crba(self.platform.model, data, state.q)
        S = rate_map(state.xi)
        Binv = np.linalg.inv(S.T @ M @ S)
        d = np.diag(Binv).copy()
        d[0:3] = d[0:3].mean()  # one alpha for x, y, z: u_fb keeps the direction (6.17) reads
        return [self.gains.alpha_scale * float(v) for v in d]

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        """Start a run: the control period ``dt`` [s], alpha (from ``state`` unless the gains give it), fresh loops."""
        self.dt = dt = check_reset(self, state, ref, dt)
        g = self.gains
        self.alpha = list(g.alpha) if g.alpha is not None else self._alpha_from_inertia(state)
        self._kf = [1.0 if tf <= 0 else dt / (tf + dt) for tf in g.f_filter]
        self._new_run()

    def _new_run(self) -> None:
        """Fresh per-run values: integrals, F_est, the tilt reference filter."""
        g = self.gains
        n = self.platform.n_xi
        self.integral = [0.0] * n
        self.u_prev = [0.0] * n
        self.yd_prev = None
        self.F = [0.0] * n
        self._have_F = False
        p = self.platform
        self.tilt = TiltReference(g.filter_omega, g.max_tilt, 0.05 * p.total_mass * p.g)
        self._g = p.g
        # (i, k_P,i, k_I,i, k_D,i) of the iPIDs, looked up once: outer loops, then roll and pitch
        self._loops_outer = tuple((i, g.kp[i], g.ki[i], g.kd[i]) for i in (0, 1, 2, 5, *range(6, n)))
        self._loops_tilt = tuple((i, g.kp[i], g.ki[i], g.kd[i]) for i in (3, 4))

    def _estimate_F(self, state: State, yd, dt: float) -> None:
        """F_est = y_ddot_meas - alpha u_applied (backward difference over dt [s] of the rates ``yd``, optional low-pass).

        u_applied is the measured input of the previous step (``state.u_applied``): for x, y, z
        the force the tilted thrust really produced, not the u_fb asked for.
        """
        if self.yd_prev is None:
            self.yd_prev = list(yd)
            return
        zipped = zip(self.F, self._kf, yd, self.yd_prev, self.alpha, state.u_applied_floats)
        if self._have_F:  # raw = (y_dot - y_dot_prev) / dt - alpha u, low-passed: F += k (raw - F)
            self.F = [f + k * ((y - p) / dt - al * ua - f) for f, k, y, p, al, ua in zipped]
        else:
            self.F = [(y - p) / dt - al * ua for f, k, y, p, al, ua in zipped]
        self._have_F = True
        self.yd_prev = list(yd)

    def _ipid_loops(self, loops, x, xd, r, rd, rdd, u: list[float], dt: float) -> None:
        """:func:`ipid` for ``loops`` = ((i, k_P,i, k_I,i, k_D,i), ...) on plain floats, results into ``u``."""
        integ, F, al = self.integral, self.F, self.alpha
        for i, kp, ki, kd in loops:
            e = r[i] - x[i]
            if i == 5:
                e = (e + _PI) % _TWO_PI - _PI
            ie = integ[i] + e * dt
            integ[i] = ie
            u[i] = (-F[i] + rdd[i] + kp * e + ki * ie + kd * (rd[i] - xd[i])) / al[i]  # ipid()

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """u_i from the iPID (6.37, corrected) of each coordinate; roll/pitch references from (6.17)."""
        dt = self._dt  # the control period (read once: this runs every tick)
        if dt is None:
            raise not_reset(self)
        x, xd = state.xi_floats, state.xi_dot_floats
        self._estimate_F(state, xd, dt)
        r, rd, rdd = ref.xi.tolist(), ref.xi_dot.tolist(), ref.xi_ddot.tolist()
        u = [0.0] * len(x)
        self._ipid_loops(self._loops_outer, x, xd, r, rd, rdd, u, dt)
        tilt = self.tilt
        tilt.update(x[5], (u[0], u[1], u[2]), rdd[0:3], self._g, dt)
        tilt.write(ref)
        r[3], r[4] = tilt.x
        rd[3], rd[4] = tilt.xd
        rdd[3], rdd[4] = tilt.xdd
        self._ipid_loops(self._loops_tilt, x, xd, r, rd, rdd, u, dt)
        self.u_prev = u
        return np.array(u)
