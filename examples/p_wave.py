"""A compression wave in a rock bar: the P-wave speed √((λ + 2G)/ρ).

A 20 m bar with rollers on its long sides (so the strain is uniaxial) is hit
at its left end by a velocity step of 0.1 m/s. The example follows the front
and compares its speed with the closed form.

    python examples/p_wave.py [--out DIR]
"""

from __future__ import annotations

import argparse

import fdem
import numpy as np


def main(out: str | None = None, length: float = 20.0, cells: int = 400, progress: bool = False) -> dict[str, float]:
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    mesh = fdem.Mesh.rectangle(length, 0.5, cells, 2)
    model = fdem.Model(mesh, material=rock)
    model.fix("top", x=False, y=True).fix("bottom", x=False, y=True)
    model.prescribe_velocity("left", vx=0.1)
    sim = fdem.Simulation(model, safety=0.9)
    station = int(np.argmin(np.hypot(mesh.points[:, 0] - 0.5 * length, mesh.points[:, 1])))
    x_station = float(mesh.points[station, 0])
    arrival = np.nan
    previous = (0.0, 0.0)
    c_p = rock.p_wave_speed
    while sim.time < 0.75 * length / c_p:
        sim.step(1)
        v = float(sim.velocities()[station, 0])
        if np.isnan(arrival) and v >= 0.05:
            t0, v0 = previous
            arrival = t0 + (0.05 - v0) * (sim.time - t0) / (v - v0)
        previous = (sim.time, v)
    if out is not None:
        sim.write_vtu(f"{out}/p_wave.vtu")
    measured = x_station / arrival
    print(f"P-wave speed: measured {measured:.1f} m/s, closed form {c_p:.1f} m/s ({measured / c_p - 1:+.2%})")
    return {"measured": measured, "closed_form": c_p}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None, help="directory for a VTU of the final state")
    main(ap.parse_args().out)
