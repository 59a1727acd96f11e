"""Geostatic start, staged excavation and the block-caving case (issue 6,
DESIGN §4.6 and §5). Tolerances beside each check."""

from __future__ import annotations

import csv
import dataclasses
import math

import fdem
import numpy as np
import pytest
from fdem.caving import BOTTOM, PAPER_PROBES, CavingCase, area_below, caving_model, run_caving, strip_means

ROCK = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)


def column(nx: int = 6, ny: int = 20, width: float = 30.0, height: float = 100.0) -> fdem.Model:
    mesh = fdem.Mesh.rectangle(width, height, nx, ny)
    model = fdem.Model(mesh, material=ROCK).set_gravity(0.0, -9.81)
    model.fix("left", x=True, y=False).fix("right", x=True, y=False).fix("bottom", x=False, y=True)
    model.pressure("top", 15.2e6)
    return model


def test_geostatic_stress_matches_the_formula():
    """σ_yy = −(p + γ (top − y)), σ_xx = K0 σ_yy (K0 = ν/(1−ν) by default or
    given), σ_zz = ν(σ_xx + σ_yy), exactly at the centroids."""
    model = column()
    model.set_geostatic_stress(top=100.0, pressure=15.2e6)
    y = model.mesh.centroids()[:, 1]
    s = model.kernel_arrays()["initial_stress"]
    syy = -(15.2e6 + 3100 * 9.81 * (100 - y))
    assert np.allclose(s[:, 1], syy, rtol=1e-14)
    assert np.allclose(s[:, 0], syy / 3, rtol=1e-14)
    assert np.allclose(s[:, 2], 0.25 * (s[:, 0] + s[:, 1]), rtol=1e-14)
    model.set_geostatic_stress(top=100.0, pressure=0.0, unit_weight=25e3, k0=0.7)
    s = model.kernel_arrays()["initial_stress"]
    assert np.allclose(s[:, 0], 0.7 * s[:, 1], rtol=1e-14)
    with pytest.raises(ValueError, match="k0"):
        model.set_geostatic_stress(top=100.0, k0=-1.0)


def test_equilibrium_stage_leaves_the_model_at_rest_at_the_lithostatic_stress():
    """Issue 6 (1): after the damped stage the largest speed is below
    1e-3 m/s and σ_yy is within 2% of −(p + ρ g depth); the clock and the
    energy account restart at zero."""
    model = column()
    model.set_geostatic_stress(top=100.0, pressure=15.2e6)
    sim = fdem.Simulation(model)
    result = sim.equilibrate(max_velocity=1e-3)
    assert result["max_velocity"] < 1e-3
    assert np.abs(sim.velocities()).max() < 1e-3
    y = sim.positions()[sim.triangles()].mean(axis=1)[:, 1]
    lith = -(15.2e6 + 3100 * 9.81 * (100 - y))
    assert np.max(np.abs(sim.stress()[:, 1] - lith) / np.abs(lith)) < 0.02
    assert sim.time == 0.0 and sim.steps == 0
    e = sim.energies()
    assert abs(e["residual"]) <= 1e-9 * e["elastic_initial"]
    assert e["external_work"] == pytest.approx(0.0, abs=1e-9 * e["elastic_initial"])


def test_excavation_takes_mass_forces_and_energy_off_the_nodes():
    """Issue 6 (2): removing elements takes their mass off their nodes
    (the remaining mass is Σ ρA of the rest to 1e-12), orphan nodes leave the
    model (zero mass, at rest, off the surface), the energy they take away
    is booked (the account closes to 1e-6 of the elastic energy)."""
    model = column(nx=6, ny=12, height=60.0)
    model.set_geostatic_stress(top=60.0, pressure=15.2e6)
    mesh = model.mesh
    c = mesh.centroids()
    hole = np.flatnonzero((np.abs(c[:, 0] - 15) < 6) & (np.abs(c[:, 1] - 30) < 6))
    sim = fdem.Simulation(model)
    sim.equilibrate(max_velocity=1e-3)
    e0 = sim.energies()
    removed = sim.deactivate(hole)
    assert removed == len(hole) and sim.deactivate(hole) == 0
    active = sim.active()
    assert not active[hole].any() and active.sum() == mesh.n_elements - len(hole)
    m = sim.masses()
    assert m.sum() == pytest.approx(ROCK.rho * mesh.areas()[active].sum(), rel=1e-12)
    orphans = np.setdiff1d(np.arange(mesh.n_nodes), np.unique(mesh.triangles[active]))
    assert len(orphans) > 0 and np.all(m[orphans] == 0.0)
    facets, _ = sim.surface_facets()
    assert not np.isin(orphans, facets).any()
    e = sim.energies()
    # at rest, what leaves is the removed elements' strain energy (the
    # kinetic part is below ½ M (1e-3 m/s)², 1e-5 of it here)
    assert e["excavated"] == pytest.approx(e0["elastic"] - e["elastic"], rel=1e-4)
    assert abs(e["residual"] - e0["residual"]) < 1e-6 * e0["elastic_initial"]
    # the hole's walls, unloaded, move in; orphans stay put with no mass
    x_orphans = sim.positions()[orphans].copy()
    sim.step(200)
    assert np.array_equal(sim.positions()[orphans], x_orphans)
    assert np.abs(sim.velocities()[np.setdiff1d(np.arange(mesh.n_nodes), orphans)]).max() > 1e-4
    with pytest.raises(ValueError, match="element 99999 does not exist"):
        sim.deactivate([99999])


