"""Rigid-body inertia: the conditions a mass and an inertia must meet to be a body, in one place.

A body of mass m > 0 with rotational inertia I about its CoM exists iff I is symmetric positive
(semi-)definite and its principal moments satisfy the triangle inequalities I_k <= I_i + I_j,
i.e. every second moment of mass Sigma_k = integral of x_k^2 dm = (I_i + I_j - I_k) / 2 is >= 0.
:func:`check_rigid_body` raises :class:`~qprr.errors.NonPhysicalError` naming the body and the
inequality; platforms (:mod:`qprr.model`) and parameter sets (:mod:`qprr.thesis.params`) call it.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from ..errors import InputError, NonPhysicalError
from ..validation import as_array, as_file, as_vector

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, a dependency of the package there (pyproject.toml)
    import tomli as tomllib

TRIANGLE_RTOL = 1e-12
"""Relative tolerance (of the largest principal moment) of the triangle inequalities: a body on the boundary
(a lamina, one second moment of mass zero) is physical and its moments carry round-off."""


def _finite(values) -> bool:
    return all(isinstance(x, (int, float, np.floating, np.integer)) and math.isfinite(x) for x in values)


def _physical(convert, *args):
    """``convert(*args)`` (a qprr.charts converter) with its errors as :class:`NonPhysicalError` (a body that cannot exist)."""
    try:
        return convert(*args)
    except InputError as exc:
        raise NonPhysicalError(str(exc)) from None


def second_moments(moments) -> np.ndarray:
    """Second moments of mass Sigma_k = (I_i + I_j - I_k) / 2 [kg m^2] along the axes of the moments (I_1, I_2, I_3).

    Sigma_k = integral of x_k^2 dm: a body exists iff all three are >= 0, i.e. iff the moments satisfy the
    triangle inequalities I_k <= I_i + I_j."""
    I = as_vector(moments, 3, "moments")
    return 0.5 * (I.sum() - 2.0 * I)


def nearest_physical_moments(moments) -> np.ndarray:
    """The physical principal moments nearest to ``moments`` in second moments of mass: negative Sigma_k set to 0.

    For a diagonal tensor this is the projection of the second-moment matrix diag(Sigma) onto the positive
    semi-definite cone (Frobenius norm), the condition of physical consistency of a rigid body's inertia.  The
    moments whose axes keep their second moments change as little as possible; with one negative Sigma_k the
    moment I_k about that axis is unchanged and the two others grow by -Sigma_k."""
    S = np.maximum(second_moments(moments), 0.0)
    return S.sum() - S


def check_rigid_body(body: str, mass: float, com, inertia, *, check_triangle: bool = True, allow_massless: bool = False) -> None:
    """Raise :class:`NonPhysicalError` unless (mass [kg], com [m], inertia (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) [kg m^2])
    can be a rigid body: finite values, mass > 0, a symmetric positive semi-definite rotational inertia (a point
    mass or a thin rod has a zero principal moment) whose principal
    moments satisfy the triangle inequalities I_k <= I_i + I_j (``check_triangle``), i.e. no negative second moment
    of mass.  ``inertia`` may also be a 3x3 matrix.  ``allow_massless``: mass 0 with a zero inertia is accepted
    (a frame-only link of a URDF)."""
    I3 = _physical(as_array, inertia, f"{body} inertia")
    if I3.shape == (3, 3):
        if not np.all(np.isfinite(I3)):
            raise NonPhysicalError(f"{body}: inertia must be a finite 3x3 matrix, got {I3.tolist()}")
        if not np.allclose(I3, I3.T, rtol=0.0, atol=1e-12 * max(1e-300, float(np.abs(I3).max()))):
            raise NonPhysicalError(f"{body}: inertia must be symmetric, got {I3.tolist()}")
        inertia = (float(I3[0, 0]), float(I3[1, 1]), float(I3[2, 2]), float(I3[0, 1]), float(I3[0, 2]), float(I3[1, 2]))
    inertia = tuple(_physical(as_vector, inertia, 6, f"{body} inertia (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) [kg m^2]").tolist())
    if allow_massless and _finite([mass]) and mass == 0.0:
        if all(float(x) == 0.0 for x in inertia):
            return
        raise NonPhysicalError(f"{body}: a massless body cannot have a rotational inertia, got {tuple(inertia)!r}")
    if not (_finite([mass]) and mass > 0.0):
        bound = ">= 0 kg (0 only with a zero inertia)" if allow_massless else "> 0 kg"
        raise NonPhysicalError(f"{body}: mass must be finite and {bound}, got {mass!r}")
    _physical(as_vector, com, 3, f"{body} com (centre of mass, m)")
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    diagonal = ixy == 0.0 and ixz == 0.0 and iyz == 0.0
    moments = np.array([ixx, iyy, izz]) if diagonal else np.linalg.eigvalsh(np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
    names = ("I_xx", "I_yy", "I_zz") if diagonal else ("I_1", "I_2", "I_3")
    axes = ("x", "y", "z") if diagonal else ("principal axis 1", "principal axis 2", "principal axis 3")
    if moments.min() < -TRIANGLE_RTOL * max(float(np.abs(moments).max()), 1e-300):
        k = int(np.argmin(moments))
        raise NonPhysicalError(
            f"{body}: rotational inertia is not positive semi-definite, {names[k]} = {moments[k]:.6g} kg m^2 (inertia {tuple(inertia)!r})"
        )
    if not check_triangle:
        return
    sigma = second_moments(moments)
    k = int(np.argmin(sigma))
    if sigma[k] < -TRIANGLE_RTOL * moments.max():
        i, j = (m for m in range(3) if m != k)
        raise NonPhysicalError(
            f"{body}: principal moments {tuple(float(x) for x in moments)} kg m^2 break the triangle inequality "
            f"{names[k]} <= {names[i]} + {names[j]}: {moments[k]:.6g} > {moments[i] + moments[j]:.6g} by {-2.0 * sigma[k]:.4g} kg m^2, "
            f"a negative second moment of mass along {axes[k]} ({sigma[k]:.4g} kg m^2)"
        )


# ------------------------------------------------------------------ inertial overrides (a TOML file)
INERTIAL_KEYS = ("mass", "com", "inertia")
"""The keys of a link's table in an inertial-overrides file: mass [kg], com [m] (3), inertia [kg m^2] (6)."""


