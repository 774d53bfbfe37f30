"""Modified Denavit-Hartenberg chains (Khalil-Kleinfinger convention), Thesis (3.27)-(3.30).

Row j of a table places frame R_j in frame R_(j-1) with four parameters:

    ^(j-1)T_j = Rot(x, alpha_j) Trans(x, d_j) Rot(z, theta_j) Trans(z, r_j)        Thesis (3.27)

(alpha_j [rad] about x_(j-1), d_j [m] along x_(j-1), theta_j [rad] about z_j, r_j [m]
along z_j).  Joint j moves along or about z_j: q_j adds to theta_j when it is revolute
(sigma_j = 0) and to r_j when it is prismatic (sigma_j = 1) (Thesis Remark 1,
q_j = (1 - sigma_j) theta_j + sigma_j r_j).  A row with ``joint=False`` is a constant
transform (the last row of Table 3.4, whose theta is the constant 0).

The chain is ^bT_j = ^bT_0 ^0T_1 ... ^(j-1)T_j (3.29); a constant base transform ^bT_0 and
tool transform ^nT_f close it as in (3.30).  :func:`chain` evaluates it with numpy,
:func:`build_model` turns the same table into a fixed-base Pinocchio model (kinematics
only: its bodies are massless) so that Pinocchio's Jacobians can be compared too.

The thesis's own table, transforms and their misprints are in :mod:`qprr.thesis.printed`
(``table_3_4``, ``mdh_3_28``, ``T_b0_3_49``...); this module only implements the
convention.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..charts import rot_x, rot_z
from ..errors import InputError, ShapeError
from ..validation import as_array, as_real, as_vector, checked_module

SIGMAS = (0, 1)
"""sigma of a row: 0 revolute (the variable is theta), 1 prismatic (the variable is r)."""


@dataclass(frozen=True)
class MDHRow:
    """One row of a modified Denavit-Hartenberg table (Khalil-Kleinfinger).

    ``alpha`` [rad], ``d`` [m], ``theta`` [rad], ``r`` [m] are the constant parts; with
    ``joint=True`` the joint value is added to ``theta`` (sigma = 0) or ``r`` (sigma = 1).
    """

    sigma: int
    alpha: float
    d: float
    theta: float
    r: float
    joint: bool = True

    def __post_init__(self) -> None:
        if isinstance(self.sigma, bool) or self.sigma not in SIGMAS:
            raise InputError(f"sigma must be 0 (revolute) or 1 (prismatic), got {self.sigma!r}")
        if not isinstance(self.joint, bool):
            raise InputError(f"joint must be True (a joint row) or False (a constant transform), got {self.joint!r}")
        for name in ("alpha", "d", "theta", "r"):
            value = getattr(self, name)
            try:
                x = float(value)
            except (TypeError, ValueError):
                x = math.nan
            if not math.isfinite(x):
                raise InputError(f"MDH parameter {name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, x)

    def parameters(self, q: float = 0.0) -> tuple[float, float, float, float]:
        """(alpha, d, theta, r) at joint value ``q`` (ignored when ``joint`` is False), Thesis Remark 1."""
        q = as_real(q, "q")
        theta, r = self.theta, self.r
        if self.joint:
            if self.sigma == 0:
                theta += float(q)
            else:
                r += float(q)
        return self.alpha, self.d, theta, r

    def transform(self, q: float = 0.0) -> np.ndarray:
        """^(j-1)T_j (4x4) at joint value ``q``, Thesis (3.27)."""
        return kk_transform(*self.parameters(q))


def _homogeneous(R=None, p=None) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[0:3, 0:3] = R
    if p is not None:
        T[0:3, 3] = p
    return T


def kk_transform(alpha: float, d: float, theta: float, r: float) -> np.ndarray:
    """Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r) (4x4), Thesis (3.27).

    Evaluated as the product of the four elementary transforms, which is what (3.27)
    states; :func:`qprr.thesis.printed.mdh_3_28` is the closed form printed as (3.28).
    """
    return _homogeneous(R=rot_x(alpha)) @ _homogeneous(p=(d, 0.0, 0.0)) @ _homogeneous(R=rot_z(theta)) @ _homogeneous(p=(0.0, 0.0, r))


def _check_rows(rows: Sequence[MDHRow]) -> tuple[MDHRow, ...]:
    if isinstance(rows, (str, bytes)) or not isinstance(rows, Iterable):
        raise InputError(f"rows must be a non-empty sequence of MDHRow, got {rows!r}")
    rows = tuple(rows)
    if not rows or not all(isinstance(row, MDHRow) for row in rows):
        raise InputError(f"rows must be a non-empty sequence of MDHRow, got {rows!r}")
    return rows


def _check_transform(T, name: str) -> np.ndarray:
    if T is None:
        return np.eye(4)
    T = as_array(T, name)
    if T.shape != (4, 4):
        raise ShapeError(f"{name} must be a 4x4 homogeneous transform, got shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise InputError(f"{name} must be finite, got {T.tolist()}")
    R = T[0:3, 0:3]
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-9 or np.linalg.det(R) < 0 or np.abs(T[3] - [0, 0, 0, 1]).max() > 0:
        raise InputError(f"{name} must be a rigid transform (rotation block orthonormal with det +1, last row 0 0 0 1)")
    return T


def n_joints(rows: Sequence[MDHRow]) -> int:
    """Number of joint variables of a table (rows with ``joint=True``)."""
    return sum(row.joint for row in _check_rows(rows))


def chain(
    rows: Sequence[MDHRow], q, base=None, tool=None, *, transform: Callable[[float, float, float, float], np.ndarray] = kk_transform
) -> list[np.ndarray]:
    """[^bT_1, ..., ^bT_n] (and ^bT_f last when ``tool`` is given), Thesis (3.29)-(3.30).

    ``q`` holds one value per joint row, in table order [m or rad]; ``base`` = ^bT_0 and
    ``tool`` = ^nT_f are constant 4x4 transforms (identity when None).  ``transform(alpha,
    d, theta, r)`` gives one link transform: (3.27) by default; pass another closed form
    (e.g. :func:`qprr.thesis.printed.mdh_3_28`) to see what it does to the chain.
    """
    rows = _check_rows(rows)
    q = as_vector(q, n_joints(rows), "q")
    if not callable(transform):
        raise InputError(f"transform must be callable (alpha, d, theta, r) -> 4x4, got {transform!r}")
    T = _check_transform(base, "base")
    out = []
    k = 0
    for row in rows:
        T = T @ np.asarray(transform(*row.parameters(q[k] if row.joint else 0.0)), dtype=float)
        k += row.joint
        out.append(T)
    if tool is not None:
        out.append(T @ _check_transform(tool, "tool"))
    return out


def frame_name(j: int) -> str:
    """Name of the frame R_j in :func:`build_model` (j = 1..n)."""
    return f"R{j}"


TOOL_FRAME = "tool"


def build_model(rows: Sequence[MDHRow], base=None, tool=None) -> pin.Model:
    """A fixed-base Pinocchio model of the table: joint j about/along z_j, frames ``R1``..``Rn`` and ``tool``.

    Joint rows become ``JointModelRZ`` (sigma = 0) or ``JointModelPZ`` (sigma = 1) placed by
    ^bT_0 and the constant part of (3.27); constant rows become operational frames.  The
    configuration vector is the joint values in table order (nq = nv = number of joint rows).
    The bodies are massless: the model is for kinematics (placements, Jacobians).
    """
    rows = _check_rows(rows)
    placement = pin.SE3(_check_transform(base, "base"))
    tool_T = pin.SE3(_check_transform(tool, "tool"))
    model = pin.Model()
    model.name = "mdh"
    parent_joint, parent_frame = 0, 0
    for j, row in enumerate(rows, start=1):
        placement = placement * pin.SE3(row.transform())
        if row.joint:
            joint_model = pin.JointModelRZ() if row.sigma == 0 else pin.JointModelPZ()
            parent_joint = model.addJoint(parent_joint, joint_model, placement, f"q{j}")
            model.appendBodyToJoint(parent_joint, pin.Inertia.Zero(), pin.SE3.Identity())
            parent_frame = model.addJointFrame(parent_joint, parent_frame)
            placement = pin.SE3.Identity()
            parent_frame = model.addFrame(pin.Frame(frame_name(j), parent_joint, parent_frame, placement, pin.FrameType.BODY))
        else:
            parent_frame = model.addFrame(pin.Frame(frame_name(j), parent_joint, parent_frame, placement, pin.FrameType.OP_FRAME))
    model.addFrame(pin.Frame(TOOL_FRAME, parent_joint, parent_frame, placement * tool_T, pin.FrameType.OP_FRAME))
    return model


checked_module(globals())
