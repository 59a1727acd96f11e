"""The description of a model: mesh, materials, loads, supports and initial
state. A :class:`Model` is a plain value (it pickles, and round-trips to a
file with :meth:`Model.save` / :meth:`Model.load`), so a run is a pure function
of its model and settings (DESIGN §9).
"""

from __future__ import annotations

import math
import os
import pickle
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._checks import float_array, number, positive, whole
from .contact import Interface
from .materials import Elastic, MohrCoulombRankine
from .mesh import Mesh

__all__ = ["Amplitude", "Model"]

Material = Elastic | MohrCoulombRankine

_FORMAT = "fdem-model"
_VERSION = 2  # 2: the model as bytes with a SHA-256 checksum


@dataclass(frozen=True)
class Amplitude:
    """A piecewise-linear time history ``factor(t)``, constant beyond its ends.

    Parameters
    ----------
    times : sequence of float
        Sample times (s), strictly increasing.
    values : sequence of float
        Factors at those times.
    """

    times: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        t = float_array("Amplitude times", self.times, (None,))
        v = float_array("Amplitude values", self.values, (None,))
        if len(t) == 0 or len(t) != len(v):
            raise ValueError("Amplitude needs equally many times and values, at least one")
        if np.any(np.diff(t) <= 0):
            raise ValueError("Amplitude times must be strictly increasing")
        object.__setattr__(self, "times", tuple(t.tolist()))
        object.__setattr__(self, "values", tuple(v.tolist()))

    @classmethod
    def ramp(cls, duration: float, start: float = 0.0) -> Amplitude:
        """0 at ``start``, rising linearly to 1 at ``start + duration``."""
        d = number("duration", duration)
        if d <= 0:
            raise ValueError(f"duration = {d} must be positive")
        return cls((start, start + d), (0.0, 1.0))

    def __call__(self, t: float) -> float:
        """The factor at time ``t`` (s)."""
        return float(np.interp(t, self.times, self.values))


@dataclass(frozen=True)
class _Constraint:
    nodes: NDArray[np.int64]
    fixed: tuple[bool, bool]
    value: Any  # (2,) or (n, 2) velocities
    amplitude: Amplitude | None


@dataclass(frozen=True)
class _Pressure:
    facets: NDArray[np.int64]
    pressure: float
    amplitude: Amplitude | None


