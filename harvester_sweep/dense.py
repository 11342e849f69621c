"""Small dense algebra of the orbit solver: D x D monodromy matrices (D = 3, or 5 with a
moving stop), one point at a time, compiled.

Each function takes one matrix: the compiled solver calls it inside its loop over points.
Solves, inverses and determinants are Gaussian elimination with partial pivoting
(LAPACK's getrf, unblocked), written out: at D = 3 a call through numba's LAPACK binding
spends more on copies, checks and workspace than on the elimination. The spectral radius
of a 3 x 3 matrix is its characteristic cubic's, taken from LAPACK where the solver's
decisions are sensitive to it.
"""

from __future__ import annotations

import numpy as np

from .jit import SOLVER_JIT, njit


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
def _det(lu, sign):
    """The determinant from LU factors and the rows' order's sign."""
    out = sign
    for k in range(lu.shape[0]):
        out *= lu[k, k]
    return out


@njit(**SOLVER_JIT)
def _inverse(lu, order):
    """The inverse from LU factors and the rows' order."""
    n = lu.shape[0]
    out = np.empty((n, n))
    unit = np.zeros(n)
    for j in range(n):
        unit[j] = 1.0
        out[:, j] = _substitute(lu, order, unit)
        unit[j] = 0.0
    return out


@njit(**SOLVER_JIT)
def det(a):
    """Determinant of ``a`` (D, D)."""
    lu, _, sign = _lu(a)
    return _det(lu, sign)


@njit(**SOLVER_JIT)
def inverse(a):
    """Inverse of ``a`` (D, D), non-singular."""
    lu, order, _ = _lu(a)
    return _inverse(lu, order)


@njit(**SOLVER_JIT)
def det_and_inverse(a):
    """Determinant of ``a`` (D, D) and, where it is not 0, its inverse (else NaN), from
    one factorisation."""
    lu, order, sign = _lu(a)
    d = _det(lu, sign)
    if d == 0.0:
        return d, np.full(a.shape, np.nan)
    return d, _inverse(lu, order)


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


#: A spectral radius from the characteristic cubic is kept where its error bound is below
#: this share of it (else LAPACK's is taken): the solver's hints take its logarithm [-].
CUBIC_TRUST = 1e-10
#: ... and where it is this far from 1 at least: the solver compares it with 1 [-].
NEAR_ONE = 1e-6


@njit(**SOLVER_JIT)
def spectral_radius(a):
    """The largest modulus of the eigenvalues of ``a`` (D, D), finite: for D = 3 the
    roots of its characteristic cubic (Numerical Recipes' real-coefficient form) where
    their error bound is within CUBIC_TRUST and the radius not within NEAR_ONE of 1;
    else LAPACK's (numba's complex solver: its real one refuses complex eigenvalues),
    which costs about forty times as much at D = 3. The cubic's coefficients carry the
    rounding of the entries' products, which a non-normal matrix makes large beside its
    eigenvalues, and its roots lose accuracy where they cluster: the bound says where."""
    if a.shape[0] == 3:
        radius, error = _cubic_radius(a)
        if error <= CUBIC_TRUST * radius and abs(radius - 1.0) >= NEAR_ONE:
            return radius
    return np.max(np.abs(np.linalg.eigvals(a.astype(np.complex128))))


@njit(**SOLVER_JIT)
def _cubic_radius(a):
    """The spectral radius of the 3 x 3 ``a`` from the roots of
    x^3 + p x^2 + q x + r = 0 (p = -trace, q = the sum of the principal 2 x 2 minors,
    r = -det), and a bound on its error: the rounding of the coefficients (a few units of
    the sums of their terms' moduli) at that root, over the polynomial's slope there (inf
    where the bound is not finite)."""
    a00, a01, a02 = a[0, 0], a[0, 1], a[0, 2]
    a10, a11, a12 = a[1, 0], a[1, 1], a[1, 2]
    a20, a21, a22 = a[2, 0], a[2, 1], a[2, 2]
    p = -(a00 + a11 + a22)
    q = (a00 * a11 - a01 * a10) + (a00 * a22 - a02 * a20) + (a11 * a22 - a12 * a21)
    m0, m1, m2 = a11 * a22 - a12 * a21, a10 * a22 - a12 * a20, a10 * a21 - a11 * a20
    r = -(a00 * m0 - a01 * m1 + a02 * m2)
    size_p = abs(a00) + abs(a11) + abs(a22)
    size_q = (abs(a00 * a11) + abs(a01 * a10) + abs(a00 * a22) + abs(a02 * a20)
              + abs(a11 * a22) + abs(a12 * a21))
    size_r = (abs(a00) * (abs(a11 * a22) + abs(a12 * a21))
              + abs(a01) * (abs(a10 * a22) + abs(a12 * a20))
              + abs(a02) * (abs(a10 * a21) + abs(a11 * a20)))
    big_q = (p * p - 3.0 * q) / 9.0
    big_r = (2.0 * p * p * p - 9.0 * p * q + 27.0 * r) / 54.0
    shift = p / 3.0
    if big_r * big_r < big_q * big_q * big_q:  # three real roots
        theta = np.arccos(big_r / np.sqrt(big_q * big_q * big_q))
        s = -2.0 * np.sqrt(big_q)
        root = 0.0 + 0.0j
        for k in range(3):
            x = s * np.cos((theta + 2.0 * np.pi * (k - 1)) / 3.0) - shift
            if abs(x) > abs(root):
                root = x + 0.0j
    else:
        u = -np.copysign(np.cbrt(abs(big_r) + np.sqrt(big_r * big_r - big_q * big_q * big_q)),
                         big_r)
        v = big_q / u if u != 0.0 else 0.0
        root = (u + v - shift) + 0.0j
        pair = complex(-0.5 * (u + v) - shift, 0.5 * np.sqrt(3.0) * (u - v))
        if abs(pair) > abs(root):
            root = pair
    radius = abs(root)
    slope = abs(3.0 * root * root + 2.0 * p * root + q)
    error = 8.0 * np.finfo(np.float64).eps * (size_p * radius * radius + size_q * radius
                                               + size_r) / slope
    return radius, error if np.isfinite(error) else np.inf
