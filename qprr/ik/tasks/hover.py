"""Hover: the thrust axis vertical (an under-actuated multirotor holds still only so)."""

from __future__ import annotations

import math

import numpy as np

from .base import Task, task_name


class HoverTask(Task):
    """Hover feasibility: the base z axis vertical and up, i.e. roll = pitch = 0.

    A multirotor whose rotors all push along z_B holds still only with z_B = e3 (world).  The
    error is the tilt as a rotation vector restricted to the horizontal: with w = R_b e3,
    s = |w_xy| and the tilt angle a = atan2(s, w_z) in [0, pi], e = (a / s) w_xy.  Near hover it
    is w_xy (the horizontal components of z_B), it has no Euler singularity, and unlike w_xy alone
    it does not vanish upside down (z_B = -e3, where |e| = pi is its maximum), so the iteration
    never settles with the rotors pushing down.  Its Jacobian follows from
    dw/dt = -R_b hat(e3) omega_body (columns 3, 4 of the base angular velocity).
    """

    dim = 2

    def __init__(self, name: str = "hover"):
        self.name = task_name(name)

    def linearize(self, platform, data, q):
        (r00, r01, wx), (r10, r11, wy), (r20, r21, wz) = data.oMi[1].rotation.tolist()
        # dw = -R hat(e3) omega_body = -R[:, 1] omega_x + R[:, 0] omega_y: rows of dw_x, dw_y, dw_z over (omega_x, omega_y)
        jx, jy, jz = (-r01, r00), (-r11, r10), (-r21, r20)
        J = np.zeros((2, platform.nv))
        s = math.hypot(wx, wy)
        gc = _gain(s, wz)
        if gc is None:  # within 1e-6 rad of upside down the tilt direction is undefined: tilt about body x, |e| = the angle
            J[:, 3:5] = (jx, jy)
            return J, _upside_down_error(r01, r11, s, wz)
        g, c = gc
        # e = g(s, wz) w_xy: de = g dw_xy + w_xy (c s ds - dwz) with s ds = w_xy . dw_xy (dg/dwz = -1 on |w| = 1)
        v = [c * (wx * jx[k] + wy * jy[k]) - jz[k] for k in (0, 1)]
        J[:, 3:5] = ((g * jx[0] + wx * v[0], g * jx[1] + wx * v[1]), (g * jy[0] + wy * v[0], g * jy[1] + wy * v[1]))
        return J, np.array([-g * wx, -g * wy])

    def error(self, platform, data, q):
        (_, r01, wx), (_, r11, wy), (_, _, wz) = data.oMi[1].rotation.tolist()
        s = math.hypot(wx, wy)
        gc = _gain(s, wz)
        if gc is None:
            return _upside_down_error(r01, r11, s, wz)
        return np.array([-gc[0] * wx, -gc[0] * wy])


def _gain(s: float, wz: float) -> tuple[float, float] | None:
    """(g, c) of e = g w_xy at |w_xy| = s, w_z = wz: g = a / s with the tilt a = atan2(s, wz) and c = (dg/ds) / s;
    None within 1e-6 rad of upside down (no tilt direction)."""
    if s > 1e-4 or (wz < 0.0 and s > 1e-6):
        a = math.atan2(s, wz)
        return a / s, (wz * s - a) / s**3
    if wz > 0.0:  # series of asin(s)/s about upright (|w| = 1): 1 + s^2/6, and c -> -2/3 - s^2/5
        return 1.0 + s * s / 6.0, -2.0 / 3.0 - 0.2 * s * s
    return None


def _upside_down_error(r01: float, r11: float, s: float, wz: float) -> np.ndarray:
    """e near upside down: the tilt angle about body x (the horizontal part of y_B, normalised)."""
    n = max(math.hypot(r01, r11), 1e-300)
    return -math.atan2(s, wz) * np.array([r01 / n, r11 / n])
