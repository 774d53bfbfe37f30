"""The description of an aerial manipulator: a free-flying multirotor base, a serial arm, a rotor set.

A :class:`Platform` is immutable.  It holds

* ``model``: the Pinocchio model, root joint a free flyer (q = [p_world, quat_xyzw, q_arm],
  v = [v_body, omega_body, q_arm_dot], both base velocities in B), gravity -g e3 (world z up);
* ``base_frame``: the frame B of the free-flyer joint (the root link of the URDF);
* ``ee_frame`` (and ``ee_frames``): the end-effector frame(s);
* ``arm``: one :class:`ArmJoint` per arm joint (1-DOF prismatic or revolute, in model order,
  so ``q_arm = q[7:]`` and ``v_arm = v[6:]``) with its limits and effort bound;
* ``rotors``: the :class:`~qprr.rotors.Rotor` set (positions and thrust axes in B, spins, drag
  ratios, thrust bounds).

Algorithms take ``(platform, data, state)``; ``data`` comes from :meth:`Platform.data` and is the
only thing they write.  Nothing in qprr modifies ``platform.model``: variants (another rotor set,
a payload) are new platforms (:meth:`Platform.replace`, :meth:`Platform.with_model`).

Build one with :func:`from_urdf` (any URDF + a rotor description), :func:`qprr.build` (the
thesis nomenclature (2.1): ``"Q-PRR"``, ``"HEX-RRR"``...) or :func:`qprr.load` (named platforms:
the thesis Q-PRR, example-robot-data's ``borinot_flying_arm_2`` and ``hextilt_flying_arm_5``).
Every name is checked when the platform is made: an unknown frame or joint raises
:class:`~qprr.errors.UnknownNameError` listing the names that exist.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import pinocchio as pin

from .errors import InputError, LimitError, NonPhysicalError, ShapeError, UnknownNameError
from .rotors import ActuationSummary, Rotor, actuation_summary, check_hover_solution, check_rotor_set, rotor_matrix, rotors_from_mapping
from .urdf.inertia import check_rigid_body, inertia_matrix, read_inertials
from .urdf.plausibility import DEFAULT as _PLAUSIBLE
from .urdf.plausibility import check_plausibility_setting
from .urdf.plausibility import check_rotors as _check_rotor_ranges
from .urdf.reader import read_urdf

_REVOLUTE = {"JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"}
_PRISMATIC = {"JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned"}
_HUGE = 1e300  # Pinocchio's "no limit" is the largest double


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class ArmJoint:
    """One joint of the arm: ``kind`` "prismatic" [m] or "revolute" [rad], its indices and bounds.

    ``lower``/``upper`` are position limits (``-inf``/``inf`` when the URDF gives none),
    ``effort`` the largest force [N] or torque [N m], ``velocity`` the largest rate.
    """

    name: str
    kind: str
    joint_id: int
    idx_q: int
    idx_v: int
    lower: float
    upper: float
    effort: float
    velocity: float


# ============================================================================ physics checks
def check_model_inertias(model: pin.Model) -> None:
    """:func:`qprr.urdf.inertia.check_rigid_body` on every body of a Pinocchio model (after fixed links are merged)."""
    if not isinstance(model, pin.Model):
        raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__} {_short(model)}")
    for j in range(1, model.njoints):
        Y = model.inertias[j]
        check_rigid_body(model.names[j], float(Y.mass), Y.lever, Y.inertia, allow_massless=True)


# ============================================================================== platform
@dataclass(frozen=True, eq=False)
class Platform:
    """An aerial manipulator (see the module docstring).  Build with :func:`from_urdf` or :func:`qprr.build`.

    ``params`` keeps what the platform was built from (for the thesis's Q-PRR its parameter set
    :class:`qprr.thesis.params.QPRRParams`, for :func:`qprr.build` the parsed (2.1) name); library
    code never reads it, only :mod:`qprr.thesis` does.  ``provenance`` says where each value comes from.
    ``motor``: the ``[motor]`` table of the rotor description (thrust factor, time constant, speed limits: the actuator
    stage :mod:`qprr.sim.actuators` builds, what ``motor-lag`` flies); empty when it has none.
    ``urdf``: the URDF text the model was read from (None for :func:`from_model`), kept for its
    visual geometry (:func:`qprr.viz.visual_model`).
    """

    name: str
    model: pin.Model
    base_frame: int
    ee_frame: int
    arm: tuple[ArmJoint, ...]
    rotors: tuple[Rotor, ...]
    ee_frames: tuple[int, ...] = ()
    params: object = None
    provenance: Mapping[str, str] = field(default_factory=dict)
    urdf: str | None = field(default=None, repr=False)
    motor: Mapping[str, object] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        model = self.model
        if not isinstance(model, pin.Model):
            raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__}")
        if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer" or model.parents[1] != 0:
            raise InputError("a platform's model needs a free-flyer root joint (load the URDF with pin.JointModelFreeFlyer())")
        n_arm = model.njoints - 2
        if not isinstance(self.arm, (tuple, list)) or not all(isinstance(j, ArmJoint) for j in self.arm):
            raise InputError(f"arm must be a tuple of ArmJoint, got {_short(self.arm)}")
        if not isinstance(self.rotors, (tuple, list)):
            raise InputError(f"rotors must be a tuple of qprr.rotors.Rotor, got {_short(self.rotors)}")
        if len(self.arm) != n_arm:
            raise InputError(f"the model has {n_arm} joints after the free flyer, the arm lists {len(self.arm)}")
        for k, j in enumerate(self.arm):
            if j.joint_id != 2 + k or j.idx_q != 7 + k or j.idx_v != 6 + k:
                raise InputError(f"arm joint {j.name!r} is not the {k + 1}-th 1-DOF joint after the free flyer")
        for fid, label in [(self.base_frame, "base_frame"), (self.ee_frame, "ee_frame")] + [(f, "ee_frames") for f in self.ee_frames]:
            if not (isinstance(fid, (int, np.integer)) and 0 <= fid < model.nframes):
                raise InputError(f"{label} must be a frame id in [0, {model.nframes}), got {fid!r}")
        if model.frames[self.base_frame].parentJoint != 1:
            raise InputError(f"base_frame {model.frames[self.base_frame].name!r} is not attached to the free-flyer joint")
        if not self.ee_frames:
            object.__setattr__(self, "ee_frames", (self.ee_frame,))
        if len(self.rotors) == 0:
            raise InputError("a platform needs at least one rotor")
        if not all(isinstance(r, Rotor) for r in self.rotors):
            raise InputError("rotors must be qprr.rotors.Rotor objects")
        object.__setattr__(self, "arm", tuple(self.arm))
        object.__setattr__(self, "rotors", tuple(self.rotors))
        gvec = model.gravity.linear
        if not (abs(gvec[0]) == 0.0 and abs(gvec[1]) == 0.0 and gvec[2] <= 0.0):  # zero: free flight
            raise InputError(f"model.gravity must point along -z of the world frame (or be zero), got {gvec.tolist()} m/s^2")

    # -------------------------------------------------------------- sizes and names
    @property
    def nq(self) -> int:
        return self.model.nq

    @property
    def nv(self) -> int:
        return self.model.nv

    @property
    def n_arm(self) -> int:
        """Number of arm joints (the thesis chart xi has 6 + n_arm entries)."""
        return len(self.arm)

    @property
    def n_rotors(self) -> int:
        return len(self.rotors)

    @property
    def n_xi(self) -> int:
        """Size of the thesis chart xi = [x, y, z, phi, theta, psi, q_arm]: 6 + n_arm (= nv)."""
        return 6 + len(self.arm)

    @property
    def n_actuators(self) -> int:
        """Rotor thrusts then arm efforts: n_rotors + n_arm."""
        return len(self.rotors) + len(self.arm)

    @property
    def arm_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.arm)

    @property
    def xi_names(self) -> tuple[str, ...]:
        """Names of the thesis coordinates: x, y, z, phi, theta, psi, then the arm joints."""
        return ("x", "y", "z", "phi", "theta", "psi", *self.arm_names)

    @property
    def g(self) -> float:
        """Gravity [m/s^2] (model.gravity = -g e3)."""
        return float(-self.model.gravity.linear[2])

    def data(self) -> pin.Data:
        """A fresh ``pin.Data`` (the only thing algorithms write)."""
        return self.model.createData()

    def frame_id(self, name: str | int) -> int:
        """Frame id of ``name`` (or a valid id); :class:`UnknownNameError` lists the frames."""
        return frame_id(self.model, name)

    # -------------------------------------------------------------- inertial
    @cached_property
    def total_mass(self) -> float:
        """Mass of the whole system [kg]."""
        return float(pin.computeTotalMass(self.model))

    # -------------------------------------------------------------- arm
    @cached_property
    def arm_lower(self) -> np.ndarray:
        return _readonly(np.array([j.lower for j in self.arm]))

    @cached_property
    def arm_upper(self) -> np.ndarray:
        return _readonly(np.array([j.upper for j in self.arm]))

    @cached_property
    def _arm_limits_with_slack(self) -> tuple[np.ndarray, np.ndarray]:
        """(arm_lower - 1e-12, arm_upper + 1e-12): the interval :meth:`check_arm_limits` accepts (rounding slack)."""
        return _readonly(self.arm_lower - 1e-12), _readonly(self.arm_upper + 1e-12)

    @cached_property
    def arm_effort_limits(self) -> np.ndarray:
        """Largest |effort| per arm joint [N or N m]."""
        return _readonly(np.array([j.effort for j in self.arm]))

    def check_arm_limits(self, q_arm, name: str = "q_arm") -> np.ndarray:
        """Return ``q_arm`` (n_arm,) if finite and inside the joint limits, else raise :class:`LimitError`."""
        from .validation import as_vector

        q_arm = as_vector(q_arm, self.n_arm, name)
        lower, upper = self._arm_limits_with_slack
        if all(lo <= x <= up for x, lo, up in zip(q_arm.tolist(), lower.tolist(), upper.tolist())):  # floats: cheaper than numpy here
            return q_arm
        bad = [k for k, j in enumerate(self.arm) if not j.lower - 1e-12 <= q_arm[k] <= j.upper + 1e-12]
        if bad:
            parts = [f"{self.arm[k].name} = {float(q_arm[k])!r} not in [{self.arm[k].lower!r}, {self.arm[k].upper!r}]" for k in bad]
            raise LimitError(f"{name}: " + "; ".join(parts))
        return q_arm

    def neutral_q(self) -> np.ndarray:
        """q at the world origin, level, arm joints at 0 (or at the limit nearest 0)."""
        q = pin.neutral(self.model)
        q[7:] = np.clip(0.0, self.arm_lower, self.arm_upper) if self.n_arm else q[7:]
        return q

    def neutral_xi(self) -> np.ndarray:
        """xi of :meth:`neutral_q`."""
        xi = np.zeros(self.n_xi)
        xi[6:] = self.neutral_q()[7:]
        return xi

    def arm_model(self) -> pin.Model:
        """A fixed-base Pinocchio model of the arm: the base link is the fixed root (a new model)."""
        return pin.buildReducedModel(self.model, [1], self.neutral_q())

    # -------------------------------------------------------------- rotors
    @cached_property
    def rotor_matrix(self) -> np.ndarray:
        """Omega (6 x n_rotors): [f_B; tau_B] = Omega f (Thesis (3.31)-(3.36), :func:`qprr.rotors.rotor_matrix`)."""
        return _readonly(rotor_matrix(self.rotors))

    @cached_property
    def actuation_matrix(self) -> np.ndarray:
        """N (nv x n_actuators) = blockdiag(Omega, I): Pinocchio's tau = N [f; efforts] (Thesis (5.44)-(5.46))."""
        N = np.zeros((self.nv, self.n_actuators))
        N[0:6, 0 : self.n_rotors] = self.rotor_matrix
        N[6:, self.n_rotors :] = np.eye(self.n_arm)
        return _readonly(N)

    @cached_property
    def thrust_min(self) -> np.ndarray:
        return _readonly(np.array([r.f_min for r in self.rotors]))

    @cached_property
    def thrust_max(self) -> np.ndarray:
        return _readonly(np.array([r.f_max for r in self.rotors]))

    @cached_property
    def wrench_rank(self) -> int:
        """Dimension of the base wrench the rotors can produce: 4 for coplanar rotors, 6 when fully actuated."""
        return int(np.linalg.matrix_rank(self.rotor_matrix, tol=1e-9))

    @property
    def fully_actuated(self) -> bool:
        """True when the rotors span every base force and torque (e.g. a tilted hexarotor)."""
        return self.wrench_rank == 6

    def actuation_summary(self) -> ActuationSummary:
        """What the rotor set can do for this platform at its neutral configuration (:func:`qprr.rotors.actuation_summary`):
        wrench rank and directions, fully vs under-actuated, the attitude map's rank and condition number, the hover
        thrusts and their margin to the bounds.  Loading refuses a set that cannot hover and control attitude
        (:func:`qprr.rotors.check_rotor_set`); this reports on any set, e.g. one given by :meth:`replace`."""
        return actuation_summary(self.rotors, self.total_mass * self.g, self.com_neutral_body)

    @cached_property
    def com_neutral_body(self) -> np.ndarray:
        """Centre of mass of the whole system [m] in B at :meth:`neutral_q`."""
        return _readonly(np.array(pin.centerOfMass(self.model, self.model.createData(), self.neutral_q())))

    @cached_property
    def thrust_axis(self) -> tuple[np.ndarray, np.ndarray]:
        """(point_body, direction_body): the line of action of equal rotor thrusts, in B.

        For equal thrusts the rotors apply f sum_i [a_i; p_i x a_i + s_i kappa_i a_i]; the force
        F = sum a_i acts along the line through c = F x tau / |F|^2 (the point of that line nearest
        B) with direction F / |F|.  A platform hovers with equal thrusts only with its CoG on this
        line (the "CoG on the thrust axis" of the thesis, x_cm = y_cm = 0 for the Q-PRR).
        """
        w = self.rotor_matrix.sum(axis=1)
        F, tau = w[0:3], w[3:6]
        nF = float(np.linalg.norm(F))
        if not nF > 1e-12:
            raise InputError(f"platform {self.name!r}: equal rotor thrusts give no net force (rotor axes cancel)")
        point = np.cross(F, tau) / nF**2
        point[np.abs(point) < 1e-15] = 0.0
        return _readonly(point), _readonly(F / nF)

    @cached_property
    def thrust_axis_basis(self) -> np.ndarray:
        """(2, 3): two unit vectors (rows, in B) spanning the plane normal to the thrust axis; (x_B, y_B) for z_B."""
        d = self.thrust_axis[1]
        e1 = np.array([1.0, 0.0, 0.0]) - d[0] * d
        if np.linalg.norm(e1) < 1e-6:
            e1 = np.array([0.0, 1.0, 0.0]) - d[1] * d
        e1 /= np.linalg.norm(e1)
        e2 = np.array([d[1] * e1[2] - d[2] * e1[1], d[2] * e1[0] - d[0] * e1[2], d[0] * e1[1] - d[1] * e1[0]])
        B = np.vstack([e1, e2])
        B[np.abs(B) < 1e-15] = 0.0
        return _readonly(B)

    # -------------------------------------------------------------- variants
    def replace(self, **changes) -> Platform:
        """A copy with some fields replaced (e.g. ``rotors=...``); the model is shared, never modified."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise UnknownNameError("platform field", sorted(unknown)[0], tuple(f.name for f in dataclasses.fields(self)))
        return dataclasses.replace(self, **changes)

    def with_model(self, model: pin.Model) -> Platform:
        """The same platform on another model of the same structure (e.g. with a payload inertia)."""
        if not isinstance(model, pin.Model):
            raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__} {_short(model)}")
        if model.nq != self.model.nq or model.nv != self.model.nv or model.nframes != self.model.nframes:
            raise ShapeError(f"model of another structure: nq {model.nq}, nv {model.nv}, nframes {model.nframes}")
        return dataclasses.replace(self, model=model)

    def without_joint_friction(self) -> Platform:
        """The same platform with the URDF's joint ``<dynamics damping friction>`` set to zero (a model copy): the plant
        (:mod:`qprr.dynamics.friction`) and the controllers then see frictionless joints.  ``self`` when it has none."""
        if not (np.any(self.model.damping) or np.any(self.model.friction)):
            return self
        model = pin.Model(self.model)
        model.damping[:] = 0.0
        model.friction[:] = 0.0
        return dataclasses.replace(self, model=model)

    def __repr__(self) -> str:
        kinds = "".join("P" if j.kind == "prismatic" else "R" for j in self.arm)
        return (
            f"Platform({self.name!r}, {self.n_rotors} rotors, arm {kinds or '-'}, {self.total_mass:.3f} kg, "
            f"{'fully actuated' if self.fully_actuated else 'under-actuated'})"
        )


# ============================================================================== argument checks
def check_platform(platform, name: str = "platform") -> Platform:
    """``platform`` if it is a :class:`Platform`, else an :class:`InputError` naming ``name``."""
    if not isinstance(platform, Platform):
        raise InputError(f"{name} must be a qprr Platform (qprr.load, qprr.build, qprr.from_urdf), got {type(platform).__name__} {_short(platform)}")
    return platform


def check_data(platform: Platform, data, name: str = "data") -> pin.Data:
    """``data`` if it is a ``pin.Data`` of ``platform``'s model (from :meth:`Platform.data`), else a qprr error naming ``name``."""
    check_platform(platform)
    if not isinstance(data, pin.Data):
        raise InputError(f"{name} must be a pinocchio.Data from platform.data(), got {type(data).__name__} {_short(data)}")
    if len(data.oMf) != platform.model.nframes:
        raise ShapeError(
            f"{name} was made for another model ({len(data.oMf)} frames; platform {platform.name!r} has "
            f"{platform.model.nframes}): use platform.data()"
        )
    return data


