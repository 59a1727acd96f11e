"""fdem: a 2D combined finite–discrete element simulator for brittle rock.

Implements Ecsi & Élesztős (2003): constant-strain triangles with explicit
central-difference dynamics and a co-rotational stress update, run by a
parallel Rust kernel. SI units throughout; stress tension positive, stored as
``[xx, yy, zz, xy]``.

Typical use::

    import fdem
    mesh = fdem.Mesh.rectangle(10.0, 5.0, 40, 20)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100))
    model.set_gravity(0.0, -9.81).fix("bottom", y=True).fix("left", x=True).fix("right", x=True)
    sim = fdem.Simulation(model, mass_damping=50.0)
    sim.run(until=0.5, output_every=0.05, output="results")
"""

from . import errors
from ._core import __version__
from .contact import Interface
from .errors import (
    CheckpointError,
    EnergyBalanceError,
    EnergyBalanceWarning,
    EnergyGrowthError,
    InvertedElementError,
    NonFiniteError,
    PlausibilityWarning,
    SimulationError,
)
from .joints import JointSet, clean_traces, jointed_rectangle
from .laboratory import MaterialPointResult, material_point
from .materials import Elastic, MohrCoulombRankine
from .mesh import Mesh, gmsh_rectangle
from .model import Amplitude, Model
from .output import VtuSeries, principal_stresses, write_vtu
from .simulation import Simulation

__all__ = [
    "Amplitude",
    "CheckpointError",
    "Elastic",
    "EnergyBalanceError",
    "EnergyBalanceWarning",
    "PlausibilityWarning",
    "EnergyGrowthError",
    "MaterialPointResult",
    "MohrCoulombRankine",
    "Interface",
    "InvertedElementError",
    "JointSet",
    "Mesh",
    "Model",
    "NonFiniteError",
    "Simulation",
    "SimulationError",
    "VtuSeries",
    "__version__",
    "clean_traces",
    "errors",
    "gmsh_rectangle",
    "jointed_rectangle",
    "material_point",
    "principal_stresses",
    "write_vtu",
]
