"""The small dense algebra at the sizes of every model: compiled elimination against LAPACK.

    python -m benchmarks.dense_sizes [--output FILE]

The orbit solver solves a D x D system and takes a spectral radius per point and Newton
step (harvester_sweep.dense). D is 3 for the tip-mass model, 5 with a moving stop, and the
beam's state size for the beam (11 for the bimorph_tip preset, 21 for mak_rod with its rod
modes). For each D this times, per matrix, over a batch of monodromy-like matrices
(non-normal, eigenvalues inside the unit circle, entries of the scales the solver sees):

- a solve of (I - M) x = b: ``dense.solve_system`` in a compiled loop, numba's LAPACK
  binding (``np.linalg.solve``) in the same loop, and NumPy's batched ``np.linalg.solve``
  (the beam solver's call);
- the spectral radius: ``dense.spectral_radius`` in a compiled loop (the characteristic
  cubic at D = 3, LAPACK beyond), and NumPy's ``eigvals`` one matrix at a time (the beam
  solver's call);

and, so that the cheaper way is also shown right, the worst relative residual
|(I - M) x - b| / (|I - M| |x|) of each solve (its backward error) and the worst relative
error of each radius against mpmath's eigenvalues at 40 digits (on the first
``REFERENCE`` matrices of each size). Best of five runs after an uncounted one, one thread.
"""

from __future__ import annotations

import argparse

import mpmath
import numba
import numpy as np
from numba import njit

from benchmarks.variants import best, provenance, report
from harvester_sweep import dense

SIZES = {3: "tip-mass model", 5: "moving stop", 11: "beam, bimorph_tip", 21: "beam, mak_rod"}
BATCH = 4096
REPEATS = 5
REFERENCE = 16


def matrices(d: int, n: int, seed: int = 0) -> np.ndarray:
    """n non-normal D x D matrices with eigenvalues of modulus 0.05 ... 0.95 (complex pairs
    among them) and condition numbers up to about 1e3, as monodromies are."""
    rng = np.random.default_rng(seed)
    out = np.empty((n, d, d))
    for k in range(n):
        v = rng.normal(size=(d, d)) @ np.diag(10.0 ** rng.uniform(-1.5, 1.5, d))
        radius = rng.uniform(0.05, 0.95, d)
        block = np.zeros((d, d))
        j = 0
        while j < d:
            if j + 1 < d and rng.random() < 0.5:  # a complex pair
                angle = rng.uniform(0, np.pi)
                c, s = radius[j] * np.cos(angle), radius[j] * np.sin(angle)
                block[j:j + 2, j:j + 2] = [[c, -s], [s, c]]
                j += 2
            else:
                block[j, j] = radius[j] * rng.choice([-1.0, 1.0])
                j += 1
        out[k] = v @ block @ np.linalg.inv(v)
    return out


@njit(cache=True)
def _dense_solves(a, b, out):
    for k in range(a.shape[0]):
        out[k] = dense.solve_system(a[k], b[k])


@njit(cache=True)
def _lapack_solves(a, b, out):
    for k in range(a.shape[0]):
        out[k] = np.linalg.solve(a[k], b[k])


@njit(cache=True)
def _dense_radii(m, out):
    for k in range(m.shape[0]):
        out[k] = dense.spectral_radius(m[k])


def _numpy_radii(m, out):
    for k in range(len(m)):
        out[k] = np.abs(np.linalg.eigvals(m[k])).max()


def _numpy_solves(a, b, out):
    out[:] = np.linalg.solve(a, b[..., None])[..., 0]


def _reference_radii(m) -> np.ndarray:
    """Spectral radii of ``m`` (k, D, D) from mpmath's eigenvalues at 40 digits."""
    with mpmath.workdps(40):
        return np.array([float(max(abs(v) for v in mpmath.eig(mpmath.matrix(a.tolist()),
                                                                left=False, right=False)))
                         for a in m])


def _residual(a, b, x) -> float:
    r = np.einsum("kij,kj->ki", a, x) - b
    return float(np.max(np.abs(r).max(axis=1)
                        / (np.abs(a).sum(axis=2).max(axis=1) * np.abs(x).max(axis=1))))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output")
    args = parser.parse_args(argv)
    numba.set_num_threads(1)
    lines = ["# Small dense algebra per matrix, by state size", "",
             f"{provenance()} Command: python -m benchmarks.dense_sizes", "",
             f"Per matrix, best of {REPEATS} runs over {BATCH} matrices, one thread; "
             "residual: worst |(I - M) x - b| / (|I - M| |x|); radius error: worst relative "
             f"error against mpmath's at 40 digits, first {REFERENCE} matrices.", "",
             "| D | model | solve: dense | solve: numba LAPACK | solve: NumPy batched "
             "| residual dense / numba LAPACK | radius: dense | radius: NumPy eigvals "
             "| radius error dense / NumPy |",
             "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for d, model in SIZES.items():
        m = matrices(d, BATCH)
        a = np.eye(d) - m
        b = np.random.default_rng(1).normal(size=(BATCH, d))
        x_dense, x_lapack, x_numpy = (np.empty((BATCH, d)) for _ in range(3))
        r_dense, r_numpy = np.empty(BATCH), np.empty(BATCH)
        us = 1e6 / BATCH
        t = [best(lambda call=call, args=args: call(*args), REPEATS)[0]
             for call, args in ((_dense_solves, (a, b, x_dense)),
                                (_lapack_solves, (a, b, x_lapack)),
                                (_numpy_solves, (a, b, x_numpy)), (_dense_radii, (m, r_dense)),
                                (_numpy_radii, (m, r_numpy)))]
        exact = _reference_radii(m[:REFERENCE])
        errors = [float(np.max(np.abs(r[:REFERENCE] - exact) / exact))
                  for r in (r_dense, r_numpy)]
        lines.append(
            f"| {d} | {model} | {t[0] * us:.2f} us | {t[1] * us:.2f} us | {t[2] * us:.2f} us "
            f"| {_residual(a, b, x_dense):.1e} / {_residual(a, b, x_lapack):.1e} "
            f"| {t[3] * us:.2f} us | {t[4] * us:.2f} us "
            f"| {errors[0]:.1e} / {errors[1]:.1e} |")
    report(lines, args.output)


if __name__ == "__main__":
    main()
