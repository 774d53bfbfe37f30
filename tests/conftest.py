"""Shared fixtures: the default Q-PRR platform and a seeded generator of in-limit states."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import qprr.thesis
from qprr.model import Platform

_PACKAGE = Path(qprr.__file__).resolve().parent


@pytest.fixture(scope="session")
def robot() -> Platform:
    """The thesis's Q-PRR ("+" layout, default parameters)."""
    return qprr.thesis.load_qprr()


@pytest.fixture(scope="session")
def cad_robot() -> Platform:
    return qprr.thesis.load_qprr("cad")


@pytest.fixture()
def data(robot):
    return robot.data()


def random_xi(rng: np.random.Generator, robot: Platform, max_pitch: float = 1.3) -> np.ndarray:
    """A random state with the arm inside its limits and |pitch| <= max_pitch."""
    xi = np.empty(9)
    xi[0:3] = rng.uniform(-5.0, 5.0, 3)
    xi[3] = rng.uniform(-np.pi, np.pi)
    xi[4] = rng.uniform(-max_pitch, max_pitch)
    xi[5] = rng.uniform(-np.pi, np.pi)
    xi[6:9] = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
    return xi


def _foreign_qprr_modules() -> list[str]:
    """qprr modules imported from another checkout (e.g. an editable install resolving a module this tree lacks)."""
    out = []
    for name, mod in list(sys.modules.items()):
        path = getattr(mod, "__file__", None)
        if (name == "qprr" or name.startswith("qprr.")) and path and _PACKAGE not in Path(path).resolve().parents:
            out.append(f"{name} ({path})")
    return sorted(out)


def pytest_sessionstart(session):
    """Compile the numba kernels of the QP IK once, before the xdist workers start (qprr[fast]; cached beside the sources
    by numba): workers that all hit a cold cache would each compile them, minutes on a busy 2-core machine."""
    import os
    from importlib.util import find_spec

    if find_spec("numba") is None or os.environ.get("PYTEST_XDIST_WORKER"):
        return
    from qprr.actuation.lexicographic import Lexicographic, QPSettings

    lex = Lexicographic(3, range(1, 3), settings=QPSettings(kernel="numba"), regularization=1e-7, active_set_first=True)
    lex.solve([(np.eye(3)[:2], np.ones(2)), (np.eye(3), np.ones(3))], -np.ones(2), np.ones(2), damping=[0.0, 1e-3])
    import qprr  # the IK's compiled iteration (qprr/ik/iteration_fast.py), which holds the kernel compiled in
    from qprr import ik

    platform = qprr.load("q-prr")
    ik.IKSolver(platform, "qp", {"kernel": "numba"}).solve(platform.data(), np.array([0.3, 0.0, 1.0]))


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    foreign = _foreign_qprr_modules()
    if foreign:
        terminalreporter.section("qprr modules from outside this tree", sep="!", red=True)
        terminalreporter.line("these tests ran code of another checkout, not of " + str(_PACKAGE) + ":")
        for line in foreign:
            terminalreporter.line("  " + line)


def pytest_sessionfinish(session, exitstatus):
    if _foreign_qprr_modules() and session.exitstatus == 0:
        session.exitstatus = 1
