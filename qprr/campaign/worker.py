"""What runs inside a worker process: build the campaign's context once, then execute runs.

:func:`run_one` is the task every backend executes (local process pool or Dask worker).  Its
arguments are plain data (the specification as a dict, one :class:`~qprr.campaign.spec.Run`),
so nothing unpicklable ever crosses a process boundary.  The first task of a campaign in a
process builds a :class:`WorkerContext` - the platform (Pinocchio model, rotors), the target function,
a user callable's module - and keeps it for the later tasks of the same campaign (keyed by the
specification's fingerprint; a new campaign replaces it): the model is built once per worker.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import math
import sys
import time
import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, QprrError
from ..model import Platform
from ..sim import SimResult
from ..sim.mismatch import perturbed
from .metrics import RunStatus, metrics_of
from .spec import MODEL_PREFIX, CampaignSpec, Run, model_error


def load_platform(name: str | Mapping, files: Mapping[str, str] | None = None) -> Platform:
    """The platform of a campaign, ``name`` as :attr:`CampaignSpec.platform` gives it.

    A name: a registered one (:func:`qprr.load`) or a (2.1) designation (:func:`qprr.build`).  A
    table ``{urdf, rotors, ee_frame}``: :func:`qprr.from_urdf` on ``files``, the text of its URDF and
    rotor file (:meth:`CampaignSpec.platform_files`), so that a worker needs no copy of them.
    """
    from ..model import from_urdf
    from ..nomenclature import build
    from ..platforms import NAMES, load
    from .spec import toml_loads

    if isinstance(name, str):
        if files is not None:
            raise InputError(f"platform name {name!r} takes no files, got files for {sorted(files)}: files go with a table")
        return load(name) if name in NAMES else build(name)
    if not isinstance(name, Mapping) or not isinstance(files, Mapping) or set(files) != {"urdf", "rotors"}:
        raise InputError(
            f"name must be a platform name or a table {{urdf, rotors, ee_frame}} with files = {{urdf: text, "
            f"rotors: text}}, got name={name!r}, files={None if files is None else sorted(files)}"
        )
    platform = name
    rotors = toml_loads(files["rotors"], f"platform.rotors = {platform['rotors']!r}")
    try:
        return from_urdf(
            files["urdf"], rotors, ee_frame=platform.get("ee_frame"), provenance={"model": str(platform["urdf"]), "rotors": str(platform["rotors"])}
        )
    except QprrError as exc:  # the file's own error, prefixed with the specification's key
        raise InputError(
            f"platform = {{urdf = {platform['urdf']!r}, rotors = {platform['rotors']!r}"
            + (f", ee_frame = {platform['ee_frame']!r}" if "ee_frame" in platform else "")
            + f"}}: {exc}"
        ) from exc


def platform_of(spec: CampaignSpec) -> Platform:
    """The campaign's platform, built in this process (a platform table's files read and checked now)."""
    if not isinstance(spec, CampaignSpec):
        raise InputError(f"spec must be a CampaignSpec, got {type(spec).__name__}")
    return load_platform(spec.platform, spec.platform_files())


def xi_names_of(spec: CampaignSpec) -> tuple[str, ...]:
    """The coordinate names of the campaign's platform (the ``rmse_<var>`` columns)."""
    return platform_of(spec).xi_names


@dataclass
class TaskPayload:
    """What a task carries: the specification (as data), its folder, a user file's source text (or None), and the
    text of a platform table's URDF and rotor file (or None)."""

    spec: dict
    base_dir: str
    source: str | None = None
    fingerprint: str = ""
    platform_files: dict | None = None


def make_task_payload(spec: CampaignSpec) -> TaskPayload:
    """The task payload of ``spec``; a ``file.py:function`` callable travels as source text (remote workers need no copy)."""
    if not isinstance(spec, CampaignSpec):
        raise InputError(f"spec must be a CampaignSpec, got {type(spec).__name__}")
    source = None
    if spec.callable is not None:
        target, _ = spec.callable.rsplit(":", 1)
        if target.endswith(".py"):
            path = Path(target) if Path(target).is_absolute() else Path(spec.base_dir) / target
            if not path.is_file():
                raise InputError(f"callable {spec.callable!r}: file {str(path)!r} does not exist")
            source = path.read_text()
    return TaskPayload(spec.to_dict(), spec.base_dir, source, spec.fingerprint, spec.platform_files())


def _load_callable(spec: CampaignSpec, source: str | None) -> Callable:
    target, fname = spec.callable.rsplit(":", 1)
    if target.endswith(".py"):
        name = f"qprr_campaign_{spec.fingerprint}"
        module = sys.modules.get(name)
        if module is None:
            module = types.ModuleType(name)
            module.__file__ = target
            sys.modules[name] = module  # objects it defines pickle by reference
            exec(compile(source, target, "exec"), module.__dict__)
    else:
        try:
            module = importlib.import_module(target)
        except ImportError as exc:
            raise InputError(f"callable {spec.callable!r}: cannot import {target!r}: {exc}") from exc
    fn = getattr(module, fname, None)
    if not callable(fn):
        raise InputError(f"callable {spec.callable!r}: {target!r} has no function {fname!r}")
    return fn


@dataclass
class WorkerContext:
    """Per-worker state of one campaign: the specification, its platform, the column names, the target."""

    spec: CampaignSpec
    names: tuple[str, ...]
    target: Callable[[Run], SimResult]


