"""Crack insertion (paper 2.4, DESIGN §4.4, docs/fracture.md): the fracture
energy of a tension bar, separation and momentum, the Brazilian disc, mesh
objectivity of a mode-I crack path, determinism, bad input.

Tolerances are stated beside each check; see docs/fracture.md for the
measurements behind them."""

from __future__ import annotations

import fdem
import numpy as np
import pytest

# soft rock with a weak cross-section (DESIGN §4.3 parameters, f_t < c cot φ)
SOFT = dict(E=10e9, nu=0.2, rho=2700.0, c=4e6, phi=35.0, psi=5.0)


def pieces(sim: fdem.Simulation) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """The bodies of the current mesh (nodes joined by elements), largest
    first, as (mass, momentum Σ m v, node ids)."""
    tri = sim.triangles()
    n = len(sim.positions())
    parent = np.arange(n)

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b, c in tri:
        for u, v in ((a, b), (b, c)):
            ru, rv = find(u), find(v)
            if ru != rv:
                parent[max(ru, rv)] = min(ru, rv)
    roots = np.array([find(i) for i in range(n)])
    m, v = sim.masses(), sim.velocities()
    out = []
    for r in np.unique(roots):
        ids = np.flatnonzero(roots == r)
        if m[ids].sum() > 0:
            out.append((float(m[ids].sum()), (m[ids, None] * v[ids]).sum(axis=0), ids))
    return sorted(out, key=lambda o: -o[0])


def pulled_bar(
    mesh: fdem.Mesh, weak: np.ndarray, gf: float, *, threads: int | None = None, softening: str = "linear"
) -> tuple[fdem.Simulation, fdem.Model]:
    """A bar on ``mesh`` with the ``weak`` elements 20% weaker in tension
    (fracture energy ``gf`` everywhere, softening along ``softening``),
    held at its left end and pulled at its right end at 20 mm/s."""
    mesh = mesh.with_sets(element_sets={"weak": weak, "rest": np.setdiff1d(np.arange(mesh.n_elements), weak)})
    model = fdem.Model(
        mesh,
        materials={
            "weak": fdem.MohrCoulombRankine(**SOFT, ft=0.8e6, Gf=gf, softening=softening),
            "rest": fdem.MohrCoulombRankine(**SOFT, ft=1.0e6, Gf=gf, softening=softening),
        },
    )
    model.fix("left", x=True, y=False).fix([int(np.argmin(np.hypot(*mesh.points.T)))], x=True, y=True)
    model.prescribe_velocity("right", vx=0.02, amplitude=fdem.Amplitude.ramp(1e-3))
    model.contact(fdem.Interface(friction=30, damping=0.5)).fracture(check_every=5)
    return fdem.Simulation(model, stiffness_damping=1e-6, threads=threads), model


def tension_bar(
    size: float, *, threads: int | None = None, softening: str = "linear"
) -> tuple[fdem.Simulation, fdem.Model, float]:
    """A 0.5 m × 0.1 m bar on an unstructured mesh, the elements crossing its
    middle 20% weaker in tension, pulled at its right end at 20 mm/s."""
    length, width = 0.5, 0.1
    mesh = fdem.jointed_rectangle(length, width, size)
    px = mesh.points[mesh.triangles][:, :, 0]
    weak = np.flatnonzero((px.min(axis=1) < 0.5 * length) & (px.max(axis=1) > 0.5 * length))
    gf = 70.0
    sim, model = pulled_bar(mesh, weak, gf, threads=threads, softening=softening)
    return sim, model, gf * width


