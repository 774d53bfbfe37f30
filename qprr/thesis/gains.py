"""The gain tables of Thesis Chapter 6 for the Q-PRR, as printed, and the stable replacements the scenarios use.

Every controller of :mod:`qprr.control` takes per-coordinate gain vectors (order x, y, z, phi,
theta, psi, r0, theta2, theta3).  Under exact linearisation each error obeys
e''' + k_D e'' + k_P e' + k_I e = 0 (Routh-Hurwitz: stable iff k_D, k_I > 0 and k_D k_P > k_I;
:meth:`IDCGains.unstable_axes`).  Printed tables that fail it are kept as printed and replaced,
in the scenarios, by the documented retunings below (docs/thesis-errata.md).
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..control.impedance import ImpedanceGains
from ..control.inverse_dynamics import IDCGains
from ..control.mfc import MFCGains

NAMES = ("x", "y", "z", "phi", "theta", "psi", "r0", "theta2", "theta3")


def _cubed(w: float) -> tuple[float, float, float]:
    """(k_P, k_D, k_I) giving the error polynomial (s + w)^3: k_P = 3w^2, k_D = 3w, k_I = w^3."""
    return 3 * w * w, 3 * w, w**3


# ------------------------------------------------------------------- Sec. 6.3.1, Table 6.2
def table_6_2() -> IDCGains:
    """Printed Table 6.2: K_pP = 1.4 I3, K_pD = 0.3 I3, K_qP = 16 I3, K_qD = 3 I3, attitude PIDs (20, 70, 3), (6, 14, 1.1), (1.5, 1.7, 0.2).

    Its attitude PIDs are unstable under exact linearisation (k_D k_P < k_I for phi (60 < 70),
    theta (6.6 < 14) and psi (0.3 < 1.7)).
    """
    return IDCGains(
        kp=(1.4, 1.4, 1.4, 20.0, 6.0, 1.5, 16.0, 16.0, 16.0),
        kd=(0.3, 0.3, 0.3, 3.0, 1.1, 0.2, 3.0, 3.0, 3.0),
        ki=(0.0, 0.0, 0.0, 70.0, 14.0, 1.7, 0.0, 0.0, 0.0),
    )


def idc() -> IDCGains:
    """Table 6.2 position and arm gains; attitude PIDs retuned to be stable: (s + 10)^3 on every angle.

    Well damped and about ten times faster than the position loop (sqrt(1.4) = 1.2 rad/s), as a
    cascade needs.
    """
    base = table_6_2()
    kp_a, kd_a, ki_a = _cubed(10.0)
    return IDCGains(
        kp=base.kp[0:3] + (kp_a,) * 3 + base.kp[6:9], kd=base.kd[0:3] + (kd_a,) * 3 + base.kd[6:9], ki=(0.0,) * 3 + (ki_a,) * 3 + (0.0,) * 3
    )


def desired_state() -> IDCGains:
    """Gains of the desired-state controller: (A.3)'s K_P = 30 with K_D = 2 sqrt(30) on position, the
    attitude PIDs of :func:`idc`, stiffer arm loops, roll/pitch filter 20 rad/s.

    * Position: K_P = 30, the gain (A.3) is written with, and K_D = 2 sqrt(K_P) = 10.95 (critical
      damping) instead of the printed 18, which puts the position loop's crossover at 18 rad/s,
      beyond what the thrust-direction cascade delivers (a barely damped 3 Hz roll/pitch
      oscillation, docs/notes-spikes.md).
    * Roll/pitch: the feedback part of the reference stays slow (20 rad/s): B is 2.5 cm below the
      CoG, so a pitch acceleration moves B sideways at once and K_D on the velocity of B feeds that
      back into the pitch reference.
    * Arm: k_P = w^2, k_D = 2 w with w = 50 rad/s.  The arm stands above B (an inverted pendulum);
      the desired-state controller uses G(xi_d), so the mismatch dG/dq (q - q_d) acts as a negative
      stiffness (about 0.05 N m/rad on theta3, 0.5 on theta2, against B_qq k_qP = 0.004 and 0.09
      with k_qP = 16).  Measured on the static mission: w <= 25 rad/s diverges, 40 and more track.
    """
    base = idc()
    w = 50.0
    kp_pos = 30.0
    kp = (kp_pos,) * 3 + base.kp[3:6] + (w * w,) * 3
    kd = (2.0 * math.sqrt(kp_pos),) * 3 + base.kd[3:6] + (2 * w,) * 3
    return IDCGains(kp=kp, kd=kd, ki=base.ki, filter_omega=20.0, max_tilt=base.max_tilt)


def desired_state_as_printed() -> IDCGains:
    """:func:`desired_state` with the position K_D = 18 printed with (A.3) (Table 6.2) instead of 2 sqrt(30): stable,
    but its roll/pitch ring at 3 Hz (docs/control.md, Table 6.3 cell by cell)."""
    base = desired_state()
    return replace(base, kd=(18.0,) * 3 + tuple(base.kd[3:]))


def annex_a3() -> IDCGains:
    """(A.3) with Table 6.2's K_P = 30 I9, K_D = 18 I9 (no integral), as printed for the desired-state controller."""
    return IDCGains(kp=(30.0,) * 9, kd=(18.0,) * 9, ki=(0.0,) * 9)


