"""Heterogeneous rock strength (issue 33, point 6): the random factors'
statistics against their distributions, the seed, and a virtual UCS
specimen that fails by cracking with a softening branch. Tolerances beside
each check."""

from __future__ import annotations

import math

import fdem
import numpy as np
import pytest
from fdem.heterogeneity import strength_factors, weibull_shape
from fdem.laboratory import compression_specimen

ROCK = fdem.MohrCoulombRankine(E=30e9, nu=0.25, rho=2700.0, c=12e6, phi=35.0, psi=5.0, ft=4e6, Gf=50.0)


def test_weibull_modulus_gives_the_coefficient_of_variation():
    """cv² = Γ(1 + 2/k)/Γ(1 + 1/k)² − 1 (to 1e-9 after the bisection);
    k ≈ 5.8 for cv = 0.2 (tabulated values: 5.79–5.80)."""
    for cv in (0.05, 0.2, 0.5, 1.0):
        k = weibull_shape(cv)
        assert math.sqrt(math.gamma(1 + 2 / k) / math.gamma(1 + 1 / k) ** 2 - 1) == pytest.approx(cv, rel=1e-9)
    assert weibull_shape(0.2) == pytest.approx(5.8, abs=0.01)


@pytest.mark.parametrize("distribution", ["weibull", "lognormal"])
def test_independent_factors_have_mean_one_and_the_asked_scatter(distribution):
    """2×10⁵ independent factors in 64 classes: mean 1 within 0.3% (the
    sampling error is 0.07%), cv within 2% of the asked 0.3 (the classes
    lose a little of the tails); the same seed gives the same factors, bit
    for bit, another seed others."""
    pts = np.random.default_rng(1).uniform(0.0, 10.0, (200_000, 2))
    w = strength_factors(pts, cv=0.3, distribution=distribution, seed=3)
    assert w.mean() == pytest.approx(1.0, rel=3e-3)
    assert w.std() / w.mean() == pytest.approx(0.3, rel=0.02)
    assert len(np.unique(w)) == 64
    assert np.array_equal(w, strength_factors(pts, cv=0.3, distribution=distribution, seed=3))
    assert not np.array_equal(w, strength_factors(pts, cv=0.3, distribution=distribution, seed=4))


def test_a_correlated_field_decorrelates_over_its_length():
    """A Gaussian field of correlation exp(−d²/ℓ²): on a 20 m × 20 m grid
    with ℓ = 0.5 m the normal values' correlation at d = ℓ/2, ℓ and 2ℓ is
    0.78, 0.37 and 0.02 within 0.06 (the sampling error of about 1 600
    correlation areas)."""
    from fdem.heterogeneity import _gaussian_field

    x = np.linspace(0.0, 20.0, 401)
    pts = np.array([[a, b] for a in x for b in x[::10]])
    z = _gaussian_field(pts, 0.5, np.random.default_rng(5)).reshape(len(x), -1)
    assert z.var() == pytest.approx(1.0, abs=0.05)
    for d in (0.25, 0.5, 1.0):
        k = int(round(d / 0.05))
        corr = np.mean(z[:-k] * z[k:]) / z.var()
        assert corr == pytest.approx(math.exp(-((d / 0.5) ** 2)), abs=0.06)