def check_model_data(platform, data, name: str = "data") -> tuple[Platform, pin.Data]:
    """(platform, data) checked by :func:`check_platform` and :func:`check_data`: the first line of algorithms on (platform, data, ...)."""
    check_platform(platform)
    return platform, check_data(platform, data, name)


def _short(x) -> str:
    text = repr(x)
    return text if len(text) <= 60 else text[:57] + "..."


# ============================================================================== loading
def frame_id(model: pin.Model, name: str | int, what: str = "frame") -> int:
    """Frame id of ``name`` in ``model`` (or a valid id); :class:`UnknownNameError` lists the frames.

    ``what`` names the argument in the error (e.g. ``"ee_frame"``)."""
    if not isinstance(model, pin.Model):
        raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__} {_short(model)}")
    if isinstance(name, (int, np.integer)) and not isinstance(name, bool):
        if 0 <= name < model.nframes:
            return int(name)
        raise UnknownNameError(f"{what} (a frame id)", name, tuple(str(i) for i in range(model.nframes)))
    if isinstance(name, str) and model.existFrame(name):
        return model.getFrameId(name)
    raise UnknownNameError(what, name, tuple(f.name for f in model.frames))


def _arm_joints(model: pin.Model) -> tuple[ArmJoint, ...]:
    out = []
    for j in range(2, model.njoints):
        jm = model.joints[j]
        short = jm.shortname()
        name = model.names[j]
        if short in _REVOLUTE:
            kind = "revolute"
        elif short in _PRISMATIC:
            kind = "prismatic"
        elif short.startswith("JointModelRU") or short == "JointModelRevoluteUnboundedUnaligned":
            raise InputError(
                f"joint {name!r} is continuous (unbounded revolute, nq = 2): not supported as an arm joint yet; "
                "give it limits in the URDF (type revolute)"
            )
        else:
            raise InputError(f"joint {name!r} of type {short} is not supported as an arm joint (1-DOF prismatic or revolute only)")
        if model.parents[j] == 0:
            raise InputError(f"joint {name!r} hangs from the world, not from the multirotor")
        lo, hi = float(model.lowerPositionLimit[jm.idx_q]), float(model.upperPositionLimit[jm.idx_q])
        lo = -math.inf if lo <= -_HUGE else lo
        hi = math.inf if hi >= _HUGE else hi
        if not lo <= hi:
            raise InputError(f"joint {name!r}: lower limit {lo!r} is above the upper limit {hi!r}")
        eff = float(model.effortLimit[jm.idx_v])
        vel = float(model.velocityLimit[jm.idx_v])
        out.append(ArmJoint(name, kind, j, jm.idx_q, jm.idx_v, lo, hi, math.inf if eff >= _HUGE else eff, math.inf if vel >= _HUGE else vel))
    return tuple(out)


