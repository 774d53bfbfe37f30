"""A logged run as the viewers read it: arrays named as the simulator's result, and their ``.npz`` file.

:class:`RunLog` holds what a picture of a run needs, under the attribute names of the
simulator's ``SimResult``: ``t`` (n,) [s], ``xi`` (n, 6 + n_arm) thesis coordinates, ``f``
(n, n_rotors) rotor thrusts [N], ``arm_effort`` (n, n_arm) [N or N m], ``x_cm`` (n, 2) CoG
offset from the thrust axis in B [m], ``contact_wrench_world`` (n, 6) the end-effector contact
wrench [force N; moment N m] in world axes, and ``platform`` (the platform's name).  Only ``t``
and ``xi`` are required.  :func:`save_run` writes any object with these attributes (a
``SimResult`` too) to ``.npz``; :func:`load_run` reads it back.
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..charts import as_array
from ..errors import InputError, NonFiniteError, ShapeError

ARRAYS = ("t", "xi", "f", "arm_effort", "x_cm", "contact_wrench_world")
"""Array attributes of a run, in file order (``t`` and ``xi`` required)."""


@dataclass(frozen=True)
class RunLog:
    """A logged run (see the module docstring); arrays are validated and read-only."""

    t: np.ndarray
    xi: np.ndarray
    f: np.ndarray | None = None
    arm_effort: np.ndarray | None = None
    x_cm: np.ndarray | None = None
    contact_wrench_world: np.ndarray | None = None
    platform: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.platform, str):
            raise InputError(f"platform must be the platform's name (a string), got {type(self.platform).__name__}")
        t = as_array(self.t, "t")
        if t.ndim != 1 or t.shape[0] < 1:
            raise ShapeError(f"t must have shape (n,) with n >= 1, got {t.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0.0):
            raise InputError("t must be finite and non-decreasing [s]")
        n = t.shape[0]
        widths = {"f": None, "arm_effort": None, "x_cm": 2, "contact_wrench_world": 6}
        xi = as_array(self.xi, "xi")
        if xi.ndim != 2 or xi.shape[0] != n or xi.shape[1] < 6:
            raise ShapeError(f"xi must have shape ({n}, 6 + n_arm) like t, got {xi.shape}")
        arrays = {"t": t, "xi": xi}
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
    """A :class:`RunLog` of any object with the attributes ``t`` and ``xi`` (and optionally the others of :data:`ARRAYS`)."""
    if isinstance(result, RunLog):
        return result
    missing = [k for k in ("t", "xi") if getattr(result, k, None) is None]
    if missing:
        raise InputError(f"a run needs the attributes t and xi; {type(result).__name__} lacks {', '.join(missing)}")
    name = getattr(result, "platform", "")
    name = name if isinstance(name, str) else getattr(name, "name", "")
    return RunLog(**{k: getattr(result, k, None) for k in ARRAYS}, platform=name)


def save_run(result, path: str | Path) -> Path:
    """Write a run (any object with :data:`ARRAYS` attributes, e.g. a ``SimResult``) to ``path`` (``.npz``)."""
    run = as_run(result)
    path = Path(path)
    if path.suffix != ".npz":
        raise InputError(f"run files end in .npz, got {str(path)!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {k: getattr(run, k) for k in ARRAYS if getattr(run, k) is not None}
    np.savez_compressed(path, **arrays, platform=np.asarray(run.platform))
    return path


def load_run(path: str | Path) -> RunLog:
    """Read a run written by :func:`save_run` (or any ``.npz`` with arrays ``t`` and ``xi``).

    Raises :class:`~qprr.errors.InputError` naming the file when it does not exist, is not a
    ``.npz`` archive or lacks ``t``/``xi``; arrays of the wrong shape raise ShapeError.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"run file {str(path)!r} does not exist (write one with qprr.viz.save_run or `qprr simulate ... --save FILE.npz`)")
    try:
        with np.load(path, allow_pickle=False) as z:
            files = set(z.files)
            missing = [k for k in ("t", "xi") if k not in files]
            if missing:
                raise InputError(f"run file {str(path)!r} lacks the array(s) {', '.join(missing)}; it holds {sorted(files)}")
            arrays = {k: z[k] for k in ARRAYS if k in files}
            name = str(z["platform"]) if "platform" in files else ""
    except (zipfile.BadZipFile, ValueError, OSError) as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(f"run file {str(path)!r} is not a .npz archive of arrays ({exc})") from exc
    return RunLog(**arrays, platform=name)
