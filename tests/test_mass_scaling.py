"""Selective mass scaling (docs/mass_scaling.md): the step it holds, the mass
it adds (closed form), the stability of the scaled system, what it does to a
vibration period, and the momentum and energy of a mid-run scaling.

Each test states its tolerance beside the assertion and where it comes from.
"""

from __future__ import annotations

import fdem
import numpy as np
import pytest
from conftest import ROCK, assembled_critical_step, perturbed_rectangle


def element_frequencies(points: np.ndarray, triangles: np.ndarray, mat: fdem.Elastic) -> np.ndarray:
    """ω_e of each lumped plane-strain CST, from its own 6×6 eigenproblem:
    ω² = (3/ρ) λ_max(Bᵀ C B) (DESIGN §4.2), built here with numpy."""
    lam, mu = mat.lame_lambda, mat.shear_modulus
    c = np.array([[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]])
    out = np.empty(len(triangles))
    for e, tri in enumerate(triangles):
        x = points[tri]
        area2 = (x[1, 0] - x[0, 0]) * (x[2, 1] - x[0, 1]) - (x[2, 0] - x[0, 0]) * (x[1, 1] - x[0, 1])
        b = np.zeros((3, 6))
        for a in range(3):
            j, k = (a + 1) % 3, (a + 2) % 3
            gx, gy = (x[j, 1] - x[k, 1]) / area2, (x[k, 0] - x[j, 0]) / area2
            b[0, 2 * a], b[1, 2 * a + 1], b[2, 2 * a], b[2, 2 * a + 1] = gx, gy, gy, gx
        out[e] = np.sqrt(3 / mat.rho * np.linalg.eigvalsh(b.T @ c @ b).max())
    return out


def areas(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    p = points[triangles]
    return 0.5 * np.abs(
        (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1])
    )


@pytest.mark.parametrize("beta", [0.0, 2e-7])
def test_mass_scaling_holds_the_step_with_the_closed_form_added_mass(beta):
    """On a mesh with slivers, ``mass_scaling = 2 Δt₀`` gives exactly that
    step, scales exactly the elements whose step was shorter, each by
    ``(ω_e / W)²`` with ``W = 2 / √(T² + 2Tβ)`` (the stiffness-damped bound
    solved for ω, T = Δt / safety), and the nodal masses sum to ρ ΣA plus
    the reported added mass. Tolerance 1e-9: rounding of the closed forms."""
    mesh = perturbed_rectangle(1.0, 0.6, 9, 6, amount=0.4, seed=3)
    model = fdem.Model(mesh, material=ROCK)
    dt0 = fdem.Simulation(model, stiffness_damping=beta).time_step
    target = 2 * dt0
    sim = fdem.Simulation(model, stiffness_damping=beta, mass_scaling=target)
    assert sim.time_step == pytest.approx(target, rel=1e-9)
    t = target / 0.8
    w_max = 2 / np.sqrt(t * t + 2 * t * beta)
    expected = np.maximum(1.0, (element_frequencies(mesh.points, mesh.triangles, ROCK) / w_max) ** 2)
    assert 0 < np.count_nonzero(expected > 1) < mesh.n_elements  # some scaled, not all
    np.testing.assert_allclose(sim.mass_scale(), expected, rtol=1e-9)
    a = areas(mesh.points, mesh.triangles)
    assert sim.added_mass == pytest.approx(ROCK.rho * ((expected - 1) * a).sum(), rel=1e-9)
    assert sim.masses().sum() == pytest.approx(ROCK.rho * a.sum() + sim.added_mass, rel=1e-12)
    # off: every mass physical
    plain = fdem.Simulation(model, stiffness_damping=beta)
    assert plain.added_mass == 0.0 and np.all(plain.mass_scale() == 1.0)


def test_scaled_system_is_stable_at_the_held_step():
    """The element bound still holds for the scaled masses: the kernel's
    critical step does not exceed that of the assembled, scaled lumped
    system (built here with numpy), and a run with random velocities at the
    held step (safety 0.9) stays bounded by the discrete-energy factor
    1 / (1 − 0.9²) (see test_elastic_physics)."""
    mesh = perturbed_rectangle(1.0, 0.6, 7, 5, amount=0.35, seed=7)
    model = fdem.Model(mesh, material=ROCK)
    dt0 = fdem.Simulation(model, safety=1.0).time_step
    sim = fdem.Simulation(model, safety=1.0, mass_scaling=1.8 * dt0)
    true_crit = assembled_critical_step(mesh, ROCK, scale=sim.mass_scale())
    assert sim.critical_time_step <= true_crit * (1 + 1e-12)
    assert sim.critical_time_step > 1.7 * dt0

    rng = np.random.default_rng(0)
    model.set_initial_velocity(rng.normal(size=(mesh.n_nodes, 2)) * 1e-3)
    run = fdem.Simulation(model, safety=0.9, mass_scaling=0.9 * 1.8 * dt0)
    e0 = run.energies()["kinetic"]
    worst = 0.0
    for _ in range(100):
        run.step(50)
        e = run.energies()
        worst = max(worst, (e["kinetic"] + e["elastic"]) / e0)
    assert worst <= 1 / (1 - 0.9**2) * (1 + 1e-3)


