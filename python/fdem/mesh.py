"""Triangle meshes with named node, facet and element groups.

A :class:`Mesh` is an immutable value: reference coordinates (m), counter-
clockwise triangles, and named groups. Build one from numpy arrays, with
:meth:`Mesh.rectangle` (structured, no dependencies), with
:func:`gmsh_rectangle` (unstructured, needs the ``gmsh`` extra), or read any
triangle mesh meshio understands (gmsh ``.msh``, ``.vtu``…) with
:meth:`Mesh.read`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _core
from ._checks import float_array, index_array, positive, whole

__all__ = ["Mesh", "gmsh_rectangle"]


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


class Mesh:
    """A 2D mesh of linear triangles with named groups.

    Parameters
    ----------
    points : array_like, shape (n_nodes, 2)
        Reference coordinates (m).
    triangles : array_like of int, shape (n_elements, 3)
        Node ids of each triangle, counter-clockwise.
    node_sets : mapping of str to array_like of int, optional
        Named groups of nodes (supports, probes).
    facet_sets : mapping of str to array_like of int, shape (k, 2), optional
        Named groups of boundary edges as node pairs (pressure, supports).
    element_sets : mapping of str to array_like of int, optional
        Named groups of elements (materials, excavation stages).
    interface_nodes : array_like of bool, shape (n_nodes,), optional
        Nodes allowed to coincide with another node (the two sides of a
        joint or crack). Coincident nodes not marked here are an error.

    Raises
    ------
    ValueError
        For wrong shapes or dtypes, NaN or infinite coordinates, clockwise or
        zero-area triangles, coincident or orphan nodes, duplicate or
        overlapping triangles, and group entries out of range; the message
        names the node, element or group.
    """

    def __init__(
        self,
        points: Any,
        triangles: Any,
        *,
        node_sets: Mapping[str, Any] | None = None,
        facet_sets: Mapping[str, Any] | None = None,
        element_sets: Mapping[str, Any] | None = None,
        interface_nodes: Any = None,
    ) -> None:
        pts = float_array("points", points, (None, 2))
        tri = index_array("triangles", triangles, (None, 3))
        if len(tri) == 0:
            raise ValueError("triangles: the mesh has no elements")
        n = len(pts)
        if interface_nodes is None:
            iface = np.zeros(n, dtype=bool)
        else:
            iface = np.asarray(interface_nodes)
            if iface.dtype != bool or iface.shape != (n,):
                raise ValueError(
                    f"interface_nodes: expected a bool array of shape ({n},), got {iface.dtype} {iface.shape}"
                )
        _core.validate_mesh(pts, tri, np.ascontiguousarray(iface))
        self._points = _frozen(pts)
        self._triangles = _frozen(tri)
        self._interface = _frozen(iface)
        self._node_sets = MappingProxyType(
            {str(k): _frozen(index_array(f"node set '{k}'", v, (None,), n)) for k, v in (node_sets or {}).items()}
        )
        self._element_sets = MappingProxyType(
            {
                str(k): _frozen(index_array(f"element set '{k}'", v, (None,), len(tri)))
                for k, v in (element_sets or {}).items()
            }
        )
        boundary = {tuple(sorted(f)) for f in self.boundary_facets().tolist()}
        fsets = {}
        for k, v in (facet_sets or {}).items():
            f = index_array(f"facet set '{k}'", v, (None, 2), n)
            for i, (a, b) in enumerate(f.tolist()):
                if (min(a, b), max(a, b)) not in boundary:
                    raise ValueError(
                        f"facet set '{k}': entry {i} ({a}, {b}) is not an edge on the mesh boundary "
                        "(an interior line is a joint: open it with Mesh.open_joints or Mesh.read(..., joints=))"
                    )
            fsets[str(k)] = _frozen(f)
        self._facet_sets = MappingProxyType(fsets)

    # --- data -------------------------------------------------------------
    @property
    def points(self) -> NDArray[np.float64]:
        """Reference coordinates (m), shape (n_nodes, 2), read-only."""
        return self._points

    @property
    def triangles(self) -> NDArray[np.int64]:
        """Counter-clockwise connectivity, shape (n_elements, 3), read-only."""
        return self._triangles

    @property
    def interface_nodes(self) -> NDArray[np.bool_]:
        """Nodes allowed to coincide with another, shape (n_nodes,)."""
        return self._interface

    @property
    def node_sets(self) -> Mapping[str, NDArray[np.int64]]:
        """Named node groups."""
        return self._node_sets

    @property
    def facet_sets(self) -> Mapping[str, NDArray[np.int64]]:
        """Named boundary-edge groups, each of shape (k, 2)."""
        return self._facet_sets

    @property
    def element_sets(self) -> Mapping[str, NDArray[np.int64]]:
        """Named element groups."""
        return self._element_sets

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return len(self._points)

    @property
    def n_elements(self) -> int:
        """Number of triangles."""
        return len(self._triangles)

    def __repr__(self) -> str:
        groups = sorted({*self._node_sets, *self._facet_sets, *self._element_sets})
        return f"Mesh({self.n_nodes} nodes, {self.n_elements} triangles, groups={groups})"

    def __reduce__(self) -> tuple[Any, ...]:
        return (
            _rebuild,
            (
                self._points,
                self._triangles,
                dict(self._node_sets),
                dict(self._facet_sets),
                dict(self._element_sets),
                self._interface,
            ),
        )

    def with_sets(
        self,
        *,
        node_sets: Mapping[str, Any] | None = None,
        facet_sets: Mapping[str, Any] | None = None,
        element_sets: Mapping[str, Any] | None = None,
    ) -> Mesh:
        """A copy with more (or replaced) named groups."""
        return Mesh(
            self._points,
            self._triangles,
            node_sets={**self._node_sets, **(node_sets or {})},
            facet_sets={**self._facet_sets, **(facet_sets or {})},
            element_sets={**self._element_sets, **(element_sets or {})},
            interface_nodes=self._interface,
        )

    def reordered(self) -> Mesh:
        """A copy with nodes and elements renumbered along a Hilbert curve
        through the mesh (nodes by position, elements by centroid), groups
        carried over in their order.

        The time loop gathers each element's nodes and each node's element
        forces; with neighbours stored near each other those reads hit the
        cache. Measured on the 135 672-element block-caving mesh (2 threads):
        the whole step 1.38× faster than in the generator's order
        (ARCHITECTURE.md, measured facts). Coincident nodes keep their order,
        so the result is deterministic. The generators of unstructured
        meshes (:meth:`polygon`, :func:`fdem.jointed_rectangle`) return
        reordered meshes; call it on meshes read from files.
        """
        node_order = np.argsort(_hilbert_key(self._points), kind="stable")
        elem_order = np.argsort(_hilbert_key(self.centroids()), kind="stable")
        new_node = np.empty(self.n_nodes, dtype=np.int64)
        new_node[node_order] = np.arange(self.n_nodes)
        new_elem = np.empty(self.n_elements, dtype=np.int64)
        new_elem[elem_order] = np.arange(self.n_elements)
        return Mesh(
            self._points[node_order],
            new_node[self._triangles[elem_order]],
            node_sets={k: new_node[v] for k, v in self._node_sets.items()},
            facet_sets={k: new_node[v] for k, v in self._facet_sets.items()},
            element_sets={k: new_elem[v] for k, v in self._element_sets.items()},
            interface_nodes=self._interface[node_order],
        )

    @classmethod
    def combine(cls, *parts: Mesh, prefixes: Sequence[str] | None = None) -> Mesh:
        """Several meshes as one model of separate bodies (e.g. a block on a
        base). Nodes of different parts that coincide stay separate and are
        marked as interface nodes, so the bodies meet by contact. Groups keep
        their names, prefixed by ``prefixes[i]`` if given; groups of the same
        name are merged.
        """
        if not parts:
            raise ValueError("combine needs at least one mesh")
        if prefixes is not None and len(prefixes) != len(parts):
            raise ValueError("prefixes must have one entry per mesh")
        points, tris, ifaces = [], [], []
        sets: dict[str, dict[str, list[Any]]] = {"node": {}, "facet": {}, "element": {}}
        n_off = e_off = 0
        for i, m in enumerate(parts):
            if not isinstance(m, Mesh):
                raise ValueError(f"part {i} is not a fdem.Mesh")
            pre = prefixes[i] if prefixes is not None else ""
            points.append(m.points)
            tris.append(m.triangles + n_off)
            ifaces.append(m.interface_nodes)
            for kind, groups, off in (
                ("node", m.node_sets, n_off),
                ("facet", m.facet_sets, n_off),
                ("element", m.element_sets, e_off),
            ):
                for name, ids in groups.items():
                    sets[kind].setdefault(pre + name, []).append(ids + off)
            n_off += m.n_nodes
            e_off += m.n_elements
        pts = np.concatenate(points)
        iface = np.concatenate(ifaces)
        # coincident nodes of different parts become interface nodes
        part_of = np.concatenate([np.full(m.n_nodes, i) for i, m in enumerate(parts)])
        order = np.lexsort((pts[:, 1], pts[:, 0]))
        same = np.all(pts[order[1:]] == pts[order[:-1]], axis=1) & (part_of[order[1:]] != part_of[order[:-1]])
        iface[order[1:][same]] = True
        iface[order[:-1][same]] = True
        merged = {kind: {k: np.concatenate(v) for k, v in groups.items()} for kind, groups in sets.items()}
        return cls(
            pts,
            np.concatenate(tris),
            node_sets=merged["node"],
            facet_sets=merged["facet"],
            element_sets=merged["element"],
            interface_nodes=iface,
        )

    def open_joints(self, lines: Mapping[str, Any], *, sliver: float = 0.2) -> Mesh:
        """A copy with interior lines opened into joints: contact interfaces,
        each with the name of its line, for its own law in
        :meth:`fdem.Model.contact` (``interfaces={name: Interface(...)}``).

        Every node on a line is split into one copy per sector of rock around
        it (the machinery of :func:`fdem.jointed_rectangle`): two along a
        line, one per sector where lines cross or meet, two where a line
        reaches the outer boundary; the end of a line inside the body (a
        crack tip) stays one node, so the joint closes there. Copies are
        marked as interface nodes. Element ids do not change; new nodes are
        appended after the old ones.

        Parameters
        ----------
        lines : mapping of str to array_like of int, shape (k, 2)
            For each joint name, the mesh edges (node pairs, any order and
            orientation) along its traces. The mesh must conform to them.
        sliver : float
            An element with a node on a line whose smallest altitude is below
            this fraction of its longest edge is refused (0 turns the check
            off). Its stable step would govern the whole run; the fix is in
            the geometry given to the mesher (:func:`fdem.clean_traces`).

        Returns
        -------
        Mesh
            With a facet set per joint holding both faces of its line; the
            other facet sets follow the split (each boundary edge once,
            oriented with the body on its left); a node set holds every copy
            of its nodes; element sets are unchanged.

        Raises
        ------
        ValueError
            Naming the joint and entry for an edge that is not in the mesh, on
            its boundary or in two joints, a name already used by a facet set,
            and the element for a sliver.
        """
        from .joints import _open_joints

        return _open_joints(self, lines, sliver)

    # --- derived ----------------------------------------------------------
    def nodes(self, group: str | Any) -> NDArray[np.int64]:
        """Node ids of a group: a node set, the nodes of a facet set or of an
        element set (in that order of lookup), or an explicit id array.

        Raises
        ------
        ValueError
            If no group has that name.
        """
        if isinstance(group, str):
            if group in self._node_sets:
                return self._node_sets[group]
            if group in self._facet_sets:
                return np.unique(self._facet_sets[group])
            if group in self._element_sets:
                return np.unique(self._triangles[self._element_sets[group]])
            raise ValueError(f"unknown group '{group}'; this mesh has {self.group_names()}")
        return index_array("nodes", group, (None,), self.n_nodes).ravel()

    def facets(self, group: str | Any) -> NDArray[np.int64]:
        """Boundary edges of a facet set by name, or an explicit (k, 2) array."""
        if isinstance(group, str):
            if group not in self._facet_sets:
                raise ValueError(f"unknown facet set '{group}'; this mesh has {sorted(self._facet_sets)}")
            return self._facet_sets[group]
        return index_array("facets", group, (None, 2), self.n_nodes)

    def elements(self, group: str | Any) -> NDArray[np.int64]:
        """Element ids of an element set by name, or an explicit id array."""
        if isinstance(group, str):
            if group not in self._element_sets:
                raise ValueError(f"unknown element set '{group}'; this mesh has {sorted(self._element_sets)}")
            return self._element_sets[group]
        return index_array("elements", group, (None,), self.n_elements).ravel()

    def group_names(self) -> list[str]:
        """All group names."""
        return sorted({*self._node_sets, *self._facet_sets, *self._element_sets})

    def boundary_facets(self) -> NDArray[np.int64]:
        """Every boundary edge, oriented with the body on its left, shape (k, 2)."""
        t = self._triangles
        e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        key = np.sort(e, axis=1)
        _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        return e[counts[inverse.ravel()] == 1]

    def centroids(self) -> NDArray[np.float64]:
        """Element centroids (m), shape (n_elements, 2)."""
        return self._points[self._triangles].mean(axis=1)

    def areas(self) -> NDArray[np.float64]:
        """Element areas (m²)."""
        p = self._points[self._triangles]
        d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])

    def min_altitudes(self) -> NDArray[np.float64]:
        """Smallest altitude of each element (m): twice its area over its
        longest edge."""
        p = self._points[self._triangles]
        edges = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]], axis=1)
        longest = np.linalg.norm(edges, axis=2).max(axis=1)
        return 2.0 * self.areas() / longest

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` (m)."""
        lo, hi = self._points.min(axis=0), self._points.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    # --- constructors -----------------------------------------------------
    @classmethod
    def rectangle(
        cls,
        width: float,
        height: float,
        nx: int,
        ny: int,
        *,
        origin: tuple[float, float] = (0.0, 0.0),
        pattern: str = "alternating",
    ) -> Mesh:
        """A structured mesh of ``nx × ny`` cells, each split into two triangles.

        Parameters
        ----------
        width, height : float
            Size (m).
        nx, ny : int
            Cells along x and y.
        origin : (float, float)
            Lower-left corner (m).
        pattern : {"alternating", "right", "left"}
            Diagonal direction: all rising ("right"), all falling ("left"), or
            alternating in a checkerboard (no preferred direction).

        The facet sets ``left``, ``right``, ``bottom`` and ``top`` hold the
        sides; the node sets ``lower_left`` etc. the corners.
        """
        w, h = positive("width", width), positive("height", height)
        nx, ny = whole("nx", nx, maximum=100_000), whole("ny", ny, maximum=100_000)
        if pattern not in ("alternating", "right", "left"):
            raise ValueError(f"pattern must be 'alternating', 'right' or 'left', got {pattern!r}")
        origin = tuple(float_array("origin", origin, (2,)).tolist())
        xs = origin[0] + w * np.arange(nx + 1) / nx
        ys = origin[1] + h * np.arange(ny + 1) / ny
        gx, gy = np.meshgrid(xs, ys)
        points = np.column_stack([gx.ravel(), gy.ravel()])
        i, j = np.meshgrid(np.arange(nx), np.arange(ny))
        i, j = i.ravel(), j.ravel()
        a = j * (nx + 1) + i
        b, c, d = a + 1, a + nx + 2, a + nx + 1
        rising = np.ones_like(a, dtype=bool) if pattern == "right" else np.zeros_like(a, dtype=bool)
        if pattern == "alternating":
            rising = (i + j) % 2 == 0
        t1 = np.where(rising[:, None], np.column_stack([a, b, c]), np.column_stack([a, b, d]))
        t2 = np.where(rising[:, None], np.column_stack([a, c, d]), np.column_stack([b, c, d]))
        triangles = np.empty((2 * len(a), 3), dtype=np.int64)
        triangles[0::2], triangles[1::2] = t1, t2
        col = lambda k: np.arange(ny + 1) * (nx + 1) + k  # noqa: E731
        row = lambda k: k * (nx + 1) + np.arange(nx + 1)  # noqa: E731
        chain = lambda ids: np.column_stack([ids[:-1], ids[1:]])  # noqa: E731
        facet_sets = {
            "bottom": chain(row(0)),
            "right": chain(col(nx)),
            "top": chain(row(ny)[::-1]),
            "left": chain(col(0)[::-1]),
        }
        node_sets = {
            "lower_left": [0],
            "lower_right": [nx],
            "upper_right": [(ny + 1) * (nx + 1) - 1],
            "upper_left": [ny * (nx + 1)],
        }
        return cls(points, triangles, facet_sets=facet_sets, node_sets=node_sets)

    @classmethod
    def polygon(
        cls,
        outline: Any,
        size: float,
        *,
        min_angle: float = 25.0,
        max_nodes: int = 2_000_000,
    ) -> Mesh:
        """An unstructured mesh of a polygon (constrained Delaunay with
        refinement, no dependencies).

        Parameters
        ----------
        outline : array_like, shape (k, 2)
            Corners in order (either orientation, not self-intersecting), m.
        size : float
            Target element edge length (m): triangles have an area of at most
            ``√3/4 size²`` and no angle below ``min_angle`` (degrees) where the
            geometry allows.
        max_nodes : int
            Refinement stops (with an error) beyond this many nodes.

        The facet set ``boundary`` holds the outline's edges.
        """
        pts = float_array("outline", outline, (None, 2))
        s = positive("size", size)
        # the node count the refinement heads for, known before it starts:
        # about A / (√3/4 s²) / 2 nodes for the polygon's area A
        # in units of the size, so that huge coordinates do not overflow
        x, y = (pts[:, 0] - pts[0, 0]) / s, (pts[:, 1] - pts[0, 1]) / s
        cells = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
        area = cells * s * s
        expected = cells / (np.sqrt(3) / 4) / 2
        if not expected <= max_nodes:
            raise ValueError(
                f"size = {s:g} m would mesh the polygon (area {area:.3g} m²) with about {expected:.3g} nodes, "
                f"more than max_nodes = {max_nodes}; check the units of size"
            )
        points, triangles, _ = _core.triangulate(
            np.ascontiguousarray(pts), np.zeros((0, 4)), np.sqrt(3) / 4 * s * s, float(min_angle), int(max_nodes)
        )
        mesh = cls(points, triangles).reordered()
        return mesh.with_sets(facet_sets={"boundary": mesh.boundary_facets()})

    @classmethod
    def disc(cls, radius: float, size: float, *, center: tuple[float, float] = (0.0, 0.0)) -> Mesh:
        """An unstructured mesh of a disc of ``radius`` (m) about ``center``,
        its circle a polygon of sides about ``size`` long (see
        :meth:`polygon`). The facet set ``boundary`` holds the rim."""
        r, s = positive("radius", radius), positive("size", size)
        ratio = r / s  # (r/s)², not r²/s², which overflows first
        expected = np.pi * ratio * ratio / (np.sqrt(3) / 4) / 2
        if not expected <= 2_000_000:
            raise ValueError(
                f"size = {s:g} m would mesh a disc of radius {r:g} m with about {expected:.3g} nodes "
                "(at most 2e6); check the units of radius and size"
            )
        k = max(12, int(np.ceil(2 * np.pi * r / s)))
        a = 2 * np.pi * np.arange(k) / k
        return cls.polygon(np.column_stack([center[0] + r * np.cos(a), center[1] + r * np.sin(a)]), s)

    @classmethod
    def from_gmsh(cls, curves: Mapping[str, int] | None = None) -> Mesh:
        """The triangles of the model gmsh holds now (``gmsh`` initialised,
        the mesh generated), as a Mesh: nodes no triangle uses (geometry
        points) are dropped and the rest renumbered in gmsh's order, and
        clockwise triangles are turned counter-clockwise. ``curves`` names
        gmsh curve tags whose line elements become facet sets.

        For meshes built in a script with gmsh's API; :meth:`read` reads a
        file written by gmsh (with physical groups) instead.
        """
        import gmsh

        tags, coords, _ = gmsh.model.mesh.getNodes()
        index = {int(t): k for k, t in enumerate(tags)}
        pts = np.asarray(coords).reshape(-1, 3)[:, :2]
        _, tri_nodes = gmsh.model.mesh.getElementsByType(2)
        tri = np.array([index[int(t)] for t in tri_nodes], dtype=np.int64).reshape(-1, 3)
        facet_sets = {}
        for name, curve in (curves or {}).items():
            _, _, nodes = gmsh.model.mesh.getElements(1, curve)
            facet_sets[name] = np.array([index[int(t)] for t in nodes[0]], dtype=np.int64).reshape(-1, 2)
        used = np.unique(tri)
        renum = -np.ones(len(pts), dtype=np.int64)
        renum[used] = np.arange(len(used))
        tri = renum[tri]
        p = pts[used][tri]
        e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        clockwise = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
        tri[clockwise] = tri[clockwise][:, ::-1]
        return cls(pts[used], tri, facet_sets={k: renum[v] for k, v in facet_sets.items()})

    @classmethod
    def read(cls, path: str | os.PathLike[str], *, joints: Sequence[str] = (), sliver: float = 0.2) -> Mesh:
        """Reads a triangle mesh with meshio (gmsh ``.msh``, ``.vtu``, …).

        Named groups come from the file's cell sets (gmsh physical groups):
        line cells become facet sets, triangle cells element sets, vertex
        cells node sets. A z coordinate must be zero. Nodes no triangle uses
        (gmsh geometry points) are dropped and the rest renumbered; clockwise
        triangles are turned counter-clockwise.

        Parameters
        ----------
        path : str or path
            The file.
        joints : sequence of str
            Names of line groups inside the body (gmsh physical lines
            embedded in the surface) to open into joints, each a contact
            interface of that name (:meth:`open_joints`). A line group not
            named here must lie on the boundary.
        sliver : float
            The sliver check of :meth:`open_joints`.

        Examples
        --------
        >>> mesh = fdem.Mesh.read("tunnel.msh", joints=["set_a", "set_b"])  # doctest: +SKIP
        >>> model.contact(Interface(), interfaces={"set_a": Interface(friction=30)})  # doctest: +SKIP
        """
        import meshio

        try:
            m = meshio.read(os.fspath(path))
        except Exception as exc:  # noqa: BLE001 - meshio raises many types
            raise ValueError(f"{path}: cannot read mesh ({exc})") from None
        pts = np.asarray(m.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3):
            raise ValueError(f"{path}: points must be 2D or 3D, got shape {pts.shape}")
        if pts.shape[1] == 3:
            if np.any(np.abs(pts[:, 2]) > 1e-9 * max(1.0, float(np.abs(pts[:, :2]).max()))):
                k = int(np.argmax(np.abs(pts[:, 2])))
                raise ValueError(f"{path}: node {k} has z = {pts[k, 2]}; fdem meshes are planar (z = 0)")
            pts = pts[:, :2]
        blocks = [(i, b) for i, b in enumerate(m.cells) if b.type == "triangle"]
        if not blocks:
            raise ValueError(f"{path}: no triangle cells (fdem needs linear triangles)")
        if any(b.type in ("triangle6", "quad", "quad8", "quad9") for b in m.cells):
            raise ValueError(f"{path}: only linear triangles are supported; found {[b.type for b in m.cells]}")
        tri = np.concatenate([b.data for _, b in blocks]).astype(np.int64)
        offsets = np.cumsum([0] + [len(b.data) for _, b in blocks])
        used = np.unique(tri)
        renum = -np.ones(len(pts), dtype=np.int64)
        renum[used] = np.arange(len(used))
        pts = pts[used]
        tri = renum[tri]
        p = pts[tri]
        cw = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 2, 0] - p[:, 0, 0]) * (
            p[:, 1, 1] - p[:, 0, 1]
        ) < 0
        tri[cw] = tri[cw][:, [0, 2, 1]]
        node_sets: dict[str, Any] = {}
        facet_sets: dict[str, Any] = {}
        element_sets: dict[str, Any] = {}
        for name, per_block in (m.cell_sets or {}).items():
            if name.startswith("gmsh:"):
                continue
            for bi, idx in enumerate(per_block):
                if idx is None or len(idx) == 0:
                    continue
                block = m.cells[bi]
                idx = np.asarray(idx, dtype=np.int64)
                if block.type == "triangle":
                    start = offsets[[i for i, _ in blocks].index(bi)]
                    element_sets.setdefault(name, []).append(start + idx)
                elif block.type == "line":
                    facet_sets.setdefault(name, []).append(renum[block.data[idx]])
                elif block.type == "vertex":
                    node_sets.setdefault(name, []).append(renum[block.data[idx].ravel()])
        if isinstance(joints, str):
            joints = [joints]
        missing = [j for j in joints if j not in facet_sets]
        if missing:
            raise ValueError(
                f"{path}: no line group named {missing[0]!r} to open as a joint; lines: {sorted(facet_sets)}"
            )
        lines = {j: np.concatenate(facet_sets.pop(j)) for j in joints}
        mesh = cls(
            pts,
            tri,
            node_sets={k: np.concatenate(v) for k, v in node_sets.items()},
            facet_sets={k: np.concatenate(v) for k, v in facet_sets.items()},
            element_sets={k: np.concatenate(v) for k, v in element_sets.items()},
        )
        return mesh.open_joints(lines, sliver=sliver) if lines else mesh


