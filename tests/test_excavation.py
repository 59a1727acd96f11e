"""Excavating rock that has cracked (issue 32, point 5; DESIGN §4.4 and
§4.6, docs/fracture.md "What a crack's pieces inherit"): the pieces crack
insertion makes of an element belong to every set the element is in, so
an excavation stage or ``deactivate`` of a set removes them with it, mass
and energy leave as for an uncracked set, and the lineage survives
renumbering and checkpoints. Tolerances beside each check."""

from __future__ import annotations

import fdem
import numpy as np
import pytest

SOFT = dict(E=10e9, nu=0.2, rho=2700.0, c=4e6, phi=35.0, psi=5.0)
RHO = SOFT["rho"]
CRACKED = 4e-3  # the bar's weak section has cracked by then (first cracks at 3 ms)


def bar(stage: float | None = None, *, renumber: float | None = None) -> tuple[fdem.Simulation, fdem.Model]:
    """The tension bar of tests/test_fracture.py (0.5 m × 0.1 m, element size
    0.014 m, pulled at 20 mm/s): its ``weak`` set, the elements across the
    middle, cracks at about 3 ms by splitting its own elements (14 pieces
    made of them by 4 ms). ``stage``: the time ``weak`` is excavated."""
    length, width = 0.5, 0.1
    mesh = fdem.jointed_rectangle(length, width, 0.014)
    px = mesh.points[mesh.triangles][:, :, 0]
    weak = np.flatnonzero((px.min(axis=1) < 0.5 * length) & (px.max(axis=1) > 0.5 * length))
    rest = np.setdiff1d(np.arange(mesh.n_elements), weak)
    mesh = mesh.with_sets(element_sets={"weak": weak, "rest": rest})
    model = fdem.Model(
        mesh,
        materials={
            "weak": fdem.MohrCoulombRankine(**SOFT, ft=0.8e6, Gf=70.0),
            "rest": fdem.MohrCoulombRankine(**SOFT, ft=1.0e6, Gf=70.0),
        },
    )
    model.fix("left", x=True, y=False).fix([int(np.argmin(np.hypot(*mesh.points.T)))], x=True, y=True)
    model.prescribe_velocity("right", vx=0.02, amplitude=fdem.Amplitude.ramp(1e-3))
    model.contact(fdem.Interface(friction=30, damping=0.5)).fracture(check_every=5)
    if stage is not None:
        model.excavate("weak", at=stage)
    return fdem.Simulation(model, stiffness_damping=1e-6, threads=1, renumber=renumber), model


def containing(points: np.ndarray, mesh: fdem.Mesh, elements: np.ndarray) -> np.ndarray:
    """Whether each point lies inside one of ``elements`` of ``mesh`` (in
    its reference configuration; on an edge counts as inside to 1e-9)."""
    tri = mesh.points[mesh.triangles[elements]]
    a, u, v = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    det = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    w = points[:, None, :] - a[None]
    l1 = (w[..., 0] * v[:, 1] - w[..., 1] * v[:, 0]) / det
    l2 = (u[:, 0] * w[..., 1] - u[:, 1] * w[..., 0]) / det
    return ((l1 > -1e-9) & (l2 > -1e-9) & (l1 + l2 < 1 + 1e-9)).any(axis=1)


def in_set(sim: fdem.Simulation, mesh: fdem.Mesh, name: str) -> np.ndarray:
    """Per element of the simulation: whether its reference centroid lies
    in the area of the mesh's set ``name`` (a piece lies inside the
    element it was cut from)."""
    c = sim.reference_positions()[sim.triangles()].mean(axis=1)
    return containing(c, mesh, mesh.elements(name))


def held(e: dict[str, float]) -> float:
    return e["kinetic"] + e["elastic"] + e["contact_elastic"] + e["cohesive_elastic"]


def test_an_excavation_stage_removes_the_pieces_of_a_set_that_cracked():
    """A set that cracks (its elements split) before its stage leaves no
    element of its area behind: no active element's reference centroid is
    inside it; the mass left is ρ Σ A of the other set (to 1e-12); the
    energy balance keeps its residual (the stage changes it by less than
    1e-6 of the largest term, which the steps around it change by more)."""
    sim, model = bar(stage=CRACKED + 1e-4)
    mesh = model.mesh
    sim.run(until=CRACKED, progress=False)
    pieces = in_set(sim, mesh, "weak") & sim.active()
    assert sim.insertions > 0 and pieces.sum() > len(mesh.elements("weak")) + 10
    # up to the stage, then one step at a time across it
    while sim.time < CRACKED + 1e-4:
        sim.step(1)
    assert sim.stages_done == 0
    e0 = sim.energies()
    sim.step(1)
    assert sim.stages_done == 1
    e1 = sim.energies()
    left = (in_set(sim, mesh, "weak") & sim.active()).sum()
    assert left == 0, f"{left} elements of the excavated set left"
    rest_mass = RHO * mesh.areas()[mesh.elements("rest")].sum()
    assert sim.masses().sum() == pytest.approx(rest_mass, rel=1e-12)
    assert e1["excavated"] > 0 and e0["excavated"] == 0
    assert abs(e1["residual"] - e0["residual"]) < 1e-6 * e1["largest_term"]


def test_deactivating_a_set_by_name_after_cracking_removes_its_pieces():
    """``Simulation.deactivate("weak")`` after the set has cracked removes
    its elements and every piece cut from them (and only those: the pieces
    of the other set stay), takes their mass off (the rest's ρ Σ A to
    1e-12) and books what leaves: ``excavated`` grows by the held energy
    (kinetic, elastic, contact and bond springs) that left, to 1e-9, and
    the residual does not move (1e-9 of the largest term)."""
    sim, model = bar()
    mesh = model.mesh
    sim.run(until=CRACKED, progress=False)
    inside = in_set(sim, mesh, "weak")
    assert sim.n_elements > mesh.n_elements and inside.sum() > len(mesh.elements("weak"))
    e0 = sim.energies()
    removed = sim.deactivate("weak")
    e1 = sim.energies()
    assert removed == inside.sum()
    active = sim.active()
    assert not (active & inside).any() and active[~inside].all()
    rest_mass = RHO * mesh.areas()[mesh.elements("rest")].sum()
    assert sim.masses().sum() == pytest.approx(rest_mass, rel=1e-12)
    assert e1["excavated"] - e0["excavated"] == pytest.approx(held(e0) - held(e1), rel=1e-9)
    assert abs(e1["residual"] - e0["residual"]) < 1e-9 * e1["largest_term"]
    assert sim.deactivate("weak") == 0
