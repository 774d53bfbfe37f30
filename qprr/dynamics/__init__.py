"""Dynamics of any platform in Pinocchio's coordinates and in the thesis chart (Thesis Chapter 5).

``dynamics_xi`` gives B, C, G of the Lagrange model (5.36) in thesis coordinates from CRBA /
RNEA and their derivatives; ``forward_dynamics_xi`` is (5.39) evaluated with ABA on the Lie
group.  Energies are Pinocchio's.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..kinematics import check_q
from ..model import Platform, check_model_data
from ..validation import as_vector


def mass_matrix(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """M(q) (nv x nv), symmetric (CRBA fills the upper triangle)."""
    check_model_data(platform, data)
    M = pin.crba(platform.model, data, check_q(platform, q))
    return np.triu(M) + np.triu(M, 1).T


def dynamics_xi(platform: Platform, data: pin.Data, xi, xi_dot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """B(xi), C(xi, xi_dot), G(xi) of Thesis (5.36) in thesis coordinates, from CRBA/RNEA.

    With v = S xi_dot (:func:`qprr.charts.rate_map`) the kinetic energy is
    1/2 xi_dot^T B xi_dot with B = S^T M S (Thesis (5.25)); G = S^T g(q) = dU/dxi (5.37).
    C is the Christoffel matrix of (5.35), C = 1/2 B_dot + 1/2 (D - D^T) with
    D_ij = sum_k dB_ik/dxi_j xi_dot_k, built from Pinocchio's derivatives:
    B_dot = S_dot^T M S + S^T (C_p + C_p^T) S + S^T M S_dot (M_dot = C_p + C_p^T),
    D = d(S^T y)/dxi |_(y = M S w) + S^T d(M a)/dq|_(a = S w) S + S^T M d(S w)/dxi, w = xi_dot.
    Raises EulerSingularityError at theta = +-pi/2 (B is singular there).
    """
    check_model_data(platform, data)
    xi = ch.as_xi(xi, "xi", platform.n_xi)
    w = as_vector(xi_dot, platform.n_xi, "xi_dot")
    ch.check_pitch(xi[4], "dynamics_xi")
    model = platform.model
    q = ch.xi_to_q(xi)
    S = ch.rate_map(xi)
    dS = ch.rate_map_derivatives(xi)  # (3, n, n): dS/dphi, dS/dtheta, dS/dpsi
    v = S @ w
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    Cp = pin.computeCoriolisMatrix(model, data, q, v).copy()
    g = pin.computeGeneralizedGravity(model, data, q).copy()
    dtau_dq, _, _ = pin.computeRNEADerivatives(model, data, q, np.zeros(platform.nv), v)
    dg_dq = pin.computeGeneralizedGravityDerivatives(model, data, q)
    dMa_dq = dtau_dq - dg_dq  # d(M(q) a)/dq at a = v

    S_dot = np.tensordot(w[3:6], dS, axes=1)
    MS = M @ S
    B = S.T @ MS
    B_dot = S_dot.T @ MS + S.T @ (Cp + Cp.T) @ S + MS.T @ S_dot
    y = MS @ w
    D = S.T @ dMa_dq @ S
    for k in range(3):
        D[:, 3 + k] += dS[k].T @ y + MS.T @ (dS[k] @ w)
    C = 0.5 * B_dot + 0.5 * (D - D.T)
    G = S.T @ g
    return B, C, G


def forward_dynamics_xi(platform: Platform, data: pin.Data, xi, xi_dot, u) -> np.ndarray:
    """xi_ddot = B^-1 (u - C xi_dot - G), Thesis (5.39), evaluated with ABA on the Lie group.

    ``u`` are generalised forces in thesis coordinates (e.g. from
    :func:`qprr.actuation.input_map`); tau = S^-T u is applied in Pinocchio's coordinates.
    """
    check_model_data(platform, data)
    xi = ch.as_xi(xi, "xi", platform.n_xi)
    xi_dot = as_vector(xi_dot, platform.n_xi, "xi_dot")
    u = as_vector(u, platform.n_xi, "u")
    ch.check_pitch(xi[4], "forward_dynamics_xi")
    q, v = ch.xi_to_qv(xi, xi_dot)
    tau = np.linalg.solve(ch.rate_map(xi).T, u)
    a = pin.aba(platform.model, data, q, v, tau, pin.Convention.LOCAL)
    return ch.a_to_xi_ddot(xi, xi_dot, a)


def kinetic_energy(platform: Platform, data: pin.Data, q, v) -> float:
    """Kinetic energy [J], Thesis (5.13)."""
    check_model_data(platform, data)
    return float(pin.computeKineticEnergy(platform.model, data, check_q(platform, q), as_vector(v, platform.nv, "v")))


def potential_energy(platform: Platform, data: pin.Data, q) -> float:
    """Gravitational potential energy [J] with U = m g z (world z up), Thesis (5.29)."""
    check_model_data(platform, data)
    return float(pin.computePotentialEnergy(platform.model, data, check_q(platform, q)))


def generalized_gravity(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """g(q) (nv,): the generalised force that holds the platform still at q (Pinocchio coordinates)."""
    check_model_data(platform, data)
    return pin.computeGeneralizedGravity(platform.model, data, check_q(platform, q)).copy()
