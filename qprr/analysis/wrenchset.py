"""The set of base wrenches a rotor set can produce, as half-spaces: hover feasibility, margins, authority.

With thrusts bounded, f_min <= f_i <= f_max, the rotors of a platform produce the base wrenches
(at B, in B axes, Thesis (3.31)-(3.36), :attr:`Platform.rotor_matrix` Omega)

    Z = { Omega f : f_min <= f <= f_max },

a zonotope: the centre c = Omega (f_min + f_max)/2 plus the segments [-1, 1] g_i with
generators g_i = Omega_i (f_max,i - f_min,i)/2.  It lies in the range of Omega (dimension
r = :attr:`Platform.wrench_rank`: 4 for coplanar rotors, f_z and the three torques; 6 for a
fully actuated tilted hexarotor).  In coordinates y = U^T w on an orthonormal basis U of that
range, Z is the intersection of the half-spaces a_k . y <= b_k whose normals a_k are
perpendicular to r - 1 of the generators, with b_k = a_k . c + sum_i |a_k . g_i|
(the facets of a zonotope).  That representation makes every question exact and batched:

* feasibility of a wrench w (an allocation inside the bounds exists): w in the range and
  a_k . y <= b_k for every k (:meth:`WrenchSet.contains`);
* the largest step t along a direction d with w + t d in Z (:meth:`WrenchSet.ray`): the
  attitude authority left at a hover wrench (d a unit torque about x, y or z of B), the
  payload a hover wrench can still take (d the wrench of one kilogram);
* the best thrust margin any allocation keeps (:meth:`WrenchSet.thrust_margin`): with equal
  bounds on every rotor, shrinking the thrust box by s on each side shrinks Z about its centre
  by the factor 1 - 2 s / (f_max - f_min), so the largest s with w still inside is read from
  the gauge of w - c.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..model import Platform, check_platform
from ..validation import as_array

AXES = ("f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z")
"""Names of the base-wrench components (at B, in B axes)."""


@dataclass(frozen=True)
class WrenchSet:
    """Z = {Omega f : f_min <= f <= f_max} as half-spaces (see the module docstring).

    ``basis`` (r, 6): orthonormal rows spanning the producible wrenches; ``normals`` (m, r) unit
    facet normals and ``offsets`` (m,) in those coordinates; ``centre`` (6,) and
    ``generators`` (6, n) of the zonotope; ``thrust_min``/``thrust_max`` (n,) the bounds [N].
    """

    basis: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray
    centre: np.ndarray
    generators: np.ndarray
    thrust_min: np.ndarray
    thrust_max: np.ndarray

    @property
    def rank(self) -> int:
        return int(self.basis.shape[0])

    @property
    def equal_bounds(self) -> bool:
        return bool(np.allclose(self.thrust_min, self.thrust_min[0]) and np.allclose(self.thrust_max, self.thrust_max[0]))

    def _scale(self) -> float:
        return float(np.abs(self.offsets).max())

    def coords(self, w) -> tuple[np.ndarray, np.ndarray]:
        """(y = U^T w (..., r), norm of the part of w outside the range (...)) for wrenches w (..., 6)."""
        w = np.asarray(w, dtype=float)
        y = w @ self.basis.T
        out = w - y @ self.basis
        return y, np.sqrt((out**2).sum(axis=-1))

    def slack(self, w) -> np.ndarray:
        """b_k - a_k . y (..., m): >= 0 on every facet inside Z."""
        y, _ = self.coords(w)
        return self.offsets - y @ self.normals.T

    def contains(self, w, tol: float = 1e-9) -> np.ndarray:
        """Whether each wrench (..., 6) can be produced within the thrust bounds (relative tolerance ``tol``)."""
        y, off = self.coords(w)
        s = self.offsets - y @ self.normals.T
        scale = self._scale()
        return (s.min(axis=-1) >= -tol * scale) & (off <= tol * scale)

    def ray(self, w, d, tol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
        """(t_lo, t_hi): {t : w + t d in Z} = [t_lo, t_hi] for wrenches w (n, 6) and directions d (n, 6) or (6,).

        Empty when t_lo > t_hi.  A direction with a part outside the producible range gives the
        interval [0, 0] if w is inside (no step possible) and an empty one otherwise.
        """
        w = np.atleast_2d(np.asarray(w, dtype=float))
        d = np.asarray(d, dtype=float)
        y, wout = self.coords(w)
        s = self.offsets - y @ self.normals.T  # (n, m)
        scale = self._scale()
        inside = (s.min(axis=1) >= -1e-9 * scale) & (wout <= 1e-9 * scale)
        yd, dout = self.coords(d)
        ad = yd @ self.normals.T  # (m,) or (n, m)
        eps = tol * max(float(np.abs(ad).max()) if ad.size else 0.0, 1e-300)
        dn = np.sqrt((d**2).sum(axis=-1))
        if d.ndim == 1:  # one direction for every wrench: select the facets once
            pos, neg = ad > eps, ad < -eps
            par = ~(pos | neg)
            up = (s[:, pos] / ad[pos]).min(axis=1) if pos.any() else np.full(w.shape[0], np.inf)
            down = (s[:, neg] / ad[neg]).max(axis=1) if neg.any() else np.full(w.shape[0], -np.inf)
            bad = (s[:, par] < -1e-9 * scale).any(axis=1) if par.any() else np.zeros(w.shape[0], dtype=bool)
            outside = np.full(w.shape[0], dout > 1e-12 * max(float(dn), 1e-300))
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                up = np.where(ad > eps, s / ad, np.inf).min(axis=1)
                down = np.where(ad < -eps, s / ad, -np.inf).max(axis=1)
            bad = ((np.abs(ad) <= eps) & (s < -1e-9 * scale)).any(axis=1)  # facets parallel to d: w must satisfy them
            outside = dout > 1e-12 * np.maximum(dn, 1e-300)
        up = np.where(bad, -np.inf, up)
        down = np.where(bad, np.inf, down)
        up = np.where(outside, np.where(inside, 0.0, -np.inf), up)
        down = np.where(outside, np.where(inside, 0.0, np.inf), down)
        return down, up

    def authority(self, w, axes=(3, 4, 5)) -> np.ndarray:
        """(n, len(axes), 2): the largest wrench component still producible on top of w, per axis
        [N or N m], in the - and + direction (0 where none: w outside Z, or an axis the rotors
        cannot produce), with the other components held."""
        w = np.atleast_2d(np.asarray(w, dtype=float))
        out = np.zeros((w.shape[0], len(axes), 2))
        for j, ax in enumerate(axes):
            e = np.zeros(6)
            e[ax] = 1.0
            lo, hi = self.ray(w, e)
            ok = lo <= hi
            out[:, j, 0] = np.where(ok, np.clip(-lo, 0.0, None), 0.0)
            out[:, j, 1] = np.where(ok, np.clip(hi, 0.0, None), 0.0)
        return out

    def gauge(self, w) -> np.ndarray:
        """max_k a_k . (y - y_c) / (b_k - a_k . y_c): <= 1 inside Z, the factor Z must grow by about its centre to reach w."""
        y, _ = self.coords(w)
        yc = self.centre @ self.basis.T
        return ((y - yc) @ self.normals.T / (self.offsets - self.normals @ yc)).max(axis=-1)

    def thrust_margin(self, w) -> np.ndarray:
        """Largest s [N] such that some allocation of w keeps every thrust in [f_min + s, f_max - s]
        (negative: w is infeasible by that much).  Needs equal bounds on every rotor."""
        if not self.equal_bounds:
            raise InputError("thrust_margin needs the same bounds on every rotor; use the allocation's per-rotor margins")
        span = float(self.thrust_max[0] - self.thrust_min[0])
        m = 0.5 * span * (1.0 - self.gauge(w))
        _, out = self.coords(w)
        return np.where(out > 1e-9 * self._scale(), -np.inf, m)

    def shrunk(self, reserve, axes=(3, 4, 5)) -> WrenchSet:
        """The wrenches w such that w + t e stays in Z for every |t| <= reserve[j] along each axis e of ``axes``.

        ``reserve``: one value [N or N m] per axis (or one for all).  Each offset b_k becomes
        b_k - max_j reserve_j |a_k . e_j| (the directions are asked one at a time).
        """
        reserve = np.broadcast_to(np.asarray(reserve, dtype=float), (len(axes),))
        if np.any(reserve < 0) or not np.all(np.isfinite(reserve)):
            raise InputError(f"reserve must be finite and >= 0, got {reserve.tolist()}")
        E = np.zeros((len(axes), 6))
        E[np.arange(len(axes)), list(axes)] = 1.0
        ae = np.abs(self.normals @ (E @ self.basis.T).T)  # (m, len(axes))
        cut = (ae * reserve[None, :]).max(axis=1)
        return WrenchSet(self.basis, self.normals, self.offsets - cut, self.centre, self.generators, self.thrust_min, self.thrust_max)

    def force_max(self, direction=(0.0, 0.0, 1.0)) -> float:
        """Largest force [N] along ``direction`` (in B) the rotors produce with no force across it, any torque.

        A linear programme over the thrust box (scipy ``linprog``, HiGHS).  For coplanar rotors
        along z_B and the vertical: sum f_max; the collective-thrust limit of a transport mission.
        """
        from scipy.optimize import linprog

        u = np.asarray(direction, dtype=float)
        u = u / np.linalg.norm(u)
        omega = self.generators / (0.5 * (self.thrust_max - self.thrust_min))[None, :]
        F = omega[0:3]
        P = np.eye(3) - np.outer(u, u)
        res = linprog(-(u @ F), A_eq=P @ F, b_eq=np.zeros(3), bounds=list(zip(self.thrust_min, self.thrust_max)), method="highs")
        if not res.success:
            return 0.0
        return float(-res.fun)


def _facets(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit facet normals (m, r) of the zonotope with generators G (r, n), and their support sum |a . g_i|."""
    r, n = G.shape
    if r == 1:
        a = np.array([[1.0], [-1.0]])
        return a, np.abs(a @ G).sum(axis=1)
    normals = []
    for S in itertools.combinations(range(n), r - 1):
        M = G[:, S].T  # (r-1, r)
        _, s, vt = np.linalg.svd(M)
        if s[-1] < 1e-9 * max(s[0], 1e-300):  # the r-1 generators are dependent: no facet
            continue
        a = vt[-1]
        a = a / np.linalg.norm(a)
        normals.extend([a, -a])
    A = np.array(normals)
    # the same facet from several generator subsets: keep one of each normal
    key = np.round(A, 9)
    _, idx = np.unique(key, axis=0, return_index=True)
    A = A[np.sort(idx)]
    return A, np.abs(A @ G).sum(axis=1)


