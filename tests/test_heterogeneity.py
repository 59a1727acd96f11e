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
    """The uniform specimen and the Weibull ones of seeds 7–10 (cv 0.3)."""
    return ucs(0.0), {seed: ucs(0.3, seed) for seed in (7, 8, 9, 10)}


def test_a_uniform_ucs_specimen_flows_uncracked_and_a_seed_gives_its_bits(ucs_runs):
    """A 50 mm × 100 mm plane-strain specimen between frictionless
    platens to 4 times the strain of its uniform strength: uniform, it
    yields at UCS = 2c cos φ/(1 − sin φ) (within 1%) and flows on that
    plateau uncracked to 3 times its yield strain; only round-off breaks
    the uniform state, late (the first cracks at 3.6–3.9 times the yield
    strain, depending on the order of the sums: with and without
    renumbering). With Weibull strength the same seed gives the same
    bits."""
    (_, uniform), runs = ucs_runs
    yield_strain = ROCK.ucs / ROCK.plane_strain_modulus
    plateau = [(s, n) for e, s, n in uniform if yield_strain * 1.1 < e < 3 * yield_strain]
    assert len(plateau) >= 15  # samples every 0.1 of the yield strain
    assert all(s == pytest.approx(ROCK.ucs, rel=0.01) and n == 0 for s, n in plateau)
    sim, _ = runs[7]
    again, _ = ucs(0.3)
    assert again.steps == sim.steps and np.array_equal(again.positions(), sim.positions())
    assert np.array_equal(again.stress(), sim.stress())


def softening(curve: list[tuple[float, float, int]]) -> tuple[float, float]:
    """The lowest stress after the peak and the stress at the end, each
    over the peak."""
    stress = np.array([s for _, s, _ in curve])
    peak = int(stress.argmax())
    return stress[peak:].min() / stress[peak], stress[-1] / stress[peak]


def test_heterogeneous_ucs_specimens_crack_and_soften(ucs_runs):
    """With Weibull strength (cv 0.3, independent per element) each of
    four specimens (seeds 7–10) peaks below UCS (bound 0.7–0.98 UCS),
    cracks (bound 100 insertions) and softens: after its peak its stress
    falls under 80% of the peak, at 4 times the yield strain it carries
    under 90% of it, and the four carry under 80% on average. How far
    one specimen has fallen *at* 4 times the yield strain is a cascade's
    outcome and scatters with the seed and the order of the sums (seed
    7: 44% and 60% without and with renumbering on 2026-11-26; 73% and
    80% before and after nodes on a crack read both sides, 2026-11-28),
    so the residual is read over the four. Measured 2026-11-28 (2-core
    Intel Xeon VM, 2 threads): peaks 0.86–0.94 UCS, 134–458 cracks,
    lowest after the peak 75% (seed 7), at 4 times the yield strain 80,
    31, 46 and 43% (mean 50%). Seed 7 flows on a residual of 80% from 2.6
    times the yield strain: Mohr–Coulomb is perfectly plastic, so once
    the cracks stop the pieces flow at their frictional strength."""
    ends = []
    for seed, (sim, curve) in ucs_runs[1].items():
        peak = max(s for _, s, _ in curve)
        assert 0.7 * ROCK.ucs < peak < 0.98 * ROCK.ucs, seed
        assert sim.insertions > 100, (seed, sim.insertions)
        lowest, end = softening(curve)
        assert lowest < 0.8, (seed, lowest)
        ends.append(end)
    assert max(ends) < 0.9 and np.mean(ends) < 0.8, ends
