"""Jointed rock masses: discontinuity sets, their traces, and meshes that
conform to them with each trace opened into an interface (DESIGN §4.7).

A :class:`JointSet` is a family of parallel traces: orientation, persistence
(trace length), bridge (intact rock between consecutive traces on a line),
spacing (normal distance between lines), stagger or offset, and an optional
random perturbation with a seed. :func:`jointed_rectangle` meshes a
rectangle so that the mesh conforms to every trace (crossings included) and
duplicates the nodes along each trace, so that each is an open contact
interface; the facet set ``joints`` (and one per set name) holds its faces.
The same opening works on any mesh that conforms to interior lines, e.g.
gmsh physical lines (:meth:`Mesh.open_joints`, ``Mesh.read(path,
joints=[...])``); :func:`clean_traces` keeps slivers out of the traces a
mesher is given.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _core
from ._checks import float_array, index_array, number, positive
from .mesh import Mesh

__all__ = ["JointSet", "clean_traces", "jointed_rectangle"]


@dataclass(frozen=True)
class JointSet:
    """A set of parallel joint traces.

    Parameters
    ----------
    angle : float
        Orientation of the traces from the x axis (degrees): 90 vertical,
        0 horizontal.
    persistence : float
        Length of each trace (m).
    bridge : float
        Intact rock between consecutive traces on one line (m), ``>= 0``.
    spacing : float
        Normal distance between neighbouring lines of traces (m).
    stagger : float
        Shift of each line's pattern relative to the previous line, as a
        fraction of the period ``persistence + bridge`` (default 0.5: traces
        of neighbouring lines overlap by half).
    offset : float
        Shift of the whole pattern along the traces (m).
    jitter : float
        Random perturbation (m) of each trace along its line and of each line
        across (the latter capped at a quarter of the spacing), ``>= 0``.
    length_jitter : float
        Random change of each trace's length, as a fraction of the
        persistence (uniform in ±that), ``0 <= length_jitter < 1``.
    angle_jitter : float
        Random rotation of each trace about its middle (degrees, uniform
        in ±that), ``0 <= angle_jitter < 45``.
    seed : int
        Seed of the perturbations (DESIGN §4.7); with all jitters zero
        the pattern is regular.
    name : str
        Name of the set's facet set in the mesh.

    Examples
    --------
    The paper's two sets (persistence × bridge × spacing):

    >>> vertical = JointSet(90, 60.0, 30.0, 2.0, name="vertical")
    >>> horizontal = JointSet(0, 30.0, 15.0, 3.0, name="horizontal")
    """

    angle: float
    persistence: float
    bridge: float
    spacing: float
    stagger: float = 0.5
    offset: float = 0.0
    jitter: float = 0.0
    seed: int = 0
    name: str = "joints"
    length_jitter: float = 0.0
    angle_jitter: float = 0.0

    def __post_init__(self) -> None:
        where = f"joint set '{self.name}'"
        object.__setattr__(self, "angle", number(f"{where}: angle", self.angle))
        for p in ("persistence", "spacing"):
            object.__setattr__(self, p, positive(f"{where}: {p}", getattr(self, p)))
        for p in ("bridge", "jitter"):
            object.__setattr__(self, p, positive(f"{where}: {p}", getattr(self, p), allow_zero=True))
        object.__setattr__(self, "stagger", number(f"{where}: stagger", self.stagger))
        object.__setattr__(self, "offset", number(f"{where}: offset", self.offset))
        lj = number(f"{where}: length_jitter", self.length_jitter)
        aj = number(f"{where}: angle_jitter", self.angle_jitter)
        if not 0 <= lj < 1:
            raise ValueError(f"{where}: length_jitter = {lj} must lie in [0, 1) (a fraction of the persistence)")
        if not 0 <= aj < 45:
            raise ValueError(f"{where}: angle_jitter = {aj} must lie in [0, 45) degrees")
        object.__setattr__(self, "length_jitter", lj)
        object.__setattr__(self, "angle_jitter", aj)
        if not isinstance(self.name, str) or not self.name:
            raise ValueError("joint set name must be a non-empty string")

    def traces(self, bounds: tuple[float, float, float, float]) -> NDArray[np.float64]:
        """The set's traces clipped to the rectangle ``(xmin, ymin, xmax,
        ymax)``, shape (k, 2, 2)."""
        x0, y0, x1, y1 = (float(v) for v in bounds)
        if not all(math.isfinite(v) for v in (x0, y0, x1, y1)) or not (x0 < x1 and y0 < y1):
            raise ValueError(
                f"joint set '{self.name}': bounds {bounds} must be finite with xmin < xmax and ymin < ymax"
            )
        a = math.radians(self.angle)
        d = np.array([math.cos(a), math.sin(a)])
        n = np.array([-math.sin(a), math.cos(a)])
        corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
        s_lo, s_hi = (corners @ n).min(), (corners @ n).max()
        t_lo, t_hi = (corners @ d).min(), (corners @ d).max()
        period = self.persistence + self.bridge
        rng = np.random.default_rng(self.seed)
        out = []
        # bound the work before doing it: a spacing or period far below the
        # region's size (a slip of units) would run without end
        with np.errstate(over="ignore", divide="ignore"):
            lines = float(np.float64(s_hi - s_lo) / self.spacing)
            per_line = float(np.float64(t_hi - t_lo) / period) + 2 if period > 0 else math.inf
        if not lines * per_line <= _MAX_TRACES:
            raise ValueError(
                f"joint set '{self.name}': spacing {self.spacing:g} m and persistence + bridge {period:g} m would "
                f"give about {lines * per_line:.3g} traces in the region (at most {_MAX_TRACES:.0e}); check the units"
            )
        n_lines = int(math.floor(lines))
        for k in range(n_lines + 1):
            s = s_lo + (k + 0.5) * self.spacing
            if self.jitter:
                s += rng.uniform(-1, 1) * min(self.jitter, 0.25 * self.spacing)
            if not s_lo < s < s_hi:
                continue
            phase = (self.offset + k * self.stagger * period) % period
            t = t_lo - period + phase
            while t < t_hi:
                start = t + (rng.uniform(-1, 1) * self.jitter if self.jitter else 0.0)
                p, q = s * n + start * d, s * n + (start + self.persistence) * d
                if self.length_jitter or self.angle_jitter:
                    # about the trace's middle: a length and a direction of
                    # its own (draws only when asked, so that the regular
                    # and position-jittered patterns stay as they were)
                    mid = 0.5 * (p + q)
                    half = 0.5 * self.persistence * (1 + rng.uniform(-1, 1) * self.length_jitter)
                    b = a + math.radians(rng.uniform(-1, 1) * self.angle_jitter)
                    u = np.array([math.cos(b), math.sin(b)])
                    p, q = mid - half * u, mid + half * u
                seg = _clip(p, q, bounds)
                if seg is not None:
                    out.append(seg)
                t += period
        return np.array(out, dtype=float).reshape(-1, 2, 2)


#: The most traces one set may generate in a region (a bound on the work).
_MAX_TRACES = 1e7


def _clip(p: NDArray[Any], q: NDArray[Any], bounds: tuple[float, float, float, float]) -> NDArray[Any] | None:
    """Liang–Barsky clipping of the segment p→q to a rectangle."""
    x0, y0, x1, y1 = bounds
    d = q - p
    lo, hi = 0.0, 1.0
    for delta, near, far in ((d[0], x0 - p[0], x1 - p[0]), (d[1], y0 - p[1], y1 - p[1])):
        if abs(delta) < 1e-300:
            if near > 0 or far < 0:
                return None
            continue
        t_near, t_far = sorted((near / delta, far / delta))
        lo, hi = max(lo, t_near), min(hi, t_far)
        if lo >= hi:
            return None
    return np.array([p + lo * d, p + hi * d])


def _snap(
    traces: NDArray[Any], labels: NDArray[Any], bounds: tuple[float, float, float, float], tol: float
) -> NDArray[Any]:
    """Moves trace ends that stop within ``tol`` of the domain boundary or of
    a trace of another set onto it (extending or trimming along the trace),
    so that no sliver of rock thinner than ``tol`` is left to mesh."""
    x0, y0, x1, y1 = bounds
    out = traces.copy()
    for i in range(len(out)):
        for end in (0, 1):
            p, q = out[i, end], out[i, 1 - end]
            d = p - q
            if not np.any(d):
                continue  # both ends snapped onto one point: nothing left to move
            d = d / np.linalg.norm(d)
            best = None
            # the domain sides
            for axis, value in ((0, x0), (0, x1), (1, y0), (1, y1)):
                if abs(d[axis]) > 1e-12:
                    t = (value - p[axis]) / d[axis]
                    if abs(t) < tol and (best is None or abs(t) < abs(best)):
                        best = t
            # traces of the other sets
            for j in np.flatnonzero(labels != labels[i]):
                a, b = out[j]
                e = b - a
                denom = d[0] * e[1] - d[1] * e[0]
                if abs(denom) < 1e-12:
                    continue
                w = a - p
                t = (w[0] * e[1] - w[1] * e[0]) / denom
                u = (w[0] * d[1] - w[1] * d[0]) / denom
                if abs(t) < tol and -1e-9 <= u <= 1 + 1e-9 and (best is None or abs(t) < abs(best)):
                    best = t
            if best is not None:
                out[i, end] = p + best * d
    return out


def _planarize(
    traces: NDArray[Any], labels: NDArray[Any], bounds: tuple[float, float, float, float], tol: float
) -> tuple[NDArray[Any], NDArray[Any]]:
    """Splits the traces at their crossings so that no two cross: every
    crossing becomes one shared point (the same floats in both traces), a
    crossing within ``tol`` of a trace end becomes that end, and ends within
    ``tol`` of the domain sides are put exactly on them. The mesher then
    never computes an intersection itself, and no two mesh nodes fall a
    round-off apart."""
    x0, y0, x1, y1 = bounds
    t = traces.copy()
    for axis, value in ((0, x0), (0, x1), (1, y0), (1, y1)):
        near = np.abs(t[:, :, axis] - value) < tol
        t[:, :, axis][near] = value
    # a trace whose ends were snapped onto one point is no trace
    keep = np.any(t[:, 0] != t[:, 1], axis=1)
    t, labels = t[keep], labels[keep]
    n = len(t)
    cuts: list[list[tuple[float, NDArray[Any]]]] = [[] for _ in range(n)]
    a, b = t[:, 0], t[:, 1]
    e = b - a
    length = np.linalg.norm(e, axis=1)
    for i in range(n):
        j = np.arange(i + 1, n)
        j = j[labels[j] != labels[i]]
        if not len(j):
            continue
        d = e[i]
        denom = d[0] * e[j, 1] - d[1] * e[j, 0]
        ok = np.abs(denom) > 1e-12 * length[i] * length[j]
        j, denom = j[ok], denom[ok]
        w = a[j] - a[i]
        u = (w[:, 0] * e[j, 1] - w[:, 1] * e[j, 0]) / denom  # along i
        v = (w[:, 0] * d[1] - w[:, 1] * d[0]) / denom  # along j
        ui, vj = tol / length[i], tol / length[j]
        hit = (u >= -ui) & (u <= 1 + ui) & (v >= -vj) & (v <= 1 + vj)
        for jj, uu, vv in zip(j[hit], u[hit], v[hit], strict=True):
            # the shared point: an existing end if the crossing is that close
            if uu * length[i] < tol:
                point = a[i]
            elif (1 - uu) * length[i] < tol:
                point = b[i]
            elif vv * length[jj] < tol:
                point = a[jj]
            elif (1 - vv) * length[jj] < tol:
                point = b[jj]
            else:
                point = a[i] + uu * d
            cuts[i].append((float(np.clip(uu, 0, 1)), point))
            cuts[jj].append((float(np.clip(vv, 0, 1)), point))
    out, out_labels = [], []
    for i in range(n):
        pts = [(0.0, a[i]), *sorted(cuts[i], key=lambda c: c[0]), (1.0, b[i])]
        chain = [pts[0][1]]
        for _, p in pts[1:]:
            if np.linalg.norm(p - chain[-1]) >= tol:
                chain.append(p)
            elif np.array_equal(p, b[i]) or any(np.array_equal(p, q) for _, q in cuts[i]):
                chain[-1] = p  # prefer the shared point over a near-duplicate
        for p, q in zip(chain[:-1], chain[1:], strict=True):
            out.append([p, q])
            out_labels.append(labels[i])
    return np.array(out, dtype=float).reshape(-1, 2, 2), np.array(out_labels, dtype=int)


def jointed_rectangle(
    width: float,
    height: float,
    size: float,
    joint_sets: Sequence[JointSet] = (),
    *,
    traces: Any = None,
    origin: tuple[float, float] = (0.0, 0.0),
    min_angle: float = 25.0,
    max_nodes: int = 2_000_000,
    uniform: bool = False,
) -> Mesh:
    """A rectangle meshed so that it conforms to joint traces, each trace
    opened into an interface.

    Parameters
    ----------
    width, height : float
        Size (m).
    size : float
        Element edge length (m). With ``uniform`` triangles are nearly
        equilateral with edges of about ``size``: the traces and sides are
        divided evenly, the inside filled with an equilateral lattice, and
        the nodes smoothed so that the worst triangle is as good as the
        geometry allows (an explicit run's step is set by its worst
        element; docs/meshing.md). Without (the default), Delaunay
        refinement from the traces alone: triangles have an area of at
        most ``√3/4 size²`` and no angle below ``min_angle`` where the
        geometry allows, and sizes anywhere down to a fifth of ``size``.
    joint_sets : sequence of JointSet
        Sets whose traces are generated and clipped to the rectangle. A set
        whose spacing is below ``size`` is rejected.
    traces : array_like, shape (k, 2, 2), optional
        Explicit traces ``[[x0, y0], [x1, y1]]`` (set name ``traces``); each
        must lie inside the rectangle and have a length.
    origin : (float, float)
        Lower-left corner (m).
    uniform : bool
        Nearly equilateral triangles of edge ``size`` (see ``size``). Trace
        ends that stop within ``size`` of another set's trace or of the
        sides are moved onto it (``size / 2`` without ``uniform``).

    Returns
    -------
    Mesh
        With facet sets ``left``, ``right``, ``bottom``, ``top``, ``joints``
        (both faces of every trace) and one per set name; the duplicated
        nodes are marked as interface nodes. Nodes and elements are
        numbered along a Hilbert curve (:meth:`Mesh.reordered`).
    """
    w, h, s = positive("width", width), positive("height", height), positive("size", size)
    x0, y0 = float(origin[0]), float(origin[1])
    bounds = (x0, y0, x0 + w, y0 + h)
    pieces, labels, names = [], [], []
    for k, js in enumerate(joint_sets):
        if not isinstance(js, JointSet):
            raise ValueError(f"joint_sets[{k}] must be a fdem.JointSet")
        if js.spacing < s:
            raise ValueError(
                f"joint set '{js.name}': spacing = {js.spacing} m is below the element size {s} m; "
                "refine the mesh or widen the spacing"
            )
        t = js.traces(bounds)
        t = t[np.linalg.norm(t[:, 1] - t[:, 0], axis=1) > 0.5 * s]
        pieces.append(t)
        labels.append(np.full(len(t), len(names)))
        names.append(js.name)
    if traces is not None:
        explicit = float_array("traces", traces, (None, 2, 2))
        tol = 1e-9 * max(w, h)
        for i, (p, q) in enumerate(explicit):
            if np.linalg.norm(q - p) <= tol:
                raise ValueError(f"trace {i} has zero length")
            for pt in (p, q):
                if not (x0 - tol <= pt[0] <= x0 + w + tol and y0 - tol <= pt[1] <= y0 + h + tol):
                    raise ValueError(f"trace {i} reaches ({pt[0]:g}, {pt[1]:g}), outside the domain {bounds}")
        pieces.append(explicit)
        labels.append(np.full(len(explicit), len(names)))
        names.append("traces")
    segs = np.concatenate(pieces) if pieces else np.zeros((0, 2, 2))
    lab = np.concatenate(labels) if labels else np.zeros(0, dtype=int)
    if len(segs):
        segs = _snap(segs, lab, bounds, (1.0 if uniform else 0.5) * s)
        segs, lab = _planarize(segs, lab, bounds, 1e-6 * s)
    outline = np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])
    pts, tri, cons = _core.triangulate(
        outline,
        np.ascontiguousarray(segs.reshape(-1, 4)),
        math.sqrt(3) / 4 * s * s,
        float(min_angle),
        int(max_nodes),
        size=s if uniform else 0.0,
    )
    # constraint edges off the outline are trace edges; label them by the nearest trace
    p0, p1 = pts[cons[:, 0]], pts[cons[:, 1]]
    tol = 1e-9 * max(w, h)
    on_side = np.zeros(len(cons), dtype=bool)
    for axis, value in ((0, x0), (0, x0 + w), (1, y0), (1, y0 + h)):
        on_side |= (np.abs(p0[:, axis] - value) < tol) & (np.abs(p1[:, axis] - value) < tol)
    cut = cons[~on_side]
    cut_label = np.zeros(len(cut), dtype=int)
    if len(cut) and len(segs):
        mid = 0.5 * (pts[cut[:, 0]] + pts[cut[:, 1]])
        a, b = segs[:, 0], segs[:, 1]
        e = b - a
        for i, m in enumerate(mid):
            u = np.clip(np.einsum("ij,ij->i", m - a, e) / np.einsum("ij,ij->i", e, e), 0, 1)
            dist = np.linalg.norm(a + u[:, None] * e - m, axis=1)
            cut_label[i] = lab[int(np.argmin(dist))]
    new_tri, parents = _core.split_along_edges(len(pts), tri, np.ascontiguousarray(cut))
    n0 = len(pts)
    points = np.concatenate([pts, pts[parents]]) if len(parents) else pts
    origin_of = np.concatenate([np.arange(n0), parents])
    iface = np.zeros(len(points), dtype=bool)
    iface[parents] = True
    iface[n0:] = True
    mesh = Mesh(points, new_tri, interface_nodes=iface)
    bf = mesh.boundary_facets()
    key = {tuple(sorted(e)): lab_i for e, lab_i in zip(cut.tolist(), cut_label.tolist(), strict=True)}
    orig = np.sort(origin_of[bf], axis=1)
    facet_label = np.array([key.get(tuple(e), -1) for e in orig.tolist()], dtype=int)
    facet_sets: dict[str, Any] = {"joints": bf[facet_label >= 0]}
    for k, name in enumerate(names):
        facet_sets[name] = bf[facet_label == k]
    bp = points[bf]
    for side, axis, value in (("left", 0, x0), ("right", 0, x0 + w), ("bottom", 1, y0), ("top", 1, y0 + h)):
        facet_sets[side] = bf[(np.abs(bp[:, 0, axis] - value) < tol) & (np.abs(bp[:, 1, axis] - value) < tol)]
    # renumbered along a Hilbert curve: neighbours near each other in memory
    return mesh.with_sets(facet_sets=facet_sets).reordered()


def clean_traces(
    traces: Any,
    bounds: tuple[float, float, float, float],
    tol: float,
    *,
    labels: Any = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Traces made fit to mesh: no rock thinner than ``tol`` left between a
    trace end and another set's trace or the rectangle's sides, and crossings
    made explicit.

    A trace that stops a little short of another set's trace or of the
    domain side leaves a sliver of rock the mesher must fill with elements
    of that thickness, and one sliver sets the stable step of the whole
    explicit run (docs/meshing.md). This moves each such end onto what it
    nearly meets (extending or trimming the trace along itself), then splits
    traces at their crossings so that a crossing is one shared point.
    :func:`jointed_rectangle` does the same before it meshes; call this on
    traces you give to gmsh yourself.

    Parameters
    ----------
    traces : array_like, shape (k, 2, 2)
        Segments ``[[x0, y0], [x1, y1]]`` (m).
    bounds : (xmin, ymin, xmax, ymax)
        The domain's rectangle (m); ends within ``tol`` of a side go onto it.
    tol : float
        The thinnest rock to keep (m), e.g. half the element size near the
        traces.
    labels : array_like of int, shape (k,), optional
        The set of each trace (ends snap only onto traces of another set);
        default all in one set.

    Returns
    -------
    traces : ndarray, shape (m, 2, 2)
        The cleaned pieces (crossings split them).
    labels : ndarray of int, shape (m,)
        The set of each piece.
    """
    t = float_array("traces", traces, (None, 2, 2))
    lab = np.zeros(len(t), dtype=np.int64) if labels is None else np.asarray(labels, dtype=np.int64)
    if lab.shape != (len(t),):
        raise ValueError(f"labels: expected shape ({len(t)},), got {lab.shape}")
    d = positive("tol", tol)
    short = np.flatnonzero(np.linalg.norm(t[:, 1] - t[:, 0], axis=1) <= d)
    if len(short):
        raise ValueError(f"trace {int(short[0])} is no longer than tol = {d:g} m; drop it or lower tol")
    b = tuple(float(v) for v in bounds)
    if len(b) != 4 or not (b[0] < b[2] and b[1] < b[3]):
        raise ValueError(f"bounds {bounds} must be (xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax")
    t = _snap(t, lab, b, d)  # type: ignore[arg-type]
    return _planarize(t, lab, b, 1e-6 * d)  # type: ignore[arg-type]


