"""The four wheel types of the lecture and their rolling and no-slip constraints.

Lecture: "Roue fixe ou centrée orientable", "Roue décentrée orientable", "Roue suédoise"
(the formalism of Campion, Bastin and d'Andréa-Novel, IEEE T-RA 12(1), 1996, as presented
by Siegwart and Nourbakhsh, *Introduction to Autonomous Mobile Robots*, Sec. 3.2).

A wheel is attached to the chassis at the point A of polar coordinates (``ell``, ``alpha``)
in the robot frame {O_R, x_R, y_R}.  ``beta`` is the angle of the wheel plane relative to
the segment O_R A, ``r`` the radius.  With xi_R = R^T(theta) q_dot_I = [x_dot_R, y_dot_R,
theta_dot] (the chassis twist in the robot frame) the constraints are rows acting on xi_R
and on the wheel's own rates (steering beta_dot, spin phi_dot, roller spin phi_sw_dot):

========================  ==========================================================================
fixed, centred steerable   no slip:  [cos(a+b), sin(a+b), l sin b] xi_R = 0
                           rolling:  [sin(a+b), -cos(a+b), -l cos b] xi_R - r phi_dot = 0
off-centred steerable      no slip:  [cos(a+b), sin(a+b), d + l sin b] xi_R + d beta_dot = 0
                           rolling:  as the fixed wheel
Swedish (roller angle g)   no slip:  [cos(a+b+g), sin(a+b+g), l sin(b+g)] xi_R + r phi_dot sin g - r_sw phi_sw_dot = 0
                           rolling:  [sin(a+b+g), -cos(a+b+g), -l cos(b+g)] xi_R - r phi_dot cos g = 0
========================  ==========================================================================

The Swedish no-slip row above is the corrected form: the lecture (and Siegwart-Nourbakhsh
(3.20)) print ``- r phi_dot sin g``, which contradicts the rolling row of the same wheel
(:meth:`SwedishWheel.no_slip_printed`, test ``test_swedish_no_slip_printed_sign_is_wrong``).
The sign only changes the roller speed phi_sw_dot, never the chassis kinematics.

Every row is a projection of the contact point's velocity, computed independently from
rigid-body kinematics by :meth:`Wheel.slip_velocity` (the tests compare the two).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from ..errors import InputError
from ._backend import exact, is_exact, is_symbolic


class WheelKind(str, Enum):
    """The wheel types of the lecture."""

    FIXED = "fixed"
    CENTRED_STEERABLE = "centred steerable"
    OFF_CENTRED_STEERABLE = "off-centred steerable"
    SWEDISH = "swedish"


@dataclass(frozen=True)
class Constraint:
    """One scalar velocity constraint of a wheel.

    ``xi . xi_R + beta_dot * beta_dot + phi_dot * phi_dot + roller_dot * phi_sw_dot = 0``,
    with xi_R = [x_dot_R (m/s), y_dot_R (m/s), theta_dot (rad/s)] in the robot frame.
    Entries are floats or sympy expressions (namespace ``m`` of the call).
    """

    name: str
    xi: tuple
    beta_dot: object = 0.0
    phi_dot: object = 0.0
    roller_dot: object = 0.0

    def value(self, xi_R, beta_dot: float = 0.0, phi_dot: float = 0.0, roller_dot: float = 0.0) -> float:
        """The residual of the constraint for the given rates (0 when it holds)."""
        return float(
            np.dot(np.asarray(self.xi, dtype=float), np.asarray(xi_R, dtype=float))
            + float(self.beta_dot) * beta_dot
            + float(self.phi_dot) * phi_dot
            + float(self.roller_dot) * roller_dot
        )


def _check(name: str, value: float, *, positive: bool = False, nonneg: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v):
        raise InputError(f"{name} must be finite, got {value!r}")
    if positive and v <= 0.0:
        raise InputError(f"{name} must be > 0, got {value!r}")
    if nonneg and v < 0.0:
        raise InputError(f"{name} must be >= 0, got {value!r}")
    return v


def _unit(a: float) -> np.ndarray:
    return np.array([math.cos(a), math.sin(a)])


def _point_velocity(xi_R, p) -> np.ndarray:
    """Velocity in the robot frame of the chassis point p (robot frame) for the twist xi_R."""
    vx, vy, w = (float(v) for v in xi_R)
    return np.array([vx - w * p[1], vy + w * p[0]])


class Wheel:
    """Common interface of the wheel types (frozen dataclasses below)."""

    kind: WheelKind
    steerable: bool = False
    #: True for the wheels whose no-slip row enters C1* (fixed and centred steerable).
    constrains_posture: bool = False

    def beta_of(self, s=0.0, m=math):
        """The wheel-plane angle beta (rad) for the wheel's own coordinate s (steering angle, if any)."""
        return exact(self.beta, m, angle=True)  # type: ignore[attr-defined]

    def _offset(self) -> float:
        """Constant part of beta (beta or beta0), plus gamma for a Swedish wheel: each kind of wheel says its own."""
        raise NotImplementedError(f"{type(self).__name__} must define _offset (the constant part of its beta)")

    def _geometry(self, s, m):
        """(A, l sin B, l cos B) with A = alpha + B and B = beta (+ gamma) at wheel coordinate s.

        Numerically the lecture's expressions.  Symbolically, written so that they stay exact:
        with (x_A, y_A) = l (cos alpha, sin alpha), l sin B = x_A sin A - y_A cos A and
        l cos B = x_A cos A + y_A sin A when x_A, y_A are rational (wheels placed at (x, y)),
        else the lecture's form with exact alpha and l (wheels on a circle at multiples of pi/k).
        """
        alpha, ell, off = float(self.alpha), float(self.ell), self._offset()  # type: ignore[attr-defined]
        if not self.steerable:
            s = 0  # fixed and Swedish wheels have no steering coordinate
        if not is_symbolic(m):
            B = off + s
            return alpha + B, ell * math.sin(B), ell * math.cos(B)
        A = exact(alpha + off, m, angle=True) + s
        x, y = ell * math.cos(alpha), ell * math.sin(alpha)
        if ell == 0.0:
            return A, 0, 0
        if is_exact(x) and is_exact(y):
            xe, ye = exact(x, m), exact(y, m)
            return A, xe * m.sin(A) - ye * m.cos(A), xe * m.cos(A) + ye * m.sin(A)
        B = exact(off, m, angle=True) + s
        le = exact(ell, m)
        return A, le * m.sin(B), le * m.cos(B)

    def rolling(self, s=0.0, m=math) -> Constraint:
        """Lecture: "Contrainte de roulement pur" [sin(a+b), -cos(a+b), -l cos b] xi_R - r phi_dot = 0."""
        A, _, lcb = self._geometry(s, m)
        return Constraint(f"{self.name} rolling", (m.sin(A), -m.cos(A), -lcb), phi_dot=-exact(self.r, m))  # type: ignore[attr-defined]

    def no_slip(self, s=0.0, m=math) -> Constraint:
        """Lecture: "Contrainte de non-glissement" [cos(a+b), sin(a+b), l sin b] xi_R = 0."""
        A, lsb, _ = self._geometry(s, m)
        return Constraint(f"{self.name} no-slip", (m.cos(A), m.sin(A), lsb))

    def constraints(self, s=0.0, m=math) -> tuple[Constraint, Constraint]:
        """(no-slip, rolling) at wheel coordinate s."""
        return self.no_slip(s, m), self.rolling(s, m)

    # ---------------------------------------------------------------- physics check
    def directions(self, s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(axle direction a, rolling direction d) in the robot frame, unit vectors (s: steering, if any).

        The no-slip row is the component of the contact-point velocity along a, the
        rolling row the component along d (for a Swedish wheel: a and d turned by gamma).
        """
        A = float(self.alpha) + float(self.beta_of(s))  # type: ignore[attr-defined]
        return _unit(A), np.array([math.sin(A), -math.cos(A)])

    def contact_point(self, s: float = 0.0) -> np.ndarray:
        """Contact point with the ground in the robot frame [m]."""
        return float(self.ell) * _unit(float(self.alpha))  # type: ignore[attr-defined]

    def slip_velocity(self, xi_R, s: float = 0.0, s_dot: float = 0.0, phi_dot: float = 0.0, roller_dot: float = 0.0) -> np.ndarray:
        """Velocity [m/s] of the material point of the wheel touching the ground, robot frame.

        Rigid-body kinematics, independent of the constraint rows: the velocity of the wheel
        centre plus omega_wheel x (-r z).  The spin axis is the axle a, oriented so that a
        positive phi_dot rolls the wheel along its rolling direction d; the contact point
        therefore moves at -r phi_dot d relative to the wheel centre.  Rolling without
        slipping is slip_velocity = 0.
        """
        a, d = self.directions(s)
        return _point_velocity(xi_R, self.contact_point(s)) - float(self.r) * phi_dot * d  # type: ignore[attr-defined]


@dataclass(frozen=True)
class FixedWheel(Wheel):
    """Fixed standard wheel: beta constant (Lecture: "Roue fixe", Remark 1)."""

    alpha: float
    beta: float
    ell: float
    r: float
    name: str = "fixed"

    kind = WheelKind.FIXED
    constrains_posture = True

    def _offset(self) -> float:
        return float(self.beta)

    def __post_init__(self):
        for f in ("alpha", "beta"):
            _check(f, getattr(self, f))
        _check("ell", self.ell, nonneg=True)
        _check("r", self.r, positive=True)


@dataclass(frozen=True)
class CentredSteerableWheel(Wheel):
    """Centred steerable wheel: steering axis through the contact point, beta = beta0 + s(t).

    The wheel's coordinate s is its steering angle measured from ``beta0`` (e.g. the
    front wheel of the tricycle has beta0 = pi/2 and s = psi, the lecture's steering angle).
    Lecture: "Roue fixe ou centrée orientable" (Remark 1: beta = beta(t)).
    """

    alpha: float
    ell: float
    r: float
    beta0: float = 0.0
    name: str = "steerable"

    kind = WheelKind.CENTRED_STEERABLE
    steerable = True
    constrains_posture = True

    def _offset(self) -> float:
        return float(self.beta0)

    def __post_init__(self):
        _check("alpha", self.alpha)
        _check("beta0", self.beta0)
        _check("ell", self.ell, nonneg=True)
        _check("r", self.r, positive=True)

    def beta_of(self, s=0.0, m=math):
        return exact(self.beta0, m, angle=True) + s


@dataclass(frozen=True)
class OffCentredSteerableWheel(Wheel):
    """Off-centred steerable (castor) wheel: contact at distance d from the steering axis.

    beta = beta0 + s(t).  Lecture: "Roue décentrée orientable": the no-slip row gains
    d on theta_dot and the term d beta_dot; the rolling row is the fixed wheel's.  The row
    as printed places the contact point at A + d (sin(a+b), -cos(a+b)), i.e. d along the
    rolling direction from the steering axis (checked by :meth:`slip_velocity`).
    """

    alpha: float
    ell: float
    d: float
    r: float
    beta0: float = 0.0
    name: str = "castor"

    kind = WheelKind.OFF_CENTRED_STEERABLE
    steerable = True

    def _offset(self) -> float:
        return float(self.beta0)

    def __post_init__(self):
        _check("alpha", self.alpha)
        _check("beta0", self.beta0)
        _check("ell", self.ell, nonneg=True)
        _check("d", self.d, positive=True)
        _check("r", self.r, positive=True)

    def beta_of(self, s=0.0, m=math):
        return exact(self.beta0, m, angle=True) + s

    def no_slip(self, s=0.0, m=math) -> Constraint:
        """Lecture: [cos(a+b), sin(a+b), d + l sin b] xi_R + d beta_dot = 0."""
        A, lsb, _ = self._geometry(s, m)
        d = exact(self.d, m)
        return Constraint(f"{self.name} no-slip", (m.cos(A), m.sin(A), d + lsb), beta_dot=d)

    def contact_point(self, s: float = 0.0) -> np.ndarray:
        _, dvec = self.directions(s)
        return float(self.ell) * _unit(float(self.alpha)) + self.d * dvec

    def slip_velocity(self, xi_R, s: float = 0.0, s_dot: float = 0.0, phi_dot: float = 0.0, roller_dot: float = 0.0) -> np.ndarray:
        """Contact-point velocity: steering axis A moves with the chassis, the fork turns at
        theta_dot + beta_dot about A, the wheel spins about its axle (see :meth:`Wheel.slip_velocity`)."""
        a, d = self.directions(s)
        pA = float(self.ell) * _unit(float(self.alpha))
        w_fork = float(xi_R[2]) + s_dot
        v_contact_centre = _point_velocity(xi_R, pA) + w_fork * self.d * np.array([-d[1], d[0]])
        return v_contact_centre - self.r * phi_dot * d


@dataclass(frozen=True)
class SwedishWheel(Wheel):
    """Swedish wheel: rollers on the rim whose axes make the angle gamma with the wheel plane.

    gamma = pi/4 for a "Swedish 45 deg" wheel; gamma = 0 is the lecture's "Swedish 90 deg"
    (no no-slip constraint left: the rollers absorb any lateral motion); gamma = pi/2 is the
    degenerate case (rollers parallel to the axle: no rolling constraint left).
    Lecture: "Roue suédoise".
    """

    alpha: float
    beta: float
    ell: float
    r: float
    gamma: float = math.pi / 4
    r_sw: float = 0.01
    name: str = "swedish"

    kind = WheelKind.SWEDISH

    def _offset(self) -> float:
        return float(self.beta) + float(self.gamma)

    def __post_init__(self):
        for f in ("alpha", "beta", "gamma"):
            _check(f, getattr(self, f))
        _check("ell", self.ell, nonneg=True)
        _check("r", self.r, positive=True)
        _check("r_sw", self.r_sw, positive=True)
        if abs(math.cos(self.gamma)) < 1e-9:
            raise InputError(f"gamma = {self.gamma!r}: rollers parallel to the axle (cos gamma = 0), the degenerate wheel of the lecture")

    def rolling(self, s=0.0, m=math) -> Constraint:
        """Lecture: [sin(a+b+g), -cos(a+b+g), -l cos(b+g)] xi_R - r phi_dot cos g = 0."""
        A, _, lcb = self._geometry(s, m)
        g = exact(self.gamma, m, angle=True)
        return Constraint(f"{self.name} rolling", (m.sin(A), -m.cos(A), -lcb), phi_dot=-exact(self.r, m) * m.cos(g))

    def no_slip(self, s=0.0, m=math) -> Constraint:
        """Corrected lecture row: [cos(a+b+g), sin(a+b+g), l sin(b+g)] xi_R + r phi_dot sin g - r_sw phi_sw_dot = 0.

        The roller spin phi_sw_dot is positive about the roller axis oriented along -d_gamma.
        """
        A, lsb, _ = self._geometry(s, m)
        g = exact(self.gamma, m, angle=True)
        return Constraint(f"{self.name} no-slip", (m.cos(A), m.sin(A), lsb), phi_dot=exact(self.r, m) * m.sin(g), roller_dot=-exact(self.r_sw, m))

    def no_slip_printed(self, s=0.0, m=math) -> Constraint:
        """The no-slip row as printed in the lecture: ... - r phi_dot sin g - r_sw phi_sw_dot = 0 (sign error)."""
        c = self.no_slip(s, m)
        return Constraint(c.name + " (printed)", c.xi, phi_dot=-c.phi_dot, roller_dot=c.roller_dot)

    def directions(self, s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(a_gamma, d_gamma): the axle and rolling directions turned by gamma."""
        A = self.alpha + self.beta + self.gamma
        return _unit(A), np.array([math.sin(A), -math.cos(A)])

    def slip_velocity(self, xi_R, s: float = 0.0, s_dot: float = 0.0, phi_dot: float = 0.0, roller_dot: float = 0.0) -> np.ndarray:
        """Velocity [m/s] of the roller's material point touching the ground, robot frame.

        The chassis point, the hub spin (-r phi_dot d, d the wheel's own rolling direction)
        and the roller spin phi_sw_dot about the roller axis -d_gamma, whose contact point
        lies r_sw below that axis: it adds -r_sw phi_sw_dot a_gamma.
        """
        A = self.alpha + self.beta
        d_wheel = np.array([math.sin(A), -math.cos(A)])
        a_g, d_g = self.directions(s)
        spin = np.array([-d_g[0], -d_g[1], 0.0]) * roller_dot
        v_roller = np.cross(spin, np.array([0.0, 0.0, -self.r_sw]))[:2]
        return _point_velocity(xi_R, self.contact_point(s)) - self.r * phi_dot * d_wheel + v_roller


__all__ = ["CentredSteerableWheel", "Constraint", "FixedWheel", "OffCentredSteerableWheel", "SwedishWheel", "Wheel", "WheelKind"]