def test_scheduled_stages_run_in_time_order_and_bad_stages_are_named():
    model = column(nx=6, ny=12, height=60.0)
    c = model.mesh.centroids()
    low = np.flatnonzero(c[:, 1] < 5)
    left, right = low[c[low, 0] < 15], low[c[low, 0] >= 15]
    model.excavate(right, at=2e-3).excavate(left, at=1e-3)
    sim = fdem.Simulation(model)
    sim.run(until=1.5e-3, progress=False)
    assert sim.stages_done == 1 and not sim.active()[left].any() and sim.active()[right].all()
    sim.run(until=2.5e-3, progress=False)
    assert sim.stages_done == 2 and not sim.active()[right].any()
    with pytest.raises(ValueError, match="elements"):
        model.excavate(np.array([10**6]), at=1.0)
    with pytest.raises(ValueError, match="at"):
        model.excavate(left, at=float("nan"))


def test_the_paper_scale_model_resolves_the_joint_spacing():
    """Issue 6 (3): the default case is the paper's 200 m × 100 m block with
    its two joint sets at their spacings (2 m vertical, 3 m horizontal) and
    at least 50 000 triangles, elements no larger than half the smallest
    spacing (measured: 78 216 triangles, 1.0 m elements)."""
    case = CavingCase()
    assert case.joint_scale == 1.0 and case.size <= 0.5 * 2.0
    model = caving_model(case)
    mesh = model.mesh
    assert mesh.n_elements >= 50_000
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    assert np.allclose(hi - lo, [200.0, 100.0])
    for name, axis, spacing in (("vertical", 0, 2.0), ("horizontal", 1, 3.0)):
        p = mesh.points[mesh.facet_sets[name]]
        lines = np.unique(np.round(p[:, 0, axis], 6))
        assert np.allclose(np.diff(lines), spacing)


def test_jointed_block_at_rest_stays_at_rest_when_plasticity_and_fracture_start():
    """The jointed caving model after its elastic equilibrium stage: its
    joints lie along the principal directions of the K0 state, so the rock
    must be in compression everywhere (σ1 < 0), and turning plasticity and
    crack insertion on must leave it at rest, uncracked, with its energy
    balance closed. History: at first cracks at joint tips set the block
    moving at 3.6 m/s and thousands followed (fixed by keeping the contact
    springs of cut joint faces, DESIGN §4.5); then 9 cracks remained, at
    joint crossings, whose corner nodes had lost contact (one contact per
    node). With a contact per face at corner nodes (2026-11-23, 2.5 m
    elements, joint spacings ×3): σ1 ≤ −2.7 MPa everywhere, no crack over
    0.04 s (before the first undercut stage), largest speed 9e-4 m/s,
    residual 2e-8 of the joint springs' energy. With the overburden as the
    cap's weight (the default since issue 37) the heavy cap's blocks bend
    between their joints and its top row reaches σ1 = +0.6 MPa; the cap is
    elastic and cannot crack, and the rock under it stays at σ1 ≤ −2.8 MPa.
    Checked: σ1 < 0 in the rock, no crack, largest speed below 0.01 m/s,
    residual within 1%."""
    from fdem.output import principal_stresses

    case = CavingCase(size=2.5, joint_scale=3.0, support=5.0)
    model = caving_model(case)
    sim = fdem.Simulation(model, stiffness_damping=2e-6)
    sim.equilibrate(max_velocity=1e-3, progress=False)
    rock = np.setdiff1d(np.arange(model.mesh.n_elements), model.mesh.elements("cap"))
    assert principal_stresses(sim.stress())[rock, 0].max() < 0.0
    held = sim.energies()["contact_elastic"]
    sim.run(until=0.04, progress=False)
    e = sim.energies()
    assert sim.stages_done == 0
    assert sim.insertions == 0
    assert np.abs(sim.velocities()).max() < 0.01
    assert abs(e["residual"]) < 0.01 * held


def test_quick_caving_runs_undercuts_in_order_and_caves(quick_caving):
    """Issue 6 (5): the quick case runs, undercuts stage by stage in the
    scheduled order, and caves: rock falls below the undercut level."""
    out, summary = quick_caving
    sim = summary["simulation"]
    case = CavingCase.quick()
    model = caving_model(case)
    assert summary["undercut_stages"] == 8 == sim.stages_done
    assert not sim.active()[model.mesh.elements("undercut_8")].any()
    # the stages' times are in order and each removes the next 10 m each way
    times = [t for t, _ in model.stages]
    assert times == sorted(times)
    c = model.mesh.centroids()
    for k in range(1, 9):
        xs = np.abs(c[model.mesh.elements(f"undercut_{k}"), 0])
        assert xs.max() < 10 * k and (k == 1 or xs.min() >= 10 * (k - 1) - case.size)
    # rock fallen into the undercut: rock (every element of it started
    # above the support layer) now below the top of that layer. The central
    # column falls as a mass (mean fall over |x| < 60 m: 1.4–1.6 m by
    # 0.8 s); on the refined mesh the same case numbered five ways
    # (generator order, Hilbert, reversed Hilbert, random, sorted by x)
    # gave 481–507 m² (2 340–2 489 cracks), on the uniform mesh (the
    # default since 2026-11-24) 492 m² holding 0.7 of the intact step and
    # 456 m² holding 0.8, 474 m² holding 0.7 with the renumbering every
    # 1 000 steps, 442 m² with the crack directions kept as codes
    # (2026-11-24 midday: other round-off). The bound is half the smallest. How much has
    # fallen below the floor (the base the support stood on) is chaotic:
    # 3–13 m².
    assert summary["fallen_area_m2"] > 240.0
    y = sim.positions()[sim.triangles()].mean(axis=1)[:, 1]
    y_ref = sim.reference_positions()[sim.triangles()].mean(axis=1)[:, 1]
    level = BOTTOM + case.support
    fallen = sim.active() & (y_ref >= level) & (y < level)
    assert sim.areas()[fallen].sum() == pytest.approx(summary["fallen_area_m2"], rel=1e-12)
    assert sim.areas()[sim.active() & (y < BOTTOM)].sum() == pytest.approx(summary["caved_area_m2"], rel=1e-12)
    assert summary["cracks_inserted"] > 0 and summary["fragments"] > 1
    # issue 6 (1): at rest, σ_yy over 5 m strips across the width within 2%
    # of lithostatic (measured 0.89% with 4 m elements, 0.10% at the
    # paper's scale; the column check is test_equilibrium_column)
    assert summary["equilibrium_speed"] < 1e-3
    assert summary["lithostatic_error"] < 0.02