def test_vary_strength_scales_ft_c_and_gf_together_and_names_bad_input():
    """Every element of a plastic material gets a class material with ft,
    c and Gf times its factor (so ft ≤ c cot φ still holds); elastic ones
    keep theirs; bad input is named."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 6, 6)
    base = fdem.Model(mesh, material=ROCK)
    model = fdem.Model(mesh, material=ROCK).vary_strength(0.3, seed=2)
    w = strength_factors(mesh.centroids(), cv=0.3, seed=2)
    for e in range(mesh.n_elements):
        m = model._materials[model._element_material[e]]
        assert m.ft == pytest.approx(ROCK.ft * w[e], rel=1e-15) and m.c == pytest.approx(ROCK.c * w[e], rel=1e-15)
        assert m.Gf == pytest.approx(ROCK.Gf * w[e], rel=1e-15) and m.E == ROCK.E
    assert len(base._materials) == 1
    elastic = fdem.Model(mesh, material=fdem.Elastic(E=1e9, nu=0.2, rho=1000.0))
    with pytest.raises(ValueError, match="MohrCoulombRankine"):
        elastic.vary_strength(0.3)
    with pytest.raises(ValueError, match="cv"):
        fdem.Model(mesh, material=ROCK).vary_strength(5.0)
    with pytest.raises(ValueError, match="distribution"):
        fdem.Model(mesh, material=ROCK).vary_strength(0.3, distribution="gauss")


def ucs(cv: float, seed: int = 7) -> tuple[fdem.Simulation, list[tuple[float, float, int]]]:
    """The specimen loaded to 4 times the yield strain of its uniform
    strength: the run and, 40 times along, (axial strain, axial stress,
    cracks inserted so far)."""
    model = compression_specimen(ROCK, width=0.05, height=0.1, cells=(10, 20), strain_rate=0.2, ramp=2e-4)
    if cv > 0:
        model.vary_strength(cv, seed=seed)
    model.contact(fdem.Interface(friction=30.0)).fracture()
    sim = fdem.Simulation(model, threads=2)
    end = 4 * ROCK.ucs / ROCK.plane_strain_modulus / 0.2
    curve = []
    while sim.time < end:
        sim.run(until=sim.time + end / 40, progress=False, checkpoint=False)
        r = sim.reaction("top")
        curve.append((-r["displacement"][1] / 0.1, r["force"][1] / 0.05, sim.insertions))
    return sim, curve


@pytest.fixture(scope="module")
def ucs_runs():
    """The uniform specimen and the Weibull one of seed 7 (cv 0.3)."""
    return ucs(0.0), ucs(0.3)


def test_a_heterogeneous_ucs_specimen_cracks_and_softens(ucs_runs):
    """A 50 mm × 100 mm plane-strain specimen between frictionless
    platens to 4 times the strain of its uniform strength: uniform, it
    yields at UCS = 2c cos φ/(1 − sin φ) (within 1%) and flows on that
    plateau uncracked to 3 times its yield strain; only round-off breaks
    the uniform state, late (the first cracks at 3.6–3.9 times the yield
    strain, depending on the order of the sums: with and without
    renumbering). With Weibull strength (cv 0.3, independent per
    element, seed 7) it peaks below that (measured 2026-11-28: 0.88 UCS;
    bound 0.7–0.98) and cracks (134 insertions; bound 100). How far it
    has softened by 4 times the yield strain is the next test. The same
    seed gives the same bits."""
    (_, uniform), (sim, curve) = ucs_runs
    yield_strain = ROCK.ucs / ROCK.plane_strain_modulus
    plateau = [(s, n) for e, s, n in uniform if yield_strain * 1.1 < e < 3 * yield_strain]
    assert len(plateau) >= 15  # samples every 0.1 of the yield strain
    assert all(s == pytest.approx(ROCK.ucs, rel=0.01) and n == 0 for s, n in plateau)
    peak = max(s for _, s, _ in curve)
    assert 0.7 * ROCK.ucs < peak < 0.98 * ROCK.ucs
    assert sim.insertions > 100
    again, _ = ucs(0.3)
    assert again.steps == sim.steps and np.array_equal(again.positions(), sim.positions())
    assert np.array_equal(again.stress(), sim.stress())


def softening(curve: list[tuple[float, float, int]]) -> tuple[float, float]:
    """The lowest stress after the peak and the stress at the end, each
    over the peak."""
    stress = np.array([s for _, s, _ in curve])
    peak = int(stress.argmax())
    return stress[peak:].min() / stress[peak], stress[-1] / stress[peak]


def test_a_heterogeneous_ucs_specimen_has_a_softening_branch(ucs_runs):
    """The specimen of the test above (seed 7) softens after its peak: its
    stress falls under 80% of the peak before 4 times the yield strain
    (measured 2026-11-28: 75% at 2.6 times, then a residual of 80% on
    which it flows plastically, Mohr–Coulomb being perfectly plastic).
    How far one specimen has fallen *at* 4 times the yield strain is a
    cascade's outcome and scatters with the seed and the order of the
    sums (seed 7: 44% and 60% without and with renumbering on
    2026-11-26; 73% and 80% before and after nodes on a crack read both
    sides, 2026-11-28, when seeds 8–10 went from 63, 42, 51% to 31, 46,
    43%): that is read over four specimens, in the slow test below."""
    _, (_, curve) = ucs_runs
    lowest, _ = softening(curve)
    assert lowest < 0.8


@pytest.mark.slow
def test_four_heterogeneous_ucs_specimens_soften_on_average():
    """Seeds 7–10 of the specimen above: each has a softening branch
    (under 80% of its peak after it), and at 4 times the yield strain
    they carry on average under 80% of their peaks (measured 2026-11-28:
    80, 31, 46 and 43%, mean 50%; the code before that day 73, 63, 42,
    51%, mean 57%). About 90 s at 2 threads."""
    ends = []
    for seed in (7, 8, 9, 10):
        _, curve = ucs(0.3, seed)
        lowest, end = softening(curve)
        assert lowest < 0.8, f"seed {seed}"
        ends.append(end)
    assert np.mean(ends) < 0.8
