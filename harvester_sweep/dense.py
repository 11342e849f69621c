"""Small dense algebra of the orbit solver: D x D monodromy matrices (D = 3, or 5 with a
moving stop), one point at a time, compiled.

Each function takes one matrix, so that the compiled solver calls it inside its loop
over points, and the batched forms (``*_each``) give the same bits. Solves, inverses and
determinants are Gaussian elimination with partial pivoting (LAPACK's getrf, unblocked),
written out: at D = 3 a call through numba's LAPACK binding spends more on copies,
checks and workspace than on the elimination. The eigenvalues are LAPACK's.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .jit import SOLVER_JIT


@njit(**SOLVER_JIT)
def _lu(a):
    """The LU factors of ``a`` (D, D) by rows, with partial pivoting: (factors, the rows'
    order, the order's sign); L's unit diagonal is implied. A zero pivot is left in place
    (a singular matrix: its determinant is 0)."""
    n = a.shape[0]
    lu = a.copy()
    order = np.arange(n)
    sign = 1.0
    for k in range(n):
        pivot, big = k, abs(lu[k, k])
        for i in range(k + 1, n):
            if abs(lu[i, k]) > big:
                pivot, big = i, abs(lu[i, k])
        if pivot != k:
            for j in range(n):
                lu[k, j], lu[pivot, j] = lu[pivot, j], lu[k, j]
            order[k], order[pivot] = order[pivot], order[k]
            sign = -sign
        if lu[k, k] != 0.0:
            for i in range(k + 1, n):
                f = lu[i, k] / lu[k, k]
                lu[i, k] = f
                for j in range(k + 1, n):
                    lu[i, j] -= f * lu[k, j]
    return lu, order, sign


@njit(**SOLVER_JIT)
def _substitute(lu, order, b):
    """x of L U x = b[order] (lu, order from _lu)."""
    n = lu.shape[0]
    x = np.empty(n)
    for i in range(n):
        s = b[order[i]]
        for j in range(i):
            s -= lu[i, j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= lu[i, j] * x[j]
        x[i] = s / lu[i, i]
    return x


@njit(**SOLVER_JIT)
def det(a):
    """Determinant of ``a`` (D, D)."""
    lu, _, sign = _lu(a)
    out = sign
    for k in range(a.shape[0]):
        out *= lu[k, k]
    return out


@njit(**SOLVER_JIT)
def inverse(a):
    """Inverse of ``a`` (D, D), non-singular."""
    n = a.shape[0]
    lu, order, _ = _lu(a)
    out = np.empty((n, n))
    unit = np.zeros(n)
    for j in range(n):
        unit[j] = 1.0
        out[:, j] = _substitute(lu, order, unit)
        unit[j] = 0.0
    return out


@njit(**SOLVER_JIT)
def solve_system(a, b):
    """x of ``a`` x = ``b`` (D,), ``a`` (D, D) non-singular."""
    lu, order, _ = _lu(a)
    return _substitute(lu, order, b)


@njit(**SOLVER_JIT)
def matvec(a, x):
    """``a`` (D, D) times ``x`` (D,), each component summed in column order."""
    n = a.shape[0]
    out = np.empty(n)
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += a[i, j] * x[j]
        out[i] = s
    return out


@njit(**SOLVER_JIT)
def row_sum_norm(a):
    """The infinity norm of ``a`` (D, D): its largest sum of |a_ij| along a row."""
    best = 0.0
    for i in range(a.shape[0]):
        s = 0.0
        for j in range(a.shape[1]):
            s += abs(a[i, j])
        best = max(best, s)
    return best


@njit(**SOLVER_JIT)
def spectral_radius(a):
    """The largest modulus of the eigenvalues of ``a`` (D, D), finite (LAPACK's complex
    solver: numba's real one refuses complex eigenvalues)."""
    return np.max(np.abs(np.linalg.eigvals(a.astype(np.complex128))))


@njit(**SOLVER_JIT)
def det_each(a):
    """det of each of ``a`` (n, D, D): (n,)."""
    out = np.empty(a.shape[0])
    for k in range(a.shape[0]):
        out[k] = det(a[k])
    return out


@njit(**SOLVER_JIT)
def inverse_each(a):
    """inverse of each of ``a`` (n, D, D)."""
    out = np.empty_like(a)
    for k in range(a.shape[0]):
        out[k] = inverse(a[k])
    return out


@njit(**SOLVER_JIT)
def solve_each(a, b):
    """solve_system for each of ``a`` (n, D, D) and ``b`` (n, D): (n, D)."""
    out = np.empty_like(b)
    for k in range(a.shape[0]):
        out[k] = solve_system(a[k], b[k])
    return out


@njit(**SOLVER_JIT)
def matvec_each(a, x):
    """matvec for each of ``a`` (n, D, D) and ``x`` (n, D): (n, D)."""
    out = np.empty_like(x)
    for k in range(a.shape[0]):
        out[k] = matvec(a[k], x[k])
    return out


@njit(**SOLVER_JIT)
def row_sum_norm_each(a):
    """row_sum_norm of each of ``a`` (n, D, D): (n,)."""
    out = np.empty(a.shape[0])
    for k in range(a.shape[0]):
        out[k] = row_sum_norm(a[k])
    return out


@njit(**SOLVER_JIT)
def spectral_radius_each(a):
    """spectral_radius of each of ``a`` (n, D, D): (n,)."""
    out = np.empty(a.shape[0])
    for k in range(a.shape[0]):
        out[k] = spectral_radius(a[k])
    return out
