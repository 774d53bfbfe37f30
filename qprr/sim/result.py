"""The logged run of a simulation: :class:`SimResult`, with the RMSE of Thesis (6.26), typed extras and a versioned file format."""

from __future__ import annotations

import json
import math
import zipfile
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path

import numpy as np

from ..actuation import AllocationFlag
from ..charts import wrap_angle, xi_names
from ..errors import InputError, ShapeError
from ..registry import Registry
from ..validation import as_file, as_real

FORMAT_VERSION = 3
"""Version of the .npz layout written by :meth:`SimResult.save`.

1: qprr 0.1, no version field, no extras (not read).  2: metadata and extras.  3: version 2 plus the
array ``rotor_bounds`` (n_rotors, 2) [N] when the result has it.  The rule: :meth:`SimResult.load`
reads :data:`READABLE_VERSIONS`; a version-2 file loads with ``rotor_bounds = None`` (not recorded).
"""

READABLE_VERSIONS = (2, 3)
"""Format versions :meth:`SimResult.load` reads (see :data:`FORMAT_VERSION`)."""

ARRAYS = ("t", "xi", "xi_dot", "xi_d", "xi_dot_d", "u", "f", "arm_effort", "x_cm", "unallocated", "flags", "u_ext")


class Status(str, Enum):
    """How a run ended: ``ok`` (completed), ``diverged`` (NaN, runaway state, Euler singularity) or ``failed`` (another qprr error)."""

    OK = "ok"
    DIVERGED = "diverged"
    FAILED = "failed"

    def __str__(self) -> str:
        return self.value


RUN_FIGURES_GROUP = "qprr.run_figures"
"""Entry-point group of :data:`RUN_FIGURES`: qprr's own ``pyproject.toml`` names ``qprr.viz.plots:plot_result`` there."""

RUN_FIGURES: Registry[Callable[..., object]] = Registry("run figure", RUN_FIGURES_GROUP, default="run")
"""Figure makers of a run, name -> ``(result, path=None, **options) -> Figure (or the path written)``.

:meth:`SimResult.plot` calls the ``"run"`` entry, :func:`qprr.viz.plot_result` (the page of ``qprr simulate
--plot``).  The simulator sits above the figures in the module map (docs/architecture.md) and never imports
them: :mod:`qprr.viz` registers its function when imported, and the entry point of :data:`RUN_FIGURES_GROUP`
names it, so ``result.plot()`` imports it on first use."""

ANGLES = (3, 4, 5)
"""Columns of xi that are ZYX Euler angles: their errors are wrapped to [-pi, pi) in :meth:`SimResult.rmse`."""