def test_tension_bar_dissipates_gf_times_the_section_on_three_meshes():
    """Issue 3 (5d) and issue 5: G_f × W within 10% on three unstructured
    meshes, at most 5% apart; the bar breaks across the weak section and
    carries no load any more; mass and momentum unchanged by every
    insertion to 1e-12. (The pieces ring after the release; their momenta
    are checked on a free bar below.)"""
    ratios = []
    for size in (0.02, 0.014, 0.01):
        sim, model, gfw = tension_bar(size)
        sim.run(until=0.012, progress=False)
        e = sim.energies()
        ratios.append(e["fracture"] / gfw)
        # the crack faces by their law (free boundary 0, no named
        # interface, cracks last), as Simulation.crack_faces finds them
        facets, laws = sim.surface_facets()
        assert np.array_equal(sim.crack_faces(), sim.positions()[facets[laws == 1]])
        faces = sim.crack_faces()
        assert len(faces) > 0
        # every crack face lies in the weak section (within two elements)
        assert np.all(np.abs(faces[:, :, 0] - 0.25) < 2 * size), size
        audit = sim.insertion_audit()
        assert audit is not None and audit["mass"] <= 1e-12 and audit["momentum"] <= 1e-12, audit
        # the bar carries (almost) no load any more: the mean σ_xx of either
        # part below 5% of f_t (measured ≤ 3%: a fully softened element still
        # bridging the crack locks a little)
        c = sim.positions()[sim.triangles()].mean(axis=1)[:, 0]
        a, sxx = sim.areas(), sim.stress()[:, 0]
        for part in (c < 0.2) & (c > 0.05), (c > 0.3) & (c < 0.45):
            assert abs(np.sum(a[part] * sxx[part]) / np.sum(a[part])) < 0.05 * 0.8e6, size
        # the energy account closes to 0.2% of the fracture energy
        assert abs(e["residual"]) < 2e-3 * gfw
    ratios = np.array(ratios)
    assert np.all(np.abs(ratios - 1) < 0.10), ratios
    assert (ratios.max() - ratios.min()) / ratios.mean() < 0.05, ratios


def test_bilinear_softening_dissipates_gf_times_the_section_on_three_meshes():
    """Petersson's bilinear curve (``softening="bilinear"``; band and bonds
    follow it): the bar still dissipates G_f × W within 10% on the three
    meshes, at most 5% apart, breaks across its weak section, and the
    account closes to 0.2% of G_f W."""
    ratios = []
    for size in (0.02, 0.014, 0.01):
        sim, _, gfw = tension_bar(size, softening="bilinear")
        # w_c = 3.6 G_f / f_t = 0.32 mm in the weak section: pulled 0.4 mm
        sim.run(until=0.02, progress=False)
        e = sim.energies()
        ratios.append(e["fracture"] / gfw)
        faces = sim.crack_faces()
        assert len(faces) > 0 and np.all(np.abs(faces[:, :, 0] - 0.25) < 2 * size), size
        assert abs(e["residual"]) < 2e-3 * gfw
    ratios = np.array(ratios)
    assert np.all(np.abs(ratios - 1) < 0.10), ratios
    assert (ratios.max() - ratios.min()) / ratios.mean() < 0.05, ratios


def test_the_paper_insertion_rule_is_available_and_locks():
    """``insert_at=1`` is the paper's rule (crack once the band has fully
    softened). In triangles it over-dissipates through stress locking of the
    band (docs/fracture.md: +13% to +35% measured); kept as an option,
    checked here so the documented figure stays true."""
    sim, model, gfw = tension_bar(0.02)
    model.fracture(check_every=5, insert_at=1.0)
    sim = fdem.Simulation(model, stiffness_damping=1e-6)
    while sim.insertions == 0 and sim.time < 0.03:
        sim.run(until=sim.time + 2.5e-4, progress=False)
    assert sim.insertions > 0
    # by the first crack the band has spent over G_f W already (1.13 here,
    # 1.35 on a gmsh mesh of the same size)
    assert sim.energies()["fracture"] > 1.10 * gfw


