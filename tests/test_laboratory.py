"""Lab helpers with load–displacement output (issue 33, point 7): direct
tension and uniaxial compression specimens return typed results and write
their curves. Tolerances beside each check."""

from __future__ import annotations

import csv

import fdem
import pytest
from fdem.laboratory import compression_specimen, run_specimen, tension_specimen

ROCK = fdem.MohrCoulombRankine(E=30e9, nu=0.25, rho=2700.0, c=12e6, phi=35.0, psi=5.0, ft=4e6, Gf=50.0)


def test_direct_tension_peaks_at_ft_and_breaks(tmp_path):
    """A 50 mm × 100 mm plane-strain bar pulled at 0.2/s: the stress on
    the grip rises with E' = E/(1 − ν²) (within 1% at half the peak),
    peaks at f_t (within 2%; measured −0.1%) and falls to under 5% of it
    once the bar has broken (five times the cracking strain); the curve
    goes to tension.csv and tension.png."""
    model = tension_specimen(ROCK, cells=(8, 16), strain_rate=0.2)
    r = run_specimen(model, 5 * ROCK.ft / ROCK.plane_strain_modulus, out=tmp_path, name="tension")
    assert r.kind == "tension"
    assert r.peak_stress == pytest.approx(ROCK.ft, rel=0.02)
    k = int(abs(r.stress - 0.5 * r.peak_stress).argmin())
    assert r.stress[k] / r.strain[k] == pytest.approx(ROCK.plane_strain_modulus, rel=0.01)
    assert r.cracks[-1] > 0 and r.stress[-1] < 0.05 * ROCK.ft
    with open(tmp_path / "tension.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 100 and float(rows[-1]["axial_strain"]) == pytest.approx(r.strain[-1])
    assert (tmp_path / "tension.png").stat().st_size > 10_000


def test_uniaxial_compression_peaks_at_ucs(tmp_path):
    """The same specimen in compression between frictionless platens:
    peak at UCS = 2c cos φ/(1 − sin φ) within 1% (measured +0.4%),
    positive in compression."""
    model = compression_specimen(ROCK, width=0.05, height=0.1, cells=(8, 16), strain_rate=0.2, ramp=2e-4)
    r = run_specimen(model, 3 * ROCK.ucs / ROCK.plane_strain_modulus, out=tmp_path, name="compression")
    assert r.kind == "compression"
    assert r.peak_stress == pytest.approx(ROCK.ucs, rel=0.01)
    assert (tmp_path / "compression.csv").exists() and (tmp_path / "compression.png").stat().st_size > 10_000
    with pytest.raises(ValueError, match="specimen"):
        run_specimen(fdem.Model(fdem.Mesh.rectangle(1.0, 1.0, 2, 2), material=ROCK), 1e-3)