# ------------------------------------------------------------------- Sec. 6.4, Tables 6.5, 6.7
# (k_P, k_D, k_I) per group (position, attitude, arm): IDCGains.from_groups
def table_6_5() -> IDCGains:
    """Thesis Table 6.5 as printed: position PD (20, 2), attitude PI (6.56) (k_P = 20, 40, 20; k_I = 5, 2, 2), arm PID (10, 2, 15).

    The attitude PI (k_D = 0) gives s^3 + k_P s + k_I, whose roots sum to zero: unstable for
    every k_I > 0.  The 9x9 K_P = 48 I9, K_D = 25 I9 of the table belong to the generic form (6.54)
    of which the layers are the per-group instances; they are not used on top of the layer gains.
    """
    return IDCGains.from_groups(3, position=(20.0, 2.0, 0.0), attitude=((20.0, 40.0, 20.0), 0.0, (5.0, 2.0, 2.0)), arm=(10.0, 2.0, 15.0))


def payload_idc() -> IDCGains:
    """Table 6.5 position PD kept; attitude PID (s + 15)^3, arm PID (s + 10)^3.

    Attitude: the printed PI is unstable; (s + 15)^3 is three times the position loop's natural
    frequency sqrt(20) = 4.5 rad/s.  Arm: the printed PID (10, 2, 15) is stable but its error
    polynomial s^3 + 2 s^2 + 10 s + 15 has roots -0.20 +- 3.05j (damping ratio 0.065: a disturbance
    rings for ~20 s).  Inverse dynamics makes the arm's stiffness to torque errors k_P times the
    link inertia (~2.5e-4 kg m^2 for theta3), so a payload release (0.07 N m step on theta3 until
    the estimate follows) needs the faster arm loop.
    """
    base = table_6_5()
    return IDCGains.from_groups(3, position=(base.kp[0:3], base.kd[0:3], base.ki[0:3]), attitude=_cubed(15.0), arm=_cubed(10.0))


def table_6_7() -> IDCGains:
    """Thesis Table 6.7 as printed: position PD (6, 5), attitude PD (5, 2; 5, 2; 25, 4.5), arm PI (8, 2) (no rate term)."""
    return IDCGains.from_groups(3, position=(6.0, 5.0, 0.0), attitude=((5.0, 5.0, 25.0), (2.0, 2.0, 4.5), 0.0), arm=(8.0, 0.0, 2.0))


def impedance_idc() -> IDCGains:
    """Table 6.7 position PD kept (poles -2, -3); attitude PD (s + 15)^2, arm PID (s + 5)^3, roll/pitch filter 20 rad/s.

    Attitude: the printed PD (k_P = 5, k_D = 2: poles -1 +- 2j) is slower than the position loop it
    serves.  Arm: the printed PI (6.79) has no rate term (s^3 + 8 s + 2, unstable).  The roll/pitch
    command filter is slowed to 20 rad/s: the impedance filter's reference acceleration steps by
    h/M_D (2 m/s^2 for h_b = 0.2 N, M_D = 0.1 kg) when the force switches, a 0.2 rad step of the
    (6.17) pitch command; at 50 rad/s the filtered command then asks for 5.6 N m, beyond the
    rotors' 4.5 N m.
    """
    base = table_6_7()
    w = 15.0
    position = (base.kp[0:3], base.kd[0:3], base.ki[0:3])
    return IDCGains.from_groups(3, position=position, attitude=(w * w, 2 * w, 0.0), arm=_cubed(5.0), filter_omega=20.0)


def impedance_table_6_7() -> ImpedanceGains:
    """Thesis Table 6.7: M_D = 0.1 I4, D_D = I4, K_P = 0.5 I4; M_D^q = 0.02 I3, D_D^q = I3, K_P^q = 0.08 I3."""
    return ImpedanceGains(M_base=(0.1,) * 4, D_base=(1.0,) * 4, K_base=(0.5,) * 4, M_arm=(0.02,) * 3, D_arm=(1.0,) * 3, K_arm=(0.08,) * 3)


def impedance_filters() -> ImpedanceGains:
    """Table 6.7 with the slider stiffness raised to 2.5 N/m.

    With K_P^q = 0.08 N/m the slider yields 0.625 m under the 0.05 N of Sec. 6.4.3.4, 15 times its
    +-0.04 m stroke; 2.5 N/m gives 0.02 m.  Its damping stays D = 1 N s/m.
    """
    return replace(impedance_table_6_7(), K_arm=(2.5, 0.08, 0.08))


# ------------------------------------------------------------------- Sec. 6.3.3.2
def mfc() -> MFCGains:
    """K_P = 60 I9, K_I = 8 I9, K_D = 35 I9 (Sec. 6.3.3.2); the estimator settings of :class:`MFCGains`."""
    return MFCGains(kp=(60.0,) * 9, ki=(8.0,) * 9, kd=(35.0,) * 9, f_filter=(0.2, 0.2) + (0.0,) * 7)