def wrench_set(platform: Platform, thrust_min=None, thrust_max=None) -> WrenchSet:
    """The :class:`WrenchSet` of ``platform``'s rotors (bounds default to the rotors' f_min, f_max).

    Raises InputError when a rotor has no finite f_max (the set is unbounded).
    """
    check_platform(platform)
    thrust_min = None if thrust_min is None else as_array(thrust_min, "thrust_min", finite=True)
    thrust_max = None if thrust_max is None else as_array(thrust_max, "thrust_max", finite=True)
    fmin = np.array(platform.thrust_min if thrust_min is None else np.broadcast_to(thrust_min, (platform.n_rotors,)), dtype=float)
    fmax = np.array(platform.thrust_max if thrust_max is None else np.broadcast_to(thrust_max, (platform.n_rotors,)), dtype=float)
    if not np.all(np.isfinite(fmax)):
        raise InputError(f"platform {platform.name!r} has rotors without a finite f_max: the wrench set is unbounded")
    if np.any(fmin >= fmax) or np.any(fmin < 0):
        raise InputError(f"thrust bounds must satisfy 0 <= f_min < f_max, got {fmin.tolist()}, {fmax.tolist()}")
    Omega = np.array(platform.rotor_matrix)
    U, s, _ = np.linalg.svd(Omega)
    r = int(np.sum(s > 1e-9 * s[0]))
    basis = U[:, :r].T.copy()
    basis[np.abs(basis) < 1e-15] = 0.0
    centre = Omega @ (0.5 * (fmin + fmax))
    gens = Omega * (0.5 * (fmax - fmin))[None, :]
    A, h = _facets(basis @ gens)
    offsets = A @ (basis @ centre) + h
    return WrenchSet(basis, A, offsets, centre, gens, fmin, fmax)
