"""Every example runs and gives the number it is about (STYLE.md)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

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
