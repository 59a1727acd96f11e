"""A virtual rock-mechanics laboratory for the Mohr–Coulomb + Rankine law.

Plane-strain compression of the paper's Palabora rock (Table 1) between
frictionless platens at several confinements:

1. the axial stress plateaus at σ_axial = N_φ σ_conf + UCS (compression as
   magnitudes), UCS = 2 c cos φ / (1 − sin φ), N_φ = (1 + sin φ)/(1 − sin φ);
2. on the plateau the lateral over axial strain rate is the plastic
   dilation ratio N_ψ = (1 + sin ψ)/(1 − sin ψ).

    python examples/virtual_laboratory.py
"""

from __future__ import annotations

import fdem
from fdem.laboratory import compression_specimen, run_specimen

ROCK = fdem.MohrCoulombRankine(E=60e9, nu=0.25, rho=3100.0, c=8e6, phi=55.0, psi=9.0, ft=1e6, Gf=70.0)


def compression(confinement: float = 0.0, material: fdem.MohrCoulombRankine = ROCK) -> dict[str, float]:
    """Loads a 1 m × 2 m specimen to three times its yield strain; returns
    the plateau axial stress (Pa, magnitude), the closed form, and the
    dilation ratio measured over the last quarter of the run."""
    rate, ramp = 0.01, 2e-3
    model = compression_specimen(material, confinement=confinement, strain_rate=rate, ramp=ramp)
    sim = fdem.Simulation(model, stiffness_damping=2e-5)
    expected = material.n_phi * confinement + material.ucs
    yield_strain = (expected - confinement) / material.plane_strain_modulus
    t_end = ramp / 2 + 3.0 * yield_strain / rate
    sim.run(until=0.75 * t_end, progress=False)
    x0, t0 = sim.positions(), sim.time
    sim.run(until=t_end, progress=False)
    dx, dt = sim.positions() - x0, sim.time - t0
    mesh = model.mesh
    lateral = (dx[mesh.nodes("right"), 0].mean() - dx[mesh.nodes("left"), 0].mean()) / 1.0
    axial = -dx[mesh.nodes("top"), 1].mean() / 2.0
    return {
        "axial": float(-sim.stress()[:, 1].mean()),
        "expected": float(expected),
        "dilation": float(lateral / axial),
        "n_psi": material.n_psi,
        "duration": dt,
    }


def main(out: str = "virtual_laboratory_output") -> None:
    """Prints each confinement's plateau against the closed form and writes
    its stress–strain curve (``compression_<MPa>.csv`` and ``.png``, by
    :func:`fdem.laboratory.run_specimen`) into ``out``."""
    print(f"UCS = {ROCK.ucs / 1e6:.2f} MPa, N_phi = {ROCK.n_phi:.3f}, N_psi = {ROCK.n_psi:.4f}")
    for p in (0.0, 2e6, 5e6, 10e6):
        model = compression_specimen(ROCK, confinement=p, strain_rate=0.01, ramp=2e-3)
        strain = 3.0 * (ROCK.n_phi * p + ROCK.ucs - p) / ROCK.plane_strain_modulus
        run_specimen(model, strain, out=out, name=f"compression_{p / 1e6:g}MPa", stiffness_damping=2e-5)
        r = compression(p)
        print(
            f"confinement {p / 1e6:5.1f} MPa: plateau {r['axial'] / 1e6:7.2f} MPa, N_phi*s3 + UCS = "
            f"{r['expected'] / 1e6:7.2f} MPa ({r['axial'] / r['expected'] - 1:+.2%}); dilation "
            f"{r['dilation']:.4f} vs N_psi {r['n_psi']:.4f} ({r['dilation'] / r['n_psi'] - 1:+.2%})"
        )


if __name__ == "__main__":
    main()
