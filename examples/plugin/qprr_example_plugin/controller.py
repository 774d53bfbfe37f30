"""The plug-in's controller: PD + gravity compensation, and how its gains follow from a platform.

Position: the world force u_p = m (p_ddot_d + K_P e_p + K_D e_p_dot) + m g e3; its direction gives the roll and
pitch references (Thesis (6.17), :func:`qprr.control.tilt_6_17`).  Every other coordinate of xi (roll, pitch, yaw,
the arm joints): u_i = G_i(xi) + b_i (K_P,i e_i + K_D,i e_i_dot), with G the generalised gravity in thesis
coordinates (S^T g(q)) and b_i the inertia the coordinate moves (the diagonal of B = S^T M S at the neutral pose).

Gains: :func:`derive` gives each coordinate the critically damped error polynomial (s + w)^2 (K_P = w^2, K_D = 2 w)
with the bandwidths w of :func:`qprr.control.gains.bandwidths` (the platform's thrust, torque and joint authority):
the controller's :class:`~qprr.control.DerivedGains`, so ``make_controller("pd-gravity", platform)`` flies any
platform with gains of its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from qprr.charts import rate_map
from qprr.control import Controller, ControllerEntry, DerivedGains, tilt_6_17
from qprr.control.gains import Authority, Targets, bandwidths


@dataclass(frozen=True)
class PDGains:
    """K_P [1/s^2] and K_D [1/s] per coordinate of xi (6 + n_arm each)."""

    kp: tuple[float, ...]
    kd: tuple[float, ...]


def derive(authority: Authority, targets: Targets) -> dict[str, object]:
    """(s + w)^2 on every coordinate, w from the platform's authority: the controller's gain derivation."""
    w = bandwidths(authority, targets)
    return {"gains": PDGains(kp=tuple(w**2), kd=tuple(2.0 * w))}


class PDGravity(Controller):
    """PD + gravity compensation (module docstring): ``PDGravity(platform, gains=PDGains(...), max_tilt=0.5)``."""

    name = "pd-gravity"

    def __init__(self, platform, gains: PDGains, max_tilt: float = 0.5) -> None:
        self.platform = platform
        self.kp, self.kd = np.asarray(gains.kp, dtype=float), np.asarray(gains.kd, dtype=float)
        self.max_tilt = float(max_tilt)
        self.data = platform.data()
        xi0 = platform.neutral_xi()
        S = rate_map(xi0)
        self.inertia = np.diag(S.T @ pin.crba(platform.model, self.data, platform.neutral_q()) @ S).copy()
        self.mass = platform.total_mass

    def step(self, t, state, ref):
        xi, xi_dot = state.xi, state.xi_dot
        e, e_dot = ref.xi - xi, ref.xi_dot - xi_dot
        f = self.mass * (ref.xi_ddot[:3] + self.kp[:3] * e[:3] + self.kd[:3] * e_dot[:3])
        f[2] += self.mass * self.platform.g
        psi = xi[5]
        ref.xi[3], ref.xi[4] = tilt_6_17(f[0], f[1], f[2], math.cos(psi), math.sin(psi), self.max_tilt)  # logged as tracked
        e[3:5], e_dot[3:5] = ref.xi[3:5] - xi[3:5], -xi_dot[3:5]
        gravity = state.force_to_xi(pin.computeGeneralizedGravity(self.platform.model, self.data, state.q))
        u = gravity + self.inertia * (self.kp * e + self.kd * e_dot)
        u[:3] = f
        return u


ENTRY = ControllerEntry(
    PDGravity,
    DerivedGains(("gains",), derive),
    "PD + gravity compensation, (s + w)^2 on every coordinate",
    scenarios=("hover-reach", "takeoff-hover", "fly-to"),
)
"""What :func:`qprr_example_plugin.register` puts in ``qprr.control.CONTROLLERS`` as ``pd-gravity``; ``scenarios``: the
core's scenarios that may fly it besides the plug-in's own (which names it)."""
