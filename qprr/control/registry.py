"""The controller registry: name -> :class:`ControllerEntry` (its factory and how its gains follow from a platform).

Every controller the command line, the scenarios and the campaigns can name is an entry of :data:`CONTROLLERS`
(:class:`qprr.registry.Registry`, default ``"idc"``).  :mod:`qprr.control` registers the core's; a plug-in registers
its own from its ``register()`` (the ``qprr.plugins`` entry point, docs/extending.md)::

    CONTROLLERS.register("pd-gravity", ControllerEntry(PDGravity, DerivedGains(("gains",), derive), "PD + gravity"))

An entry must say how its gains are derived from a platform, or that it has none: ``gains`` is a
:class:`DerivedGains` (the constructor arguments it fills and ``derive(authority, targets) -> {argument: value}``,
read from the platform's :class:`qprr.control.gains.Authority` and the bandwidth :class:`qprr.control.gains.Targets`)
or a :class:`NoGains` with the reason (``mpc``: cost weights).  An entry with neither is refused when it is made,
with that reason: a controller without a derivation would fly its class's fixed defaults on every platform, the
silent fallback this registry replaces.

``scenarios``: the registered scenarios (of the core or of other plug-ins) that may fly the controller besides those
that name it themselves (:meth:`qprr.scenarios.Scenario.controller_names`): ``("hover-reach", "fly-to")`` makes a new
controller a choice of ``qprr simulate hover-reach --controller NAME`` without editing the scenario.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..errors import InputError
from ..registry import Registry

DEFAULT_CONTROLLER = "idc"
"""The controller a caller gets without naming one: the inverse-dynamics controller (Thesis Sec. 6.3.1)."""


@dataclass(frozen=True)
class DerivedGains:
    """How a controller's gains follow from a platform: ``derive(authority, targets)`` returns the constructor
    keyword arguments named in ``arguments`` (e.g. ``{"gains": IDCGains(...)}``); ``authority`` is the platform's
    :class:`qprr.control.gains.Authority`, ``targets`` the :class:`qprr.control.gains.Targets` (the bandwidth rules
    of :mod:`qprr.control.gains`: :func:`qprr.control.gains.bandwidths` gives w per coordinate)."""

    arguments: tuple[str, ...]
    derive: Callable[..., dict[str, object]]

    def __post_init__(self) -> None:
        args = self.arguments
        if isinstance(args, str) or not isinstance(args, tuple) or not args or not all(isinstance(a, str) and a for a in args):
            raise InputError(f"DerivedGains.arguments must be a non-empty tuple of constructor argument names, got {args!r}")
        if not callable(self.derive):
            raise InputError(f"DerivedGains.derive must be a function (authority, targets) -> {{argument: value}}, got {self.derive!r}")


@dataclass(frozen=True)
class NoGains:
    """A controller with no gains to derive from a platform, and why (``mpc``: cost weights of its own).

    ``settings``: constructor arguments a gains file may still set, each as a table of fields (``[mpc.weights]``,
    ``[mpc.settings]``); the factory receives each as a dict of field -> value and builds its object from it."""

    reason: str
    settings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.reason, str) or not self.reason.strip():
            raise InputError(f"NoGains needs the reason the controller has no gains (e.g. 'cost weights, not gains'), got {self.reason!r}")
        if isinstance(self.settings, str) or not isinstance(self.settings, tuple) or not all(isinstance(a, str) and a for a in self.settings):
            raise InputError(f"NoGains.settings must be a tuple of constructor argument names, got {self.settings!r}")


@dataclass(frozen=True)
class ControllerEntry:
    """A registered controller: ``factory(platform, **kwargs) -> Controller`` (a :class:`qprr.control.base.Controller`
    subclass or a function), ``gains`` (:class:`DerivedGains` or :class:`NoGains`, required), a one-line
    ``description`` and the ``scenarios`` that may fly it besides those naming it (module docstring)."""

    factory: Callable[..., object]
    gains: DerivedGains | NoGains | None = None
    description: str = ""
    scenarios: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not callable(self.factory):
            raise InputError(f"ControllerEntry.factory must be a class or function (platform, **kwargs) -> Controller, got {self.factory!r}")
        if not isinstance(self.gains, (DerivedGains, NoGains)):
            raise InputError(
                f"controller {_name_of(self.factory)} declares no gain derivation (gains={self.gains!r}): give "
                "gains=DerivedGains(arguments, derive) (how its gains follow from a platform's authority, qprr.control.gains) "
                "or gains=NoGains(reason) (it has none); without one it would fly its class's fixed defaults on every platform"
            )
        if not isinstance(self.description, str):
            raise InputError(f"ControllerEntry.description must be a string, got {self.description!r}")
        names = self.scenarios
        if isinstance(names, str) or not isinstance(names, tuple) or not all(isinstance(n, str) and n for n in names):
            raise InputError(f"ControllerEntry.scenarios must be a tuple of scenario names, got {names!r}")

    @property
    def gain_arguments(self) -> tuple[str, ...]:
        """The constructor arguments its gain derivation fills (() for :class:`NoGains`)."""
        return self.gains.arguments if isinstance(self.gains, DerivedGains) else ()


def _name_of(factory) -> str:
    return repr(f"{factory.__module__}.{factory.__qualname__}") if isinstance(factory, type) else repr(factory)


def _check(name: str, entry: object) -> None:
    if not isinstance(entry, ControllerEntry):
        raise InputError(
            f"controller {name!r}: register a qprr.control.ControllerEntry(factory, gains=DerivedGains(...) or NoGains(reason)), "
            f"got {type(entry).__name__} (docs/extending.md)"
        )


CONTROLLERS: Registry[ControllerEntry] = Registry("controller", default=DEFAULT_CONTROLLER, check=_check)
"""Controller name -> :class:`ControllerEntry`; the core's are registered by :mod:`qprr.control`, plug-ins add theirs."""


def has_derived_gains(entry: ControllerEntry) -> bool:
    """Whether ``entry``'s gains are derived from the platform (:class:`DerivedGains`)."""
    return isinstance(entry.gains, DerivedGains)


GAIN_ARGUMENTS = CONTROLLERS.derived(lambda entry: entry.gain_arguments, keep=has_derived_gains)
"""Controller name -> the constructor arguments its gains are derived into (only the controllers with
:class:`DerivedGains`; a live view of :data:`CONTROLLERS`)."""


__all__ = ["CONTROLLERS", "DEFAULT_CONTROLLER", "GAIN_ARGUMENTS", "ControllerEntry", "DerivedGains", "NoGains", "has_derived_gains"]
