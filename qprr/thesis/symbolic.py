"""Independent symbolic Lagrange model of the Q-PRR (Thesis Sec. 5.2), derived with sympy.

This module is the referee of :func:`qprr.dynamics.dynamics_xi`: it derives the dynamics
from the energies written in thesis coordinates xi = [x, y, z, phi, theta, psi, r0,
theta2, theta3] and uses neither Pinocchio nor :mod:`qprr.dynamics` (only the parameters of
:mod:`qprr.thesis.params` and the input checks of :mod:`qprr.charts`).

Geometry (all in B, the body frame at the multirotor CoG; link frames coincide with B at
theta2 = theta3 = 0 and every link extends along its +z axis, Thesis (3.58)):
joint r0 at [r0, 0, d0]; joint theta2 at [r0, 0, d0 + d1]; joint theta3 at
[r0, 0, d0 + d1] + Ry(theta2) [0, 0, d2]; link i has orientation R_i^b = I, Ry(theta2),
Ry(theta2 + theta3) and its CoM at joint_i + R_i^b com_i (``Link.com``, link frame).

Kinetic energy per body, Thesis (5.13)-(5.22) with the angular velocity in body axes:
T_i = 1/2 m_i |p_dot + R_b (omega_b x c_i + c_i_dot)|^2 + 1/2 omega_i^T I_i omega_i, where
omega_b = T(phi_b) euler_dot is built from Thesis (3.22)-(3.24) (= (3.25)) and
omega_i = (R_i^b)^T omega_b + [0, rate about y, 0].  Using R_b^T R_b = I the translational
part is 1/2 m (|p_dot|^2 + 2 p_dot . R_b w + |w|^2), w = omega_b x c + c_dot.
B = d^2 T / d xi_dot^2 (5.24)-(5.25); U = sum m g e3^T (p + R_b c) (5.26)-(5.29);
G = dU/dxi (5.37); C is the Christoffel matrix (5.35) from the symbolic dB/dxi_k.

Numeric parameters are substituted before differentiation; the expressions are turned
into plain Python/``math`` code with common-subexpression elimination (what
``sympy.lambdify(..., cse=True)`` does), cached in-process and on disk
(``$QPRR_CACHE_DIR`` or ``~/.cache/qprr``), so the derivation runs once per parameter set.
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

try:
    import sympy as sp
    from sympy.printing.pycode import PythonCodePrinter
except ImportError as exc:  # pragma: no cover - exercised only without the test extra
    raise ImportError('qprr.thesis.symbolic needs sympy, which is in the test extra: pip install "qprr[test]"') from exc

from ..charts import EULER_TOL
from ..errors import EulerSingularityError, InputError
from ..validation import as_vector, checked_module
from .params import QPRRParams, thesis_params

XI_NAMES = ("x", "y", "z", "phi", "theta", "psi", "r0", "theta2", "theta3")
_CODEGEN_VERSION = "1"


# ----------------------------------------------------------------------------- derivation
def _rx(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _num(x: float):
    return sp.Float(float(x), 17)


def _nvec(v) -> sp.Matrix:
    return sp.Matrix([_num(a) for a in v])


def _nmat(m: np.ndarray) -> sp.Matrix:
    return sp.Matrix(3, 3, [_num(a) for a in np.asarray(m, dtype=float).ravel()])


@dataclass
class _Derivation:
    """Symbolic pieces: coordinates, rates and the expressions of T, U, B, dB/dxi_k, G."""

    xi: tuple
    xi_dot: tuple
    T: object
    U: object
    B: object  # sp.Matrix 9x9
    dB: dict  # k -> sp.Matrix 9x9, only for coordinates B depends on
    G: object  # sp.Matrix 9x1


def _bodies(p: QPRRParams, q, qd, omega_b):
    """(mass, c_B, omega_body_axes, inertia) of every body; c_B is the CoM in B."""
    _, _, _, _, _, _, r0, t2, t3 = q
    t2d, t3d = qd[7], qd[8]
    zero = sp.zeros(3, 1)
    out = [(_num(p.multirotor_mass), zero, omega_b, _nmat(p.multirotor_inertia_matrix()))]
    if p.rail is not None:  # fixed to the multirotor, rail frame = B
        out.append((_num(p.rail.mass), _nvec(p.rail.com), omega_b, _nmat(p.rail.inertia_matrix())))
    l1, l2, l3 = p.links
    R2, R3 = _ry(t2), _ry(t2 + t3)
    j1 = sp.Matrix([r0, 0, _num(p.d0)])
    j2 = sp.Matrix([r0, 0, _num(p.d0 + p.d1)])
    j3 = j2 + R2 * sp.Matrix([0, 0, _num(p.d2)])
    ey = sp.Matrix([0, 1, 0])
    out.append((_num(l1.mass), j1 + _nvec(l1.com), omega_b, _nmat(l1.inertia_matrix())))
    out.append((_num(l2.mass), j2 + R2 * _nvec(l2.com), R2.T * omega_b + ey * t2d, _nmat(l2.inertia_matrix())))
    out.append((_num(l3.mass), j3 + R3 * _nvec(l3.com), R3.T * omega_b + ey * (t2d + t3d), _nmat(l3.inertia_matrix())))
    return out


def _derive(p: QPRRParams) -> _Derivation:
    q = sp.symbols("x y z phi theta psi r0 theta2 theta3", real=True)
    qd = sp.symbols("x_dot y_dot z_dot phi_dot theta_dot psi_dot r0_dot theta2_dot theta3_dot", real=True)
    phi, theta, psi = q[3:6]
    Rb = _rz(psi) * _ry(theta) * _rx(phi)  # Thesis (3.4)
    # Thesis (3.22)-(3.24): omega_body = Rx^T Ry^T [0,0,psi_dot] + Rx^T [0,theta_dot,0] + [phi_dot,0,0]
    omega_b = _rx(phi).T * _ry(theta).T * sp.Matrix([0, 0, qd[5]]) + _rx(phi).T * sp.Matrix([0, qd[4], 0]) + sp.Matrix([qd[3], 0, 0])
    p_dot = sp.Matrix(qd[0:3])
    g = _num(p.g)

    rest = list(qd[3:9])  # rates other than p_dot: euler rates and arm rates
    m_tot = 0
    mJw = sp.zeros(3, 6)  # sum m dw/d(rest), w in B
    Brr = sp.zeros(6, 6)
    T = 0
    U = 0
    for m, c, omega, inertia in _bodies(p, q, qd, omega_b):
        c_dot = c.jacobian(q[6:9]) * sp.Matrix(qd[6:9])
        w = omega_b.cross(c) + c_dot  # velocity of the CoM relative to the translating B, in B
        Jw = w.jacobian(rest)
        Jo = omega.jacobian(rest)
        m_tot += m
        mJw += m * Jw
        Brr += m * (Jw.T * Jw) + Jo.T * inertia * Jo
        Rw = Rb * w
        T += m / 2 * (p_dot.dot(p_dot) + 2 * p_dot.dot(Rw) + w.dot(w)) + (omega.T * inertia * omega)[0, 0] / 2
        U += m * g * (q[2] + (Rb * c)[2])  # Thesis (5.28), world z up

    B = sp.zeros(9, 9)
    B[0:3, 0:3] = m_tot * sp.eye(3)
    B13 = Rb * mJw  # B_12 and B_13 of Sec. 5.2.2, in one block
    B[0:3, 3:9] = B13
    B[3:9, 0:3] = B13.T
    B[3:9, 3:9] = Brr
    dB = {}
    for k, s in enumerate(q):
        if any(e.has(s) for e in B):
            dB[k] = B.diff(s)
    G = sp.Matrix([sp.diff(U, s) for s in q])  # Thesis (5.37)
    return _Derivation(q, qd, T, U, B, dB, G)


# ---------------------------------------------------------------------------- code generation
class _Printer(PythonCodePrinter):
    def _print_Float(self, expr):  # full double precision
        return repr(float(expr))


def _function_source(name: str, args, exprs) -> str:
    """Source of ``def name(*args)`` returning the tuple of ``exprs``, after CSE."""
    printer = _Printer({"fully_qualified_modules": True})
    repl, reduced = sp.cse(list(exprs), symbols=sp.numbered_symbols("_t"))
    lines = [f"def {name}({', '.join(str(a) for a in args)}):"]
    for sym, e in repl:
        lines.append(f"    {sym} = {printer.doprint(e)}")
    body = ", ".join(printer.doprint(e) for e in reduced)
    lines.append(f"    return ({body},)")
    return "\n".join(lines) + "\n"


def _symmetric_layout(mats):
    """Unique nonzero entries (upper triangles) of a list of symmetric 9x9 matrices.

    Returns (exprs, dest, src): flat[dest] = values[src] rebuilds the stacked matrices.
    """
    exprs, dest, src = [], [], []
    for n, M in enumerate(mats):
        for i in range(9):
            for j in range(i, 9):
                e = M[i, j]
                if e == 0:
                    continue
                idx = len(exprs)
                exprs.append(e)
                dest.append(n * 81 + i * 9 + j)
                src.append(idx)
                if i != j:
                    dest.append(n * 81 + j * 9 + i)
                    src.append(idx)
    return exprs, dest, src


def _generate(p: QPRRParams) -> str:
    """Python source of the model for ``p`` (functions and index tables)."""
    d = _derive(p)
    ks = sorted(d.dB)
    B_exprs, B_dest, B_src = _symmetric_layout([d.B])
    dyn_exprs, dyn_dest, dyn_src = _symmetric_layout([d.B] + [d.dB[k] for k in ks])
    n_dyn = len(dyn_exprs)
    parts = [
        f"# Generated by qprr.thesis.symbolic (codegen v{_CODEGEN_VERSION}) for variant {p.variant!r}: do not edit.",
        "import math",
        f"DB_COORDS = {tuple(ks)!r}",
        f"B_DEST = {tuple(B_dest)!r}",
        f"B_SRC = {tuple(B_src)!r}",
        f"DYN_DEST = {tuple(dyn_dest)!r}",
        f"DYN_SRC = {tuple(dyn_src)!r}",
        f"N_DYN = {n_dyn}",
        _function_source("mass_matrix", d.xi, B_exprs),
        _function_source("gravity", d.xi, list(d.G)),
        _function_source("dynamics", d.xi, dyn_exprs + list(d.G)),
        _function_source("kinetic", d.xi + d.xi_dot, [d.T]),
        _function_source("potential", d.xi, [d.U]),
    ]
    return "\n".join(parts)


def _cache_dir() -> Path:
    env = os.environ.get("QPRR_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "qprr"


def _cache_key(p: QPRRParams) -> str:
    h = hashlib.sha256()
    h.update(repr(p).encode())  # provenance is excluded from repr; floats repr exactly
    h.update(Path(__file__).read_bytes())
    h.update(sp.__version__.encode())
    return h.hexdigest()[:24]


def _load_or_generate(p: QPRRParams) -> tuple[str, float, bool]:
    """(source, seconds spent, from_disk).  Disk errors fall back to an in-memory derivation."""
    t0 = time.perf_counter()
    path = _cache_dir() / f"symbolic_{p.variant}_{_cache_key(p)}.py"
    try:
        src = path.read_text()
        compile(src, str(path), "exec")  # a damaged file is regenerated below
        return src, time.perf_counter() - t0, True
    except (OSError, SyntaxError, ValueError):
        pass
    src = _generate(p)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "w") as f:
            f.write(src)
        os.replace(tmp, path)  # atomic: concurrent processes never read a partial file
    except OSError:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
    return src, time.perf_counter() - t0, False


# ------------------------------------------------------------------------------ the model
@dataclass(frozen=True)
class SymbolicModel:
    """B(xi), C(xi, xi_dot), G(xi) of Thesis (5.36) from the independent sympy derivation.

    ``setup_seconds`` is the one-off cost of deriving + generating code (or of reading it
    from the disk cache when ``from_disk_cache``).
    """

    params: QPRRParams
    setup_seconds: float
    from_disk_cache: bool
    source: str = field(repr=False)
    _ns: dict = field(repr=False, compare=False)

    def _xi(self, xi, name: str = "xi") -> list:
        return as_vector(xi, 9, name).tolist()

    def B(self, xi) -> np.ndarray:
        """Inertia matrix B(xi) (9x9, symmetric positive definite), Thesis (5.24)-(5.25)."""
        vals = np.asarray(self._ns["mass_matrix"](*self._xi(xi)))
        out = np.zeros(81)
        out[self._ns["_B_dest"]] = vals[self._ns["_B_src"]]
        return out.reshape(9, 9)

    def G(self, xi) -> np.ndarray:
        """Gravity vector G = dU/dxi (9,), Thesis (5.37)."""
        return np.asarray(self._ns["gravity"](*self._xi(xi)))

    def _B_dB_G(self, xi):
        ns = self._ns
        vals = np.asarray(ns["dynamics"](*xi))
        n = ns["N_DYN"]
        flat = np.zeros(81 * (1 + len(ns["DB_COORDS"])))
        flat[ns["_dyn_dest"]] = vals[:n][ns["_dyn_src"]]
        stack = flat.reshape(-1, 9, 9)
        return stack[0], stack[1:], vals[n:]

    def inertia_derivatives(self, xi) -> np.ndarray:
        """dB/dxi_k for k = 0..8 as an array of shape (9, 9, 9) (index k first)."""
        _, dB, _ = self._B_dB_G(self._xi(xi))
        out = np.zeros((9, 9, 9))
        out[list(self._ns["DB_COORDS"])] = dB
        return out

    def _christoffel(self, dB: np.ndarray, w: np.ndarray) -> np.ndarray:
        """C_ij = 1/2 sum_k (db_ij/dxi_k + db_ik/dxi_j - db_jk/dxi_i) xi_dot_k, Thesis (5.35)."""
        ks = self._ns["_ks"]
        B_dot = np.tensordot(w[ks], dB, axes=1)  # sum_k db_ij/dxi_k w_k
        E = np.zeros((9, 9))  # E[a, b] = sum_k db_bk/dxi_a w_k
        E[ks] = dB @ w
        return 0.5 * (B_dot + E.T - E)

    def C(self, xi, xi_dot) -> np.ndarray:
        """Coriolis/centrifugal matrix by the Christoffel symbols, Thesis (5.35)."""
        return self.dynamics(xi, xi_dot)[1]

    def dynamics(self, xi, xi_dot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(B, C, G) of Thesis (5.36) at (xi, xi_dot)."""
        x = self._xi(xi)
        w = as_vector(xi_dot, 9, "xi_dot")
        B, dB, G = self._B_dB_G(x)
        return B, self._christoffel(dB, w), G

    def B_dot(self, xi, xi_dot) -> np.ndarray:
        """dB/dt = sum_k dB/dxi_k xi_dot_k (analytic)."""
        w = as_vector(xi_dot, 9, "xi_dot")
        _, dB, _ = self._B_dB_G(self._xi(xi))
        return np.tensordot(w[self._ns["_ks"]], dB, axes=1)

    def kinetic_energy(self, xi, xi_dot) -> float:
        """Kinetic energy T [J] of the whole system, Thesis (5.13)-(5.23) (evaluated from T, not from B)."""
        return float(self._ns["kinetic"](*self._xi(xi), *self._xi(xi_dot, "xi_dot"))[0])

    def potential_energy(self, xi) -> float:
        """Potential energy U [J], world z up, Thesis (5.29)."""
        return float(self._ns["potential"](*self._xi(xi))[0])

    def forward_dynamics(self, xi, xi_dot, u) -> np.ndarray:
        """xi_ddot = B^-1 (u - C xi_dot - G), Thesis (5.39); u: generalised forces in xi coordinates.

        Raises EulerSingularityError at theta = +-pi/2 where B is singular.
        """
        x = as_vector(xi, 9, "xi")
        w = as_vector(xi_dot, 9, "xi_dot")
        u = as_vector(u, 9, "u")
        if abs(math.cos(x[4])) < EULER_TOL:
            raise EulerSingularityError(f"forward_dynamics: B(xi) is singular at pitch theta = {x[4]!r} rad (|cos theta| < {EULER_TOL:g})")
        B, C, G = self.dynamics(x, w)
        return np.linalg.solve(B, u - C @ w - G)