def test_a_free_bar_flies_apart_and_free_pieces_keep_their_momentum():
    """Issue 5: a free bar stretched by an initial velocity field
    v_x = v0 (2x/L − 1) breaks across its weak section into two main pieces
    (plus < 2% of debris: 0.95% with isotropic bonds, 1.1% with the
    mixed-mode bonds, 2026-11-26; how much of the rough crack crumbles is
    not a reference value) that fly apart in the directions they had, with no
    bond or contact left between them. Total momentum stays at its initial
    value to 1e-12 of Σ m|v| and every insertion keeps mass and momentum to
    round-off. (Debris stays wedged in the rough crack and knocks both
    halves, so their momenta are not constant afterwards: measured +14% in
    2.5 ms, paid for by the halves' vibration, the energy account closing to
    1e-4 J.)"""
    length, width = 0.5, 0.1
    mesh = fdem.jointed_rectangle(length, width, 0.01)
    px = mesh.points[mesh.triangles][:, :, 0]
    weak = np.flatnonzero((px.min(axis=1) < 0.5 * length) & (px.max(axis=1) > 0.5 * length))
    mesh = mesh.with_sets(element_sets={"weak": weak, "rest": np.setdiff1d(np.arange(mesh.n_elements), weak)})
    rock = {**SOFT, "c": 8e6}
    model = fdem.Model(
        mesh,
        materials={
            "weak": fdem.MohrCoulombRankine(**rock, ft=0.8e6, Gf=1.0),
            "rest": fdem.MohrCoulombRankine(**rock, ft=2e6, Gf=20.0),
        },
    )
    v0 = 0.3
    model.set_initial_velocity(lambda x, y: (v0 * (2 * x / length - 1), 0 * y))
    model.contact(fdem.Interface(friction=30, damping=0.5)).fracture(check_every=5)
    sim = fdem.Simulation(model)
    m, v = sim.masses(), sim.velocities()
    p0, scale = (m[:, None] * v).sum(axis=0), (m * np.hypot(*v.T)).sum()
    sim.run(until=1.5e-3, progress=False)
    parts = pieces(sim)
    total = sum(p[0] for p in parts)
    assert parts[1][0] > 0.45 * total and parts[0][0] + parts[1][0] > 0.98 * total
    label = np.full(len(sim.positions()), -1)
    for k, p in enumerate(parts):
        label[p[2]] = k
    c, bonds = sim.contacts(), sim.bonds()
    assert not any({label[n], label[f[0]]} == {0, 1} for n, f in zip(c["node"], c["facet"], strict=True))
    assert not any({label[a], label[b]} == {0, 1} for a, b in bonds["nodes"])
    x = sim.positions()
    left, right = sorted(parts[:2], key=lambda p: x[p[2], 0].mean())
    half = 0.5 * total * 0.5 * v0  # each half's momentum before the break
    assert left[1][0] < -0.5 * half and right[1][0] > 0.5 * half
    m, v = sim.masses(), sim.velocities()
    assert np.hypot(*((m[:, None] * v).sum(axis=0) - p0)) < 1e-12 * scale
    audit = sim.insertion_audit()
    assert audit["mass"] <= 1e-12 and audit["momentum"] <= 1e-12


def brazilian_disc(size: float) -> tuple[fdem.Simulation, fdem.Mesh]:
    """A D = 50 mm disc between steel platens; the top platen moves down at
    50 mm/s, the bottom one is fixed; light mass damping holds the disc's
    rigid-body rattle between the platens."""
    radius = 0.025
    rock = fdem.MohrCoulombRankine(E=30e9, nu=0.25, rho=2700.0, c=15e6, phi=35.0, psi=5.0, ft=5e6, Gf=30.0)
    steel = fdem.Elastic(E=200e9, nu=0.3, rho=7800.0)
    disc = fdem.Mesh.disc(radius, size)
    disc = disc.with_sets(element_sets={"rock": np.arange(disc.n_elements)})
    w, h, gap = 0.03, 0.01, 1e-6
    plates = [fdem.Mesh.rectangle(w, h, 12, 4, origin=(-w / 2, y)) for y in (radius + gap, -radius - gap - h)]
    plates = [p.with_sets(element_sets={"steel": np.arange(p.n_elements)}) for p in plates]
    mesh = fdem.Mesh.combine(disc, *plates, prefixes=["disc_", "top_", "bottom_"])
    model = fdem.Model(mesh, materials={"disc_rock": rock, "top_steel": steel, "bottom_steel": steel})
    model.fix("bottom_bottom")
    model.prescribe_velocity("top_top", vx=0.0, vy=-0.05, amplitude=fdem.Amplitude.ramp(2e-4))
    model.contact(fdem.Interface(friction=30, damping=0.5)).fracture(check_every=5)
    return fdem.Simulation(model, stiffness_damping=2e-7, mass_damping=5000.0), mesh