def _default_ee_frame(model: pin.Model, arm: Sequence[ArmJoint]) -> int:
    """The last frame on the last arm joint, when the arm is a chain (each joint on the previous one)."""
    if not arm:
        raise InputError("a platform without arm joints needs an explicit ee_frame")
    for k in range(1, len(arm)):
        if model.parents[arm[k].joint_id] != arm[k - 1].joint_id:
            names = [f.name for f in model.frames]
            raise UnknownNameError("ee_frame (the arm is a tree: name the end effector)", None, names)
    last = arm[-1].joint_id
    candidates = [i for i, f in enumerate(model.frames) if f.parentJoint == last]
    return candidates[-1]


def _base_frame(model: pin.Model) -> int:
    for i, f in enumerate(model.frames):
        if f.parentJoint == 1 and f.type == pin.FrameType.BODY and f.placement.isIdentity():
            return i
    raise InputError("no body frame on the free-flyer joint with identity placement (the URDF root link)")


def _resolve_rotors(model: pin.Model, base: int, rotors, rotor_source: str | None) -> tuple[Rotor, ...]:
    """The rotor tuple of :func:`from_model`: a mapping's frames resolved on ``model`` (errors prefixed with the file)."""
    try:
        if isinstance(rotors, Mapping):
            frames, moving, at_b = {}, {}, []
            data = model.createData()
            pin.framesForwardKinematics(model, data, pin.neutral(model))
            oMb = data.oMf[base]
            for i, f in enumerate(model.frames):
                if f.parentJoint > 1:  # on an arm link: not a place for a rotor
                    moving[f.name] = model.names[f.parentJoint]
                if f.parentJoint != 1:  # the world ("universe") or an arm link
                    continue
                bMf = oMb.actInv(data.oMf[i])
                frames[f.name] = (tuple(bMf.translation), tuple(bMf.rotation[:, 2]))
                if bMf.isIdentity(1e-12):
                    at_b.append(f.name)
            written_in = rotors.get("base_link")
            if isinstance(written_in, str) and written_in not in at_b:
                where = (
                    f"it moves with arm joint {moving[written_in]!r}"
                    if written_in in moving
                    else f"it is not a frame of {model.name!r}"
                    if written_in not in frames
                    else "it is not at B"
                )
                raise InputError(
                    f"base_link = {written_in!r}, but rotor positions are written in B, the frame of the URDF's root "
                    f"link {model.frames[base].name!r} (where qprr puts the free-flyer joint), and {where}; "
                    f"frames at B: {at_b} (is the multirotor body the root of your URDF?)"
                )
            for k, entry in enumerate(rotors.get("rotor") or ()):
                if isinstance(entry, Mapping) and entry.get("frame") in moving:
                    raise InputError(
                        f"rotor {k + 1}: frame {entry['frame']!r} moves with arm joint {moving[entry['frame']]!r}; "
                        f"rotors sit on the multirotor body, the URDF's root link {model.frames[base].name!r} "
                        "(is the body the root of your URDF?)"
                    )
            rotors = rotors_from_mapping(rotors, frames)
        elif isinstance(rotors, (str, Path)):
            raise InputError(f"rotors: a file path is read by from_urdf (or qprr.rotors.read_rotor_file); got {str(rotors)!r}")
        rotors = tuple(rotors)
        if not all(isinstance(r, Rotor) for r in rotors):
            raise InputError(f"rotors must be qprr.rotors.Rotor objects, got {_short(rotors)}")
    except (InputError, UnknownNameError) as exc:
        if rotor_source is not None:
            exc.within(f"rotor file {rotor_source!r}")
        raise
    return rotors


