"""Shared helpers for the test suite."""

from __future__ import annotations

import fdem
import numpy as np
import pytest

ROCK = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)


def perturbed_rectangle(
    width: float, height: float, nx: int, ny: int, amount: float = 0.25, seed: int = 1
) -> fdem.Mesh:
    """A structured rectangle whose interior nodes are moved randomly by up to
    ``amount`` of a cell: an unstructured interior with straight sides."""
    base = fdem.Mesh.rectangle(width, height, nx, ny, pattern="alternating")
    pts = base.points.copy()
    hx, hy = width / nx, height / ny
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    interior = np.all((pts > lo + 1e-12) & (pts < hi - 1e-12), axis=1)
    rng = np.random.default_rng(seed)
    pts[interior] += rng.uniform(-amount, amount, (interior.sum(), 2)) * [hx, hy]
    return fdem.Mesh(pts, base.triangles, facet_sets=dict(base.facet_sets), node_sets=dict(base.node_sets))


def assembled_critical_step(mesh: fdem.Mesh, mat: fdem.Elastic, scale: np.ndarray | None = None) -> float:
    """True critical step 2/ω_max of the assembled lumped system, built here
    independently of the kernel (dense numpy, free-free); ``scale`` is an
    optional density factor per element (mass scaling)."""
    n = mesh.n_nodes
    lam, mu = mat.lame_lambda, mat.shear_modulus
    c = np.array([[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]])
    k = np.zeros((2 * n, 2 * n))
    m = np.zeros(2 * n)
    for e, tri in enumerate(mesh.triangles):
        x = mesh.points[tri]
        area = 0.5 * ((x[1, 0] - x[0, 0]) * (x[2, 1] - x[0, 1]) - (x[2, 0] - x[0, 0]) * (x[1, 1] - x[0, 1]))
        b = np.zeros((3, 6))
        for a in range(3):
            j, k2 = (a + 1) % 3, (a + 2) % 3
            gx, gy = (x[j, 1] - x[k2, 1]) / (2 * area), (x[k2, 0] - x[j, 0]) / (2 * area)
            b[0, 2 * a], b[1, 2 * a + 1], b[2, 2 * a], b[2, 2 * a + 1] = gx, gy, gy, gx
        dofs = np.ravel([[2 * v, 2 * v + 1] for v in tri])
        k[np.ix_(dofs, dofs)] += area * b.T @ c @ b
        m[dofs] += mat.rho * (1.0 if scale is None else scale[e]) * area / 3
    s = 1 / np.sqrt(m)
    w2 = np.linalg.eigvalsh(s[:, None] * k * s[None, :]).max()
    return float(2 / np.sqrt(w2))


@pytest.fixture
def rock() -> fdem.Elastic:
    return ROCK


@pytest.fixture(scope="session")
def quick_caving(tmp_path_factory):
    """The README's demo (`fdem demo`): the quick caving case, run once for
    every module that reads it (tests/test_caving.py, test_caving_metrics.py)."""
    from fdem.demos import run_demo

    out = tmp_path_factory.mktemp("caving")
    summary = run_demo(out, quick=True, progress=False)
    return out, summary
