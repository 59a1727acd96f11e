"""In-situ stress under gravity: a rock column settles to σ_v = ρ g z.

A 100 m column with rollers on its sides and base is loaded by its own
weight and brought to rest with mass damping tuned to its first mode. In
plane strain with no lateral strain, σ_xx = K0 σ_yy with K0 = ν / (1 − ν)
and σ_zz = ν (σ_xx + σ_yy). Writes a VTU series and a picture.

    python examples/lithostatic.py [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import fdem
import numpy as np
from fdem.plot import plot_field


def main(out: str | None = "lithostatic_output", height: float = 100.0, progress: bool = True) -> dict[str, float]:
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    g = 9.81
    mesh = fdem.Mesh.rectangle(20.0, height, 8, 40)
    model = fdem.Model(mesh, material=rock).set_gravity(0.0, -g)
    model.fix("left", x=True, y=False).fix("right", x=True, y=False).fix("bottom", x=False, y=True)
    omega1 = 0.5 * np.pi * rock.p_wave_speed / height  # first mode of the column
    sim = fdem.Simulation(model, mass_damping=2.0 * omega1)
    period = 2 * np.pi / omega1
    sim.run(until=30 * period, output_every=3 * period, output=out, overwrite=True, progress=progress)
    depth = height - mesh.centroids()[:, 1]
    s = sim.stress()
    exact = -rock.rho * g * depth
    error = float(np.abs(s[:, 1] - exact).max() / (rock.rho * g * height))
    k0 = float(np.median(s[:, 0] / s[:, 1]))
    if out is not None:
        plot_field(sim, "stress_yy", Path(out) / "lithostatic.png", title="Vertical stress under gravity")
    print(
        f"σ_yy vs −ρ g z: largest error {error:.2%} of ρ g H; K0 = {k0:.4f} (ν/(1−ν) = {rock.nu / (1 - rock.nu):.4f})"
    )
    return {"max_error": error, "k0": k0, "k0_closed_form": rock.nu / (1 - rock.nu)}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="lithostatic_output")
    main(ap.parse_args().out)
