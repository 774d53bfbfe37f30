"""Registries the core owns and plug-ins fill: one per kind of named thing.

The core (everything outside :mod:`qprr.thesis` and the command-line front ends) never imports a
plug-in.  A plug-in is a package that declares a function in the ``qprr.plugins`` entry-point group
of its distribution's metadata, e.g. in ``pyproject.toml``::

    [project.entry-points."qprr.plugins"]
    thesis = "qprr.thesis:register"

and whose function registers its entries here.  The thesis's Q-PRR (``qprr.load("q-prr")``), its
scenarios (``qprr simulate static-idc``), comparisons (``qprr compare``) and checks (``qprr check``)
arrive this way.  Plug-ins are loaded lazily and once: the first time a registry is listed, or asked
for a name it does not hold (:func:`load_plugins`).  A plug-in that fails to import raises; it is
never skipped.

==========================  ==================================================================
registry                    name -> value
==========================  ==================================================================
``qprr.platforms.PLATFORMS``       platform name -> loader ``(**options) -> Platform``
``qprr.platforms.ROTOR_DYNAMICS``  platform name -> ``(**overrides) -> RotorDynamics``
:data:`SCENARIOS`           scenario name -> :class:`qprr.scenarios.Scenario`
:data:`PARAMETER_SETS`      "<platform>:<variant>" -> ``() -> parameters`` of a named platform
:data:`GAIN_TABLES`         "<platform>:<table>" -> ``() -> gains`` (:mod:`qprr.control` dataclasses)
:data:`COMPARISONS`         comparison name -> ``(names, *, duration, plot_dir, progress) -> reports``
:data:`CHECKS`              check-suite name -> ``(verbose) -> exit code`` (``qprr check`` runs them all)
:data:`MAP_REFERENCES`      provider name -> ``(map_name, platform, result) -> MapReference | None``
:data:`COMMANDS`            command-group name -> ``register_cli(subparsers)`` (``qprr`` front end), from the
                            entry points ``qprr.commands`` (the thesis: ``qprr urdf``)
==========================  ==================================================================

Beside the modules that own their kind (each a :class:`Registry` with a documented default, docs/extending.md):
``qprr.control.CONTROLLERS`` (controllers with their gain derivation, default ``idc``),
``qprr.ik.IK_METHODS`` (default ``qp``), ``qprr.sim.INTEGRATORS`` (default ``midpoint``),
``qprr.campaign.METRICS`` (campaign metrics, default ``rmse``), ``qprr.design.DESIGN_METRICS`` (design metrics,
default ``hover_volume``); ``qprr.platforms.PLATFORMS`` has the default ``qprr.platforms.DEFAULT_PLATFORM``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from importlib import metadata
from typing import Generic, TypeVar

from .errors import InputError, UnknownNameError

PLUGIN_GROUP = "qprr.plugins"
"""Entry-point group of the plug-ins: each entry names a function ``register() -> None``."""
COMMAND_GROUP = "qprr.commands"
"""Entry-point group of the plug-ins' command groups (:data:`COMMANDS`): each entry names ``register_cli(subparsers)``."""

T = TypeVar("T")

_LOADED: dict[str, str] = {}
"""Plug-ins loaded so far: entry-point name -> its ``module:function``."""
_PENDING: list | None = None
"""Entry points of :data:`PLUGIN_GROUP` not loaded yet (None: the installed metadata not read yet; it is read once)."""


def load_plugins() -> tuple[str, ...]:
    """Load every plug-in of :data:`PLUGIN_GROUP` not loaded yet (each once); return the names of those loaded.

    The installed metadata is read on the first call only.  An import error inside a plug-in propagates
    and the plug-in stays pending: a broken plug-in fails at every lookup, it never reads as a missing name."""
    global _PENDING
    if _PENDING is None:
        _PENDING = list(metadata.entry_points(group=PLUGIN_GROUP))
    while _PENDING:
        ep = _PENDING.pop(0)
        if ep.name in _LOADED:
            continue
        _LOADED[ep.name] = ep.value  # marked first: a plug-in's register() may read a registry
        try:
            ep.load()()
        except BaseException:
            del _LOADED[ep.name]
            _PENDING.insert(0, ep)
            raise
    return tuple(_LOADED)