def from_model(
    model: pin.Model,
    rotors,
    *,
    ee_frame: str | int | None = None,
    ee_frames: Sequence[str | int] = (),
    name: str | None = None,
    params: object = None,
    provenance: Mapping[str, str] | None = None,
    allow_nonphysical: bool = False,
    urdf: str | None = None,
    rotor_source: str | None = None,
    plausibility=_PLAUSIBLE,
) -> Platform:
    """A :class:`Platform` on an existing free-flyer Pinocchio model (the model is copied, never modified).

    ``rotors``: a sequence of :class:`~qprr.rotors.Rotor`, or a rotor description mapping whose
    entries may name frames of ``model`` fixed to the base (see :func:`qprr.rotors.rotors_from_mapping`).
    ``allow_nonphysical=True`` skips the inertia checks (to study a printed, non-physical table:
    the provenance then says so); the mass matrix must still be positive definite.  ``urdf``: the
    URDF text ``model`` was read from, kept on the platform for its visual geometry.
    ``rotor_source``: the file the rotor description was read from, named in its errors.
    The rotors must be able to lift the platform (sum of f_max a_z >= m g), else
    :class:`~qprr.errors.NonPhysicalError` (the usual cause: masses in grams), and to hover and control
    attitude (:func:`qprr.rotors.check_rotor_set`), else :class:`~qprr.errors.ActuationError`.
    ``plausibility``: the ranges of the rotor values (:class:`qprr.urdf.plausibility.Plausibility`, None: no range check).
    """
    plausibility = check_plausibility_setting(plausibility)
    if not isinstance(model, pin.Model):
        raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__} {_short(model)}")
    if not (isinstance(rotors, Mapping) or (isinstance(rotors, Sequence) and not isinstance(rotors, str))):
        raise InputError(
            f"rotors must be a sequence of qprr.rotors.Rotor or a rotor description mapping, got {type(rotors).__name__} {_short(rotors)}"
        )
    model = pin.Model(model)
    if allow_nonphysical:
        provenance = {**(provenance or {}), "WARNING": "inertia checks skipped (allow_nonphysical=True): not a physical body set"}
    else:
        check_model_inertias(model)
    arm = _arm_joints(model)
    base = _base_frame(model)
    rotors_given = rotors
    rotors = _resolve_rotors(model, base, rotors, rotor_source)
    _check_rotor_ranges(rotors, plausibility, f"rotor file {rotor_source!r}" if rotor_source else "rotors")
    ee = _default_ee_frame(model, arm) if ee_frame is None else frame_id(model, ee_frame, "ee_frame")
    extra = tuple(frame_id(model, f, "ee_frames entry") for f in ee_frames)
    platform = Platform(
        name=name or model.name or "platform",
        model=model,
        base_frame=base,
        ee_frame=ee,
        arm=arm,
        rotors=tuple(rotors),
        ee_frames=(ee, *[f for f in extra if f != ee]),
        params=params,
        provenance=dict(provenance or {}),
        urdf=urdf,
        motor=_motor_table(rotors_given, rotor_source),
    )
    _check_mass_matrix(platform)
    _check_lift(platform, rotor_source)
    if platform.g > 0.0:  # g = 0: free flight, nothing to hover against
        source = f"rotor file {rotor_source!r}" if rotor_source else f"platform {platform.name!r}"
        _check_thrust_to_weight(platform, plausibility, source)
        check_rotor_set(platform.rotors, platform.total_mass * platform.g, platform.com_neutral_body, source)
        check_hover_solution(platform.rotors, platform.total_mass * platform.g, platform.com_neutral_body, source)
    return platform


