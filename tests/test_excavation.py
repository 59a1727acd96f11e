"""Excavating rock that has cracked (issue 32, point 5; DESIGN §4.4 and
§4.6, docs/fracture.md "What a crack's pieces inherit"): the pieces crack
insertion makes of an element belong to every set the element is in, so
an excavation stage or ``deactivate`` of a set removes them with it, mass
and energy leave as for an uncracked set, and the lineage survives
renumbering and checkpoints. Tolerances beside each check."""

from __future__ import annotations

from pathlib import Path

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
    inside it; the mass left is ρ Σ A of the other set (to 1e-12); what
    left is booked as ``excavated`` (a quarter of the balance's largest
    term here) and the balance still closes to 1e-3 of its largest term
    over the next 0.5 ms (measured 3.1e-4; 2.8e-4 without the stage). The
    exact booking at the removal: the next test."""
    stage = CRACKED + 1e-4
    sim, model = bar(stage=stage)
    mesh = model.mesh
    sim.run(until=CRACKED, progress=False)
    pieces = in_set(sim, mesh, "weak") & sim.active()
    assert sim.insertions > 0 and pieces.sum() > len(mesh.elements("weak")) + 10
    while sim.stages_done == 0:
        sim.step(1)
    assert stage <= sim.time < stage + 2 * sim.time_step
    left = (in_set(sim, mesh, "weak") & sim.active()).sum()
    assert left == 0, f"{left} elements of the excavated set left"
    assert np.array_equal(~sim.active(), np.isin(sim.element_origins(), mesh.elements("weak")))
    rest_mass = RHO * mesh.areas()[mesh.elements("rest")].sum()
    assert sim.masses().sum() == pytest.approx(rest_mass, rel=1e-12)
    e = sim.energies()
    assert e["excavated"] > 0.1 * e["largest_term"]
    while sim.time < stage + 5e-4:
        sim.step(20)
        e = sim.energies()
        assert abs(e["residual"]) < 1e-3 * e["largest_term"], sim.time


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


def test_pieces_inherit_their_element_s_sets_and_material():
    """Every piece's parent was made before it and its origin is a model
    element; pieces have their origin's material; ``Simulation.elements``
    lists a set as it is now (exactly the elements whose reference
    centroid lies in the set's area); the model's element ids remove
    their pieces too, and ``descendants=False`` exactly the elements
    named."""
    sim, model = bar()
    mesh = model.mesh
    sim.run(until=CRACKED, progress=False)
    m0, m = mesh.n_elements, sim.n_elements
    parents, origins = sim.element_parents(), sim.element_origins()
    ids = np.arange(m)
    assert np.array_equal(parents[:m0], ids[:m0]) and np.all(parents[m0:] < ids[m0:])
    assert np.all(origins < m0) and np.array_equal(origins[parents], origins)
    materials = model.kernel_arrays()["element_material"]
    assert np.array_equal(sim._core.element_materials(), materials[origins])
    weak = sim.elements("weak")
    assert np.array_equal(weak, np.flatnonzero(in_set(sim, mesh, "weak")))
    assert len(weak) > len(mesh.elements("weak")) and np.array_equal(sim.elements(mesh.elements("weak")), weak)
    with pytest.raises(ValueError, match="not an element of the model"):
        sim.elements([m0])
    # one model element with pieces: by id with its pieces, or alone
    cut = int(origins[m0])
    family = np.flatnonzero(origins == cut)
    assert len(family) > 1
    assert sim.deactivate([cut], descendants=False) == 1
    assert np.array_equal(np.flatnonzero(~sim.active()), [cut])
    assert sim.deactivate([cut]) == len(family) - 1
    assert np.array_equal(np.flatnonzero(~sim.active()), family)
    # a piece's id names that piece and what is cut from it later
    piece = int(np.setdiff1d(weak, family).max())
    assert sim.deactivate([piece]) == 1 and not sim.active()[piece]


def test_the_lineage_survives_renumbering_and_checkpoints(tmp_path):
    """Parents and origins read the same after a renumbering and after a
    restart; a stage after either removes the set's pieces (mass to
    1e-12), and the restored run is bit for bit the run that went on."""
    stage = CRACKED + 1e-4
    sim, model = bar(stage=stage, renumber=0.01)
    sim.run(until=CRACKED, progress=False)
    assert sim.renumberings > 0
    parents, origins = sim.element_parents(), sim.element_origins()
    sim.renumber()
    assert np.array_equal(sim.element_parents(), parents) and np.array_equal(sim.element_origins(), origins)
    path = sim.save_checkpoint(tmp_path / "cracked.ckpt")
    back = fdem.Simulation.from_checkpoint(path, model, threads=2)
    assert np.array_equal(back.element_parents(), parents)
    rest_mass = RHO * model.mesh.areas()[model.mesh.elements("rest")].sum()
    for s in (sim, back):
        s.run(until=stage + 1e-4, progress=False)
        assert s.stages_done == 1 and not (in_set(s, model.mesh, "weak") & s.active()).any()
        assert s.masses().sum() == pytest.approx(rest_mass, rel=1e-12)
    assert np.array_equal(sim.positions(), back.positions()) and sim.energies() == back.energies()


def without_lineage(path, out, parents: np.ndarray, bonds: int, materials: int) -> None:
    """The checkpoint at ``path`` as format 6 wrote it, without the lineage,
    bond-offset and bond-law blocks at the end of its state (postcard: the
    count and each parent as varints; the count of the ``bonds`` and two
    f64 each, the local damping and two empty lists; the count of the
    bonds and each one's mixed-mode law (a tag and six f64), the count of
    the ``materials`` and one f64 each; the count of the materials and
    each one's softening curve, one byte for linear softening, and the
    count of the bonds and each one's kink, one byte for none; the
    renumbering interval, one byte for none; the contact offsets, two
    empty lists for a run that holds none), resealed, at ``out``."""
    import struct
    import zlib

    b = Path(path).read_bytes()
    assert b[:8] == b"FDEMCKPT" and struct.unpack_from("<I", b, 8)[0] == 12
    s_len, u_len = struct.unpack_from("<QQ", b, 16)
    varint = lambda n: max(1, -(-int(n).bit_length() // 7))  # noqa: E731
    block = varint(len(parents)) + sum(varint(p) for p in parents) + varint(bonds) + 16 * bonds + 8 + 2
    block += varint(bonds) + 49 * bonds + varint(materials) + 8 * materials
    block += varint(materials) + materials + varint(bonds) + bonds + 1 + 2
    state, user = b[40 : 40 + s_len - block], b[40 + s_len :]
    head = bytearray(b[:40])
    struct.pack_into("<I", head, 8, 6)
    struct.pack_into("<Q", head, 16, len(state))
    struct.pack_into("<I", head, 32, zlib.crc32(state + user))
    struct.pack_into("<I", head, 36, zlib.crc32(bytes(head[:36])))
    Path(out).write_bytes(bytes(head) + state + user)
    assert u_len == len(user)


def test_a_checkpoint_without_lineage_gets_it_back_from_the_model(tmp_path):
    """A format-6 checkpoint (no lineage) of a cracked, renumbered run
    restores with each piece placed in the model element that holds its
    reference centroid: the origins are the ones the run kept."""
    sim, model = bar(renumber=0.01)
    sim.run(until=CRACKED, progress=False)
    origins = sim.element_origins()
    assert sim.n_elements > model.mesh.n_elements and sim.renumberings > 0
    path = sim.save_checkpoint(tmp_path / "v7.ckpt")
    assert not sim.contacts()["offset"].any()
    without_lineage(path, tmp_path / "v6.ckpt", sim.element_parents(), len(sim.bonds()["nodes"]), len(model._materials))
    raw, _ = fdem._core.Simulation.read_checkpoint(str(tmp_path / "v6.ckpt"), 1)
    assert np.array_equal(raw.element_parents(), np.arange(sim.n_elements))
    back = fdem.Simulation.from_checkpoint(tmp_path / "v6.ckpt", model, threads=1)
    assert np.array_equal(back.element_origins(), origins)
    assert back.deactivate("weak") == len(sim.elements("weak"))
