"""Bad input raises ValueError naming the offending entity (issue 2, item 5);
a run that breaks raises a SimulationError after valid output."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import fdem
import meshio
import numpy as np
import pytest
from conftest import ROCK
from fdem import _core

SQUARE_PTS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
SQUARE_TRI = np.array([[0, 1, 2], [0, 2, 3]])


def test_good_square_is_accepted():
    assert fdem.Mesh(SQUARE_PTS, SQUARE_TRI).n_elements == 2


@pytest.mark.parametrize(
    "points, triangles, match",
    [
        (SQUARE_PTS, [[0, 1, 2], [0, 3, 2]], r"element 1 is clockwise"),
        ([[0, 0], [1, 0], [2, 0]], [[0, 1, 2]], r"element 0 has zero area"),
        ([[0, 0], [1, 0], [np.nan, 1], [0, 1]], SQUARE_TRI, r"points: entry 2 is NaN or infinite"),
        ([[0, 0], [1, 0], [1, np.inf], [0, 1]], SQUARE_TRI, r"points: entry 2 is NaN or infinite"),
        ([[0, 0], [1, 0], [1, 1], [0, 1], [5, 5]], SQUARE_TRI, r"node 4 belongs to no element"),
        ([[0, 0], [1, 0], [1, 1], [0, 1], [1, 0]], [[0, 1, 2], [0, 2, 3], [4, 2, 0]], r"node 4 coincides with node 1"),
        (SQUARE_PTS, [[0, 1, 7], [0, 2, 3]], r"element 0 refers to node 7"),
        (SQUARE_PTS, [[0, 1, -2], [0, 2, 3]], r"id -2 is negative"),
        (SQUARE_PTS, [[0, 1, 1], [0, 2, 3]], r"element 0 uses the same node twice"),
        (np.zeros((4, 3)), SQUARE_TRI, r"points: expected shape \(n, 2\), got \(4, 3\)"),
        (SQUARE_PTS, [[0, 1], [0, 2]], r"triangles: expected shape \(n, 3\)"),
        (SQUARE_PTS, [[0, 1, 2.5], [0, 2, 3]], r"triangles: ids must be integers"),
        ([["a", "b"]] * 4, SQUARE_TRI, r"points: expected numbers"),
        (SQUARE_PTS, np.zeros((0, 3), dtype=int), r"no elements"),
    ],
)
def test_bad_mesh_names_the_entity(points, triangles, match):
    with pytest.raises(ValueError, match=match):
        fdem.Mesh(points, triangles)


def test_non_contiguous_and_other_dtypes_are_accepted():
    pts = np.asfortranarray(np.column_stack([SQUARE_PTS, np.ones(4)]))[:, :2]
    assert not pts.flags.c_contiguous
    tri = SQUARE_TRI.astype(np.uint16)
    mesh = fdem.Mesh(pts.astype(np.float32), tri)
    assert mesh.points.dtype == np.float64 and mesh.triangles.dtype == np.int64


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"E": 0.0, "nu": 0.2, "rho": 1.0}, r"^E = 0.0 must be positive"),
        ({"E": -1e9, "nu": 0.2, "rho": 1.0}, r"^E = "),
        ({"E": 1e9, "nu": 0.5, "rho": 1.0}, r"^nu = 0.5 must lie in \(-1, 0.5\)"),
        ({"E": 1e9, "nu": -1.0, "rho": 1.0}, r"^nu = "),
        ({"E": 1e9, "nu": 0.2, "rho": 0.0}, r"^rho = 0.0 must be positive"),
        ({"E": float("nan"), "nu": 0.2, "rho": 1.0}, r"^E = nan must be finite"),
        ({"E": "stiff", "nu": 0.2, "rho": 1.0}, r"^E must be a number"),
    ],
)
def test_bad_material_names_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        fdem.Elastic(**kwargs)


def test_kernel_rejects_bad_material_rows_by_name():
    arrays = fdem.Model(fdem.Mesh(SQUARE_PTS, SQUARE_TRI), material=ROCK).kernel_arrays()
    arrays["materials"] = [{"kind": "elastic", "rho": 2700.0, "E": 1e9, "nu": 0.7}]
    with pytest.raises(ValueError, match=r"material 0: material parameter nu = 0.7"):
        _core.Simulation(**arrays)


def test_unknown_group_name():
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    model = fdem.Model(mesh, material=ROCK)
    with pytest.raises(ValueError, match=r"unknown group 'base'.*'bottom'"):
        model.fix("base")
    with pytest.raises(ValueError, match=r"unknown facet set 'roof'"):
        model.pressure("roof", 1e6)
    with pytest.raises(ValueError, match=r"unknown element set 'ore'"):
        fdem.Model(mesh, materials={"ore": ROCK})


def test_facet_set_off_the_boundary_is_named():
    with pytest.raises(ValueError, match=r"facet set 'cut': entry 0 \(0, 2\) is not an edge on the mesh boundary"):
        fdem.Mesh(SQUARE_PTS, SQUARE_TRI, facet_sets={"cut": [[0, 2]]})


def test_bad_settings_name_the_parameter():
    model = fdem.Model(fdem.Mesh(SQUARE_PTS, SQUARE_TRI), material=ROCK)
    for kwargs, match in [
        ({"safety": 1.5}, r"safety = 1.5"),
        ({"dt": -1.0}, r"dt = -1.0 must be positive"),
        ({"mass_damping": -2.0}, r"mass_damping = -2.0"),
        ({"threads": 0}, r"threads = 0"),
    ]:
        with pytest.raises(ValueError, match=match):
            fdem.Simulation(model, **kwargs)


def test_initial_fields_are_checked():
    model = fdem.Model(fdem.Mesh(SQUARE_PTS, SQUARE_TRI), material=ROCK)
    with pytest.raises(ValueError, match=r"initial stress: expected shape \(4,\)"):
        model.set_initial_stress((1.0, 2.0))
    with pytest.raises(ValueError, match=r"initial velocity: entry 1 is NaN"):
        model.set_initial_velocity(np.array([[0, 0], [np.nan, 0], [0, 0], [0, 0]]))


def test_panic_becomes_runtime_error_not_panic_exception():
    with pytest.raises(RuntimeError, match="internal error in the fdem kernel") as info:
        _core._panic_selftest()
    assert type(info.value) is RuntimeError


def test_inverted_element_stops_after_valid_output(tmp_path):
    """Crushing a block inverts an element: the run raises
    InvertedElementError with the element, step and time, and every frame
    in the .pvd index written before is complete and readable."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 4, 4)
    model = fdem.Model(mesh, material=ROCK).fix("bottom")
    model.prescribe_velocity("upper_left", vx=0.0, vy=-3000.0)
    sim = fdem.Simulation(model)
    with pytest.raises(fdem.InvertedElementError) as info:
        sim.run(until=1.0, output_every=2e-5, output=tmp_path, progress=False)
    err = info.value
    assert 0 <= err.element < mesh.n_elements and err.step > 0 and err.time > 0
    assert f"element {err.element} inverted" in str(err) and f"step {err.step}" in str(err)
    tree = ET.parse(tmp_path / "fdem.pvd")
    files = [d.get("file") for d in tree.iter("DataSet")]
    assert len(files) >= 2
    for f in files:
        m = meshio.read(tmp_path / f)
        assert len(m.cells[0].data) == mesh.n_elements
    assert not list(tmp_path.glob("*.tmp"))