def _open_joints(mesh: Mesh, lines: Mapping[str, Any], sliver: float) -> Mesh:
    """Implementation of :meth:`Mesh.open_joints` (kept beside the other
    joint machinery; the mesh module imports it lazily)."""
    if not isinstance(lines, Mapping) or not lines:
        raise ValueError("joints: give a mapping of joint name to (k, 2) node pairs, at least one")
    frac = number("sliver", sliver)
    if not 0 <= frac < 1:
        raise ValueError(f"sliver = {frac} must lie in [0, 1) (a fraction of the longest edge of an element)")
    n0, tri = mesh.n_nodes, mesh.triangles
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    keys, counts = np.unique(edges, axis=0, return_counts=True)
    uses = {(int(a), int(b)): int(c) for (a, b), c in zip(keys, counts, strict=True)}
    owner: dict[tuple[int, int], str] = {}
    for name, value in lines.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"joint names must be non-empty strings, got {name!r}")
        if name in mesh.facet_sets:
            raise ValueError(f"joint '{name}': the mesh already has a facet set of that name")
        f = index_array(f"joint '{name}'", value, (None, 2), n0)
        if len(f) == 0:
            raise ValueError(f"joint '{name}' has no edges")
        for i, (a, b) in enumerate(f.tolist()):
            key = (min(a, b), max(a, b))
            if key not in uses:
                raise ValueError(
                    f"joint '{name}': entry {i} ({a}, {b}) is not an edge of the mesh; the mesh must conform "
                    "to the joint (embed the line in the gmsh surface)"
                )
            if uses[key] == 1:
                raise ValueError(
                    f"joint '{name}': entry {i} ({a}, {b}) lies on the mesh boundary; a joint runs inside the "
                    "body (a boundary line is a facet set: leave it out of joints)"
                )
            if key in owner and owner[key] != name:
                raise ValueError(f"joint '{name}': edge ({a}, {b}) also belongs to joint '{owner[key]}'")
            owner[key] = name
    cut = np.array(sorted(owner), dtype=np.int64)
    on_trace = np.zeros(n0, dtype=bool)
    on_trace[cut.ravel()] = True
    # a sliver beside a trace: refused, not repaired. Collapsing it would
    # move the trace or its neighbours; the fix that keeps the geometry is
    # upstream, in the traces the mesher was given (clean_traces).
    near = np.flatnonzero(on_trace[tri].any(axis=1))
    p = mesh.points[tri[near]]
    longest = np.linalg.norm(p - np.roll(p, -1, axis=1), axis=2).max(axis=1)
    altitude = mesh.min_altitudes()[near]
    bad = np.flatnonzero(altitude < frac * longest)
    if len(bad):
        k = bad[np.argmin(altitude[bad] / longest[bad])]
        e = int(near[k])
        touched = sorted({owner[key] for key in owner if set(key) & set(tri[e].tolist())})
        raise ValueError(
            f"element {e} beside joint {', '.join(repr(s) for s in touched) or '?'} is a sliver: smallest "
            f"altitude {altitude[k]:.3g} m against its longest edge {longest[k]:.3g} m (below sliver = {frac:g}; "
            f"{len(bad)} such elements). Its step would govern the whole run; snap the trace ends that "
            "nearly meet another trace or the boundary (fdem.clean_traces) and mesh again"
        )
    new_tri, parents = _core.split_along_edges(n0, np.ascontiguousarray(tri), cut)
    origin_of = np.concatenate([np.arange(n0), parents])
    points = mesh.points[origin_of]
    iface = np.concatenate([mesh.interface_nodes, np.ones(len(parents), dtype=bool)])
    iface[parents] = True
    opened = Mesh(points, new_tri, interface_nodes=iface)
    bf = opened.boundary_facets()
    by_origin: dict[tuple[int, int], list[int]] = {}
    for i, (a, b) in enumerate(np.sort(origin_of[bf], axis=1).tolist()):
        by_origin.setdefault((a, b), []).append(i)
    facet_sets: dict[str, Any] = {}
    for name, f in mesh.facet_sets.items():
        facet_sets[name] = bf[[by_origin[(min(a, b), max(a, b))][0] for a, b in f.tolist()]]
    for name in lines:
        rows = [i for key, n in owner.items() if n == name for i in by_origin[key]]
        facet_sets[name] = bf[np.sort(rows)]
    node_sets = {k: np.flatnonzero(np.isin(origin_of, v)) for k, v in mesh.node_sets.items()}
    return Mesh(
        points,
        new_tri,
        node_sets=node_sets,
        facet_sets=facet_sets,
        element_sets=dict(mesh.element_sets),
        interface_nodes=iface,
    )
