"""Physical parameters of the Q-PRR, each with its provenance.

Frames: B is the body frame at the multirotor centre of gravity, x_B forward (the
prismatic axis), z_B along the thrust, y_B = z_B x x_B.  Link frames i = 1..3 have the
joint at their origin and coincide in orientation with B when theta2 = theta3 = 0;
every link extends along its +z axis (Thesis (3.58): p_eb = [r0 + d2 s2 + d3 s23, 0,
d0 + d1 + d2 c2 + d3 c23]).  World frame E: z up, gravity -g e3 (Thesis (5.27)-(5.29)).

Values printed in the thesis cite their table or equation; values the thesis does not
print say "chosen" with a one-line reason (see the README of the seeds: d0..d3, l, b, c
are not printed).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError, NonPhysicalError
from ..urdf.inertia import _finite, check_rigid_body, nearest_physical_moments, second_moments  # noqa: F401 (re-exported)


@dataclass(frozen=True)
class Link:
    """One rigid body of the arm.

    ``com`` is the centre of mass in the link frame [m]; ``inertia`` the rotational
    inertia about the CoM in link-frame axes, (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) [kg m^2].
    """

    name: str
    mass: float
    length: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]

    def inertia_matrix(self) -> np.ndarray:
        ixx, iyy, izz, ixy, ixz, iyz = self.inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


@dataclass(frozen=True)
class RotorPlacement:
    """A rotor: position in B [m], spin sign (+1: reaction torque along +z_B)."""

    position: tuple[float, float, float]
    spin: int


LAYOUTS = ("plus", "x")


@dataclass(frozen=True)
class QPRRParams:
    """Immutable parameter set of the Q-PRR (SI units)."""

    g: float
    multirotor_mass: float
    multirotor_inertia: tuple[float, float, float, float, float, float]
    d0: float
    d1: float
    d2: float
    d3: float
    links: tuple[Link, Link, Link]
    r0_limits: tuple[float, float]
    theta2_limits: tuple[float, float]
    theta3_limits: tuple[float, float]
    effort_limits: tuple[float, float, float]
    velocity_limits: tuple[float, float, float]
    arm_length: float  # l: distance from a rotor axis to z_B
    thrust_factor: float  # b: f_i = b w_i^2
    drag_factor: float  # c: tau_i = c w_i^2
    thrust_max: float  # per rotor [N]
    thrust_min: float = 0.0
    rail: Link | None = None  # manipulator base fixed to the multirotor (CAD variant only)
    variant: str = "thesis"
    nonphysical: tuple[str, ...] = ()
    """Bodies whose rotational inertia is knowingly non-physical (the explicit opt-in of
    ``thesis_params(table_3_2="printed-nonphysical")``): their triangle inequality is not
    checked.  Every other check still applies.  Empty for every physical parameter set."""
    provenance: dict = field(default_factory=dict, compare=False, hash=False, repr=False)

    def __post_init__(self) -> None:
        """Validate on construction (also after :meth:`with_changes`): raise :class:`NonPhysicalError` naming the
        body or device and the inequality that fails (see :func:`check_params`)."""
        check_params(self)

    # --- derived quantities -------------------------------------------------------
    @property
    def arm_mass(self) -> float:
        return float(sum(link.mass for link in self.links))

    @property
    def total_mass(self) -> float:
        rail = self.rail.mass if self.rail is not None else 0.0
        return self.multirotor_mass + self.arm_mass + rail

    @property
    def kappa(self) -> float:
        """Yaw torque per newton of thrust, c/b [m] (the factor the force form of (3.36) needs)."""
        return self.drag_factor / self.thrust_factor

    @property
    def lower_limits(self) -> np.ndarray:
        return np.array([self.r0_limits[0], self.theta2_limits[0], self.theta3_limits[0]])

    @property
    def upper_limits(self) -> np.ndarray:
        return np.array([self.r0_limits[1], self.theta2_limits[1], self.theta3_limits[1]])

    def multirotor_inertia_matrix(self) -> np.ndarray:
        ixx, iyy, izz, ixy, ixz, iyz = self.multirotor_inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])

    def rotors(self, layout: str = "plus") -> tuple[RotorPlacement, RotorPlacement, RotorPlacement, RotorPlacement]:
        """Rotor positions in B for the "+" layout of Thesis (3.36) or the "X" layout.

        "+": rotor 1 on -x_B, 2 on -y_B, 3 on +x_B, 4 on +y_B, so that with thrust along
        +z_B the body torque is tau = [l(f4 - f2), l(f1 - f3), kappa(f1 - f2 + f3 - f4)]
        exactly as (3.34)-(3.36).  "x": the same rotors turned by +45 deg about z_B.
        """
        if layout not in LAYOUTS:
            from ..errors import UnknownNameError

            raise UnknownNameError("layout", layout, LAYOUTS)
        l = self.arm_length
        plus = [(-l, 0.0), (0.0, -l), (l, 0.0), (0.0, l)]
        if layout == "x":
            c = s = np.sqrt(0.5)
            plus = [(c * x - s * y, s * x + c * y) for x, y in plus]
        spins = (1, -1, 1, -1)
        return tuple(RotorPlacement((float(x), float(y), 0.0), spin) for (x, y), spin in zip(plus, spins))

    def hover_thrust(self) -> float:
        """Per-rotor thrust [N] that holds the whole system's weight, m_G g / 4."""
        return self.total_mass * self.g / 4.0

    def with_changes(self, **changes) -> QPRRParams:
        """A copy with some fields replaced (the original stays untouched).

        A new d1, d2 or d3 also sets the length of its link (the same quantity) unless ``links`` is given."""
        unknown = set(changes) - set(self.__dataclass_fields__)
        if unknown:
            raise InputError(f"unknown parameter field(s) {sorted(unknown)}; valid: {sorted(self.__dataclass_fields__)}")
        if "links" not in changes and changes.keys() & {"d1", "d2", "d3"}:
            changes["links"] = tuple(replace(link, length=changes.get(d, link.length)) for link, d in zip(self.links, ("d1", "d2", "d3")))
        return replace(self, **changes)


