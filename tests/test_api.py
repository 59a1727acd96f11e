"""The Python API: meshes from files, output files, persistence, CLI, stubs."""

from __future__ import annotations

import pickle
import subprocess
import sys
import xml.etree.ElementTree as ET

import fdem
import meshio
import numpy as np
import pytest
from conftest import ROCK
from fdem.cli import main as cli_main


def _gmsh_file(path):
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        geo = gmsh.model.geo
        p = [geo.addPoint(*xy, 0, 0.25) for xy in [(0, 0), (2, 0), (2, 1), (0, 1)]]
        lines = [geo.addLine(p[k], p[(k + 1) % 4]) for k in range(4)]
        surf = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        geo.synchronize()
        gmsh.model.addPhysicalGroup(1, [lines[0]], name="base")
        gmsh.model.addPhysicalGroup(1, [lines[2]], name="roof")
        gmsh.model.addPhysicalGroup(2, [surf], name="rock")
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def test_read_gmsh_file_with_named_groups(tmp_path):
    f = tmp_path / "block.msh"
    _gmsh_file(f)
    mesh = fdem.Mesh.read(f)
    assert {"base", "roof", "rock"} <= set(mesh.group_names())
    assert len(mesh.element_sets["rock"]) == mesh.n_elements
    assert np.allclose(mesh.points[mesh.nodes("base"), 1], 0.0)
    assert np.allclose(mesh.points[mesh.nodes("roof"), 1], 1.0)
    assert np.all(mesh.areas() > 0)
    # and it runs: pressure on the roof, fixed base
    model = fdem.Model(mesh, materials={"rock": ROCK}).fix("base").pressure("roof", 1e6)
    fdem.Simulation(model).step(10)


def test_read_vtu_written_by_meshio(tmp_path):
    base = fdem.Mesh.rectangle(1.0, 1.0, 3, 3)
    meshio.write(
        tmp_path / "m.vtu",
        meshio.Mesh(np.column_stack([base.points, np.zeros(base.n_nodes)]), [("triangle", base.triangles)]),
    )
    mesh = fdem.Mesh.read(tmp_path / "m.vtu")
    assert mesh.n_elements == base.n_elements and np.allclose(mesh.points, base.points)


