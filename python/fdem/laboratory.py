"""Calibration tools: a single material point driven along a strain path, and
virtual laboratory specimens (plane-strain compression, triaxial, tension).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _core
from ._checks import float_array, positive
from .materials import Elastic
from .mesh import Mesh
from .model import Amplitude, Model
from .output import write_csv
from .plot import pyplot, save_axes

__all__ = [
    "MaterialPointResult",
    "material_point",
    "compression_specimen",
    "tension_specimen",
    "run_specimen",
    "SpecimenResult",
    "brazilian_disc",
    "run_brazilian",
    "BrazilianResult",
]


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


#: Elastic steel of the loading jaws and platens (Pa, kg/m³).
STEEL = Elastic(E=200e9, nu=0.3, rho=7800.0)


def brazilian_disc(
    material: Elastic,
    *,
    diameter: float = 0.05,
    elements_across_radius: int = 16,
    loading: str = "jaws",
    speed: float = 0.05,
    ramp: float = 2e-4,
    friction: float = 10.0,
    loader: Elastic = STEEL,
    interface: Any = None,
    refine: int = 4,
    pole: float = np.radians(15.0),
) -> Model:
    """A Brazilian (indirect tension) disc between two loaders, as a model
    ready to run (:func:`run_brazilian`).

    The disc of ``diameter`` (m) is meshed with triangles of about
    ``radius / elements_across_radius``. ``loading`` is ``"jaws"``, the
    ISRM curved jaws (ISRM 1978, suggested method for the Brazilian test:
    a concave face of radius 1.5 R, which meets the disc over an arc of
    2α ≈ 10–15° near failure), or ``"platens"``, flat platens (a line
    load that spreads only as the contact flattens). The loaders are
    elastic ``loader`` bodies meeting the disc by frictional contact
    (``friction`` in degrees, a dashpot of ξ = 0.5), touching it at the
    start. The loaders close on the disc from both sides, each at half
    ``speed`` (m/s, the rate of closure), reached over ``ramp`` (s): the
    disc's centre stays at rest, where a disc pushed by one loader onto a
    fixed one would first fly across the gap and ring from the impact.

    Near the poles, within ``pole`` (rad) of the loaded diameter, the
    disc's rim and the loaders' faces are divided ``refine`` times finer
    and the mesh grades out from there. The loaders meet the disc over a
    strip the uniform mesh cannot resolve: for this rock (E = 30 GPa) at
    the peak, Hertz's half width for a 1.5 R jaw is 0.9 mm, under one
    element of 16 across the radius, so the whole load sat on one node
    pair, and the spurious tension it makes in the elements around that
    node (σxx ≈ 2× the centre's) cracked the disc under the jaw at 0.64 of
    the peak. With the rim 4 times finer there, the first crack starts at
    the centre on 8, 16 and 32 elements across the radius
    (docs/fracture.md, "The Brazilian test").

    Node sets: ``loader_top`` and ``loader_bottom`` (the driven nodes of
    the loaders: their reactions are the load); element sets ``disc``,
    ``top``, ``bottom``. Run it with :func:`run_brazilian`.
    """
    from .contact import Interface

    d = positive("diameter", diameter)
    r = 0.5 * d
    n = int(elements_across_radius)
    if n < 4:
        raise ValueError(f"elements_across_radius must be at least 4, got {elements_across_radius}")
    if loading not in ("jaws", "platens"):
        raise ValueError(f"loading must be 'jaws' or 'platens', not {loading!r}")
    size = r / n
    # a vertex at each pole (k a multiple of 4): the loaders touch the
    # disc there at the start, not a chord a fraction of a mm lower
    k = 4 * max(3, int(np.ceil(2 * np.pi * r / size / 4)))
    a = 2 * np.pi * np.arange(k) / k
    if refine > 1:
        # the rim divided ``refine`` times finer within ``pole`` of each
        # pole, where the loaders touch; the mesh grades out from there
        near = np.minimum(np.abs(a - 0.5 * np.pi), np.abs(a - 1.5 * np.pi)) < pole - 1e-12
        fine = [a]
        for j in np.flatnonzero(near):
            fine.append(a[j] + (2 * np.pi / k) * np.arange(1, refine) / refine)
        a = np.sort(np.concatenate(fine))
    disc = Mesh.polygon(np.column_stack([r * np.cos(a), r * np.sin(a)]), size)
    half = 0.45 * r  # the loaders' half width
    height = 0.3 * r
    # the loaders: structured grids mapped onto their contact face (the
    # ISRM jaw's concave arc of radius 1.5 R about a centre on the disc's
    # axis, or a flat face), as fine along it as the disc's rim there
    nx = 2 * int(np.ceil(half * refine / size))
    ny = max(2, int(np.ceil(height / size)))
    grid = Mesh.rectangle(2 * half, 1.0, nx, ny, origin=(-half, 0.0))
    gx, gt = grid.points[:, 0], grid.points[:, 1]
    if loading == "jaws":
        rj = 1.5 * r
        face = r - (rj - np.sqrt(rj**2 - gx**2))
    else:
        face = np.full_like(gx, r)
    top_y = r + height
    mapped = np.column_stack([gx, face + gt * (top_y - face)])
    top = Mesh(mapped, grid.triangles)
    bottom = Mesh(mapped * np.array([1.0, -1.0]), grid.triangles[:, ::-1])
    parts = [
        m.with_sets(element_sets={name: np.arange(m.n_elements)})
        for m, name in ((disc, "disc"), (top, "top"), (bottom, "bottom"))
    ]
    mesh = Mesh.combine(*parts)
    driven = np.flatnonzero(np.abs(mesh.points[:, 1] - top_y) < 1e-9 * d)
    held = np.flatnonzero(np.abs(mesh.points[:, 1] + top_y) < 1e-9 * d)
    mesh = mesh.with_sets(node_sets={"loader_top": driven, "loader_bottom": held})
    model = Model(mesh, materials={"disc": material, "top": loader, "bottom": loader})
    v = 0.5 * positive("speed", speed)
    ramp_up = Amplitude.ramp(positive("ramp", ramp))
    model.prescribe_velocity("loader_top", vx=0.0, vy=-v, amplitude=ramp_up)
    model.prescribe_velocity("loader_bottom", vx=0.0, vy=v, amplitude=ramp_up)
    model.contact(interface if interface is not None else Interface(friction=friction, damping=0.5))
    if hasattr(material, "ft"):
        model.fracture()
    return model


@dataclass(frozen=True)
class BrazilianResult:
    """What a Brazilian test gives (:func:`run_brazilian`).

    Attributes
    ----------
    diameter : float
        D (m).
    time, closure, load : (k,) arrays
        Samples: simulated time (s), the loaders' closure (m, the travel of
        their driven faces towards each other) and the load P (N per unit
        thickness: the mean of the forces the disc exerts on the two
        loaders).
    centre_stress, centre_reference : (k,) arrays
        σxx averaged over the disc's elements within 0.15 R of its centre
        (Pa), and the same average of the elastic solution for two
        diametral point loads P (Timoshenko & Goodier, §41: σxx at the
        centre itself is 2P/(πD)); equal within the discretisation before
        the first crack.
    peak_load : float
        The largest load (N/m).
    tensile_strength : float
        2 P_peak / (π D) (Pa), the indirect tensile strength (ISRM 1978).
    first_crack : dict or None
        ``time``, ``load`` and ``position`` (m, the centroid of the
        elements cut by the first insertion), or None without a crack.
    simulation : fdem.Simulation
        The run, at its end.
    """

    diameter: float
    time: NDArray[np.float64]
    closure: NDArray[np.float64]
    load: NDArray[np.float64]
    centre_stress: NDArray[np.float64]
    centre_reference: NDArray[np.float64]
    peak_load: float
    tensile_strength: float
    first_crack: dict[str, Any] | None
    simulation: Any

    def write(self, out: str | os.PathLike[str]) -> list[Path]:
        """Writes ``brazilian.csv`` (the samples) and ``brazilian.png``
        (load against closure, the first crack and the peak marked) into
        ``out``; returns their paths."""
        plt = pyplot()
        d = Path(out)
        d.mkdir(parents=True, exist_ok=True)
        table = write_csv(
            d / "brazilian.csv",
            ["time_s", "closure_m", "load_N_per_m", "centre_sxx_Pa", "centre_sxx_elastic_Pa"],
            zip(self.time, self.closure, self.load, self.centre_stress, self.centre_reference, strict=True),
        )
        picture = d / "brazilian.png"
        fig, ax = plt.subplots(figsize=(6.5, 4.5), dpi=110)
        ax.plot(self.closure * 1e6, self.load / 1e3, label="load")
        k = int(np.argmax(self.load))
        ax.plot(
            [self.closure[k] * 1e6],
            [self.peak_load / 1e3],
            "r*",
            ms=10,
            label=f"peak: 2P/(πD) = {self.tensile_strength / 1e6:.2f} MPa",
        )
        if self.first_crack is not None:
            j = int(np.searchsorted(self.time, self.first_crack["time"]))
            j = min(j, len(self.time) - 1)
            ax.plot([self.closure[j] * 1e6], [self.first_crack["load"] / 1e3], "ko", mfc="none", label="first crack")
        save_axes(
            fig,
            ax,
            picture,
            xlabel="closure of the loaders (µm)",
            ylabel="load P (kN per m thickness)",
            title=f"Brazilian test, D = {self.diameter * 1e3:.0f} mm",
        )
        return [table, picture]


def run_brazilian(
    model: Model,
    *,
    out: str | os.PathLike[str] | None = None,
    threads: int | None = None,
    max_closure: float | None = None,
    samples: int = 400,
    stop_at: float = 0.5,
) -> BrazilianResult:
    """Runs a Brazilian disc model of :func:`brazilian_disc` until the load
    has fallen below ``stop_at`` of its peak after cracking, or the loaders
    have closed by ``max_closure`` (m; default 0.002 D), sampling the load
    ``samples`` times over that closure; writes the curve and its picture
    into ``out`` if given (:meth:`BrazilianResult.write`)."""
    from .simulation import Simulation

    mesh = model.mesh
    disc = mesh.elements("disc")
    pts = mesh.points[np.unique(mesh.triangles[disc])]
    radius = float(np.hypot(*pts.T).max())
    diameter = 2 * radius
    driven = {}
    for c in model._constraints:
        for name in ("loader_top", "loader_bottom"):
            if np.array_equal(c.nodes, mesh.nodes(name)):
                driven[name] = c
    if len(driven) != 2:
        raise ValueError(
            "run_brazilian needs a model of brazilian_disc (loaders driven at loader_top and loader_bottom)"
        )
    # the rate at which the loaders close, and the time they take to reach it
    speed = sum(abs(float(np.asarray(c.value)[..., 1].max())) for c in driven.values())
    ramp = max(c.amplitude.times[-1] if c.amplitude is not None else 0.0 for c in driven.values())
    closure_max = positive("max_closure", max_closure) if max_closure is not None else 2e-3 * diameter
    until = ramp + closure_max / speed
    dt_sample = until / int(samples)
    centre = disc[np.hypot(*mesh.centroids()[disc].T) < 0.15 * radius]
    sim = Simulation(model, threads=threads)
    n0 = sim.n_elements
    rows: list[list[float]] = []
    peak, first = 0.0, None
    while sim.time < until:
        sim.run(until=sim.time + dt_sample, progress=False, checkpoint=False)
        up, down = sim.reaction("loader_top"), sim.reaction("loader_bottom")
        load = 0.5 * (up["force"][1] - down["force"][1])
        closure = down["displacement"][1] - up["displacement"][1]
        s, a = sim.stress(), sim.areas()
        xc = sim.positions()[sim.triangles()[centre]].mean(axis=1)
        reference = _area_mean(a[centre], _point_loads_sxx(xc, load, radius))
        rows.append([sim.time, closure, load, _area_mean(a[centre], s[centre, 0]), reference])
        if first is None and sim.insertions:
            new = np.arange(n0, sim.n_elements)
            where = sim.positions()[sim.triangles()[new]].mean(axis=1).mean(axis=0)
            first = {"time": sim.time, "load": load, "position": where}
        peak = max(peak, load)
        if sim.insertions and load < stop_at * peak:
            break
    data = np.array(rows)
    result = BrazilianResult(
        diameter=diameter,
        time=data[:, 0],
        closure=data[:, 1],
        load=data[:, 2],
        centre_stress=data[:, 3],
        centre_reference=data[:, 4],
        peak_load=peak,
        tensile_strength=2 * peak / (np.pi * diameter),
        first_crack=first,
        simulation=sim,
    )
    if out is not None:
        result.write(out)
    return result


def _area_mean(area: NDArray[np.float64], values: NDArray[np.float64]) -> float:
    return float(np.sum(area * values) / np.sum(area))


def _point_loads_sxx(xy: NDArray[np.float64], load: float, radius: float) -> NDArray[np.float64]:
    """σxx (Pa) at ``xy`` of a disc of ``radius`` under two diametral point
    loads ``load`` (N/m) on the y axis (Timoshenko & Goodier, Theory of
    Elasticity, §41); 2P/(πD) at the centre."""
    x, y = xy[:, 0], xy[:, 1]
    r1, r2 = x**2 + (radius - y) ** 2, x**2 + (radius + y) ** 2
    return -(2 * load / np.pi) * ((radius - y) * x**2 / r1**2 + (radius + y) * x**2 / r2**2 - 1 / (2 * radius))


def tension_specimen(
    material: Elastic,
    *,
    width: float = 0.05,
    height: float = 0.1,
    cells: tuple[int, int] = (8, 16),
    strain_rate: float = 0.01,
    ramp: float = 2e-4,
) -> Model:
    """A plane-strain direct-tension specimen: the base is held vertically
    (its left corner also horizontally), the top pulled up at
    ``strain_rate × height`` (m/s), reached over ``ramp`` (s); the sides
    are free. Run it with :func:`run_specimen`; with a
    :class:`MohrCoulombRankine` material crack insertion is on (contact on
    the crack faces, DESIGN §4.5), so the specimen breaks."""
    from .contact import Interface

    w, h = positive("width", width), positive("height", height)
    mesh = Mesh.rectangle(w, h, cells[0], cells[1])
    model = Model(mesh, material=material)
    model.fix("bottom", x=False, y=True).fix("lower_left", x=True, y=True)
    model.prescribe_velocity(
        "top", vy=positive("strain_rate", strain_rate) * h, amplitude=Amplitude.ramp(positive("ramp", ramp))
    )
    if hasattr(material, "ft"):
        model.contact(Interface(friction=30.0)).fracture()
    return model


@dataclass(frozen=True)
class SpecimenResult:
    """A specimen test's curves (:func:`run_specimen`).

    Attributes
    ----------
    kind : str
        ``"compression"`` or ``"tension"`` (the sense of the top platen).
    time, strain, stress : (k,) arrays
        Samples: simulated time (s), axial strain (the top's travel over
        the height, positive in the loading sense) and axial stress (Pa,
        the load on the top platen over the width, positive in the
        loading sense: compressive in compression, tensile in tension).
    lateral_strain : (k,) array
        Mean travel of the right side minus the left over the width
        (positive outwards).
    cracks : (k,) array of int
        Crack insertions so far.
    peak_stress, peak_strain : float
        The largest axial stress (Pa) and the strain where it was reached.
    simulation : fdem.Simulation
        The run, at its end.
    """

    kind: str
    time: NDArray[np.float64]
    strain: NDArray[np.float64]
    stress: NDArray[np.float64]
    lateral_strain: NDArray[np.float64]
    cracks: NDArray[np.int64]
    peak_stress: float
    peak_strain: float
    simulation: Any

    def write(self, out: str | os.PathLike[str], name: str = "specimen") -> list[Path]:
        """Writes ``{name}.csv`` (the samples) and ``{name}.png`` (stress
        against strain, the peak marked) into ``out``; returns their
        paths."""
        plt = pyplot()
        d = Path(out)
        d.mkdir(parents=True, exist_ok=True)
        table = write_csv(
            d / f"{name}.csv",
            ["time_s", "axial_strain", "axial_stress_Pa", "lateral_strain", "cracks"],
            zip(self.time, self.strain, self.stress, self.lateral_strain, self.cracks, strict=True),
        )
        picture = d / f"{name}.png"
        fig, ax = plt.subplots(figsize=(6.5, 4.5), dpi=110)
        ax.plot(self.strain * 1e3, self.stress / 1e6, label=f"{self.kind}")
        ax.plot(
            [self.peak_strain * 1e3],
            [self.peak_stress / 1e6],
            "r*",
            ms=10,
            label=f"peak {self.peak_stress / 1e6:.2f} MPa",
        )
        sense = "compression" if self.kind == "compression" else "tension"
        save_axes(
            fig,
            ax,
            picture,
            xlabel="axial strain (‰)",
            ylabel=f"axial stress (MPa, {sense} positive)",
            title=f"{self.kind.capitalize()} specimen: {int(self.cracks[-1])} cracks at the end",
        )
        return [table, picture]


def run_specimen(
    model: Model,
    until_strain: float,
    *,
    samples: int = 100,
    out: str | os.PathLike[str] | None = None,
    name: str = "specimen",
    threads: int | None = None,
    stiffness_damping: float = 0.0,
) -> SpecimenResult:
    """Runs a specimen of :func:`compression_specimen` or
    :func:`tension_specimen` until its axial strain is ``until_strain``,
    taking ``samples`` samples of the load on the top platen
    (:meth:`fdem.Simulation.reaction`) and the strains; writes
    ``{name}.csv`` and ``{name}.png`` into ``out`` if given."""
    from .simulation import Simulation

    mesh = model.mesh
    top = mesh.nodes("top")
    drive = [c for c in model._constraints if np.array_equal(c.nodes, top)]
    if not drive:
        raise ValueError("run_specimen needs a specimen model (a top platen with a prescribed velocity)")
    v = float(np.asarray(drive[-1].value)[..., 1].max())
    ramp = drive[-1].amplitude.times[-1] if drive[-1].amplitude is not None else 0.0
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    width, height = float(hi[0] - lo[0]), float(hi[1] - lo[1])
    sense = 1.0 if v > 0 else -1.0  # +1 tension, −1 compression
    until = 0.5 * ramp + positive("until_strain", until_strain) * height / abs(v)
    sim = Simulation(model, threads=threads, stiffness_damping=stiffness_damping)
    left, right = mesh.nodes("left"), mesh.nodes("right")
    rows = []
    for k in range(1, int(samples) + 1):
        sim.run(until=until * k / samples, progress=False, checkpoint=False)
        r = sim.reaction("top")
        u = sim.displacements()
        lateral = (u[right, 0].mean() - u[left, 0].mean()) / width
        rows.append(
            [sim.time, sense * r["displacement"][1] / height, -sense * r["force"][1] / width, lateral, sim.insertions]
        )
    data = np.array(rows)
    k = int(np.argmax(data[:, 2]))
    result = SpecimenResult(
        kind="tension" if sense > 0 else "compression",
        time=data[:, 0],
        strain=data[:, 1],
        stress=data[:, 2],
        lateral_strain=data[:, 3],
        cracks=data[:, 4].astype(np.int64),
        peak_stress=float(data[k, 2]),
        peak_strain=float(data[k, 1]),
        simulation=sim,
    )
    if out is not None:
        result.write(out, name)
    return result