def build_context(payload: TaskPayload) -> WorkerContext:
    """Build the platform and the target of a campaign (once per worker)."""
    spec = CampaignSpec.from_mapping(payload.spec, base_dir=payload.base_dir)
    platform = load_platform(spec.platform, payload.platform_files)
    if spec.scenario is not None:
        from ..scenarios import SCENARIOS

        sc = SCENARIOS[spec.scenario]

        def target(run: Run) -> SimResult:
            options = {k: v for k, v in run.params.items() if k != "controller" and not k.startswith(MODEL_PREFIX)}
            if "seed" in sc.options:
                options["seed"] = run.seed
            err = model_error(run.params)
            plant = None if err is None or err.is_nominal else perturbed(platform, err)
            extra = {} if plant is None else {"plant": plant}
            return sc.run(platform=platform, controller=run.params.get("controller"), **extra, **options)
    else:
        fn = _load_callable(spec, payload.source)
        try:
            takes_platform = len(inspect.signature(fn).parameters) >= 3
        except (TypeError, ValueError):
            takes_platform = False

        def target(run: Run) -> SimResult:
            if takes_platform:  # (params, seed, platform): the platform built once per worker
                return fn(dict(run.params), run.seed, platform)
            return fn(dict(run.params), run.seed)

    return WorkerContext(spec, platform.xi_names, target)


def execute(ctx: WorkerContext, run: Run) -> dict[str, object]:
    """Run ``run`` and return its row (``run``, ``seed``, parameters, metrics); failures become rows too."""
    spec = ctx.spec
    t0 = time.perf_counter()
    result, status, reason = None, None, ""
    try:
        result = ctx.target(run)
        if not isinstance(result, SimResult):
            result, status, reason = None, RunStatus.ERROR, f"the target returned {type(result).__name__}, not a SimResult"
        elif tuple(result.names) != tuple(ctx.names):  # its errors would be lost in the campaign's columns
            result, status, reason = (
                None,
                RunStatus.ERROR,
                (
                    f"the target flew {result.platform or 'a platform'} (coordinates {', '.join(result.names)}), not the "
                    f"campaign's platform = {spec.platform_label!r} (coordinates {', '.join(ctx.names)}): set platform in the "
                    f"specification to the one the target flies, and take it as the target's third argument"
                ),
            )
    except QprrError as err:
        result = err.result
        status = None if result is not None else RunStatus.FAILED
        reason = f"{type(err).__name__}: {err}"
    except Exception as err:  # a bug in a target must not lose the campaign: recorded, then visible in the table
        status, reason = RunStatus.ERROR, f"{type(err).__name__}: {err}"
    wall = time.perf_counter() - t0
    row: dict[str, object] = {"run": run.index, "seed": run.seed}
    row.update(params_row(spec, run.params))
    row.update(metrics_of(result, spec.metrics, ctx.names, spec.extras, status=status, reason=reason, wall_time=wall, success=spec.success))
    return row


def params_row(spec: CampaignSpec, params: Mapping[str, object]) -> dict[str, object]:
    """The parameter columns of a run (see :func:`param_columns`)."""
    out = {}
    for k in param_columns(spec):
        if k == "controller" and "controller" not in params:
            out[k] = default_controller(spec)
        else:
            out[k] = params[k]
    return out


def default_controller(spec: CampaignSpec) -> str:
    """The controller a scenario's runs fly when the campaign names none: the scenario's first, or the one its mission
    file names (:func:`qprr.scenarios.missions.flown_controller`)."""
    from ..scenarios.missions import flown_controller

    return flown_controller(spec.scenario, None, dict(spec.options)) if spec.scenario is not None else ""


def param_columns(spec: CampaignSpec) -> tuple[str, ...]:
    """``controller`` (scenarios, or callables given one), then the parameters that vary."""
    has_ctrl = spec.scenario is not None or "controller" in spec.parameter_names
    return (("controller",) if has_ctrl else ()) + tuple(k for k in spec.varying if k != "controller")


_CONTEXT: dict[str, WorkerContext] = {}
"""This process's context, keyed by the specification's fingerprint (one campaign at a time).
Only worker processes fill it; it holds the model so that it is built once per worker."""


def run_one(payload: TaskPayload, run: Run) -> dict[str, object]:
    """The task of every backend: the row of ``run`` (context built on the first call in this process)."""
    ctx = _CONTEXT.get(payload.fingerprint)
    if ctx is None:
        _CONTEXT.clear()
        ctx = _CONTEXT[payload.fingerprint] = build_context(payload)
    return execute(ctx, run)


def nan_row(spec: CampaignSpec, names, run: Run, status: RunStatus, reason: str) -> dict[str, object]:
    """The row of a run whose task raised outside the target (``error``, re-run on resume); runs lost with a worker get none."""
    row: dict[str, object] = {"run": run.index, "seed": run.seed}
    row.update(params_row(spec, run.params))
    row.update(metrics_of(None, spec.metrics, names, spec.extras, status=status, reason=reason, wall_time=math.nan))
    return row


# the worker's entry points (the other functions are the runner's helpers on a validated specification)
__all__ = ["WorkerContext", "TaskPayload", "build_context", "execute", "load_platform", "make_task_payload", "run_one"]