def _hilbert_key(points: NDArray[np.float64], bits: int = 16) -> NDArray[np.uint64]:
    """Index of each point along a Hilbert curve of ``2^bits`` cells a side
    over the points' bounding square (the classic bit-by-bit
    rotate-and-reflect construction, vectorised over the points)."""
    lo = points.min(axis=0)
    span = float((points.max(axis=0) - lo).max()) or 1.0
    n = 1 << bits
    q = np.minimum(((points - lo) / span * n).astype(np.int64), n - 1)
    x, y = q[:, 0].copy(), q[:, 1].copy()
    d = np.zeros(len(points), dtype=np.uint64)
    s = n >> 1
    while s > 0:
        rx = (x & s) > 0
        ry = (y & s) > 0
        d += np.uint64(s) * np.uint64(s) * ((3 * rx.astype(np.uint64)) ^ ry.astype(np.uint64))
        # rotate the quadrant so that the curve inside it starts and ends
        # where the coarser level expects
        flip = ~ry & rx
        x = np.where(flip, n - 1 - x, x)
        y = np.where(flip, n - 1 - y, y)
        swap = ~ry
        x, y = np.where(swap, y, x), np.where(swap, x, y)
        s >>= 1
    return d


def _rebuild(points: Any, triangles: Any, ns: Any, fs: Any, es: Any, iface: Any) -> Mesh:
    return Mesh(points, triangles, node_sets=ns, facet_sets=fs, element_sets=es, interface_nodes=iface)