def _build(p: QPRRParams) -> SymbolicModel:
    src, seconds, from_disk = _load_or_generate(p)
    ns: dict = {}
    exec(compile(src, f"<qprr.thesis.symbolic {p.variant}>", "exec"), ns)
    ns["_B_dest"] = np.array(ns["B_DEST"], dtype=int)
    ns["_B_src"] = np.array(ns["B_SRC"], dtype=int)
    ns["_dyn_dest"] = np.array(ns["DYN_DEST"], dtype=int)
    ns["_dyn_src"] = np.array(ns["DYN_SRC"], dtype=int)
    ns["_ks"] = np.array(ns["DB_COORDS"], dtype=int)
    return SymbolicModel(params=p, setup_seconds=seconds, from_disk_cache=from_disk, source=src, _ns=ns)


@functools.lru_cache(maxsize=8)
def _cached(p: QPRRParams) -> SymbolicModel:
    return _build(p)


def symbolic_model(params: QPRRParams | None = None) -> SymbolicModel:
    """The symbolic model of ``params`` (default :func:`thesis_params`), derived once per process.

    The first call for a parameter set derives and generates code (or reads it from the
    disk cache); later calls return the same object.
    """
    p = params if params is not None else thesis_params()
    if not isinstance(p, QPRRParams):
        raise InputError(f"params must be a QPRRParams or None, got {p!r} of type {type(p).__name__}")
    return _cached(p)


