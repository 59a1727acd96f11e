"""The paper's Table 2 beside fdem's caving run: where its nine points lie
in the model, the stresses there, and the vertical stress across the
abutments (Ecsi & Élesztős 2003, §4.2; docs/caving.md, "Table 2 side by
side", gives the reasoning for the frame and the comparison).

The paper lists stresses at nine nodes at 3.5 s with coordinates x from 0
to 77.58 m and y from −533.76 to −478 m, but does not say where its origin
is. :data:`FRAMES` are the two readings; ``"left"`` (x measured from the
block's left side, so the undercut runs from x = 20 to 180 m) is the one
the paper's own numbers support, and the default of
:class:`fdem.caving.CavingCase`. In both, y is the model's own elevation
(the block spans y = −534 to −434 m). The model is symmetric but its joint
pattern is not, so every point is also read at its mirror image across
the midline, with σxy's sign turned: the spread between the two is what
the realisation alone makes of the same physics.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .output import stress_at
from .plot import pyplot, save_axes

if TYPE_CHECKING:
    from .simulation import Simulation

__all__ = [
    "PAPER_TABLE2",
    "FRAMES",
    "ABUTMENT_LINE",
    "probe_points",
    "probe_stress",
    "stress_profile",
    "abutment_peaks",
]

#: Table 2 of the paper at 3.5 s: node, x (m), y (m), σxx, σyy, σzz, σxy (MPa).
PAPER_TABLE2: tuple[tuple[str, float, float, float, float, float, float], ...] = (
    ("91693", 77.58, -533.76, -1.298, -1.107, -0.792, -0.611),
    ("91953", 67.44, -529.09, 0.011, 0.074, -0.335, 0.087),
    ("3320", 51.00, -520.00, -1.535, 0.015, -0.236, -0.613),
    ("63098", 38.20, -520.40, -9.079, -5.526, -3.651, -6.747),
    ("19556", 27.71, -514.65, -9.312, -34.463, -10.944, -12.985),
    ("16475", 16.00, -507.00, -20.551, -51.560, -18.028, -10.029),
    ("12485", 16.00, -495.00, -30.486, -63.564, -23.512, 3.075),
    ("11496", 8.00, -481.00, -23.092, -17.362, -10.113, 3.266),
    ("1911", 0.00, -478.00, -21.642, -0.274, -5.479, 1.536),
)

#: Readings of the paper's x: ``"left"``, x from the block's left side
#: (model x = x − width/2); ``"centred"``, x from the midline (model x = x).
FRAMES = ("left", "centred")

#: The horizontal line (m, model y) along which the abutment stress is read:
#: midway between the paper's two abutment points at x = 16 m (y = −507 and
#: −495 m).
ABUTMENT_LINE = -501.0


def probe_points(frame: str, width: float) -> NDArray[np.float64]:
    """The Table 2 points in model coordinates (m), shape (9, 2), for the
    reading ``frame`` (:data:`FRAMES`) of a block ``width`` m wide centred
    on x = 0."""
    if frame not in FRAMES:
        raise ValueError(f"probe_frame must be one of {FRAMES}, not {frame!r}")
    shift = -0.5 * width if frame == "left" else 0.0
    return np.array([[x + shift, y] for _, x, y, *_ in PAPER_TABLE2])


def probe_stress(sim: Simulation, points: Any) -> NDArray[np.float64]:
    """Stress ``[xx, yy, zz, xy]`` (Pa) at each point, NaN in a void
    (:func:`fdem.output.stress_at`): a CST element's stress is the value
    the paper's nodal output would average over the elements at a node."""
    return stress_at(sim, points)


def stress_profile(sim: Simulation, y: float, x_edges: NDArray[np.float64], half_height: float) -> NDArray[np.float64]:
    """Stress ``[xx, yy, zz, xy]`` (Pa) along the horizontal line ``y`` (m):
    the area-weighted mean over the active elements whose centroid lies in
    each box ``[x_edges[i], x_edges[i+1]) × [y − half_height, y + half_height]``
    (current configuration), shape (len(x_edges) − 1, 4); NaN where a box
    holds no element. Averaging over a box of a few elements reads the
    smooth field that CST's element-wise constant stress samples."""
    act = np.flatnonzero(sim.active())
    corners = sim.positions()[sim.triangles()[act]]
    cen = corners.mean(axis=1)
    d1, d2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    n = len(x_edges) - 1
    box = np.searchsorted(x_edges, cen[:, 0], side="right") - 1
    inside = (box >= 0) & (box < n) & (np.abs(cen[:, 1] - y) <= half_height)
    box, w = box[inside], area[inside]
    s = sim.stress()[act[inside]]
    total = np.bincount(box, weights=w, minlength=n)
    out = np.full((n, 4), np.nan)
    hit = total > 0
    for k in range(4):
        out[hit, k] = np.bincount(box, weights=w * s[:, k], minlength=n)[hit] / total[hit]
    return out


