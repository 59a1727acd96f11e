"""The metrics caving engineers judge a cave by, as pure functions of a
state's arrays (so each can be checked on a constructed state) and one
function that reads them from a caving run (:func:`caving_metrics`;
docs/caving.md, "Caving metrics").

- **Cave back height**: how far above the undercut level the rock over
  the midline has caved: the highest initial elevation, within a band
  about the midline, of rock that has moved down by more than a threshold
  or has fractured through (failure factor 1), measured from the undercut
  level (Brady & Brown 1993, *Rock mechanics for underground mining*, §15:
  the cave back is the boundary between caved and intact rock).
- **Angle of break** on each side: the angle above the horizontal of the
  line from the undercut's edge to the outermost point of the top surface
  that has subsided by more than the threshold (Brady & Brown §15.5; the
  steeper the angle, the narrower the zone of surface disturbance).
- **Subsidence profile**: the top face's vertical displacement against x.
- **Yielded area**: the area of rock that has flowed plastically or
  fractured.
- **Fragment sizes**: equivalent diameters √(4A/π) of the fragments, with
  the sizes P20, P50 and P80 that 20, 50 and 80% of the fragmented area
  passes, leaving out the fragments that touch a side wall (the intact
  abutments).
- **Energy partition**: the shares of the energy supplied since
  equilibrium held as kinetic energy and dissipated by plastic flow,
  fracture, friction and damping.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: Settlement (m) from which rock counts as caved and the surface as
#: disturbed: 0.1 m, well above the elastic settlement of the undercut's
#: first stages (millimetres) and below one element.
SETTLEMENT = 0.1

#: Equivalent plastic strain from which an element counts as yielded.
YIELD_STRAIN = 1e-4

__all__ = [
    "cave_back_height",
    "angles_of_break",
    "subsidence_profile",
    "yielded_area",
    "passing_sizes",
    "caving_metrics",
]


def cave_back_height(
    reference_centroids: NDArray[np.float64],
    settlement: NDArray[np.float64],
    fractured: NDArray[np.bool_],
    *,
    level: float,
    band: float,
    threshold: float,
) -> float:
    """Height (m) above ``level`` of the cave back over the midline: the
    highest initial centroid elevation, among elements within ``band`` m of
    x = 0, of those that have settled (moved down) by more than
    ``threshold`` m or are ``fractured``; 0 where none has."""
    c = np.asarray(reference_centroids, dtype=float)
    caved = (np.abs(c[:, 0]) <= band) & ((np.asarray(settlement) > threshold) | np.asarray(fractured, dtype=bool))
    caved &= c[:, 1] >= level
    return float(c[caved, 1].max() - level) if caved.any() else 0.0


def subsidence_profile(
    top_x: NDArray[np.float64], top_settlement: NDArray[np.float64], edges: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The top face's settlement (m, downwards positive) in bins of x
    (``edges``, m): the largest settlement of the top face's nodes in each
    bin (by their initial x), NaN where a bin holds none."""
    x, s = np.asarray(top_x, dtype=float), np.asarray(top_settlement, dtype=float)
    k = np.searchsorted(edges, x, side="right") - 1
    out = np.full(len(edges) - 1, np.nan)
    for b in range(len(out)):
        sel = k == b
        if sel.any():
            out[b] = float(s[sel].max())
    return out


def angles_of_break(
    top_x: NDArray[np.float64],
    top_settlement: NDArray[np.float64],
    *,
    edges_x: tuple[float, float],
    level: float,
    top: float,
    threshold: float,
) -> tuple[float, float]:
    """Angles of break (degrees above the horizontal) on the left and right:
    from the undercut's edge ``(edges_x[i], level)`` to the outermost top
    face point (initial x in ``top_x``) that has settled by more than
    ``threshold`` m on that side. 90° when the disturbance lies straight
    above the edge or inside it; NaN when nothing on the top face has
    settled that far (the cave has not reached it)."""
    x, s = np.asarray(top_x, dtype=float), np.asarray(top_settlement, dtype=float)
    moved = x[s > threshold]
    if not len(moved):
        return float("nan"), float("nan")
    height = top - level
    left = edges_x[0] - moved.min()  # how far beyond the left edge, outwards
    right = moved.max() - edges_x[1]
    return (
        math.degrees(math.atan2(height, max(left, 0.0))),
        math.degrees(math.atan2(height, max(right, 0.0))),
    )


