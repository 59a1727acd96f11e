"""Gradual excavation: the removed elements' forces released over a ramp
(issue 36, point 2)."""

from __future__ import annotations

import fdem
import numpy as np
import pytest

SIGMA = -10e6  # Pa, the in-situ stress (compression negative)


def plate_with_core(ramp: float, local_damping: float = 0.0) -> fdem.Simulation:
    """A 20 m × 20 m plate under a uniform in-situ stress, held by rollers,
    its central 4 m × 4 m core excavated at t = 1 ms."""
    mesh = fdem.Mesh.rectangle(20.0, 20.0, 20, 20, origin=(-10.0, -10.0))
    core = np.flatnonzero(np.all(np.abs(mesh.centroids()) < 2.0, axis=1))
    mesh = mesh.with_sets(element_sets={"core": core})
    model = fdem.Model(mesh, material=fdem.Elastic(E=10e9, nu=0.25, rho=2500.0))
    for side in ("left", "right"):
        model.fix(side, x=True, y=False)
    for side in ("bottom", "top"):
        model.fix(side, x=False, y=True)
    model.set_initial_stress((SIGMA, SIGMA, 0.5 * SIGMA, 0.0))
    model.excavate("core", at=1e-3, ramp=ramp)
    return fdem.Simulation(model, local_damping=local_damping)


def test_a_ramped_release_is_gentle_ends_where_the_sudden_one_does_and_keeps_the_books():
    """Removed at once, the core's stress leaves the opening's walls in one
    step and a release wave rings through the plate; released over 20 ms
    (about ten transit times of the plate) the walls unload
    quasi-statically: the fastest wall speed is a fraction of the sudden
    release's, and once at rest (local damping) the two end in the same
    state (displacements within 1e-3 of their largest). The ramp's loads
    are external work, so the energy account closes through the ramp to
    2e-4 of its largest term (measured 9e-5; the sudden release, a jump
    the central difference integrates only to first order, 1.8e-3)."""
    speeds, final = {}, {}
    for ramp in (0.0, 0.02):
        sim = plate_with_core(ramp)
        fastest = 0.0
        while sim.time < 0.025:
            sim.run(until=sim.time + 5e-4, progress=False, checkpoint=False)
            fastest = max(fastest, float(np.abs(sim.velocities()).max()))
        speeds[ramp] = fastest
        e = sim.energies()
        assert abs(e["residual"]) < (2e-4 if ramp else 5e-3) * e["largest_term"]
        sim.configure(local_damping=0.8)
        sim.run(until=0.12, progress=False, checkpoint=False)
        final[ramp] = sim.displacements()
    assert speeds[0.02] < 0.2 * speeds[0.0]
    scale = np.abs(final[0.0]).max()
    assert np.abs(final[0.02] - final[0.0]).max() < 1e-3 * scale


def test_a_run_resumed_during_the_ramp_goes_on_bit_for_bit(tmp_path):
    sim = plate_with_core(0.02)
    sim.run(until=0.008, progress=False, checkpoint=False)
    path = sim.save_checkpoint(tmp_path / "ramp.ckpt")
    sim.run(until=0.016, progress=False, checkpoint=False)
    back = fdem.Simulation.from_checkpoint(path, sim.model)
    back.run(until=0.016, progress=False, checkpoint=False)
    assert np.array_equal(back.positions(), sim.positions())
    assert back.energies() == sim.energies()


def test_a_bad_ramp_is_refused_naming_it():
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    model = fdem.Model(mesh, material=fdem.Elastic(E=1e9, nu=0.25, rho=2000.0))
    for bad in (-1.0, float("inf"), float("nan")):
        with pytest.raises(ValueError, match="ramp"):
            model.excavate([0], at=0.0, ramp=bad)


def most_launched(ramp: float, tmp_path) -> float:
    """The tiny block-caving case (4 m elements, joint spacings ×8, stages
    every 60 ms) with its undercut released over ``ramp`` s: the largest
    kinetic energy per unit mass (J/kg) that any fragment holds beyond what
    its fall paid for (``Simulation.fragments()``'s ``energy_beyond_fall``,
    of its centre of mass), sampled every 10 ms to 0.5 s."""
    from fdem.caving import CavingCase, run_caving

    case = CavingCase(size=4.0, joint_scale=8.0, support=5.0, interval=0.06, until=0.01, output_every=0.01, ramp=ramp)
    sim = run_caving(tmp_path / f"ramp_{ramp}", case, progress=False)["simulation"]
    worst = 0.0
    while sim.time < 0.5:
        sim.run(until=sim.time + 0.01, progress=False, checkpoint=False)
        worst = max(worst, float(sim.fragments()["energy_beyond_fall"].max()))
    return worst


def test_a_ramped_undercut_launches_fragments_less_than_a_sudden_one(tmp_path):
    """A gradual release exists to be gentler than a sudden one, and with
    cracks it must stay so: a crack that cuts into the star of a node
    carrying a release load ends that load at once (docs/fracture.md,
    "Cracks end a gradual excavation's loads"). Before, the dead load of
    the wall's stress stayed on pieces that had broken loose and drove
    them: released over 20 ms, the quick caving case shot a 2 m² piece at
    36 m/s (665 J/kg beyond its fall) where the sudden undercut's fastest
    held 12.8 J/kg, and this tiny case's worst held 14.1 J/kg against the
    sudden one's 13.4 (2-core Zen 3 VM, 2026-11-27). Asked: the ramped
    undercut's worst below the sudden one's (measured 7.5 against
    13.4 J/kg)."""
    from fdem.caving import CavingCase

    for bad in (-0.01, float("inf"), float("nan")):
        with pytest.raises(ValueError, match="CavingCase.ramp"):
            CavingCase(ramp=bad)
    sudden, ramped = most_launched(0.0, tmp_path), most_launched(0.02, tmp_path)
    assert ramped < sudden, (ramped, sudden)