def _motor_table(rotors, rotor_source: str | None) -> dict:
    """The ``[motor]`` table of a rotor description mapping (its values checked where the stage is built), else {}."""
    if not isinstance(rotors, Mapping) or "motor" not in rotors:
        return {}
    if not isinstance(rotors["motor"], Mapping):
        where = f"rotor file {rotor_source!r}: " if rotor_source else ""
        raise InputError(f"{where}[motor] must be a table (thrust_factor, time_constant, w_min, w_max), got {rotors['motor']!r}")
    return dict(rotors["motor"])


def _check_thrust_to_weight(platform: Platform, plausibility, source: str) -> None:
    """sum f_max a_z / (m g) within ``plausibility.thrust_to_weight_max`` (thrusts in grams-force give ~100x)."""
    if plausibility is None:
        return
    ratio = max_lift(platform) / (platform.total_mass * platform.g)
    if ratio > plausibility.thrust_to_weight_max:
        from .errors import PlausibilityError

        raise PlausibilityError(
            f"{source}: the rotors' thrust-to-weight ratio sum(f_max) / (m g) = {ratio:.4g} is outside the "
            f"plausible range for an aerial robot (<= {plausibility.thrust_to_weight_max:g}; racing drones reach "
            f"10-15): thrust bounds in grams-force? (f_max of rotor 1 = {platform.rotors[0].f_max:g} gf = "
            f"{platform.rotors[0].f_max * 9.80665e-3:.4g} N), or masses too small (m = {platform.total_mass:.6g} kg). "
            "If you mean it, pass plausibility=dataclasses.replace(qprr.urdf.plausibility.DEFAULT, thrust_to_weight_max=...)"
        )