def test_brazilian_disc_centre_stress_and_split_along_the_loaded_diameter():
    """Issue 5: before cracking the tensile stress at the centre follows the
    point-load solution σ_xx = 2P/(πDt) (averaged, like the elements, over
    the centre r < 0.15 R with the closed-form field of two diametral point
    loads) within 3%, with P the force through the top platen; the disc
    then splits along the loaded diameter."""
    radius, diameter = 0.025, 0.05
    sim, mesh = brazilian_disc(0.002)
    top = mesh.elements("top_steel")
    disc = mesh.elements("disc_rock")
    c0 = mesh.centroids()[disc]
    centre = disc[np.hypot(*c0.T) < 0.15 * radius]
    checked = 0
    while sim.time < 2.5e-3:
        sim.run(until=sim.time + 5e-5, progress=False)
        if sim.insertions:
            break
        s, a = sim.stress(), sim.areas()
        force = -np.sum(a[top] * s[top, 1]) / 0.01  # ∫σ_yy dA / height = −P
        if force < 100e3:  # past the start-up transient of the platen
            continue
        xc = sim.positions()[sim.triangles()[centre]].mean(axis=1)
        x, y = xc[:, 0], xc[:, 1]
        r1, r2 = x**2 + (radius - y) ** 2, x**2 + (radius + y) ** 2
        exact = -(2 * force / np.pi) * ((radius - y) * x**2 / r1**2 + (radius + y) * x**2 / r2**2 - 1 / diameter)
        fe = np.sum(a[centre] * s[centre, 0]) / np.sum(a[centre])
        ex = np.sum(a[centre] * exact) / np.sum(a[centre])
        assert fe == pytest.approx(ex, rel=0.03), (sim.time, force)
        # and the average is the textbook centre value to within 6% (the
        # closed form itself varies that much over the region)
        assert fe == pytest.approx(2 * force / (np.pi * diameter), rel=0.06)
        checked += 1
    assert checked >= 5 and sim.insertions > 0
    sim.run(until=sim.time + 0.5e-3, progress=False)
    faces = sim.crack_faces()
    mid = faces.mean(axis=1)
    length = np.hypot(*(faces[:, 1] - faces[:, 0]).T)
    inside = np.hypot(*mid.T) < 0.8 * radius  # away from the crushed contacts
    near_axis = np.abs(mid[:, 0]) < 0.1 * diameter
    assert length[inside & near_axis].sum() > 0.8 * length[inside].sum()
    # the split runs through the centre region from top to bottom
    ys = mid[inside & near_axis, 1]
    assert ys.min() < -0.5 * radius and ys.max() > 0.5 * radius


