"""Every example runs and gives the number it is about (STYLE.md)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_p_wave_example():
    r = load("p_wave").main(length=10.0, cells=200)
    assert r["measured"] == pytest.approx(r["closed_form"], rel=0.01)


def test_lithostatic_example(tmp_path):
    r = load("lithostatic").main(out=str(tmp_path), height=50.0, progress=False)
    assert r["max_error"] < 0.01
    assert r["k0"] == pytest.approx(r["k0_closed_form"], rel=0.01)
    assert (tmp_path / "lithostatic.png").stat().st_size > 10_000


@pytest.mark.parametrize("confinement", [0.0, 2e6, 5e6, 10e6])
def test_virtual_laboratory_compression(confinement):
    """Plateau σ_axial = N_φ σ_conf + UCS within 1%, dilation ratio N_ψ
    within 2% (issue 3)."""
    r = load("virtual_laboratory").compression(confinement)
    assert r["axial"] == pytest.approx(r["expected"], rel=0.01)
    assert r["dilation"] == pytest.approx(r["n_psi"], rel=0.02)


def _check_brazilian(r):
    assert r["tensile_strength"] == pytest.approx(r["ft"], rel=0.10)
    assert r["first_crack_radius_fraction"] < 0.5
    assert r["elastic_samples"] >= 20 and r["centre_stress_departure"] < 0.03
    assert r["crack_share_along_diameter"] >= 0.8


@pytest.mark.parametrize(("elements", "loading"), [(8, "jaws"), (16, "jaws"), (16, "platens")])
def test_brazilian_example(elements, loading):
    """Issue 33 (2): before cracking the centre stress is the elastic
    solution for two diametral loads P (Timoshenko & Goodier §41) within 3%
    (measured 0.8–1.6%); the first crack starts in the central half of the
    loaded diameter and the crack runs along it (80% of the cracked pieces
    in the inner 0.8 R within 0.1 D of it); with the ISRM jaws the peak
    gives 2P/(πD) within 10% of f_t (measured +8.1% at 8, +5.9% at 16,
    +3.7% at 32 elements across the radius; flat platens +3.3% at 16)."""
    _check_brazilian(load("brazilian").main(elements, loading, out=None))


@pytest.mark.slow
def test_brazilian_example_fine_mesh():
    """The same on 32 elements across the radius (45 s on 2 cores)."""
    _check_brazilian(load("brazilian").main(32, "jaws", out=None))


def test_notched_beam_on_the_coarse_mesh(tmp_path):
    """Issue 33 (3), the small version: the notched-beam example on its
    coarse mesh (20 mm at the ligament, five elements across it) to 0.8
    mm, 20 s on the 2-core VM: elastic with no crack below 40% of
    Petersson's peak, then a peak within 10% of his tests' 16 kN/m
    (measured 2026-11-26: 16.46 kN/m, +2.9%; Petersson's bilinear
    softening), the curve and its picture written. The coarse mesh still
    cascades (an insertion moves the load by up to 13% of the peak) and
    reads 6% stiff, so those and the three finer meshes are the slow
    tests below."""
    r = load("three_point_bending").main(0.02, out=str(tmp_path))
    assert r["peak_load"] == pytest.approx(r["petersson_peak"], rel=0.10)
    # the crack runs up from the notch tip, at mid-span (measured: 1.7°
    # from the vertical, 2.8 mm off, 73 mm up by 0.8 mm)
    assert abs(r["crack_angle_deg"]) < 10 and abs(r["crack_offset"]) < 0.02 and r["crack_height"] > 0.05
    assert (tmp_path / "beam.png").stat().st_size > 10_000
    text = (tmp_path / "beam.csv").read_text()
    assert text.startswith("time_s,deflection_m,load_N_per_m")
    data = np.loadtxt(tmp_path / "beam.csv", delimiter=",", skiprows=1)
    first = int(np.argmax(data[:, 5] > 0))
    assert data[first, 5] > 0 and data[first - 1, 2] > 0.4 * r["petersson_peak"]


def test_notched_beam_crack_leaves_the_notch_as_one_crack():
    """docs/fracture.md, "A node on a crack reads both sides": on 10 mm
    the crack leaves the notch tip as one crack (its two faces end at the
    same point), 20 s on 2 cores to 0.275 mm of deflection. When each copy
    of a node read σ1 over its own star only, the notch tip's right copy
    read −19.9° against the left's 4.3° and split a second crack from the
    tip 30.4° off the first: by then 4 insertions and two far ends 3.7 mm
    apart, against 2 insertions and one far end now (measured
    2026-11-28)."""
    beam = load("three_point_bending")
    sim = beam.simulation(beam.model(0.01))
    sim.run(until=0.06, progress=False)
    faces = sim.crack_faces()
    tip = np.array([beam.LENGTH / 2, beam.NOTCH])
    d = np.linalg.norm(faces - tip, axis=2)
    at_tip = d.min(axis=1) < 1e-3
    assert at_tip.sum() >= 2, "the notch tip has cracked"
    far = faces[at_tip][np.arange(at_tip.sum()), d[at_tip].argmax(axis=1)]
    # the two faces of one crack end at copies of one node (µm apart)
    assert np.ptp(far, axis=0).max() < 1e-3, far


@pytest.fixture(scope="module")
def beam_runs():
    """The notched beam on 10, 7 and 5 mm at the ligament, and on 10 mm
    with insertion at full softening (``late``) and with checks every 5
    and 20 steps, with Petersson's bilinear softening (the example's
    default): 10 min 46 s on the 2-core Zen 5 VM (2026-11-26)."""
    beam = load("three_point_bending")
    runs = {size: beam.main(size, out=None) for size in (0.01, 0.007, 0.005)}
    runs["late"] = beam.main(0.01, insert_at=1.0, out=None)
    for every in (5, 20):
        runs[f"every {every}"] = beam.main(0.01, check_every=every, out=None)
    return runs


@pytest.mark.slow
def test_notched_beam_meshes_and_insertion(beam_runs):
    """Issue 33 (3) on 10, 7 and 5 mm at the ligament, the load being the
    mean of the pad's and the supports' reactions (docs/fracture.md, "The
    notched beam"): with the default early insertion no insertion changes
    the 1 ms mean load by more than 5% of the peak; the three peaks (1 ms
    mean) lie within 5% of each other; the stiffness is the closed form
    within 5%. Measured 2026-11-28 (2-core Intel Xeon VM) with Petersson's
    bilinear softening: changes 2.5%, 1.5% and 3.3%; peaks 15.58, 15.45
    and 15.57 kN/m (0.8% apart); stiffness +1.8%, +1.2% and +0.7%."""
    meshes = [beam_runs[size] for size in (0.01, 0.007, 0.005)]
    for r in meshes:
        assert r["stiffness"] == pytest.approx(r["closed_form_stiffness"], rel=0.05)
        assert r["largest_change_at_insertion"] < 0.05
    peaks = [r["peak_load"] for r in meshes]
    assert max(peaks) <= 1.05 * min(peaks)
    # issue 33 (4): the crack paths agree between the meshes: up from the
    # notch within 10° of the vertical (symmetry) and of each other, within
    # 1 cm of mid-span (measured 2026-11-28: +0.1°, +2.5°, −5.0°; −1.4,
    # 0.0, −2.2 mm off; 80, 76, 74 mm up by 0.8 mm)
    angles = [r["crack_angle_deg"] for r in meshes]
    assert all(abs(a) < 10 for a in angles) and max(angles) - min(angles) < 10, angles
    assert all(abs(r["crack_offset"]) < 0.01 for r in meshes), [r["crack_offset"] for r in meshes]


@pytest.mark.slow
def test_notched_beam_insertion_rule(beam_runs):
    """Issue 33 (3): the peak does not depend on when a crack is inserted
    by more than 3%: on 10 mm the default early insertion and insertion
    at full softening (``insert_at = 1``, no bonds, the paper's rule).
    Measured 2026-11-28: 15.58 against 15.60 kN/m, 0.15% apart (with
    linear softening, 2026-11-26, 17.08 against 17.67, 3.3%: its band,
    softening more slowly, locked more before the late rule cut it)."""
    assert beam_runs[0.01]["peak_load"] == pytest.approx(beam_runs["late"]["peak_load"], rel=0.03)


@pytest.mark.slow
def test_notched_beam_check_interval(beam_runs):
    """Issue 33 (3): the peak does not depend on the check interval by
    more than 3% over 5, 10 and 20 steps, on 10 mm. Measured 2026-11-28
    (9ea0b7d, 2-core Intel Xeon VM): 15.581, 15.581 and 15.583 kN/m, within
    0.012%. Before a node on a crack read both sides (docs/fracture.md),
    15.993, 15.532 and 15.984 (2.97%): near the tip, branches that the
    one-sided reading let through took the default's crack tip an
    element ahead just before the peak."""
    for every in (5, 20):
        assert beam_runs[f"every {every}"]["peak_load"] == pytest.approx(beam_runs[0.01]["peak_load"], rel=0.03)


@pytest.mark.slow
def test_notched_beam_peak_against_petersson(beam_runs):
    """Issue 33 (3): the peak within 10% of Petersson's tests (about 0.8
    kN on 50 mm thick beams, 16 kN/m) on every mesh, with the concrete's
    softening curve as Petersson fitted it (bilinear: f_t/3 at 0.8
    G_f/f_t, zero at 3.6 G_f/f_t). Measured 2026-11-26: −2.9%, −3.5% and
    −2.7% on 10, 7 and 5 mm. With linear softening and the same G_f the
    peaks read +6.8%, +10.3% and +10.4% (docs/fracture.md, "Softening
    laws"): the first slope of the curve sets a notched beam's peak."""
    for size in (0.01, 0.007, 0.005):
        r = beam_runs[size]
        assert r["peak_load"] == pytest.approx(r["petersson_peak"], rel=0.10)


def test_bridged_energy_of_the_broken_beam():
    """The energy a broken notched beam has still to dissipate at large
    deflection (rigid halves turning about the top of the ligament),
    against the closed forms of the moment ∫ w σ(w) dw: f_t w_c²/6 for
    linear softening; f_t w_k² (1/2 − 2/9) + (f_t/3)(w_c − w_k)(2 w_k +
    w_c)/6 for Petersson's bilinear curve (to 1e-12); it falls as 1/δ."""
    beam = load("three_point_bending")
    ft, gf, span = beam.FT, beam.GF, beam.SPAN
    phi = 2 * 5e-3 / span
    w_c = 2 * gf / ft
    assert beam.bridged_energy(5e-3, "linear") == pytest.approx(ft * w_c**2 / 6 / (2 * phi), rel=1e-12)
    w_k, w_c = 0.8 * gf / ft, 3.6 * gf / ft
    moment = ft * w_k**2 * (1 / 2 - 2 / 9) + (ft / 3) * (w_c - w_k) * (2 * w_k + w_c) / 6
    assert beam.bridged_energy(5e-3) == pytest.approx(moment / (2 * phi), rel=1e-12)
    assert beam.bridged_energy(2.5e-3) == pytest.approx(2 * beam.bridged_energy(5e-3), rel=1e-12)


@pytest.mark.slow
def test_notched_beam_work_of_fracture():
    """Issue 33 (4) on the notched beam: broken through its ligament, the
    beam has dissipated G_f per unit of ligament, as in Petersson's
    work-of-fracture tests. At 5 mm deflection (15 times the peak's) the
    fracture energy is within 10% of G_f (D − a) and within 3% of that
    less what is still bridged (``bridged_energy``). Measured 2026-11-28
    (2-core Intel Xeon VM, 402 s at one thread beside another run): 11.60 J/m,
    0.935 G_f (D − a) and 0.971 of the 11.94 J/m expected, 17 cracks,
    0.176 m of crack projected on the vertical: inside 3% by 0.1 point,
    on a mesh whose debris moves the reading by a few per cent either way
    (docs/fracture.md). Before a node on a crack
    read both sides (docs/fracture.md, "A node on a crack reads both
    sides"): 11.53 J/m, 0.930 and 0.965 (an expected failure), with 27
    cracks and 0.243 m. On 7 mm: 0.949 at 3 mm against 0.939 expected
    (2026-11-26)."""
    r = load("three_point_bending").work_of_fracture(0.02, 5e-3, threads=1)
    assert r["ratio_to_ligament"] == pytest.approx(1.0, rel=0.10), r
    assert r["ratio_to_expected"] == pytest.approx(1.0, rel=0.03), r


@pytest.mark.slow
def test_notched_beam_work_of_fracture_on_10_mm():
    """As :func:`test_notched_beam_work_of_fracture` on 10 mm, at 3 mm
    deflection: within 10% of G_f (D − a) less what is still bridged.
    Measured 2026-11-28 (2-core Intel Xeon VM, 418 s at one thread beside
    another run): 11.46 J/m against 11.64 expected (0.985), one crack
    straight through the ligament (11 insertions, 0.100 m projected on the
    vertical). Before a node on a crack read both sides (docs/fracture.md,
    "A node on a crack reads both sides"), the crack branched from its own
    nodes at 30.4° and 30.7° and the beam dissipated 14.27 J/m (+23%)."""
    r = load("three_point_bending").work_of_fracture(0.01, 3e-3, threads=1)
    assert r["ratio_to_expected"] == pytest.approx(1.0, rel=0.10), r


def test_caving_ensemble_example(tmp_path):
    """Issue 35 (4) at a tiny size (joint spacings ×8, 4 m elements,
    to 0.06 s): 2 realisations × 2 friction angles on a local cluster, every
    run ok, the realisations different, the table and figure written."""
    pytest.importorskip("distributed")
    from fdem.caving import CavingCase

    tiny = CavingCase(size=4.0, joint_scale=8.0, support=5.0, until=0.06, interval=0.03, output_every=0.03)
    r = load("caving_ensemble").main(str(tmp_path), seeds=2, frictions=(25.0, 41.0), case=tiny, quiet=True)
    table = r["table"]
    assert len(table) == 4
    assert list(table["status"]) == ["ok"] * 4, list(table["error"])
    assert sorted(set(table["joint_law.friction"])) == [25.0, 41.0]
    assert sorted(set(table["seed"])) == [0, 1]
    # two realisations of the joints are two meshes
    assert table.groupby("joint_law.friction")["elements_initial"].nunique().min() == 2
    assert list(r["spread"].index) == [25.0, 41.0]
    assert (tmp_path / "spread.csv").is_file()
    assert (tmp_path / "spread.png").stat().st_size > 10_000


def test_caving_levers_side_wall_check():
    """docs/caving.md, "What differs, and why": at the paper's node 1911
    (the left wall, 44 m below the top) rollers carry the lithostatic state
    (σyy = −(15.2 MPa + 30.41 kN/m³ × 44 m), σxx = σyy ν/(1 − ν)) within 1%;
    pinned walls unload σyy there only in a block that starts stress-free,
    by carrying the weight in shear (|σxy| > 5 MPa, where the paper has
    1.5 MPa)."""
    levers = load("caving_levers")
    r = levers.wall_stress("roller", "geostatic", False)
    assert r["syy"] == pytest.approx(r["closed_form_syy"], rel=0.01)
    assert r["sxx"] == pytest.approx(r["closed_form_sxx"], rel=0.01)
    pinned = levers.wall_stress("pinned", "zero", False)
    assert pinned["syy"] > -0.25 * abs(r["closed_form_syy"])
    assert abs(pinned["sxy"]) > 5.0


def test_tunnel_example(tmp_path):
    """Issue 36 (1) at the quick size: a gmsh mesh of a 60 m square with an
    R 3 m tunnel and two joint sets opened into interfaces, geostatic
    stress (σv 10 MPa, K0 1.5), equilibrium and two excavation stages,
    each brought to rest but for loose blocks at the wall; the tunnel
    converges, the rock around it cracks, and the pictures are written.
    The quick mesh's right springline holds a block at limit equilibrium
    that keeps sliding into the tunnel (4.5 mm/s after 2 s; 1.5 m², its
    centroid 0.4 m from the wall): the example reports it (``settle``)
    and the rest of the rock must be at rest (measured 2e-14 m/s). A
    loose block must be a block at the wall: its centroid within 2 m of
    it (the joint spacings are 4.5 and 5.5 m) and all of them together
    under 5 m² (the opening is 28 m²); a rock mass that does not come to
    rest fails."""
    r = load("tunnel").main(size="quick", out=str(tmp_path))
    assert r["joint_faces"] > 500
    assert r["max_velocity"] < 1e-3
    assert r["loose_area"] < 5.0 and r["loose_distance"] < 2.0
    assert r["cracks"] > 0
    # jointed, yielding rock converges more than the elastic plate
    assert r["crown"] > r["crown_kirsch"] and r["springline"] > r["springline_kirsch"]
    for name in ("tunnel_stage1_fracture.png", "tunnel_stage2_fracture.png", "tunnel_displacement.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_tunnel_elastic_matches_kirsch():
    """Issue 36 (1): the elastic variant (no joints, one stage, rollers at
    L = 20 a) against Kirsch's excavation-induced wall displacement in plane
    strain, u = a/(4G) [(p + q) − (3 − 4ν)(p − q) cos 2θ], within 5%
    (measured −0.4% at the crown, −2.2% at the springline; of the latter
    about 0.8% is the finite boundary, the rest the 0.25 m wall mesh)."""
    r = load("tunnel").main(elastic=True, out=None)
    assert r["crown"] == pytest.approx(r["crown_kirsch"], rel=0.05)
    assert r["springline"] == pytest.approx(r["springline_kirsch"], rel=0.05)
    assert r["max_velocity"] < 1e-4


def test_tunnel_example_fine_mesh_comes_to_rest():
    """Issue 36 (2): on the finer jointed mesh (0.2 m at the wall, 5 603
    triangles), which crept on at 1.4 mm/s after 2 s of mass-damped
    equilibrium when each stage was removed at once, gradual excavation
    under local damping brings both stages to rest (about 5 s on 2
    cores)."""
    r = load("tunnel").main(size="fine", out=None)
    assert r["max_velocity"] < 1e-3 and r["loose_blocks"] == 0
    assert r["crown"] > r["crown_kirsch"] and r["springline"] > r["springline_kirsch"]
