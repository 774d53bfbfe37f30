"""Closed forms of the Q-PRR's planar arm used as references by the analysis tests.

The arm moves the end effector in the x-z plane of B: p = (r0 + d2 s2 + d3 s23, h + d2 c2 + d3 c23),
h = d0 + d1 (Thesis (3.58)), theta2 in [-a, a], theta3 in [-b, b], r0 in [r_lo, r_hi].

2R part (r0 fixed): about joint 2, a point at distance rho from it is reached with
theta3 = +-acos((rho^2 - d2^2 - d3^2) / (2 d2 d3)) and theta2 = phi -+ delta(rho), phi the polar
angle from z, delta = atan2(d3 sin theta3, d2 + d3 cos theta3).  So the region is
{rho in [rho(b), d2 + d3], |phi| <= a + min(delta(rho), a)} (the union of the two elbow
branches), its area  A = int (2a + 2 min(delta, a)) rho drho  and, turned about the z axis
through joint 2 (the hover workspace of the Q-PRR with r0 = 0: joint 2 is on z_B),
V = 2 pi int rho^2 (1 - cos(a + min(delta, a))) drho  (Pappus over the right half).

2R + P (the slider): the region swept by translating the 2R region along x by [r_lo, r_hi];
each horizontal slice is the 2R slice grown by the stroke, gaps shorter than the stroke filled.
Its area is integrated over z with the slice ends found by bisection on the exact predicate.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate


class PlanarArm:
    def __init__(self, params):
        self.d2, self.d3 = params.d2, params.d3
        self.h = params.d0 + params.d1
        self.a = params.theta2_limits[1]
        self.b = params.theta3_limits[1]
        self.r_lo, self.r_hi = params.r0_limits
        assert params.theta2_limits[0] == -self.a and params.theta3_limits[0] == -self.b
        self.rho_min = np.sqrt(self.d2**2 + self.d3**2 + 2 * self.d2 * self.d3 * np.cos(self.b))
        self.rho_max = self.d2 + self.d3

    def delta(self, rho):
        c3 = np.clip((rho**2 - self.d2**2 - self.d3**2) / (2 * self.d2 * self.d3), -1.0, 1.0)
        t3 = np.arccos(c3)
        return np.arctan2(self.d3 * np.sin(t3), self.d2 + self.d3 * np.cos(t3))

    def half_angle(self, rho):
        return np.minimum(np.pi, self.a + np.minimum(self.delta(rho), self.a))

    def area_2r(self) -> float:
        f = lambda r: 2.0 * float(self.half_angle(r)) * r  # noqa: E731
        return integrate.quad(f, self.rho_min, self.rho_max, epsabs=1e-15, epsrel=1e-13, limit=400)[0]

    def volume_2r_revolved(self) -> float:
        f = lambda r: r * r * (1.0 - np.cos(float(self.half_angle(r))))  # noqa: E731
        return 2.0 * np.pi * integrate.quad(f, self.rho_min, self.rho_max, epsabs=1e-15, epsrel=1e-13, limit=400)[0]

    def inside_2r(self, x, z):
        """Exact membership of (x, z) relative to joint 2 (z measured from joint 2)."""
        rho = np.hypot(x, z)
        phi = np.arctan2(x, z)
        ok = (rho >= self.rho_min) & (rho <= self.rho_max)
        return ok & (np.abs(phi) <= self.half_angle(np.clip(rho, self.rho_min, self.rho_max)))

    def slices(self, zs: np.ndarray, nx: int = 4001):
        """Interval ends of the 2R region on each horizontal line z (relative to joint 2), by bisection."""
        xs = np.linspace(-self.rho_max - 1e-9, self.rho_max + 1e-9, nx)
        X, Z = np.meshgrid(xs, zs)
        ins = self.inside_2r(X, Z)
        out = []
        for k, z in enumerate(zs):
            edges = np.flatnonzero(np.diff(ins[k].astype(np.int8)))
            lo, hi = xs[edges].copy(), xs[edges + 1].copy()
            lo_in = ins[k][edges]
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                m_in = self.inside_2r(mid, np.full_like(mid, z))
                same = m_in == lo_in
                lo = np.where(same, mid, lo)
                hi = np.where(same, hi, mid)
            out.append(0.5 * (lo + hi))
        return out

    def area_swept(self, nz: int = 2001) -> float:
        """Area of the 2R + P region (slider stroke r_hi - r_lo): trapezoids over z of the swept slice lengths
        (relative accuracy about 1e-4: slices kink where the topology changes)."""
        L = self.r_hi - self.r_lo
        zs = np.linspace(-self.rho_max, self.rho_max, nz)
        f = np.zeros(nz)
        for k, pts in enumerate(self.slices(zs)):
            if len(pts) == 0:
                continue
            iv = list(zip(pts[0::2], pts[1::2]))
            tot = sum(e - s for s, e in iv) + L
            for (_, e0), (s1, _) in zip(iv[:-1], iv[1:]):
                tot += min(s1 - e0, L)
            f[k] = tot
        return float(np.trapezoid(f, zs))

    def boundary_2r(self, n: int = 4000) -> np.ndarray:
        """Points (m, 2) on the exact boundary of the 2R region, in B's (x, z) (r0 = 0).

        The boundary is made of images of the joint-box faces and of the singular set (theta3 = 0,
        the arm straight): the outer arc, the inner arc (theta3 at a limit) and the circles of
        radius d3 about the elbow at theta2 = +-a; the parts of these curves inside the region are dropped.
        """
        a, b, d2, d3 = self.a, self.b, self.d2, self.d3
        pts = []
        t = np.linspace(-a, a, n)
        pts.append(np.column_stack([self.rho_max * np.sin(t), self.rho_max * np.cos(t)]))  # outer arc, arm straight
        tmax = a + self.delta(self.rho_min)
        t = np.linspace(-tmax, tmax, n)
        pts.append(np.column_stack([self.rho_min * np.sin(t), self.rho_min * np.cos(t)]))  # inner arc, theta3 at a limit
        t3 = np.linspace(-b, b, n)
        for t2 in (-a, a):  # theta2 at a limit: a circle of radius d3 about the elbow
            pts.append(np.column_stack([d2 * np.sin(t2) + d3 * np.sin(t2 + t3), d2 * np.cos(t2) + d3 * np.cos(t2 + t3)]))
        P = np.vstack(pts)
        # keep the points of these curves that are on the boundary: a step of 1e-7 m leaves the region
        ang = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
        out = np.zeros(len(P), dtype=bool)
        for t in ang:
            out |= ~self.inside_2r(P[:, 0] + 1e-7 * np.cos(t), P[:, 1] + 1e-7 * np.sin(t))
        return P[out] + np.array([0.0, self.h])
