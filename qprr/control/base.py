"""What every controller shares: the state it reads, the reference it tracks, the step contract.

A controller is an object with one method, :meth:`Controller.step`, called once per control
period by the simulator:

    u = controller.step(t, state, ref)

* ``state`` (:class:`State`) holds the measured Pinocchio state (q, v), the thesis
  coordinates (xi, xi_dot) and the rotation/trigonometric values the maps below need;
* ``ref`` (:class:`Reference`) holds xi_d, xi_dot_d, xi_ddot_d from the trajectory.  Roll
  and pitch are not given by the trajectory: a controller that derives references itself
  (roll/pitch from (6.17), the BSG's r0 and theta3) writes them into ``ref`` so the log
  records what was actually tracked;
* ``u`` (6 + n_arm,) is the desired generalised force in thesis coordinates
  u = [u_fb (world force, N), u_tau (Euler-angle torques, N m), u_mu (arm efforts)]
  (Thesis (5.40)).  The simulator maps it to Pinocchio's tau = S^-T u and allocates it
  to the rotors (:mod:`qprr.actuation`).

Adding a controller means writing a subclass; the simulator does not change.  Controllers
take the platform they control and never modify it.

:class:`State` lives in :mod:`qprr.charts` with the rest of the conversion: it is the same
map S on plain floats with cached trigonometry, for the control loop.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..charts import State, as_xi
from ..errors import InputError, NotResetError
from ..validation import as_int, as_real, as_vector


class Reference:
    """Reference at one step: ``xi``, ``xi_dot``, ``xi_ddot`` (6 + n_arm,) each, thesis coordinates.

    The simulator points these at rows of its log (pre-filled from the trajectory);
    controllers overwrite the entries they generate (roll, pitch, BSG joints).
    """

    __slots__ = ("xi", "xi_dot", "xi_ddot")

    def __init__(self, xi=None, xi_dot=None, xi_ddot=None, n_xi: int | None = None) -> None:
        if n_xi is None:
            n_xi = as_xi(xi, "xi").shape[0] if xi is not None else 9
        n_xi = as_int(n_xi, "n_xi", lo=6)
        # float arrays are kept as given (the simulator's rows of its log), others converted
        self.xi = np.zeros(n_xi) if xi is None else as_vector(xi, n_xi, "xi")
        self.xi_dot = np.zeros(n_xi) if xi_dot is None else as_vector(xi_dot, n_xi, "xi_dot")
        self.xi_ddot = np.zeros(n_xi) if xi_ddot is None else as_vector(xi_ddot, n_xi, "xi_ddot")


def check_reset(controller, state, ref, dt) -> float:
    """The arguments of :meth:`Controller.reset` checked (a :class:`State` and a :class:`Reference` of the controller's
    platform size, when it has one, a control period dt > 0 [s]); returns dt as a float.  ``reset`` runs once per run:
    the per-step calls (``step``) take the simulator's own State and Reference unchecked."""
    if not isinstance(controller, Controller):
        raise InputError(f"controller must be a qprr.control.Controller, got {type(controller).__name__}")
    if not isinstance(state, State):
        raise InputError(f"state must be a qprr.charts.State, got {type(state).__name__}")
    if not isinstance(ref, Reference):
        raise InputError(f"ref must be a qprr.control.Reference, got {type(ref).__name__}")
    platform = controller.platform
    if platform is not None and (state.n_arm != platform.n_arm or np.shape(ref.xi) != (platform.n_xi,)):
        raise InputError(
            f"state and ref must be of the controller's platform ({platform.n_xi} thesis coordinates), "
            f"got a state of {6 + state.n_arm} and a reference of shape {np.shape(ref.xi)}"
        )
    return as_real(dt, "dt", positive=True, unit="s")


def not_reset(controller) -> NotResetError:
    """The error of a controller used before :meth:`Controller.reset` gave it its control period."""
    return NotResetError(
        f"{type(controller).__name__}.dt (the control period) is not set: call reset(state, ref, dt) first (qprr.sim.simulate does it before the run)"
    )


class Controller(ABC):
    """Base class: ``step(t, state, ref) -> u`` (see the module docstring)."""

    name: str = "controller"
    platform = None
    """The :class:`~qprr.model.Platform` controlled (its sizes are checked by :meth:`reset`), or None for a
    controller not tied to one."""
    uses_applied_force: bool = False
    """Set True to have the simulator fill ``state.u_applied`` (costs ~1 us per step)."""
    output: str = "xi"
    """What :meth:`step` returns: "xi" (default), u in thesis coordinates; or "pinocchio",
    tau = S^-T u at the measured state (a controller that computes tau anyway saves two
    coordinate changes per step; the simulator still logs u)."""

    tilt = None
    """The roll/pitch reference filter of a controller that derives them from (6.17) (a
    :class:`~qprr.control.filters.TiltReference` or :class:`~qprr.control.filters.SingleTiltReference`,
    made by :meth:`reset`), else None.  A wrapper (e.g. the thesis's BSG) may read its last references."""

    _dt: float | None = None

    @property
    def dt(self) -> float:
        """Control period [s], set by :meth:`reset` (which the simulator calls before the run); there is no
        default: reading it before ``reset`` raises :class:`~qprr.errors.NotResetError`."""
        dt = self._dt
        if dt is None:
            raise not_reset(self)
        return dt

    @dt.setter
    def dt(self, value: float | None) -> None:
        self._dt = value

    uses_preview: bool = False
    """Set True to be handed the run's whole reference trajectory before it starts (:meth:`set_preview`):
    a controller that plans over a horizon (e.g. :mod:`qprr.control.mpc`).  Others see only ``ref``."""

    def set_preview(self, trajectory) -> None:
        """Called by the simulator before :meth:`reset` when ``uses_preview`` is True, with the trajectory
        (an object with ``sample(t)``, thesis coordinates) the run follows (default: keep it as ``self.trajectory``)."""
        self.trajectory = trajectory

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        """Called once before the run with the initial state and the control period ``dt`` [s]."""
        self.dt = check_reset(self, state, ref, dt)

    def report(self) -> tuple[dict[str, float], dict[str, np.ndarray]]:
        """(metrics, series) the controller measured about itself during the run, copied into the
        :class:`~qprr.sim.SimResult` by the simulator (e.g. an MPC's solve times); default none."""
        return {}, {}

    def run_warnings(self) -> tuple[str, ...]:
        """What the controller found wrong with its own run although it completed (e.g. an MPC that stopped at its
        iteration limit too often, or whose inputs chattered), one sentence each; the simulator appends them to the
        result's ``reason`` ("completed with warnings: ...").  Default none."""
        return ()

    @abstractmethod
    def step(self, t: float, state: State, ref: Reference) -> np.ndarray:
        """Desired generalised force (6 + n_arm,): u in thesis coordinates (or tau if ``output == "pinocchio"``)."""
