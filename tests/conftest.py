"""Shared fixtures: the default robot and a seeded generator of in-limit states."""

from __future__ import annotations

import numpy as np
import pytest

import qprr
from qprr import model as qm


@pytest.fixture(scope="session")
def robot() -> qm.Robot:
    return qprr.load()


@pytest.fixture(scope="session")
def cad_robot() -> qm.Robot:
    return qprr.load("cad")


@pytest.fixture()
def data(robot):
    return robot.data()


def random_xi(rng: np.random.Generator, robot: qm.Robot, max_pitch: float = 1.3) -> np.ndarray:
    """A random state with the arm inside its limits and |pitch| <= max_pitch."""
    xi = np.empty(9)
    xi[0:3] = rng.uniform(-5.0, 5.0, 3)
    xi[3] = rng.uniform(-np.pi, np.pi)
    xi[4] = rng.uniform(-max_pitch, max_pitch)
    xi[5] = rng.uniform(-np.pi, np.pi)
    xi[6:9] = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
    return xi