def gmsh_rectangle(
    width: float,
    height: float,
    size: float,
    *,
    origin: tuple[float, float] = (0.0, 0.0),
    seed: int = 0,
) -> Mesh:
    """An unstructured mesh of a rectangle made with gmsh (the ``gmsh`` extra).

    Parameters
    ----------
    width, height : float
        Size (m).
    size : float
        Target element edge length (m).
    origin : (float, float)
        Lower-left corner (m).
    seed : int
        gmsh's random seed (``Mesh.RandomSeed``), for reproducible meshes.

    The facet sets ``left``, ``right``, ``bottom`` and ``top`` hold the sides.
    """
    try:
        import gmsh
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("gmsh_rectangle needs gmsh: pip install 'fdem[gmsh]'") from exc
    w, h, s = positive("width", width), positive("height", height), positive("size", size)
    x0, y0 = float_array("origin", origin, (2,)).tolist()
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.RandomSeed", int(seed))
        gmsh.model.add("rectangle")
        geo = gmsh.model.geo
        c = [
            geo.addPoint(x0, y0, 0, s),
            geo.addPoint(x0 + w, y0, 0, s),
            geo.addPoint(x0 + w, y0 + h, 0, s),
            geo.addPoint(x0, y0 + h, 0, s),
        ]
        lines = [geo.addLine(c[k], c[(k + 1) % 4]) for k in range(4)]
        surf = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        geo.synchronize()
        for name, line in zip(("bottom", "right", "top", "left"), lines, strict=True):
            gmsh.model.addPhysicalGroup(1, [line], name=name)
        gmsh.model.addPhysicalGroup(2, [surf], name="body")
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.model.mesh.generate(2)
        return Mesh.from_gmsh(dict(zip(("bottom", "right", "top", "left"), lines, strict=True)))
    finally:
        gmsh.finalize()