# ------------------------------------------------------- closed-form blocks of Sec. 5.2.2
def _np_rot(axis: int, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def _hat(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _arm_bodies_numeric(p: QPRRParams, q_arm: np.ndarray):
    """(m, p_ci^b, J_p^(ci), J_o^(ci), R_ci^b, I_ci^i) of each arm body (rail first if any).

    J_p, J_o (3x3) map [r0_dot, theta2_dot, theta3_dot] to the CoM velocity and angular
    velocity relative to B, in B axes, Thesis (5.16)-(5.21).
    """
    r0, t2, t3 = q_arm
    ex, ey = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    R2, R3 = _np_rot(1, t2), _np_rot(1, t2 + t3)
    j2 = np.array([r0, 0.0, p.d0 + p.d1])
    j3 = j2 + R2 @ np.array([0.0, 0.0, p.d2])
    l1, l2, l3 = p.links
    out = []
    if p.rail is not None:
        zero = np.zeros((3, 3))
        out.append((p.rail.mass, np.array(p.rail.com), zero, zero, np.eye(3), p.rail.inertia_matrix()))
    c1 = np.array([r0, 0.0, p.d0]) + np.array(l1.com)
    Jp1 = np.column_stack([ex, np.zeros(3), np.zeros(3)])
    out.append((l1.mass, c1, Jp1, np.zeros((3, 3)), np.eye(3), l1.inertia_matrix()))
    c2 = j2 + R2 @ np.array(l2.com)
    Jp2 = np.column_stack([ex, np.cross(ey, c2 - j2), np.zeros(3)])
    Jo2 = np.column_stack([np.zeros(3), ey, np.zeros(3)])
    out.append((l2.mass, c2, Jp2, Jo2, R2, l2.inertia_matrix()))
    c3 = j3 + R3 @ np.array(l3.com)
    Jp3 = np.column_stack([ex, np.cross(ey, c3 - j2), np.cross(ey, c3 - j3)])
    Jo3 = np.column_stack([np.zeros(3), ey, ey])
    out.append((l3.mass, c3, Jp3, Jo3, R3, l3.inertia_matrix()))
    return out


def _inertia_blocks(p: QPRRParams, xi, printed: bool) -> np.ndarray:
    xi = as_vector(xi, 9, "xi")
    phi, theta, psi = xi[3:6]
    Rb = _np_rot(2, psi) @ _np_rot(1, theta) @ _np_rot(0, phi)
    sf, cf, st, ct = math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta)
    T = np.array([[1.0, 0.0, -st], [0.0, cf, sf * ct], [0.0, -sf, cf * ct]])  # Thesis (3.25)
    Q = Rb.T @ T if printed else T  # printed (5.15): Q = R_b^T T(phi_b)
    bodies = _arm_bodies_numeric(p, xi[6:9])
    B11 = (p.multirotor_mass + sum(b[0] for b in bodies)) * np.eye(3)
    B12 = -sum(m * Rb @ _hat(c) @ T for m, c, *_ in bodies)
    B13 = sum(m * Rb @ Jp for m, c, Jp, *_ in bodies)
    B22 = Q.T @ p.multirotor_inertia_matrix() @ Q
    B23 = np.zeros((3, 3))
    B33 = np.zeros((3, 3))
    for m, c, Jp, Jo, R, inertia in bodies:
        I_b = R @ inertia @ R.T  # link inertia about its CoM in B axes
        B22 = B22 + Q.T @ I_b @ Q - m * T.T @ _hat(c) @ _hat(c) @ T
        if printed:
            B23 -= m * T.T @ _hat(c) @ Jp - Q.T @ I_b @ Jp.T
            B33 -= m * Jp.T @ Jp - Jo.T @ I_b @ Jo
        else:
            B23 += m * T.T @ _hat(c) @ Jp + T.T @ I_b @ Jo
            B33 += m * Jp.T @ Jp + Jo.T @ I_b @ Jo
    return np.block([[B11, B12, B13], [B12.T, B22, B23], [B13.T, B23.T, B33]])


def thesis_inertia_matrix(params: QPRRParams, xi) -> np.ndarray:
    """B (9x9) assembled from the blocks B11..B33 exactly as printed after Thesis (5.25).

    Printed: Q = R_b^T T(phi_b) (5.15); B22 = Q^T I_b Q + sum(Q^T R I R^T Q - m T^T p^2 T);
    B23 = -sum(m T^T p^ J_p - Q^T R I R^T J_p^T); B33 = -sum(m J_p^T J_p - J_o^T R I R^T J_o).
    Kept to document the errata; use :func:`inertia_matrix_blocks` (corrected) instead.
    """
    return _inertia_blocks(params, xi, printed=True)


def inertia_matrix_blocks(params: QPRRParams, xi) -> np.ndarray:
    """B (9x9) from the closed-form blocks of Sec. 5.2.2, corrected.

    With omega_b = T(phi_b) euler_dot in body axes (3.25) and p^ = hat(p_ci^b):
    B11 = m_G I3, B12 = -sum m R_b p^ T, B13 = sum m R_b J_p (as printed);
    B22 = T^T I_b^b T + sum(T^T R_ci I_ci R_ci^T T - m T^T p^ p^ T)   (Q = T, not R_b^T T),
    B23 = sum(m T^T p^ J_p + T^T R_ci I_ci R_ci^T J_o)               (sign, J_o not J_p^T),
    B33 = sum(m J_p^T J_p + J_o^T R_ci I_ci R_ci^T J_o)              (no leading minus).
    """
    return _inertia_blocks(params, xi, printed=False)


checked_module(globals())
