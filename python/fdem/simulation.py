"""Running a model: :class:`Simulation` drives the native time loop and
writes results.

Over 800 lines because it is one class, the user's whole handle on a run:
stepping, checkpoints, energies, readouts and output are sixty short,
documented methods of it, each a thin call into the kernel; split by topic
they would still be one class's methods, only harder to find.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time as _time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _core
from ._checks import float_array, index_array, number, positive, whole
from .errors import CheckpointError, EnergyBalanceError, EnergyBalanceWarning, SimulationError
from .model import Model
from .output import VtuSeries, stress_at, write_vtu
from .progress import RunProgress

__all__ = ["Simulation"]


class Simulation:
    """An explicit FDEM run of a :class:`Model`.

    Parameters
    ----------
    model : Model
        What to simulate (copied into the kernel; later changes to the model
        do not affect this simulation).
    threads : int, optional
        Worker threads (default: all cores). Results are bit-for-bit the same
        for any count.
    safety : float
        Safety factor ``s`` on the critical step (0 < s ≤ 1): the step is
        ``s`` times the least of every element's ``2/ω_e`` and, with contact,
        every boundary node's ``2/√(ω_e² + ω_c²)`` (``ω_c`` its penalty
        springs' frequency) and, when some interface law has a damping
        ratio below 0.1, ``1/ω_c``, which keeps the onsets of an undamped,
        rattling contact from changing the energy (docs/contact.md).
    dt : float, optional
        A fixed time step (s) instead of the automatic one.
    mass_damping : float
        Mass-proportional damping ``α`` (1/s).
    stiffness_damping : float
        Stiffness-proportional (element viscous) damping ``β`` (s).
    local_damping : float
        Local (non-viscous) damping ``α_L`` in [0, 1), as in FLAC and UDEC
        (Cundall 1987): each free velocity component of a node feels
        ``−α_L |f| sign(v)`` on top of its net force ``f``. It damps what
        accelerates, not steady motion, and a linear oscillator keeps
        ``√((1 − α_L)/(1 + α_L))`` of its amplitude every half cycle at
        any frequency (1/3 at FLAC's 0.8 for statics). For equilibrium and
        excavation stages; 0 (off) by default; its work is booked as
        ``damping`` in :meth:`energies`.
    dt_interval : int
        Steps between re-evaluations of the automatic stable step.
    energy_growth : float
        Watchdog: stop with :class:`fdem.errors.EnergyGrowthError` when the
        energy balance shows more energy created (minus its residual) than
        this fraction of its largest term (default 5%; checked every 50
        steps). A stable run creates well under 1%; an unstable one grows
        exponentially and is caught within those steps. 0 turns it off.
    mass_scaling : float, optional
        Selective mass scaling: the time step Δt (s) to hold. Where an
        element, or a contact node with its penalty springs, would need a
        shorter step than ``mass_scaling / safety``, the density of its
        elements is raised by the factor that makes it meet that step, no
        more (LS-DYNA's DT2MS idea). Masses are only raised at set-up, at
        settings changes and when the topology changes (cracks,
        excavation); a mass raised during the run keeps the node's
        momentum, and the kinetic energy this takes is the ``mass_scaling``
        term of :meth:`energies`. Added mass is real mass: gravity acts on
        it. :meth:`added_mass` and :meth:`mass_scale` report where and how
        much (docs/mass_scaling.md). ``None`` (default): every mass is
        physical.
    renumber : float, optional
        Spatial renumbering for memory locality (docs/renumbering.md): once
        crack insertion has grown the element count by this fraction (e.g.
        0.05) since the last renumbering, the kernel puts its nodes and
        elements back in the order of a Hilbert curve through their current
        positions. Ids do not change: every array and id this class reports
        or takes stays in creation order (the model's nodes and elements,
        then those crack insertion made, in the order it made them). Results
        differ from a run without it only in the order of floating-point
        sums. Default 0.05: it makes a fragmenting run faster (the 10⁴
        element impact of ``benchmarks/fracture_impact.py`` 2.6 against
        2.0×10⁶ element-updates/s on one thread), and a run that hardly
        cracks is never renumbered. ``None``: never.
    renumber_every : int, optional
        With ``renumber`` set, also renumber at every multiple of this many
        steps, whatever the growth: falling, mixing rock spoils the order
        too (the block-caving case uses 1000). ``None`` (default): on
        growth only.

    Raises
    ------
    ValueError
        For any invalid model or setting, naming the node, element or
        parameter.
    """

    def __init__(
        self,
        model: Model,
        *,
        threads: int | None = None,
        safety: float = 0.8,
        dt: float | None = None,
        mass_damping: float = 0.0,
        stiffness_damping: float = 0.0,
        dt_interval: int = 100,
        energy_growth: float = 0.05,
        mass_scaling: float | None = None,
        renumber: float | None = 0.05,
        renumber_every: int | None = None,
        local_damping: float = 0.0,
    ) -> None:
        if not isinstance(model, Model):
            raise ValueError(f"model must be a fdem.Model, got {type(model).__name__}")
        if threads is not None:
            threads = whole("threads", threads, maximum=4096)
        self.model = model
        self._settings = self._check_settings(
            safety,
            dt,
            mass_damping,
            stiffness_damping,
            dt_interval,
            energy_growth,
            mass_scaling,
            renumber,
            local_damping,
            renumber_every,
        )
        arrays = model.kernel_arrays()
        self._fingerprint = _fingerprint(arrays)
        self._core = _core.Simulation(**arrays, **self._settings, threads=int(threads or 0))
        self._check_start(model)
        self._series: dict[tuple[str, str], VtuSeries] = {}
        self._resume: dict[tuple[str, str], dict[str, Any]] = {}
        self.user_data: dict[str, Any] = {}
        """The caller's own bookkeeping (JSON-serialisable: numbers, strings,
        lists, dicts), saved in every checkpoint and given back by
        :meth:`from_checkpoint`: a driver script that keeps tables beside the
        run (probe histories, counters) stores them here, so that they always
        match the state they were saved with."""

    def _check_start(self, model: Model) -> None:
        """Refuses a start that can only give infinities: a stable step that
        is not a positive finite number (a modulus or density at the ends of
        the float range), or an initial state whose energy is not finite."""
        dt = self._core.time_step
        if not (math.isfinite(dt) and dt > 1e-300):
            speeds = [(m, math.sqrt(m.E / m.rho) if m.rho > 0 else math.inf) for m in model._materials]
            worst = max(speeds, key=lambda p: abs(math.log(p[1])) if 0 < p[1] < math.inf else math.inf)[0]
            raise ValueError(
                f"the stable time step is {dt:g} s: E = {worst.E:g} Pa and rho = {worst.rho:g} kg/m³ give a wave "
                "speed of zero or infinity; check the material's units"
            )
        e = self._core.energies()
        if not (math.isfinite(e["elastic_initial"]) and math.isfinite(e["kinetic_initial"])):
            stress = model._initial_stress
            if stress is not None and not np.all(np.isfinite(stress) & (np.abs(stress) < 1e150)):
                k = int(np.argmax(np.where(np.isfinite(stress), np.abs(stress), np.inf).max(axis=1)))
                raise ValueError(f"initial stress of element {k} is {stress[k].tolist()} Pa: its energy is not finite")
            raise ValueError("the initial state's energy is not finite: check the initial stress and velocities")

    @staticmethod
    def _check_settings(
        safety: Any,
        dt: Any,
        alpha: Any,
        beta: Any,
        interval: Any,
        growth: Any,
        scaling: Any,
        renumber: Any,
        local: Any = 0.0,
        every: Any = None,
    ) -> dict[str, Any]:
        s = number("safety", safety)
        if not 0 < s <= 1:
            raise ValueError(f"safety = {s} must lie in (0, 1]")
        a_local = number("local_damping", local)
        if not 0 <= a_local < 1:
            raise ValueError(f"local_damping = {a_local} must lie in [0, 1) (FLAC's default for statics is 0.8)")
        return {
            "local_damping": a_local,
            "safety": s,
            "fixed_dt": None if dt is None else positive("dt", dt),
            "mass_damping": positive("mass_damping", alpha, allow_zero=True),
            "stiffness_damping": positive("stiffness_damping", beta, allow_zero=True),
            "dt_interval": whole("dt_interval", interval),
            "energy_growth": positive("energy_growth", growth, allow_zero=True),
            "mass_scaling": None if scaling is None else positive("mass_scaling", scaling),
            "renumber": None if renumber is None else positive("renumber", renumber),
            "renumber_every": None if every is None else whole("renumber_every", every),
        }

    def configure(self, **changes: Any) -> Simulation:
        """Changes run settings between stages (``safety``, ``dt``,
        ``mass_damping``, ``stiffness_damping``, ``local_damping``, ``dt_interval``,
        ``energy_growth``, ``mass_scaling``, ``renumber``,
        ``renumber_every``, ``check_every``). Turning mass scaling on, or raising its step,
        scales masses at once; turning it off keeps the
        masses added so far. ``check_every`` is the number of steps between
        fracture checks (:meth:`Model.fracture`; the model must have
        fracture), saved with the run."""
        known = {
            "safety",
            "dt",
            "mass_damping",
            "stiffness_damping",
            "local_damping",
            "dt_interval",
            "energy_growth",
            "mass_scaling",
            "renumber",
            "renumber_every",
            "check_every",
        }
        unknown = set(changes) - known
        if unknown:
            raise ValueError(f"unknown setting(s) {sorted(unknown)}; known: {sorted(known)}")
        steps = None
        if "check_every" in changes:
            steps = whole("check_every", changes.pop("check_every"))
            if self._core.fracture_interval is None:
                raise ValueError("check_every: the model has no fracture (Model.fracture) to check")
        settings = self._settings
        if changes:
            cur = dict(self._settings)
            cur["dt"] = cur.pop("fixed_dt")
            cur.update(changes)
            settings = self._check_settings(
                cur["safety"],
                cur["dt"],
                cur["mass_damping"],
                cur["stiffness_damping"],
                cur["dt_interval"],
                cur["energy_growth"],
                cur["mass_scaling"],
                cur["renumber"],
                cur.get("local_damping", 0.0),
                cur.get("renumber_every"),
            )
        # everything checked before anything changes
        if steps is not None:
            self._core.set_fracture_interval(steps)
        if changes:
            self._settings = settings
            self._core.set_settings(**settings)
        return self

    # --- state ------------------------------------------------------------
    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return float(self._core.time)

    @property
    def steps(self) -> int:
        """Steps taken."""
        return int(self._core.steps)

    @property
    def n_nodes(self) -> int:
        """Nodes now (crack insertion adds some)."""
        return int(self._core.n_nodes)

    @property
    def n_elements(self) -> int:
        """Elements now (crack insertion splits some)."""
        return int(self._core.n_elements)

    @property
    def check_every(self) -> int | None:
        """Steps between fracture checks (``None`` without fracture):
        :meth:`Model.fracture`'s ``check_every`` or the last
        :meth:`configure`'s."""
        n = self._core.fracture_interval
        return None if n is None else int(n)

    @property
    def time_step(self) -> float:
        """The step in use (s)."""
        return float(self._core.time_step)

    @property
    def critical_time_step(self) -> float:
        """``min_e 2/ω_e`` of the current mesh (s), before the safety factor."""
        return float(self._core.critical_time_step)

    @property
    def threads(self) -> int:
        """Worker threads."""
        return int(self._core.threads)

    def positions(self) -> NDArray[np.float64]:
        """Current node coordinates (m), shape (n_nodes, 2), a copy."""
        return self._core.positions()

    def reference_positions(self) -> NDArray[np.float64]:
        """Reference node coordinates (m), shape (n_nodes, 2)."""
        return self._core.reference_positions()

    def displacements(self) -> NDArray[np.float64]:
        """Node displacements from the reference configuration (m)."""
        return self._core.positions() - self._core.reference_positions()

    def velocities(self) -> NDArray[np.float64]:
        """Node velocities at the current whole step (m/s)."""
        return self._core.velocities()

    def reaction_forces(self) -> NDArray[np.float64]:
        """Reaction forces (N per unit thickness), shape (n_nodes, 2): the
        force each node's support (a fixed or prescribed velocity
        component, :meth:`Model.fix`, :meth:`Model.prescribe_velocity`)
        exerts on the model at the current whole step; zero for free nodes
        and components. It is the force that gives a held node its
        prescribed velocity against the elements, loads, gravity, contact
        and mass damping acting on it (the term whose work is the energy
        ledger's ``support_work``)."""
        return self._core.reaction_forces()

    def node_origins(self) -> NDArray[np.int64]:
        """The node of the model each node descends from (crack insertion
        copies nodes; a copy of a held node keeps its support)."""
        return self._core.node_origins()

    def _group_nodes(self, where: str | Any) -> NDArray[np.bool_]:
        """Which nodes now belong to the model's node group ``where``: its
        nodes and the copies crack insertion made of them."""
        return np.isin(self._core.node_origins(), self.model.mesh.nodes(where))

    def reaction(self, where: str | Any) -> dict[str, Any]:
        """The load on a support: the force the model exerts on the
        supports of the node group ``where`` (a group name or node ids of
        the model; their copies made by crack insertion included), and the
        group's mean displacement, at the current whole step.

        Returns ``{"force": (2,) N per unit thickness, "displacement": (2,)
        m, "nodes": int}``. The force is minus the sum of
        :meth:`reaction_forces` over the group: a platen pressing down on a
        specimen (prescribed ``vy < 0``) reads a positive ``force[1]``, the
        specimen pushing it back up."""
        mask = self._group_nodes(where)
        r = self._core.reaction_forces()[mask]
        u = self.displacements()[mask]
        return {"force": -r.sum(axis=0), "displacement": u.mean(axis=0), "nodes": int(mask.sum())}

    def probe(self, where: Any) -> dict[str, NDArray[np.float64]]:
        """The state at a probe now. ``where`` is a point ``(x, y)`` (m, in
        the current configuration): ``{"stress": [xx, yy, zz, xy]}`` (Pa)
        of the element holding it, NaN in a void; or a node group (a group
        name or node ids of the model, with the copies crack insertion
        made of them): ``{"displacement": (2,), "velocity": (2,)}``, means
        over its nodes (m, m/s)."""
        if _is_point(where):
            return {"stress": stress_at(self, [[float(where[0]), float(where[1])]])[0]}
        mask = self._group_nodes(where)
        return {
            "displacement": self.displacements()[mask].mean(axis=0),
            "velocity": self.velocities()[mask].mean(axis=0),
        }

    def stress(self) -> NDArray[np.float64]:
        """Cauchy stress per element ``[xx, yy, zz, xy]`` (Pa, tension positive)."""
        return self._core.stress()

    def triangles(self) -> NDArray[np.int64]:
        """Current connectivity (changes when cracks are inserted)."""
        return self._core.triangles()

    def masses(self) -> NDArray[np.float64]:
        """Lumped nodal masses (kg per unit thickness), the ones the
        equation of motion uses: with mass scaling, physical plus added."""
        return self._core.masses()

    def mass_scale(self) -> NDArray[np.float64]:
        """Each element's density factor from mass scaling (1 where its
        mass is physical)."""
        return self._core.mass_scale()

    @property
    def added_mass(self) -> float:
        """Mass added by mass scaling to the active elements, ``Σ (s_e − 1)
        ρ_e A_e`` (kg per unit thickness); :meth:`masses` sums to the
        physical mass plus this."""
        return float(self._core.added_mass())

    def areas(self) -> NDArray[np.float64]:
        """Current element areas (m²)."""
        return self._core.areas()

    def active(self) -> NDArray[np.bool_]:
        """Whether each element is active (not excavated)."""
        return self._core.active()

    def element_state(self) -> dict[str, NDArray[np.float64]]:
        """Per-element material state: ``kappa`` (fracturing strain κ),
        ``crack_band`` (h_c, m; 0 before the first crack), ``failure_factor``
        (κ H / f_t, eq. 2.21), ``crack_direction`` (direction of σ1 at the last
        tensile plastic step, rad, current frame), ``plastic_strain`` (n, 4,
        current frame) and ``equivalent_plastic_strain``."""
        return dict(self._core.element_state())

    def contacts(self) -> dict[str, NDArray[Any]]:
        """The active contacts: ``node``, ``facet`` (n, 2) node pairs, ``xi``
        (position on the facet), ``gap`` (m, negative = penetration),
        ``normal_force`` and ``tangential_force`` (N/m), ``slipping``, and
        ``offset`` (m): the penetration the spring does not count, the depth
        at which a node found already inside the facet's element was taken
        up (docs/contact.md, "Which facet a node touches", item 7; 0 for a
        contact entered through the facet's line)."""
        return dict(self._core.contacts())

    def contact_stats(self) -> dict[str, int]:
        """Contact-search counters: ``pairs_evaluated`` (candidate pairs
        tested, all steps; a contact whose last facet still holds tests only
        that one), ``broad_phase_builds``, ``candidate_pairs`` (now),
        ``contacts`` (now)."""
        return dict(self._core.contact_stats())

    @property
    def insertions(self) -> int:
        """Cracks inserted so far (nodes opened); 0 without fracture."""
        return int(self._core.insertions or 0)

    def phase_times(self) -> dict[str, float]:
        """Wall-clock seconds spent so far in each phase of the step
        (``nodes``, ``elements``, ``broad_phase``, ``surface``, ``time_step``,
        ``fracture``, ``topology``); for profiling, results never depend on
        them. On more than one thread the contact's assembly (part of
        ``surface``) runs beside the element pass (``elements``), so their
        clocks overlap."""
        return dict(self._core.phase_times())

    def surface_facets(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """The free-surface facets (n, 2), body on their left, and the index of
        each one's interface law (0: free boundary)."""
        return self._core.surface_facets()

    def crack_faces(self) -> NDArray[np.float64]:
        """The faces of the inserted cracks at their current positions,
        (k, 2, 2) (m): each face's two end points, a crack having two faces;
        empty without fracture."""
        f = self._crack_facets()
        x = self.positions()
        return np.stack([x[f[:, 0]], x[f[:, 1]]], axis=1) if len(f) else np.zeros((0, 2, 2))

    def _crack_facets(self) -> NDArray[np.int64]:
        """Node pairs (k, 2) of the surface facets that are crack faces."""
        if self.model._contact is None:
            return np.zeros((0, 2), dtype=np.int64)
        facets, laws = self.surface_facets()
        return facets[laws == self.model._contact["crack"]]

    def crack_length(self, along: Any = None) -> float:
        """Length of material the inserted cracks have cut (m, per unit
        thickness): half the reference length of all crack faces (a crack
        has two), so a crack is measured as it was cut, not as it opened.
        With ``along`` (a direction ``(x, y)``), the cracks' projection on
        that direction instead: ``½ Σ |t·e|`` over the faces, with ``t``
        a face's reference vector and ``e`` the unit direction. Fracture
        energy per unit crack length, the crack band's measure, uses the
        projection on the line the crack runs along overall (a tension
        bar's width, a beam's ligament): a crack zigzagging through
        triangles is longer than the band it cuts. 0 without fracture."""
        if self.model._contact is None:
            return 0.0
        f = self._crack_facets()
        x = self.reference_positions()
        t = x[f[:, 1]] - x[f[:, 0]]
        if along is None:
            return 0.5 * float(np.hypot(t[:, 0], t[:, 1]).sum())
        e = np.asarray(along, dtype=np.float64).reshape(2)
        norm = float(np.hypot(*e))
        if not (norm > 0 and math.isfinite(norm)):
            raise ValueError(f"along = {along!r} must be a nonzero direction (x, y)")
        return 0.5 * float(np.abs(t @ (e / norm)).sum())

    def insertion_audit(self) -> dict[str, float] | None:
        """The largest relative change of total ``mass`` and of linear
        ``momentum`` (over Σ m|v|) any crack insertion has caused so far;
        both are zero in exact arithmetic (DESIGN §4.4). ``None`` without
        fracture."""
        return self._core.insertion_audit()

    def bonds(self) -> dict[str, NDArray[Any]]:
        """The intact cohesive bonds across cracks inserted before full
        softening (``Model.fracture(insert_at=...)``): ``nodes`` (k, 2),
        ``length`` (m), ``strength`` (Pa), ``final_opening`` (m: ``2 G_I /
        strength``, where the traction ends in pure opening unless the bond
        continues a bilinear curve's kink), ``max_opening`` (m), ``damage`` (0–1) and ``offset`` (k, 2) (m: the
        opening with which a bond took over the force through its node when
        its crack was inserted, docs/fracture.md)."""
        return self._core.bonds()

    def energies(self) -> dict[str, float]:
        """The energy account (J per unit thickness): ``kinetic``, ``elastic``,
        ``external_work``, ``support_work``, damping and dissipation terms,
        and the balance ``residual``."""
        return dict(self._core.energies())

    # --- stepping ---------------------------------------------------------
    def step(self, n: int = 1) -> Simulation:
        """Advances exactly ``n`` steps."""
        self._core.step(whole("n", n, minimum=0, maximum=2**63 - 1))
        return self

    # --- staging ----------------------------------------------------------
    @property
    def renumberings(self) -> int:
        """How often the kernel has renumbered its nodes and elements
        (``renumber`` setting or :meth:`renumber`)."""
        return int(self._core.renumberings)

    def renumber(self) -> Simulation:
        """Puts the kernel's nodes and elements in the order of a Hilbert
        curve through their current positions now, as the ``renumber``
        setting does during a run (docs/renumbering.md): e.g. after
        restoring a run made without it. Ids and results do not change,
        bar the order of floating-point sums in the steps that follow."""
        self._core.renumber()
        return self

    def deactivate(self, where: str | Any, *, descendants: bool = True, ramp: float = 0.0) -> int:
        """Removes elements now, as an excavation stage would; returns how
        many were removed (already removed ones are skipped).

        ``where`` is an element-set name of the model's mesh or element ids.
        An id names the rock that element was when it was made: with
        ``descendants`` (the default, and what excavation stages do) every
        piece crack insertion has cut from it since goes with it, so a set
        name or the model's element ids remove the set as it is now, pieces
        included (:meth:`elements` lists them). ``descendants=False``
        removes exactly the elements named, by their current ids (e.g. one
        fragment's elements), and leaves pieces cut from them elsewhere.
        With ``ramp`` (s) > 0 their forces on the nodes that stay are
        released over that time (:meth:`Model.excavate`).
        """
        if isinstance(where, str):
            ids = self.model.mesh.elements(where)
        else:
            ids = index_array("elements", where, (None,))  # the kernel names a missing one
        r = number("ramp", ramp)
        if not (r >= 0 and math.isfinite(r)):
            raise ValueError(f"ramp = {r} s must be finite and not negative")
        return int(self._core.deactivate(np.ascontiguousarray(ids, dtype=np.int64), bool(descendants), r))

    def elements(self, where: str | Any) -> NDArray[np.int64]:
        """The elements now (ids, ascending, removed ones included) of an
        element set of the model's mesh or of the model's elements ``where``
        (ids): those elements and every piece crack insertion has cut from
        them. Pieces are in every set their model element is in, and have
        its material (docs/fracture.md)."""
        ids = self.model.mesh.elements(where) if isinstance(where, str) else index_array("elements", where, (None,))
        ids = np.asarray(ids, dtype=np.int64)
        m = self.model.mesh.n_elements
        if ids.size and int(ids.max()) >= m:
            raise ValueError(f"elements: id {int(ids.max())} is not an element of the model (it has {m})")
        return np.flatnonzero(np.isin(self._core.element_origins(), ids))

    def element_origins(self) -> NDArray[np.int64]:
        """Each element's origin: the element of the model (id) it descends
        from through crack insertion; itself for an element of the model.
        An element is in every element set its origin is in."""
        return self._core.element_origins()

    def element_parents(self) -> NDArray[np.int64]:
        """Each element's parent: the element (id) crack insertion cut it
        from, itself for an element of the model (a parent's id is below
        its piece's)."""
        return self._core.element_parents()

    @property
    def stages_done(self) -> int:
        """Excavation stages (``Model.excavate``) run so far."""
        return int(self._core.stages_done)

    def equilibrate(
        self,
        *,
        max_velocity: float = 1e-3,
        damping: float | None = None,
        max_time: float | None = None,
        check_every: int = 50,
        restart_clock: bool = True,
        elastic: bool = True,
        progress: bool = False,
        local_damping: float | None = None,
    ) -> dict[str, float]:
        """A damped equilibrium stage (DESIGN §4.6): runs with mass damping
        until the largest node speed is below ``max_velocity`` (m/s), then
        restores the run's damping and, with ``restart_clock``, starts the
        clock (and the energy account) again at t = 0, so that excavation
        stages are timed from the equilibrium.

        Parameters
        ----------
        damping : float, optional
            Mass damping α (1/s) for the stage; default ``π c_p / H``, critical
            for the fundamental mode of a column of height ``H`` (the mesh's
            larger extent) and P-wave speed ``c_p`` of the stiffest material.
        max_time : float, optional
            Give up (``RuntimeError``) after this much simulated time; default
            100 ``H / c_p``.
        check_every : int
            Steps between checks of the largest speed.
        elastic : bool
            Run the stage elastically: no plastic flow, softening or crack
            insertion until it ends. The start from a geostatic stress is not
            in equilibrium where joints and free faces meet the initial
            stress, and its transient would otherwise crack the rock (with
            f_t small against the in-situ stress) before any excavation.
        local_damping : float, optional
            Damp the stage with local damping ``α_L`` (e.g. 0.8, FLAC's
            default for statics; see the class's ``local_damping``) instead
            of mass damping. Mass damping resists any motion, the slow creep
            of loosening blocks too; local damping only what accelerates.

        Returns a dict with the stage's ``time`` (s), ``steps`` and final
        ``max_velocity``.
        """
        tol = positive("max_velocity", max_velocity)
        lo, hi = self.model.mesh.points.min(axis=0), self.model.mesh.points.max(axis=0)
        height = float(max(hi - lo))
        cp = max(m.p_wave_speed for m in self.model._materials)
        alpha = np.pi * cp / height if damping is None else positive("damping", damping)
        limit = 100 * height / cp if max_time is None else positive("max_time", max_time)
        before = dict(self._settings)
        if local_damping is None:
            self.configure(mass_damping=alpha)
        else:
            self.configure(mass_damping=0.0, local_damping=local_damping)
        self._core.set_elastic_stage(bool(elastic))
        t0, s0 = self.time, self.steps
        speed = np.inf
        try:
            while True:
                self._core.step(int(check_every))
                v = self._core.velocities()
                speed = float(np.sqrt((v * v).sum(axis=1).max())) if len(v) else 0.0
                if progress:
                    print(f"equilibrium: t = {self.time - t0:.4f} s, max speed {speed:.2e} m/s", flush=True)
                if speed < tol:
                    break
                if self.time - t0 > limit:
                    raise RuntimeError(
                        f"no equilibrium after {self.time - t0:.3g} s: largest speed {speed:.3g} m/s "
                        f"> {tol:g} m/s (raise max_time or damping)"
                    )
        finally:
            self._core.set_elastic_stage(False)
            self._settings = before
            self._core.set_settings(**self._settings)
        result = {"time": self.time - t0, "steps": float(self.steps - s0), "max_velocity": speed}
        if restart_clock:
            self._core.restart_clock()
        return result

    def fragment_labels(self) -> NDArray[np.int64]:
        """The fragment of every element: active elements that share a node
        form one fragment, numbered from 0; excavated elements get -1."""
        return self._core.fragment_labels()

    def fragments(self, where: Any = None) -> dict[str, NDArray[Any]]:
        """Fragments (bodies) now: per fragment its ``area`` (m²), ``mass``
        (kg per unit thickness), ``centroid`` (k, 2), the ``velocity``
        (k, 2; m/s) and ``displacement`` (k, 2; m) of its centre of mass
        (each element weighted by its mass, at the mean of its nodes: the
        lumped mass's momentum) and number of ``elements``, largest first.
        ``where`` (a boolean mask over the elements) counts only those
        elements, and the bodies that hold any of them.

        ``energy_beyond_fall`` (J/kg) is ``|v|²/2 − g·u`` with ``g`` the
        model's gravity vector: the kinetic energy per unit mass beyond what
        its fall paid for, which a release or a collision gave it
        (docs/caving.md, "Fragments faster than free fall")."""
        labels = self.fragment_labels()
        keep = labels >= 0
        if where is not None:
            keep &= np.asarray(where, dtype=bool)
        lab = labels[keep]
        k = int(lab.max()) + 1 if len(lab) else 0
        tri = self.triangles()[keep]
        areas = self.areas()[keep]
        rho = np.array([m.rho for m in self.model._materials])[self._core.element_materials()]
        mass = areas * rho[keep]
        area = np.bincount(lab, weights=areas, minlength=k)
        m = np.bincount(lab, weights=mass, minlength=k)

        def mean(nodal: NDArray[np.float64]) -> NDArray[np.float64]:
            e = nodal[tri].mean(axis=1)
            return np.column_stack(
                [np.bincount(lab, weights=mass * e[:, d], minlength=k) / np.maximum(m, 1e-300) for d in (0, 1)]
            )

        centroid, velocity, displacement = mean(self.positions()), mean(self.velocities()), mean(self.displacements())
        beyond = 0.5 * (velocity**2).sum(axis=1) - displacement @ np.asarray(self.model.gravity, dtype=float)
        count = np.bincount(lab, minlength=k)
        order = np.argsort(-area, kind="stable")
        if where is not None:
            order = order[count[order] > 0]
        return {
            "area": area[order],
            "mass": m[order],
            "centroid": centroid[order],
            "velocity": velocity[order],
            "displacement": displacement[order],
            "energy_beyond_fall": beyond[order],
            "elements": count[order],
        }

    def overlaps(self, min_depth: float = 0.0) -> dict[str, NDArray[Any]]:
        """Nodes that lie inside an active element they are not a node of:
        per such pair its ``node``, ``element`` (index into
        :meth:`triangles`), ``depth`` (m, the node's distance to the
        element's nearest edge) and whether the node is ``in_contact``,
        deepest first; ``min_depth`` (m) leaves out shallower ones. Nodes
        of excavated elements only are not counted.

        A node in contact lies a little inside its facet's body (the
        penalty's penetration); a node without a contact should lie
        inside none. Where one does, the contact law let it in without
        force (docs/contact.md, "Which facet a node touches", item 7)."""
        x = self.positions()
        ids = np.flatnonzero(self.active())
        tri = self.triangles()[ids]
        if len(tri) == 0:
            none = np.zeros(0, np.int64)
            return {"node": none, "element": none, "depth": np.zeros(0), "in_contact": np.zeros(0, bool)}
        p = x[tri]
        e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        ccw = np.where(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0.0, -1.0, 1.0)
        # a grid of cells twice the median edge; an element is listed in
        # every cell its box meets, a node looked up in its own cell
        edges = np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2)
        cell = 2.0 * float(np.median(edges))
        lo = np.floor(p.min(axis=1) / cell).astype(np.int64)
        hi = np.floor(p.max(axis=1) / cell).astype(np.int64)
        origin = lo.min(axis=0)
        width = int(hi[:, 1].max() - origin[1]) + 2

        def within(counts: NDArray[np.int64]) -> NDArray[np.int64]:
            # 0, 1, …, counts[i] − 1 for each i in turn
            return np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)

        span = hi - lo + 1
        per = span[:, 0] * span[:, 1]
        elem = np.repeat(np.arange(len(tri)), per)
        k = within(per)
        ix = lo[elem, 0] + k // span[elem, 1]
        iy = lo[elem, 1] + k % span[elem, 1]
        cells = (ix - origin[0]) * width + (iy - origin[1])
        order = np.argsort(cells, kind="stable")
        cells, elem = cells[order], elem[order]
        live = np.zeros(len(x), bool)
        live[tri.ravel()] = True
        nodes = np.flatnonzero(live)
        ij = np.floor(x[nodes] / cell).astype(np.int64)
        node_cell = (ij[:, 0] - origin[0]) * width + (ij[:, 1] - origin[1])
        start = np.searchsorted(cells, node_cell, side="left")
        stop = np.searchsorted(cells, node_cell, side="right")
        count = stop - start
        n = np.repeat(nodes, count)
        e = elem[np.repeat(start, count) + within(count)]
        own = (tri[e] == n[:, None]).any(axis=1)
        n, e = n[~own], e[~own]
        q, a = x[n], p[e]
        depth = np.full(len(n), np.inf)
        for j in range(3):
            u, d = a[:, j], a[:, (j + 1) % 3] - a[:, j]
            s = (d[:, 0] * (q[:, 1] - u[:, 1]) - d[:, 1] * (q[:, 0] - u[:, 0])) / np.hypot(d[:, 0], d[:, 1])
            depth = np.minimum(depth, s * ccw[e])
        inside = depth > max(min_depth, 0.0)
        n, e, depth = n[inside], ids[e[inside]], depth[inside]
        order = np.lexsort((e, n, -depth))
        touching = np.zeros(len(x), bool)
        touching[np.asarray(self.contacts()["node"], dtype=np.int64)] = True
        return {"node": n[order], "element": e[order], "depth": depth[order], "in_contact": touching[n[order]]}

    def set_prescribed_velocity(self, nodes: Any, values: Any) -> None:
        """Changes the prescribed velocity (m/s) of nodes that already have
        one: ``values`` is one ``(vx, vy)`` for all of them or a row per node."""
        ids = index_array("nodes", np.ravel(nodes) if np.ndim(nodes) == 0 else nodes, (None,), upper=self.n_nodes)
        v = float_array("values", values, (None, 2) if np.ndim(values) == 2 else (2,)).reshape(-1, 2)
        if len(v) == 1 and len(ids) > 1:
            v = np.repeat(v, len(ids), axis=0)
        if len(v) != len(ids):
            raise ValueError(f"values: {len(v)} rows for {len(ids)} nodes")
        self._core.set_prescribed_velocity(ids, np.ascontiguousarray(v))

    def write_vtu(self, path: str | os.PathLike[str]) -> None:
        """Writes the current state to one VTU file."""
        write_vtu(self, path)

    # --- checkpoints --------------------------------------------------------
    def _meta(self) -> bytes:
        from . import __version__

        meta = {
            "fdem": __version__,
            "fingerprint": self._fingerprint,
            "settings": self._settings,
            # with the series a restored run has not reopened yet (it does at
            # its first ``run``): a checkpoint before that must not lose them
            "series": [series.state() for series in self._series.values()]
            + [st for key, st in self._resume.items() if key not in self._series],
            "user": self.user_data,
        }
        try:
            return json.dumps(meta).encode()
        except (TypeError, ValueError) as e:
            raise ValueError(f"Simulation.user_data must be JSON-serialisable for a checkpoint: {e}") from None

    def save_checkpoint(self, path: str | os.PathLike[str]) -> Path:
        """Writes the complete state to ``path`` (atomically: a temporary file,
        flushed to disk, renamed over ``path``); returns the path.

        The file is versioned and checksummed (docs/checkpoints.md). It holds
        the kernel's whole state (topology, material state, contact history,
        the broad phase's candidate list, the excavation schedule, the
        time-step history, the energy account) and, for
        :meth:`from_checkpoint`, the run settings, a fingerprint of the
        model and the output series this simulation writes.
        """
        path = Path(path)
        self._core.write_checkpoint(os.fspath(path), self._meta())
        return path

    @classmethod
    def from_checkpoint(cls, path: str | os.PathLike[str], model: Model, *, threads: int | None = None) -> Simulation:
        """Continues a run from a checkpoint written by :meth:`save_checkpoint`
        or :meth:`run`, in this or a new process, on any number of threads:
        the continued run is bit-for-bit the run that was not interrupted.

        ``model`` must be the model the run was built from (rebuilt by the
        same script); its fingerprint is checked. A :meth:`run` into the same
        ``output`` directory and ``name`` continues the output series: frames
        written after the checkpoint are replaced.

        Raises
        ------
        fdem.errors.CheckpointError
            The file is missing, not a checkpoint, truncated, corrupted,
            written by a newer fdem, or belongs to another model.
        """
        if not isinstance(model, Model):
            raise ValueError(f"model must be a fdem.Model, got {type(model).__name__}")
        if threads is not None:
            threads = whole("threads", threads, maximum=4096)
        source = os.fspath(path)
        core, user = _core.Simulation.read_checkpoint(source, int(threads or 0))
        try:
            meta = json.loads(bytes(user).decode())
            settings, fingerprint, series = meta["settings"], meta["fingerprint"], meta["series"]
        except (ValueError, KeyError, TypeError) as e:
            raise CheckpointError(
                f"{source}: the run description in the checkpoint is unreadable ({e})", source
            ) from None
        mine = _fingerprint(model.kernel_arrays())
        if fingerprint != mine:
            raise CheckpointError(
                f"{source}: the checkpoint belongs to another model (fingerprint {fingerprint[:12]}…, "
                f"this model {mine[:12]}…); rebuild the model exactly as the run that wrote it",
                source,
            )
        # a checkpoint older than format 7 kept no lineage: its pieces are
        # placed inside the model's elements (nothing to do otherwise)
        core.recover_lineage(
            np.ascontiguousarray(model.mesh.points, dtype=np.float64),
            np.ascontiguousarray(model.mesh.triangles, dtype=np.int64),
        )
        self = cls.__new__(cls)
        self.model = model
        # older checkpoints' run descriptions predate mass scaling and
        # renumbering; before the renumbering interval was a setting, a run
        # that renumbered did so every 1000 steps too
        every = 1000 if settings.get("renumber") is not None else None
        self._settings = {
            "mass_scaling": None,
            "renumber": None,
            "local_damping": 0.0,
            "renumber_every": every,
            **settings,
        }
        self._fingerprint = mine
        self._core = core
        self._series = {}
        self._resume = {(st["directory"], st["name"]): st for st in series}
        self.user_data = meta.get("user", {})
        return self

    def _snapshot(self) -> tuple[int, bytes]:
        return self.steps, self._core.checkpoint_bytes(b"")

    def _last_good_state(self, snapshot: tuple[int, bytes], failed_step: int) -> bool:
        """Replaces the failed state by the one of the step before
        ``failed_step``: the snapshot, replayed (runs are deterministic).
        Returns whether it could."""
        step0, data = snapshot
        if failed_step - 1 < step0:
            return False
        core, _ = _core.Simulation.from_checkpoint_bytes(data, self.threads)
        core.step(int(failed_step - 1 - step0))
        self._core = core
        return True

    def _checkpoint_path(self, checkpoint: Any, output: Any, name: str) -> Path | None:
        if checkpoint is True:
            return None if output is None else Path(output) / f"{name}.ckpt"
        if checkpoint is False or checkpoint is None:
            return None
        return Path(checkpoint)

    def _audit(self, e: dict[str, float], tolerance: float, stop: bool, warned: list[bool], ckpt: Path | None) -> None:
        """The energy audit of the state whose energies are ``e``; with
        ``stop``, the checkpoint ``ckpt`` must hold that state already."""
        largest = e["largest_term"]
        if largest <= 0 or abs(e["residual"]) <= tolerance * largest:
            return
        rel = abs(e["residual"]) / largest
        msg = (
            f"energy balance residual {e['residual']:.4e} J is {100 * rel:.2f}% of the largest term "
            f"({largest:.4e} J) at step {self.steps}, time {self.time:.6g} s (tolerance {100 * tolerance:g}%)"
        )
        if stop:
            err = EnergyBalanceError(msg, e["residual"], largest, self.steps, self.time)
            err.checkpoint = None if ckpt is None else os.fspath(ckpt)
            raise err
        if not warned[0]:
            warnings.warn(EnergyBalanceWarning(msg), stacklevel=3)
            warned[0] = True

    def run(
        self,
        until: float,
        *,
        output_every: float | None = None,
        output: str | os.PathLike[str] | None = None,
        name: str = "fdem",
        overwrite: bool = False,
        progress: bool = True,
        checkpoint: bool | str | os.PathLike[str] = True,
        energy_tolerance: float = 0.01,
        stop_on_energy_error: bool = False,
        final_frame: bool = True,
        reactions: Sequence[str] = (),
        probes: dict[str, Any] | None = None,
    ) -> Simulation:
        """Advances to simulated time ``until`` (s), writing a frame every
        ``output_every`` seconds into the directory ``output``.

        The run stops at the first step at or after ``until``; steps are not
        shortened to hit output times, so results do not depend on the output
        interval. A run may be continued by calling :meth:`run` again (the same
        series continues), also after :meth:`from_checkpoint`.

        Parameters
        ----------
        checkpoint : bool or path
            Where the run keeps its checkpoint (replaced atomically at every
            frame, at the end, on Ctrl-C and on an error): ``True`` (default)
            for ``{output}/{name}.ckpt`` when there is an output directory,
            a path for that file, ``False`` for none.
        energy_tolerance : float
            The energy audit: at every frame (and at the end) the balance
            residual is compared with this fraction of the balance's largest
            term; above it, an :class:`fdem.errors.EnergyBalanceWarning` (once
            per call). Every frame's balance is in ``{name}_energy.csv``.
        stop_on_energy_error : bool
            Stop instead, with :class:`fdem.errors.EnergyBalanceError`, after
            writing the checkpoint.
        final_frame : bool
            Write the state at the end as a frame even when it is not an
            output time (the default: a series ends where the run ends).
            ``False`` puts it only in the energy history and the checkpoint:
            for a driver that stops often between output times (the caving
            case stops every 0.05 s for its probe table; a frame at every
            stop cost 0.6 s each at the paper's scale).
        reactions : sequence of str
            Node groups (names of the model's mesh) whose support load and
            mean displacement (:meth:`reaction`) are written at every frame
            and energy row into ``{output}/{name}_reactions.csv``: the
            load–displacement history of a platen or a support. Fixed when
            the series starts; a resumed series keeps its groups.
        probes : dict, optional
            Named probes (:meth:`probe`: a point ``(x, y)`` as floats, or a
            node group) whose state goes into ``{output}/{name}_probes.csv``
            at every frame and energy row: the stress at a point, the mean
            displacement and velocity of a group. Fixed when the series
            starts, like ``reactions``.

        Ctrl-C stops the run within a second at a step boundary, after
        writing the current state as a frame and the checkpoint, and raises
        ``KeyboardInterrupt``.

        Raises
        ------
        fdem.errors.SimulationError
            When an element inverts, a value becomes NaN or infinite, or
            energy grows without a source (the watchdog). The simulation is
            set back to the last good state (the step before), which is
            written as a frame and a checkpoint first (their paths are the
            exception's ``frame`` and ``checkpoint``); frames written before
            stay valid.
        """
        until = number("until", until)
        if until < self.time:
            raise ValueError(f"until = {until:g} s is before the current time {self.time:g} s (a run goes forward)")
        if output_every is not None:
            output_every = positive("output_every", output_every)
            if output is None:
                raise ValueError("output_every needs output= (the directory the frames go to)")
        tolerance = positive("energy_tolerance", energy_tolerance)
        ckpt = self._checkpoint_path(checkpoint, output, name)
        series = None
        if output is not None:
            key = (os.fspath(output), name)
            if key not in self._series:
                if key in self._resume and not overwrite:
                    self._series[key] = VtuSeries.resume(self._resume.pop(key), self.steps)
                else:
                    reactions = [reactions] if isinstance(reactions, str) else list(reactions)
                    for group in reactions:
                        self.model.mesh.nodes(group)  # an unknown group is named before anything is written
                    probe_specs = {str(k): _probe_spec(self, k, v) for k, v in (probes or {}).items()}
                    self._series[key] = VtuSeries(
                        output, name, overwrite=overwrite, reactions=reactions, probes=probe_specs
                    )
                    self._series[key].write(self)
            series = self._series[key]
        origin = series.origin if series is not None and series.origin is not None else self.time
        k_next = math.floor((self.time - origin) / output_every) + 1 if output_every else 0
        next_out = origin + k_next * output_every if output_every else np.inf
        last_written = self.time
        warned = [False]

        def frame(always: bool = True, vtu: bool = True) -> dict[str, float]:
            """The state now as a frame (unless already written; with
            ``vtu`` false only its energy row) and the checkpoint; returns
            its energies."""
            nonlocal last_written
            e = self.energies()
            if series is not None and (always or self.time > last_written):
                if vtu:
                    series.write(self, e)
                    last_written = self.time
                else:
                    series.record_energy(self, e)
            if ckpt is not None:
                self.save_checkpoint(ckpt)
            return e

        budget = 8
        snapshot = self._snapshot()
        snap_wall = _time.perf_counter()
        snap_cost = 0.0
        with RunProgress(self.time, until, enabled=progress) as bar:
            try:
                while self.time < until:
                    target = min(until, next_out)
                    t0 = _time.perf_counter()
                    taken = self._core.advance(target, budget)
                    wall = _time.perf_counter() - t0
                    if taken == budget and wall < 0.1:
                        budget *= 2
                    elif wall > 0.4 and budget > 1:
                        budget //= 2
                    bar.update(self.time, self.steps)
                    if self.time >= next_out:
                        self._audit(frame(), tolerance, stop_on_energy_error, warned, ckpt)
                    if self.time >= next_out:
                        # the next output time after now, in one step (an
                        # output interval far below the time step would
                        # take forever counting through the skipped ones)
                        k_next = max(k_next + 1, math.floor((self.time - origin) / output_every) + 1)  # type: ignore[operator]
                        next_out = origin + k_next * output_every  # type: ignore[operator]
                        while self.time >= next_out:
                            k_next += 1
                            next_out = origin + k_next * output_every  # type: ignore[operator]
                    # an in-memory copy of a good state to fall back on
                    # (a replay from it gives the step before a failure);
                    # its cost is kept under 1% of the run (0.15 s for the
                    # paper-scale caving model late on: one every 15 s, and
                    # a failure replays at most that long; at 5% it took
                    # 4.5% of that run)
                    now = _time.perf_counter()
                    if now - snap_wall > max(2.0, 100 * snap_cost):
                        snapshot = self._snapshot()
                        snap_cost = _time.perf_counter() - now
                        snap_wall = _time.perf_counter()
            except EnergyBalanceError:
                raise  # the state is good: the audit wrote its checkpoint
            except SimulationError as err:
                if self._last_good_state(snapshot, err.step):
                    if series is not None:
                        err.frame = os.fspath(series.write(self))
                    if ckpt is not None:
                        err.checkpoint = os.fspath(self.save_checkpoint(ckpt))
                    err.add_note(
                        f"the simulation was set back to the last good state, step {self.steps}, t = {self.time:.6g} s"
                        + (f"; checkpoint {err.checkpoint}" if err.checkpoint else "")
                        + (f"; frame {err.frame}" if err.frame else "")
                    )
                raise
            except KeyboardInterrupt:
                frame(always=False)
                raise
        self._audit(frame(always=False, vtu=final_frame), tolerance, stop_on_energy_error, warned, ckpt)
        return self


