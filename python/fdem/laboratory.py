"""Calibration tools: a single material point driven along a strain path, and
virtual laboratory specimens (plane-strain compression, triaxial, tension).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _core
from ._checks import float_array, positive
from .materials import Elastic
from .mesh import Mesh
from .model import Amplitude, Model

__all__ = ["MaterialPointResult", "material_point", "compression_specimen"]


@dataclass(frozen=True)
class MaterialPointResult:
    """The history of a material point: ``n + 1`` states for ``n`` steps.

    Attributes
    ----------
    stress : (n+1, 4) array
        Cauchy stress ``[xx, yy, zz, xy]`` (Pa, tension positive).
    plastic_strain : (n+1, 4) array
        Plastic strain (co-rotational frame, tensor shear).
    kappa, equivalent_plastic_strain, failure_factor : (n+1,) arrays
        Fracturing strain κ, accumulated equivalent plastic strain, κ H / f_t.
    active : (n,) array of uint8
        Active set of each step (bits: 1 MC main plane, 2 MC σ1–σ2, 4 MC σ2–σ3,
        8/16/32 Rankine σ1/σ2/σ3); 0 for an elastic step.
    plastic_dissipation, fracture_dissipation : (n,) arrays
        Dissipation of each step (J/m³).
    """

    stress: NDArray[np.float64]
    plastic_strain: NDArray[np.float64]
    kappa: NDArray[np.float64]
    equivalent_plastic_strain: NDArray[np.float64]
    failure_factor: NDArray[np.float64]
    active: NDArray[np.uint8]
    plastic_dissipation: NDArray[np.float64]
    fracture_dissipation: NDArray[np.float64]


def material_point(
    material: Elastic,
    *,
    strain_increments: Any = None,
    deformation_gradients: Any = None,
    initial_stress: Any = (0.0, 0.0, 0.0, 0.0),
    element_size: float = 1.0,
) -> MaterialPointResult:
    """Drives one material point of ``material`` along a path.

    Parameters
    ----------
    material : Elastic or MohrCoulombRankine
        The material.
    strain_increments : array_like, shape (n, 3)
        ``[Δε_xx, Δε_yy, Δε_xy]`` per step (tensor shear; plane strain,
        ``ε_zz = 0``), applied without rotation. Give this or
        ``deformation_gradients``.
    deformation_gradients : array_like, shape (n, 2, 2) or (n, 4)
        Deformation gradients ``F`` at successive instants from ``F = I``;
        rotations are handled by the elements' co-rotational update.
    initial_stress : (4,) array_like
        Cauchy stress at the start ``[xx, yy, zz, xy]`` (Pa).
    element_size : float
        Crack-band width ``h_c`` (m) the point softens over: the size of the
        element it represents.

    Returns
    -------
    MaterialPointResult
    """
    if not isinstance(material, Elastic):
        raise ValueError(f"material must be a fdem material, got {type(material).__name__}")
    if (strain_increments is None) == (deformation_gradients is None):
        raise ValueError("give exactly one of strain_increments and deformation_gradients")
    s0 = float_array("initial_stress", initial_stress, (4,))
    kw: dict[str, Any] = {}
    if strain_increments is not None:
        kw["strain_increments"] = float_array("strain_increments", strain_increments, (None, 3))
    else:
        f = np.asarray(deformation_gradients, dtype=float)
        if f.ndim == 3:
            f = float_array("deformation_gradients", f, (None, 2, 2)).reshape(-1, 4)
        kw["deformation_gradients"] = float_array("deformation_gradients", f, (None, 4))
    out = _core.material_point(material._kernel_dict(), tuple(s0), positive("element_size", element_size), **kw)
    return MaterialPointResult(**out)


def compression_specimen(
    material: Elastic,
    *,
    width: float = 1.0,
    height: float = 2.0,
    cells: tuple[int, int] = (8, 16),
    confinement: float = 0.0,
    strain_rate: float = 0.01,
    ramp: float = 2e-3,
) -> Model:
    """A plane-strain specimen between frictionless platens.

    The base is held vertically (its left corner also horizontally); the top
    platen moves down at ``strain_rate × height`` (m/s), reached over a
    linear ``ramp`` (s) so that no stress wave rings on the plateau; the
    sides carry a confining pressure ``confinement`` (Pa, compression
    positive) with the matching initial stress. Quasi-static needs
    ``strain_rate`` far below the specimen's first frequency; inertia of the
    plastic dilation otherwise adds a lateral compression that ``N_φ``
    magnifies (0.01/s keeps it under 0.3%).
    """
    w, h = positive("width", width), positive("height", height)
    mesh = Mesh.rectangle(w, h, cells[0], cells[1])
    model = Model(mesh, material=material)
    model.fix("bottom", x=False, y=True).fix("lower_left", x=True, y=True)
    model.prescribe_velocity(
        "top", vy=-positive("strain_rate", strain_rate) * h, amplitude=Amplitude.ramp(positive("ramp", ramp))
    )
    if confinement:
        p = positive("confinement", confinement)
        model.pressure("left", p).pressure("right", p)
        model.set_initial_stress((-p, -p, -2 * material.nu * p, 0.0))
    return model