def _bar_period(mesh: fdem.Mesh, **settings) -> tuple[float, fdem.Simulation]:
    """Period of the first mode of a fixed-free bar with roller sides,
    from the first two upward zero crossings of the tip's mean velocity."""
    length = 1.0
    model = fdem.Model(mesh, material=ROCK)
    model.fix("left", x=True, y=True).fix("top", x=False, y=True).fix("bottom", x=False, y=True)
    model.set_initial_velocity(lambda x, y: np.column_stack([0.1 * np.sin(0.5 * np.pi * x / length), 0 * x]))
    sim = fdem.Simulation(model, **settings)
    tip = np.flatnonzero(np.isclose(mesh.points[:, 0], length))
    crossings, prev, t_prev = [], None, 0.0
    while len(crossings) < 3:
        sim.step(1)
        v = sim.velocities()[tip, 0].mean()
        if prev is not None and prev < 0 <= v:
            crossings.append(t_prev + (sim.time - t_prev) * (-prev) / (v - prev))
        prev, t_prev = v, sim.time
    return crossings[2] - crossings[1], sim


def test_bar_period_moves_by_less_than_the_added_mass_fraction():
    """First mode of a fixed-free bar (period 4L/c_p) on a mesh with slivers.
    Mass scaling to twice the step adds mass to the slivers only; by the
    Rayleigh quotient the period grows by about ½ Σ Δm φ² / Σ m φ², which for
    φ = sin(πx/2L) (Σ m φ² ≈ M/2, φ² ≤ 1) is at most ΔM / M: that is the
    tolerance on the change. Both periods are within 1% of 4L/c_p (the
    mesh's own dispersion)."""
    mesh = perturbed_rectangle(1.0, 0.1, 40, 4, amount=0.4, seed=5)
    exact = 4 * 1.0 / ROCK.p_wave_speed
    t0, plain = _bar_period(mesh)
    t1, scaled = _bar_period(mesh, mass_scaling=2 * plain.time_step)
    fraction = scaled.added_mass / plain.masses().sum()
    assert 0 < fraction < 0.05
    assert abs(t0 / exact - 1) < 0.01
    assert abs(t1 / exact - 1) < 0.01
    assert abs(t1 / t0 - 1) <= fraction
    assert scaled.steps < 0.6 * plain.steps


def test_mid_run_scaling_keeps_momentum_and_books_the_kinetic_energy():
    """A free body moving and vibrating; switching mass scaling on mid-run
    raises masses at once. Linear momentum Σ m v (whole-step velocities) is
    unchanged (to 1e-12 of Σ m |v|); the kinetic energy drops by exactly the
    booked ``mass_scaling`` term, so the balance residual does not move (to
    1e-9 of the largest term)."""
    mesh = perturbed_rectangle(1.0, 0.6, 9, 6, amount=0.4, seed=3)
    model = fdem.Model(mesh, material=ROCK)
    rng = np.random.default_rng(1)
    model.set_initial_velocity(np.array([0.5, -0.2]) + rng.normal(size=(mesh.n_nodes, 2)) * 1e-2)
    sim = fdem.Simulation(model)
    sim.step(200)
    m0, v0, e0 = sim.masses(), sim.velocities(), sim.energies()
    sim.configure(mass_scaling=2 * sim.time_step)
    m1, v1, e1 = sim.masses(), sim.velocities(), sim.energies()
    assert m1.sum() > m0.sum() * 1.001
    scale = (m0[:, None] * np.abs(v0)).sum()
    np.testing.assert_allclose((m1[:, None] * v1).sum(axis=0), (m0[:, None] * v0).sum(axis=0), atol=1e-12 * scale)
    drop = e0["kinetic"] - e1["kinetic"]
    assert drop > 0
    assert e1["mass_scaling"] == pytest.approx(drop, rel=1e-9)
    assert abs(e1["residual"] - e0["residual"]) <= 1e-9 * e1["largest_term"]
    sim.step(500)
    e2 = sim.energies()
    assert abs(e2["residual"]) <= 1e-3 * e2["largest_term"]


def test_mass_scale_is_written_to_the_vtu(tmp_path):
    """Where mass was added is visible in ParaView: cell field
    ``mass_scale`` of every frame equals the kernel's factors."""
    meshio = pytest.importorskip("meshio")
    mesh = perturbed_rectangle(1.0, 0.6, 9, 6, amount=0.4, seed=3)
    model = fdem.Model(mesh, material=ROCK)
    sim = fdem.Simulation(model, mass_scaling=2 * fdem.Simulation(model).time_step)
    sim.run(until=5 * sim.time_step, output_every=2 * sim.time_step, output=tmp_path, progress=False)
    frame = meshio.read(sorted(tmp_path.glob("fdem_*.vtu"))[-1])
    np.testing.assert_array_equal(frame.cell_data["mass_scale"][0], sim.mass_scale())
    assert frame.cell_data["mass_scale"][0].max() > 1


def test_mass_scaling_is_validated():
    """A non-positive or non-finite step is refused, naming the parameter."""
    model = fdem.Model(fdem.Mesh.rectangle(1.0, 1.0, 2, 2), material=ROCK)
    for bad in (0.0, -1e-6, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="mass_scaling"):
            fdem.Simulation(model, mass_scaling=bad)