class Registry(Mapping[str, T], Generic[T]):
    """Named entries of one ``kind`` (used in error messages); read like a dict.

    :meth:`register` adds one entry; :meth:`register_source` a batch computed on the first read
    (so a plug-in can offer entries whose modules are costly to import without importing them).
    Looking up a name the registry does not hold, or listing it, first loads the plug-ins
    (:func:`load_plugins`); a name still unknown raises :class:`~qprr.errors.UnknownNameError`
    listing the valid ones."""

    def __init__(self, kind: str, group: str | None = None, *, default: str | None = None, check: Callable[[str, T], None] | None = None) -> None:
        self.kind = kind
        self.group = group
        """An entry-point group whose entries are this registry's values (name -> the object it names), or None."""
        self.default = default
        """The name a caller gets without naming one (listed first), or None."""
        self.check = check
        """``check(name, value)`` run on every entry before it is added: raises :class:`~qprr.errors.InputError` saying
        why a value is refused (a controller without its gain derivation...); None: any value."""
        self._entries: dict[str, T] = {}
        self._sources: list[Callable[[], Iterable[tuple[str, T]]]] = []
        if group is not None:
            self._sources.append(self._entry_points)

    def _entry_points(self) -> Iterable[tuple[str, T]]:
        return [(ep.name, ep.load()) for ep in metadata.entry_points(group=self.group) if ep.name not in self._entries]

    def register(self, name: str, value: T) -> T:
        """Add ``value`` under ``name``; another value under a taken name raises InputError."""
        if not isinstance(name, str) or not name:
            raise InputError(f"a {self.kind} name must be a non-empty string, got {name!r}")
        if name in self._entries and self._entries[name] is not value:
            raise InputError(f"{self.kind} {name!r} is already registered (by {self._entries[name]!r}): choose another name")
        if self.check is not None:
            self.check(name, value)
        self._entries[name] = value
        return value

    def register_source(self, source: Callable[[], Iterable[tuple[str, T]]]) -> None:
        """Add the ``(name, value)`` pairs ``source()`` yields, when the registry is first read."""
        if not callable(source):
            raise InputError(f"a {self.kind} source must be callable, got {type(source).__name__}")
        self._sources.append(source)

    def _drain(self) -> None:
        while self._sources:
            source = self._sources.pop(0)
            for name, value in source():
                self.register(name, value)

    def _complete(self) -> None:
        load_plugins()
        self._drain()

    def __getitem__(self, name: str) -> T:
        self._drain()
        if name not in self._entries:
            self._complete()
        if name not in self._entries:
            raise UnknownNameError(self.kind, name, self._valid())
        return self._entries[name]

    def __contains__(self, name: object) -> bool:
        self._drain()
        if name not in self._entries:
            self._complete()
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        self._complete()
        return iter(self._names())

    def __len__(self) -> int:
        self._complete()
        return len(self._entries)

    def derived(self, part: Callable[[T], object], keep: Callable[[T], bool] | None = None) -> Mapping[str, object]:
        """A read-only live view: name -> ``part(value)`` for the entries where ``keep(value)`` holds (None: all).

        What other modules read of one registry (the orders of the integrators, the gain arguments of the
        controllers), so each kind has one registry and the tables beside it follow it, plug-ins' entries included."""
        return _View(self, part, keep)

    def _names(self) -> tuple[str, ...]:
        """The names in registration order, :attr:`default` first."""
        first = (self.default,) if self.default in self._entries else ()
        return (*first, *(n for n in self._entries if n != self.default))

    def _valid(self) -> tuple[str, ...]:
        if _LOADED:
            return self._names()
        return (*self._names(), f"(no plug-in found in the entry points {PLUGIN_GROUP!r}: is qprr installed, e.g. pip install -e .?)")

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self._entries) or 'empty'})"


class _View(Mapping[str, object]):
    """:meth:`Registry.derived`: a part of every (kept) entry of a registry, read when looked up."""

    def __init__(self, registry: Registry, part: Callable, keep: Callable | None) -> None:
        self.registry, self.part, self.keep = registry, part, keep

    def _kept(self, value) -> bool:
        return self.keep is None or bool(self.keep(value))

    def __getitem__(self, name: str):
        value = self.registry[name]
        if not self._kept(value):
            raise UnknownNameError(self.registry.kind, name, tuple(self))
        return self.part(value)

    def __contains__(self, name: object) -> bool:
        return name in self.registry and self._kept(self.registry[name])

    def __iter__(self) -> Iterator[str]:
        return iter([n for n, v in self.registry.items() if self._kept(v)])

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def __repr__(self) -> str:
        return f"{dict(self)!r}"


SCENARIOS: Registry = Registry("scenario")
"""Scenario name -> :class:`qprr.scenarios.Scenario` (the generic ones are added by :mod:`qprr.scenarios`)."""
PARAMETER_SETS: Registry[Callable[[], object]] = Registry("parameter set")
"""``"<platform>:<variant>"`` -> a function returning the parameters of that named platform (e.g. ``"q-prr:cad"``)."""
GAIN_TABLES: Registry[Callable[[], object]] = Registry("gain table")
"""``"<platform>:<table>"`` -> a function returning a gain set of :mod:`qprr.control` (e.g. ``"q-prr:table-6.2"``)."""
COMPARISONS: Registry[Callable[..., Iterable]] = Registry("comparison")
"""Comparison name -> ``run(names, *, duration, plot_dir, progress)`` yielding reports with ``name``, ``lines``,
``figures`` and ``ok`` (one runner may serve several names: ``qprr compare`` calls it once with all of them)."""
CHECKS: Registry[Callable[[bool], int]] = Registry("check suite")
"""Check-suite name -> ``run(verbose) -> exit code`` (0: every check holds); ``qprr check`` runs them all."""
MAP_REFERENCES: Registry[Callable[..., object]] = Registry("map reference")
"""Provider name -> ``(map_name, platform, result) -> MapReference | None``: published numbers for a design map."""
COMMANDS: Registry[Callable[..., None]] = Registry("command group", COMMAND_GROUP)
"""Command-group name -> ``register_cli(subparsers)`` adding a plug-in's commands to the ``qprr`` front end: the
entry points of :data:`COMMAND_GROUP` (read on first use; the front end's modules are not plug-in code)."""


__all__ = [
    "CHECKS",
    "COMMAND_GROUP",
    "COMMANDS",
    "COMPARISONS",
    "GAIN_TABLES",
    "MAP_REFERENCES",
    "PARAMETER_SETS",
    "PLUGIN_GROUP",
    "SCENARIOS",
    "Registry",
    "load_plugins",
]
