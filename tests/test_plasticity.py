"""The Mohr–Coulomb + Rankine law through the Python API (issue 3)."""

from __future__ import annotations

import math

import fdem
import meshio
import numpy as np
import pytest

PALABORA = dict(E=60e9, nu=0.25, rho=3100.0, c=8e6, phi=55.0, psi=9.0, ft=1e6, Gf=70.0)


@pytest.mark.parametrize(
    "change, match",
    [
        ({"c": -1.0}, r"^c = -1.0 must be >= 0"),
        ({"phi": 90.0}, r"^phi = 90.0 must lie in \[0, 90\)"),
        ({"phi": -5.0}, r"^phi = -5.0"),
        ({"psi": 95.0}, r"^psi = 95.0 must lie in \[0, 90\)"),
        ({"psi": -1.0}, r"^psi = -1.0"),
        ({"psi": 60.0}, r"^psi = 60.0 must not exceed phi = 55.0"),
        ({"ft": 0.0}, r"^ft = 0.0 must be positive"),
        ({"ft": 6e6}, r"^ft = 6000000.0 must not exceed c\*cot\(phi\) = 5.6\d+e\+06"),
        ({"Gf": 0.0}, r"^Gf = 0.0 must be positive"),
        ({"Gf": -70.0}, r"^Gf = -70.0"),
        ({"crack_band": "round"}, r"crack_band = 'round'"),
        ({"softening": "exponential"}, r"^softening = 'exponential' must be 'linear', 'bilinear' or a kink"),
        ({"softening": (1.2, 0.2)}, r"^softening = \(1.2, 0.2\) must be .* both in \(0, 1\)"),
        ({"softening": 0.3}, r"^softening = 0.3 must be"),
        ({"E": -1.0}, r"^E = -1.0"),
    ],
)
def test_bad_parameters_are_named(change, match):
    with pytest.raises(ValueError, match=match):
        fdem.MohrCoulombRankine(**{**PALABORA, **change})


def test_derived_strengths_of_table_1():
    rock = fdem.MohrCoulombRankine(**PALABORA)
    phi = math.radians(55)
    assert rock.ucs == pytest.approx(2 * 8e6 * math.cos(phi) / (1 - math.sin(phi)), rel=1e-14)
    assert rock.snap_back_size == pytest.approx(2 * 60e9 / (1 - 0.25**2) * 70 / 1e12, rel=1e-14)


def test_material_point_uniaxial_strain_tension():
    """Uniaxial strain in x: elastic to σxx = f_t, then linear softening
    σ = f_t − H κ down to zero; the dissipation integrates to G_f / h_c and
    the failure factor reaches 1 exactly when σxx reaches zero (eq. 2.21).
    Tolerances: the peak within one increment's stress, the dissipation
    within 0.1% (increments of 1/2000 of the softening strain)."""
    rock = fdem.MohrCoulombRankine(**{**PALABORA, "nu": 0.0})
    h = 0.5
    hmod = h * rock.ft**2 / (2 * rock.Gf)
    eps_peak = rock.ft / rock.E
    n = 4000
    d = (eps_peak + 1.2 * rock.ft / hmod) / n
    r = fdem.material_point(rock, strain_increments=np.tile([d, 0.0, 0.0], (n, 1)), element_size=h)
    sxx = r.stress[:, 0]
    assert sxx.max() == pytest.approx(rock.ft, abs=rock.E * d)
    assert sxx[-1] == pytest.approx(0.0, abs=1e-6 * rock.ft)
    assert (r.fracture_dissipation.sum()) == pytest.approx(rock.Gf / h, rel=1e-3)
    assert r.plastic_dissipation.sum() == 0.0
    softened = np.flatnonzero(r.failure_factor >= 1.0)[0]
    assert sxx[softened] == pytest.approx(0.0, abs=rock.E * d)
    # the softening branch has slope −E H / (E − H) in σ–ε (B.3 with total strain)
    mid = (sxx > 0.3 * rock.ft) & (sxx < 0.7 * rock.ft) & (np.arange(n + 1) > np.argmax(sxx))
    slope = np.polyfit(np.arange(n + 1)[mid] * d, sxx[mid], 1)[0]
    assert slope == pytest.approx(-rock.E * hmod / (rock.E - hmod), rel=1e-6)
    assert set(np.unique(r.active)) <= {0, 8, 8 | 16}


def test_material_point_triaxial_compression_plateau():
    """Plane-strain compression in y with σxx held by a strain path that
    keeps the point on the main plane: the plateau satisfies the MC main
    plane, σ1 (1 + sin φ) − σ3 (1 − sin φ) = 2 c cos φ, within 1e-9."""
    rock = fdem.MohrCoulombRankine(**PALABORA)
    n = 3000
    incs = np.tile([0.3e-6, -1e-6, 0.0], (n, 1))
    r = fdem.material_point(rock, strain_increments=incs, initial_stress=(-5e6, -5e6, -2.5e6, 0))
    s = -np.sort(-np.column_stack([r.stress[:, 0], r.stress[:, 1], r.stress[:, 2]]), axis=1)
    on = r.active == 1
    assert on.sum() > 100
    sp = math.sin(math.radians(55))
    f = s[1:][on, 0] * (1 + sp) - s[1:][on, 2] * (1 - sp) - 2 * 8e6 * math.cos(math.radians(55))
    assert np.abs(f).max() < 1e-9 * 8e6 * 20


