"""Spatial renumbering of nodes and elements during a run
(docs/renumbering.md): a pure relabelling that the user never sees. Every
array and id the simulation reports stays in creation order; the physics
of the next steps is the same up to the order of floating-point sums; a
run that renumbers is bit-for-bit the same on any thread count and after a
restart. Tolerances beside each check."""

from __future__ import annotations

import dataclasses

import fdem
import numpy as np
import pytest
from fdem.caving import CavingCase, caving_model
from test_fracture import tension_bar

# the quick caving case, cracking under the advancing undercut
CASE = dataclasses.replace(CavingCase.quick(), renumber=None)
T_START = 0.3


@pytest.fixture(scope="module")
def cracking(tmp_path_factory: pytest.TempPathFactory) -> tuple[fdem.Model, str]:
    """A checkpoint of the quick case at 0.3 s, made without renumbering
    (its element count has grown by crack insertion since the start)."""
    model = caving_model(CASE)
    sim = fdem.Simulation(model, threads=2, stiffness_damping=2e-6, renumber=None)
    sim.equilibrate(max_velocity=1e-3)
    sim.configure(mass_scaling=0.8 * sim.time_step)
    while sim.time < T_START:
        sim.step(200)
    assert sim.insertions > 300 and sim.renumberings == 0
    path = tmp_path_factory.mktemp("renumber") / "cracking.ckpt"
    sim.save_checkpoint(path)
    return model, str(path)


def restore(cracking: tuple[fdem.Model, str], threads: int = 2) -> fdem.Simulation:
    model, path = cracking
    return fdem.Simulation.from_checkpoint(path, model, threads=threads)


READOUTS = ("positions", "reference_positions", "triangles", "masses", "mass_scale", "active", "stress", "areas")


def test_renumbering_changes_no_reported_number(cracking):
    """Right after a renumbering every per-node and per-element array, the
    ids inside results (connectivity, surface facets, contacts, bonds,
    fragments) and the material state are bit-identical to the run's
    before; the whole-step velocities and the energies, which sum over
    nodes, agree to round-off (1e-13 relative)."""
    a, b = restore(cracking), restore(cracking)
    b.renumber()
    assert b.renumberings == 1
    for name in READOUTS + ("fragment_labels",):
        assert np.array_equal(getattr(a, name)(), getattr(b, name)()), name
    for key, va in a.element_state().items():
        assert np.array_equal(va, b.element_state()[key]), key
    for key, va in a.bonds().items():
        assert np.array_equal(va, b.bonds()[key]), key
    for fa, fb in zip(a.surface_facets(), b.surface_facets(), strict=True):
        assert np.array_equal(fa, fb)

    def contacts(sim: fdem.Simulation) -> list[tuple]:
        c = sim.contacts()
        return list(zip(c["node"].tolist(), map(tuple, c["facet"].tolist()), c["gap"].tolist(), strict=True))

    assert contacts(a) == contacts(b)
    va, vb = a.velocities(), b.velocities()
    assert np.max(np.abs(va - vb)) <= 1e-13 * np.max(np.abs(va))
    ea, eb = a.energies(), b.energies()
    scale = max(abs(v) for v in ea.values())
    for key in ea:
        assert abs(ea[key] - eb[key]) <= 1e-13 * scale, key


def test_renumbered_run_steps_on_with_the_same_physics(cracking):
    """The steps after a renumbering compute what they would have without
    it, up to the order of sums: up to the next crack-insertion check
    positions agree to 1e-12 m and velocities to 1e-9 relative; through the
    check the same cracks open at the same places (the multiset of node
    positions agrees to 1e-12 m; which new node gets which id may differ),
    and the stable step, the mass and the contact count agree. A value the
    renumbering failed to move (a node's mass, an element's plastic state
    or stored frequency, a contact's memory, a node's crack flag) would show
    here as a different force, step or crack."""
    a, b = restore(cracking), restore(cracking)
    b.renumber()
    interval = a.check_every  # steps between crack checks
    before_check = interval - a.steps % interval - 1
    a.step(before_check)
    b.step(before_check)
    assert np.max(np.abs(a.positions() - b.positions())) <= 1e-12
    va, vb = a.velocities(), b.velocities()
    assert np.max(np.abs(va - vb)) <= 1e-9 * np.max(np.abs(va))
    n0 = a.insertions
    while a.insertions == n0:
        a.step(interval)
        b.step(interval)
        assert b.insertions == a.insertions
    assert (a.n_nodes, a.n_elements) == (b.n_nodes, b.n_elements)
    pa = a.positions()[np.lexsort(a.positions().T[::-1])]
    pb = b.positions()[np.lexsort(b.positions().T[::-1])]
    assert np.max(np.abs(pa - pb)) <= 1e-12
    assert b.time_step == pytest.approx(a.time_step, rel=1e-12)
    assert b.masses().sum() == pytest.approx(a.masses().sum(), rel=1e-13)
    assert len(b.contacts()["node"]) == len(a.contacts()["node"])