def max_lift(platform: Platform) -> float:
    """The rotors' largest total thrust along z_B [N]: sum of f_max a_z over the rotors with a_z > 0 (a bound of what can
    be lifted; :meth:`Platform.actuation_summary` gives the exact hover margin)."""
    return float(sum(r.f_max * r.axis_body[2] for r in check_platform(platform).rotors if r.axis_body[2] > 0.0))


def check_flight(platform: Platform, source: str | None = None) -> None:
    """The load-time checks of a platform's physics, for a platform made another way (a payload, another model): the
    inertias (:func:`check_model_inertias`), the mass matrix, the lift (sum f_max a_z >= m g) and the rotor set's
    hover and attitude authority (:func:`qprr.rotors.check_rotor_set`).  ``source`` names what is checked in errors."""
    check_model_inertias(check_platform(platform).model)
    _check_mass_matrix(platform)
    _check_lift(platform, None)
    if platform.g > 0.0:  # g = 0: free flight, nothing to hover against
        check_rotor_set(platform.rotors, platform.total_mass * platform.g, platform.com_neutral_body, source or f"platform {platform.name!r}")


def _check_lift(platform: Platform, rotor_source: str | None) -> None:
    """The rotors' largest total thrust along z_B (sum f_max a_z over a_z > 0) must reach m g (a necessary condition)."""
    lift = max_lift(platform)
    weight = platform.total_mass * platform.g
    if lift < weight:
        rot = f"rotor file {rotor_source!r}" if rotor_source else "the rotor set"
        model = platform.model
        j = max(range(1, model.njoints), key=lambda k: model.inertias[k].mass)
        links = [f.name for f in model.frames if f.parentJoint == j and f.type == pin.FrameType.BODY]
        raise NonPhysicalError(
            f"platform {platform.name!r} cannot lift itself: its rotors push at most {lift:.6g} N along z_B "
            f"({rot}), its weight m g is {weight:.6g} N (m = {platform.total_mass:.6g} kg, g = {platform.g:.6g} m/s^2); "
            f"the heaviest body: link {' + '.join(map(repr, links))} ({model.inertias[j].mass:.6g} kg); "
            "URDF masses are in kg (grams / 1000), thrust bounds in N"
        )