def _fingerprint(arrays: dict[str, Any]) -> str:
    """SHA-256 of everything the kernel is built from: a restart checks that
    it is given the model the checkpoint was written for."""
    h = hashlib.sha256()

    def feed(v: Any) -> None:
        if isinstance(v, np.ndarray):
            a = np.ascontiguousarray(v)
            h.update(f"nd{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        elif isinstance(v, dict):
            h.update(b"{")
            for k in sorted(v):
                h.update(repr(k).encode())
                feed(v[k])
            h.update(b"}")
        elif isinstance(v, list | tuple):
            h.update(b"[")
            for x in v:
                feed(x)
            h.update(b"]")
        else:
            h.update(repr(v).encode())

    feed(arrays)
    return h.hexdigest()


def _is_point(where: Any) -> bool:
    """Whether a probe is a point ``(x, y)`` rather than a node group."""
    if isinstance(where, str):
        return False
    a = np.asarray(where)
    return a.shape == (2,) and a.dtype.kind == "f"


def _probe_spec(sim: Simulation, name: Any, where: Any) -> Any:
    """A probe in a form a checkpoint can keep (JSON): a point as two
    floats, a group name, or node ids; checked now, so that a bad one is
    named before anything is written."""
    if _is_point(where):
        x, y = (float(v) for v in where)
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError(f"probe {name!r}: point {where!r} must be finite")
        return [x, y]
    ids = sim.model.mesh.nodes(where)
    return where if isinstance(where, str) else [int(i) for i in ids]
