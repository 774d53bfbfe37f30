"""CoG stabiliser "BSG" of Thesis Sec. 6.3.3.1, (6.33)-(6.35).

The BSG keeps the system's centre of gravity on the thrust axis (x_cm = 0 in B) while the end
effector keeps a desired pitch theta_e^d:

* (6.34)-(6.35): theta_e = theta + theta2 + theta3, so theta3_d = theta_e^d - theta - theta2_d;
* (6.33): x_cm = beta1 r0 + beta2 sin(theta2) + beta3 sin(theta2 + theta3) with
  beta1 = (m1 + m2 + m3) / m_G, beta2 = d2 (m2 / 2 + m3) / m_G, beta3 = m3 d3 / (2 m_G)
  (homogeneous links, Hypothesis 1), so r0_d = -(beta2 s2 + beta3 s23) / beta1.

theta is the measured pitch ("the current pitch"; the thesis's (6.35) writes theta^d of (6.17),
``pitch="desired"`` uses the last roll/pitch reference instead).  r0_d and theta3_d are
clamped to the joint limits (then x_cm cannot be exactly 0: with theta2_d = -0.5 and
theta_e^d = 0 the unclamped r0_d is 4.1 cm, just beyond the 4 cm stroke of Sec. 4.4.3).
Their rates and accelerations come from a command filter.  The BSG wraps another
controller (the thesis uses the MFC): it writes r0_d and theta3_d into the reference, then
calls the inner controller.
"""

from __future__ import annotations

import math

import numpy as np

from ..charts import State
from ..control.base import Controller, Reference, check_reset
from ..control.filters import CommandFilter
from ..errors import InputError, UnknownNameError
from ..model import Platform
from ..validation import as_real, checked_module
from .params import QPRRParams
from .robot import params_of


def cog_betas(params: QPRRParams) -> tuple[float, float, float]:
    """(beta1, beta2, beta3) of Thesis (6.33) from the link masses and lengths."""
    m1, m2, m3 = (link.mass for link in params.links)
    mG = params.total_mass
    return (m1 + m2 + m3) / mG, params.d2 * (0.5 * m2 + m3) / mG, 0.5 * m3 * params.d3 / mG


def x_cm_thesis(params: QPRRParams, r0: float, theta2: float, theta3: float) -> float:
    """x_cm of Thesis (6.33) [m] (CoG offset along x_B; valid under Hypothesis 1)."""
    b1, b2, b3 = cog_betas(params)
    return b1 * r0 + b2 * math.sin(theta2) + b3 * math.sin(theta2 + theta3)


class CogStabilizer(Controller):
    """BSG (6.33)-(6.35) in front of an inner controller; see the module docstring."""

    name = "bsg"

    def __init__(self, platform: Platform, inner: Controller, *, theta_e_d: float = 0.0, pitch: str = "measured", filter_omega: float = 20.0) -> None:
        if pitch not in ("measured", "desired"):
            raise UnknownNameError("BSG pitch source", pitch, ("measured", "desired"))
        if not isinstance(inner, Controller):
            raise InputError(f"inner must be a Controller, got {type(inner).__name__}")
        theta_e_d = as_real(theta_e_d, "theta_e_d", unit="rad")
        filter_omega = as_real(filter_omega, "filter_omega", positive=True, unit="rad/s")
        params = params_of(platform)
        self.platform = platform
        self.inner = inner
        self.theta_e_d = float(theta_e_d)
        self.pitch = pitch
        self.betas = cog_betas(params)
        self.lo = params.lower_limits
        self.hi = params.upper_limits
        self.filter_omega = float(filter_omega)
        self.name = f"bsg+{inner.name}"
        self.uses_applied_force = inner.uses_applied_force
        self.output = inner.output
        self.filter = CommandFilter(2, self.filter_omega)
        self._started = False

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        self.dt = dt = check_reset(self, state, ref, dt)
        self.filter = CommandFilter(2, self.filter_omega)
        self._started = False
        self.inner.reset(state, ref, dt)
        if self.pitch == "desired" and self.inner.tilt is None:
            raise InputError(
                f"pitch='desired' reads the inner controller's roll/pitch references, but "
                f"{type(self.inner).__name__} ({self.inner.name}) derives none (its tilt is None): "
                f"use pitch='measured' or an inner controller with a tilt reference"
            )

    def joint_references(self, theta: float, theta2_d: float) -> tuple[float, float]:
        """(r0_d, theta3_d) of (6.33)-(6.35) for pitch ``theta``, clamped to the joint limits."""
        b1, b2, b3 = self.betas
        t3 = min(max(self.theta_e_d - theta - theta2_d, self.lo[2]), self.hi[2])
        r0 = -(b2 * math.sin(theta2_d) + b3 * math.sin(theta2_d + t3)) / b1
        return min(max(r0, self.lo[0]), self.hi[0]), t3

    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """Write r0_d, theta3_d (filtered, with rates) into ``ref`` and return the inner controller's u."""
        dt = self.dt
        theta = state.xi_floats[4] if self.pitch == "measured" else self.inner.tilt.x[1]
        r0_d, t3_d = self.joint_references(float(theta), ref.xi.item(7))
        if not self._started:
            self.filter.reset((r0_d, t3_d))
            self._started = True
        self.filter.update((r0_d, t3_d), dt)
        f = self.filter
        ref.xi[6], ref.xi[8] = f.x
        ref.xi_dot[6], ref.xi_dot[8] = f.xd
        ref.xi_ddot[6], ref.xi_ddot[8] = f.xdd
        return self.inner.step(t, state, ref)


checked_module(globals())