def yielded_area(
    areas: NDArray[np.float64], plastic_strain: NDArray[np.float64], failure_factor: NDArray[np.float64]
) -> float:
    """Area (m²) of the elements that have flowed plastically (equivalent
    plastic strain above 0) or fractured through (failure factor ≥ 1)."""
    a = np.asarray(areas, dtype=float)
    y = (np.asarray(plastic_strain) > 0) | (np.asarray(failure_factor) >= 1.0)
    return float(a[y].sum())


def passing_sizes(areas: NDArray[np.float64], fractions: tuple[float, ...] = (0.2, 0.5, 0.8)) -> list[float]:
    """Equivalent diameters √(4A/π) (m) that the given fractions of the
    total fragment area pass (area-weighted, as a sieve passes mass): the
    smallest diameter d such that the fragments no larger than d hold at
    least that fraction of the area. NaN without fragments."""
    a = np.sort(np.asarray(areas, dtype=float))
    if not len(a):
        return [float("nan")] * len(fractions)
    d = np.sqrt(4 * a / np.pi)
    passing = np.cumsum(a) / a.sum()
    return [float(d[min(int(np.searchsorted(passing, f - 1e-12)), len(d) - 1)]) for f in fractions]


def caving_metrics(
    sim: Any, *, width: float, bottom: float, top: float, support: float, undercut: float, size: float
) -> dict[str, float]:
    """The metrics of a caving run's current state (see the module): cave
    back height over the midline (band ``max(5 m, size)`` wide each way),
    the angles of break, the largest subsidence of the top face, the
    yielded area (equivalent plastic strain above ``YIELD_STRAIN`` or
    fractured) and the fragment sizes P20/P50/P80 (fragments touching a
    side wall left out), and that fragment count. Settlement counts from
    ``SETTLEMENT`` m."""
    x, x0 = sim.positions(), sim.reference_positions()
    tri = sim.triangles()
    act = sim.active()
    c0 = x0[tri[act]].mean(axis=1)
    settle_e = (x0[tri[act]][:, :, 1] - x[tri[act]][:, :, 1]).mean(axis=1)
    state = sim.element_state()
    ff = state["failure_factor"][act]
    level = bottom + support
    back = cave_back_height(c0, settle_e, ff >= 1.0, level=level, band=max(5.0, size), threshold=SETTLEMENT)
    topn = np.flatnonzero(np.abs(x0[:, 1] - top) < 1e-6 * max(1.0, abs(top)))
    settle_top = x0[topn, 1] - x[topn, 1]
    left, right = angles_of_break(
        x0[topn, 0], settle_top, edges_x=(-0.5 * undercut, 0.5 * undercut), level=level, top=top, threshold=SETTLEMENT
    )
    areas = sim.areas()
    yielded = yielded_area(areas[act], state["equivalent_plastic_strain"][act] - YIELD_STRAIN, ff)
    labels = sim.fragment_labels()[act]
    fragment_area = np.bincount(labels, weights=areas[act]) if len(labels) else np.zeros(0)
    # fragments with a node on a side wall (at its initial place) are the
    # abutments, not caved rock
    wall = np.abs(x0[:, 0]) > 0.5 * width * (1 - 1e-9)
    walled = np.unique(labels[wall[tri[act]].any(axis=1)])
    keep = np.setdiff1d(np.arange(len(fragment_area)), walled)
    p20, p50, p80 = passing_sizes(fragment_area[keep])
    e = sim.energies()
    supplied = abs(e["external_work"]) + abs(e["support_work"]) + e["kinetic_initial"] + e["elastic_initial"]
    share = (lambda v: v / supplied) if supplied > 0 else (lambda v: 0.0)
    return {
        "cave_back_m": back,
        "angle_of_break_left_deg": left,
        "angle_of_break_right_deg": right,
        "subsidence_max_m": float(settle_top.max()) if len(settle_top) else float("nan"),
        "yielded_area_m2": yielded,
        "fragments_free": float(len(keep)),
        "p20_m": p20,
        "p50_m": p50,
        "p80_m": p80,
        # the energy partition: where the energy supplied since equilibrium
        # (work of gravity, loads and supports, and the initial state) went
        "energy_kinetic": share(e["kinetic"]),
        "energy_plastic": share(e["plastic"]),
        "energy_fracture": share(e["fracture"]),
        "energy_friction": share(e["friction"]),
        "energy_damping": share(e["contact_damping"] + e["mass_damping"] + e["viscous_damping"]),
    }