def _check_mass_matrix(platform: Platform) -> None:
    """The joint-space inertia must be positive definite (no massless actuated subtree)."""
    model = platform.model
    data = model.createData()
    M = pin.crba(model, data, platform.neutral_q())
    M = np.triu(M) + np.triu(M, 1).T
    try:
        np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        diag = np.diag(M)
        k = int(np.argmin(diag[6:])) if platform.n_arm else None
        which = f"arm joint {platform.arm[k].name!r} moves no mass" if k is not None and diag[6 + k] <= 0 else "the inertia is degenerate"
        raise NonPhysicalError(f"platform {platform.name!r}: the mass matrix is not positive definite ({which})") from None


def from_urdf(
    urdf: str | Path,
    rotors,
    *,
    ee_frame: str | int | None = None,
    ee_frames: Sequence[str | int] = (),
    g: float = 9.81,
    name: str | None = None,
    params: object = None,
    provenance: Mapping[str, str] | None = None,
    allow_nonphysical: bool = False,
    plausibility=_PLAUSIBLE,
    inertials: str | Path | None = None,
) -> Platform:
    """A :class:`Platform` from a URDF (a path, or the XML text) and a rotor description.

    The URDF is read once and checked first (:func:`qprr.urdf.reader.read_urdf`: its structure, names, numbers, axes
    and limits, every physical value against ``plausibility`` (:class:`qprr.urdf.plausibility.Plausibility`; None: no
    range check), the serial arm, and the inertials, which Pinocchio's parser drops silently when malformed), then the
    model is built with a free-flyer root and gravity -g e3 (g >= 0; 0 for free flight).  ``rotors``: a sequence of
    :class:`~qprr.rotors.Rotor`, a rotor description mapping, or the path of a TOML rotor file
    (:func:`qprr.rotors.read_rotor_file`).  ``ee_frame`` defaults to the last frame of the last arm joint of a serial
    arm.  ``allow_nonphysical=True`` skips the inertial checks (and the model's, :func:`from_model`).  ``inertials``: a TOML file of
    inertial overrides (:func:`qprr.urdf.inertia.read_inertials`, e.g. written by ``qprr log identify --write-inertials``)
    applied to the model before its checks (:func:`apply_inertials`).
    """
    from .validation import as_real

    text, source = _urdf_text(urdf)
    g = as_real(g, "g", nonnegative=True, unit="m/s^2")  # g = 0: free flight (conservation tests)
    plausibility = check_plausibility_setting(plausibility)
    read_urdf(text, source, plausibility=plausibility, inertials=not allow_nonphysical)
    try:
        model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    except ValueError as exc:  # urdfdom prints its reason on stderr
        raise InputError(f"{source}: Pinocchio's URDF parser rejected it ({exc})") from exc
    model.gravity = pin.Motion(np.array([0.0, 0.0, -float(g)]), np.zeros(3))
    if inertials is not None:
        model = apply_inertials(model, read_inertials(inertials), f"inertials {Path(inertials).name}")
    rotor_source = None
    if isinstance(rotors, (str, Path)):
        from .rotors import read_rotor_file
        from .validation import as_file

        rotor_source = str(rotors)
        if Path(rotors).suffix.lower() != ".toml":
            raise InputError(f"rotors: a rotor description file must be a .toml file, got {rotor_source!r}")
        rotors = read_rotor_file(as_file(rotors, "rotors", what="rotor description file"))
    prov = {"model": source, **(provenance or {})}
    if rotor_source is not None:
        prov.setdefault("rotors", rotor_source)
    if inertials is not None:
        prov["inertials"] = str(inertials)
    return from_model(
        model,
        rotors,
        ee_frame=ee_frame,
        ee_frames=ee_frames,
        name=name or model.name,
        params=params,
        provenance=prov,
        allow_nonphysical=allow_nonphysical,
        urdf=text,
        rotor_source=rotor_source,
        plausibility=plausibility,
    )


