"""The logged run of a simulation: :class:`SimResult`, with the RMSE of Thesis (6.26), typed extras and a versioned file format."""

from __future__ import annotations

import json
import math
import zipfile
import zlib
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path

import numpy as np

from ..charts import as_file, as_real, wrap_angle, xi_names
from ..errors import InputError, ShapeError

FORMAT_VERSION = 2
"""Version of the .npz layout written by :meth:`SimResult.save` (1: qprr 0.1, no version field, no extras)."""

ARRAYS = ("t", "xi", "xi_dot", "xi_d", "xi_dot_d", "u", "f", "arm_effort", "x_cm", "unallocated", "flags", "u_ext")


class Status(str, Enum):
    """How a run ended: ``ok`` (completed), ``diverged`` (NaN, runaway state, Euler singularity) or ``failed`` (another qprr error)."""

    OK = "ok"
    DIVERGED = "diverged"
    FAILED = "failed"

    def __str__(self) -> str:
        return self.value


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
      coordinates); flags (m,) bits: 1 rotor bound, 2 arm effort clipped, 4 an arm joint at its stop;
      u_ext (m, n_xi) disturbance;
    * ``status`` (:class:`Status`) and ``reason``; ``series``: extra named arrays (e.g. the
      contact force, the payload mass estimate; time series have m rows); ``metrics``: extra
      named numbers (e.g. the recovery time of a payload drop).  Both are saved.
    * ``arm_kinds``: "prismatic" or "revolute" per arm joint (the units of the figures; empty in
      files written before it existed).
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

    def __post_init__(self) -> None:
        if self.control_period is None:
            self.control_period = self.dt
        self.status = Status(self.status)
        if not self.names:
            self.names = xi_names(self.xi.shape[1] - 6) if self.xi.ndim == 2 else ()

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    @property
    def n_arm(self) -> int:
        return int(self.xi.shape[1]) - 6

    def rmse(self, start: float = 0.0) -> dict[str, float]:
        """Thesis (6.26): sqrt(mean((xi_d - xi)^2)) per variable over t >= ``start``; Euler-angle errors wrapped to [-pi, pi)."""
        sel = self.t >= as_real(start, "start", unit="s")
        e = self.xi_d[sel] - self.xi[sel]
        e[:, ANGLES] = wrap_angle(e[:, ANGLES])
        return {name: float(np.sqrt(np.mean(e[:, i] ** 2))) for i, name in enumerate(self.names)}

    def saturation_fraction(self) -> float:
        """Fraction of ticks where a rotor thrust bound was active."""
        return float(np.mean((self.flags & 1) != 0)) if self.n else 0.0

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
        meta = dict(format_version=FORMAT_VERSION, scenario=self.scenario, controller=self.controller, dt=self.dt,
                    integrator=self.integrator, control_period=self.control_period, wall_time=self.wall_time,
                    status=self.status.value, reason=self.reason, seed=None if self.seed is None else int(self.seed), platform=self.platform,
                    names=list(self.names), metrics={k: float(v) for k, v in self.metrics.items()},
                    series=sorted(self.series), arm_kinds=list(self.arm_kinds))
        arrays = {k: getattr(self, k) for k in ARRAYS}
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
            if version != FORMAT_VERSION:
                raise InputError(f"{source} has format version {version!r}; this qprr reads version {FORMAT_VERSION}")
            missing = [k for k in ARRAYS if k not in files]
            if missing:
                raise InputError(f"{source} lacks the arrays {missing}: truncated or not a result file")
            meta = _check_meta(meta, source)
            missing = [k for k in meta["series"] if f"series_{k}" not in files]
            if missing:
                raise InputError(f"{source} lacks the series {missing} its metadata lists: truncated or corrupted")
            arrays = {k: _read(z, k, source) for k in ARRAYS}
            series = {k: _read(z, f"series_{k}", source) for k in meta["series"]}
        _validate(arrays, meta, source)
        return cls(**arrays, scenario=meta["scenario"], controller=meta["controller"], dt=float(meta["dt"]),
                   integrator=meta["integrator"], wall_time=float(meta["wall_time"]), status=meta["status"],
                   reason=meta["reason"], seed=meta["seed"], control_period=float(meta["control_period"]),
                   platform=meta["platform"], names=tuple(meta["names"]), series=series,
                   metrics={k: float(v) for k, v in meta["metrics"].items()}, arm_kinds=tuple(meta["arm_kinds"]))


_READ_ERRORS = (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error)
"""What numpy and zipfile raise on a foreign, truncated or corrupted file (ValueError: also pickled object arrays)."""


def _read(z, key: str, source: str) -> np.ndarray:
    """One array of an open .npz (InputError naming it if the file is truncated or corrupted there)."""
    try:
        return z[key]
    except _READ_ERRORS as exc:
        raise InputError(f"{source}: cannot read {key!r} ({type(exc).__name__}: {exc}): truncated, corrupted or not a "
                         "qprr result file") from exc


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
    meta = {"platform": "", "names": [], "metrics": {}, "series": [], "arm_kinds": [], **meta}
    missing = [k for k in ("scenario", "controller", "integrator", "dt", "control_period", "wall_time", "status", "reason", "seed")
               if k not in meta]
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
    for key in ("names", "arm_kinds"):
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
