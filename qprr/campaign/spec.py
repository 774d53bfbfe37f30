"""A campaign specification: what to run, over which parameters, with which seeds (TOML / JSON / dict).

A :class:`CampaignSpec` names a *target* and the parameters of its runs:

* ``scenario``: a registered scenario (:data:`qprr.scenarios.SCENARIOS`), run as
  ``run(name, controller, platform=..., plant=..., **options)``; or ``callable``: a function
  ``(params, seed) -> SimResult`` given as ``"package.module:function"`` or
  ``"path/to/file.py:function"`` (a relative path is taken from the specification's folder);
* ``platform``: a name (:data:`qprr.platforms.NAMES` or a (2.1) designation such as ``"HEX-RRR"``,
  built by :func:`qprr.build`) or a table ``{urdf = FILE, rotors = FILE.toml, ee_frame = NAME}``
  (:data:`PLATFORM_KEYS`; paths relative to the specification's folder; the files' SHA-256 join
  the table, so a changed file is a changed specification and fingerprint); the ``rmse_<var>``
  columns are named from its coordinates;
* ``options``: fixed parameters of every run; ``grid``: lists of values, every combination is
  run (the last name varies fastest); ``random``: :class:`Distribution` s, drawn anew for each
  run; ``samples``: runs per grid point (each with its own draws and seed); ``paired = true``:
  the k-th sample of every grid point gets the same draws and seed (common random numbers:
  controllers or gains are compared on identical missions, errors and noise);
* parameter names: ``controller``; ``model.mass``, ``model.arm_mass``, ``model.inertia``,
  ``model.kappa``, ``model.f_max``, ``model.payload`` (:class:`qprr.sim.mismatch.ModelError`:
  the plant is a perturbed copy of the platform, the controller keeps the nominal model);
  ``seed`` (overrides the derived seed); any other name is a scenario option (or a parameter of
  the callable);
* ``metrics`` kept per run (names of the registry :data:`qprr.campaign.metrics.METRICS`, default
  :data:`qprr.campaign.metrics.DEFAULT_METRICS`; a plug-in's metric too) and ``extras`` (names of
  ``SimResult.metrics`` entries to keep as columns); ``success``: upper bounds on metric
  columns (e.g. ``rmse_position = 0.5``) that a completed run must meet to count as a success.

Reproducibility: run ``i`` draws its random parameters from ``SeedSequence(seed, spawn_key=(i, 0))``
and gets the simulation seed ``SeedSequence(seed, spawn_key=(i, 1))`` (``i`` modulo ``samples``
when paired): the table depends on the
specification only, never on the number of workers or the order in which runs finish, and
adding runs does not change the earlier ones.

Example (TOML)::

    name = "idc-payload"
    scenario = "static-idc"
    seed = 7
    samples = 3
    [options]
    duration = 30.0
    [grid]
    controller = ["idc", "dsid", "mfc"]
    "model.payload" = [0.0, 0.1, 0.2]
    [random]
    "model.mass" = { dist = "uniform", low = 0.9, high = 1.1 }
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from ..errors import InputError, MissingDependencyError, UnknownNameError
from ..platforms import DEFAULT_PLATFORM
from ..sim.mismatch import ModelError
from ..validation import as_file
from .metrics import DEFAULT_METRICS, METRICS, is_nonnegative

MODEL_PREFIX = "model."
MODEL_PARAMS = tuple(MODEL_PREFIX + f.name for f in fields(ModelError))
"""Parameters that perturb the plant (:class:`qprr.sim.mismatch.ModelError` fields)."""


DISTRIBUTIONS = ("uniform", "loguniform", "normal", "choice", "integers")

_SPEC_KEYS = (
    "name",
    "scenario",
    "callable",
    "platform",
    "seed",
    "samples",
    "paired",
    "options",
    "grid",
    "random",
    "metrics",
    "extras",
    "success",
    "description",
)


def _number(x, what: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise InputError(f"{what} must be a finite number, got {x!r}")
    return float(x)


@dataclass(frozen=True)
class Distribution:
    """A random parameter.

    ``kind``: "uniform" (``low``, ``high``), "loguniform" (``low`` > 0, ``high``), "normal"
    (``mean``, ``std``, optionally clipped to [``low``, ``high``]), "choice" (``values``,
    equally likely) or "integers" (``low`` to ``high`` inclusive).
    """

    kind: str
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = None
    values: tuple = ()

    def __post_init__(self) -> None:
        k = self.kind
        if k not in DISTRIBUTIONS:
            raise UnknownNameError("distribution", k, DISTRIBUTIONS)
        if k in ("uniform", "loguniform", "integers"):
            if self.low is None or self.high is None:
                raise InputError(f"a {k} distribution needs low and high, got low={self.low!r}, high={self.high!r}")
            lo, hi = _number(self.low, f"{k} low"), _number(self.high, f"{k} high")
            if not lo <= hi:
                raise InputError(f"{k} distribution: low must be <= high, got low={lo!r}, high={hi!r}")
            if k == "loguniform" and lo <= 0:
                raise InputError(f"loguniform distribution: low must be > 0, got {lo!r}")
            if k == "integers" and (lo != int(lo) or hi != int(hi)):
                raise InputError(f"integers distribution: low and high must be integers, got {lo!r}, {hi!r}")
        if k == "normal":
            if self.mean is None or self.std is None:
                raise InputError(f"a normal distribution needs mean and std, got mean={self.mean!r}, std={self.std!r}")
            _number(self.mean, "normal mean")
            if not _number(self.std, "normal std") >= 0:
                raise InputError(f"normal distribution: std must be >= 0, got {self.std!r}")
            if self.low is not None and self.high is not None and not _number(self.low, "low") <= _number(self.high, "high"):
                raise InputError(f"normal distribution: low must be <= high, got {self.low!r}, {self.high!r}")
        if k == "choice":
            if not self.values:
                raise InputError("a choice distribution needs a non-empty list of values")
            object.__setattr__(self, "values", tuple(self.values))

    @classmethod
    def from_mapping(cls, d: Mapping, name: str) -> Distribution:
        """``{dist = "uniform", low = 0.9, high = 1.1}`` (TOML) or the same dict."""
        if not isinstance(d, Mapping):
            raise InputError(f'random parameter {name!r} must be a table such as {{dist = "uniform", low = 0, high = 1}}, got {d!r}')
        d = dict(d)
        if "dist" not in d:
            raise InputError(f"random parameter {name!r} needs dist = one of {', '.join(DISTRIBUTIONS)}")
        kind = d.pop("dist")
        allowed = {"low", "high", "mean", "std", "values"}
        for key in d:
            if key not in allowed:
                raise UnknownNameError(f"field of random parameter {name!r}", key, sorted(allowed))
        if "values" in d:
            d["values"] = tuple(d["values"])
        return cls(kind, **d)

    def to_dict(self) -> dict:
        out = {"dist": self.kind}
        for key in ("low", "high", "mean", "std"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        if self.values:
            out["values"] = list(self.values)
        return out

    def sample(self, rng: np.random.Generator):
        """One draw (a Python float, int or choice value)."""
        if not isinstance(rng, np.random.Generator):
            raise InputError(f"rng must be a numpy.random.Generator (np.random.default_rng(seed)), got {type(rng).__name__}")
        k = self.kind
        if k == "uniform":
            return float(rng.uniform(self.low, self.high))
        if k == "loguniform":
            return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))
        if k == "normal":
            x = float(rng.normal(self.mean, self.std))
            lo = -math.inf if self.low is None else self.low
            hi = math.inf if self.high is None else self.high
            return min(max(x, lo), hi)
        if k == "integers":
            return int(rng.integers(int(self.low), int(self.high), endpoint=True))
        return self.values[int(rng.integers(len(self.values)))]


@dataclass(frozen=True)
class Run:
    """One run of a campaign: its index, its parameters (name -> value) and its simulation seed."""

    index: int
    params: Mapping[str, object]
    seed: int


def _grid_values(name: str, value) -> tuple:
    if isinstance(value, Mapping):
        keys = set(value)
        if keys != {"start", "stop", "num"}:
            raise InputError(f"grid parameter {name!r}: a list of values or {{start, stop, num}}, got keys {sorted(keys)}")
        num = value["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise InputError(f"grid parameter {name!r}: num must be an integer >= 1, got {num!r}")
        return tuple(float(x) for x in np.linspace(_number(value["start"], "start"), _number(value["stop"], "stop"), num))
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise InputError(f"grid parameter {name!r} must be a list of values, got {value!r}")
    values = tuple(value)
    if not values:
        raise InputError(f"grid parameter {name!r} has no values")
    return values


PLATFORM_KEYS = ("urdf", "rotors", "ee_frame", "sha256")
"""Keys of a platform table: ``urdf`` and ``rotors`` (files, relative to the specification's folder), ``ee_frame``
(optional), ``sha256`` (the files' content hashes: computed when the files are read; given, the files must match)."""

_TABLE_EXAMPLE = 'platform = { urdf = "robot.urdf", rotors = "robot.rotors.toml", ee_frame = "ee" }'


def platform_names() -> tuple[str, ...]:
    """The platform names a campaign accepts besides (2.1) designations: :data:`qprr.platforms.NAMES`, each once."""
    from ..platforms import NAMES

    return tuple(dict.fromkeys(NAMES))


def _check_platform_name(name: str) -> str:
    """A campaign's platform by name: a registered platform (:data:`qprr.platforms.NAMES`) or a (2.1) designation."""
    from ..errors import QprrError
    from ..nomenclature import parse

    valid = platform_names()
    if name in valid:
        return name
    try:
        parse(name)
    except QprrError:
        raise UnknownNameError(
            "platform", name, (*valid, "or a (2.1) designation such as 'HEX-RRR'", f"or a URDF with its rotor file: {_TABLE_EXAMPLE}")
        ) from None
    return name


def _platform_file(table: Mapping, key: str, suffixes: tuple[str, ...], base_dir: str) -> Path:
    value = table.get(key)
    if not isinstance(value, str) or not value:
        raise InputError(f"platform.{key} must be a file name (a string), got {value!r}: {_TABLE_EXAMPLE}")
    if suffixes and not value.lower().endswith(suffixes):
        raise InputError(f"platform.{key} = {value!r} must be a {' or '.join(suffixes)} file: {_TABLE_EXAMPLE}")
    return Path(value) if Path(value).is_absolute() else Path(base_dir) / value


def _read_platform_file(table: Mapping, key: str, base_dir: str) -> bytes:
    path = _platform_file(table, key, (), base_dir)
    if not path.is_file():
        raise InputError(
            f"platform.{key} = {table[key]!r}: no file {str(path)!r} (paths are relative to the "
            f"specification's folder {base_dir!r}): give the file's path"
        )
    return path.read_bytes()


def _check_platform_table(table: Mapping, base_dir: str) -> dict:
    """A campaign's platform given by files (see :data:`PLATFORM_KEYS`), normalised with its ``sha256`` table."""
    for k in table:
        if k not in PLATFORM_KEYS:
            raise UnknownNameError("key of the platform table", k, PLATFORM_KEYS)
    out = {}
    for key, suffixes in (("urdf", (".urdf", ".xml")), ("rotors", (".toml",))):
        _platform_file(table, key, suffixes, base_dir)
        out[key] = table[key]
    if "ee_frame" in table:
        if not isinstance(table["ee_frame"], str) or not table["ee_frame"]:
            raise InputError(
                f"platform.ee_frame must be a frame name of the URDF (a string), got {table['ee_frame']!r}; "
                f"leave it out for the last frame of the arm"
            )
        out["ee_frame"] = table["ee_frame"]
    digests = table.get("sha256")
    if digests is None:  # read the files now: their content is part of the specification
        digests = {}
        for key in ("urdf", "rotors"):
            digests[key] = hashlib.sha256(_read_platform_file(table, key, base_dir)).hexdigest()
    if (
        not isinstance(digests, Mapping)
        or set(digests) != {"urdf", "rotors"}
        or not all(isinstance(v, str) and len(v) == 64 and all(c in "0123456789abcdef" for c in v) for v in digests.values())
    ):
        raise InputError(
            f"platform.sha256 must be {{urdf = HEX, rotors = HEX}} (64 hex digits each, the files' SHA-256), "
            f"got {digests!r}: leave it out and it is computed from the files"
        )
    out["sha256"] = {"urdf": digests["urdf"], "rotors": digests["rotors"]}
    return out


def _check_platform(value, base_dir: str) -> str | dict:
    if isinstance(value, str):
        return _check_platform_name(value)
    if isinstance(value, Mapping):
        return _check_platform_table(value, base_dir)
    raise InputError(
        f"platform must be a name (one of {', '.join(platform_names())} or a (2.1) designation such as "
        f"'HEX-RRR') or a table {_TABLE_EXAMPLE}, got {value!r}"
    )


def toml_loads(text: str, what: str) -> dict:
    """Parse TOML ``text`` (``what`` names it in errors); Python 3.10 needs tomli."""
    try:
        import tomllib
    except ImportError:  # Python 3.10
        try:
            import tomli as tomllib
        except ImportError as exc:
            raise MissingDependencyError("tomli", "reading TOML files on Python 3.10", "pip install tomli") from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{what}: invalid TOML: {exc}") from exc


@dataclass(frozen=True)
class CampaignSpec:
    """A campaign: a target, fixed/grid/random parameters, seeds and metrics (module docstring)."""

    name: str
    scenario: str | None = None
    callable: str | None = None
    platform: str | Mapping[str, object] = DEFAULT_PLATFORM
    seed: int = 0
    samples: int = 1
    options: Mapping[str, object] = field(default_factory=dict)
    grid: Mapping[str, tuple] = field(default_factory=dict)
    random: Mapping[str, Distribution] = field(default_factory=dict)
    metrics: tuple[str, ...] = DEFAULT_METRICS
    extras: tuple[str, ...] = ()
    success: Mapping[str, float] = field(default_factory=dict)
    paired: bool = False
    description: str = ""
    base_dir: str = "."

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or any(c in self.name for c in "/\\"):
            raise InputError(f"campaign name must be a non-empty string without slashes, got {self.name!r}")
        if (self.scenario is None) == (self.callable is None):
            raise InputError('a campaign needs exactly one target: scenario = NAME or callable = "module:function"')
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise InputError(f"seed must be an integer >= 0, got {self.seed!r}")
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 1:
            raise InputError(f"samples must be an integer >= 1, got {self.samples!r}")
        if not isinstance(self.paired, bool):
            raise InputError(f"paired must be true or false, got {self.paired!r}")
        if not isinstance(self.base_dir, (str, Path)):
            raise InputError(f"base_dir must be a folder (a string), got {self.base_dir!r}")
        object.__setattr__(self, "base_dir", str(self.base_dir))
        object.__setattr__(self, "platform", _check_platform(self.platform, self.base_dir))
        for where in ("options", "grid", "random", "success"):
            if not isinstance(getattr(self, where), Mapping):
                raise InputError(f"{where} must be a table (mapping) of parameter = value, got {getattr(self, where)!r}")
        for where in ("metrics", "extras"):
            if isinstance(getattr(self, where), str) or not isinstance(getattr(self, where), (list, tuple)):
                raise InputError(f"{where} must be a list of names, got {getattr(self, where)!r}")
        object.__setattr__(self, "options", dict(self.options))
        object.__setattr__(self, "grid", {k: _grid_values(k, v) for k, v in self.grid.items()})
        rnd = {k: v if isinstance(v, Distribution) else Distribution.from_mapping(v, k) for k, v in self.random.items()}
        object.__setattr__(self, "random", rnd)
        object.__setattr__(self, "metrics", tuple(self.metrics))
        object.__setattr__(self, "extras", tuple(self.extras))
        for m in self.metrics:
            if m not in METRICS:
                raise UnknownNameError("metric", m, tuple(METRICS))
        if not isinstance(self.success, Mapping):
            raise InputError(f"[success] must be a table metric = upper bound, got {self.success!r}")
        object.__setattr__(self, "success", {k: _number(v, f"success bound of {k!r}") for k, v in self.success.items()})
        for k, bound in self.success.items():
            if bound < 0 and is_nonnegative(k):
                raise InputError(
                    f"[success] {k} = {bound!r}: no run can meet it ({k} is >= 0 for every run, a success needs {k} <= the bound): give a bound >= 0"
                )
        seen: dict[str, str] = {}
        for where in ("options", "grid", "random"):
            for k in getattr(self, where):
                if not isinstance(k, str) or not k:
                    raise InputError(f"parameter names must be non-empty strings, got {k!r} in [{where}]")
                if k in seen:
                    raise InputError(f"parameter {k!r} is given twice: in [{seen[k]}] and in [{where}]")
                seen[k] = where
                if k.startswith(MODEL_PREFIX) and k not in MODEL_PARAMS:
                    raise UnknownNameError("model-error parameter", k, MODEL_PARAMS)
        if self.scenario is not None:
            self._check_scenario()
            self._embed_option_files()
        elif not isinstance(self.callable, str) or ":" not in self.callable:
            raise InputError(f'callable must be "package.module:function" or "file.py:function", got {self.callable!r}')
        # every model-error combination must be valid (fails here, not in a worker)
        for k, values in self.grid.items():
            if k.startswith(MODEL_PREFIX):
                for v in values:
                    ModelError(**{k[len(MODEL_PREFIX) :]: v})

    def _check_scenario(self) -> None:
        from ..scenarios import SCENARIOS

        sc = SCENARIOS[self.scenario]  # UnknownNameError lists the scenarios
        if self.platform != DEFAULT_PLATFORM and sc.platforms is not None and self.platform not in sc.platforms:
            anywhere = ", ".join(n for n, x in SCENARIOS.items() if x.platforms is None)
            raise InputError(
                f"scenario {sc.name!r} runs on {', '.join(sc.platforms)}, not on platform = {self.platform_label!r}: "
                f"choose a scenario for any platform ({anywhere}) or one of its platforms"
            )
        for k in self.parameter_names:
            if k in ("controller", "seed") or k.startswith(MODEL_PREFIX):
                continue
            if k not in sc.options:
                raise UnknownNameError(f"option of scenario {sc.name!r}", k, ("controller", "seed", *MODEL_PARAMS, *sc.options))
        if any(k.startswith(MODEL_PREFIX) for k in self.parameter_names) and not sc.takes_plant:
            raise InputError(
                f"scenario {sc.name!r} cannot fly a perturbed plant: model.* parameters need one of "
                f"{', '.join(n for n, s in SCENARIOS.items() if s.takes_plant)}"
            )
        if "seed" in self.parameter_names and "seed" not in sc.options:
            raise InputError(f"scenario {sc.name!r} takes no seed")
        for c in self._values("controller"):
            if c not in sc.controller_names():
                raise UnknownNameError(f"controller of scenario {sc.name!r}", c, sc.controller_names())

    def _embed_option_files(self) -> None:
        """Options that name a TOML file (``Option.file``) replaced by the file's content, read relative to the
        specification's folder; a missing or unreadable file is refused here, not in a worker."""
        from ..scenarios import SCENARIOS

        sc = SCENARIOS[self.scenario]
        options = dict(self.options)
        for k, value in self.options.items():
            if k in sc.options and sc.options[k].file and isinstance(value, str) and value:
                path = Path(value) if Path(value).is_absolute() else Path(self.base_dir) / value
                if not path.is_file():
                    raise InputError(
                        f"options.{k} = {value!r}: no file {str(path)!r} (paths are relative to the specification's folder {self.base_dir!r})"
                    )
                options[k] = toml_loads(path.read_text(), f"options.{k} = {value!r}")
        object.__setattr__(self, "options", options)

    def _values(self, name: str) -> tuple:
        if name in self.options:
            return (self.options[name],)
        if name in self.grid:
            return self.grid[name]
        if name in self.random and self.random[name].kind == "choice":
            return self.random[name].values
        return ()

    # ------------------------------------------------------------------ platform
    @property
    def platform_label(self) -> str:
        """The platform as the specification gives it: its name, or ``urdf FILE, rotors FILE[, ee_frame F]``."""
        if isinstance(self.platform, str):
            return self.platform
        return ", ".join(f"{k} {self.platform[k]}" for k in ("urdf", "rotors", "ee_frame") if k in self.platform)

    def platform_files(self) -> dict[str, str] | None:
        """The text of a platform table's files (``urdf``, ``rotors``), checked against its ``sha256``; None for a name.

        Raises :class:`InputError` naming the file when it is missing or its content changed since
        the specification was read (a changed URDF is a changed specification)."""
        if isinstance(self.platform, str):
            return None
        out = {}
        for key in ("urdf", "rotors"):
            data = _read_platform_file(self.platform, key, self.base_dir)
            digest = hashlib.sha256(data).hexdigest()
            if digest != self.platform["sha256"][key]:
                raise InputError(
                    f"platform.{key} = {self.platform[key]!r}: the file changed (sha256 {digest[:12]}..., "
                    f"the specification's {self.platform['sha256'][key][:12]}...): load the specification again "
                    f"(a new fingerprint: a new campaign) or restore the file"
                )
            try:
                out[key] = data.decode()
            except UnicodeDecodeError as exc:
                raise InputError(f"platform.{key} = {self.platform[key]!r} is not a text file: {exc}") from exc
        return out

    # ------------------------------------------------------------------ parameters and runs
    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Every parameter given (fixed, grid, random)."""
        return (*self.options, *self.grid, *self.random)

    @property
    def varying(self) -> tuple[str, ...]:
        """The parameters that change between runs (grid then random), the columns of the results table."""
        return (*self.grid, *self.random)

    @property
    def n_points(self) -> int:
        return math.prod(len(v) for v in self.grid.values())

    @property
    def n_runs(self) -> int:
        return self.n_points * self.samples

    def run(self, index: int) -> Run:
        """Run ``index`` (0 <= index < n_runs): grid point ``index // samples``, its random draws and seed."""
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < self.n_runs:
            raise InputError(f"run index must be an integer in [0, {self.n_runs}), got {index!r}")
        index = int(index)
        point = index // self.samples
        chosen = {}
        for k in reversed(list(self.grid)):  # the last grid name varies fastest
            point, j = divmod(point, len(self.grid[k]))
            chosen[k] = self.grid[k][j]
        params: dict[str, object] = {**dict(self.options), **{k: chosen[k] for k in self.grid}}
        key = index % self.samples if self.paired else index  # paired: the k-th sample of every grid point alike
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(key, 0)))
        for k, d in self.random.items():
            params[k] = d.sample(rng)
        derived = int(np.random.SeedSequence(self.seed, spawn_key=(key, 1)).generate_state(1, dtype=np.uint32)[0])
        seed = params["seed"] if "seed" in params else derived
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise InputError(f"run {index}: seed must be an integer, got {seed!r}")
        return Run(index, params, int(seed))

    def runs(self) -> Iterator[Run]:
        """Every run, in index order."""
        return (self.run(i) for i in range(self.n_runs))

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict:
        """The specification as plain data (TOML/JSON-able); :meth:`from_mapping` reads it back."""
        out = {"name": self.name}
        out["scenario" if self.scenario is not None else "callable"] = self.scenario if self.scenario is not None else self.callable
        platform = self.platform if isinstance(self.platform, str) else {**self.platform, "sha256": dict(self.platform["sha256"])}
        out.update(
            platform=platform,
            seed=self.seed,
            samples=self.samples,
            options=dict(self.options),
            grid={k: list(v) for k, v in self.grid.items()},
            random={k: d.to_dict() for k, d in self.random.items()},
            metrics=list(self.metrics),
            extras=list(self.extras),
            success=dict(self.success),
        )
        if self.paired:
            out["paired"] = True
        if self.description:
            out["description"] = self.description
        return out

    @property
    def fingerprint(self) -> str:
        """SHA-256 (16 hex digits) of :meth:`to_dict`: results files remember the specification they belong to."""
        return hashlib.sha256(json.dumps(self.to_dict(), sort_keys=True, default=str).encode()).hexdigest()[:16]

    @classmethod
    def from_mapping(cls, d: Mapping, base_dir: str | Path = ".") -> CampaignSpec:
        """From a dict (what TOML/JSON give); unknown keys raise :class:`UnknownNameError`."""
        if not isinstance(d, Mapping):
            raise InputError(f"a campaign specification is a table, got {type(d).__name__}")
        for k in d:
            if k not in _SPEC_KEYS:
                raise UnknownNameError("campaign specification key", k, _SPEC_KEYS)
        if "name" not in d:
            raise InputError("a campaign specification needs a name")
        kw = dict(d)
        for key in ("options", "grid", "random"):
            if key in kw and not isinstance(kw[key], Mapping):
                raise InputError(f"[{key}] must be a table of parameters, got {kw[key]!r}")
        for key in ("metrics", "extras"):
            if key in kw and (isinstance(kw[key], str) or not isinstance(kw[key], (list, tuple))):
                raise InputError(f"{key} must be a list of names, got {kw[key]!r}")
        return cls(**kw, base_dir=str(base_dir))

    @classmethod
    def load(cls, path: str | Path) -> CampaignSpec:
        """Read a ``.toml`` or ``.json`` specification."""
        path = as_file(path, "path", what="campaign specification")
        try:
            text = path.read_text()
        except UnicodeDecodeError as exc:
            raise InputError(f"{str(path)!r} is not a text file (a .toml or .json specification): {exc}") from exc
        if path.suffix == ".toml":
            data = toml_loads(text, repr(str(path)))
        elif path.suffix == ".json":
            try:
                data = json.loads(text)
            except json.JSONDecodeError as exc:
                raise InputError(f"{str(path)!r}: invalid JSON: {exc}") from exc
        else:
            raise InputError(f"campaign specifications end in .toml or .json, got {str(path)!r}")
        if not data:
            raise InputError(f"{str(path)!r} is empty: a campaign specification needs a name and a target (scenario or callable)")
        return cls.from_mapping(data, base_dir=path.resolve().parent)


def model_error(params: Mapping[str, object]) -> ModelError | None:
    """The :class:`ModelError` of a run's ``model.*`` parameters (None if it has none)."""
    if not isinstance(params, Mapping):
        raise InputError(f"params must be a mapping of parameter name -> value, got {type(params).__name__}")
    kw = {k[len(MODEL_PREFIX) :]: v for k, v in params.items() if k.startswith(MODEL_PREFIX)}
    return ModelError(**kw) if kw else None
