"""The logged run of a simulation: :class:`SimResult`, with the RMSE of Thesis (6.26), typed extras and a versioned file format."""

from __future__ import annotations

import json
import math
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
        meta = dict(format_version=FORMAT_VERSION, scenario=self.scenario, controller=self.controller, dt=self.dt,
                    integrator=self.integrator, control_period=self.control_period, wall_time=self.wall_time,
                    status=self.status.value, reason=self.reason, seed=self.seed, platform=self.platform,
                    names=list(self.names), metrics={k: float(v) for k, v in self.metrics.items()},
                    series=sorted(self.series))
        arrays = {k: getattr(self, k) for k in ARRAYS}
        extras = {f"series_{k}": np.asarray(v) for k, v in self.series.items()}
        try:
            np.savez_compressed(path, **arrays, **extras, meta=np.array(json.dumps(meta)))
        except OSError as exc:
            raise InputError(f"cannot save {str(path)!r}: {exc.strerror or exc}") from exc
        return path

    @classmethod
    def load(cls, path: str | Path) -> SimResult:
        """Read a file written by :meth:`save`, validating its version, shapes and types."""
        path = as_file(path, "path", what="result file")
        try:
            z = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError) as exc:
            raise InputError(f"{str(path)!r} is not a qprr result file (.npz): {exc}") from exc
        with z:
            files = set(z.files)
            if "meta" not in files:
                raise InputError(f"{str(path)!r} has no qprr metadata: not a result file of qprr >= 0.2 (format {FORMAT_VERSION})")
            try:
                meta = json.loads(str(z["meta"]))
            except (ValueError, TypeError) as exc:
                raise InputError(f"{str(path)!r}: corrupted metadata ({exc})") from exc
            version = meta.get("format_version")
            if version != FORMAT_VERSION:
                raise InputError(f"{str(path)!r} has format version {version!r}; this qprr reads version {FORMAT_VERSION}")
            missing = [k for k in ARRAYS if k not in files]
            if missing:
                raise InputError(f"{str(path)!r} lacks the arrays {missing}: truncated or not a result file")
            arrays = {k: z[k] for k in ARRAYS}
            series = {k: z[f"series_{k}"] for k in meta.get("series", []) if f"series_{k}" in files}
        _validate(arrays, meta, str(path))
        return cls(**arrays, scenario=str(meta["scenario"]), controller=str(meta["controller"]), dt=float(meta["dt"]),
                   integrator=str(meta["integrator"]), wall_time=float(meta["wall_time"]), status=meta["status"],
                   reason=str(meta["reason"]), seed=meta["seed"], control_period=float(meta["control_period"]),
                   platform=str(meta.get("platform", "")), names=tuple(meta.get("names", ())), series=series,
                   metrics={k: float(v) for k, v in meta.get("metrics", {}).items()})


def _validate(arrays: dict, meta: dict, source: str) -> None:
    """Shapes and types of a loaded result (raise InputError naming the array)."""
    t = arrays["t"]
    if t.ndim != 1 or t.dtype.kind != "f":
        raise ShapeError(f"{source}: t must be a 1-D float array, got shape {t.shape} dtype {t.dtype}")
    m = t.shape[0]
    n_xi = arrays["xi"].shape[1] if arrays["xi"].ndim == 2 else -1
    if n_xi < 6:
        raise ShapeError(f"{source}: xi must have shape ({m}, 6 + n_arm), got {arrays['xi'].shape}")
    for k in ARRAYS:
        a = arrays[k]
        want = 1 if k in ("t", "flags") else 2
        if a.ndim != want or a.shape[0] != m:
            raise ShapeError(f"{source}: {k} must be a {want}-D array of {m} rows like t, got shape {a.shape}")
        if (k != "flags" and a.dtype.kind != "f") or (k == "flags" and a.dtype.kind not in "iu"):
            raise InputError(f"{source}: {k} must be {'float' if k != 'flags' else 'integer'}, got dtype {a.dtype}")
    for k in ("xi_dot", "xi_d", "xi_dot_d", "u", "u_ext"):
        if arrays[k].shape != (m, n_xi):
            raise ShapeError(f"{source}: {k} must have shape ({m}, {n_xi}), got {arrays[k].shape}")
    for key in ("dt", "control_period", "wall_time"):
        v = meta.get(key)
        if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise InputError(f"{source}: metadata {key} must be a number >= 0, got {v!r}")
    if meta.get("status") not in {s.value for s in Status}:
        raise InputError(f"{source}: unknown status {meta.get('status')!r}; valid: {[s.value for s in Status]}")
    for key in ("scenario", "controller", "integrator", "reason"):
        if not isinstance(meta.get(key), str):
            raise InputError(f"{source}: metadata {key} must be a string, got {meta.get(key)!r}")
    if meta.get("seed") is not None and not (isinstance(meta["seed"], int) and not isinstance(meta["seed"], bool)):
        raise InputError(f"{source}: metadata seed must be an integer or null, got {meta['seed']!r}")
    metrics = meta.get("metrics", {})
    if not isinstance(metrics, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in metrics.values()):
        raise InputError(f"{source}: metadata metrics must map names to numbers, got {metrics!r}")
    names = meta.get("names", [])
    if not isinstance(names, list) or (names and len(names) != n_xi) or not all(isinstance(x, str) for x in names):
        raise InputError(f"{source}: metadata names must be the {n_xi} names of xi, got {names!r}")