def test_a_renumbering_run_is_the_same_on_any_thread_count_and_after_a_restart(cracking, tmp_path):
    """With renumbering on (at 1% growth, so that it happens every 50–250
    steps here), 1 and 2 threads end on the same bits, and a run stopped,
    checkpointed and restored between renumberings ends on the same bits as
    one that was not stopped."""
    runs = []
    for threads in (1, 2):
        sim = restore(cracking, threads).configure(renumber=0.01)
        sim.step(400)
        runs.append(sim)
    one, two = runs
    assert one.renumberings >= 2
    assert np.array_equal(one.positions(), two.positions())
    assert np.array_equal(one.stress(), two.stress())
    sim = restore(cracking).configure(renumber=0.01)
    sim.step(100)
    assert 1 <= sim.renumberings < one.renumberings
    sim.save_checkpoint(tmp_path / "mid.ckpt")
    again = fdem.Simulation.from_checkpoint(tmp_path / "mid.ckpt", cracking[0], threads=2)
    again.step(300)
    assert again.renumberings == one.renumberings
    assert np.array_equal(again.positions(), two.positions())
    assert np.array_equal(again.triangles(), two.triangles())
    assert again.energies() == two.energies()


def test_ids_given_to_the_simulation_stay_ids_after_a_renumbering(cracking):
    """Element ids for ``deactivate`` and node ids for prescribed
    velocities mean the same entities after a renumbering; a bad setting
    is refused by name."""
    a, b = restore(cracking), restore(cracking)
    b.renumber()
    ids = np.flatnonzero(a.active())[:50]
    assert a.deactivate(ids) == b.deactivate(ids) == 50
    assert np.array_equal(a.active(), b.active())
    with pytest.raises(ValueError, match="renumber"):
        a.configure(renumber=-1.0)


def test_a_model_without_contact_renumbers_too():
    """A plate under gravity and edge pressure, no contact or fracture:
    renumbered, its readouts are unchanged and the next steps agree to
    1e-12 m."""
    mesh = fdem.Mesh.rectangle(10.0, 4.0, 20, 8)
    model = fdem.Model(mesh, material=fdem.Elastic(E=10e9, nu=0.25, rho=2500.0)).set_gravity(0.0, -9.81)
    model.fix("left").pressure("top", 1e6)
    a, b = fdem.Simulation(model, threads=2, renumber=None), fdem.Simulation(model, threads=2, renumber=None)
    a.step(10)
    b.step(10)
    b.renumber()
    for name in READOUTS:
        assert np.array_equal(getattr(a, name)(), getattr(b, name)()), name
    a.step(30)
    b.step(30)
    assert np.max(np.abs(a.positions() - b.positions())) <= 1e-12


def test_renumbering_keeps_the_forces_of_intact_cohesive_bonds():
    """Bonds across young cracks act through the contact forces; a
    renumbering adds those up again from the contact records and must add
    the bonds' forces too (it dropped them: the bonded nodes' whole-step
    velocities jumped by 0.04 m/s and the next step lost the bonds). The
    tension bar of test_fracture with ten bonds intact: velocities agree to
    1e-13 relative right after, and positions to 1e-12 m 500 steps on."""
    (a, _, _), (b, _, _) = tension_bar(0.02, threads=2), tension_bar(0.02, threads=2)
    a.step(5000)
    b.step(5000)
    bonds = a.bonds()
    assert len(bonds["length"]) >= 5 and np.all(bonds["damage"] < 1)
    b.renumber()
    va, vb = a.velocities(), b.velocities()
    assert np.max(np.abs(va - vb)) <= 1e-13 * np.max(np.abs(va))
    a.step(500)
    b.step(500)
    assert np.max(np.abs(a.positions() - b.positions())) <= 1e-12


def test_motion_renumbers_every_thousand_steps_without_growth():
    """Besides the renumberings that growth triggers, a run with
    ``renumber_every=1000`` renumbers at every 1000th step (falling rock
    spoils the order as surely as new elements: docs/renumbering.md), the
    same on any thread count, and steps on with the physics of a run that
    does not renumber: positions to 1e-12 m after 2 500 steps of a plate
    under gravity and edge pressure (no contact, no fracture, no growth).
    With the defaults (growth only) the plate is never renumbered."""
    mesh = fdem.Mesh.rectangle(10.0, 4.0, 20, 8)
    model = fdem.Model(mesh, material=fdem.Elastic(E=10e9, nu=0.25, rho=2500.0)).set_gravity(0.0, -9.81)
    model.fix("left").pressure("top", 1e6)
    plain = fdem.Simulation(model, threads=2, renumber=None)
    runs = [fdem.Simulation(model, threads=t, renumber_every=1000) for t in (1, 2)]
    plain.step(999)
    for sim in runs:
        sim.step(999)
        assert sim.renumberings == 0
        sim.step(1)
        assert sim.renumberings == 1
        sim.step(1500)
        assert sim.renumberings == 2
    plain.step(1501)
    default = fdem.Simulation(model, threads=2)
    default.step(2500)
    assert default.renumberings == 0 and np.array_equal(default.positions(), plain.positions())
    one, two = runs
    assert np.array_equal(one.positions(), two.positions())
    assert np.max(np.abs(one.positions() - plain.positions())) <= 1e-12