def _loose_nodes(summary):
    """The contact-free nodes lying deeper than 1% of the mean element size
    `h` (√(2A) averaged) inside another piece, and the deepest depth (m)."""
    sim = summary["simulation"]
    h = float(np.sqrt(2.0 * sim.areas()[sim.active()]).mean())
    o = sim.overlaps(min_depth=0.01 * h)
    free = ~o["in_contact"]
    return np.unique(o["node"][free]), (float(o["depth"][free].max()) if free.any() else 0.0), h


def _stress_released_by_the_undercut(case, until):
    """The largest compressive principal stress (Pa, as a magnitude) held,
    one step before each excavation stage up to `until` (s), by the active
    elements that share a node with the elements the stage removes: the
    stress the sudden undercut releases (stops do not change a run's bits,
    so this is the demo's own state)."""
    model = caving_model(case)
    sim, _ = fdem.caving._started(model, case, threads=None, progress=False, wall0=0.0)
    worst = 0.0
    for at, ids in model.stages:
        if at > until:
            break
        sim.run(until=at - 1.5 * sim.time_step, progress=False)
        tri, active = sim.triangles(), sim.active()
        removed = np.zeros(len(tri), bool)
        removed[sim.elements(ids)] = True
        removed &= active
        touched = np.zeros(sim.n_nodes, bool)
        touched[tri[removed].ravel()] = True
        beside = active & ~removed & touched[tri].any(axis=1)
        s = sim.stress()[beside]
        sigma_3 = 0.5 * (s[:, 0] + s[:, 1]) - np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 3])
        worst = max(worst, float(-sigma_3.min(initial=0.0)))
    return worst


def test_quick_caving_leaves_few_pieces_inside_another(quick_caving):
    """Items 6, 7, 9 and 10 of docs/contact.md, "Which facet a node
    touches": contact-free nodes deeper than 1% of the mean element size
    `h` (3.1 m) inside another piece at the end of the demo (0.8 s). At
    most 2, none deeper than 3% of `h` (9.3 cm). Measured (2-core Zen 4
    VM, 2026-11-29): none; 0–1 a run over eleven numberings of the case
    (`benchmarks/caving_numberings.py`), the deepest 10.8 cm. Before item
    11 (a node where its piece touches itself), 1 (3.5 cm) and 0–2 a run.
    Before a facet's line extended past a sharp corner bore only just past
    it (item 6) and item 7 looked past interior sides and took a node up
    behind the twin of its face, the demo left 2 (7.6 cm) and the
    numberings 0–4 a run, to 12.1 cm; before items 9 and 10, 5 (7.8 cm);
    before item 7, 80 (0.41 m)."""
    loose, deepest, h = _loose_nodes(quick_caving[1])
    assert len(loose) <= 2, f"{len(loose)} nodes without contact deeper than {0.01 * h:.3f} m (deepest {deepest:.3f} m)"
    assert deepest < 0.03 * h, deepest


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="over eleven numberings of the quick case 2 contact-free nodes lie deeper than 1% of h inside "
    "another piece at 0.8 s, the deepest 10.8 cm (docs/contact.md, 'What is left')",
)
def test_quick_caving_leaves_no_piece_inside_another_whatever_the_numbering(tmp_path):
    """No node without a contact may lie inside another piece deeper than
    1% of the mean element size `h`, in the quick case with renumbering
    off and at 1, 2, …, 10% (the chaos of a falling rock mass turns each
    numbering into a different run; one run can pass by luck). Contact
    penetrations under the overburden stay far below 1% of `h`. Measured
    (2-core Zen 4 VM, 2026-11-29): 0–1 a run, 2 in all, the deepest 10.8
    cm (the demo's own numbering, 5%: none). An expected failure until a
    node inside a piece is taken up wherever it entered."""
    found = []
    for k, renumber in enumerate([None] + [i / 100 for i in range(1, 11)]):
        case = dataclasses.replace(CavingCase.quick(), renumber=renumber)
        summary = run_caving(tmp_path / str(k), case, progress=False)
        loose, deepest, _ = _loose_nodes(summary)
        found += [(renumber, len(loose), deepest)] if len(loose) else []
    assert not found, f"(renumbering, loose nodes, deepest m): {found}"


def test_quick_caving_keeps_mass_and_closes_its_energy_balance(quick_caving):
    """Issue 6 (5): total nodal mass equals Σ ρ A of the elements left plus
    the mass that mass scaling added, Σ (s_e − 1) ρ A (to 1e-12 relative,
    cracks included: every insertion keeps mass), and the energy balance
    closes within 2% of the energy supplied (work of gravity and the top
    pressure; measured 0.19% on the uniform mesh, 0.07% on the refined
    one). Crack insertions re-form contacts; what that releases or creates
    is booked as `resurfacing` and must stay small too. Mass scaling holds
    0.7 of the intact step (the step may fall 10% below that between
    topology changes, as elements deform) and adds under 2% of the mass
    (measured 0.53%; 2.6% when it held 0.8, docs/mass_scaling.md). The
    cap carries the overburden as its weight: its own, raised density."""
    _, summary = quick_caving
    sim = summary["simulation"]
    active = sim.active()
    model = caving_model(CavingCase.quick())
    cap = model.mesh.elements("cap")
    rho = np.full(sim.n_elements, 3100.0)
    rho[sim.elements(cap)] = model._materials[model._element_material[cap[0]]].rho
    rho = rho[active]
    # reference areas: the elements' areas in their reference shape
    x0 = sim.reference_positions()[sim.triangles()[active]]
    d1, d2 = x0[:, 1] - x0[:, 0], x0[:, 2] - x0[:, 0]
    a0 = 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    scale = sim.mass_scale()[active]
    added = (rho * (scale - 1) * a0).sum()
    assert sim.added_mass == pytest.approx(added, rel=1e-12)
    assert sim.masses().sum() == pytest.approx((rho * a0).sum() + added, rel=1e-12)
    assert 0 < added < 0.02 * (rho * a0).sum()
    assert summary["time_step_s"] >= 0.9 * CavingCase.quick().mass_scaling * summary["intact_time_step_s"]
    audit = sim.insertion_audit()
    assert audit["mass"] <= 1e-12 and audit["momentum"] <= 1e-12
    assert abs(summary["energy_residual_J"]) < 0.02 * summary["energy_supplied_J"]
    assert abs(sim.energies()["resurfacing"]) < 0.02 * summary["energy_supplied_J"]


