"""A wheeled robot as a set of wheels on a chassis: Pfaffian matrix, kernel, ICR, manoeuvrability.

Lecture: "Contraintes de non-glissement et de roulement pur", "Manœuvrabilité d'un robot".

Configuration (posture level, the lecture's q for the unicycle, tricycle and car):
q = [x, y, theta, sigma_1, ..., sigma_ns] with (x, y) the origin O_R of the robot frame in
the world [m], theta its heading [rad] and sigma the steering coordinates of the centred
steerable wheels [rad] (one per wheel, or fewer when a linkage couples them: the car's
Ackermann pair is driven by the single angle of the virtual central wheel).

With xi_R = R^T(theta) q_dot_I the no-slip constraints of the fixed and centred steerable
wheels read C1*(beta_s) R^T(theta) q_dot_I = 0 (castors and Swedish wheels never constrain
the posture: their own free rates absorb any chassis motion).  Their Pfaffian form is
A^T(q) q_dot = 0 with A^T = [C1* R^T(theta), 0] (:meth:`WheeledRobot.pfaffian`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..charts import rot_z, wrap_angle
from ..errors import InputError
from ..validation import as_real, as_vector
from ._backend import is_symbolic, matrix
from .wheels import Wheel, WheelKind

RANK_TOL = 1e-9
"""Singular values below RANK_TOL (matrices with O(1) entries) count as zero."""


def rotation(theta, m=math):
    """Lecture: R(theta), the elementary rotation about z of the "Manœuvrabilité : préliminaires" slide.

    Numeric: :func:`qprr.charts.rot_z`; symbolic: the same matrix in sympy.
    """
    if not is_symbolic(m):
        return rot_z(float(theta))
    c, s = m.cos(theta), m.sin(theta)
    return m.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rank(M, tol: float = RANK_TOL) -> int:
    """Numerical rank of M (0 for an empty matrix)."""
    M = np.atleast_2d(np.asarray(M, dtype=float))
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int(np.count_nonzero(s > tol * max(1.0, s[0])))


def kernel(M, n: int | None = None, tol: float = RANK_TOL) -> np.ndarray:
    """Orthonormal basis (columns) of ker M; M with n columns (n needed when M has no rows)."""
    M = np.asarray(M, dtype=float)
    if M.size == 0:
        return np.eye(n if n is not None else M.shape[1])
    _, s, Vt = np.linalg.svd(M)
    r = int(np.count_nonzero(s > tol * max(1.0, s[0])))
    return Vt[r:].T.copy()


def wheel_at(kind: type, x: float, y: float, r: float, heading: float = 0.0, **kw) -> Wheel:
    """A wheel whose contact point (or steering axis) is at (x, y) in the robot frame [m].

    alpha, ell are the polar coordinates of (x, y); beta (or beta0 for steerable wheels) is
    chosen so that the wheel rolls along ``heading`` (rad, robot frame; 0 = along x_R) for a
    zero steering angle: beta = pi/2 + heading - alpha.  A wheel at the origin gets
    alpha = pi/2 (the lecture's Remark 2).  E.g. the lecture's Example 1 right wheel
    (alpha = -pi/2, beta = pi, returned as -pi) is ``wheel_at(FixedWheel, 0, -L, r)``.
    """
    ell = math.hypot(x, y)
    alpha = math.atan2(y, x) if ell > 0.0 else math.pi / 2
    beta = float(wrap_angle(math.pi / 2 + heading - alpha))
    if kind.__name__ in ("CentredSteerableWheel", "OffCentredSteerableWheel"):
        return kind(alpha=alpha, ell=ell, r=r, beta0=beta, **kw)
    return kind(alpha=alpha, beta=beta, ell=ell, r=r, **kw)


# ---------------------------------------------------------------------------- steering linkages
@dataclass(frozen=True)
class AckermannSteering:
    """Ackermann linkage of two front wheels driven by the angle psi of a virtual central wheel.

    Lecture: "Ackermann": cot psi_o - cot psi_i = 2L/D and cot psi_tr = cot psi_i + L/D =
    cot psi_o - L/D, with D the wheelbase (rear axle to front axle) and 2L the front track.
    For psi > 0 (turning left) the inner wheel is the left one.  Returns (psi_left, psi_right):
    psi_left = atan2(D sin psi, D cos psi - L sin psi), psi_right = atan2(D sin psi, D cos psi + L sin psi)
    (the cotangent relations written without dividing by sin psi, so psi = 0 is regular).
    """

    D: float
    L: float
    names: tuple[str, ...] = ("psi",)
    description: str = "Ackermann linkage driven by the virtual central wheel's angle psi"

    def __post_init__(self) -> None:
        object.__setattr__(self, "D", as_real(self.D, "D (wheelbase)", positive=True, unit="m"))
        object.__setattr__(self, "L", as_real(self.L, "L (half front track)", positive=True, unit="m"))

    def __call__(self, sigma, m=math) -> tuple:
        psi = sigma[0]
        D, L = self.D, self.L
        if is_symbolic(m):
            from ._backend import exact

            D, L = exact(D, m), exact(L, m)
        s, c = m.sin(psi), m.cos(psi)
        return (m.atan2(D * s, D * c - L * s), m.atan2(D * s, D * c + L * s))


@dataclass(frozen=True)
class NamedSteering:
    """Each centred steerable wheel has its own steering coordinate, under the given names (e.g. the
    tricycle's front wheel is steered by ``psi``)."""

    names: tuple[str, ...]
    description: str = "one steering coordinate per steerable wheel"

    def __call__(self, sigma, m=math) -> tuple:
        return tuple(sigma)


@dataclass(frozen=True)
class SynchroSteering:
    """All centred steerable wheels turned together by one belt: every wheel gets the angle sigma[0]."""

    n_wheels: int
    names: tuple[str, ...] = ("beta",)
    description: str = "synchro drive: one steering angle for every wheel"

    def __call__(self, sigma, m=math) -> tuple:
        return tuple(sigma[0] for _ in range(self.n_wheels))


# ---------------------------------------------------------------------------- results
class MobilityStatus(str, Enum):
    ADMISSIBLE = "admissible"
    NOT_ADMISSIBLE = "not admissible"
    IMMOBILE = "immobile"


@dataclass(frozen=True)
class Mobility:
    """Degrees of mobility, steerability and manoeuvrability at one steering configuration.

    ``delta_m = 3 - rank C1*(beta_s)``; ``delta_s``: chassis degrees of freedom moved through
    the steering, the rank of d(ker C1*)/d sigma (equal to the lecture's rank C1s(beta_s) when
    every steerable wheel has its own steering angle, see ``rank_C1s``); ``delta_M =
    delta_m + delta_s``; ``type = (delta_m, delta_s)`` and whether it is one of the five
    admissible types (computed by :func:`admissible_types`).
    """

    delta_m: int
    delta_s: int
    delta_M: int
    rank_C1s: int
    type: tuple[int, int]
    status: MobilityStatus
    reason: str


class ICRStatus(str, Enum):
    UNIQUE = "unique"
    AT_INFINITY = "at infinity"
    LINE = "on a line"
    ANYWHERE = "anywhere"
    NONE = "none"


@dataclass(frozen=True)
class ICR:
    """Instantaneous centre of rotation.  ``point_R``: robot frame [m] (``point_I``: world frame,
    when the pose was given); ``direction``: the translation direction (ICR at infinity) or
    the line's direction (ICR on a line, through ``point_R``), robot frame."""

    status: ICRStatus
    point_R: np.ndarray | None
    point_I: np.ndarray | None
    direction: np.ndarray | None
    reason: str


def admissible_types() -> list[tuple[int, int]]:
    """The five admissible types (delta_m, delta_s), enumerated from the lecture's conditions.

    a) 1 <= delta_m <= 3; b) 0 <= delta_s <= 2; c) 2 <= delta_m + delta_s <= 3; and
    delta_s <= 3 - delta_m (the rows of C1s are rows of C1*, so rank C1s <= rank C1*).
    Lecture: "Manœuvrabilité d'un robot" (table of the five couples).
    """
    out = [(dm, ds) for dm in range(3, -1, -1) for ds in range(4) if 1 <= dm <= 3 and 0 <= ds <= 2 and 2 <= dm + ds <= 3 and ds <= 3 - dm]
    return out


# ---------------------------------------------------------------------------- the robot
@dataclass(frozen=True)
class WheeledRobot:
    """Wheels on a rigid chassis (robot frame at O_R).

    ``steering``: a linkage mapping the steering coordinates sigma to one angle per centred
    steerable wheel (None: each such wheel has its own coordinate ``<wheel name>``).
    """

    name: str
    wheels: tuple[Wheel, ...]
    steering: Callable | None = None
    _fixed_rows: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not self.wheels:
            raise InputError(f"robot {self.name!r} needs at least one wheel")
        for w in self.wheels:
            if not isinstance(w, Wheel):
                raise InputError(f"robot {self.name!r}: wheels must be Wheel objects, got {type(w).__name__}")
        n_s = len(self.steered_wheels)
        if self.steering is not None:
            probe = self.steering([0.1] * len(self.steering.names))
            if len(probe) != n_s:
                raise InputError(f"robot {self.name!r}: the steering linkage returns {len(probe)} angles for {n_s} steerable wheels")
        # Independent no-slip rows of the fixed wheels (constant): two wheels on one axle give
        # the same row, kept once so that A has independent columns where the lecture's has.
        rows: list[int] = []
        for i, w in enumerate(self.wheels):
            if w.kind is WheelKind.FIXED:
                trial = [self.wheels[j].no_slip().xi for j in rows] + [w.no_slip().xi]
                if rank(np.array(trial, dtype=float)) == len(trial):
                    rows.append(i)
        object.__setattr__(self, "_fixed_rows", tuple(rows))

    # ------------------------------------------------------------ bookkeeping
    @property
    def fixed_wheels(self) -> tuple[Wheel, ...]:
        return tuple(w for w in self.wheels if w.kind is WheelKind.FIXED)

    @property
    def steered_wheels(self) -> tuple[Wheel, ...]:
        """Centred steerable wheels, in order (their angles are beta_s)."""
        return tuple(w for w in self.wheels if w.kind is WheelKind.CENTRED_STEERABLE)

    @property
    def steering_names(self) -> tuple[str, ...]:
        if self.steering is not None:
            return tuple(self.steering.names)
        return tuple(w.name for w in self.steered_wheels)

    @property
    def coordinates(self) -> tuple[str, ...]:
        """Names of q at posture level: x, y, theta, then the steering coordinates."""
        return ("x", "y", "theta") + self.steering_names

    @property
    def n_steering(self) -> int:
        return len(self.steering_names)

    def _sigma(self, sigma) -> np.ndarray:
        if sigma is None:
            sigma = generic_steering(self.n_steering)
        return as_vector(sigma, self.n_steering, f"steering coordinates {self.steering_names} of {self.name!r}")

    def steering_angles(self, sigma, m=math) -> tuple:
        """Steering coordinate s of each centred steerable wheel (beta = beta0 + s)."""
        if self.steering is not None:
            return tuple(self.steering(sigma, m))
        return tuple(sigma)

    # ------------------------------------------------------------ lecture matrices
    def C1f(self, m=math):
        """Lecture: C1f (N_f x 3), the no-slip rows of the fixed wheels (all of them)."""
        return matrix([list(w.no_slip(0.0, m).xi) for w in self.fixed_wheels], m) if self.fixed_wheels else _empty(m)

    def C1s(self, sigma=None, m=math):
        """Lecture: C1s(beta_s) (N_s x 3), the no-slip rows of the centred steerable wheels."""
        if not self.steered_wheels:
            return _empty(m)
        sig = self._sigma(sigma) if not is_symbolic(m) else sigma
        angles = self.steering_angles(sig, m)
        return matrix([list(w.no_slip(s, m).xi) for w, s in zip(self.steered_wheels, angles)], m)

    def C1_star(self, sigma=None, m=math):
        """Lecture: C1*(beta_s) = [C1f; C1s(beta_s)]."""
        f, s = self.C1f(m), self.C1s(sigma, m)
        if is_symbolic(m):
            return f.col_join(s) if f.rows and s.rows else (f if f.rows else s)
        return np.vstack([f.reshape(-1, 3), s.reshape(-1, 3)])

    def J1(self, sigma=None, castor_angles=None, m=math):
        """Lecture: J1(beta_so) (N x 3), the rolling rows of the standard wheels (fixed, centred
        steerable, castors; in that order).  ``castor_angles``: one per castor (default 0)."""
        sig = self._sigma(sigma) if not is_symbolic(m) else sigma
        angles = self.steering_angles(sig, m)
        castors = [w for w in self.wheels if w.kind is WheelKind.OFF_CENTRED_STEERABLE]
        cast = [0.0] * len(castors) if castor_angles is None else list(castor_angles)
        if len(cast) != len(castors):
            raise InputError(f"castor_angles: {len(castors)} castors on {self.name!r}, got {len(cast)} angles")
        rows = [list(w.rolling(0.0, m).xi) for w in self.fixed_wheels]
        rows += [list(w.rolling(s, m).xi) for w, s in zip(self.steered_wheels, angles)]
        rows += [list(w.rolling(s, m).xi) for w, s in zip(castors, cast)]
        return matrix(rows, m)

    def J2(self) -> np.ndarray:
        """Lecture: J2 = diag(r_1, ..., r_N) over the standard wheels, in the order of :meth:`J1`."""
        order = (
            [w for w in self.wheels if w.kind is WheelKind.FIXED]
            + list(self.steered_wheels)
            + [w for w in self.wheels if w.kind is WheelKind.OFF_CENTRED_STEERABLE]
        )
        return np.diag([w.r for w in order])

    # ------------------------------------------------------------ Pfaffian form
    def pfaffian(self, q, m=math):
        """A(q) (n x k) of the posture-level constraints A^T(q) q_dot = 0.

        Columns: the independent no-slip rows of the fixed wheels, then one per centred
        steerable wheel, each times R^T(theta), with zeros on the steering rates.
        For the tricycle this is the lecture's A (slide "forme pfaffienne").
        """
        n = 3 + self.n_steering
        if is_symbolic(m):
            theta, sigma = q[2], list(q[3:])
        else:
            qv = as_vector(q, n, f"q of {self.name!r} {self.coordinates}")
            theta, sigma = qv[2], qv[3:]
        angles = self.steering_angles(sigma, m)
        rows = [list(self.wheels[i].no_slip(0.0, m).xi) for i in self._fixed_rows]
        rows += [list(w.no_slip(s, m).xi) for w, s in zip(self.steered_wheels, angles)]
        if not rows:
            return _empty(m, n)
        C = matrix(rows, m)
        Rt = rotation(theta, m).T
        posture = C * Rt if is_symbolic(m) else C @ Rt
        if is_symbolic(m):
            At = posture.row_join(m.zeros(len(rows), self.n_steering)) if self.n_steering else posture
            return At.T
        At = np.hstack([posture, np.zeros((len(rows), self.n_steering))])
        return At.T

    def velocity_basis(self, q) -> np.ndarray:
        """Orthonormal basis of ker A^T(q) (columns; numeric SVD, not smooth in q).

        The named kinematic models of :mod:`qprr.wheeled.robots` give smooth bases B(q);
        both span the same space (tested).
        """
        A = self.pfaffian(q)
        return kernel(A.T, n=3 + self.n_steering)

    # ------------------------------------------------------------ manoeuvrability
    def twist_basis(self, sigma=None) -> np.ndarray:
        """Orthonormal basis (3 x delta_m) of the admissible chassis twists xi_R, ker C1*(beta_s)."""
        return kernel(self.C1_star(sigma), n=3)

    def mobility(self, sigma=None, *, step: float = 1e-6, tol: float = 1e-6) -> Mobility:
        """delta_m, delta_s, delta_M and the type at steering coordinates ``sigma``.

        Lecture: delta_m = 3 - rank C1*(beta_s), delta_s = rank C1s(beta_s), delta_M =
        delta_m + delta_s, and the five admissible types.  ``sigma=None`` evaluates at a
        generic steering configuration (:func:`generic_steering`): the degrees are generic
        ranks, a special steering angle can lower them.  delta_s is computed as the number
        of independent directions in which the steering moves ker C1* (central differences
        of its orthogonal projector, step ``step``, rank tolerance ``tol``); with independent
        steering angles it equals rank C1s (both are reported).
        """
        sig = self._sigma(sigma)
        dm = 3 - rank(self.C1_star(sig))
        rank_c1s = rank(self.C1s(sig)) if self.steered_wheels else 0
        ds = 0
        if self.n_steering and 0 < dm < 3:
            P0 = _projector(self.twist_basis(sig))
            cols = []
            for j in range(self.n_steering):
                e = np.zeros(self.n_steering)
                e[j] = step
                Pp, Pm = _projector(self.twist_basis(sig + e)), _projector(self.twist_basis(sig - e))
                if Pp.shape != P0.shape or Pm.shape != P0.shape:
                    raise InputError(f"steering {sig.tolist()} of {self.name!r} is not generic: delta_m changes nearby")
                cols.append(((Pp - Pm) / (2 * step)).ravel())
            ds = rank(np.array(cols).T, tol=tol)
        t = (dm, ds)
        if dm == 0:
            status, reason = MobilityStatus.IMMOBILE, "rank C1* = 3: the wheel axes have no common point, no motion is possible"
        elif t in admissible_types():
            status, reason = MobilityStatus.ADMISSIBLE, f"type ({dm}, {ds})"
        else:
            status, reason = (
                MobilityStatus.NOT_ADMISSIBLE,
                f"({dm}, {ds}) violates the lecture's conditions (delta_M = {dm + ds} < 2)"
                if dm + ds < 2
                else f"({dm}, {ds}) is not one of the five admissible types",
            )
        return Mobility(dm, ds, dm + ds, rank_c1s, t, status, reason)

    def icr(self, sigma=None, twist=None, pose=None, *, tol: float = 1e-9) -> ICR:
        """Instantaneous centre of rotation from the wheel axes.

        Lecture: "Centre instantané de rotation": the point where the axes of the wheels
        meet.  A point p (robot frame) is the ICR of a rotation iff that rotation, the twist
        (p_y, -p_x, 1), satisfies every no-slip row: C1* (p_y, -p_x, 1) = 0, i.e. p lies on
        every wheel axis.  With ``twist`` = xi_R given, the ICR of that motion; otherwise the
        set allowed by the wheels: unique (delta_m = 1), a line (delta_m = 2, e.g. the
        unicycle's axle), anywhere (delta_m = 3) or none (delta_m = 0).  ``pose`` = (x, y,
        theta) adds the world-frame point.
        """
        sig = self._sigma(sigma)
        N = self.twist_basis(sig)
        if twist is not None:
            tw = as_vector(twist, 3, "twist")
            if N.shape[1] < 3 and np.linalg.norm(tw - N @ (N.T @ tw)) > 1e-9 * max(1.0, np.linalg.norm(tw)):
                raise InputError(f"twist {tw.tolist()} violates the no-slip constraints of {self.name!r}")
            return _icr_of_twist(tw, pose, tol)
        k = N.shape[1]
        if k == 0:
            return ICR(ICRStatus.NONE, None, None, None, "rank C1* = 3: no admissible motion, the wheel axes do not meet")
        if k == 1:
            return _icr_of_twist(N[:, 0], pose, tol)
        if k == 3:
            return ICR(ICRStatus.ANYWHERE, None, None, None, "no posture constraint: the inputs place the ICR anywhere")
        n = np.cross(N[:, 0], N[:, 1])  # normal of the 2-D kernel: n . (p_y, -p_x, 1) = 0
        a, b = -n[1], n[0]  # a p_x + b p_y = -n[2]
        nn = math.hypot(a, b)
        if nn < tol:
            return ICR(ICRStatus.AT_INFINITY, None, None, None, "only rotations about no finite point: the ICR line is at infinity")
        p0 = -n[2] * np.array([a, b]) / nn**2
        direction = np.array([-b, a]) / nn
        return ICR(
            ICRStatus.LINE, p0, _to_world(p0, pose), direction, "delta_m = 2: the ICR lies on this line (the common wheel axis), placed by the inputs"
        )


def _empty(m, n: int = 3):
    return m.zeros(0, n) if is_symbolic(m) else np.zeros((0, n))


def _projector(N: np.ndarray) -> np.ndarray:
    return N @ N.T


def _to_world(p, pose):
    if pose is None or p is None:
        return None
    x, y, th = as_vector(pose, 3, "pose")
    return np.array([x, y]) + rot_z(th)[:2, :2] @ p


def _icr_of_twist(tw, pose, tol) -> ICR:
    vx, vy, w = tw
    speed = math.hypot(vx, vy)
    if abs(w) <= tol * max(1.0, speed):
        d = np.array([vx, vy]) / speed if speed > 0 else None
        return ICR(ICRStatus.AT_INFINITY, None, None, d, "pure translation: the ICR is at infinity")
    p = np.array([-vy / w, vx / w])
    return ICR(ICRStatus.UNIQUE, p, _to_world(p, pose), None, "unique ICR")


def generic_steering(n: int) -> np.ndarray:
    """A fixed, generic steering configuration (0.37, 0.59, 0.81, ... rad) for rank computations."""
    return 0.37 + 0.22 * np.arange(n, dtype=float)


__all__ = [
    "ICR",
    "AckermannSteering",
    "ICRStatus",
    "Mobility",
    "MobilityStatus",
    "NamedSteering",
    "SynchroSteering",
    "WheeledRobot",
    "admissible_types",
    "generic_steering",
    "kernel",
    "rank",
    "rotation",
    "wheel_at",
]