def test_read_errors_name_the_file(tmp_path):
    with pytest.raises(ValueError, match="missing.msh: cannot read mesh"):
        fdem.Mesh.read(tmp_path / "missing.msh")
    pts = np.array([[0, 0, 0], [1, 0, 1], [0, 1, 0]], dtype=float)
    meshio.write(tmp_path / "bent.vtu", meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(ValueError, match="node 1 has z = 1.0"):
        fdem.Mesh.read(tmp_path / "bent.vtu")


def test_output_series_opens_and_has_the_documented_fields(tmp_path):
    mesh = fdem.Mesh.rectangle(2.0, 1.0, 6, 3)
    model = fdem.Model(mesh, material=ROCK).set_gravity(0, -9.81).fix("bottom")
    sim = fdem.Simulation(model, mass_damping=100.0)
    sim.run(until=2e-3, output_every=5e-4, output=tmp_path, name="col", progress=False)
    root = ET.parse(tmp_path / "col.pvd").getroot()
    frames = list(root.iter("DataSet"))
    times = [float(d.get("timestep")) for d in frames]
    assert len(frames) == 5 and times == sorted(times) and times[0] == 0.0
    last = meshio.read(tmp_path / frames[-1].get("file"))
    assert last.points.shape == (mesh.n_nodes, 3)
    for key in ("displacement", "velocity"):
        assert last.point_data[key].shape == (mesh.n_nodes, 3)
    for key, cols in (("stress", 4), ("principal_stress_1", None), ("active", None)):
        arr = last.cell_data[key][0]
        assert len(arr) == mesh.n_elements and (cols is None or arr.shape[1] == cols)
    assert np.allclose(last.cell_data["stress"][0], sim.stress())
    assert len(last.cells) == 1  # no joints or cracks: triangles only
    energy = np.genfromtxt(tmp_path / "col_energy.csv", delimiter=",", names=True)
    assert len(energy) == 5 and "kinetic" in energy.dtype.names
    # a second series with the same name is refused unless overwrite=True
    with pytest.raises(FileExistsError, match="col.pvd already exists"):
        fdem.Simulation(model).run(until=1e-4, output=tmp_path, name="col", progress=False)


def test_stops_between_output_times_leave_no_frame_when_asked(tmp_path):
    """A driver that stops between output times (``final_frame=False``)
    gets frames at the output times only, and every stop in the energy
    history and the checkpoint; the last run's end is a frame by default."""
    mesh = fdem.Mesh.rectangle(2.0, 1.0, 6, 3)
    model = fdem.Model(mesh, material=ROCK).set_gravity(0, -9.81).fix("bottom")
    sim = fdem.Simulation(model, mass_damping=100.0)
    ckpt = tmp_path / "col.ckpt"
    for k in range(1, 8):
        sim.run(
            until=k * 2.5e-4,
            output_every=5e-4,
            output=tmp_path,
            name="col",
            progress=False,
            energy_tolerance=0.05,
            final_frame=k == 7,
        )
        # the checkpoint is this stop's state
        assert fdem.Simulation.from_checkpoint(ckpt, model).steps == sim.steps
    times = [float(d.get("timestep")) for d in ET.parse(tmp_path / "col.pvd").getroot().iter("DataSet")]
    # frames at 0, 5e-4, 1e-3, 1.5e-3 (each at the first step past it) and
    # at the end (1.75e-3): not at the stops in between
    assert len(times) == 5 and times[0] == 0.0 and times[-1] == pytest.approx(sim.time, rel=1e-8)
    assert all(abs(t - k * 5e-4) < 2 * sim.time_step for k, t in enumerate(times[:-1]))
    energy = np.genfromtxt(tmp_path / "col_energy.csv", delimiter=",", names=True)
    # one row per frame and per stop: 0 and the seven stops (three of which
    # are at or just past output times, so both)
    assert len(energy) == 8 and energy["time"][-1] == sim.time


def test_run_continues_a_series_and_stops_at_until():
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    sim = fdem.Simulation(fdem.Model(mesh, material=ROCK).set_gravity(0, -9.81))
    sim.run(until=1e-4, progress=False)
    assert 1e-4 <= sim.time < 1e-4 + sim.time_step * 1.01
    sim.run(until=2e-4, progress=False)
    assert sim.time >= 2e-4


def test_model_round_trips_through_pickle_and_file(tmp_path):
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 3, 3)
    model = (
        fdem.Model(mesh, material=ROCK)
        .set_gravity(0, -9.81)
        .fix("bottom")
        .pressure("top", 1e5, amplitude=fdem.Amplitude.ramp(1e-3))
    )
    clone = pickle.loads(pickle.dumps(model))
    path = tmp_path / "m.fdem"
    model.save(path)
    loaded = fdem.Model.load(path)
    results = []
    for m in (model, clone, loaded):
        sim = fdem.Simulation(m, threads=1)
        sim.step(50)
        results.append(sim.positions())
    assert np.array_equal(results[0], results[1]) and np.array_equal(results[0], results[2])
    (tmp_path / "junk.fdem").write_bytes(b"not a model")
    with pytest.raises(ValueError, match="junk.fdem: not a readable fdem model file"):
        fdem.Model.load(tmp_path / "junk.fdem")


