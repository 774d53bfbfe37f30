"""Filters that give references consistent derivatives, and the roll/pitch references of (6.17).

* :class:`CommandFilter`: second-order critically damped filter, n channels;
* :func:`tilt_6_17`: Thesis (6.17), the roll/pitch that point the thrust axis along a world force;
* :class:`TiltReference`: (6.17) split into a feedforward part (the reference acceleration) and
  the rest, each filtered, with rates and accelerations (the IDC, the MFC);
* :class:`SingleTiltReference`: (6.17) of the whole force through one filter (the layered
  controllers of Sec. 6.4).
"""

from __future__ import annotations

import math
from math import asin, atan, cos, sin, sqrt
from typing import TYPE_CHECKING

from ..validation import as_int, as_real

if TYPE_CHECKING:
    from .base import Reference


def _filter_args(omega, max_tilt, uz_min) -> tuple[float, float, float]:
    """(omega [rad/s] > 0, max_tilt in (0, pi/2) [rad], uz_min >= 0 [N]) of the tilt references, checked."""
    omega = as_real(omega, "omega", positive=True, unit="rad/s")
    max_tilt = as_real(max_tilt, "max_tilt", positive=True, hi=0.5 * math.pi, unit="rad")
    return omega, max_tilt, as_real(uz_min, "uz_min", nonnegative=True, unit="N")


class CommandFilter:
    """Second-order critically damped filter giving a reference with consistent derivatives.

    x_f'' = w^2 (x_raw - x_f) - 2 w x_f', stepped by semi-implicit Euler
    (a = w^2 (x_raw - x) - 2 w xd, xd += dt a, x += dt xd): (x, xd, a) are exactly consistent
    (a plant that integrates a the same way follows x step for step) and ``xdd`` is the
    acceleration actually used over the step.  The scheme is stable for w dt < 0.83: the
    bandwidth used is min(omega, 0.7 / dt).  Its step matrix on (x, dt xd) has determinant
    1 - 2 w dt, so for w dt > 0.5 one pole is negative (-0.58 at w dt = 0.7) and a step or
    kink of the input rings on alternate steps; smooth inputs do not excite it.
    ``n`` channels; ``x``, ``xd``, ``xdd`` after :meth:`update`.
    """

    __slots__ = ("omega", "x", "xd", "xdd", "_init")

    def __init__(self, n: int, omega: float) -> None:
        n = as_int(n, "n", lo=0)
        self.omega = as_real(omega, "omega", positive=True, unit="rad/s")
        self.x = [0.0] * n
        self.xd = [0.0] * n
        self.xdd = [0.0] * n
        self._init = False

    def reset(self, values) -> None:
        self.x = [float(v) for v in values]
        self.xd = [0.0] * len(self.x)
        self.xdd = [0.0] * len(self.x)
        self._init = True

    def update(self, raw, dt: float) -> None:
        if not self._init:
            self.reset(raw)
        w = min(self.omega, 0.7 / dt)
        w2, w2x = w * w, 2.0 * w
        x, xd, xdd = self.x, self.xd, self.xdd
        for i, r in enumerate(raw):
            acc = w2 * (r - x[i]) - w2x * xd[i]
            xdd[i] = acc
            xd[i] += dt * acc
            x[i] += dt * xd[i]


def tilt_6_17(fx: float, fy: float, fz: float, cp: float, sp: float, lim: float) -> tuple[float, float]:
    """(phi, theta) that point z_B along the world force f at yaw psi, Thesis (6.17), clamped to +-lim.

    theta = atan((fx c_psi + fy s_psi) / fz), phi = asin((fx s_psi - fy c_psi) / |f|); the clamp
    is max(-lim, min(lim, angle)) written so that NaN ends on a bound.
    """
    theta = atan((fx * cp + fy * sp) / fz)
    if not -lim < theta < lim:
        theta = theta if theta < lim else lim
        theta = theta if theta > -lim else -lim
    phi = asin((fx * sp - fy * cp) / sqrt(fx * fx + fy * fy + fz * fz))
    if not -lim < phi < lim:
        phi = phi if phi < lim else lim
        phi = phi if phi > -lim else -lim
    return phi, theta