@dataclass
class SimResult:
    """Logged run, one row per control tick (values at the tick).

    ``dt`` [s] integration step, ``control_period`` [s] the controller's period (the spacing of
    the rows).  With n_xi = 6 + n_arm:

    * t (m,) [s]; xi, xi_dot (m, n_xi) measured thesis coordinates; xi_d, xi_dot_d (m, n_xi)
      references actually tracked (roll/pitch from the controller);
    * u (m, n_xi) controller output, thesis generalised forces (u_fb world force [N], Euler
      torques [N m], arm efforts); f (m, n_rotors) rotor thrusts [N]; arm_effort (m, n_arm) applied;
    * x_cm (m, 3) system CoM in B [m] (Thesis (3.78)); unallocated (m, nv) tau_d - N f (Pinocchio
      coordinates); flags (m,) the :class:`~qprr.actuation.AllocationFlag` bits of each tick (integers: 1
      ROTOR_SATURATED a rotor bound, 2 ARM_SATURATED an arm effort clipped, 4 JOINT_STOP an arm joint at its
      stop; read them as ``res.flags & AllocationFlag.ROTOR_SATURATED``); u_ext (m, n_xi) disturbance;
    * ``status`` (:class:`Status`) and ``reason``; ``series``: extra named arrays (e.g. the
      contact force, the payload mass estimate; time series have m rows); ``metrics``: extra
      named numbers (e.g. the recovery time of a payload drop).  Both are saved.
    * ``arm_kinds``: "prismatic" or "revolute" per arm joint (the units of the figures; empty in
      files written before it existed).
    * ``rotor_bounds`` (n_rotors, 2) [N]: per rotor [f_min, f_max], the thrust bounds the run's
      allocation respected (the platform's, or those given to its allocator); None when not
      recorded (a result built by hand, a file of format 2).
    * ``rotor_names``: one name per column of ``f``, as the platform's rotor description gives them (figures label the
      thrusts with them); empty when not recorded (a result built by hand, a file written before it existed).
    """

    scenario: str
    controller: str
    dt: float
    integrator: str
    t: np.ndarray
    xi: np.ndarray
    xi_dot: np.ndarray
    xi_d: np.ndarray
    xi_dot_d: np.ndarray
    u: np.ndarray
    f: np.ndarray
    arm_effort: np.ndarray
    x_cm: np.ndarray
    unallocated: np.ndarray
    flags: np.ndarray
    u_ext: np.ndarray
    wall_time: float = 0.0
    status: Status = Status.OK
    reason: str = ""
    seed: int | None = None
    control_period: float | None = None
    platform: str = ""
    names: tuple[str, ...] = ()
    series: dict[str, np.ndarray] = field(default_factory=dict)
    metrics: dict[str, float] = field(default_factory=dict)
    arm_kinds: tuple[str, ...] = ()
    rotor_bounds: np.ndarray | None = None
    rotor_names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.control_period is None:
            self.control_period = self.dt
        self.status = Status(self.status)
        if not self.names:
            self.names = xi_names(self.xi.shape[1] - 6) if self.xi.ndim == 2 else ()
        if self.rotor_bounds is not None:
            self.rotor_bounds = _check_rotor_bounds(self.rotor_bounds, self.f, "rotor_bounds")
        self.rotor_names = _check_rotor_names(self.rotor_names, self.f, "rotor_names")

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    @property
    def n_arm(self) -> int:
        return int(self.xi.shape[1]) - 6

    def rmse(self, start: float = 0.0) -> dict[str, float]:
        """Thesis (6.26): sqrt(mean((xi_d - xi)^2)) per variable over t >= ``start``; Euler-angle errors wrapped to [-pi, pi).

        ``start`` beyond the last logged tick (no sample to average) raises InputError naming the run's span."""
        start = as_real(start, "start", unit="s")
        sel = self.t >= start
        if not sel.any():
            span = f"[{float(self.t[0])!r}, {float(self.t[-1])!r}] s" if self.n else "no tick"
            raise InputError(f"rmse: start = {start!r} s is after the last logged tick (the run covers {span}); give a start within the run")
        e = self.xi_d[sel] - self.xi[sel]
        e[:, ANGLES] = wrap_angle(e[:, ANGLES])
        return {name: float(np.sqrt(np.mean(e[:, i] ** 2))) for i, name in enumerate(self.names)}

    def plot(self, path: str | Path | None = None, **options):
        """A figure of the run: :func:`qprr.viz.plot_result` on this result (python-control's ``response.plot()``).

        ``path`` None returns the ``matplotlib.figure.Figure``; a file path (.png, .pdf, .svg, its folder existing)
        saves the page there and returns the path.  ``options`` go to :func:`~qprr.viz.plot_result` (``panels``,
        ``ax``, ``title``, ``events``, ...).  The figure maker is the ``"run"`` entry of :data:`RUN_FIGURES`."""
        if RUN_FIGURES.default not in RUN_FIGURES:
            raise InputError(
                "no figure maker for runs is registered: import qprr.viz, or install qprr (pip install -e .) so that its "
                f"entry point {RUN_FIGURES_GROUP!r} is found"
            )
        return RUN_FIGURES[RUN_FIGURES.default](self, path, **options)

    def saturation_fraction(self) -> float:
        """Fraction of ticks where a rotor thrust bound was active."""
        return float(np.mean((self.flags & AllocationFlag.ROTOR_SATURATED) != 0)) if self.n else 0.0

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write every array, the extras and the metadata to a ``.npz`` file (format :data:`FORMAT_VERSION`).

        The parent folder must exist (it is not created: a typo would otherwise make one)."""
        if not isinstance(path, (str, Path)) or str(path) == "":
            raise InputError(f"path must be a file path ending in .npz, got {path!r}")
        path = Path(path)
        if path.suffix != ".npz":
            raise InputError(f"result files end in .npz, got {str(path)!r}")
        if not path.parent.is_dir():
            raise InputError(f"cannot save {str(path)!r}: folder {str(path.parent)!r} does not exist")
        bad = [k for k in self.series if not isinstance(k, str)] + [k for k in self.metrics if not isinstance(k, str)]
        if bad:
            raise InputError(f"series and metrics are named by strings, got {bad[0]!r}")
        bad = [k for k in self.series if "\x00" in k or not _utf8(k)]
        if bad:
            raise InputError(f"series name {bad[0]!r} cannot be stored (a NUL character or no UTF-8 form)")
        bad = [k for k, v in self.metrics.items() if not _is_number(v)]
        if bad:
            raise InputError(f"metric {bad[0]!r} must be a number, got {self.metrics[bad[0]]!r}")
        meta = dict(
            format_version=FORMAT_VERSION,
            scenario=self.scenario,
            controller=self.controller,
            dt=self.dt,
            integrator=self.integrator,
            control_period=self.control_period,
            wall_time=self.wall_time,
            status=self.status.value,
            reason=self.reason,
            seed=None if self.seed is None else int(self.seed),
            platform=self.platform,
            names=list(self.names),
            metrics={k: float(v) for k, v in self.metrics.items()},
            series=sorted(self.series),
            arm_kinds=list(self.arm_kinds),
            rotor_names=list(self.rotor_names),
        )
        arrays = {k: getattr(self, k) for k in ARRAYS}
        if self.rotor_bounds is not None:
            arrays["rotor_bounds"] = self.rotor_bounds
        extras = {f"series_{k}": np.asarray(v) for k, v in self.series.items()}
        try:
            np.savez_compressed(path, **arrays, **extras, meta=np.array(json.dumps(meta)))
        except OSError as exc:
            raise InputError(f"cannot save {str(path)!r}: {exc.strerror or exc}") from exc
        return path

    @classmethod
    def load(cls, path: str | Path) -> SimResult:
        """Read a file written by :meth:`save`, validating its version, metadata, shapes and types.

        A missing, foreign, truncated or corrupted file, another format version or an array of the
        wrong shape or type raises :class:`~qprr.errors.InputError` (:class:`~qprr.errors.ShapeError`
        for shapes) naming the file and what is wrong."""
        path = as_file(path, "path", what="result file")
        source = repr(str(path))
        try:
            z = np.load(path, allow_pickle=False)
        except _READ_ERRORS as exc:
            raise InputError(f"{source} is not a qprr result file (.npz, format {FORMAT_VERSION}): {exc}") from exc
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise InputError(f"{source} holds a single array (.npy data), not a qprr result file (.npz, format {FORMAT_VERSION})")
        with z:
            files = set(z.files)
            if "meta" not in files:
                raise InputError(f"{source} has no qprr metadata: not a result file of qprr >= 0.2 (format {FORMAT_VERSION})")
            try:
                meta = json.loads(str(_read(z, "meta", source)[()]))
            except ValueError as exc:
                raise InputError(f"{source}: corrupted metadata ({exc})") from exc
            if not isinstance(meta, dict):
                raise InputError(f"{source}: corrupted metadata (a JSON object expected, got {type(meta).__name__})")
            version = meta.get("format_version")
            if version not in READABLE_VERSIONS or isinstance(version, bool):
                raise InputError(f"{source} has format version {version!r}; this qprr reads versions {', '.join(map(str, READABLE_VERSIONS))}")
            missing = [k for k in ARRAYS if k not in files]
            if missing:
                raise InputError(f"{source} lacks the arrays {missing}: truncated or not a result file")
            meta = _check_meta(meta, source)
            missing = [k for k in meta["series"] if f"series_{k}" not in files]
            if missing:
                raise InputError(f"{source} lacks the series {missing} its metadata lists: truncated or corrupted")
            arrays = {k: _read(z, k, source) for k in ARRAYS}
            series = {k: _read(z, f"series_{k}", source) for k in meta["series"]}
            bounds = _read(z, "rotor_bounds", source) if version >= 3 and "rotor_bounds" in files else None
        _validate(arrays, meta, source)
        if bounds is not None:
            bounds = _check_rotor_bounds(bounds, arrays["f"], f"{source}: rotor_bounds", loaded=True)
        return cls(
            **arrays,
            scenario=meta["scenario"],
            controller=meta["controller"],
            dt=float(meta["dt"]),
            integrator=meta["integrator"],
            wall_time=float(meta["wall_time"]),
            status=meta["status"],
            reason=meta["reason"],
            seed=meta["seed"],
            control_period=float(meta["control_period"]),
            platform=meta["platform"],
            names=tuple(meta["names"]),
            series=series,
            metrics={k: float(v) for k, v in meta["metrics"].items()},
            arm_kinds=tuple(meta["arm_kinds"]),
            rotor_bounds=bounds,
            rotor_names=tuple(meta["rotor_names"]),
        )


_READ_ERRORS = (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error)
"""What numpy and zipfile raise on a foreign, truncated or corrupted file (ValueError: also pickled object arrays)."""


def _check_rotor_bounds(bounds, f: np.ndarray, what: str, loaded: bool = False) -> np.ndarray:
    """``bounds`` as a float array (n_rotors, 2) of [f_min, f_max] rows, f_min <= f_max, n_rotors the columns of ``f``."""
    if loaded and bounds.dtype.kind != "f":
        raise InputError(f"{what} must be float, got dtype {bounds.dtype}")
    try:
        b = np.array(bounds, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be an array (n_rotors, 2) of thrust bounds [N], got {bounds!r:.80}") from exc
    n_rotors = f.shape[1] if f.ndim == 2 else -1
    if b.shape != (n_rotors, 2):
        raise ShapeError(f"{what} must have shape ({n_rotors}, 2) (one [f_min, f_max] row per rotor of f), got {b.shape}")
    if not (np.all(np.isfinite(b)) and np.all(b[:, 0] <= b[:, 1])):
        raise InputError(f"{what} must hold finite rows [f_min, f_max] with f_min <= f_max [N], got {b.tolist()}")
    return b


def _check_rotor_names(names, f: np.ndarray, what: str) -> tuple[str, ...]:
    """``names`` as a tuple of strings, empty or one per column of ``f`` (the rotors)."""
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise InputError(f"{what} must be a sequence of strings (one per rotor), got {names!r:.80}")
    names = tuple(names)
    n_rotors = f.shape[1] if f.ndim == 2 else -1
    if names and len(names) != n_rotors:
        raise ShapeError(f"{what} has {len(names)} names for the {n_rotors} rotors (columns of f): give one per rotor, or none")
    return names


def _read(z, key: str, source: str) -> np.ndarray:
    """One array of an open .npz (InputError naming it if the file is truncated or corrupted there)."""
    try:
        return z[key]
    except _READ_ERRORS as exc:
        raise InputError(f"{source}: cannot read {key!r} ({type(exc).__name__}: {exc}): truncated, corrupted or not a qprr result file") from exc


def _utf8(text: str) -> bool:
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def _is_number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def _check_meta(meta: dict, source: str) -> dict:
    """The metadata's entries with their types checked (InputError naming the entry); optional ones filled in."""
    meta = {"platform": "", "names": [], "metrics": {}, "series": [], "arm_kinds": [], "rotor_names": [], **meta}
    missing = [k for k in ("scenario", "controller", "integrator", "dt", "control_period", "wall_time", "status", "reason", "seed") if k not in meta]
    if missing:
        raise InputError(f"{source}: metadata lacks {missing}: truncated or corrupted")
    for key in ("scenario", "controller", "integrator", "reason", "platform"):
        if not isinstance(meta[key], str):
            raise InputError(f"{source}: metadata {key} must be a string, got {meta[key]!r}")
    for key, low in (("dt", "> 0"), ("control_period", "> 0"), ("wall_time", ">= 0")):
        v = meta[key]
        if not (_is_number(v) and math.isfinite(v) and (v > 0 if low == "> 0" else v >= 0)):
            raise InputError(f"{source}: metadata {key} must be a number {low}, got {v!r}")
    if meta["status"] not in {s.value for s in Status}:
        raise InputError(f"{source}: unknown status {meta['status']!r}; valid: {[s.value for s in Status]}")
    if meta["seed"] is not None and not (isinstance(meta["seed"], int) and not isinstance(meta["seed"], bool)):
        raise InputError(f"{source}: metadata seed must be an integer or null, got {meta['seed']!r}")
    for key in ("names", "arm_kinds", "rotor_names"):
        if not (isinstance(meta[key], list) and all(isinstance(n, str) for n in meta[key])):
            raise InputError(f"{source}: metadata {key} must be a list of strings, got {meta[key]!r}")
    m = meta["metrics"]
    if not (isinstance(m, dict) and all(_is_number(v) for v in m.values())):
        raise InputError(f"{source}: metadata metrics must map names to numbers, got {m!r}")
    if not (isinstance(meta["series"], list) and all(isinstance(n, str) for n in meta["series"])):
        raise InputError(f"{source}: metadata series must be a list of names, got {meta['series']!r}")
    return meta