@pytest.mark.parametrize("kind", ["right", "left", "unstructured"])
def test_a_mode_one_crack_runs_normal_to_the_load_whatever_the_mesh(kind):
    """Issue 5 objectivity: a square under uniaxial straining along 22.5°
    (half-way between the 0°, 45° and 90° lines of the structured meshes)
    cracks normal to it, at 112.5°, on structured meshes of either diagonal
    and on an unstructured one: the crack path through the central region
    within 8° of 112.5° (measured 107°–120° over 32–44 cells a side; a crack
    following mesh lines would run at 90° or 135°, 22.5° off)."""
    side, theta = 0.2, np.radians(22.5)
    if kind == "unstructured":
        mesh = fdem.jointed_rectangle(side, side, side / 30, origin=(-side / 2, -side / 2))
    else:
        mesh = fdem.Mesh.rectangle(side, side, 36, 36, origin=(-side / 2, -side / 2), pattern=kind)
    weak = np.flatnonzero(np.hypot(*mesh.centroids().T) < 0.012)
    mesh = mesh.with_sets(element_sets={"weak": weak, "rest": np.setdiff1d(np.arange(mesh.n_elements), weak)})
    material = dict(**{**SOFT, "c": 8e6}, Gf=20.0)
    model = fdem.Model(
        mesh,
        materials={
            "weak": fdem.MohrCoulombRankine(**material, ft=0.7e6),
            "rest": fdem.MohrCoulombRankine(**material, ft=1.0e6),
        },
    )
    n = np.array([np.cos(theta), np.sin(theta)])
    rate = 0.5
    model.prescribe_velocity(
        np.unique(mesh.boundary_facets()),
        vx=lambda x, y: rate * (x * n[0] + y * n[1]) * n[0],
        vy=lambda x, y: rate * (x * n[0] + y * n[1]) * n[1],
        amplitude=fdem.Amplitude.ramp(2e-4),
    )
    model.contact(fdem.Interface(friction=30, damping=0.5)).fracture(check_every=5)
    sim = fdem.Simulation(model, stiffness_damping=1e-6)
    sim.run(until=5e-4, progress=False)
    faces = sim.crack_faces()
    mid = faces.mean(axis=1)
    faces = faces[(np.abs(mid) < 0.06).all(axis=1)]
    length = np.hypot(*(faces[:, 1] - faces[:, 0]).T)
    assert length.sum() > 2 * 0.1  # both faces of a crack across most of the region
    cov = np.cov(faces.mean(axis=1).T, aweights=length)
    w, vec = np.linalg.eigh(cov)
    axis = np.degrees(np.arctan2(vec[1, -1], vec[0, -1])) % 180
    assert abs(axis - 112.5) < 8.0, axis


def test_fracture_is_bit_for_bit_on_one_and_two_threads():
    def run(threads):
        sim, _, _ = tension_bar(0.008, threads=threads)
        sim.run(until=0.0042, progress=False)
        assert sim.insertions > 0
        return sim.triangles(), sim.positions(), sim.stress(), sim.energies(), sim.bonds()["max_opening"]

    a, b = run(1), run(2)
    assert len(a[0]) > 2 * 1024
    for u, w in zip(a, b, strict=True):
        if isinstance(u, dict):
            assert u == w
        else:
            assert np.array_equal(u, w)


def test_the_check_interval_changes_between_stages_and_is_saved(tmp_path):
    """``configure(check_every=…)`` sets the steps between fracture checks
    from then on; the run keeps it through a checkpoint. Checked by what it
    does: with checks too far apart to come before 0.012 s the bar softens
    but is not cut, and brought back to 5 steps it is."""
    sim, model, _ = tension_bar(0.02)
    assert sim.check_every == 5
    sim.configure(check_every=10**9)
    sim.run(until=0.012, progress=False)
    assert sim.insertions == 0 and sim.energies()["fracture"] > 0
    sim.configure(check_every=5)
    sim.run(until=0.014, progress=False)
    assert sim.insertions > 0
    sim.configure(check_every=7, safety=0.7)
    again = fdem.Simulation.from_checkpoint(sim.save_checkpoint(tmp_path / "bar.ckpt"), model)
    assert again.check_every == 7
    with pytest.raises(ValueError, match="check_every"):
        sim.configure(check_every=0)
    with pytest.raises(ValueError, match="safety"):
        sim.configure(check_every=3, safety=2.0)
    assert sim.check_every == 7  # nothing changed by a refused call
    plain = fdem.Model(fdem.Mesh.rectangle(1, 1, 2, 2), material=fdem.Elastic(E=1e9, nu=0.2, rho=2000.0))
    plain_sim = fdem.Simulation(plain)
    assert plain_sim.check_every is None
    with pytest.raises(ValueError, match="no fracture"):
        plain_sim.configure(check_every=3)