# --- issue 36, point 4: unit slips, impossible values, bounded work --------


@pytest.mark.parametrize(
    ("make", "word"),
    [
        (lambda: fdem.Elastic(E=30e3, nu=0.25, rho=2700.0), "E = 30000 Pa"),
        (lambda: fdem.Elastic(E=30e9, nu=0.25, rho=2.6), "rho = 2.6"),
        (
            lambda: fdem.MohrCoulombRankine(E=30e9, nu=0.25, rho=2700.0, c=1e6, phi=0.6, psi=0.1, ft=1e5, Gf=50.0),
            "phi = 0.6 degrees",
        ),
        (
            lambda: fdem.MohrCoulombRankine(E=30e9, nu=0.25, rho=2700.0, c=8.0, phi=30.0, psi=0.0, ft=1.0, Gf=50.0),
            "c = 8 Pa",
        ),
        (lambda: fdem.Interface(friction=0.6), "friction = 0.6 degrees"),
    ],
)
def test_a_likely_unit_slip_warns_naming_the_parameter(make, word):
    """Allowed but almost certainly a slip of units: a PlausibilityWarning
    that names the parameter and the likely mistake."""
    from fdem.errors import PlausibilityWarning

    with pytest.warns(PlausibilityWarning, match=word):
        make()


def _tiny_model(**material):
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    return fdem.Model(mesh, material=fdem.Elastic(**{"E": 30e9, "nu": 0.25, "rho": 2700.0, **material}))