def _validate(arrays: dict, meta: dict, source: str) -> None:
    """Shapes and types of a loaded result (ShapeError / InputError naming the array)."""
    t = arrays["t"]
    if t.ndim != 1 or t.dtype.kind != "f":
        raise ShapeError(f"{source}: t must be a 1-D float array, got shape {t.shape} dtype {t.dtype}")
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise InputError(f"{source}: t must be finite and increasing (one row per control tick)")
    m = t.shape[0]
    n_xi = arrays["xi"].shape[1] if arrays["xi"].ndim == 2 else -1
    if n_xi < 6:
        raise ShapeError(f"{source}: xi must have shape ({m}, 6 + n_arm), got {arrays['xi'].shape}")
    for k in ARRAYS:
        a = arrays[k]
        if a.ndim == 0 or a.shape[0] != m:
            raise ShapeError(f"{source}: {k} has shape {a.shape}, t has {m} rows")
        if k == "flags":
            if a.ndim != 1 or a.dtype.kind not in "iu":
                raise InputError(f"{source}: flags must be a 1-D integer array, got shape {a.shape} dtype {a.dtype}")
        elif a.dtype.kind != "f":
            raise InputError(f"{source}: {k} must be float, got dtype {a.dtype}")
    n_rotors = arrays["f"].shape[1] if arrays["f"].ndim == 2 else 0
    shapes = {k: (m, n_xi) for k in ("xi_dot", "xi_d", "xi_dot_d", "u", "u_ext", "unallocated")}
    shapes.update(f=(m, max(n_rotors, 1)), arm_effort=(m, n_xi - 6), x_cm=(m, 3))
    for k, shape in shapes.items():
        if arrays[k].shape != shape:
            expected = f"({m}, n_rotors >= 1)" if k == "f" else str(shape)
            raise ShapeError(f"{source}: {k} must have shape {expected}, got {arrays[k].shape}")
    if meta["names"] and len(meta["names"]) != n_xi:
        raise ShapeError(f"{source}: metadata names has {len(meta['names'])} entries for xi's {n_xi} columns")
