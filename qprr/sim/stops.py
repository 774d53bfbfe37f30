"""Mechanical stops of the arm joints: plastic impacts at the joint limits (any number of arm joints)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin


def apply_joint_stops(model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """Plastic impacts of the arm joints (q[7 + j], v[6 + j]) at their limits ``lo[j]``, ``hi[j]``.

    Position: a joint past its limit is moved back onto it by the mass-weighted correction
    dq = -M^-1 E (E^T M^-1 E)^-1 penetration, the displacement an internal joint force
    produces, so the system's centre of mass does not move (and the base recoils as it would).
    Velocity: the impulses E lambda that zero the outward rates of the joints at their stops
    act on the whole tree, v+ = v - M^-1 E lambda (M^-1 from Pinocchio), found by projected
    Gauss-Seidel (an impulse only pushes a joint inward).  Being internal they leave the
    momentum unchanged, and kinetic energy can only decrease; a joint held against its stop by
    the controller stays there step after step.
    """
    stops = []  # (velocity index, limit, +1 at the upper stop / -1 at the lower): on or past it
    for j in range(len(lo)):
        if q[7 + j] <= lo[j]:
            stops.append((6 + j, lo[j], -1.0))
        elif q[7 + j] >= hi[j]:
            stops.append((6 + j, hi[j], 1.0))
    if not stops:
        return q, v
    idx = [i for i, _, _ in stops]
    Minv = pin.computeMinverse(model, data, q)
    cols = np.array([_upper_column(Minv, i) for i in idx]).T  # M^-1 E
    penetration = np.array([q[i + 1] - limit for i, limit, _ in stops])
    q = pin.integrate(model, q, -(cols @ np.linalg.solve(cols[idx], penetration)))
    for i, limit, _ in stops:
        q[i + 1] = limit  # exactly on the stop (the correction is exact to first order)
    Minv = pin.computeMinverse(model, data, q)  # the impulses act at the corrected configuration
    cols = {i: _upper_column(Minv, i) for i in idx}
    v = v.copy()
    impulse = {i: 0.0 for i in idx}  # accumulated; side * impulse >= 0 (pushes inward)
    for _ in range(50):
        largest = 0.0
        for i, _, side in stops:
            c = cols[i]
            new = side * max(0.0, side * (impulse[i] + v[i] / c[i]))
            d = new - impulse[i]
            if d != 0.0:
                v -= c * d
                impulse[i] = new
                largest = max(largest, abs(d) * c[i])
        if largest < 1e-12:
            break
    return q, v


def _upper_column(Minv: np.ndarray, i: int) -> np.ndarray:
    """Column i of the symmetric M^-1 read from its upper triangle (all Pinocchio versions fill it)."""
    return np.concatenate((Minv[:i, i], Minv[i, i:]))