def test_material_point_rotation_path_matches_unrotated_path():
    """Stretching while turning, F(t) = R(θ(t)) U(t) with coaxial U: the
    Green–Naghdi update sees D̂ = U̇ U⁻¹ whatever R does, so the Cauchy
    stress is R σ(U) Rᵀ of the unrotated path (objectivity), within 1e-6
    (the midpoint rule errs by O(Δθ² Δε) per step)."""
    rock = fdem.MohrCoulombRankine(**PALABORA)
    n, th_end = 400, 0.7
    stretch = np.linspace(0, 3e-4, n + 1)[1:]
    angles = np.linspace(0, th_end, n + 1)[1:]
    u = [np.array([[1 + e, 0.0], [0.0, 1 - 0.3 * e]]) for e in stretch]

    def rot(a):
        return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])

    plain = fdem.material_point(rock, deformation_gradients=np.array(u), element_size=0.3)
    turned = fdem.material_point(
        rock, deformation_gradients=np.array([rot(a) @ x for a, x in zip(angles, u, strict=True)]), element_size=0.3
    )
    s = plain.stress[-1]
    sig = np.array([[s[0], s[3]], [s[3], s[1]]])
    expected = rot(th_end) @ sig @ rot(th_end).T
    t = turned.stress[-1]
    got = np.array([[t[0], t[3]], [t[3], t[1]]])
    assert np.abs(got - expected).max() <= 1e-6 * np.abs(sig).max()
    assert t[2] == pytest.approx(s[2], rel=1e-6)


def test_material_point_input_errors():
    rock = fdem.MohrCoulombRankine(**PALABORA)
    with pytest.raises(ValueError, match="exactly one of"):
        fdem.material_point(rock)
    with pytest.raises(ValueError, match=r"strain_increments: expected shape \(n, 3\)"):
        fdem.material_point(rock, strain_increments=np.zeros((3, 2)))
    with pytest.raises(ValueError, match="deformation gradient 1 must be finite with a positive determinant"):
        fdem.material_point(rock, deformation_gradients=[np.eye(2), np.diag([1.0, -1.0])])
    with pytest.raises(ValueError, match="snap-back"):
        fdem.material_point(rock, strain_increments=np.zeros((2, 3)), element_size=100.0)


def test_coarse_mesh_beyond_snap_back_is_rejected_naming_the_element():
    rock = fdem.MohrCoulombRankine(**PALABORA)  # limit 8.96 m
    mesh = fdem.Mesh.rectangle(40.0, 20.0, 4, 2)  # 10 m cells
    with pytest.raises(ValueError, match=r"element 0 is 14.1421 m across, larger than the snap-back limit .* 8.9600 m"):
        fdem.Simulation(fdem.Model(mesh, material=rock))
    fdem.Simulation(fdem.Model(fdem.Mesh.rectangle(40.0, 20.0, 8, 4), material=rock))


def test_bilinear_softening_has_its_own_snap_back_limit():
    """Petersson's curve on Table 1's rock: w_c = 3.6 Gf/ft, and the
    steepest branch (3 ft/w_c) sets the snap-back limit E' w_c / (3 ft) =
    5.376 m, against 8.96 m with linear softening. The kernel checks the
    same limit: 5 m cells (7.07 m across) pass with linear softening and
    are rejected, naming the element, with bilinear."""
    rock = fdem.MohrCoulombRankine(**PALABORA, softening="bilinear")
    assert rock.softening_kink == pytest.approx((1 / 3, 2 / 9), rel=1e-15)
    assert rock.critical_opening == pytest.approx(3.6 * 70 / 1e6, rel=1e-14)
    limit = 60e9 / (1 - 0.25**2) * 3.6 * 70 / 1e6 / 3e6
    assert rock.snap_back_size == pytest.approx(limit, rel=1e-14)
    mesh = fdem.Mesh.rectangle(40.0, 20.0, 8, 4)
    fdem.Simulation(fdem.Model(mesh, material=fdem.MohrCoulombRankine(**PALABORA)))
    with pytest.raises(ValueError, match=r"element 0 is 7.0711 m across, larger than the snap-back limit .* 5.3760 m"):
        fdem.Simulation(fdem.Model(mesh, material=rock))
    general = fdem.MohrCoulombRankine(**PALABORA, softening=(0.25, 0.1))
    assert general.critical_opening == pytest.approx(70 / 1e6 / (0.5 * 0.35), rel=1e-14)


def test_state_is_written_to_the_output(tmp_path):
    rock = fdem.MohrCoulombRankine(**{**PALABORA, "E": 10e9, "ft": 0.5e6})
    mesh = fdem.Mesh.rectangle(1.0, 0.2, 10, 2)
    model = fdem.Model(mesh, material=rock).fix("left", x=True, y=False).fix("lower_left")
    model.prescribe_velocity("right", vx=0.5)
    sim = fdem.Simulation(model)
    sim.run(until=2e-4, output_every=1e-4, output=tmp_path, progress=False)
    state = sim.element_state()
    assert (state["kappa"] > 0).any() and (state["crack_band"] > 0).any()
    cracked = state["crack_band"] > 0
    # the bar is pulled along x: crack normals along x, band = cell width 0.1 m
    assert np.allclose(np.abs(np.cos(state["crack_direction"][cracked])), 1.0, atol=1e-3)
    last = meshio.read(tmp_path / "fdem_00002.vtu")
    # one name per field: every element_state field under its own name
    for key in ("failure_factor", *(k for k in state if k != "failure_factor")):
        assert key in last.cell_data, key
    for key in ("kappa", "crack_band", "crack_direction", "plastic_strain", "equivalent_plastic_strain"):
        assert np.array_equal(last.cell_data[key][0], state[key]), key
    assert np.allclose(last.cell_data["failure_factor"][0], np.minimum(state["failure_factor"], 1.0))
    assert np.allclose(last.cell_data["failure_factor_raw"][0], state["failure_factor"])
    e = sim.energies()
    assert e["fracture"] > 0
