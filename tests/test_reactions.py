"""Reaction forces and load–displacement output (issue 33, point 1): the
force the model exerts on a supported or driven node group, checked
against statics and plane-strain elasticity. Tolerances beside each check."""

from __future__ import annotations

import csv

import fdem
import numpy as np
import pytest
from fdem.laboratory import compression_specimen

ROCK = fdem.Elastic(E=30e9, nu=0.25, rho=2500.0)


def test_a_column_at_rest_weighs_on_its_base_what_statics_says():
    """A 10 m × 40 m elastic column on a fixed base between rollers, under
    gravity and 2 MPa on its top, brought to rest: the base carries its
    weight plus the top load, ρ g W H + p W, within 0.1% (the rest of the
    damped stage's motion); the rollers push on each other's side equally
    (their x forces cancel to 1e-6 of the base load), and no support
    carries anything in its free direction."""
    mesh = fdem.Mesh.rectangle(10.0, 40.0, 5, 20)
    model = fdem.Model(mesh, material=ROCK).set_gravity(0.0, -9.81)
    model.fix("bottom", x=False, y=True).fix("left", x=True, y=False).fix("right", x=True, y=False)
    model.pressure("top", 2e6)
    model.set_geostatic_stress(top=40.0, pressure=2e6)
    sim = fdem.Simulation(model, threads=1)
    sim.equilibrate(max_velocity=1e-5, progress=False)
    load = 2500.0 * 9.81 * 10.0 * 40.0 + 2e6 * 10.0
    base = sim.reaction("bottom")
    assert base["force"][1] == pytest.approx(-load, rel=1e-3)
    assert base["nodes"] == 6
    left, right = sim.reaction("left")["force"], sim.reaction("right")["force"]
    assert abs(left[0] + right[0]) < 1e-6 * load
    assert left[0] < 0 < right[0]
    r = sim.reaction_forces()
    held = np.zeros(len(r), dtype=bool)
    held[mesh.nodes("bottom")] = True
    held[mesh.nodes("left")] = held[mesh.nodes("right")] = True
    assert np.all(r[~held] == 0.0)
    free_x = np.setdiff1d(mesh.nodes("bottom"), np.union1d(mesh.nodes("left"), mesh.nodes("right")))
    assert np.all(r[free_x, 0] == 0.0)
    assert np.array_equal(sim.node_origins(), np.arange(mesh.n_nodes))


def test_platen_load_follows_plane_strain_elasticity_and_is_written_to_csv(tmp_path):
    """A plane-strain specimen (1 m × 2 m) between frictionless platens,
    the top one driven down at 0.01/s: the top platen's load is
    E/(1 − ν²) ε W at every frame after the ramp (ε the platen's travel
    over the height), within 0.5% (the ramp leaves a stress wave of about
    0.1% of the load at ε = 1e-3); the base carries the same load within
    0.5%; ``{name}_reactions.csv`` holds those histories, one row per
    frame, the force the specimen exerts on each platen."""
    model = compression_specimen(ROCK, width=1.0, height=2.0, cells=(8, 16), strain_rate=0.01)
    sim = fdem.Simulation(model, threads=1)
    sim.run(until=0.05, output_every=0.005, output=tmp_path, reactions=["top", "bottom"], progress=False)
    with open(tmp_path / "fdem_reactions.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 11
    stiffness = ROCK.E / (1 - ROCK.nu**2) * 1.0 / 2.0  # N/m per m of travel
    for row in rows[4:]:
        travel = -float(row["top_uy"])
        assert float(row["top_fy"]) == pytest.approx(stiffness * travel, rel=5e-3)
        assert -float(row["bottom_fy"]) == pytest.approx(float(row["top_fy"]), rel=5e-3)
    now = sim.reaction("top")
    assert float(rows[-1]["top_fy"]) == now["force"][1]
    assert now["displacement"][1] == pytest.approx(-0.01 * 2.0 * (0.05 - 0.5 * 2e-3), rel=1e-2)
    with pytest.raises(ValueError, match="nowhere"):
        fdem.Simulation(model).run(until=1e-4, output=tmp_path / "x", reactions=["nowhere"], progress=False)


def test_a_resumed_run_continues_its_reaction_history_bit_for_bit(tmp_path):
    """A run restored from a checkpoint drops the reaction rows written
    after it and writes them again: the history equals the uninterrupted
    run's, character for character, and keeps its groups."""
    import shutil

    model = compression_specimen(ROCK, width=1.0, height=2.0, cells=(4, 8), strain_rate=0.01)
    sim = fdem.Simulation(model, threads=1)
    sim.run(until=0.02, output_every=0.005, output=tmp_path, reactions=["top"], progress=False)
    shutil.copy(tmp_path / "fdem.ckpt", tmp_path / "mid.ckpt")
    sim.run(until=0.04, output_every=0.005, output=tmp_path, progress=False)
    whole = (tmp_path / "fdem_reactions.csv").read_text()
    assert len(whole.splitlines()) == 1 + 9
    again = fdem.Simulation.from_checkpoint(tmp_path / "mid.ckpt", model, threads=2)
    again.run(until=0.04, output_every=0.005, output=tmp_path, progress=False)
    assert (tmp_path / "fdem_reactions.csv").read_text() == whole


def test_probes_record_the_stress_at_a_point_and_a_groups_motion(tmp_path):
    """Issue 36 (3): named probes at every frame, to ``{name}_probes.csv``
    and by ``Simulation.probe``: the stress at the specimen's centre is the
    uniaxial plane-strain state σyy = −E'ε, σxx = 0 (within 0.5% and 0.5%
    of σyy), the top group moves with the platen; a void point reads NaN;
    a bad probe is named before anything is written."""
    model = compression_specimen(ROCK, width=1.0, height=2.0, cells=(8, 16), strain_rate=0.01)
    sim = fdem.Simulation(model, threads=1)
    probes = {"centre": (0.5, 1.0), "top": "top", "outside": (5.0, 5.0)}
    sim.run(until=0.05, output_every=0.01, output=tmp_path, probes=probes, progress=False)
    with open(tmp_path / "fdem_probes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 6
    last = rows[-1]
    strain = -float(last["top_displacement_y"]) / 2.0
    syy = float(last["centre_stress_yy"])
    assert syy == pytest.approx(-ROCK.E / (1 - ROCK.nu**2) * strain, rel=5e-3)
    assert abs(float(last["centre_stress_xx"])) < 5e-3 * abs(syy)
    assert np.isnan(float(last["outside_stress_xx"]))
    assert sim.probe("top")["displacement"][1] == pytest.approx(float(last["top_displacement_y"]), rel=1e-12)
    assert sim.probe((0.5, 1.0))["stress"][1] == float(last["centre_stress_yy"])
    with pytest.raises(ValueError, match="nowhere"):
        fdem.Simulation(model).run(until=1e-4, output=tmp_path / "x", probes={"p": "nowhere"}, progress=False)
