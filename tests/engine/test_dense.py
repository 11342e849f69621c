"""The orbit solver's small dense algebra (harvester_sweep.dense) against numpy's LAPACK and,
where the eigenvalues are ill-conditioned, against mpmath at 40 digits."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from harvester_sweep import dense

SCALES = np.array([1e-6, 1e-2, 1e-5])  # a monodromy's components: x [m], v [m/s], V [V]


def _each(function, *arrays):
    """``function`` of each matrix (and vector) of the stacks ``arrays``, stacked."""
    return np.array([function(*args) for args in zip(*arrays)])


@pytest.mark.parametrize("size", [3, 5, 12])
def test_eliminations_agree_with_lapack(size):
    rng = np.random.default_rng(size)
    a = rng.normal(size=(200, size, size))
    b = rng.normal(size=(200, size))
    np.testing.assert_allclose(_each(dense.det, a), np.linalg.det(a), rtol=1e-10)
    np.testing.assert_allclose(_each(dense.inverse, a), np.linalg.inv(a), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(_each(dense.solve_system, a, b),
                               np.linalg.solve(a, b[..., None])[..., 0],
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(_each(dense.matvec, a, b), np.einsum("nij,nj->ni", a, b),
                               rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(_each(dense.row_sum_norm, a),
                               np.linalg.norm(a, ord=np.inf, axis=(1, 2)), rtol=1e-14)
    assert dense.det(np.zeros((size, size))) == 0.0


def _monodromies(rng, n, pair):
    """n matrices V L V^-1 in a monodromy's component scales, with eigenvalues in the unit
    disk (a complex pair and a real one, or three real ones)."""
    out = []
    for _ in range(n):
        v = rng.normal(size=(3, 3)) * SCALES[:, None]
        if pair:
            rho, phase, third = rng.uniform(0, 1.2), rng.uniform(0, np.pi), rng.uniform(-1, 1)
            c, s = rho * np.cos(phase), rho * np.sin(phase)
            eigen = np.array([[c, -s, 0], [s, c, 0], [0, 0, third]])
        else:
            eigen = np.diag(rng.uniform(-1.2, 1.2, 3))
        out.append(v @ eigen @ np.linalg.inv(v))
    return np.array(out)


@pytest.mark.parametrize("pair", [False, True])
def test_spectral_radius_is_as_right_as_lapacks(pair):
    """The cubic's radius (or LAPACK's, where its bound says so) is LAPACK's to rounding
    for most matrices, and elsewhere no farther from the eigenvalues at 40 digits than ten
    times LAPACK's own error or the bound it is kept within (CUBIC_TRUST): at 1e-12 of the
    radius a few are ten times farther than LAPACK's, which no decision of the solver can
    see."""
    rng = np.random.default_rng(11 + pair)
    a = _monodromies(rng, 3000, pair)
    radius = _each(dense.spectral_radius, a)
    lapack = np.abs(np.linalg.eigvals(a)).max(axis=1)
    off = np.abs(radius - lapack) / lapack
    assert np.median(off) < 1e-15
    for k in np.flatnonzero(off > 1e-12):
        with mpmath.workdps(40):
            exact = float(max(abs(e) for e in mpmath.eig(mpmath.matrix(a[k].tolist()),
                                                         left=False, right=False)))
        assert abs(radius[k] - exact) <= 10 * abs(lapack[k] - exact) + dense.CUBIC_TRUST * exact


def test_a_radius_near_one_is_lapacks():
    """The solver compares the radius with 1: within NEAR_ONE of it, LAPACK decides."""
    rng = np.random.default_rng(5)
    v = rng.normal(size=(3, 3)) * SCALES[:, None]
    for radius in (1 - 1e-8, 1 + 1e-9, 1 - 0.5 * dense.NEAR_ONE):
        a = v @ np.diag([radius, 0.3, -0.2]) @ np.linalg.inv(v)
        assert dense.spectral_radius(a) == np.max(np.abs(np.linalg.eigvals(
            a.astype(complex))))
        assert (dense.spectral_radius(a) < 1) == (radius < 1)
