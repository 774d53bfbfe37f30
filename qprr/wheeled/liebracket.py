"""Integrability of the Pfaffian constraints by Lie brackets (Frobenius theorem).

Lecture: "Contraintes non holonômes": whether a constraint can be integrated is not visible
a priori; the Frobenius theorem answers it through the Lie brackets [., .] of the columns of
B(q) (A^T(q) B(q) = 0) over the whole configuration space, which give the number of
integrable constraints.

With Delta = span{b_1, ..., b_m} (the columns of B) and Delta_bar its involutive closure
(Delta plus all iterated brackets, the accessibility distribution), the Pfaffian system
A^T(q) q_dot = 0 of rank k = n - m contains exactly h = n - dim Delta_bar independent
integrable (holonomic) constraints; the other k - h are non-holonomic.  h = k: every
constraint integrates (holonomic system); h = 0: completely non-holonomic (every
configuration is reachable).  The integrable combinations are the one-forms annihilating
Delta_bar.  A single constraint w . dq = 0 integrates on its own iff w ^ dw = 0.

Brackets are computed symbolically with sympy (the ``symbolic`` extra); the rank of the
distribution is its generic rank, evaluated at seeded random configurations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from itertools import combinations

import numpy as np

from ..errors import InputError
from ._backend import sympy_module
from .chassis import rank
from .kinematics import KinematicModel


class Integrability(str, Enum):
    HOLONOMIC = "holonomic"
    NONHOLONOMIC = "nonholonomic"
    PARTIAL = "partially integrable"
    UNCONSTRAINED = "unconstrained"


@dataclass(frozen=True)
class FrobeniusResult:
    """Outcome of the Lie-bracket test for one model.

    ``n``: dimension of q; ``k``: rank of the constraints (n - rank B); ``growth``: dim of
    the distribution after 0, 1, 2... levels of brackets; ``dim_closure`` = dim Delta_bar;
    ``n_integrable`` = h = n - dim Delta_bar; ``n_nonholonomic`` = k - h; ``integrable_forms``:
    a basis of the annihilator of Delta_bar (sympy row vectors, the integrable combinations
    of the constraints); ``alone``: for each constraint (column of A), whether it integrates
    on its own (w ^ dw = 0); ``brackets``: the new directions found, by name ("[b1, b2]"...).
    """

    model: str
    coordinates: tuple[str, ...]
    n: int
    k: int
    growth: tuple[int, ...]
    dim_closure: int
    n_integrable: int
    n_nonholonomic: int
    status: Integrability
    integrable_forms: tuple
    alone: tuple[tuple[str, bool], ...]
    brackets: tuple[tuple[str, object], ...]
    reason: str


def lie_bracket(f, g, q, *, simplify: bool = False):
    """[f, g] = (dg/dq) f - (df/dq) g for sympy column vectors f, g in the symbols q."""
    sp = sympy_module()
    qv = sp.Matrix(q)
    br = g.jacobian(qv) * f - f.jacobian(qv) * g
    return sp.simplify(br) if simplify else br


def _numeric_zero(expr_list, q, points, tol: float = 1e-10) -> bool:
    """Whether every expression vanishes at the sample points (generic test of an identity)."""
    sp = sympy_module()
    fn = sp.lambdify(list(q), list(expr_list), "numpy")
    return all(np.max(np.abs(np.array(fn(*p), dtype=float))) <= tol for p in points)


def _generic_rank(vectors, q, points) -> int:
    if not vectors:
        return 0
    sp = sympy_module()
    M = sp.Matrix.hstack(*vectors)
    fn = sp.lambdify(list(q), M, "numpy")
    return max(rank(np.array(fn(*p), dtype=float)) for p in points)


def _sample_points(model: KinematicModel, n_points: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    pts = []
    while len(pts) < n_points:
        p = rng.uniform(-1.2, 1.2, model.n)  # |angles| < 1.2 rad: away from the rear tricycle's psi = pi/2
        if model.singularity(p) is None:
            pts.append(p)
    return pts


def integrable_alone(w, q, points=None) -> bool:
    """Whether the single Pfaffian form w . dq = 0 is integrable: w ^ dw = 0 (Frobenius, rank 1).

    (w ^ dw)_{ijk} = w_i dw_{jk} - w_j dw_{ik} + w_k dw_{ij} with dw_{jk} = d_j w_k - d_k w_j.
    With ``points``, the components are tested numerically there (generic test); otherwise
    each is simplified symbolically.
    """
    sp = sympy_module()
    n = len(q)
    dw = [[sp.diff(w[k], q[j]) - sp.diff(w[j], q[k]) for k in range(n)] for j in range(n)]
    terms = [w[i] * dw[j][k] - w[j] * dw[i][k] + w[k] * dw[i][j] for i, j, k in combinations(range(n), 3)]
    if not terms:
        return True
    if points is not None:
        return _numeric_zero(terms, q, points)
    return all(sp.simplify(t) == 0 for t in terms)


def _annihilator(basis, q, points) -> tuple:
    """Basis of the one-forms annihilating span(basis): constant ones read off numerically
    (reduced row echelon form, identical at every sample point, rationalised), otherwise the
    symbolic null space of the transposed basis."""
    sp = sympy_module()
    M = sp.Matrix.hstack(*basis).T
    fn = sp.lambdify(list(q), M, "numpy")
    rrefs = []
    for p in points:
        Mp = np.array(fn(*p), dtype=float)
        _, s, Vt = np.linalg.svd(Mp)
        r = int(np.count_nonzero(s > 1e-9 * s[0]))
        W = Vt[r:]
        rrefs.append(np.array(sp.Matrix(W).rref(iszerofunc=lambda x: abs(x) < 1e-9)[0], dtype=float))
    if all(np.allclose(R, rrefs[0], atol=1e-9) for R in rrefs[1:]):
        out = []
        for row in rrefs[0]:
            scale = min((abs(v) for v in row if abs(v) > 1e-9), default=1.0)
            out.append(sp.Matrix([[sp.nsimplify(v / scale, tolerance=1e-9, rational=True) for v in row]]))
        return tuple(out)
    return tuple(sp.simplify(v.T) for v in M.nullspace())


def frobenius(model: KinematicModel, *, max_depth: int | None = None, n_points: int = 3, seed: int = 0) -> FrobeniusResult:
    """Lie-bracket (Frobenius) test of ``model``'s constraints (see the module docstring).

    Lecture: "Contraintes non holonômes", Théorème de Frobenius: the Lie brackets of the
    columns of B(q) (A^T(q) B(q) = 0) over the configuration space give the number of
    integrable constraints.

    Brackets of increasing depth are added while they raise the generic rank of the
    distribution (``max_depth`` levels at most, default n).  Needs sympy:
    ``pip install "qprr[symbolic]"``.
    """
    if not isinstance(model, KinematicModel):
        raise InputError(f"model must be a KinematicModel, got {type(model).__name__}")
    q, A, B = model.symbolic()
    n = len(q)
    points = _sample_points(model, n_points, seed)
    cols = [B[:, j] for j in range(B.shape[1])]
    names = [f"b{j + 1}" for j in range(len(cols))]
    basis, basis_names = [], []
    for c, nm in zip(cols, names):  # independent columns of B
        if _generic_rank(basis + [c], q, points) > len(basis):
            basis.append(c)
            basis_names.append(nm)
    m = len(basis)
    k = n - m
    growth = [m]
    found: list[tuple[str, object]] = []
    frontier = list(zip(basis_names, basis))
    depth = 0
    max_depth = n if max_depth is None else int(max_depth)
    while len(basis) < n and depth < max_depth and frontier:
        depth += 1
        new = []
        for na, fa in frontier:
            for nb, fb in zip(names, cols):
                if na == nb:
                    continue
                br = lie_bracket(fb, fa, q)  # [b, f]: brackets of the inputs' fields with the last level
                if _numeric_zero(list(br), q, points):
                    continue
                if _generic_rank(basis + [br], q, points) > len(basis):
                    label = f"[{nb}, {na}]"
                    basis.append(br)
                    new.append((label, br))
                    found.append((label, br))
                    if len(basis) == n:
                        break
            if len(basis) == n:
                break
        growth.append(len(basis))
        frontier = new
    dim = len(basis)
    h = n - dim
    forms = _annihilator(basis, q, points) if h > 0 else ()
    alone = []
    if A.shape[1] > 0:
        for j in range(A.shape[1]):
            alone.append((f"constraint {j + 1}", integrable_alone([A[i, j] for i in range(n)], q, points)))
    if k == 0:
        status, reason = Integrability.UNCONSTRAINED, "no constraint: B spans every direction"
    elif h == k:
        status, reason = Integrability.HOLONOMIC, f"the distribution is involutive: all {k} constraints integrate"
    elif h == 0:
        status, reason = Integrability.NONHOLONOMIC, f"the brackets span all {n} directions: none of the {k} constraints integrates"
    else:
        status, reason = Integrability.PARTIAL, f"{h} of the {k} constraints integrate (the forms in integrable_forms), {k - h} do not"
    return FrobeniusResult(
        model.name, tuple(model.coordinates), n, k, tuple(growth), dim, h, k - h, status, forms, tuple(alone), tuple(found), reason
    )


class WithWheelAngles(KinematicModel):
    """``model`` extended by the spin angles of its wheels: q = [q_model, phi_1, ..., phi_N].

    The rolling constraints (Lecture: J1 R^T(theta) q_dot_I - J2 phi_dot = 0, Swedish rows
    with r cos gamma) become Pfaffian constraints of the extended configuration:
    phi_dot_i = rho_i(q) . q_dot.  B_ext = [B; P B] with P the rows rho_i, A_ext = [[A, P^T],
    [0, -I]].  Used to ask which rolling constraints integrate (the differential drive's
    theta = r (phi_d - phi_g) / 2L is holonomic, the no-slip constraint is not).  Castors are
    excluded (their angle is not in q).
    """

    def __init__(self, model: KinematicModel):
        if model.robot is None:  # pragma: no cover
            raise InputError(f"{model.name!r} has no wheels")
        self.base = model
        self.name = f"{model.name} + wheel angles"
        self.description = model.description + ", with the wheels' spin angles"
        self.lecture = model.lecture
        self.wheels = [w for w in model.robot.wheels if w.kind.value != "off-centred steerable"]
        self.coordinates = tuple(model.coordinates) + tuple(f"phi_{i + 1}" for i in range(len(self.wheels)))
        self.inputs = model.inputs
        self.input_units = model.input_units
        self.robot = model.robot

    def _P(self, q, m):
        """Rows rho_i: phi_dot_i = rho_i . q_dot_model (rolling constraints)."""
        from .chassis import rotation

        base = self.base
        nb = base.n
        sig = list(q[3 : 3 + base.robot.n_steering])
        angles = dict(zip((id(w) for w in base.robot.steered_wheels), base.robot.steering_angles(sig, m)))
        Rt = rotation(q[2], m).T
        rows = []
        for w in self.wheels:
            row = w.rolling(angles.get(id(w), 0), m)
            coef = [sum(row.xi[a] * Rt[a, b] for a in range(3)) / -row.phi_dot for b in range(3)]
            rows.append(coef + [0] * (nb - 3))
        return rows

    def A(self, q, m=math):
        sp_ = m
        base = self.base
        nb, nw = base.n, len(self.wheels)
        if m is math:
            q = self.check_q(q)
        Ab = base.A(q[:nb] if m is math else list(q[:nb]), m)
        P = self._P(q, m)
        if m is math:
            top = np.hstack([Ab, np.array(P, dtype=float).T])
            bottom = np.hstack([np.zeros((nw, Ab.shape[1])), -np.eye(nw)])
            return np.vstack([top, bottom])
        Pm = sp_.Matrix(P)
        top = Ab.row_join(Pm.T)
        bottom = sp_.zeros(nw, Ab.shape[1]).row_join(-sp_.eye(nw))
        return top.col_join(bottom)

    def B(self, q, m=math):
        base = self.base
        nb = base.n
        if m is math:
            q = self.check_q(q)
            Bb = base.B(q[:nb])
            return np.vstack([Bb, np.array(self._P(q, m), dtype=float) @ Bb])
        Bb = base.B(list(q[:nb]), m)
        return Bb.col_join(m.Matrix(self._P(q, m)) * Bb)

    def singularity(self, q):
        return self.base.singularity(q[: self.base.n])

    def flow(self, q, u, h):  # pragma: no cover - analysis only
        raise NotImplementedError("WithWheelAngles is for the Frobenius analysis; simulate the base model")


__all__ = ["FrobeniusResult", "Integrability", "WithWheelAngles", "commutator_motion", "frobenius", "integrable_alone", "lie_bracket"]


def commutator_motion(model: KinematicModel, q, i: int, j: int, eps: float) -> np.ndarray:
    """The four-leg manoeuvre flow_{-b_j} o flow_{-b_i} o flow_{b_j} o flow_{b_i}, each for eps seconds.

    Returns the 5 configurations (start, after each leg) from the model's exact flows.  Its
    net displacement is eps^2 [b_i, b_j](q) + O(eps^3): the direction the bracket adds is
    reached by wiggling (the physical meaning of the Lie bracket, e.g. parallel parking).
    """
    q = model.check_q(q)
    if not (0 <= i < model.n_inputs and 0 <= j < model.n_inputs and i != j):
        raise InputError(f"input indices {i}, {j} must be distinct and in [0, {model.n_inputs})")
    e = np.eye(model.n_inputs)
    pts = [q]
    for k, sign in ((i, 1.0), (j, 1.0), (i, -1.0), (j, -1.0)):
        pts.append(model.flow(pts[-1], sign * e[k], eps))
    return np.array(pts)