class TiltReference:
    """Roll/pitch references of Thesis (6.17) with the rates and accelerations (6.20) needs.

    (6.17): theta_r = atan((u_x c_psi + u_y s_psi) / u_z), phi_r = asin((u_x s_psi - u_y c_psi) / |u|).

    The reference is split into a feedforward part, (6.17) applied to the reference
    acceleration (u = p_ddot_d + g e3: it depends on the trajectory only), and the rest
    (feedback and coupling terms of u_fb).  Each goes through a critically damped
    second-order :class:`CommandFilter` that also gives its rates (Remark 4: numerical
    differentiation with noise-robust filters): the feedforward through a fast one
    (``omega_ff`` = 700 rad/s, lag 3 ms; no loop closes through it), the rest through
    ``omega``.  The feedforward filter does not smooth a non-smooth reference, it
    differentiates it: a step of the tilt rate (a jerk step of the reference, e.g. at the ends
    of a quintic phase) comes out as a one-step tilt acceleration of (w dt)^2 times the
    rate step divided by dt (72 rad/s^2 for the 0.15 rad/s step of the static mission's x
    phase), ringing on alternate steps (w dt = 0.7, see :class:`CommandFilter`).  References
    must therefore be C3 in position (jerk continuous, as the default septic law of
    :mod:`qprr.trajectory`); the filter then follows with a 3 ms lag and no ringing.
    Lowering it to w dt = 0.5 (no negative pole) costs 18 % of x RMSE on the static mission
    through the longer lag (docs/notes-spikes.md).

    Filtering the whole of (6.17) with one filter costs either a lag of ~2/omega
    on the nominal tilt or, with a fast filter, feeds the high-frequency content of u_fb
    (arm reactions, the sideways motion of B under pitch acceleration) back into the
    attitude loop, which diverges under disturbances; the split avoids both.

    When u_z < ``uz_min`` (Hypothesis 2 violated: the reference asks for more than free-fall
    deceleration) the last raw reference is held.  Angles are clamped to ``max_tilt``.
    """

    __slots__ = ("omega", "omega_ff", "max_tilt", "uz_min", "x", "xd", "xdd", "_s", "_k", "_ff", "_n", "_raw")

    def __init__(self, omega: float, max_tilt: float, uz_min: float, omega_ff: float = 700.0) -> None:
        self.omega, self.max_tilt, self.uz_min = _filter_args(omega, max_tilt, uz_min)
        self.omega_ff = as_real(omega_ff, "omega_ff", positive=True, unit="rad/s")
        self.reset()

    def reset(self) -> None:
        """Forget the filter states; the bandwidths ``omega``, ``omega_ff`` are read from here on."""
        self.x, self.xd, self.xdd = [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]
        # the two CommandFilter-like states, flat: (x, xd) of the feedback filter and of the
        # feedforward filter for roll, then for pitch; set at the first update
        self._s = (0.0,) * 8
        self._k = (None, self.omega, self.omega_ff)  # (dt, w^2, 2 w, wf^2, 2 wf) once dt is known
        self._ff = (0.0, 0.0)  # last feedforward tilt (held when (6.17) is undefined)
        self._n = 0
        self._raw = None

    def update(self, psi: float, u_fb, a_ref, g: float, dt: float) -> None:
        """Advance one step: ``u_fb`` (3,) world force asked for, ``a_ref`` (3,) reference acceleration [m/s^2]."""
        cp, sp = cos(psi), sin(psi)
        lim = self.max_tilt
        ax, ay, az = a_ref
        azg = az + g
        if azg > 0.05 * g:
            self._ff = ff0, ff1 = tilt_6_17(ax, ay, azg, cp, sp, lim)
        else:
            ff0, ff1 = self._ff
        ux, uy, uz = u_fb
        if uz > self.uz_min:
            self._raw = raw0, raw1 = tilt_6_17(ux, uy, uz, cp, sp, lim)
        elif self._raw is not None:
            raw0, raw1 = self._raw
        else:
            raw0, raw1 = ff0, ff1
        if self._n == 0:  # filters start at rest on the first raw values
            self._s = (raw0 - ff0, 0.0, ff0, 0.0, raw1 - ff1, 0.0, ff1, 0.0)
        self._n += 1
        k = self._k
        if k[0] != dt:  # bandwidths min(omega, 0.7 / dt) (CommandFilter's stability bound)
            w = k[1] if k[1] < 0.7 / dt else 0.7 / dt
            wf = k[2] if k[2] < 0.7 / dt else 0.7 / dt
            self._k = k = (dt, k[1], k[2], w * w, 2.0 * w, wf * wf, 2.0 * wf)
        _, _, _, w2, w2x, wf2, wf2x = k
        bx0, bxd0, fx0, fxd0, bx1, bxd1, fx1, fxd1 = self._s
        # both second-order filters (feedback part b, feedforward part f), semi-implicit Euler
        # as in CommandFilter: a = w^2 (x_raw - x) - 2 w xd, xd += dt a, x += dt xd
        ab0 = w2 * ((raw0 - ff0) - bx0) - w2x * bxd0
        bxd0 = bxd0 + dt * ab0
        bx0 = bx0 + dt * bxd0
        af0 = wf2 * (ff0 - fx0) - wf2x * fxd0
        fxd0 = fxd0 + dt * af0
        fx0 = fx0 + dt * fxd0
        ab1 = w2 * ((raw1 - ff1) - bx1) - w2x * bxd1
        bxd1 = bxd1 + dt * ab1
        bx1 = bx1 + dt * bxd1
        af1 = wf2 * (ff1 - fx1) - wf2x * fxd1
        fxd1 = fxd1 + dt * af1
        fx1 = fx1 + dt * fxd1
        self._s = (bx0, bxd0, fx0, fxd0, bx1, bxd1, fx1, fxd1)
        self.x = [fx0 + bx0, fx1 + bx1]
        self.xd = [fxd0 + bxd0, fxd1 + bxd1]
        self.xdd = [af0 + ab0, af1 + ab1]

    def write(self, ref: Reference) -> None:
        """Store the current references in ``ref`` (entries 3, 4 of xi, xi_dot, xi_ddot)."""
        ref.xi[3], ref.xi[4] = self.x
        ref.xi_dot[3], ref.xi_dot[4] = self.xd
        ref.xi_ddot[3], ref.xi_ddot[4] = self.xdd