def check_params(p: QPRRParams) -> None:
    """Raise :class:`NonPhysicalError` naming the body or device and the inequality a parameter set breaks.

    Checks: finite values everywhere; every body (multirotor, links, rail) by :func:`check_rigid_body`
    (the bodies listed in ``p.nonphysical`` skip the triangle inequality only); g >= 0; positive lengths
    (d1, d2, d3, every link length, the rotor arm l; d0 >= 0: the rail may sit at B's height; the rail's
    length >= 0); lower <= upper joint limits; positive effort and velocity limits; positive rotor
    factors b and c; f_min <= f_max with f_max > 0."""
    if not isinstance(p, QPRRParams):
        raise InputError(f"p must be a QPRRParams, got {type(p).__name__}")
    if not isinstance(p.nonphysical, tuple):
        raise InputError(f"nonphysical must be a tuple of body names, got {p.nonphysical!r}")
    if not (_finite([p.g]) and p.g >= 0.0):
        raise NonPhysicalError(f"gravity g must be a finite number >= 0 m/s^2, got {p.g!r}")
    check_rigid_body("multirotor", p.multirotor_mass, (0.0, 0.0, 0.0), p.multirotor_inertia, check_triangle="multirotor" not in p.nonphysical)
    if len(p.links) != 3 or not all(isinstance(link, Link) for link in p.links):
        raise InputError(f"links must be three Link objects, got {p.links!r}")
    bodies = list(p.links) + ([p.rail] if p.rail is not None else [])
    for link in bodies:
        check_rigid_body(link.name, link.mass, link.com, link.inertia, check_triangle=link.name not in p.nonphysical)
    for name in ("d1", "d2", "d3", "arm_length", "thrust_factor", "drag_factor", "thrust_max"):
        value = getattr(p, name)
        if not (_finite([value]) and value > 0.0):
            raise NonPhysicalError(f"{name} must be a positive finite number, got {value!r}")
    for link in p.links:
        if not (_finite([link.length]) and link.length > 0.0):
            raise NonPhysicalError(f"{link.name}: length must be a positive finite number of m, got {link.length!r}")
    for link, d_name in zip(p.links, ("d1", "d2", "d3")):  # the model reads d1..d3: a link length that differs is a trap
        if _finite([getattr(p, d_name)]) and link.length != getattr(p, d_name):
            raise InputError(
                f"{link.name}.length = {link.length!r} m contradicts {d_name} = {getattr(p, d_name)!r} m (the joint "
                f"offsets d1, d2, d3 are the link lengths; change both)"
            )
    if p.rail is not None and not (_finite([p.rail.length]) and p.rail.length >= 0.0):
        raise NonPhysicalError(f"{p.rail.name}: length must be a finite number >= 0 m, got {p.rail.length!r}")
    if not (_finite([p.d0]) and p.d0 >= 0.0):
        raise NonPhysicalError(f"d0 must be a finite number >= 0 m, got {p.d0!r}")
    if not (_finite([p.thrust_min]) and p.thrust_min <= p.thrust_max):
        raise NonPhysicalError(f"rotor thrust bounds need f_min <= f_max, got f_min = {p.thrust_min!r} N, f_max = {p.thrust_max!r} N")
    for name in ("r0_limits", "theta2_limits", "theta3_limits"):
        lim = getattr(p, name)
        if len(lim) != 2 or not _finite(lim) or not lim[0] <= lim[1]:
            raise NonPhysicalError(f"{name} must be finite (lower, upper) with lower <= upper, got {lim!r}")
    for name in ("effort_limits", "velocity_limits"):
        lim = getattr(p, name)
        if len(lim) != 3 or not _finite(lim) or min(lim) <= 0.0:
            raise NonPhysicalError(f"{name} must be 3 positive finite numbers (r0, theta2, theta3), got {lim!r}")


