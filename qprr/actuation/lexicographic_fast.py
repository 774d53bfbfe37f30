"""The compiled form of :meth:`qprr.actuation.lexicographic.Lexicographic.solve` (numba, ``pip install qprr[fast]``).

One call solves every level of the lexicographic bounded least squares: the null-space basis by SVD, each level's
unconstrained minimiser by Cholesky, the 1-D closed form, and the active-set KKT steps from the previous call's active
bounds -- the steps of the readable path in ``lexicographic.py`` (``_clamped_1d``, ``_within``, ``_violated``,
``kkt_on_active_set``, ``_kkt_solve``, ``null_space``), with the same tolerances, in the same order.  What it does
not do is hand a level to ProxQP, or take a least-squares solution of a singular system: when the active-set steps do
not end at a KKT point, or meet such a system, it returns ``ok = False`` and the caller solves the whole problem on the
readable path (which does both).  tests/test_lexicographic_fast.py checks it
against that path to round-off on seeded random problems, bounds active and not.

This module is imported only when the numba kernel is asked for (:func:`qprr.actuation.lexicographic.resolve_kernel`);
numba compiles it on first use and caches the machine code beside the source (``cache=True``): the first call in a
fresh environment costs a few seconds, later processes load it.
"""

from __future__ import annotations

import numba
import numpy as np

_JIT = {"cache": True, "nogil": True}


@numba.njit(**_JIT)
def mm(A, B):
    """A @ B by loops: numba's @ calls BLAS, whose call costs more than these small products (0.35 us for a 3 x 3
    product against 0.09 us, measured); the IK's compiled iteration uses it too."""
    out = np.zeros((A.shape[0], B.shape[1]))
    for i in range(A.shape[0]):
        for k in range(A.shape[1]):
            a = A[i, k]
            for j in range(B.shape[1]):
                out[i, j] += a * B[k, j]
    return out


@numba.njit(**_JIT)
def mv(A, x):
    """A @ x by loops (:func:`mm`)."""
    out = np.zeros(A.shape[0])
    for i in range(A.shape[0]):
        for k in range(A.shape[1]):
            out[i] += A[i, k] * x[k]
    return out


@numba.njit(**_JIT)
def _bound_scale(lo, up):
    """1 + the largest finite |bound| (``lexicographic._bound_scale``)."""
    big = 0.0
    for i in range(lo.shape[0]):
        if np.isfinite(lo[i]) and abs(lo[i]) > big:
            big = abs(lo[i])
        if np.isfinite(up[i]) and abs(up[i]) > big:
            big = abs(up[i])
    return 1.0 + big


