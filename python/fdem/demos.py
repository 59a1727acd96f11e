"""The demonstration case run by ``fdem demo``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .materials import Elastic
from .mesh import Mesh
from .model import Model
from .plot import plot_field
from .simulation import Simulation

__all__ = ["run_demo"]


def run_demo(out: Path, *, quick: bool = True, progress: bool = True) -> Simulation:
    """A rock block (Table 1 elastic constants of the paper) loaded by its own
    weight and 15.2 MPa on its top face, rollers on the sides and base,
    settling to its in-situ stress. Writes a VTU series with a ``.pvd`` index
    and ``demo.png`` into ``out``."""
    rock = Elastic(E=60e9, nu=0.25, rho=3100.0)
    width, height = 200.0, 100.0
    nx, ny = (40, 20) if quick else (200, 100)
    mesh = Mesh.rectangle(width, height, nx, ny)
    model = Model(mesh, material=rock).set_gravity(0.0, -30.41e3 / rock.rho)
    model.fix("left", x=True, y=False).fix("right", x=True, y=False).fix("bottom", x=False, y=True)
    model.pressure("top", 15.2e6)
    omega1 = 0.5 * np.pi * rock.p_wave_speed / height
    sim = Simulation(model, mass_damping=2.0 * omega1)
    period = 2 * np.pi / omega1
    sim.run(until=20 * period, output_every=2 * period, output=out, name="demo", overwrite=True, progress=progress)
    picture = Path(out) / "demo.png"
    plot_field(sim, "stress_yy", picture, title="In-situ vertical stress (15.2 MPa top load + gravity)")
    print(f"wrote {out}/demo.pvd (open in ParaView) and {picture}")
    return sim