def _homogeneous_link(name: str, mass: float, length: float, inertia: tuple[float, float, float]) -> Link:
    """Hypothesis 1 (Thesis 3.3.2): homogeneous link, CoM at mid-length on the link axis."""
    return Link(name, mass, length, (0.0, 0.0, length / 2.0), (*inertia, 0.0, 0.0, 0.0))


# Table 3.1 masses [kg] and Table 3.2 principal inertias [kg m^2] (products zero: Table 3.2 text).
_TABLE_3_1_MASS = {"base": 0.033, "link1": 0.1172, "link2": 0.2773, "link3": 0.0961}
_TABLE_3_1_COM_MM = {
    "base": (-14.17, 17.5, -19.87),
    "link1": (-23.88, 13.11, 27.67),
    "link2": (12.45, 19.31, 5.0),
    "link3": (7.05, -0.05, 4.99),
}
_TABLE_3_2_INERTIA = {
    "base": (1.67e-6, 1.32e-6, 2.56e-6),
    "link1": (1.981e-5, 1.972e-5, 2.28e-5),
    "link2": (2.274e-5, 5.013e-5, 2.2767e-5),
    "link3": (4.33e-6, 7.99e-6, 3.94e-6),
}
"""Table 3.2 as printed.  Link 2's moments break the triangle inequality (see :data:`LINK2_INERTIA_PHYSICAL`)."""

LINK2_INERTIA_PHYSICAL = (2.5052e-5, 5.013e-5, 2.5079e-5)
"""Link 2's principal moments [kg m^2] used by default, in link axes.  Table 3.2 prints (2.274e-5, 5.013e-5,
2.2767e-5): I_yy exceeds I_xx + I_zz by 4.623e-6 kg m^2, i.e. a second moment of mass along y of
-2.3115e-6 kg m^2, which no body has (an independent engine, MuJoCo, refuses the URDF).  The correction is
:func:`nearest_physical_moments` (that second moment set to 0, the two others kept: I_yy, the moment about the
joint axis that the planar arm dynamics use, unchanged; I_xx and I_zz + 2.3115e-6 kg m^2, 10 %), rounded up to
the table's five significant digits (2.50515e-5 -> 2.5052e-5, 2.50785e-5 -> 2.5079e-5): the exact boundary (a
lamina) is physical but one rounding away from unphysical in another program's arithmetic; rounded up, the
second moment along y is +5e-10 kg m^2 (a 0.15 mm thick plate).  docs/thesis-errata.md, "Parameters"."""

TABLE_3_2_CHOICES = ("physical", "printed-nonphysical")