def test_quick_caving_writes_its_results(quick_caving):
    """Issue 6 (4): VTU series and index, Fig. 4 and Fig. 5 pictures, probe
    table with the paper's points, fragments, energy, summary."""
    out, summary = quick_caving
    assert (out / "caving.pvd").exists() and len(list(out.glob("caving_*.vtu"))) >= 5
    for name in summary["figures"] + ["fragments.png", "energy.png", "demo.png"]:
        assert (out / name).stat().st_size > 10_000, name
    assert any(f.startswith("fig4_") for f in summary["figures"])
    assert any(f.startswith("fig5_") for f in summary["figures"])
    assert len(set(summary["figures"])) == len(summary["figures"]), summary["figures"]
    with open(out / "probes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {r["node"] for r in rows} == {str(float(n)) for n, _, _ in PAPER_PROBES}
    first = [r for r in rows if float(r["time_s"]) == 0.0]
    # at the start every probe is in rock, in compression
    assert all(float(r["syy_MPa"]) < 0 for r in first)
    with open(out / "fragments.csv", newline="") as f:
        frags = list(csv.DictReader(f))
    assert len(frags) == summary["fragments"]
    # each fragment's centre-of-mass motion, as Simulation.fragments() gives it
    assert {"vx_m_s", "vy_m_s", "ux_m", "uy_m"} <= set(frags[0])
    assert all(math.isfinite(float(r["vy_m_s"])) for r in frags)
    # docs/caving.md, "Fragments faster than free fall": no piece holds more
    # kinetic energy beyond its fall than the undercut's release can give.
    # Removing a stress σ from a face at once sends it off at σ / (ρ c_p),
    # and a piece it strikes (or a face where the release wave reflects)
    # leaves at up to twice that: ½ (2 σ / (ρ c_p))², with σ the largest
    # compressive stress the rock beside any stage holds just before it
    # (106 MPa in the demo since contact item 11: 101 J/kg; 136 MPa at the
    # undercut's corner before the 0.41 s stage, 167 J/kg, before it; the
    # lithostatic stress there is 18 MPa). Measured 22.4 J/kg, 22.4–44.1
    # over eleven numberings (2-core Zen 4 VM, 2026-11-29).
    rock = fdem.caving.ROCK
    m_modulus = rock.E * (1 - rock.nu) / ((1 + rock.nu) * (1 - 2 * rock.nu))
    sigma = _stress_released_by_the_undercut(CavingCase.quick(), until=0.8)
    # more than the overburden at the model's base: the support carried it
    assert sigma > fdem.caving.TOP_PRESSURE + fdem.caving.UNIT_WEIGHT * fdem.caving.HEIGHT
    bound = 0.5 * (2 * sigma / (rock.rho * math.sqrt(m_modulus / rock.rho))) ** 2
    assert 0.0 < summary["fragment_energy_beyond_fall_J_per_kg"] < bound
    assert summary["fragment_speed_max_m_s"] > 0.0
    text = (out / "summary.txt").read_text()
    assert "energy_residual_J" in text
    # where the loop's time went: every phase of the step is clocked inside
    # the loop (each alone within its wall time), and the element pass and
    # the contact evaluation, the bulk of a step, were both clocked
    phases = {k: v for k, v in summary.items() if k.startswith("phase_")}
    assert set(phases) == {f"phase_{k}_s" for k in summary["simulation"].phase_times()}
    assert all(0.0 <= v <= summary["wall_s"] for v in phases.values()), phases
    assert phases["phase_elements_s"] > 0.0 and phases["phase_surface_s"] > 0.0
    assert "phase_elements_s" in text


def test_figure_times_are_each_drawn_once():
    """A run to 1.3 s at the paper's schedule: the third stage (0.05 + 3 ×
    0.2 s) and half the run (0.65 s) are one picture, not two (the floats
    differ in the last bit)."""
    times = CavingCase(until=1.3).figure_times()
    assert times == [0.0, 0.65, 1.3]
    assert CavingCase().figure_times() == [0.0, 0.65, 1.75, 3.5]


def test_strip_means_integrate_over_the_strips_exactly():
    """The lithostatic check's estimator: the part of a triangle below a
    line (closed form against a hand-computed case), and strips that
    partition a mesh's area exactly, so that a field linear in y is read at
    the strips' middles to within the per-element constant's error."""
    tri = np.array([[[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]])
    # below y = 1: the whole (2 m²) less the similar top triangle (0.5 m²)
    assert area_below(tri, 1.0)[0] == pytest.approx(1.5, rel=1e-15)
    assert area_below(tri, 0.5)[0] == pytest.approx(2.0 - 0.5 * 1.5**2, rel=1e-15)
    assert area_below(tri, -1.0)[0] == 0.0 and area_below(tri, 3.0)[0] == 2.0
    mesh = fdem.jointed_rectangle(20.0, 10.0, 0.7)
    corners = mesh.points[mesh.triangles]
    edges = np.array([0.3, 2.5, 2.6, 7.0, 9.9])
    y = corners[:, :, 1].mean(axis=1)
    means, area = strip_means(corners, 3.0 * y, edges)
    np.testing.assert_allclose(area, 20.0 * np.diff(edges), rtol=1e-12)
    # a constant per element is the linear field at its centroid: off by
    # at most the field's change over an element (3 × 0.7 m)
    np.testing.assert_allclose(means, 1.5 * (edges[1:] + edges[:-1]), atol=3.0 * 0.7)
    # and a constant field is read exactly
    np.testing.assert_allclose(strip_means(corners, np.full(len(y), -2.0), edges)[0], -2.0, rtol=1e-12)


def test_table2_points_sit_where_the_frame_puts_them(quick_caving):
    """Issue 37 (3): the paper's x read from the block's left side (the
    default) puts its points at model x = x − 100 m, the centred reading at
    x; y is the model's own. The run's probe table holds those positions,
    the mirror points, and the paper's points at x = 16 m in the left
    abutment, 4 m outside the undercut's edge."""
    from fdem.caving_stress import PAPER_TABLE2, probe_points

    xy = np.array([[x, y] for _, x, y, *_ in PAPER_TABLE2])
    assert np.array_equal(probe_points("left", 200.0), xy - [100.0, 0.0])
    assert np.array_equal(probe_points("centred", 200.0), xy)
    assert CavingCase().probe_frame == "left"
    with pytest.raises(ValueError, match="probe_frame"):
        CavingCase(probe_frame="middle")
    abutment = probe_points("left", 200.0)[[5, 6]]
    assert np.allclose(abutment[:, 0], -0.5 * CavingCase().undercut - 4.0)
    out, _ = quick_caving
    with open(out / "probes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for name, x, y, *_ in PAPER_TABLE2:
        mine = [r for r in rows if r["node"] == str(float(name))]
        assert {(float(r["x_m"]), float(r["y_m"])) for r in mine} == {(x - 100.0, y)}
        assert {(float(r["x_paper_m"]), float(r["y_paper_m"])) for r in mine} == {(x, y)}
    table = (out / "table2.csv").read_text().splitlines()
    assert table[0].startswith("# time_s") and "left" in table[0] and len(table) == 2 + 9
    assert (out / "table2.png").stat().st_size > 10_000 and (out / "abutment.png").stat().st_size > 10_000


def test_probes_and_profiles_read_a_known_stress_field():
    """The readers on a constructed state: the geostatic start of the quick
    case, σyy = −(p + γ (top − y)) element by element. A probe returns the
    stress of the element holding the point (NaN outside the rock); the
    line profile, an area mean over boxes of elements, is within γ h of the
    line's value (h the box's half height, the most an element's centroid
    can lie off the line); the abutment factor is then 1 within the same."""
    from fdem.caving import TOP, TOP_PRESSURE, UNIT_WEIGHT
    from fdem.caving_stress import ABUTMENT_LINE, abutment_peaks, probe_stress, stress_profile

    case = CavingCase.quick()
    sim = fdem.Simulation(caving_model(case), threads=1)
    cen = sim.positions()[sim.triangles()].mean(axis=1)
    pts = cen[[10, 500, 2000]]
    got = probe_stress(sim, np.vstack([pts, [[0.0, TOP + 10.0]]]))
    assert np.array_equal(got[:3], sim.stress()[[10, 500, 2000]])
    assert np.isnan(got[3]).all()
    edges = np.arange(-100.0, 100.0 + 1e-9, case.size)
    prof = stress_profile(sim, ABUTMENT_LINE, edges, case.size)
    lith = -(TOP_PRESSURE + UNIT_WEIGHT * (TOP - ABUTMENT_LINE))
    assert np.isfinite(prof).all()
    assert np.max(np.abs(prof[:, 1] - lith)) <= UNIT_WEIGHT * case.size
    peaks = abutment_peaks(sim, width=200.0, undercut=case.undercut, size=case.size, lithostatic=lith)
    assert peaks["left_x"] < -80.0 < 80.0 < peaks["right_x"]
    for side in ("left", "right"):
        assert abs(peaks[f"{side}_factor"] - 1.0) <= UNIT_WEIGHT * case.size / abs(lith)


def test_abutments_carry_the_undercut_load(quick_caving):
    """Issue 37 (3): once the undercut is complete the rock beside each
    edge carries what the undercut no longer does: the peak σyy along the
    probes' depth beside each edge is above 1.5 times the lithostatic value
    there (the paper's points at x = 16 m show 3.0 and 3.7). Before the
    first stage it is the lithostatic value (within 10%: the peak of boxes
    of 4 m elements)."""
    out, summary = quick_caving
    with open(out / "abutment.csv", newline="") as f:
        next(f)
        rows = list(csv.DictReader(f))
    start = rows[0]
    assert abs(float(start["left_factor"]) - 1) < 0.1 and abs(float(start["right_factor"]) - 1) < 0.1
    stages = max(int(r["stages_done"]) for r in rows)
    assert stages == round(CavingCase.quick().undercut / 20.0)
    done = next(r for r in rows if int(r["stages_done"]) == stages)
    assert float(done["left_factor"]) > 1.5 and float(done["right_factor"]) > 1.5
    assert summary["abutment_factor_undercut_done_left"] == float(done["left_factor"])
    assert summary["abutment_factor_undercut_done_right"] == float(done["right_factor"])


def test_overburden_as_the_caps_weight_loads_the_block_as_the_pressure_does():
    """Issue 37 (2), the piston lever: ``overburden="mass"`` replaces the
    15.2 MPa face pressure by the weight of the top cap, whose density is
    raised so that its weight is p W exactly (the cap's elements make whole
    rows: 4 m of the nominal 5 m on the quick mesh), with no pressure left
    on the face and the same geostatic stress below the cap."""
    from dataclasses import replace

    from fdem.caving import TOP_PRESSURE, UNIT_WEIGHT, WIDTH

    m0 = caving_model(replace(CavingCase.quick(), overburden="pressure"))
    m1 = caving_model(CavingCase.quick())
    assert CavingCase().overburden == "mass"
    cap = m1.mesh.elements("cap")
    area = m1.mesh.areas()[cap].sum()
    assert 0.75 * 5.0 * WIDTH < area <= 5.0 * WIDTH
    g = UNIT_WEIGHT / 3100.0
    rho_cap = m1._materials[m1._element_material[cap[0]]].rho
    assert (rho_cap - 3100.0) * g * area == pytest.approx(TOP_PRESSURE * WIDTH, rel=1e-12)
    assert not m1._pressures and m0._pressures
    below = np.setdiff1d(np.arange(m1.mesh.n_elements), cap)
    s0, s1 = m0.kernel_arrays()["initial_stress"], m1.kernel_arrays()["initial_stress"]
    assert np.array_equal(s0[below], s1[below])
    with pytest.raises(ValueError, match="overburden"):
        CavingCase(overburden="rock")
    with pytest.raises(ValueError, match="cap"):
        CavingCase(overburden="mass", cap=0.0)


def test_a_case_round_trips_through_json_and_names_bad_fields(tmp_path):
    """Issue 35 (2): every field, custom joint sets included, survives
    save and load; an unknown field, a value of the wrong type, a bad joint
    set or schedule is a ValueError naming the field and the file."""
    from dataclasses import replace

    case = replace(
        CavingCase.quick(),
        joints=(fdem.JointSet(60.0, 20.0, 5.0, 8.0, jitter=0.5, seed=3, name="inclined"),),
        schedule="one-sided",
        k0=1.0,
        mass_scaling=None,
        rock=fdem.MohrCoulombRankine(E=30e9, nu=0.2, rho=2700.0, c=5e6, phi=40.0, psi=5.0, ft=2e6, Gf=50.0),
        joint_law=fdem.Interface(friction=25.0, cohesion=1e4, damping=0.5),
        top_pressure=5e6,
        floor=20.0,
    )
    case.save(tmp_path / "case.json")
    assert CavingCase.load(tmp_path / "case.json") == case
    for text, word in (
        ('{"size": "big"}', "size must be a finite number"),
        ('{"sizes": 1}', "unknown field 'sizes'"),
        ('{"joints": [{"angle": 0, "persistence": -1, "bridge": 1, "spacing": 1}]}', r"joints\[0\]"),
        ('{"schedule": "left"}', "schedule"),
        ('{"check_every": 2.5}', "check_every"),
        ('{"rock": {"E": -1}}', "rock"),
        ('{"top_pressure": -1}', "top_pressure"),
        ('{"floor": -3}', "floor"),
        ("[1, 2]", "JSON object"),
    ):
        (tmp_path / "bad.json").write_text(text)
        with pytest.raises(ValueError, match=word) as err:
            CavingCase.load(tmp_path / "bad.json")
        assert "bad.json" in str(err.value)


def test_custom_joint_sets_and_a_one_sided_undercut_build_the_model():
    """Issue 35 (2): joint sets of the case are the mesh's (an inclined set
    meshes, its faces at 60° within 1°); the one-sided schedule removes
    the support from the undercut's left edge rightwards, 2 step per
    stage, the same total as the symmetric one."""
    from dataclasses import replace

    case = replace(
        CavingCase.quick(),
        joints=(fdem.JointSet(60.0, 40.0, 10.0, 12.0, name="inclined"),),
        schedule="one-sided",
    )
    model = caving_model(case)
    faces = model.mesh.points[model.mesh.facet_sets["inclined"]]
    d = faces[:, 1] - faces[:, 0]
    angles = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 180.0
    assert len(faces) > 0 and np.all(np.abs(angles - 60.0) < 1.0)
    c = model.mesh.centroids()
    stages = [model.mesh.elements(f"undercut_{k}") for k in range(1, 9)]
    for k, ids in enumerate(stages, start=1):
        x = c[ids, 0]
        assert x.min() > -80.0 - 4.0 and x.max() < -80.0 + 20.0 * k + 4.0
    symmetric = caving_model(CavingCase.quick())
    total = sum(len(model.mesh.elements(f"undercut_{k}")) for k in range(1, 9))
    total_sym = sum(len(symmetric.mesh.elements(f"undercut_{k}")) for k in range(1, 9))
    assert abs(total - total_sym) <= 0.05 * total_sym


def test_run_caving_takes_a_model_the_user_changed(tmp_path):
    """Issue 35 (2): a user's own model (here the quick case with stronger
    joints and an undercut of the left half only, as extra stages built by
    hand) goes through run_caving with its probes, metrics, figures and
    summary; its own stages run."""
    from dataclasses import replace

    case = replace(CavingCase.quick(), until=0.2, output_every=0.1)
    mesh = caving_model(case).mesh
    c = mesh.centroids()
    support = mesh.elements("support")
    left = support[c[support, 0] < 0.0]
    model = fdem.Model(
        mesh,
        materials={
            "rock": fdem.MohrCoulombRankine(E=60e9, nu=0.25, rho=3100.0, c=8e6, phi=55.0, psi=9.0, ft=1e6, Gf=70.0),
            "support": fdem.Elastic(E=60e9, nu=0.25, rho=3100.0),
            "cap": fdem.Elastic(E=60e9, nu=0.25, rho=3100.0),
        },
    ).set_gravity(0.0, -9.81)
    model.fix("left", x=True, y=False).fix("right", x=True, y=False).fix("bottom")
    model.pressure("top", 15.2e6).set_geostatic_stress(top=-434.0, pressure=15.2e6)
    model.contact(fdem.Interface(damping=0.5), interfaces={"joints": fdem.Interface(friction=40.0, damping=0.5)})
    model.fracture(insert_at=1.0, min_size=0.6, check_every=6)
    model.excavate(left, at=0.05)
    summary = run_caving(tmp_path, case, model=model, threads=2, progress=False)
    assert summary["undercut_stages"] == 1
    for name in ("probes.csv", "table2.csv", "metrics.csv", "abutment.csv", "summary.txt"):
        assert (tmp_path / name).exists(), name
    with pytest.raises(ValueError, match="fdem.Model"):
        run_caving(tmp_path / "x", case, model="not a model", progress=False)


def test_the_case_sets_the_rock_joints_and_top_load_of_the_model():
    """Issue 35 (2): a case's rock, joint law and top pressure are the
    model's: the geostatic σyy under the cap is −(p + γ depth) with the
    case's p and the rock's unit weight (γ = 30.41 kN/m³ × ρ/3100), to
    1e-12."""
    from dataclasses import replace

    from fdem.caving import TOP

    rock = fdem.MohrCoulombRankine(E=30e9, nu=0.2, rho=2700.0, c=5e6, phi=40.0, psi=5.0, ft=2e6, Gf=50.0)
    case = replace(CavingCase.quick(), rock=rock, top_pressure=5e6, overburden="pressure")
    model = caving_model(case)
    rock_ids = model.mesh.elements("rock")
    assert all(model._materials[model._element_material[e]] is rock for e in rock_ids[:10])
    y = model.mesh.centroids()[rock_ids, 1]
    gamma = 30.41e3 * 2700.0 / 3100.0
    syy = model.kernel_arrays()["initial_stress"][rock_ids, 1]
    assert np.allclose(syy, -(5e6 + gamma * (TOP - y)), rtol=1e-12)


def test_an_undercut_schedule_of_any_regions_and_times():
    """Issue 35 (2): stages given as (time, x_from, x_to) remove the
    support standing in each strip at its time, in the order given; a
    stage with nothing left to remove, or a bad stage, is named."""
    from dataclasses import replace

    regions = ((0.05, 40.0, 80.0), (0.2, -80.0, -40.0), (0.3, -40.0, 40.0))
    case = replace(CavingCase.quick(), regions=regions)
    model = caving_model(case)
    c = model.mesh.centroids()
    for k, (_, x0, x1) in enumerate(regions, start=1):
        x = c[model.mesh.elements(f"undercut_{k}"), 0]
        assert len(x) and x.min() >= x0 and x.max() < x1
    assert [t for t, _ in model.stages] == [0.05, 0.2, 0.3]
    assert CavingCase.from_json(case.to_json()) == case
    with pytest.raises(ValueError, match="stage 2"):
        caving_model(replace(case, regions=((0.05, -80.0, 80.0), (0.1, 0.0, 10.0))))
    with pytest.raises(ValueError, match=r"regions\[0\]"):
        replace(case, regions=((0.05, 10.0, 0.0),))


def test_an_undercut_schedule_of_boxes_and_polygons(tmp_path):
    """Issue 35 (2): an undercut schedule as any sequence of stages, each a
    time and a region in model coordinates (a box or a polygon): a stage
    removes the elements still standing whose centroids lie in its region
    (a half-open box [xmin, xmax) × [ymin, ymax), a polygon by the
    even-odd rule, matplotlib's Path the reference). Boxes over the
    support layer with the symmetric schedule's widths and times build the
    same model and run to the same bits through run_caving, which keeps
    its probes, metrics, figures and checkpoint; a bad value names its
    field; the case round-trips through its JSON file."""
    import json
    from dataclasses import replace

    from fdem.caving import UndercutStage
    from matplotlib.path import Path as MplPath

    base = replace(CavingCase.quick(), undercut=40.0, until=0.12, output_every=0.06)
    top = BOTTOM + base.support
    boxes = tuple(
        UndercutStage(base.start + (k - 1) * base.interval, box=(-k * base.step, BOTTOM, k * base.step, top))
        for k in (1, 2)
    )
    symmetric, regional = caving_model(base), caving_model(replace(base, regions=boxes))
    for k in (1, 2):
        assert np.array_equal(symmetric.mesh.elements(f"undercut_{k}"), regional.mesh.elements(f"undercut_{k}"))
    assert [t for t, _ in symmetric.stages] == [t for t, _ in regional.stages] == [0.05, 0.11]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(symmetric.stages, regional.stages, strict=True))
    a = run_caving(tmp_path / "symmetric", base, threads=1, progress=False)
    b = run_caving(tmp_path / "regions", replace(base, regions=boxes), threads=1, progress=False)
    assert b["undercut_stages"] == 2
    assert np.array_equal(a["simulation"].positions(), b["simulation"].positions())
    for key in ("cracks_inserted", "fallen_area_m2", "metric_cave_back_m", "metric_yielded_area_m2"):
        assert a[key] == b[key], key
    for name in ("probes.csv", "table2.csv", "metrics.csv", "stages.csv", "caving.ckpt", "summary.txt"):
        assert (tmp_path / "regions" / name).exists(), name
    assert b["figures"]
    with open(tmp_path / "regions" / "stages.csv", newline="") as f:
        assert [float(r["undercut_width_m"]) for r in csv.DictReader(f)] == [20.0, 40.0]
    # a checkpoint of a run whose case kept its stages as (time, x_from,
    # x_to) resumes under the same stages as boxes
    ckpt = tmp_path / "regions" / "caving.ckpt"
    sim = fdem.Simulation.from_checkpoint(ckpt, regional)
    sim.user_data["caving"]["case"]["regions"] = [[0.05, -10.0, 10.0], [0.11, -20.0, 20.0]]
    sim.save_checkpoint(ckpt)
    more = run_caving(tmp_path / "regions", replace(base, regions=boxes, until=0.15), progress=False, resume=True)
    assert more["simulation"].time >= 0.15

    # a polygon: a wedge reaching up into the rock, and a box to the right
    wedge = ((-30.0, BOTTOM), (10.0, BOTTOM), (-10.0, BOTTOM + 25.0))
    stages = (UndercutStage(0.05, polygon=wedge), UndercutStage(0.08, box=(20.0, BOTTOM, 60.0, top)))
    case = replace(base, regions=stages)
    mesh = caving_model(case).mesh
    c = mesh.centroids()
    inside = MplPath(np.array(wedge)).contains_points(c)
    assert np.array_equal(mesh.elements("undercut_1"), np.flatnonzero(inside))
    assert np.any(c[inside, 1] > top)  # rock too, not only the support
    second = np.flatnonzero((c[:, 0] >= 20.0) & (c[:, 0] < 60.0) & (c[:, 1] < top) & ~inside)
    assert np.array_equal(mesh.elements("undercut_2"), second)
    # the width stages.csv and the figures show: the regions' x-extent
    assert [case.undercut_width(k) for k in (0, 1, 2)] == [0.0, 40.0, 90.0]
    assert [base.undercut_width(k) for k in (1, 2)] == [20.0, 40.0]

    # the file round trip, with the (time, x_from, x_to) shorthand: a box
    # over the support layer
    path = tmp_path / "case.json"
    replace(case, regions=(*stages, (0.1, -60.0, -40.0))).save(path)
    loaded = CavingCase.load(path)
    assert loaded.regions[2] == UndercutStage(0.1, box=(-60.0, BOTTOM, -40.0, top))
    assert loaded == replace(case, regions=(*stages, UndercutStage(0.1, box=(-60.0, BOTTOM, -40.0, top))))

    # bad values name their field
    with pytest.raises(ValueError, match="time"):
        UndercutStage(float("nan"), box=(0.0, 0.0, 1.0, 1.0))
    for stage, field in (
        ({"time": 0.1, "box": [10.0, BOTTOM, 0.0, top]}, r"regions\[1\]\.box"),
        ({"time": 0.1, "polygon": [[0.0, BOTTOM], [1.0, BOTTOM]]}, r"regions\[1\]\.polygon"),
        ({"time": -0.1, "box": [0.0, BOTTOM, 10.0, top]}, r"regions\[1\]\.time"),
        ({"time": 0.1}, r"regions\[1\]"),
        ({"time": 0.1, "box": [0.0, BOTTOM, 10.0, top], "polygon": wedge}, r"regions\[1\]"),
        ({"time": 0.1, "radius": 3.0}, r"regions\[1\].*radius"),
    ):
        data = json.loads(case.to_json())
        data["regions"][1] = stage
        with pytest.raises(ValueError, match=f"bad.json: .*{field}"):
            CavingCase.from_json(json.dumps(data), source="bad.json")
    with pytest.raises(ValueError, match=r"UndercutStage\.box"):
        UndercutStage(0.1, box=(0.0, BOTTOM, 0.0, top))
    with pytest.raises(ValueError, match=r"CavingCase\.regions\[1\]"):
        replace(base, regions=(boxes[0], "everything"))
    with pytest.raises(ValueError, match=r"regions\[1\].*removes no element"):
        caving_model(replace(base, regions=(boxes[0], boxes[0])))


def test_a_floor_keeps_the_block_and_holds_the_caved_rock(tmp_path):
    """``CavingCase.floor`` (docs/caving.md, "What differs, and why"): the
    block on a rigid trough keeps its elements, contact stiffness and step
    (the trough is extra bodies, all fixed, unstressed); by 1.3 s the quick
    case's column (5 m of support removed under it, free fall 5 m in about
    1 s) rests on the floor at the base: no rock below it, where without
    the floor 340 m² had gone below by 1.25 s. The trough is no fragment
    of the summary. A negative or infinite depth is refused by name."""
    from dataclasses import replace

    for bad in (-1.0, float("inf")):
        with pytest.raises(ValueError, match="floor"):
            CavingCase(floor=bad)
    case = replace(CavingCase.quick(), floor=0.0)
    block, model = caving_model(CavingCase.quick()), caving_model(case)
    n = block.mesh.n_elements
    assert np.array_equal(model.mesh.triangles[:n], block.mesh.triangles)
    trough = model.mesh.elements("trough")
    assert np.array_equal(trough, np.arange(n, model.mesh.n_elements))
    assert model.mesh.points[model.mesh.nodes("trough"), 1].max() == pytest.approx(BOTTOM)
    a, b = block.kernel_arrays(), model.kernel_arrays()
    assert np.array_equal(a["contact_laws"], b["contact_laws"])
    assert np.all(b["initial_stress"][trough] == 0.0)
    fixed = b["constraint_nodes"][b["constraint_fixed"].all(axis=1)]
    assert set(model.mesh.nodes("trough").tolist()) <= set(fixed.tolist())
    assert fdem.Simulation(model, threads=1).time_step == fdem.Simulation(block, threads=1).time_step
    summary = run_caving(tmp_path, replace(case, until=1.3, output_every=1.3), threads=1, progress=False)
    assert summary["undercut_stages"] == 8
    assert summary["caved_area_m2"] == 0.0
    sim = summary["simulation"]
    ref = sim.reference_positions()[sim.triangles()].mean(axis=1)[:, 1]
    rock = sim.active() & (ref >= BOTTOM)
    assert sim.positions()[sim.triangles()[rock]].mean(axis=1)[:, 1].min() > BOTTOM
    with open(tmp_path / "fragments.csv", newline="") as f:
        lowest = min(float(r["y_m"]) for r in csv.DictReader(f))
    assert lowest > BOTTOM