def test_pressure_amplitude_scales_the_load():
    """A ramped pressure on a free-floating block gives it momentum
    ∫ p L dt = p L T/2 after a ramp of T (Newton's second law)."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    p, ramp = 1e5, 1e-4
    model = fdem.Model(mesh, material=ROCK).pressure("top", p, amplitude=fdem.Amplitude.ramp(ramp))
    sim = fdem.Simulation(model, dt=1e-6)
    sim.step(100)
    momentum = (sim.masses()[:, None] * sim.velocities()).sum(axis=0)
    assert abs(momentum[1] - (-p * 1.0 * ramp / 2)) < 1e-3 * p * ramp
    assert abs(momentum[0]) < 1e-9 * p * ramp


def test_cli_info_and_run(tmp_path, capsys):
    assert cli_main(["info"]) == 0
    assert "fdem" in capsys.readouterr().out
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    path = tmp_path / "col.fdem"
    fdem.Model(mesh, material=ROCK).set_gravity(0, -9.81).fix("bottom").save(path)
    code = cli_main(
        ["run", str(path), "--until", "1e-4", "--output-every", "5e-5", "--out", str(tmp_path / "out"), "--quiet"]
    )
    assert code == 0 and (tmp_path / "out" / "col.pvd").exists()
    assert cli_main(["run", str(tmp_path / "missing.fdem"), "--until", "1"]) == 2


def test_console_script_is_installed():
    out = subprocess.run([sys.executable, "-m", "fdem.cli", "info"], capture_output=True, text=True, check=True)
    assert out.stdout.startswith("fdem ")


def test_stub_matches_the_native_module():
    pytest.importorskip("mypy")
    out = subprocess.run([sys.executable, "-m", "mypy.stubtest", "fdem._core"], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr


def test_joint_faces_are_written_as_lines(tmp_path):
    mesh = fdem.jointed_rectangle(4.0, 2.0, 0.5, [fdem.JointSet(90, 10.0, 0.0, 1.0, name="v")])
    model = fdem.Model(mesh, material=ROCK).fix("bottom").contact(interfaces={"v": fdem.Interface()})
    sim = fdem.Simulation(model)
    sim.write_vtu(tmp_path / "j.vtu")
    m = meshio.read(tmp_path / "j.vtu")
    lines = m.cells[1].data
    assert m.cells[1].type == "line" and len(lines) == len(mesh.facet_sets["v"])
    assert np.all(m.cell_data["interface"][1] == 1) and np.all(m.cell_data["interface"][0] == -1)


def _spread(mesh):
    """Spread of node ids within each triangle (max − min)."""
    t = mesh.triangles
    return t.max(axis=1) - t.min(axis=1)


def test_reordered_mesh_is_local_and_keeps_its_groups():
    mesh = fdem.jointed_rectangle(20.0, 10.0, 0.5, [fdem.JointSet(90, 10.0, 3.0, 2.0, name="v")])
    rng = np.random.default_rng(7)
    pn, pe = rng.permutation(mesh.n_nodes), rng.permutation(mesh.n_elements)
    inv = np.empty_like(pn)
    inv[pn] = np.arange(len(pn))
    shuffled = fdem.Mesh(
        mesh.points[pn],
        inv[mesh.triangles[pe]],
        interface_nodes=mesh.interface_nodes[pn],
        facet_sets={k: inv[v] for k, v in mesh.facet_sets.items()},
        element_sets={"first": np.flatnonzero(pe < 10)},
    )
    # a random numbering spreads a triangle's nodes over half the ids (the
    # expected range of three uniform draws); along the Hilbert curve most
    # triangles' nodes lie within a few ids (a jump where the curve leaves a
    # quadrant is rare: the mean grows like √n)
    n = mesh.n_nodes
    assert np.median(_spread(shuffled)) > 0.3 * n
    out = shuffled.reordered()
    for m in (out, mesh):  # the generator returns it ordered
        assert np.median(_spread(m)) <= 16 and _spread(m).mean() < 0.05 * n
    # the same mesh: triangles as coordinate triples, groups by coordinates
    key = lambda m, t: sorted(map(tuple, np.round(m.points[t].reshape(len(t), -1), 12).tolist()))  # noqa: E731
    assert key(out, out.triangles) == key(mesh, mesh.triangles)
    for name, facets in mesh.facet_sets.items():
        assert key(out, out.facet_sets[name]) == key(mesh, facets), name
    assert key(out, out.triangles[out.element_sets["first"]]) == key(mesh, mesh.triangles[pe[pe < 10]])
    assert out.interface_nodes.sum() == mesh.interface_nodes.sum()
    # deterministic, and ordering an ordered mesh changes nothing
    again = shuffled.reordered()
    assert np.array_equal(again.triangles, out.triangles) and np.array_equal(again.points, out.points)
    twice = out.reordered()
    assert np.array_equal(twice.triangles, out.triangles) and np.array_equal(twice.points, out.points)


def test_hilbert_key_walks_a_grid_one_neighbour_at_a_time():
    """The defining property of a Hilbert curve: on a 2^k × 2^k grid the keys
    are 0 … 4^k − 1 and cells with consecutive keys share a side."""
    from fdem.mesh import _hilbert_key

    g = np.arange(16.0)
    cells = np.array([[x, y] for x in g for y in g])
    key = _hilbert_key(cells, bits=4)
    assert sorted(key.tolist()) == list(range(256))
    path = cells[np.argsort(key)]
    assert np.all(np.abs(np.diff(path, axis=0)).sum(axis=1) == 1.0)


def test_frames_carry_principal_stresses_fragments_and_leave_out_excavated_cells(tmp_path):
    """Issue 36 (5): a frame has σ1 ≥ σ2 ≥ σ3 (σzz among them) and the
    in-plane principal direction, checked on a uniform stress rotated by
    30° (σ = R diag(−1, −4) Rᵀ MPa, σzz = ν(σxx + σyy)); the fragment of
    each cell; the failure factor capped at 1 beside its raw value; and no
    excavated cell."""
    mesh = fdem.Mesh.rectangle(2.0, 1.0, 4, 2)
    model = fdem.Model(mesh, material=fdem.Elastic(E=30e9, nu=0.25, rho=2700.0))
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    a, b = -1e6, -4e6
    sxx, syy, sxy = a * c * c + b * s * s, a * s * s + b * c * c, (a - b) * s * c
    model.set_initial_stress((sxx, syy, 0.25 * (sxx + syy), sxy))
    left = np.flatnonzero(mesh.centroids()[:, 0] < 0.5)
    model.excavate(left, at=0.0)
    sim = fdem.Simulation(model)
    sim.run(until=sim.time_step, output_every=sim.time_step, output=tmp_path, progress=False)
    start = meshio.read(tmp_path / "fdem_00000.vtu")  # the initial state, whole
    p1, p2, p3 = (start.cell_data[f"principal_stress_{k}"][0] for k in (1, 2, 3))
    expected = sorted([a, b, 0.25 * (a + b)], reverse=True)
    for k in range(mesh.n_elements):
        assert [p1[k], p2[k], p3[k]] == pytest.approx(expected, rel=1e-9)
    assert np.allclose(start.cell_data["principal_direction"][0], 30.0, atol=1e-6)
    m = meshio.read(sorted(tmp_path.glob("fdem_*.vtu"))[-1])
    n = int(sim.active().sum())
    assert len(start.cells_dict["triangle"]) == mesh.n_elements
    assert len(m.cells_dict["triangle"]) == n < mesh.n_elements
    assert np.array_equal(m.cell_data["fragment"][0], sim.fragment_labels()[sim.active()])
    assert np.all(m.cell_data["failure_factor"][0] <= 1.0)
    assert "failure_factor_raw" in m.cell_data


def test_interface_faces_carry_their_tractions_and_a_legend(tmp_path):
    """Issue 36 (5): a 1 m × 0.5 m block resting on a base under gravity:
    the normal tractions of the interface faces, times their lengths, add
    up to the block's weight (within 1%: the contact forces of both sides'
    nodes, each on the face it presses); the frame names its interface
    laws in its field data."""
    top = fdem.Mesh.rectangle(1.0, 0.5, 4, 2, origin=(0.0, 0.5))
    base = fdem.Mesh.rectangle(2.0, 0.5, 8, 2, origin=(-0.5, 0.0))
    mesh = fdem.Mesh.combine(top, base, prefixes=["top_", "base_"])
    rock = fdem.Elastic(E=1e9, nu=0.25, rho=2000.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0.0, -10.0)
    model.fix("base_bottom").contact(fdem.Interface(friction=30.0, damping=0.5))
    sim = fdem.Simulation(model)
    sim.equilibrate(max_velocity=1e-5, progress=False)
    fdem.output.write_vtu(sim, tmp_path / "rest.vtu")
    m = meshio.read(tmp_path / "rest.vtu")
    # the contact is on free surfaces (law 0), not written as line cells:
    # read the tractions of every surface face
    faces = sim.surface_facets()[0]
    tr = fdem.output.interface_tractions(sim, faces)
    x = sim.positions()
    length = np.linalg.norm(x[faces[:, 1]] - x[faces[:, 0]], axis=1)
    assert np.sum(tr["normal_traction"] * length) == pytest.approx(2000.0 * 10.0 * 0.5, rel=0.01)
    assert "interface_0_default" in m.field_data and "interface_1_cracks" in m.field_data


def test_write_vtu_makes_its_folder_and_plots_take_the_api_names(tmp_path):
    """Issue 36 (4, 5): ``write_vtu`` into a folder that does not exist yet
    makes it; every field of ``element_state`` is in the file under its own
    name, and ``plot_field`` takes those names."""
    import meshio
    from fdem.plot import plot_field

    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    sim = fdem.Simulation(fdem.Model(mesh, material=fdem.Elastic(E=1e9, nu=0.25, rho=2000.0)))
    target = tmp_path / "a" / "b" / "state.vtu"
    sim.write_vtu(target)
    cells = meshio.read(target).cell_data
    assert all(k in cells for k in sim.element_state())
    plot_field(sim, "equivalent_plastic_strain", tmp_path / "eps.png")
    assert (tmp_path / "eps.png").stat().st_size > 1000


def test_fragments_report_their_centre_of_mass_motion():
    """``Simulation.fragments()`` gives each body's centre-of-mass velocity,
    displacement and kinetic energy per unit mass beyond its fall. A block thrown at (1.5, 2) m/s under g = 9.81 m/s²
    is in free flight: v = v₀ + g t and u = v₀ t + g t²/2 (the central
    difference integrates a constant acceleration exactly, to round-off;
    1e-9 of the largest term asked)."""
    mesh = fdem.Mesh.rectangle(1.0, 0.5, 4, 2)
    model = fdem.Model(mesh, material=ROCK).set_gravity(0, -9.81).set_initial_velocity((1.5, 2.0))
    sim = fdem.Simulation(model)
    sim.run(until=2e-3, progress=False, checkpoint=False)
    t = sim.time
    f = sim.fragments()
    assert len(f["area"]) == 1
    assert f["velocity"][0] == pytest.approx([1.5, 2.0 - 9.81 * t], abs=1e-9 * 2.0)
    assert f["displacement"][0] == pytest.approx([1.5 * t, 2.0 * t - 0.5 * 9.81 * t**2], abs=1e-9 * 2.0 * t)
    # in free flight the energy beyond the fall is the throw's, v₀²/2
    assert f["energy_beyond_fall"][0] == pytest.approx(0.5 * (1.5**2 + 2.0**2), rel=1e-9)


def test_overlaps_find_a_node_driven_into_another_body_at_its_depth():
    """``Simulation.overlaps()`` lists each node that lies inside an active
    element it is not a node of, with its depth (distance to the nearest
    edge). Without contact, the triangle (0.2, 0.2), (1.2, 0.2), (0.2, 1.2)
    slides at 10 m/s from 1.5 m to the right into the triangle (0, 0),
    (1, 0), (0, 1). In free flight its first vertex is at
    `(0.2 + 1.5 − 10 t, 0.2)`. Inside the other triangle its depth is
    `min(x, y, (1 − x − y)/√2)` (closed form, to 1e-9 m), and nothing else
    overlaps. ``min_depth`` leaves out shallower nodes."""
    pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.7, 0.2], [2.7, 0.2], [1.7, 1.2]]
    mesh = fdem.Mesh(pts, [[0, 1, 2], [3, 4, 5]], node_sets={"moving": [3, 4, 5]})
    model = fdem.Model(mesh, material=ROCK).set_initial_velocity((-10.0, 0.0), where=[3, 4, 5])
    sim = fdem.Simulation(model)
    assert len(sim.overlaps()["node"]) == 0
    sim.run(until=0.14, progress=False, checkpoint=False)
    x = 1.7 - 10.0 * sim.time
    assert sim.positions()[3] == pytest.approx([x, 0.2], abs=1e-9)
    depth = min(x, 0.2, (1.0 - x - 0.2) / np.sqrt(2.0))
    assert depth > 0.05
    o = sim.overlaps()
    assert o["node"].tolist() == [3] and o["element"].tolist() == [0]
    assert o["depth"][0] == pytest.approx(depth, abs=1e-9)
    assert not o["in_contact"][0]
    assert len(sim.overlaps(min_depth=depth + 0.01)["node"]) == 0