PROVENANCE = {
    "g": "Thesis (5.29): g = 9.8 m/s^2",
    "multirotor_mass": "Table 3.3: 3.029 kg; the 33 g arm base of Table 3.1 is absent from the closed forms (3.77)-(3.78), "
    "so this variant leaves it out (the CAD variant adds it)",
    "multirotor_inertia": "Table 3.3: Ixx, Iyy, Izz, Ixy, Ixz, Iyz at the CoG in B axes, products used as tensor entries",
    "link masses": "Table 3.1: 0.1172, 0.2773, 0.0961 kg",
    "link inertias": "Table 3.2: principal moments in link axes (products zero by symmetry, Table 3.2 text); link 2 corrected "
    "to the nearest physical body (2.5052e-5, 5.013e-5, 2.5079e-5): the printed (2.274e-5, 5.013e-5, 2.2767e-5) breaks the "
    "triangle inequality I_yy <= I_xx + I_zz by 4.623e-6 kg m^2 (LINK2_INERTIA_PHYSICAL, docs/thesis-errata.md)",
    "link CoM": "Hypothesis 1 (Sec. 3.3.2): homogeneous links, CoM at mid-length, as in (3.78)",
    "d2": "(4.46)-(4.48): the coefficient 4 d2^2 = 0.1299 gives d2 = 0.18 m",
    "d0 + d1": "(4.47): 2 (d0 + d1) d2 = 0.0342 gives d0 + d1 = 0.095 m",
    "d1": "chosen: 0.055 m = twice the 27.67 mm CoM height of link 1 (Table 3.1), so the CoM is mid-length",
    "d0": "chosen: 0.095 - d1 = 0.040 m (rail height between B and the slider)",
    "d3": "chosen: 0.10 m; not recoverable from (4.46)-(4.48); a short wrist link lighter than link 2 (Table 3.1)",
    "r0 limits": "Sec. 4.4.3: r0 in [-0.04, 0.04] m",
    "theta2 limits": "chosen: +-2pi/3 rad, servo range of a hobby-grade joint, keeps theta2 = pi (arm folded into the body) out",
    "theta3 limits": "chosen: +-2pi/3 rad, same servo class as theta2",
    "effort limits": "chosen: 20 N for the slider, 5 N m for each revolute joint (hold link 2+3 horizontal with margin)",
    "velocity limits": "chosen: 0.5 m/s slider, 6 rad/s revolute",
    "l": "chosen: 0.225 m, a 450 mm-class frame consistent with Izz = 0.0116 kg m^2 of Table 3.3",
    "b": "chosen: 3.0e-5 N s^2: hover (8.6 N per rotor) at ~540 rad/s, typical of 10-inch propellers",
    "c": "chosen: 7.5e-7 N m s^2: c/b = 0.025 m yaw torque per newton, typical of 10-inch propellers",
    "thrust_max": "chosen: 20 N per rotor: thrust-to-weight ratio 2.3 for the 3.52 kg system",
    "rail": "CAD variant only: Table 3.1 'Base' (33 g) with its CoM offset, fixed to the multirotor",
    "CAD CoM": "CAD variant only: Table 3.1 p_C [mm] read as the CoM in the link frame (the CAD origin is not printed: interpretation)",
}


def thesis_params(table_3_2: str = "physical") -> QPRRParams:
    """Default parameters: the inertial model assumed by the thesis's closed forms (Hypothesis 1).

    ``table_3_2``: "physical" (default) uses :data:`LINK2_INERTIA_PHYSICAL` for link 2;
    "printed-nonphysical" keeps Table 3.2 as printed, a link-2 inertia no body can have (the
    parameter set then lists "link2" in ``nonphysical`` and its variant says so).
    """
    if table_3_2 not in TABLE_3_2_CHOICES:
        from ..errors import UnknownNameError

        raise UnknownNameError("Table 3.2 choice", table_3_2, TABLE_3_2_CHOICES)
    printed = table_3_2 == "printed-nonphysical"
    d0, d1, d2, d3 = 0.040, 0.055, 0.18, 0.10
    links = (
        _homogeneous_link("link1", _TABLE_3_1_MASS["link1"], d1, _TABLE_3_2_INERTIA["link1"]),
        _homogeneous_link("link2", _TABLE_3_1_MASS["link2"], d2, _TABLE_3_2_INERTIA["link2"] if printed else LINK2_INERTIA_PHYSICAL),
        _homogeneous_link("link3", _TABLE_3_1_MASS["link3"], d3, _TABLE_3_2_INERTIA["link3"]),
    )
    rev = 2.0 * np.pi / 3.0
    return QPRRParams(
        g=9.8,
        multirotor_mass=3.029,
        multirotor_inertia=(6.98664e-3, 7.23191e-3, 11.57173e-3, -3.6e-7, 2.876e-4, -8.01e-5),
        d0=d0,
        d1=d1,
        d2=d2,
        d3=d3,
        links=links,
        r0_limits=(-0.04, 0.04),
        theta2_limits=(-rev, rev),
        theta3_limits=(-rev, rev),
        effort_limits=(20.0, 5.0, 5.0),
        velocity_limits=(0.5, 6.0, 6.0),
        arm_length=0.225,
        thrust_factor=3.0e-5,
        drag_factor=7.5e-7,
        thrust_max=20.0,
        variant="thesis-table-3.2-printed-nonphysical" if printed else "thesis",
        nonphysical=("link2",) if printed else (),
        provenance=dict(PROVENANCE),
    )


def cad_params() -> QPRRParams:
    """Variant with the CAD centres of mass of Table 3.1 and the 33 g arm base as a separate body."""
    base = thesis_params()

    def cad(link: Link) -> Link:
        com = tuple(v / 1000.0 for v in _TABLE_3_1_COM_MM[link.name])
        return replace(link, com=com)

    rail = Link(
        "rail",
        _TABLE_3_1_MASS["base"],
        0.0,
        tuple(v / 1000.0 for v in _TABLE_3_1_COM_MM["base"]),
        (*_TABLE_3_2_INERTIA["base"], 0.0, 0.0, 0.0),
    )
    return replace(base, links=tuple(cad(k) for k in base.links), rail=rail, variant="cad")


VARIANTS = {"thesis": thesis_params, "cad": cad_params}
