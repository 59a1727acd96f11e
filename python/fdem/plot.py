"""Pictures of results with matplotlib (Agg, no display needed)."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from .output import cell_fields

if TYPE_CHECKING:
    from .simulation import Simulation

__all__ = ["plot_field", "pyplot", "save_axes"]


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend (files, no display), for
    the pictures fdem writes."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def save_axes(fig: Any, ax: Any, path: str | os.PathLike[str], *, xlabel: str, ylabel: str, title: str) -> None:
    """Labels a one-panel figure (grid, legend), saves it as PNG and
    closes it."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    pyplot().close(fig)


_LABELS = {
    "principal_stress_1": ("first principal stress σ1", "MPa", 1e-6),
    "principal_stress_2": ("second principal stress σ2", "MPa", 1e-6),
    "principal_stress_3": ("third principal stress σ3", "MPa", 1e-6),
    "principal_direction": ("direction of the larger in-plane principal stress", "degrees", 1.0),
    "stress_xx": ("σxx", "MPa", 1e-6),
    "stress_yy": ("σyy", "MPa", 1e-6),
    "stress_zz": ("σzz", "MPa", 1e-6),
    "stress_xy": ("σxy", "MPa", 1e-6),
    "displacement": ("displacement magnitude", "m", 1.0),
    "velocity": ("speed", "m/s", 1.0),
}


def field_values(sim: Simulation, field: str) -> tuple[np.ndarray, bool]:
    """Values of ``field`` per element (cell) or per node, and whether they
    are per node."""
    if field == "displacement":
        return np.linalg.norm(sim.displacements(), axis=1), True
    if field == "velocity":
        return np.linalg.norm(sim.velocities(), axis=1), True
    cells = cell_fields(sim)
    if field.startswith("stress_"):
        k = ["xx", "yy", "zz", "xy"].index(field[len("stress_") :])
        return cells["stress"][:, k], False
    if field not in cells:
        known = sorted([*cells, *_LABELS])
        raise ValueError(f"unknown field {field!r}; known: {known}")
    return np.asarray(cells[field], dtype=float), False


def plot_field(
    sim: Simulation,
    field: str = "principal_stress_1",
    path: str | os.PathLike[str] | None = None,
    *,
    title: str | None = None,
    cmap: str = "turbo",
    limits: tuple[float, float] | None = None,
    show_mesh: bool = False,
    show_interfaces: bool = True,
    ax: Any = None,
) -> Any:
    """Draws a field on the deformed mesh and saves it as PNG if ``path`` is
    given. Returns the matplotlib figure.

    Parameters
    ----------
    field : str
        ``principal_stress_1``, ``stress_xx`` … ``stress_xy``, ``displacement``,
        ``velocity`` or any cell field written to the VTU files.
    limits : (float, float), optional
        Colour range in display units (MPa for stresses).
    show_interfaces : bool
        Draw the faces of joints and cracks (black lines).
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    x = sim.positions()
    tri = sim.triangles()
    active = sim.active()
    values, per_node = field_values(sim, field)
    label, unit, scale = _LABELS.get(field, (field, "", 1.0))
    t = Triangulation(x[:, 0], x[:, 1], tri, mask=~active)
    if ax is None:
        xmin, ymin = x.min(axis=0)
        xmax, ymax = x.max(axis=0)
        aspect = (ymax - ymin) / max(xmax - xmin, 1e-30)
        if aspect <= 1:
            size = (9.0, max(2.5, 7.5 * aspect + 1.5))
        else:
            size = (max(3.5, 7.5 / aspect + 2.5), 9.0)
        fig, ax = plt.subplots(figsize=size, dpi=110)
    else:
        fig = ax.figure
    kw: dict[str, Any] = {"cmap": cmap}
    if limits is not None:
        kw["vmin"], kw["vmax"] = limits
    if per_node:
        art = ax.tripcolor(t, values * scale, shading="gouraud", **kw)
    else:
        art = ax.tripcolor(t, facecolors=values * scale, **kw)
    if show_mesh:
        ax.triplot(t, color="k", lw=0.2, alpha=0.4)
    if show_interfaces:
        facets, laws = sim.surface_facets()
        segs = x[facets[laws > 0]]
        if len(segs):
            from matplotlib.collections import LineCollection

            ax.add_collection(LineCollection(segs, colors="k", linewidths=0.4, alpha=0.7))
    fig.colorbar(art, ax=ax, label=f"{label} ({unit})" if unit else label, shrink=0.85)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or f"{label} at t = {sim.time:.4g} s")
    fig.tight_layout()
    if path is not None:
        fig.savefig(os.fspath(path))
        plt.close(fig)
    return fig
