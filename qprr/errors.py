"""Exceptions raised by qprr.

Every exception derives from :class:`QprrError` and from the built-in that matches
its meaning, so ``except ValueError`` keeps working for callers that do not know
qprr.  Messages name the offending argument and its value.
"""

from __future__ import annotations


class QprrError(Exception):
    """Base class of every error raised by qprr.

    ``result``: the partial :class:`~qprr.sim.result.SimResult` of a simulation the error stopped (set by
    :func:`qprr.sim.simulate` on the error it raises: the log up to the failure, status DIVERGED or FAILED); None for
    every other error.  ``time``: the simulated time [s] the message names (set by :meth:`with_time`, or where a
    run's divergence is detected, :meth:`DivergenceError.at`); None for an error not tied to a time of a run.
    """

    result = None
    time: float | None = None
    time_prefix = "at t = {t:.3f} s of the run: "
    """What :meth:`with_time` puts in front of the message."""

    def with_time(self, t: float) -> QprrError:
        """This error, raised during a run, with the run's time ``t`` [s] named in front of its message
        (:attr:`time_prefix`: "at t = 1.234 s of the run: ..."); the same object (type, attributes and traceback kept).
        An error that already names its time is returned as is."""
        if self.time is None:
            self._set_message(self.time_prefix.format(t=t) + str(self))
            self.time = t
        return self

    def within(self, where: str) -> QprrError:
        """This error with ``where`` (what was being read, e.g. "rotor file 'x.toml'") named in front of its message,
        "where: ..."; the same object (type, attributes and traceback kept), to re-raise."""
        self._set_message(f"{where}: {self}")
        return self

    def _set_message(self, message: str) -> None:
        """Replace the message (what ``str(self)`` shows)."""
        self.args = (message,)


class InputError(QprrError, ValueError):
    """An argument has the wrong shape, a non-finite entry or a forbidden value."""


class ShapeError(InputError):
    """An array argument has the wrong shape."""


class NonFiniteError(InputError):
    """An array argument contains NaN or inf."""


class LimitError(InputError):
    """A joint value lies outside its limits where the function requires it inside."""


class NonPhysicalError(InputError):
    """A parameter set describes a body or a device that cannot exist (negative mass, an inertia that breaks the
    triangle inequality, lower limit above the upper one...); the message names the body and the inequality."""


class EulerSingularityError(InputError):
    """ZYX Euler angles are singular (pitch theta = +-pi/2): rates or angles are not unique."""


class UnknownNameError(QprrError, KeyError):
    """An unknown name (layout, scenario, controller, method, option...) was given."""

    def __init__(self, kind: str, name: object, valid: list[str] | tuple[str, ...]) -> None:
        self.kind = kind
        self.name = name
        self.valid = tuple(valid)
        super().__init__(f"unknown {kind} {name!r}; valid: {', '.join(map(repr, self.valid))}")

    def __str__(self) -> str:  # KeyError would otherwise repr() the message
        return str(self.args[0])


class DivergenceError(QprrError, RuntimeError):
    """A simulation or an iterative algorithm diverged (NaN or runaway state).

    Raised during a run, its message starts with "diverged at t = <time> s: " (:meth:`at`, :meth:`with_time`)."""

    time_prefix = "diverged at t = {t:.3f} s: "

    @classmethod
    def at(cls, t: float, what: str) -> DivergenceError:
        """The divergence of a run at simulated time ``t`` [s]: "diverged at t = <t> s: <what>", :attr:`time` set."""
        return cls(what).with_time(t)


class SolverError(QprrError, RuntimeError):
    """A numerical solver (QP, linear system) failed to return a trustworthy answer."""


class NotResetError(QprrError, RuntimeError):
    """An object used before the call that sets it up for a run (e.g. a controller's ``dt`` before ``reset``)."""


class MissingDependencyError(QprrError, ImportError):
    """An optional dependency is not installed; the message gives the install command."""

    def __init__(self, package: str, purpose: str, install: str) -> None:
        self.package, self.purpose, self.install = package, purpose, install
        super().__init__(f"{package} is needed for {purpose}: {install}")

    def _set_message(self, message: str) -> None:
        """Replace the message: ImportError shows its ``msg``, not its ``args``."""
        self.args = (message,)
        self.msg = message


class MissingTopicError(QprrError, LookupError):
    """A flight log lacks a topic (or a field of it) that a computation needs; the message names the topic, what
    needs it and the PX4 logging profile (the ``SDLOG_PROFILE`` bit) that adds it."""

    def __init__(self, message: str, topic: str = "") -> None:
        self.topic = topic
        super().__init__(message)

    def __str__(self) -> str:  # LookupError would otherwise show the bare message
        return str(self.args[0])


class NoFlightError(QprrError, RuntimeError):
    """A flight log holds no flight (never armed, or armed but never airborne) where a computation needs one; the
    one-line message says which."""


class PortInUseError(QprrError, OSError):
    """A network port the caller asked for is already taken (e.g. by another ``qprr view``)."""


class KinematicSingularityError(InputError):
    """A kinematic model is singular at the given configuration (its B(q) is undefined there,
    e.g. the rear-driven tricycle at psi = +-pi/2)."""


class ActuationError(InputError):
    """A rotor set cannot control the vehicle: it cannot hover with thrusts inside their bounds, or it lacks one of
    the wrench directions every flight controller needs (collective thrust and three independent torques), or two
    rotors are the same rotor; the message names the rotor file and the rotors."""


class PlausibilityError(InputError):
    """A physical input lies outside the documented plausibility range for aerial robots (docs/platforms.md), most
    often a unit slip (millimetres for metres, degrees for radians, grams for kilograms); the message names the input,
    the likely slip and the ``plausibility=`` setting that accepts the value on purpose."""


class ActuationWarning(UserWarning):
    """A rotor set that can fly but is badly conditioned (one wrench direction far weaker than the others)."""


class ScheduleWarning(UserWarning):
    """A mission longer than its run: phases or payload events at or after the end are never flown, a phase ending after
    it is flown in part (a short run of a long mission on purpose: filter this category)."""