def test_cracks_are_line_cells_in_the_output(tmp_path):
    sim, model, _ = tension_bar(0.02)
    sim.run(until=0.012, output_every=0.006, output=tmp_path / "bar", progress=False)
    import meshio

    last = sorted((tmp_path / "bar").glob("*.vtu"))[-1]
    m = meshio.read(last)
    lines = [b for b in m.cells if b.type == "line"]
    assert lines and sum(len(b.data) for b in lines) > 0
    assert "interface" in m.cell_data
    crack_cells = np.concatenate(
        [d for d, b in zip(m.cell_data["interface"], m.cells, strict=True) if b.type == "line"]
    )
    assert np.any(crack_cells == 1)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"check_every": 0}, "check_every"),
        ({"insert_at": 0.0}, r"insert_at = 0.0 must lie in \(0, 1\]"),
        ({"insert_at": 1.5}, "insert_at"),
        ({"min_size": -0.1}, "min_size"),
        ({"min_quality": 0.95}, "min_quality"),
        ({"edge_tolerance": 60}, "edge_tolerance"),
        ({"crack_tolerance": float("nan")}, "crack_tolerance"),
    ],
)
def test_bad_fracture_parameters_are_named(kwargs, match):
    model = fdem.Model(fdem.Mesh.rectangle(1, 1, 2, 2), material=fdem.MohrCoulombRankine(**SOFT, ft=1e6, Gf=70.0))
    with pytest.raises(ValueError, match=match):
        model.fracture(**kwargs)


def test_fracture_without_contact_is_refused():
    model = fdem.Model(fdem.Mesh.rectangle(1, 1, 2, 2), material=fdem.MohrCoulombRankine(**SOFT, ft=1e6, Gf=70.0))
    model.fracture()
    with pytest.raises(ValueError, match="fracture needs contact"):
        fdem.Simulation(model)


def test_mixed_mode_bond_parameters_default_and_are_checked():
    """GII defaults to Gf (fdem.materials.GII_PER_GF), is checked and named,
    and the bonds of a run carry a unit crack normal (docs/fracture.md,
    "Mixed-mode bonds")."""
    rock = fdem.MohrCoulombRankine(**{**SOFT, "c": 8e6}, ft=1e6, Gf=10.0)
    assert rock.shear_fracture_energy == 10.0 == fdem.materials.GII_PER_GF * rock.Gf
    assert fdem.MohrCoulombRankine(**{**SOFT, "c": 8e6}, ft=1e6, Gf=10.0, GII=40.0).shear_fracture_energy == 40.0
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="GII"):
            fdem.MohrCoulombRankine(**{**SOFT, "c": 8e6}, ft=1e6, Gf=10.0, GII=bad)


def test_crack_length_of_a_straight_crack_and_its_energy_per_unit_length():
    """A 0.4 m × 0.1 m bar on a structured 16 × 4 mesh, its middle column
    of cells weaker, pulled apart: it cracks along the grid line x = 0.2 m.
    `crack_length` counts that crack once (0.1 m, to round-off), its
    projection on the section is 0.1 m and on the bar's axis 0; fracture
    energy per unit crack length is G_f within 10% (measured 1.037 G_f,
    docs/fracture.md, "Energy per unit crack length"); a zero direction
    is refused by name."""
    mesh = fdem.Mesh.rectangle(0.4, 0.1, 16, 4)
    weak = np.flatnonzero(np.abs(mesh.centroids()[:, 0] - 0.2) < 0.0125)
    gf = 20.0
    sim, _ = pulled_bar(mesh, weak, gf)
    assert sim.crack_length() == 0.0
    sim.run(until=0.006, progress=False)
    facets, laws = sim.surface_facets()
    crack = facets[laws == 1]  # free boundary 0, cracks last
    assert len(crack) == 8
    assert np.allclose(sim.reference_positions()[crack][:, :, 0], 0.2)
    assert sim.crack_length() == pytest.approx(0.1, rel=1e-12)
    assert sim.crack_length(along=(0, 2)) == pytest.approx(0.1, rel=1e-12)
    assert sim.crack_length(along=(1, 0)) == pytest.approx(0.0, abs=1e-15)
    assert sim.energies()["fracture"] / (gf * sim.crack_length()) == pytest.approx(1.0, rel=0.10)
    with pytest.raises(ValueError, match="along"):
        sim.crack_length(along=(0, 0))
