"""Hypothesis strategies shared by the tests: thesis states with the arm inside its limits."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from qprr.params import QPRRParams, thesis_params

ANGLE = st.floats(-math.pi, math.pi)
PITCH = st.floats(-1.39, 1.39)  # away from the ZYX singularity theta = +-pi/2
POSITION = st.floats(-5.0, 5.0)
RATE = st.floats(-3.0, 3.0)


def xi_strategy(params: QPRRParams | None = None):
    """xi = [x, y, z, phi, theta, psi, r0, theta2, theta3] with the arm inside its limits."""
    p = params if params is not None else thesis_params()
    arm = [st.floats(float(a), float(b)) for a, b in zip(p.lower_limits, p.upper_limits)]
    return st.tuples(POSITION, POSITION, POSITION, ANGLE, PITCH, ANGLE, *arm).map(np.array)


def rates_strategy():
    """xi_dot (or any 9-vector of rates) in [-3, 3]."""
    return st.lists(RATE, min_size=9, max_size=9).map(np.array)
