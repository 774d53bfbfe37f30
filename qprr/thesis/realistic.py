"""What a real Q-PRR would meet that the thesis leaves out: motor lag, air drag, joint friction, wind.

The thesis's scenarios fly ideal actuators in still air (Sec. 5.3 drops F_v and D of (5.36)).
This module bundles the Q-PRR's values for the generic stages of :mod:`qprr.sim`
(:class:`~qprr.sim.actuators.RotorDynamics`, :mod:`qprr.sim.wind`) for the ``realistic-*``
scenarios.  None of them is printed in the thesis; each value is chosen and says why:

===================  ================================  =====================================================
quantity             value                             provenance
===================  ================================  =====================================================
thrust factor b      3.0e-5 N s^2                      the parameters' ``thrust_factor`` (chosen there)
speed limits         0 .. sqrt(f_max / b) = 816 rad/s  the thrust bounds [0, 20] N of the parameters
motor time constant  5 ms                              borinot's upstream Gazebo model (qprr/data), a vehicle
                                                       of the same class (2.9 kg); slower motors destabilise
                                                       the thesis-gain controllers: ``qprr compare lag``
rotor drag K_1       (1.0, 1.0, 0.3) N s/m             chosen: ~0.3 m / s^-1 per kg horizontally, the order
                                                       Faessler et al. (RA-L 2018) identify for rotor drag
form drag K_2        (0.03, 0.03, 0.09) N s^2/m^2      1/2 rho C_d A, rho = 1.2 kg/m^3, C_d = 1, frontal area
                                                       0.05 m^2 (side), 0.15 m^2 (top)
angular drag         0.01 N m s/rad                    chosen (small)
joint friction F_v   r0 0.5 N s/m, theta2 7.5e-3,      chosen: F_v / M_jj = 1 s^-1 on every joint (M_jj at the
                     theta3 2.5e-4 N m s/rad           neutral posture: 0.49 kg, 7.4e-3, 2.5e-4 kg m^2), a
                                                       third of the arm loops' k_D = 3 s^-1
mean wind            (2, 1, 0) m/s                     a light breeze (2.2 m/s)
turbulence           Dryden, MIL-F-8785C low altitude,  "light" turbulence (W_20 = 15 kt), the mission's
                     h = 10 m, W_20 = 7.7 m/s,          altitude; V = the mean wind speed (the frozen field
                     V = |mean|                         passes a hovering vehicle at that speed)
gust                 1 - cosine, 2 m/s along y,        during the arm phase of the static mission
                     t = 18 .. 21 s
===================  ================================  =====================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import Platform, check_platform
from ..sim.actuators import RotorDynamics
from ..sim.disturbances import Disturbances
from ..sim.wind import AerodynamicDrag, Dryden, Gust, ViscousFriction, Wind
from ..validation import as_real, as_vector
from .robot import load_qprr, params_of

TIME_CONSTANT = 0.005
"""Motor time constant of the Q-PRR [s] (chosen, see the module table)."""
DRAG_LINEAR = (1.0, 1.0, 0.3)
DRAG_QUADRATIC = (0.03, 0.03, 0.09)
DRAG_ANGULAR = 0.01
FRICTION_ARM = (0.5, 0.0075, 0.00025)
MEAN_WIND = (2.0, 1.0, 0.0)
W20 = 7.7
ALTITUDE = 10.0
GUST = Gust(18.0, 3.0, (0.0, 2.0, 0.0))


def qprr_rotor_dynamics(platform: Platform | None = None, *, time_constant: float = TIME_CONSTANT, **overrides) -> RotorDynamics:
    """The Q-PRR's actuator stage: f = b w^2 with b of its parameters, speeds up to sqrt(f_max / b), lag ``time_constant`` [s]."""
    platform = load_qprr() if platform is None else check_platform(platform)
    time_constant = as_real(time_constant, "time_constant", positive=True, unit="s")
    p = params_of(platform)
    return RotorDynamics.for_rotors(platform.rotors, p.thrust_factor, time_constant, **overrides)


def realistic_wind(mean=MEAN_WIND, w20: float = W20, gust: bool = True, altitude: float = ALTITUDE) -> Wind:
    """The realistic scenarios' wind: ``mean`` [m/s] + Dryden turbulence (``w20`` [m/s]; 0: none) + the gust (or not)."""
    mean = tuple(as_vector(mean, 3, "mean").tolist())
    w20 = as_real(w20, "w20", nonnegative=True, unit="m/s")
    altitude = as_real(altitude, "altitude", positive=True, unit="m")
    speed = float(np.linalg.norm(mean))
    turbulence = Dryden.low_altitude(altitude, w20, max(speed, 1.0)) if w20 > 0.0 else None
    return Wind(tuple(mean), turbulence, (GUST,) if gust else ())


@dataclass(frozen=True)
class Realistic:
    """The realistic stages of one run: ``actuators`` (or None) and ``disturbance`` (drag with wind, friction; or None)."""

    actuators: RotorDynamics | None
    disturbance: Disturbances | None

    def simulate_kwargs(self) -> dict:
        return {"actuators": self.actuators, "disturbance": self.disturbance}


def realistic(
    platform: Platform | None = None,
    *,
    motors: bool = True,
    drag: bool = True,
    friction: bool = True,
    mean_wind=MEAN_WIND,
    w20: float = W20,
    gust: bool = True,
    time_constant: float = TIME_CONSTANT,
) -> Realistic:
    """Every stage of the module table, each switchable (all on by default)."""
    platform = load_qprr() if platform is None else check_platform(platform)
    mean_wind = as_vector(mean_wind, 3, "mean_wind")
    w20 = as_real(w20, "w20", nonnegative=True, unit="m/s")
    time_constant = as_real(time_constant, "time_constant", positive=True, unit="s")
    parts = []
    if drag:
        parts.append(AerodynamicDrag(DRAG_LINEAR, DRAG_QUADRATIC, DRAG_ANGULAR, realistic_wind(mean_wind, w20, gust)))
    if friction:
        parts.append(ViscousFriction((0.0,) * 6 + FRICTION_ARM))
    act = qprr_rotor_dynamics(platform, time_constant=time_constant, initial="hover") if motors else None
    return Realistic(act, Disturbances(tuple(parts)) if parts else None)


def steady_wind_offset(platform: Platform | None = None, kp_position: float = 1.4, mean_wind=MEAN_WIND) -> float:
    """Steady position offset [m] a PD position loop of gain ``kp_position`` [1/s^2] leaves in the mean wind:
    |F_drag| / (m k_P), with the drag of the module table at rest (v_r = -w).  For the Table 6.2 gains (k_P = 1.4)."""
    platform = load_qprr() if platform is None else check_platform(platform)
    kp_position = as_real(kp_position, "kp_position", positive=True, unit="1/s^2")
    w = as_vector(mean_wind, 3, "mean_wind")
    F = np.asarray(DRAG_LINEAR) * w + np.asarray(DRAG_QUADRATIC) * np.linalg.norm(w) * w
    return float(np.linalg.norm(F) / (platform.total_mass * kp_position))


__all__ = ["GUST", "TIME_CONSTANT", "Realistic", "realistic", "qprr_rotor_dynamics", "steady_wind_offset", "realistic_wind"]