def abutment_peaks(
    sim: Simulation, *, width: float, undercut: float, size: float, lithostatic: float, y: float = ABUTMENT_LINE
) -> dict[str, float]:
    """The vertical-stress concentration in each abutment: along the line
    ``y`` (boxes ``size`` m wide and ``2 size`` m tall, :func:`stress_profile`),
    the most compressive σyy (Pa) between the undercut's edge (``±undercut/2``)
    and the side wall, where it lies (m), and its ratio to the lithostatic
    σyy there (``lithostatic``, Pa, negative): the abutment concentration
    factor (Brady & Brown 1993, ch. 15: the load the undercut no longer
    carries moves to the rock beside it). Keys ``left_syy``, ``left_x``,
    ``left_factor`` and the same for ``right``; NaN where an abutment holds
    no rock on the line."""
    edges = np.arange(-0.5 * width, 0.5 * width + 0.5 * size, size)
    centres = 0.5 * (edges[1:] + edges[:-1])
    syy = stress_profile(sim, y, edges, size)[:, 1]
    out: dict[str, float] = {}
    for side, mask in (("left", centres <= -0.5 * undercut), ("right", centres >= 0.5 * undercut)):
        vals = np.where(mask & np.isfinite(syy), syy, np.inf)
        k = int(np.argmin(vals))
        if np.isfinite(vals[k]):
            out[f"{side}_syy"], out[f"{side}_x"] = float(vals[k]), float(centres[k])
            out[f"{side}_factor"] = float(vals[k] / lithostatic)
        else:
            out[f"{side}_syy"] = out[f"{side}_x"] = out[f"{side}_factor"] = float("nan")
    return out


def write_table2(out: Path, rows: list[list[float]], frame: str, points: NDArray[np.float64]) -> list[list[Any]]:
    """Writes ``table2.csv`` and ``table2.md``: the paper's four stresses
    beside ours (and at the mirror points) at the last sample of ``rows``
    (the probe table of :func:`fdem.caving.run_caving`). Returns the rows
    written."""
    last = max(r[0] for r in rows)
    final = {int(r[1]): r for r in rows if r[0] == last}
    table = []
    for (name, xp, yp, *published), (xm, ym) in zip(PAPER_TABLE2, points, strict=True):
        r = final[int(name)]
        table.append([name, xp, yp, xm, ym, *published, *r[6:10], *r[10:14]])
    header = ["node", "x_paper_m", "y_paper_m", "x_m", "y_m"]
    for who in ("paper", "fdem", "mirror"):
        header += [f"{who}_{k}_MPa" for k in ("sxx", "syy", "szz", "sxy")]
    with open(out / "table2.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["# time_s", last, "frame", frame])
        w.writerow(header)
        w.writerows(table)

    def cell(v: float) -> str:
        return "void" if not np.isfinite(v) else f"{v:.1f}"

    lines = [
        f"Table 2 of the paper (3.5 s) beside fdem at t = {last:.2f} s, frame {frame!r}; σ in MPa;"
        " 'mirror' is the same point mirrored across the midline (σxy sign turned)",
        "",
        "| node | x, y paper (m) | x, y model (m) | paper σxx, σyy, σzz, σxy | fdem | mirror |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for t in table:
        paper = ", ".join(f"{v:.2f}" for v in t[5:9])
        ours = ", ".join(cell(v) for v in t[9:13])
        mirror = ", ".join(cell(v) for v in t[13:17])
        lines.append(f"| {t[0]} | {t[1]:.2f}, {t[2]:.2f} | {t[3]:.2f}, {t[4]:.2f} | {paper} | {ours} | {mirror} |")
    (out / "table2.md").write_text("\n".join(lines) + "\n")
    return table


def plot_table2(out: Path, rows: list[list[float]], frame: str) -> None:
    """``table2.png``: σyy and σxx at the nine points over time (ours, solid;
    the mirror points, dotted) with the paper's values at 3.5 s (stars)."""
    plt = pyplot()
    data = np.array(rows, dtype=float)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), dpi=110, sharex=True)
    colours = plt.get_cmap("tab10")
    for k, (name, *_, sxx, syy, _szz, _sxy) in enumerate(PAPER_TABLE2):
        mine = data[data[:, 1] == float(name)]
        for ax, col, paper in ((axes[0], 7, syy), (axes[1], 6, sxx)):
            ax.plot(mine[:, 0], mine[:, col], color=colours(k), label=f"{name}")
            ax.plot(mine[:, 0], mine[:, col + 4], color=colours(k), ls=":", lw=1)
            ax.plot([3.5], [paper], marker="*", ms=11, color=colours(k), mec="k", mew=0.5, ls="none")
    for ax, what in zip(axes, ("σyy", "σxx"), strict=True):
        ax.set_xlabel("time (s)")
        ax.set_ylabel(f"{what} (MPa)")
        ax.grid(alpha=0.3)
    axes[0].set_title(f"σyy at the Table 2 points (frame {frame!r}); ★ the paper at 3.5 s")
    axes[1].set_title("σxx; dotted: the mirror point")
    axes[0].legend(fontsize=7, ncol=3, title="node", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "table2.png")
    plt.close(fig)


def plot_abutments(
    out: Path,
    x: NDArray[np.float64],
    syy: NDArray[np.float64],
    lithostatic: float,
    *,
    time: float,
    undercut: float,
    y: float,
    paper: list[tuple[float, float]],
) -> None:
    """``abutment.png``: σyy along the line ``y`` against x with the
    lithostatic value and the undercut's edges; ``paper`` are (x, σyy in
    MPa) of the paper's points near the line, in the model's frame, both
    sides."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4.5), dpi=110)
    ax.plot(x, syy / 1e6, label=f"fdem, t = {time:.2f} s")
    ax.axhline(lithostatic / 1e6, color="k", ls="--", lw=1, label="lithostatic −(p + γ depth)")
    for e in (-0.5 * undercut, 0.5 * undercut):
        ax.axvline(e, color="grey", ls=":", lw=1)
    if paper:
        px, ps = zip(*paper, strict=True)
        ax.plot(px, ps, "r*", ms=10, ls="none", label="the paper at 3.5 s (its x = 16 m, left frame, and mirrored)")
    save_axes(
        fig,
        ax,
        out / "abutment.png",
        xlabel="x (m); dotted: the undercut's edges",
        ylabel="σyy (MPa)",
        title=f"Vertical stress along y = {y:.0f} m across the abutments",
    )