def test_impossible_values_are_value_errors_naming_the_parameter(tmp_path):
    """A stage before time zero, a run back in time, frames without a
    folder, a modulus or density that makes the step infinite, an initial
    stress whose energy is infinite: each a ValueError that names it."""
    import warnings

    with pytest.raises(ValueError, match="at = -0.5"):
        _tiny_model().excavate([0], at=-0.5)
    sim = fdem.Simulation(_tiny_model())
    with pytest.raises(ValueError, match="until = -1"):
        sim.run(until=-1.0, progress=False)
    with pytest.raises(ValueError, match="output_every needs output"):
        sim.run(until=1e-4, output_every=1e-5, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for bad in ({"E": 5e-324}, {"rho": 5e-324}):
            with pytest.raises(ValueError, match="stable time step"):
                fdem.Simulation(_tiny_model(**bad))
    with pytest.raises(ValueError, match="initial stress of element 0"):
        fdem.Simulation(_tiny_model().set_initial_stress((1e308, 1e308, 0.0, 0.0)))
    from fdem.output import principal_stresses

    with pytest.raises(ValueError, match="shape"):
        principal_stresses(np.zeros(3))


def test_nothing_hangs_on_a_bad_size(tmp_path):
    """An output interval far below the step writes a frame per step and
    returns (it counted through 1e11 skipped output times before); a joint
    spacing or period far below the region, and a disc of kilometres meshed
    at a millimetre, are refused before any work (each took minutes or
    gigabytes)."""
    import time

    sim = fdem.Simulation(_tiny_model())
    t0 = time.perf_counter()
    sim.run(until=1e-4, output_every=1e-15, output=tmp_path, progress=False)
    assert time.perf_counter() - t0 < 5.0
    for joint in (fdem.JointSet(0.0, 1.0, 0.0, 1e-300), fdem.JointSet(0.0, 5e-324, 0.0, 1.0)):
        with pytest.raises(ValueError, match="traces"):
            joint.traces((0.0, 0.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="nodes"):
        fdem.Mesh.disc(2700.0, 0.001)
    with pytest.raises(ValueError, match="max_nodes"):
        fdem.Mesh.polygon([[0, 0], [1000, 0], [1000, 1000], [0, 1000]], 0.01)


def test_a_damaged_model_file_is_refused_naming_it(tmp_path):
    """Model files carry a SHA-256 of the model: every one of 200 random
    single-bit flips is a ValueError naming the file (18 of 40 loaded as
    another model before); a file of junk too."""
    import random

    path = tmp_path / "m.fdem"
    _tiny_model().save(path)
    assert isinstance(fdem.Model.load(path), fdem.Model)
    data = path.read_bytes()
    rng = random.Random(1)
    for _ in range(200):
        flipped = bytearray(data)
        k = rng.randrange(len(data))
        flipped[k] ^= 1 << rng.randrange(8)
        bad = tmp_path / "bad.fdem"
        bad.write_bytes(bytes(flipped))
        with pytest.raises(ValueError, match="bad.fdem"):
            fdem.Model.load(bad)


def test_overlapping_triangles_that_share_no_edge_are_refused():
    """Mesh's docstring promises a ValueError for overlapping triangles:
    also for those that share no edge (crossing, or one inside the other),
    naming both elements; a jointed mesh, whose two sides of a joint touch
    along it with their own nodes, passes."""
    crossing = [[0, 0], [1, 0], [0, 1], [0.2, 0.2], [1.2, 0.2], [0.2, 1.2]]
    with pytest.raises(ValueError, match="elements 0 and 1 overlap"):
        fdem.Mesh(crossing, [[0, 1, 2], [3, 4, 5]])
    inside = [[0, 0], [4, 0], [0, 4], [1, 1], [2, 1], [1, 2]]
    with pytest.raises(ValueError, match="overlap"):
        fdem.Mesh(inside, [[0, 1, 2], [3, 4, 5]])
    fdem.jointed_rectangle(10.0, 5.0, 0.5, [fdem.JointSet(90.0, 3.0, 1.0, 2.0)])


def test_a_full_disk_names_the_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    """A frame that cannot be written (the disk is full) is an OSError that
    names the file; no ``.tmp`` file is left behind, and the frames and
    index written before stay as they were."""
    import errno

    import meshio

    sim = fdem.Simulation(_tiny_model())
    sim.run(until=1e-4, output_every=5e-5, output=tmp_path, progress=False, checkpoint=False)
    index = (tmp_path / "fdem.pvd").read_text()

    def full(path, *args, **kwargs):
        with open(path, "wb") as f:
            f.write(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(meshio, "write", full)
    with pytest.raises(OSError, match=r"fdem_\d{5}\.vtu: could not be written"):
        sim.run(until=3e-4, output_every=5e-5, output=tmp_path, progress=False, checkpoint=False)
    assert not list(tmp_path.glob("*.tmp"))
    assert (tmp_path / "fdem.pvd").read_text() == index


def test_an_interrupted_frame_is_listed_once(tmp_path, monkeypatch):
    """Ctrl-C while the index is being replaced: the run's handler writes
    the state again, and the series lists that time once (it listed it
    twice, and the duplicate survived a resume)."""
    from fdem import output

    sim = fdem.Simulation(_tiny_model())
    sim.run(until=1e-4, output_every=5e-5, output=tmp_path, progress=False)
    real = output.VtuSeries._write_index
    calls = {"n": 0}

    def interrupted(self):
        calls["n"] += 1
        real(self)
        if calls["n"] == 1:
            raise KeyboardInterrupt

    monkeypatch.setattr(output.VtuSeries, "_write_index", interrupted)
    with pytest.raises(KeyboardInterrupt):
        sim.run(until=3e-4, output_every=5e-5, output=tmp_path, progress=False)
    times = [float(d.get("timestep")) for d in ET.parse(tmp_path / "fdem.pvd").getroot().iter("DataSet")]
    assert len(times) == len(set(times))