def read_inertials(path) -> dict:
    """Parse an inertial-overrides TOML file: one table ``[link.NAME]`` per moving body, with any of ``mass = m``
    [kg], ``com = [x, y, z]`` [m] (the centre of mass in the link's frame) and ``inertia = [ixx, ixy, ixz, iyy,
    iyz, izz]`` [kg m^2] (about the centre of mass, the link frame's axes; the order of URDF's <inertia>).  Returns
    {NAME: {key: value}}; every value checked for its shape and finiteness (``mass`` > 0); the physics of the whole
    body (the triangle inequalities) is checked when it is applied (:func:`qprr.model.apply_inertials`)."""
    path = as_file(path, "inertials", what="inertial-overrides TOML file")
    try:
        desc = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"inertials: {str(path)!r} is not valid TOML: {exc}") from None
    links = desc.get("link")
    if set(desc) != {"link"} or not isinstance(links, dict) or not links:
        raise InputError(f"inertials: {str(path)!r} must hold only [link.NAME] tables (got the keys {sorted(desc)})")
    out = {}
    for name, entry in links.items():
        where = f"inertials {path.name}: link {name!r}"
        if not isinstance(entry, dict) or not entry or set(entry) - set(INERTIAL_KEYS):
            raise InputError(f"{where} must be a table of {', '.join(INERTIAL_KEYS)}, got {entry!r}")
        values = {}
        if "mass" in entry:
            m = entry["mass"]
            if not (_finite([m]) and m > 0.0):
                raise NonPhysicalError(f"{where}: mass must be finite and > 0 kg, got {m!r}")
            values["mass"] = float(m)
        if "com" in entry:
            values["com"] = as_vector(entry["com"], 3, f"{where} com [m]")
        if "inertia" in entry:
            values["inertia"] = as_vector(entry["inertia"], 6, f"{where} inertia [ixx, ixy, ixz, iyy, iyz, izz] [kg m^2]")
        out[str(name)] = values
    return out


def inertia_matrix(ixx_ixy_ixz_iyy_iyz_izz) -> np.ndarray:
    """The 3x3 matrix of URDF's six inertia values (ixx, ixy, ixz, iyy, iyz, izz)."""
    xx, xy, xz, yy, yz, zz = (float(v) for v in ixx_ixy_ixz_iyy_iyz_izz)
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