class Model:
    """A model: a mesh with materials, loads, supports and initial conditions.

    Parameters
    ----------
    mesh : Mesh
        The mesh.
    material : Elastic, optional
        One material for every element.
    materials : mapping of element-set name to material, optional
        Materials by element set; every element must get exactly one.

    Examples
    --------
    >>> import fdem
    >>> mesh = fdem.Mesh.rectangle(2.0, 1.0, 8, 4)
    >>> model = fdem.Model(mesh, material=fdem.Elastic(E=30e9, nu=0.25, rho=2700))
    >>> model.set_gravity(0.0, -9.81).fix("bottom", y=True).fix("left", x=True)  # doctest: +ELLIPSIS
    <fdem.Model ...>
    """

    def __init__(
        self,
        mesh: Mesh,
        material: Material | None = None,
        *,
        materials: Mapping[str, Material] | None = None,
    ) -> None:
        if not isinstance(mesh, Mesh):
            raise ValueError(f"mesh must be a fdem.Mesh, got {type(mesh).__name__}")
        self.mesh = mesh
        if (material is None) == (materials is None):
            raise ValueError("give either material= (one for all elements) or materials= (by element set)")
        self._materials: list[Material] = []
        self._element_material = -np.ones(mesh.n_elements, dtype=np.int64)
        if material is not None:
            self._check_material("material", material)
            self._materials.append(material)
            self._element_material[:] = 0
        else:
            assert materials is not None
            for name, mat in materials.items():
                self._check_material(f"materials['{name}']", mat)
                ids = mesh.elements(name)
                taken = ids[self._element_material[ids] >= 0]
                if len(taken):
                    raise ValueError(f"element {int(taken[0])} of set '{name}' already has a material")
                if mat not in self._materials:
                    self._materials.append(mat)
                self._element_material[ids] = self._materials.index(mat)
            missing = np.flatnonzero(self._element_material < 0)
            if len(missing):
                raise ValueError(f"element {int(missing[0])} has no material (not in any set of materials=)")
        self.gravity: tuple[float, float] = (0.0, 0.0)
        self._constraints: list[_Constraint] = []
        self._pressures: list[_Pressure] = []
        self._initial_velocity: NDArray[np.float64] | None = None
        self._initial_stress: NDArray[np.float64] | None = None
        self._contact: dict[str, Any] | None = None
        self._fracture: dict[str, Any] | None = None
        self._stages: list[tuple[float, NDArray[np.int64]]] = []
        self._stage_ramps: list[float] = []

    @staticmethod
    def _check_material(name: str, m: Any) -> None:
        if not isinstance(m, Elastic):
            raise ValueError(f"{name} must be a fdem material (e.g. fdem.Elastic), got {type(m).__name__}")

    def __repr__(self) -> str:
        return f"<fdem.Model {self.mesh!r}, {len(self._materials)} material(s)>"

    # --- loads and supports ----------------------------------------------
    def set_gravity(self, gx: float, gy: float) -> Model:
        """Gravitational acceleration (m/s²), e.g. ``(0, -9.81)``."""
        self.gravity = (number("gx", gx), number("gy", gy))
        return self

    def fix(self, where: str | Any, *, x: bool = True, y: bool = True) -> Model:
        """Fixes the x and/or y velocity of a group's nodes to zero. A roller
        on a vertical side is ``fix(side, x=True, y=False)``.

        Parameters
        ----------
        where : str or array_like of int
            A group name (node, facet or element set) or node ids.
        """
        if not (x or y):
            raise ValueError("fix needs x=True and/or y=True")
        self._constraints.append(_Constraint(self.mesh.nodes(where), (bool(x), bool(y)), (0.0, 0.0), None))
        return self

    def prescribe_velocity(
        self,
        where: str | Any,
        *,
        vx: float | Callable[[Any, Any], Any] | None = None,
        vy: float | Callable[[Any, Any], Any] | None = None,
        amplitude: Amplitude | None = None,
    ) -> Model:
        """Holds velocity components (m/s) of a group's nodes, scaled by
        ``amplitude(t)`` if given.

        Parameters
        ----------
        where : str or array_like of int
            A group name or node ids.
        vx, vy : float or callable, optional
            A constant, or a function ``f(x, y)`` of the nodes' reference
            coordinates returning one value per node (e.g. a linear field).
            A component left as ``None`` stays free.
        amplitude : Amplitude, optional
            Time history multiplying both components.
        """
        if vx is None and vy is None:
            raise ValueError("prescribe_velocity needs vx and/or vy")
        if amplitude is not None and not isinstance(amplitude, Amplitude):
            raise ValueError("amplitude must be a fdem.Amplitude")
        nodes = self.mesh.nodes(where)
        xy = self.mesh.points[nodes]
        values = np.zeros((len(nodes), 2))
        for d, (name, comp) in enumerate((("vx", vx), ("vy", vy))):
            if comp is None:
                continue
            if callable(comp):
                values[:, d] = float_array(
                    f"{name} (returned by the function)",
                    np.broadcast_to(comp(xy[:, 0], xy[:, 1]), (len(nodes),)),
                    (len(nodes),),
                )
            else:
                values[:, d] = number(name, comp)
        self._constraints.append(_Constraint(nodes, (vx is not None, vy is not None), values, amplitude))
        return self

    def pressure(self, facets: str | Any, p: float, *, amplitude: Amplitude | None = None) -> Model:
        """Follower pressure ``p`` (Pa, positive pushes into the body) on
        boundary facets (a facet-set name or a (k, 2) node-pair array),
        scaled by ``amplitude(t)`` if given."""
        if amplitude is not None and not isinstance(amplitude, Amplitude):
            raise ValueError("amplitude must be a fdem.Amplitude")
        self._pressures.append(_Pressure(self.mesh.facets(facets), number("p", p), amplitude))
        return self

    def contact(
        self,
        default: Interface | None = None,
        *,
        interfaces: Mapping[str, Interface] | None = None,
        cracks: Interface | None = None,
        margin: float | None = None,
    ) -> Model:
        """Switches on contact between all free surfaces (DESIGN §4.5).

        Parameters
        ----------
        default : Interface
            The law of free boundaries (every facet not named below).
        interfaces : mapping of facet-set name to Interface
            Laws of named interfaces, e.g. ``{"joints": Interface(friction=33,
            cohesion=50e3)}`` for the faces of joint sets.
        cracks : Interface
            The law of crack faces inserted during the run (default: the
            default law).
        margin : float, optional
            Broad-phase box enlargement (m); default a fifth of the mean facet
            length. The candidate list is rebuilt when a node has moved half
            of it.
        """
        default = default if default is not None else Interface()
        # every named interface and the cracks get their own law index (even
        # if equal to the default), so that their faces can be told apart in
        # the output
        laws: list[Interface] = [default]
        named: dict[str, int] = {}
        for name, law in (interfaces or {}).items():
            if not isinstance(law, Interface):
                raise ValueError(f"interfaces['{name}'] must be a fdem.Interface")
            self.mesh.facets(name)
            named[name] = len(laws)
            laws.append(law)
        if cracks is not None and not isinstance(cracks, Interface):
            raise ValueError("cracks must be a fdem.Interface")
        laws.append(cracks if cracks is not None else default)
        crack_index = len(laws) - 1
        self._contact = {
            "laws": laws,
            "named": named,
            "crack": crack_index,
            "margin": None if margin is None else positive("margin", margin),
        }
        return self

    def fracture(
        self,
        *,
        check_every: int = 10,
        edge_tolerance: float = 15.0,
        crack_tolerance: float = 30.0,
        min_quality: float = 0.2,
        min_size: float = 0.25,
        insert_at: float = 0.02,
    ) -> Model:
        """Switches on crack insertion by the rotating-crack model (paper
        2.4, DESIGN §4.4). Every ``check_every`` steps
        (:meth:`Simulation.configure` changes it during a run; a due node
        is cut up to that many steps late, docs/fracture.md) the failure factors
        of the elements (κ H / f_t, Mohr–Coulomb + Rankine materials) are
        averaged at the nodes; at every node that has reached 1 a crack is
        opened normal to σ1: along an existing edge within ``edge_tolerance``
        degrees, else through the crossed element (split with its neighbour),
        unless a new triangle would fall below ``min_quality`` (4√3 A / Σ l²,
        1 for equilateral) or have an altitude (2A / longest edge) below
        ``min_size`` times the smallest altitude of the initial mesh, when the
        crack snaps to the nearer edge. The stable time step scales with the
        smallest altitude, so ``min_size`` bounds how far fracturing can
        shrink it. A crack face within ``crack_tolerance`` degrees means the
        direction is already cracked. Only nodes still being driven (an
        adjacent element has fractured further since the previous check) are
        opened: fully softened debris is not cut again and again.

        ``insert_at`` is the nodal failure factor F̄ at which a crack is
        inserted. At 1 (the paper) the softening band has spent all of G_f
        and the new crack is traction-free. Below 1 the crack comes earlier
        and a cohesive bond across it (penalty: the ``cracks`` law's normal
        stiffness) dissipates the rest, (1 − F̄)² G_f: bands of triangles
        lock as they soften (docs/fracture.md) and an early crack sidesteps
        that, so the dissipated energy stays G_f per unit crack length.
        Needs :meth:`contact`: crack faces get its ``cracks`` law.
        """
        check_every = whole("check_every", check_every)
        e, c, q = (
            number("edge_tolerance", edge_tolerance),
            number("crack_tolerance", crack_tolerance),
            number("min_quality", min_quality),
        )
        if not 0 <= e <= 45:
            raise ValueError(f"edge_tolerance = {e} must lie in [0, 45] degrees")
        if not 0 <= c <= 90:
            raise ValueError(f"crack_tolerance = {c} must lie in [0, 90] degrees")
        if not 0 <= q <= 0.9:
            raise ValueError(f"min_quality = {q} must lie in [0, 0.9]")
        f = number("insert_at", insert_at)
        if not 0 < f <= 1:
            raise ValueError(f"insert_at = {f} must lie in (0, 1] (a nodal failure factor)")
        s = number("min_size", min_size)
        if not 0 <= s <= 1:
            raise ValueError(f"min_size = {s} must lie in [0, 1] (a fraction of the smallest initial altitude)")
        self._fracture = {"interval": int(check_every), "edge": e, "crack": c, "quality": q, "size": s, "insert_at": f}
        return self

    # --- staging ----------------------------------------------------------
    def excavate(self, where: str | Any, *, at: float, ramp: float = 0.0) -> Model:
        """Schedules an excavation stage (DESIGN §4.6): the elements of
        ``where`` (an element-set name or element ids) are removed once the
        simulated time reaches ``at`` (s), with every piece crack insertion
        has cut from them by then. Their mass and forces leave their
        nodes; nodes left without elements leave the model; the energy they
        take away is booked as ``excavated``. Stages run in time order.

        With ``ramp`` (s) > 0 the excavation is gradual, as in FLAC and
        UDEC: the forces the removed elements exerted on the nodes that
        stay are applied to those nodes as loads that fall linearly to zero
        over ``ramp``, so the rock around the opening unloads over that
        time instead of at once (an instantaneous excavation of a stressed
        opening sends a release wave that can crack the walls). The loads'
        work is booked as external work."""
        r = number("ramp", ramp)
        if not (r >= 0 and math.isfinite(r)):
            raise ValueError(f"ramp = {r} s must be finite and not negative (the release time of the stage)")
        t = number("at", at)
        if t < 0:
            raise ValueError(f"at = {t} s must not be negative (the time of the excavation stage)")
        ids = self.mesh.elements(where)
        if len(ids) == 0:
            raise ValueError(f"excavation stage at {t} s has no elements")
        self._stages.append((t, np.asarray(ids, dtype=np.int64)))
        ramps = getattr(self, "_stage_ramps", None)
        if ramps is None:  # a model saved before gradual excavation
            ramps = self._stage_ramps = [0.0] * (len(self._stages) - 1)
        ramps.append(r)
        return self

    @property
    def stages(self) -> list[tuple[float, NDArray[np.int64]]]:
        """The scheduled excavation stages ``(time, element ids)``."""
        return list(self._stages)

    # --- initial state ----------------------------------------------------
    def vary_strength(
        self,
        cv: float,
        *,
        where: str | Any | None = None,
        distribution: str = "weibull",
        correlation_length: float | None = None,
        seed: int = 0,
        levels: int = 64,
    ) -> Model:
        """Heterogeneous rock: multiplies the tensile strength ``ft``, the
        cohesion ``c`` and the fracture energies ``Gf`` and ``GII`` of each element's
        Mohr–Coulomb–Rankine material by a random factor of mean 1 and
        coefficient of variation ``cv`` (:func:`fdem.heterogeneity.strength_factors`:
        ``distribution`` ``"weibull"`` or ``"lognormal"``, independent per
        element or correlated over ``correlation_length`` m, from ``seed``,
        in ``levels`` classes, each a material of its own).

        ``ft`` and ``c`` scale together so that ``ft ≤ c cot φ`` holds for
        every factor; ``Gf`` scales with them, so that the crack band's
        snap-back limit ``2 E' Gf / ft²`` falls only as 1/factor. Elastic
        materials and elements outside ``where`` (default: all) keep their
        material. The same seed gives the same model, bit for bit.
        """
        from dataclasses import replace

        from .heterogeneity import strength_factors

        c = float(number("cv", cv))
        ids = np.arange(self.mesh.n_elements) if where is None else self.mesh.elements(where)
        plastic = np.array([isinstance(self._materials[m], MohrCoulombRankine) for m in self._element_material[ids]])
        ids = ids[plastic] if len(ids) else ids
        if len(ids) == 0:
            raise ValueError(
                "vary_strength: no element with a MohrCoulombRankine material"
                + (f" in {where!r}" if where is not None else "")
            )
        factors = strength_factors(
            self.mesh.centroids()[ids],
            cv=c,
            distribution=distribution,
            correlation_length=None
            if correlation_length is None
            else float(positive("correlation_length", correlation_length)),
            seed=int(whole("seed", seed, minimum=0)),
            levels=int(whole("levels", levels)),
        )
        variants: dict[tuple[int, float], int] = {}
        new = self._element_material.copy()
        for e, w in zip(ids.tolist(), factors.tolist(), strict=True):
            key = (int(self._element_material[e]), w)
            if key not in variants:
                base = self._materials[key[0]]
                assert isinstance(base, MohrCoulombRankine)
                variants[key] = len(self._materials)
                gii = None if base.GII is None else base.GII * w
                self._materials.append(replace(base, ft=base.ft * w, c=base.c * w, Gf=base.Gf * w, GII=gii))
            new[e] = variants[key]
        self._element_material = new
        return self

    def set_initial_velocity(
        self, value: tuple[float, float] | Any | Callable[[Any, Any], Any], where: str | Any | None = None
    ) -> Model:
        """Initial velocity (m/s): a constant ``(vx, vy)``, an array of shape
        (n_nodes, 2), or a function ``f(x, y) -> (n, 2)`` of node reference
        coordinates; applied to the nodes of ``where`` (default: all)."""
        nodes = np.arange(self.mesh.n_nodes) if where is None else self.mesh.nodes(where)
        v = self._field("initial velocity", value, self.mesh.points[nodes], 2, len(nodes), self.mesh.n_nodes, nodes)
        if self._initial_velocity is None:
            self._initial_velocity = np.zeros((self.mesh.n_nodes, 2))
        self._initial_velocity[nodes] = v
        return self

    def set_geostatic_stress(
        self,
        *,
        top: float,
        pressure: float = 0.0,
        unit_weight: float | None = None,
        k0: float | None = None,
        where: str | Any | None = None,
    ) -> Model:
        """Geostatic initial stress (DESIGN §4.6, compression negative):
        ``σ_yy = −(p_top + γ (top − y))``, ``σ_xx = K0 σ_yy``,
        ``σ_zz = ν (σ_xx + σ_yy)``, ``σ_xy = 0`` at element centroids.

        Parameters
        ----------
        top : float
            Level of the top face (m), where the vertical stress is ``pressure``.
        pressure : float
            Vertical pressure on the top face (Pa, positive compressive).
        unit_weight : float, optional
            γ (N/m³); default ρ |g| of each element's material with the model's
            gravity.
        k0 : float, optional
            Horizontal-to-vertical stress ratio; default ``ν / (1 − ν)`` of each
            element's material (no lateral strain).
        where : str or element ids, optional
            Elements to set (default all).

        With rollers on the sides this state is in equilibrium under gravity
        and the top pressure; :meth:`fdem.Simulation.equilibrate` removes the
        small imbalance of the discretisation and of closing joints.
        """
        y_top, p_top = number("top", top), number("pressure", pressure)
        elems = np.arange(self.mesh.n_elements) if where is None else self.mesh.elements(where)
        mats = [self._materials[i] for i in self._element_material[elems]]
        nu = np.array([m.nu for m in mats])
        g = float(np.hypot(*self.gravity))
        if unit_weight is None:
            gamma = np.array([m.rho for m in mats]) * g
        else:
            gamma = np.full(len(elems), number("unit_weight", unit_weight))
        if k0 is None:
            ratio = nu / (1 - nu)
        else:
            ratio = np.full(len(elems), number("k0", k0))
            if np.any(ratio < 0):
                raise ValueError(f"k0 = {k0} must be >= 0")
        y = self.mesh.centroids()[elems, 1]
        syy = -(p_top + gamma * (y_top - y))
        sxx = ratio * syy
        stress = np.column_stack([sxx, syy, nu * (sxx + syy), np.zeros(len(elems))])
        return self.set_initial_stress(stress, where=elems if where is not None else None)

    def set_initial_stress(
        self, value: tuple[float, float, float, float] | Any | Callable[[Any, Any], Any], where: str | Any | None = None
    ) -> Model:
        """Initial Cauchy stress ``[xx, yy, zz, xy]`` (Pa, tension positive):
        a constant, an array of shape (n_elements, 4), or a function
        ``f(x, y) -> (n, 4)`` of element centroids; applied to the elements of
        ``where`` (default: all)."""
        elems = np.arange(self.mesh.n_elements) if where is None else self.mesh.elements(where)
        c = self.mesh.centroids()[elems]
        s = self._field("initial stress", value, c, 4, len(elems), self.mesh.n_elements, elems)
        if self._initial_stress is None:
            self._initial_stress = np.zeros((self.mesh.n_elements, 4))
        self._initial_stress[elems] = s
        return self

    @staticmethod
    def _field(name: str, value: Any, xy: Any, cols: int, n: int, total: int, ids: Any) -> NDArray[np.float64]:
        if callable(value):
            out = value(xy[:, 0], xy[:, 1])
            label = f"{name} (returned by the function)"
            if isinstance(out, (tuple, list)) and len(out) == cols:
                # one entry per component, each a scalar or an array over the points
                try:
                    out = np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), (n,)) for c in out])
                except ValueError as exc:
                    raise ValueError(f"{label}: each of the {cols} components must be a number or {n} values") from exc
            try:
                out = np.broadcast_to(out, (n, cols))
            except ValueError:
                raise ValueError(
                    f"{label}: expected shape ({n}, {cols}) or {cols} components, got shape {np.shape(out)}"
                ) from None
            return float_array(label, out, (n, cols))
        if np.ndim(value) == 1:
            return np.broadcast_to(float_array(name, value, (cols,)), (n, cols)).copy()
        full = float_array(name, value, (None, cols))
        if len(full) == total:
            return full[ids]
        if len(full) == n:
            return full
        raise ValueError(f"{name}: expected {total} or {n} rows, got {len(full)}")

    # --- persistence ------------------------------------------------------
    def save(self, path: str | os.PathLike[str]) -> None:
        """Writes the model to a file (pickle with a format header and a
        SHA-256 checksum of the model's bytes), atomically."""
        import hashlib

        body = pickle.dumps(self, protocol=4)
        from .output import atomic_path

        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            pickle.dump(
                {"format": _FORMAT, "version": _VERSION, "sha256": hashlib.sha256(body).hexdigest(), "body": body},
                f,
                protocol=4,
            )

    @staticmethod
    def load(path: str | os.PathLike[str]) -> Model:
        """Reads a model written by :meth:`save`. A damaged or edited file
        (its checksum does not match) is a ValueError naming the file.
        Only load files you trust (the format is a pickle)."""
        import hashlib

        try:
            with open(path, "rb") as f:
                data = pickle.load(f)
        except Exception as exc:  # noqa: BLE001 - a damaged pickle raises anything
            raise ValueError(f"{path}: not a readable fdem model file ({type(exc).__name__}: {exc})") from None
        if not isinstance(data, dict) or data.get("format") != _FORMAT:
            raise ValueError(f"{path}: not an fdem model file")
        version = data.get("version", 0)
        if not isinstance(version, int) or version > _VERSION:
            raise ValueError(f"{path}: written by a newer fdem (format {version!r} > {_VERSION})")
        if version >= 2:
            body = data.get("body")
            if not isinstance(body, bytes) or hashlib.sha256(body).hexdigest() != data.get("sha256"):
                raise ValueError(f"{path}: damaged fdem model file (its checksum does not match)")
            try:
                model = pickle.loads(body)
            except Exception as exc:  # noqa: BLE001
                raise ValueError(f"{path}: damaged fdem model file ({type(exc).__name__}: {exc})") from None
        else:
            model = data.get("model")
        if not isinstance(model, Model):
            raise ValueError(f"{path}: damaged fdem model file (no model in it)")
        return model

    # --- kernel arrays ----------------------------------------------------
    def _amplitude_table(self) -> list[Amplitude]:
        table: list[Amplitude] = []
        for a in [c.amplitude for c in self._constraints] + [p.amplitude for p in self._pressures]:
            if a is not None and a not in table:
                table.append(a)
        return table

    def kernel_arrays(self) -> dict[str, Any]:
        """The arrays the native kernel is built from (for inspection)."""
        amps = self._amplitude_table()
        amp_id = lambda a: -1 if a is None else amps.index(a)  # noqa: E731
        cn, cf, cv, ca = [], [], [], []
        for c in self._constraints:
            k = len(c.nodes)
            cn.append(c.nodes)
            cf.append(np.tile(c.fixed, (k, 1)))
            cv.append(np.broadcast_to(np.asarray(c.value, dtype=np.float64), (k, 2)))
            ca.append(np.full(k, amp_id(c.amplitude), dtype=np.int64))
        pf, pv, pa = [], [], []
        for p in self._pressures:
            k = len(p.facets)
            pf.append(p.facets)
            pv.append(np.full(k, p.pressure))
            pa.append(np.full(k, amp_id(p.amplitude), dtype=np.int64))
        out: dict[str, Any] = {
            "points": np.ascontiguousarray(self.mesh.points),
            "triangles": np.ascontiguousarray(self.mesh.triangles),
            "materials": [m._kernel_dict() for m in self._materials],
            "element_material": self._element_material.copy(),
            "may_coincide": np.ascontiguousarray(self.mesh.interface_nodes),
            "gravity": self.gravity,
            "amplitudes": [(list(a.times), list(a.values)) for a in amps],
            "initial_velocity": self._initial_velocity,
            "initial_stress": self._initial_stress,
            "stage_times": [t for t, _ in self._stages],
            "stage_elements": [ids for _, ids in self._stages],
            "stage_ramps": list(getattr(self, "_stage_ramps", None) or [0.0] * len(self._stages)),
        }
        if cn:
            out.update(
                constraint_nodes=np.concatenate(cn),
                constraint_fixed=np.ascontiguousarray(np.concatenate(cf).astype(bool)),
                constraint_values=np.concatenate(cv).astype(np.float64),
                constraint_amplitude=np.concatenate(ca),
            )
        if self._contact is not None:
            young = max(m.E for m in self._materials)
            bf = self.mesh.boundary_facets()
            size = float(np.linalg.norm(np.diff(self.mesh.points[bf], axis=1), axis=2).mean())
            c = self._contact
            facets = [self.mesh.facets(name) for name in c["named"]]
            laws = [np.full(len(f), law, dtype=np.int64) for f, law in zip(facets, c["named"].values(), strict=True)]
            out.update(
                contact_laws=np.array([law._kernel_row(young, size) for law in c["laws"]], dtype=np.float64),
                contact_facets=np.concatenate(facets) if facets else np.zeros((0, 2), dtype=np.int64),
                contact_facet_laws=np.concatenate(laws) if laws else np.zeros(0, dtype=np.int64),
                crack_law=c["crack"],
                contact_margin=c["margin"],
            )
        if self._fracture is not None:
            if self._contact is None:
                raise ValueError("fracture needs contact: call model.contact(...) (crack faces are contact surfaces)")
            f = self._fracture
            out.update(
                fracture_interval=whole("check_every", f["interval"]),
                fracture_edge_tolerance=f["edge"],
                fracture_crack_tolerance=f["crack"],
                fracture_min_quality=f["quality"],
                fracture_min_altitude=f["size"] * _smallest_altitude(self.mesh),
                fracture_insert_at=f["insert_at"],
            )
        if pf:
            out.update(
                pressure_facets=np.concatenate(pf),
                pressure_values=np.concatenate(pv),
                pressure_amplitude=np.concatenate(pa),
            )
        return out


def _smallest_altitude(mesh: Mesh) -> float:
    """Smallest altitude 2A / l_max over the triangles of ``mesh`` (m)."""
    p = mesh.points[mesh.triangles]
    e = np.roll(p, -1, axis=1) - p
    area2 = np.abs(e[:, 0, 0] * e[:, 1, 1] - e[:, 0, 1] * e[:, 1, 0])
    longest = np.sqrt((e**2).sum(axis=2).max(axis=1))
    return float((area2 / longest).min())