@numba.njit(**_JIT)
def _spd_solve(H, rhs):
    """(H^-1 rhs, True) by Cholesky, or (anything, False) when H is not positive definite to working precision."""
    m = H.shape[0]
    L = np.zeros((m, m))
    for j in range(m):
        d = H[j, j]
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if not d > 0.0:
            return np.zeros(m), False
        L[j, j] = np.sqrt(d)
        for i in range(j + 1, m):
            s = H[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = s / L[j, j]
    y = np.empty(m)
    for i in range(m):
        s = rhs[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    z = np.empty(m)
    for i in range(m - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, m):
            s -= L[k, i] * z[k]
        z[i] = s / L[i, i]
    return z, bool(np.all(np.isfinite(z)))


@numba.njit(**_JIT)
def _within(Cz, lo, up):
    """lo <= Cz <= up within 1e-10 of the bound scale (``lexicographic._within``)."""
    ftol = 1e-10 * _bound_scale(lo, up)
    for i in range(Cz.shape[0]):
        if Cz[i] - lo[i] < -ftol or up[i] - Cz[i] < -ftol:
            return False
    return True


@numba.njit(**_JIT)
def _reflect(v, X, rows, cols, from_left):
    """X <- H X (``from_left``, on X[rows, cols]) or X H (on X[cols, rows]) with the Householder reflection
    H = I - 2 v v^T / (v^T v) acting on the index range ``rows`` (v indexed from rows.start)."""
    vv = 0.0
    for i in range(v.shape[0]):
        vv += v[i] * v[i]
    for c in cols:
        dot = 0.0
        for i in range(v.shape[0]):
            dot += v[i] * (X[rows.start + i, c] if from_left else X[c, rows.start + i])
        f = 2.0 * dot / vv
        for i in range(v.shape[0]):
            if from_left:
                X[rows.start + i, c] -= f * v[i]
            else:
                X[c, rows.start + i] -= f * v[i]


@numba.njit(**_JIT)
def _null_space_qr(B, tol):
    """(N, ok): an orthonormal basis of ker B, the last m - k columns of Q in the Householder QR B^T = Q R, when B
    (k x m, k < m) certainly has full row rank: its smallest singular value is at least 1 / ||R^-1||_F (Frobenius
    norm), here above 1e3 tol, so :func:`_null_space`'s SVD would count k singular values above tol too (its rank
    decision).  Else ok False.  Any orthonormal basis of ker B gives the levels below the same optimum (their
    regularisation ||z||^2 and bounds do not depend on it).  A third of an SVD's time on 6 x 9."""
    k, m = B.shape
    G = np.ascontiguousarray(B.T)  # reduced to R in its top k rows
    Q = np.eye(m)
    for j in range(k):
        v = G[j:, j].copy()
        norm = np.sqrt(np.sum(v * v))
        if norm == 0.0:
            return Q, False
        v[0] += norm if v[0] >= 0.0 else -norm  # v = x + sign(x_0) |x| e_0: no cancellation
        _reflect(v, G, range(j, m), range(j, k), True)
        _reflect(v, Q, range(j, m), range(m), False)
    rinv_f2 = 0.0  # ||R^-1||_F^2, column by column of R^-1 (back substitution on the identity)
    for col in range(k):
        y = np.zeros(k)
        for i in range(k - 1, -1, -1):
            acc = 1.0 if i == col else 0.0
            for c in range(i + 1, k):
                acc -= G[i, c] * y[c]
            y[i] = acc / G[i, i]
        rinv_f2 += np.sum(y * y)
    if not (np.isfinite(rinv_f2) and 1.0 / np.sqrt(rinv_f2) > 1e3 * tol):
        return Q, False
    return np.ascontiguousarray(Q[:, k:]), True


@numba.njit(**_JIT)
def _null_space(B, tol):
    """Orthonormal basis (columns) of the kernel of B; singular values <= tol count as zero (by the SVD, or by a QR
    when B certainly has full row rank: :func:`_null_space_qr`)."""
    m = B.shape[1]
    if B.shape[0] == 0:
        return np.eye(m)
    if B.shape[0] < m:
        N, ok = _null_space_qr(B, tol)
        if ok:
            return N
    _, s, Vt = np.linalg.svd(B)
    rank = 0
    for v in s:
        if v > tol:
            rank += 1
    return np.ascontiguousarray(Vt[rank:].T)


@numba.njit(**_JIT)
def _clamped_1d(B, r, reg, c, lo, up, tol):
    """argmin_z ||B z - r||^2 + reg z^2 over {z : lo <= c z <= up}, entries of c zero to tol ignored
    (``lexicographic._clamped_1d``)."""
    bb = B @ B + reg
    z = (B @ r) / bb if bb > 0.0 else 0.0
    zl, zu = -np.inf, np.inf
    small = tol * max(1.0, np.abs(c).max() if c.shape[0] else 0.0)
    for i in range(c.shape[0]):
        ci = c[i]
        if ci > small:
            zl, zu = max(zl, lo[i] / ci), min(zu, up[i] / ci)
        elif ci < -small:
            zl, zu = max(zl, up[i] / ci), min(zu, lo[i] / ci)
    if zl <= zu:
        z = min(max(z, zl), zu)
    else:
        z = 0.0
    out = np.empty(1)
    out[0] = z
    return out


@numba.njit(**_JIT)
def _lu_solve(K, rhs):
    """(K^-1 rhs, True) by Gaussian elimination with partial pivoting (LAPACK's dgesv, which np.linalg.solve calls),
    or (anything, False) on an exactly zero pivot, where np.linalg.solve raises."""
    n = K.shape[0]
    U = K.copy()
    x = rhs.copy()
    for j in range(n):
        p = j
        for i in range(j + 1, n):
            if abs(U[i, j]) > abs(U[p, j]):
                p = i
        if U[p, j] == 0.0:
            return x, False
        if p != j:
            for c in range(n):
                U[j, c], U[p, c] = U[p, c], U[j, c]
            x[j], x[p] = x[p], x[j]
        for i in range(j + 1, n):
            f = U[i, j] / U[j, j]
            for c in range(j, n):
                U[i, c] -= f * U[j, c]
            x[i] -= f * x[j]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for c in range(i + 1, n):
            s -= U[i, c] * x[c]
        x[i] = s / U[i, i]
    return x, True


@numba.njit(**_JIT)
def _kkt_solve(H, g, A, b):
    """(z, mu, stationarity residual, constraint residual, ok) of min 1/2 z^T H z + g^T z s.t. A z = b
    (``lexicographic._kkt_solve``); ok False where that one takes a least-squares solution (H not positive definite
    with no active bound, a singular KKT matrix): the caller then hands the problem back to the numpy path."""
    n, k = H.shape[0], A.shape[0]
    if k == 0:
        z, ok = _spd_solve(H, -g)
        return z, np.zeros(0), mv(H, z) + g, np.zeros(0), ok
    K = np.zeros((n + k, n + k))
    K[:n, :n] = H
    K[:n, n:] = A.T
    K[n:, :n] = A
    rhs = np.concatenate((-g, b))
    sol, ok = _lu_solve(K, rhs)
    r = mv(K, sol) - rhs
    return sol[:n], -sol[n:], r[:n], r[n:], ok


@numba.njit(**_JIT)
def _kkt_on_active_set(H, g, C, lo, up, at_lo, at_up):
    """(z, at_lo, at_up, ok): the active-set steps of ``lexicographic.kkt_on_active_set`` (ok False: its None)."""
    nc = C.shape[0]
    at_lo = at_lo & np.isfinite(lo)
    at_up = at_up & np.isfinite(up) & ~at_lo
    ftol = 1e-10 * _bound_scale(lo, up)
    gscale0 = 1.0 + (np.abs(g).max() if g.shape[0] else 0.0)
    hmax = np.abs(H).max() if H.size else 0.0
    n_steps = 2 * nc + 2
    seen = np.zeros((n_steps, 2 * nc), dtype=np.bool_)
    for step in range(n_steps):
        key = np.concatenate((at_lo, at_up))
        cycling = False
        for j in range(step):
            if np.array_equal(seen[j], key):
                cycling = True
                break
        seen[step] = key
        idx = np.flatnonzero(at_lo | at_up)
        Ak = np.ascontiguousarray(C[idx])
        bk = np.where(at_lo, lo, up)[idx]
        zp, mu, res_x, res_b, solved = _kkt_solve(H, g, Ak, bk)
        if not solved:
            return zp, at_lo, at_up, False
        gscale = gscale0 + hmax * (1.0 + (np.abs(zp).max() if zp.shape[0] else 0.0))
        if (res_x.shape[0] and np.abs(res_x).max() > 1e-10 * gscale) or (res_b.shape[0] and np.abs(res_b).max() > ftol):
            return zp, at_lo, at_up, False
        wrong = np.where(at_lo[idx], -mu, mu)
        Czp = mv(C, zp)
        viol_lo = lo - Czp > ftol
        viol_up = (Czp - up > ftol) & ~viol_lo
        release = wrong > (1e-9 if cycling else 1e-12) * gscale
        if not release.any() and not viol_lo.any() and not viol_up.any():
            return zp, at_lo, at_up, True
        if release.any():
            i = idx[np.argmax(wrong)]
            at_lo[i] = False
            at_up[i] = False
        elif not cycling:
            at_lo |= viol_lo
            at_up |= viol_up
        else:
            gap = np.maximum(np.where(viol_lo, lo - Czp, -np.inf), np.where(viol_up, Czp - up, -np.inf))
            i = np.argmax(gap)
            if viol_lo[i]:
                at_lo[i] = True
            else:
                at_up[i] = True
    return np.zeros(H.shape[0]), at_lo, at_up, False


@numba.njit(**_JIT)
def _box_level(H, g, C, lo, up, rank_tol, guess):
    """One level's min 1/2 z^T H z + g^T z s.t. lo <= C z <= up (``Lexicographic.solve_box_qp`` with
    ``active_set_first``, without its ProxQP): (z, ok, kept rows, at_lo, at_up) with the active bounds over the kept
    rows of C; ``guess`` = (n, at_lo, at_up) from the previous call, n < 0: none."""
    guess_n, guess_lo, guess_up = guess
    z, chol = _spd_solve(H, -g)
    if chol and _within(mv(C, z), lo, up):
        return z, True, -1, guess_lo, guess_up
    nc0 = C.shape[0]
    cmax = np.abs(C).max() if C.size else 0.0
    keep = np.zeros(nc0, dtype=np.bool_)
    for i in range(nc0):
        keep[i] = np.abs(C[i]).max() > rank_tol * max(1.0, cmax)
    rows = np.flatnonzero(keep)
    Ck = np.ascontiguousarray(C[rows])
    lok, upk = lo[rows], up[rows]
    nc = rows.shape[0]
    if guess_n == nc:
        at_lo, at_up = guess_lo[:nc].copy(), guess_up[:nc].copy()
    elif chol:
        Cz = mv(Ck, z)
        ftol = 1e-10 * _bound_scale(lok, upk)
        at_lo = lok - Cz > ftol
        at_up = (Cz - upk > ftol) & ~at_lo
    else:
        at_lo, at_up = np.zeros(nc, dtype=np.bool_), np.zeros(nc, dtype=np.bool_)
    zk, at_lo, at_up, ok = _kkt_on_active_set(H, g, Ck, lok, upk, at_lo, at_up)
    return zk, ok, nc, at_lo, at_up


@numba.njit(**_JIT)
def lex_solve(A, b, offsets, bounds, x, weights, guesses):
    """Every level of ``Lexicographic.solve`` (no equality).

    ``A``, ``b``: the levels stacked, level k in rows offsets[k]:offsets[k + 1].  ``bounds`` = (lower, upper, b0):
    lower <= x[b0 : b0 + len(lower)] <= upper.  ``x``: the start (x0, in the bounds; empty: 0 clipped into the
    bounds, ``Lexicographic.solve``'s default).  ``weights`` = (reg0, damping, rank_tol): the regularisation,
    damping[k] added at level k, the rank tolerance.  ``guesses`` = (n, at_lo, at_up): the active bounds of level k in
    the previous call (n[k] < 0: none), updated in place.  Returns (x, x_levels (K, n), ok); ok False: a level
    needs the numpy path (the guesses are then left as they were).
    """
    lower, upper, b0 = bounds
    reg0, damping, rank_tol = weights
    guess_n, guess_lo, guess_up = guesses
    n = A.shape[1]
    nb = lower.shape[0]
    K = offsets.shape[0] - 1
    if x.shape[0] == 0:
        x = np.zeros(n)
        x[b0 : b0 + nb] = np.minimum(np.maximum(0.0, lower), upper)
    else:
        x = x.copy()
    x_levels = np.zeros((K, n))
    new_n = guess_n.copy()
    new_lo = guess_lo.copy()
    new_up = guess_up.copy()
    Z = np.eye(n)
    for k in range(K):
        Ak = A[offsets[k] : offsets[k + 1]]
        if Z.shape[1] == 0:
            x_levels[k] = x
            continue
        B = mm(Ak, Z)
        r = b[offsets[k] : offsets[k + 1]] - mv(Ak, x)
        reg = reg0 + damping[k]
        xb = x[b0 : b0 + nb]
        lo_z = np.minimum(lower - xb, 0.0)
        up_z = np.maximum(upper - xb, 0.0)
        Cz = np.ascontiguousarray(Z[b0 : b0 + nb])
        m = B.shape[1]
        if m == 1:
            z = _clamped_1d(np.ascontiguousarray(B[:, 0]), r, reg, np.ascontiguousarray(Cz[:, 0]), lo_z, up_z, rank_tol)
        else:
            H = mm(B.T, B)
            for i in range(m):
                H[i, i] += reg
            z, ok, nc, at_lo, at_up = _box_level(H, -mv(B.T, r), Cz, lo_z, up_z, rank_tol, (guess_n[k], guess_lo[k], guess_up[k]))
            if not ok:
                return x, x_levels, False
            if nc < 0 or not (at_lo.any() or at_up.any()):
                new_n[k] = -1
            else:
                new_n[k] = nc
                new_lo[k, :nc] = at_lo
                new_up[k, :nc] = at_up
        x = x + mv(Z, z)
        x_levels[k] = x
        if k < K - 1:
            Z = mm(Z, _null_space(B, rank_tol))
    guess_n[:] = new_n
    guess_lo[:] = new_lo
    guess_up[:] = new_up
    return x, x_levels, True
