"""Hypothesis strategies shared by the tests: thesis states with the arm inside its limits."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from qprr.thesis.params import QPRRParams, thesis_params

ANGLE = st.floats(-math.pi, math.pi)
PITCH = st.floats(-1.39, 1.39)  # away from the ZYX singularity theta = +-pi/2
POSITION = st.floats(-5.0, 5.0)
RATE = st.floats(-3.0, 3.0)


def xi_strategy(params: QPRRParams | None = None):
    """xi = [x, y, z, phi, theta, psi, r0, theta2, theta3] with the arm inside its limits."""
    p = params if params is not None else thesis_params()
    arm = [st.floats(float(a), float(b)) for a, b in zip(p.lower_limits, p.upper_limits)]
    return st.tuples(POSITION, POSITION, POSITION, ANGLE, PITCH, ANGLE, *arm).map(np.array)


def rates_strategy(n: int = 9):
    """xi_dot (or any n-vector of rates, default 9) in [-3, 3]."""
    return st.lists(RATE, min_size=n, max_size=n).map(np.array)


def platform_xi_strategy(platform, max_pitch: float = 1.39):
    """xi of any platform (6 + n_arm): position in [-5, 5]^3 m, |pitch| <= max_pitch, arm inside its limits
    (a joint without limits in [-pi, pi] or [-1, 1] m)."""
    arm = []
    for j in platform.arm:
        span = math.pi if j.kind == "revolute" else 1.0
        arm.append(st.floats(max(j.lower, -span), min(j.upper, span)))
    return st.tuples(POSITION, POSITION, POSITION, ANGLE, st.floats(-max_pitch, max_pitch), ANGLE, *arm).map(np.array)
