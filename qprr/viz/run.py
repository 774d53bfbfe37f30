"""A run as the viewers read it: :class:`RunLog`, and :func:`load_run` for result files.

:class:`RunLog` holds what a picture of a run needs, under the attribute names of the
simulator's :class:`~qprr.sim.SimResult`: ``t`` (n,) [s], ``xi`` (n, 6 + n_arm) thesis
coordinates, ``f`` (n, n_rotors) rotor thrusts [N], ``arm_effort`` (n, n_arm) [N or N m],
``contact_wrench_world`` (n, 6) the end-effector contact wrench [force N; moment N m] in world
axes, ``payload_mass`` (n,) [kg] and ``payload_com_ee`` (n, 3) [m, end-effector frame] the payload the end effector
carries, and ``platform`` (the platform's name).  Only ``t`` and ``xi`` are required; a path with
no simulator behind it (an IK path, :mod:`qprr.viz.ikpath`) is a RunLog too.

Runs on disk are result files of the simulator (:meth:`SimResult.save
<qprr.sim.SimResult.save>`, ``qprr simulate ... --save FILE.npz``): one file format in the
project.  :func:`load_run` reads one as a RunLog (the ``contact_wrench_world``, ``payload_mass`` and
``payload_com_ee`` series, when logged, are drawn).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, NonFiniteError, ShapeError
from ..validation import as_array

ARRAYS = ("t", "xi", "f", "arm_effort", "contact_wrench_world", "payload_mass", "payload_com_ee")
"""Array attributes of a run, in file order (``t`` and ``xi`` required)."""


@dataclass(frozen=True)
class RunLog:
    """A logged run (see the module docstring); arrays are validated and read-only."""

    t: np.ndarray
    xi: np.ndarray
    f: np.ndarray | None = None
    arm_effort: np.ndarray | None = None
    contact_wrench_world: np.ndarray | None = None
    platform: str = ""
    payload_mass: np.ndarray | None = None
    payload_com_ee: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.platform, str):
            raise InputError(f"platform must be the platform's name (a string), got {type(self.platform).__name__}")
        t = as_array(self.t, "t")
        if t.ndim != 1 or t.shape[0] < 1:
            raise ShapeError(f"t must have shape (n,) with n >= 1, got {t.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0.0):
            raise InputError("t must be finite and non-decreasing [s]")
        n = t.shape[0]
        widths = {"f": None, "arm_effort": None, "contact_wrench_world": 6, "payload_com_ee": 3}
        xi = as_array(self.xi, "xi")
        if xi.ndim != 2 or xi.shape[0] != n or xi.shape[1] < 6:
            raise ShapeError(f"xi must have shape ({n}, 6 + n_arm) like t, got {xi.shape}")
        arrays = {"t": t, "xi": xi}
        if self.payload_mass is not None:
            mass = as_array(self.payload_mass, "payload_mass")
            if mass.shape != (n,) or not np.all(mass >= 0.0):
                raise ShapeError(f"payload_mass must have shape ({n},) like t, masses >= 0 kg, got shape {mass.shape}")
            arrays["payload_mass"] = mass
        for name, width in widths.items():
            a = getattr(self, name)
            if a is None:
                continue
            a = as_array(a, name)
            if a.ndim != 2 or a.shape[0] != n or (width is not None and a.shape[1] != width):
                want = f"({n}, {width})" if width is not None else f"({n}, k)"
                raise ShapeError(f"{name} must have shape {want}, got {a.shape}")
            arrays[name] = a
        for name, a in arrays.items():
            if not np.all(np.isfinite(a)):
                raise NonFiniteError(f"{name} must be finite (first bad row {int(np.flatnonzero(~np.isfinite(a).reshape(n, -1).all(1))[0])})")
            a = np.array(a, dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "platform", str(self.platform))

    @property
    def n(self) -> int:
        return int(self.t.shape[0])


def as_run(result) -> RunLog:
    """The :class:`RunLog` of a :class:`~qprr.sim.SimResult` (its ``contact_wrench_world``, ``payload_mass`` and
    ``payload_com_ee`` series drawn when logged), or ``result`` itself when it is one (a run from elsewhere: build a
    :class:`RunLog` of its arrays)."""
    from ..sim.result import SimResult

    if isinstance(result, RunLog):
        return result
    if not isinstance(result, SimResult):
        raise InputError(
            f"result must be a run: a qprr.sim.SimResult or a qprr.viz.RunLog (RunLog(t, xi, ...) of another run's "
            f"arrays), got {type(result).__name__}"
        )
    series = result.series
    return RunLog(
        result.t,
        result.xi,
        result.f,
        result.arm_effort,
        series.get("contact_wrench_world"),
        platform=result.platform,
        payload_mass=series.get("payload_mass"),
        payload_com_ee=series.get("payload_com_ee"),
    )


def load_run(path: str | Path) -> RunLog:
    """The run of a result file (:meth:`qprr.sim.SimResult.load`: validated, errors name the file) as a :class:`RunLog`."""
    from ..sim.result import SimResult

    return as_run(SimResult.load(path))
