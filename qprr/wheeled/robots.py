"""The lecture's wheeled robots and exercises, each a kinematic model built on its wheels.

=====================  ===============================================================  ===================
name                   model                                                            lecture slide
=====================  ===============================================================  ===================
``fixed-wheel``        one fixed wheel, q = [x, y, theta, phi], the printed A(q)        "Contraintes non holonômes", Exemple
``unicycle``           differential drive, q = [x, y, theta], u = (v, omega)            "I) unicycle", "conduite différentielle"
``tricycle-front``     front-driven tricycle, q = [x, y, theta, psi], u = (u1, u2)      "II) tricycle motorisé à l'avant"
``tricycle-rear``      rear-driven tricycle (the exercise's solution of point 1)        "Exercice" (tricycle), Solution
``car``                car with Ackermann steering = rear-driven virtual tricycle       "voiture ... épure d'Ackermann"
``bicycle``            bicycle with steerable front wheel, rear-wheel reference         "Exercice (vélo avec roue avant orientable)"
``omni``               three Swedish wheels, u = (x_dot, y_dot, theta_dot)              "III) Robot omnidirectionnel"
``mecanum``            four Swedish 45 deg wheels (Uranus, youBot)                      "4 roues suédoises 45°"
``synchro``            synchro drive, q = [x, y, theta, beta], u = (v, beta_dot)        "Synchro drive"
=====================  ===============================================================  ===================

Exercises: :func:`tricycle_exercise` (q0 = [0, 0, pi/4, 0], D = 0.3 m, 30 s, the three
command cases) and :func:`bicycle_exercise` (degrees of the fixed, front-steered and
rear-steered bicycles); :data:`TYPE_EXAMPLES` are three-wheel robots of the five types.

Lengths in metres, angles in radians, speeds in m/s and rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, KinematicSingularityError, UnknownNameError
from ..validation import as_real, checked_args
from ._backend import exact, is_symbolic, matrix
from .chassis import AckermannSteering, Mobility, NamedSteering, SynchroSteering, WheeledRobot, wheel_at
from .kinematics import KinematicModel, check_duration
from .sim import WheeledSimResult, heading_quadrature, se2_flow, simulate_wheeled, sinc
from .wheels import CentredSteerableWheel, FixedWheel, OffCentredSteerableWheel, SwedishWheel


def _positive(name: str, value) -> float:
    return as_real(value, name, positive=True, unit="m")


def _cos_sin(q, m):
    return m.cos(q[2]), m.sin(q[2])


# ============================================================================ fixed wheel
class FixedWheelModel(KinematicModel):
    """One fixed wheel of radius r: q = [x, y, theta, phi] (theta: orientation of the wheel plane,
    phi: spin angle); u = (v, omega), v the speed of the centre along the wheel plane.

    Lecture: "Contraintes non holonômes", Exemple: A(q) = [[-sin th, cos th], [cos th, sin th],
    [0, 0], [0, r]], i.e. the no-slip (1) -x_dot sin th + y_dot cos th = 0 and the rolling
    (2) x_dot cos th + y_dot sin th = -r phi_dot.  With (2) a positive v spins the wheel
    backwards: phi_dot = -v / r.
    """

    name = "fixed-wheel"
    description = "one fixed wheel, q = [x, y, theta, phi], the lecture's A(q)"
    lecture = "Contraintes non holonômes, Exemple (roue fixe)"
    coordinates = ("x", "y", "theta", "phi")
    inputs = ("v", "omega")
    input_units = ("m/s", "rad/s")

    def __init__(self, r: float = 0.1):
        self.r = _positive("r", r)
        # Lecture Remark 2: alpha = pi/2, ell = 0, beta = 0 gives these constraints up to the sign of phi.
        self.robot = WheeledRobot("fixed wheel", (FixedWheel(math.pi / 2, 0.0, 0.0, self.r, name="wheel"),))

    def A(self, q, m=math):
        c, s = _cos_sin(q if is_symbolic(m) else self.check_q(q), m)
        return matrix([[-s, c], [c, s], [0, 0], [0, exact(self.r, m)]], m)

    def B(self, q, m=math):
        c, s = _cos_sin(q if is_symbolic(m) else self.check_q(q), m)
        return matrix([[c, 0], [s, 0], [0, 1], [-1 / exact(self.r, m), 0]], m)

    def flow(self, q, u, h):
        q, (v, w), h = self.check_q(q), self.check_u(u), check_duration(h)
        return np.concatenate([se2_flow(q[0:3], (v, 0.0, w), h), [q[3] - v * h / self.r]])

    def wheel_speeds(self, q, u):
        return {"wheel": -float(self.check_u(u)[0]) / self.r}


# ============================================================================ unicycle
@checked_args
def differential_drive(phi_dot_d: float, phi_dot_g: float, r: float, L: float) -> tuple[float, float]:
    """(v, omega) of a differential-drive robot from its wheel rates [rad/s].

    Lecture: "conduite différentielle": v = r (phi_dot_g - phi_dot_d) / 2,
    omega = -r (phi_dot_g + phi_dot_d) / (2 L), 2L the axle width.  The slide measures both
    wheel angles about outward axes: the right wheel rolls forward for phi_dot_d < 0
    (phi_dot_d = -phi_dot_g: straight ahead; phi_dot_d = phi_dot_g: clockwise spin).
    """
    return r * (phi_dot_g - phi_dot_d) / 2.0, -r * (phi_dot_g + phi_dot_d) / (2.0 * L)


@checked_args
def differential_drive_inverse(v: float, omega: float, r: float, L: float) -> tuple[float, float]:
    """(phi_dot_d, phi_dot_g) giving (v, omega), inverse of :func:`differential_drive` (same convention)."""
    return -(v + L * omega) / r, (v - L * omega) / r


@checked_args
def icr_offset(phi_dot_d: float, phi_dot_g: float, L: float) -> float:
    """rho, the signed distance from the axle centre to the ICR along y_R (left positive) [m].

    Lecture: "Robot à conduite différentielle et CIR": v_d = -r phi_dot_d = (rho + L) omega,
    v_g = r phi_dot_g = (rho - L) omega, rho = L (phi_dot_d - phi_dot_g) / (phi_dot_d + phi_dot_g).
    Infinite for phi_dot_d = -phi_dot_g (straight line).
    """
    den = phi_dot_d + phi_dot_g
    if den == 0.0:
        return math.inf
    return L * (phi_dot_d - phi_dot_g) / den


class Unicycle(KinematicModel):
    """Unicycle / differential drive: q = [x, y, theta], u = (v, omega).

    Lecture: "Modèle cinématique en posture du robot de type unicycle": x_dot = v cos th,
    y_dot = v sin th, th_dot = omega.  Wheels: the lecture's Example 1 (right wheel alpha =
    -pi/2, beta = pi; left alpha = pi/2, beta = 0; ell = L, radius r) and a rear castor.
    """

    name = "unicycle"
    description = "differential drive: two fixed wheels on one axle and a castor"
    lecture = "I) Robot mobile de type unicycle; Manœuvrabilité, Exemple 1"
    coordinates = ("x", "y", "theta")
    inputs = ("v", "omega")
    input_units = ("m/s", "rad/s")

    def __init__(self, r: float = 0.05, L: float = 0.15, castor: float = 0.12):
        self.r, self.L = _positive("r", r), _positive("L", L)
        self.robot = WheeledRobot(
            "unicycle",
            (
                wheel_at(FixedWheel, 0.0, -self.L, self.r, name="right"),
                wheel_at(FixedWheel, 0.0, self.L, self.r, name="left"),
                wheel_at(OffCentredSteerableWheel, -_positive("castor", castor), 0.0, 0.3 * self.r, d=0.03, name="castor"),
            ),
        )

    def B(self, q, m=math):
        c, s = _cos_sin(q if is_symbolic(m) else self.check_q(q), m)
        return matrix([[c, 0], [s, 0], [0, 1]], m)

    def flow(self, q, u, h):
        q, (v, w), h = self.check_q(q), self.check_u(u), check_duration(h)
        return se2_flow(q, (v, 0.0, w), h)


# ============================================================================ tricycles
def _tricycle_wheels(D: float, L: float, r: float, name: str):
    rear = (
        (wheel_at(FixedWheel, 0.0, -L, r, name="rear right"), wheel_at(FixedWheel, 0.0, L, r, name="rear left"))
        if L > 0
        else (wheel_at(FixedWheel, 0.0, 0.0, r, name="rear"),)
    )
    return WheeledRobot(name, rear + (wheel_at(CentredSteerableWheel, D, 0.0, r, name="front"),), steering=NamedSteering(("psi",)))


class FrontTricycle(KinematicModel):
    """Tricycle driven by its front (steerable) wheel: q = [x, y, theta, psi], u = (u1, u2).

    (x, y) is the centre of the rear axle, psi the steering angle, D the distance from the
    front wheel to the rear axle; u1 is the front wheel's speed [m/s], u2 = psi_dot [rad/s].
    Lecture: "Modèle cinématique en posture du robot de type tricycle motorisé à l'avant":
    B(q) = [[cos th cos psi, 0], [sin th cos psi, 0], [sin psi / D, 0], [0, 1]], and the
    Pfaffian form A^T = [[-sin th, cos th, 0, 0], [-sin(th+psi), cos(th+psi), D cos psi, 0]].
    Valid everywhere.
    """

    name = "tricycle-front"
    description = "tricycle, front wheel driven and steered"
    lecture = "II) tricycle motorisé à l'avant; forme pfaffienne; B(q)"
    coordinates = ("x", "y", "theta", "psi")
    inputs = ("u1", "u2")
    input_units = ("m/s", "rad/s")

    def __init__(self, D: float = 0.3, L: float = 0.15, r: float = 0.05):
        self.D, self.L, self.r = _positive("D", D), as_real(L, "L", nonnegative=True, unit="m"), _positive("r", r)
        if not (math.isfinite(self.L) and self.L >= 0):
            raise InputError(f"L (half rear track) must be >= 0, got {L!r}")
        self.robot = _tricycle_wheels(self.D, self.L, self.r, self.name)

    def B(self, q, m=math):
        q = q if is_symbolic(m) else self.check_q(q)
        c, s = _cos_sin(q, m)
        cp, sp = m.cos(q[3]), m.sin(q[3])
        return matrix([[c * cp, 0], [s * cp, 0], [sp / exact(self.D, m), 0], [0, 1]], m)

    def flow(self, q, u, h):
        q, (u1, u2), h = self.check_q(q), self.check_u(u), check_duration(h)
        x, y, th, psi = q
        D = self.D
        if u2 == 0.0:
            return np.concatenate([se2_flow(q[0:3], (u1 * math.cos(psi), 0.0, u1 * math.sin(psi) / D), h), [psi]])

        def heading(t):  # theta(t) = theta0 + u1/(D u2) (cos psi0 - cos psi(t)), written with sinc
            half = 0.5 * u2 * t
            return th + (u1 / D) * t * np.sin(psi + half) * np.sinc(half / np.pi)

        def speed(t):
            return u1 * np.cos(psi + u2 * t)

        xe, ye = heading_quadrature(x, y, speed, heading, h, abs(u2) + abs(u1) / D)
        return np.array([xe, ye, float(heading(np.array([h]))[0]), psi + u2 * h])


class RearTricycle(KinematicModel):
    """Tricycle driven at the rear axle: q = [x, y, theta, psi], u = (u1, u2).

    u1 is the speed of the rear-axle centre [m/s], u2 = psi_dot.  Lecture: Exercise
    (tricycle), solution of point 1: B(q) = [[cos th, 0], [sin th, 0], [tan psi / D, 0], [0, 1]],
    same A(q) as the front-driven tricycle.  Point 2 of the exercise: B is undefined at
    psi = +-pi/2 (the front wheel across the chassis cannot follow a moving rear axle:
    theta_dot -> infinity); :meth:`singularity` reports it and :meth:`flow` refuses to cross it.
    """

    name = "tricycle-rear"
    description = "tricycle, rear axle driven, front wheel steered"
    lecture = "Exercice (tricycle motorisé à l'arrière), Solution du point 1"
    coordinates = ("x", "y", "theta", "psi")
    inputs = ("u1", "u2")
    input_units = ("m/s", "rad/s")
    COS_TOL = 1e-9

    def __init__(self, D: float = 0.3, L: float = 0.15, r: float = 0.05):
        self.D, self.L, self.r = _positive("D", D), as_real(L, "L", nonnegative=True, unit="m"), _positive("r", r)
        if not (math.isfinite(self.L) and self.L >= 0):
            raise InputError(f"L (half rear track) must be >= 0, got {L!r}")
        self.robot = _tricycle_wheels(self.D, self.L, self.r, self.name)

    def singularity(self, q):
        c = math.cos(float(q[3]))
        if abs(c) < self.COS_TOL:
            return f"psi = {q[3]:.6g} rad: cos psi = {c:.2g}, tan psi / D undefined (front wheel across the chassis)"
        return None

    def B(self, q, m=math):
        q = q if is_symbolic(m) else self.check_q(q)
        if not is_symbolic(m) and self.singularity(q):
            raise KinematicSingularityError(f"{self.name}: {self.singularity(q)}")
        c, s = _cos_sin(q, m)
        return matrix([[c, 0], [s, 0], [m.tan(q[3]) / exact(self.D, m), 0], [0, 1]], m)

    def velocity(self, q, u):
        """q_dot = B(q) u; with u1 = 0 the velocity [0, 0, 0, u2] is defined at psi = pi/2 too."""
        q, u = self.check_q(q), self.check_u(u)
        if u[0] == 0.0:
            return np.array([0.0, 0.0, 0.0, u[1]])
        return self.B(q) @ u

    def flow(self, q, u, h):
        q, (u1, u2), h = self.check_q(q), self.check_u(u), check_duration(h)
        x, y, th, psi = q
        D = self.D
        if u1 == 0.0:  # steering at rest: regular even across psi = pi/2
            return np.array([x, y, th, psi + u2 * h])
        why = self.singularity(q)
        if why:
            raise KinematicSingularityError(f"{self.name}: {why}")
        if u2 == 0.0:
            return np.concatenate([se2_flow(q[0:3], (u1, 0.0, u1 * math.tan(psi) / D), h), [psi]])
        c1 = math.cos(psi + u2 * h)
        # cos psi(t) must keep its sign: a zero crossing is the singularity psi = pi/2 + k pi
        k0, k1 = math.floor((psi - math.pi / 2) / math.pi), math.floor((psi + u2 * h - math.pi / 2) / math.pi)
        if k0 != k1 or abs(c1) < self.COS_TOL:
            t_s = ((math.pi / 2 + (k0 + 1 if u2 > 0 else k0) * math.pi) - psi) / u2
            raise KinematicSingularityError(f"{self.name}: psi reaches {psi + u2 * t_s:.6g} rad (cos psi = 0) {t_s:.6g} s into the step")
        tan0 = math.tan(psi)

        def heading(t):  # theta0 - u1/(D u2) ln(cos psi(t)/cos psi0), written with log1p (regular as u2 -> 0)
            d = u2 * t
            w = -2.0 * np.sin(d / 2) ** 2 - tan0 * np.sin(d)
            with np.errstate(divide="ignore", invalid="ignore"):
                r = np.where(np.abs(d) > 1e-12, -np.log1p(w) / np.where(d == 0, 1.0, d), tan0)
            return th + (u1 / D) * t * r

        tan_max = max(abs(math.tan(psi)), abs(math.tan(psi + u2 * h)))  # tan is monotonic between singularities
        xe, ye = heading_quadrature(x, y, lambda t: np.full_like(t, u1), heading, h, abs(u2) + abs(u1) * tan_max / D)
        return np.array([xe, ye, float(heading(np.array([h]))[0]), psi + u2 * h])


class Car(RearTricycle):
    """Car-like robot with Ackermann steering: the rear-driven tricycle of its virtual central wheel.

    q = [x, y, theta, psi] with psi the angle of the virtual wheel at the centre of the
    front axle; u = (u1, u2) = (rear-axle-centre speed, psi_dot).  The two front wheels are
    steered by the Ackermann linkage (:class:`~qprr.wheeled.chassis.AckermannSteering`):
    Lecture: "épure d'Ackermann": cot psi_o - cot psi_i = 2L/D, cot psi_tr = cot psi_i + L/D
    = cot psi_o - L/D, which keeps a unique ICR on the rear axle line.  ``D``: wheelbase,
    ``L``: half of the front track (the lecture's 2L is the track), ``psi_max``: steering limit.
    """

    name = "car"
    description = "car-like robot, rear-wheel drive, Ackermann front axle"
    lecture = "voiture avec épure d'Ackermann; équivalence avec le tricycle"

    def __init__(self, D: float = 0.5, L: float = 0.2, r: float = 0.08, psi_max: float = 0.6, rear_L: float | None = None):
        self.D, self.L, self.r = _positive("D", D), _positive("L", L), _positive("r", r)
        self.psi_max = _positive("psi_max", psi_max)
        if self.psi_max >= math.pi / 2:
            raise InputError(f"psi_max must be < pi/2 rad, got {psi_max!r}")
        Lr = self.L if rear_L is None else _positive("rear_L", rear_L)
        self.rear_L = Lr
        self.robot = WheeledRobot(
            "car",
            (
                wheel_at(FixedWheel, 0.0, -Lr, self.r, name="rear right"),
                wheel_at(FixedWheel, 0.0, Lr, self.r, name="rear left"),
                wheel_at(CentredSteerableWheel, self.D, self.L, self.r, name="front left"),
                wheel_at(CentredSteerableWheel, self.D, -self.L, self.r, name="front right"),
            ),
            steering=AckermannSteering(self.D, self.L),
        )
        self.virtual = RearTricycle(self.D, Lr, self.r)

    @checked_args
    def front_angles(self, psi: float) -> tuple[float, float]:
        """(psi_left, psi_right) of the front wheels for the virtual wheel's angle psi [rad]."""
        return self.robot.steering_angles([psi])


class Bicycle(RearTricycle):
    """Bicycle with a steerable front wheel, rear-wheel reference and rear-wheel drive.

    The rear-driven tricycle with a single rear wheel (Lecture: "Exercice (vélo avec roue
    avant orientable)"): q = [x, y, theta, psi], u = (rear-wheel speed, psi_dot).
    """

    name = "bicycle"
    description = "bicycle, steerable front wheel, rear-wheel drive"
    lecture = "Exercice (vélo avec roue avant orientable)"

    def __init__(self, D: float = 1.0, r: float = 0.35):
        super().__init__(D=D, L=0.0, r=r)
        self.robot = WheeledRobot(
            "bicycle",
            (wheel_at(FixedWheel, 0.0, 0.0, self.r, name="rear"), wheel_at(CentredSteerableWheel, self.D, 0.0, self.r, name="front")),
            steering=NamedSteering(("psi",)),
        )


# ============================================================================ omnidirectional
class Omnidirectional(KinematicModel):
    """Omnidirectional robot: q = [x, y, theta], u = (x_dot, y_dot, theta_dot) in the world frame.

    Lecture: "III) Robot omnidirectionnel", modèle en posture x_dot = u1, y_dot = u2,
    theta_dot = u3.  No posture constraint (A has no columns); the wheels' rates follow from
    their rolling constraints (:meth:`wheel_speeds`).  Default: three Swedish wheels at the
    vertices of an equilateral triangle (``ell`` from the centre), planes tangent to the
    circle, rollers at ``gamma`` (0: the lecture's "Swedish 90 deg").
    """

    name = "omni"
    description = "three Swedish wheels on an equilateral triangle"
    lecture = "III) Robot omnidirectionnel; Roue suédoise"
    coordinates = ("x", "y", "theta")
    inputs = ("u1", "u2", "u3")
    input_units = ("m/s", "m/s", "rad/s")

    def __init__(self, ell: float = 0.2, r: float = 0.05, gamma: float = 0.0, robot: WheeledRobot | None = None):
        ell, r = _positive("ell", ell), _positive("r", r)
        self.robot = robot or WheeledRobot(
            "omni",
            tuple(
                SwedishWheel(alpha=a, beta=0.0, ell=ell, r=r, gamma=gamma, name=f"wheel {i + 1}")
                for i, a in enumerate((0.0, 2 * math.pi / 3, 4 * math.pi / 3))
            ),
        )

    def A(self, q, m=math):
        return m.zeros(3, 0) if is_symbolic(m) else np.zeros((3, 0))

    def B(self, q, m=math):
        return m.eye(3) if is_symbolic(m) else np.eye(3)

    def flow(self, q, u, h):
        return self.check_q(q) + check_duration(h) * self.check_u(u)


class Mecanum(Omnidirectional):
    """Four Swedish 45 deg (mecanum) wheels on a rectangle (Lecture: robots Uranus, youBot)."""

    name = "mecanum"
    description = "four Swedish 45 deg wheels (Uranus, youBot)"
    lecture = "Robots omnidirectionnels, 4 roues suédoises 45°"

    def __init__(self, a: float = 0.25, b: float = 0.2, r: float = 0.05):
        a, b, r = _positive("a", a), _positive("b", b), _positive("r", r)
        wheels = []
        for name, (x, y), g in (
            ("front left", (a, b), -math.pi / 4),
            ("front right", (a, -b), math.pi / 4),
            ("rear left", (-a, b), math.pi / 4),
            ("rear right", (-a, -b), -math.pi / 4),
        ):
            w = wheel_at(FixedWheel, x, y, r)
            wheels.append(SwedishWheel(alpha=w.alpha, beta=w.beta, ell=w.ell, r=r, gamma=g, name=name))
        super().__init__(robot=WheeledRobot("mecanum", tuple(wheels)))


class SynchroDrive(KinematicModel):
    """Synchro drive: every wheel steered by one belt, q = [x, y, theta, beta], u = (v, beta_dot).

    beta is the common wheel angle in the robot frame; the wheels roll at v along theta +
    beta; the chassis never turns (Lecture: "Synchro drive ... l'orientation du châssis du
    robot n'est pas contrôlable").  Modelled with centred steerable wheels: steering about
    the contact point, as the synchronised wheels must (with an offset, steering at rest
    would drag the three contact points).
    """

    name = "synchro"
    description = "synchro drive: three wheels steered together, chassis heading fixed"
    lecture = "Robots omnidirectionnels – cas d'étude, Synchro drive (Nomad 200)"
    coordinates = ("x", "y", "theta", "beta")
    inputs = ("v", "beta_dot")
    input_units = ("m/s", "rad/s")

    def __init__(self, ell: float = 0.2, r: float = 0.05):
        ell, r = _positive("ell", ell), _positive("r", r)
        wheels = tuple(
            wheel_at(CentredSteerableWheel, ell * math.cos(a), ell * math.sin(a), r, name=f"wheel {i + 1}")
            for i, a in enumerate((0.0, 2 * math.pi / 3, 4 * math.pi / 3))
        )
        self.robot = WheeledRobot("synchro", wheels, steering=SynchroSteering(3))

    def B(self, q, m=math):
        q = q if is_symbolic(m) else self.check_q(q)
        a = q[2] + q[3]
        return matrix([[m.cos(a), 0], [m.sin(a), 0], [0, 0], [0, 1]], m)

    def flow(self, q, u, h):
        q, (v, w), h = self.check_q(q), self.check_u(u), check_duration(h)
        a = q[2] + q[3] + 0.5 * w * h
        k = v * h * sinc(0.5 * w * h)  # int_0^h v cos(c + w t) dt = v h cos(c + w h/2) sinc(w h/2)
        return np.array([q[0] + k * math.cos(a), q[1] + k * math.sin(a), q[2], q[3] + w * h])


# ============================================================================ registry
ROBOTS: dict[str, Callable[[], KinematicModel]] = {
    "fixed-wheel": FixedWheelModel,
    "unicycle": Unicycle,
    "tricycle-front": FrontTricycle,
    "tricycle-rear": RearTricycle,
    "car": Car,
    "bicycle": Bicycle,
    "omni": Omnidirectional,
    "mecanum": Mecanum,
    "synchro": SynchroDrive,
}
"""The lecture's robots by name (factories with the default parameters)."""


def get_robot(name: str, **params) -> KinematicModel:
    """The model called ``name`` (see :data:`ROBOTS`); UnknownNameError lists the valid ones."""
    if name not in ROBOTS:
        raise UnknownNameError("wheeled robot", name, tuple(ROBOTS))
    return ROBOTS[name](**params)


# ============================================================================ the five types
def _bicycle_lecture(front: str, rear: str, ell: float = 0.5, r: float = 0.3) -> WheeledRobot:
    """Bicycle in the lecture's frame (origin midway, front wheel alpha = 0, rear alpha = pi)."""
    wheels = []
    for where, kind, alpha in (("front", front, 0.0), ("rear", rear, math.pi)):
        beta = math.pi / 2 - alpha if alpha == 0.0 else -math.pi / 2  # Example 2: (0, pi/2) and (pi, -pi/2)
        if kind == "fixed":
            wheels.append(FixedWheel(alpha, beta, ell, r, name=where))
        else:
            wheels.append(CentredSteerableWheel(alpha, ell, r, beta0=beta, name=where))
    return WheeledRobot(f"bicycle ({front} front, {rear} rear)", tuple(wheels))


def _castor(x: float, y: float, name: str) -> OffCentredSteerableWheel:
    return wheel_at(OffCentredSteerableWheel, x, y, 0.03, d=0.03, name=name)


TYPE_EXAMPLES: dict[tuple[int, int], WheeledRobot] = {
    (3, 0): Omnidirectional().robot,
    (2, 0): Unicycle().robot,
    (2, 1): WheeledRobot(
        "one steerable wheel, two castors",
        (wheel_at(CentredSteerableWheel, 0.3, 0.0, 0.05, name="front"), _castor(0.0, 0.15, "castor left"), _castor(0.0, -0.15, "castor right")),
    ),
    (1, 1): FrontTricycle().robot,
    (1, 2): WheeledRobot(
        "two steerable wheels, one castor",
        (
            wheel_at(CentredSteerableWheel, 0.3, 0.0, 0.05, name="front"),
            wheel_at(CentredSteerableWheel, -0.3, 0.0, 0.05, name="rear"),
            _castor(0.0, 0.15, "castor"),
        ),
    ),
}
"""Three-wheel robots of the five admissible types (Lecture: "Robots à 3 roues pour chaque type
admissible"; Campion et al. 1996); the key is the type the lecture assigns, the tests compute it."""


@dataclass(frozen=True)
class BicycleExercise:
    """Degrees of the lecture's bicycles: Example 2 (both wheels fixed), the exercise's
    front-steered bicycle (point 1) and the rear-steered one (point 2)."""

    fixed: Mobility
    front_steered: Mobility
    rear_steered: Mobility


def bicycle_exercise(ell: float = 0.5) -> BicycleExercise:
    """Lecture: Exemple 2 (vélo à roues fixes: delta_m = 1, delta_s = 0, delta_M = 1) and the
    Exercise (vélo avec roue avant orientable: delta_m = delta_s = 1; roue arrière orientable)."""
    ell = _positive("ell", ell)
    return BicycleExercise(
        _bicycle_lecture("fixed", "fixed", ell).mobility(),
        _bicycle_lecture("steerable", "fixed", ell).mobility(),
        _bicycle_lecture("fixed", "steerable", ell).mobility(),
    )


# ============================================================================ tricycle exercise
TRICYCLE_CASES = {"a": (1.0, math.pi / 6), "b": (1.0, 0.0), "c": (0.0, math.pi / 6)}
"""Lecture, Exercise (tricycle), point 3: the commands (u1 [m/s], u2 [rad/s]) of cases a, b, c."""
TRICYCLE_Q0 = (0.0, 0.0, math.pi / 4, 0.0)
"""q0 = [0, 0, pi/4, 0] of the exercise."""


def tricycle_exercise(case: str, drive: str = "rear", *, duration: float = 30.0, dt: float = 0.01, D: float = 0.3) -> WheeledSimResult:
    """Lecture, Exercise (tricycle), point 3: from q0 = [0, 0, pi/4, 0], D = 0.3 m, 30 s.

    ``case`` "a" (u1 = 1 m/s, u2 = pi/6 rad/s), "b" (1, 0) or "c" (0, pi/6); ``drive``
    "rear" (the exercise's robot, solution of point 1) or "front".  In case a the steering
    angle reaches pi/2 at t = 3 s: the rear-driven model stops there with status "singular"
    (point 2 of the exercise: the model is not valid everywhere), the front-driven one runs
    the 30 s.
    """
    if case not in TRICYCLE_CASES:
        raise UnknownNameError("tricycle exercise case", case, tuple(TRICYCLE_CASES))
    models = {"rear": RearTricycle, "front": FrontTricycle}
    if drive not in models:
        raise UnknownNameError("tricycle drive", drive, tuple(models))
    model = models[drive](D=D)
    res = simulate_wheeled(model, TRICYCLE_Q0, TRICYCLE_CASES[case], duration, dt)
    res.extras["case"] = case
    return res


__all__ = [
    "ROBOTS",
    "TRICYCLE_CASES",
    "TRICYCLE_Q0",
    "TYPE_EXAMPLES",
    "Bicycle",
    "BicycleExercise",
    "Car",
    "FixedWheelModel",
    "FrontTricycle",
    "Mecanum",
    "Omnidirectional",
    "RearTricycle",
    "SynchroDrive",
    "Unicycle",
    "bicycle_exercise",
    "differential_drive",
    "differential_drive_inverse",
    "get_robot",
    "icr_offset",
    "tricycle_exercise",
]