def apply_inertials(model: pin.Model, overrides: Mapping[str, Mapping], source: str = "inertials") -> pin.Model:
    """A copy of ``model`` with the inertial ``overrides`` ({link: {"mass", "com", "inertia"}},
    :func:`qprr.urdf.inertia.read_inertials`) applied: each names a link a joint moves (its frame is the joint's; a link
    fixed to another is merged into it by Pinocchio's parser: give the values of that one); the values replace the
    moving body's (the link and what is fixed to it), the others are kept (the centre of mass in the link's frame, the
    inertia about it in the link's axes).  Unknown links raise :class:`~qprr.errors.UnknownNameError`, a body that
    cannot exist :class:`~qprr.errors.NonPhysicalError` naming the link and the value."""
    model = pin.Model(model)
    moving = {}
    for f in model.frames:
        if f.type == pin.FrameType.BODY and f.parentJoint > 0 and f.placement.isIdentity() and f.parentJoint not in moving.values():
            moving[f.name] = f.parentJoint
    for name, values in overrides.items():
        if name not in moving:
            raise UnknownNameError(f"link of {source}", name, tuple(moving))
        j = moving[name]
        Y = model.inertias[j]
        mass = values.get("mass", float(Y.mass))
        com = np.asarray(values.get("com", np.array(Y.lever)), dtype=float)
        inertia = inertia_matrix(values["inertia"]) if "inertia" in values else np.array(Y.inertia)
        check_rigid_body(f"{source}: link {name!r}", mass, com, inertia)
        model.inertias[j] = pin.Inertia(mass, com, inertia)
    return model


def _urdf_text(urdf: str | Path) -> tuple[str, str]:
    from .validation import as_file

    if isinstance(urdf, Path) or (isinstance(urdf, str) and not urdf.lstrip().startswith("<")):
        path = as_file(urdf, "urdf", what="URDF file")
        try:
            return path.read_text(), str(path)
        except UnicodeDecodeError as exc:
            raise InputError(f"urdf: URDF file {str(path)!r} is not text (XML): {exc}") from None
    if isinstance(urdf, str):
        return urdf, "URDF text"
    raise InputError(f"urdf must be a path or the URDF XML text, got {type(urdf).__name__} {_short(urdf)}")