class SingleTiltReference:
    """Roll/pitch references of Thesis (6.17) of the whole force u_fb through one :class:`CommandFilter`.

    The layered controllers of Sec. 6.4 (:mod:`qprr.control.inverse_dynamics`, ``tilt="single"``):
    (6.17) of u_fb (feedforward, feedback and any compensated wrench together), clamped to
    ``max_tilt``, held when u_fb,z <= ``uz_min`` (Hypothesis 2 violated), filtered at ``omega``;
    the filter starts on the first raw values.  Same interface as :class:`TiltReference`.
    """

    __slots__ = ("filter", "max_tilt", "uz_min", "_raw", "_started")

    def __init__(self, omega: float, max_tilt: float, uz_min: float) -> None:
        omega, self.max_tilt, self.uz_min = _filter_args(omega, max_tilt, uz_min)
        self.filter = CommandFilter(2, omega)
        self.reset()

    def reset(self) -> None:
        self.filter = CommandFilter(2, self.filter.omega)
        self._raw = (0.0, 0.0)
        self._started = False

    @property
    def x(self) -> list[float]:
        return self.filter.x

    @property
    def xd(self) -> list[float]:
        return self.filter.xd

    @property
    def xdd(self) -> list[float]:
        return self.filter.xdd

    def update(self, psi: float, u_fb, a_ref, g: float, dt: float) -> None:
        """Advance one step: ``u_fb`` (3,) world force asked for (``a_ref``, ``g`` unused: one filter for all of it)."""
        ux, uy, uz = u_fb
        if uz > self.uz_min:
            self._raw = tilt_6_17(ux, uy, uz, cos(psi), sin(psi), self.max_tilt)
        if not self._started:
            self.filter.reset(self._raw)
            self._started = True
        self.filter.update(self._raw, dt)

    def write(self, ref: Reference) -> None:
        """Store the current references in ``ref`` (entries 3, 4 of xi, xi_dot, xi_ddot)."""
        f = self.filter
        ref.xi[3], ref.xi[4] = f.x
        ref.xi_dot[3], ref.xi_dot[4] = f.xd
        ref.xi_ddot[3], ref.xi_ddot[4] = f.xdd
