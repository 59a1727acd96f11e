"""The block-caving case of Ecsi & Élesztős (2003), sections 3–4 and Table 1
(DESIGN §5): a 200 m × 100 m jointed rock block, geostatic start, a support
layer undercut in 10 m steps both ways from the midline up to 160 m, free
fall below, run to 3.5 s, with the paper's kinds of results.

:func:`caving_model` builds the model, :func:`run_caving` runs it and writes
everything into one directory:

- ``caving.pvd`` with one ``caving_NNNNN.vtu`` per output time (ParaView);
- ``fig4_principal_stress_*.png``: first principal stress with the joints
  and cracks drawn (the paper's Fig. 4), at several times;
- ``fig5_caving_3.5s.png`` (or at the last time): the fractured, flowing rock
  (Fig. 5), coloured by speed;
- ``probes.csv``: σxx, σyy, σzz, σxy at the paper's Table 2 points over time,
  in the frame ``CavingCase.probe_frame`` and at their mirror images;
- ``table2.csv``, ``table2.md`` and ``table2.png``: the paper's Table 2
  beside ours at the end (3.5 s), and ours over time
  (:mod:`fdem.caving_stress`);
- ``metrics.csv``, ``metrics.png`` and ``subsidence.csv``: cave back
  height, angles of break, subsidence, yielded area and fragment sizes
  over time (:mod:`fdem.caving_metrics`), and the top face's subsidence
  profile at the end;
- ``abutment.csv``, ``abutment_profile.csv`` and ``abutment.png``: the
  vertical stress across the abutments at the probes' depth against the
  lithostatic value, and its peak beside each undercut edge over time;
- ``fragments.csv`` and ``fragments.png``: fragment sizes at the end;
- ``caving_energy.csv`` and ``energy.png``: the energy account over time;
- ``summary.txt``: what happened, in numbers.
"""

from __future__ import annotations

import csv
import json
import math
import os
import time as _time
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .caving_floor import block_penalty, with_trough
from .caving_metrics import caving_metrics, subsidence_profile
from .caving_stress import (
    ABUTMENT_LINE,
    FRAMES,
    PAPER_TABLE2,
    abutment_peaks,
    plot_abutments,
    plot_table2,
    probe_points,
    probe_stress,
    stress_profile,
    write_table2,
)
from .contact import Interface
from .errors import SimulationError
from .joints import JointSet, jointed_rectangle
from .materials import Elastic, MohrCoulombRankine
from .model import Model
from .plot import plot_field, pyplot
from .simulation import Simulation

__all__ = [
    "CavingCase",
    "UndercutStage",
    "caving_model",
    "run_caving",
    "probe_stress",
    "PAPER_PROBES",
    "paper_joint_sets",
]

# Table 2 of the paper: node, x (m), y (m) at 3.5 s, in the paper's frame
# (fdem.caving_stress has its stresses and the frames)
PAPER_PROBES: tuple[tuple[str, float, float], ...] = tuple((n, x, y) for n, x, y, *_ in PAPER_TABLE2)

#: The ways the undercut can advance (:class:`CavingCase`).
SCHEDULES = ("symmetric", "one-sided")

#: The ways the overburden can load the block (:class:`CavingCase`).
OVERBURDEN = ("pressure", "mass")

WIDTH, HEIGHT = 200.0, 100.0
BOTTOM = -534.0  # the paper's probe coordinates put the block between y = −534 and −434 m
TOP = BOTTOM + HEIGHT
TOP_PRESSURE = 15.2e6
UNIT_WEIGHT = 30.41e3
ROCK = MohrCoulombRankine(E=60e9, nu=0.25, rho=3100.0, c=8e6, phi=55.0, psi=9.0, ft=1e6, Gf=70.0)
JOINTS = Interface(friction=33.0, cohesion=50e3, damping=0.5)
CRACKS = Interface(friction=33.0, damping=0.5)


@dataclass(frozen=True)
class UndercutStage:
    """One stage of an undercut schedule (:attr:`CavingCase.regions`): at
    ``time`` the elements still standing whose centroids lie in a region
    of the model are removed (:meth:`Model.excavate`).

    Parameters
    ----------
    time : float
        When the stage removes its elements (s of simulated time after the
        equilibrium stage), ``>= 0``.
    box : (xmin, ymin, xmax, ymax), optional
        A rectangle in model coordinates (m; the block spans x from −100
        to 100 m and y from −534 to −434 m), half-open: centroids with
        ``xmin <= x < xmax`` and ``ymin <= y < ymax``.
    polygon : sequence of (x, y), optional
        At least three corners (m), in either orientation; a centroid is
        inside by the even-odd rule. Give exactly one of ``box`` and
        ``polygon``.

    Any element can be in a region, rock as well as support: a box over
    the support layer, ``(x0, BOTTOM, x1, BOTTOM + support)``, is the
    paper's kind of undercut, and the symmetric schedule is the boxes
    ``(−k step, BOTTOM, k step, BOTTOM + support)`` at ``start + (k − 1)
    interval``.

    Raises
    ------
    ValueError
        A bad value, naming the field (``UndercutStage.box``; within a
        case, ``CavingCase.regions[i].box``).

    Examples
    --------
    >>> UndercutStage(0.05, box=(-10.0, BOTTOM, 10.0, BOTTOM + 3.0))
    UndercutStage(time=0.05, box=(-10.0, -534.0, 10.0, -531.0), polygon=None)
    """

    time: float
    box: tuple[float, float, float, float] | None = None
    polygon: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        self._check("UndercutStage")

    def _check(self, where: str) -> None:
        """Validates and normalises the fields (tuples of floats), naming
        each bad one as ``where.field``."""
        t = _finite(f"{where}.time", self.time)
        if t < 0:
            raise ValueError(f"{where}.time = {t} must be >= 0 (s)")
        object.__setattr__(self, "time", t)
        if (self.box is None) == (self.polygon is None):
            raise ValueError(f"{where}: give exactly one of box (xmin, ymin, xmax, ymax) and polygon [(x, y), ...]")
        if self.box is not None:
            box = _floats(f"{where}.box", self.box)
            if len(box) != 4 or not (box[0] < box[2] and box[1] < box[3]):
                raise ValueError(
                    f"{where}.box = {self.box!r} must be (xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax (m)"
                )
            object.__setattr__(self, "box", box)
        else:
            corners: Any = self.polygon
            if isinstance(corners, (str, bytes)) or not hasattr(corners, "__len__") or len(corners) < 3:
                raise ValueError(f"{where}.polygon = {corners!r} must be a sequence of at least three (x, y) corners")
            poly = tuple(_floats(f"{where}.polygon[{i}]", c) for i, c in enumerate(corners))
            if any(len(c) != 2 for c in poly):
                raise ValueError(f"{where}.polygon = {corners!r}: every corner is an (x, y) pair")
            xy = np.array(poly)
            area = 0.5 * abs(np.dot(xy[:, 0], np.roll(xy[:, 1], -1)) - np.dot(xy[:, 1], np.roll(xy[:, 0], -1)))
            if not area > 0:
                raise ValueError(f"{where}.polygon = {corners!r} encloses no area")
            object.__setattr__(self, "polygon", poly)

    def contains(self, points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Which of ``points`` (n, 2) lie in the stage's region (the box
        half-open, the polygon by the even-odd rule)."""
        x, y = points[:, 0], points[:, 1]
        if self.box is not None:
            x0, y0, x1, y1 = self.box
            return (x >= x0) & (x < x1) & (y >= y0) & (y < y1)
        corners = np.array(self.polygon)
        inside = np.zeros(len(points), dtype=bool)
        for (ax, ay), (bx, by) in zip(corners, np.roll(corners, -1, axis=0), strict=True):
            # edges that straddle the point's height, crossed to its right
            straddle = (ay > y) != (by > y)
            if ay != by:
                cross = ax + (y - ay) * (bx - ax) / (by - ay)
                inside ^= straddle & (x < cross)
        return inside

    def x_range(self) -> tuple[float, float]:
        """The least and largest x of the region (m)."""
        if self.box is not None:
            return self.box[0], self.box[2]
        xs = [c[0] for c in self.polygon or ()]
        return min(xs), max(xs)


def _finite(name: str, value: Any) -> float:
    """``value`` as a finite float, or a ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} = {value!r} must be a number")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} = {value!r} must be finite")
    return v


def _floats(name: str, value: Any) -> tuple[float, ...]:
    """A sequence of finite numbers as a tuple of floats, or a ValueError
    naming ``name``."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise ValueError(f"{name} = {value!r} must be a sequence of numbers")
    return tuple(_finite(name, v) for v in value)


def _stage(where: str, value: Any, support: float) -> UndercutStage:
    """A stage of :attr:`CavingCase.regions` from an :class:`UndercutStage`,
    a mapping of its fields (as JSON has it) or the shorthand ``(time,
    x_from, x_to)``: the box over the support layer between those x."""
    if isinstance(value, UndercutStage):
        stage = value
    elif isinstance(value, Mapping):
        unknown = set(value) - {"time", "box", "polygon"}
        if unknown:
            raise ValueError(f"{where}: unknown field(s) {sorted(unknown)} (an undercut stage has time, box, polygon)")
        if "time" not in value:
            raise ValueError(f"{where}: the stage has no time")
        # built without its own check, so that a bad value is named here
        stage = object.__new__(UndercutStage)
        for name in ("time", "box", "polygon"):
            object.__setattr__(stage, name, value.get(name))
    elif isinstance(value, (tuple, list)) and len(value) == 3:
        t, x0, x1 = (_finite(f"{where}", v) for v in value)
        if not x0 < x1:
            raise ValueError(f"{where} = {tuple(value)} must be (time >= 0, x_from, x_to) with x_from < x_to")
        stage = object.__new__(UndercutStage)
        for name, v in (("time", t), ("box", (x0, BOTTOM, x1, BOTTOM + support)), ("polygon", None)):
            object.__setattr__(stage, name, v)
    else:
        raise ValueError(
            f"{where} = {value!r} must be a fdem.caving.UndercutStage, its fields as a mapping, or (time, x_from, x_to)"
        )
    stage._check(where)
    return stage


@dataclass(frozen=True)
class CavingCase:
    """Sizes of a caving run.

    ``size`` is the element edge length (m): 1.0 by default, two elements
    across the paper's 2 m joint spacing. The mesh is uniform
    (``uniform_mesh``, :func:`jointed_rectangle`, docs/meshing.md): nearly
    equilateral triangles, 54 746 of them at 1.0 m; ``uniform_mesh=False``
    meshes by Delaunay refinement from the joint traces instead (78 216
    triangles down to a fifth of the size, an intact step 0.65 times as
    long; the paper-scale run took 1 h 05 min on it, 26–59 min on the
    uniform mesh on the same machine, docs/caving.md). With 0.75 m on the refined mesh (135 672
    triangles) the run to 0.5 s gives 5 972 cracks against 4 955, 2 883
    fragments against 2 739 and the same work supplied within 5%, at 2.5×
    the cost (docs/caving.md). The joint sets are the paper's (vertical 60 ×
    30 × 2 m, horizontal 30 × 15 × 3 m) with their spacings multiplied by
    ``joint_scale`` (1 at the paper's scale); the support layer is
    ``support`` m thick; the undercut advances ``step`` m each way every
    ``interval`` s from ``start`` until it is ``undercut`` m wide. Cracks
    open at the nodal failure factor ``insert_at`` (:meth:`Model.fracture`):
    1, the paper's rule, by default. Under the 15–18 MPa confinement of
    this case, cracks opened early (``insert_at`` ≪ 1) snap to element
    edges up to 15° off the principal plane and release the shear stress
    across them; at joint tips, where the geostatic state is strongly
    deviatoric, that sets off a cascade (docs/caving.md). The top ``cap``
    m of rock, which carries the 15.2 MPa overburden pressure onto the
    model, stay elastic (no plastic flow, no cracks): loose wedges cut out
    of the loaded face by cracks would otherwise be driven into the rock
    by the follower pressure (docs/caving.md). ``min_size`` bounds the
    triangles crack insertion creates (:meth:`Model.fracture`): 0.6 of the
    mesh's smallest altitude, where the library default is 0.25. The stable
    step scales with that altitude, so this is what the run's cost hangs
    on; 0.6 is the largest value with which the Brazilian-disc crack path
    test still passes (docs/caving.md has the measured trade-off).
    ``mass_scaling`` is the fraction of the intact model's stable step held
    for the whole run after the equilibrium stage (selective mass scaling,
    docs/mass_scaling.md; ``None`` turns it off): without it, the contact
    springs of fragment corners with a single element halve the step once
    the rock cracks. 0.7 adds 0.5% of the mass in the quick case (0.8: 2.6%,
    on the uniform mesh, whose intact step is long: docs/mass_scaling.md);
    the added mass is reported in the summary.
    ``renumber`` is the growth of the element count by crack insertion after
    which the kernel renumbers nodes and elements along a Hilbert curve
    (and, with it set, every 1000th step as the rock moves;
    :class:`Simulation`, docs/renumbering.md): a speed setting, which
    changes results only in the order of floating-point sums.
    ``safety`` is the fraction of the estimated critical step taken
    (:class:`Simulation`): 0.9, where the library's default is 0.8. Since the
    contact dashpots act on the predicted velocities (docs/contact.md) the
    estimate holds a margin: the quick case at rest stays at rest at 1.2
    times it and first gains energy at 1.3.
    ``check_every`` is the number of steps between fracture checks
    (:meth:`Model.fracture`; :meth:`Simulation.configure` changes it during
    a run): a due node is cut up to that many steps late, 0.97 ms of
    simulated time in the quick case and 0.24 ms at the paper's scale. How
    much that delay matters was measured over several numberings each
    (docs/caving.md, "The check interval is a delay in time"): on the quick
    4 m mesh 2 to 8 steps cave the same (448–556 m²) but 10 steps (1.6 ms)
    a third less, and with the step halved 12 steps cave like 6 and 20
    like 10, so the bound is a time; 2 m elements lose nothing even at 40
    steps (3.2 ms), so it is not the time a crack takes to cross an
    element, which halves with the element. With 1 m elements (the
    paper's; the quick case's joints and schedule) 24 steps (0.95 ms)
    instead of 6 save a tenth of the run (the insertions' rebuilds), and
    cave within the spread of the numberings, but give 5% more fragments
    on average, beyond that spread (so do longer delays at 2 m). The
    default stays at 6.
    ``probe_frame`` says where the paper's Table 2 points lie in the model
    (:data:`fdem.caving_stress.FRAMES`): ``"left"``, x measured from the
    block's left side, which puts the paper's points at x = 0–16 m in the
    left abutment and those at x ≥ 38 m over the caved undercut, is the
    reading the paper's own numbers support (docs/caving.md, "Table 2
    side by side"); ``"centred"`` measures x from the midline.
    ``overburden`` says how the 500 m of rock above the block load it
    with the paper's 15.2 MPa face load. ``"mass"`` (the default): as the
    weight of the top ``cap`` layer, whose density is raised to
    ρ + p W / (g A) (A the cap elements' area), so that the overburden
    over a caving column falls with it, as rock does, and the column falls
    under gravity ("the material is allowed to fall freely", paper §4.1).
    ``"pressure"``: a follower pressure on the top face, which pushes
    whatever lies under it, caved or not, with the full 15.2 MPa: a
    detached 100 m column is driven down at up to g + p/(ρ h) ≈ 6 g like
    a piston, its fastest nodes reach 54 m/s by 3.5 s against 34 m/s of
    free fall, and the pressure does 1.9 times the work (docs/caving.md,
    "The overburden: a weight, not a piston"). Both start from the same
    geostatic state below the cap.
    ``k0`` is the ratio of horizontal to vertical in-situ stress; ``None``
    (the default) takes ν/(1 − ν) = 1/3, the state of no lateral strain
    (DESIGN §4.6): the paper gives no ratio.
    ``joints`` replaces the paper's two joint sets (their spacings times
    ``joint_scale``) by the sets given (:class:`fdem.JointSet`, with
    orientation, persistence, bridge, spacing and a seeded jitter); inclined
    sets mesh conformingly like the paper's (docs/meshing.md).
    ``schedule`` is how the undercut advances: ``"symmetric"`` (the paper:
    ``step`` m each way from the midline per stage) or ``"one-sided"``
    (from the left edge of the undercut rightwards, ``2 step`` m per stage:
    the same area per stage). ``rock`` (default: Table 1's), ``joint_law``
    and ``crack_law`` (default: 33°, 50 kPa and 33°, both with ξ = 0.5)
    and ``top_pressure`` (Pa, 15.2 MPa) replace the paper's materials and
    load; gravity stays 30.41 kN/m³ over 3100 kg/m³. ``regions`` replaces
    the schedule by any sequence of stages (:class:`UndercutStage`: a time
    and a box or polygon in model coordinates), each removing at its time
    the elements still standing, support or rock, whose centroids lie in
    its region; ``(time, x_from, x_to)`` is short for the box over the
    support layer between those x (``undercut`` still names the
    undercut's full width, whose edges the abutment and metrics read;
    :meth:`undercut_width` is the width the stages have opened). ``floor``
    puts the block on a rigid trough whose floor lies ``floor`` m below the
    block's base (walls under the abutments up to the base), so that the
    caved rock stays in the cave (:mod:`fdem.caving_floor`); ``None`` (the
    default, the paper's "the material is allowed to fall freely") has
    none. With the floor at the base (0) the paper-scale abutments carry
    what the paper's Table 2 gives there much more nearly (docs/caving.md,
    "What differs, and why"). The case round-trips through JSON
    (:meth:`to_json`, :meth:`from_json`, :meth:`save`, :meth:`load`),
    which names the field of any bad value."""

    size: float = 1.0
    joint_scale: float = 1.0
    support: float = 3.0
    step: float = 10.0
    undercut: float = 160.0
    start: float = 0.05
    interval: float = 0.2
    until: float = 3.5
    output_every: float = 0.25
    insert_at: float = 1.0
    cap: float = 5.0
    min_size: float = 0.6
    mass_scaling: float | None = 0.7
    renumber: float | None = 0.05
    uniform_mesh: bool = True
    check_every: int = 6
    safety: float = 0.9
    probe_frame: str = "left"
    overburden: str = "mass"
    k0: float | None = None
    joints: tuple[JointSet, ...] | None = None
    schedule: str = "symmetric"
    rock: MohrCoulombRankine | None = None
    joint_law: Interface | None = None
    crack_law: Interface | None = None
    top_pressure: float = TOP_PRESSURE
    regions: tuple[UndercutStage, ...] | None = None
    floor: float | None = None

    def __post_init__(self) -> None:
        if self.probe_frame not in FRAMES:
            raise ValueError(f"CavingCase.probe_frame must be one of {FRAMES}, not {self.probe_frame!r}")
        if self.overburden not in OVERBURDEN:
            raise ValueError(f"CavingCase.overburden must be one of {OVERBURDEN}, not {self.overburden!r}")
        if self.schedule not in SCHEDULES:
            raise ValueError(f"CavingCase.schedule must be one of {SCHEDULES}, not {self.schedule!r}")
        if self.joints is not None:
            sets = tuple(self.joints)
            for i, j in enumerate(sets):
                if not isinstance(j, JointSet):
                    raise ValueError(f"CavingCase.joints[{i}] must be a fdem.JointSet, got {type(j).__name__}")
            object.__setattr__(self, "joints", sets)
        if self.regions is not None:
            if isinstance(self.regions, (str, bytes, Mapping)) or not hasattr(self.regions, "__iter__"):
                raise ValueError(f"CavingCase.regions = {self.regions!r} must be a sequence of undercut stages")
            regions = tuple(_stage(f"CavingCase.regions[{i}]", r, self.support) for i, r in enumerate(self.regions))
            if not regions:
                raise ValueError("CavingCase.regions is empty: give at least one stage, or None for the schedule")
            object.__setattr__(self, "regions", regions)
        if self.rock is not None and not isinstance(self.rock, MohrCoulombRankine):
            raise ValueError(f"CavingCase.rock must be a fdem.MohrCoulombRankine, got {type(self.rock).__name__}")
        for name in ("joint_law", "crack_law"):
            law = getattr(self, name)
            if law is not None and not isinstance(law, Interface):
                raise ValueError(f"CavingCase.{name} must be a fdem.Interface, got {type(law).__name__}")
        if not (math.isfinite(self.top_pressure) and self.top_pressure >= 0):
            raise ValueError(f"CavingCase.top_pressure = {self.top_pressure} must be a finite pressure >= 0 (Pa)")
        if self.floor is not None and not (math.isfinite(self.floor) and self.floor >= 0):
            raise ValueError(f"CavingCase.floor = {self.floor} must be a depth >= 0 (m below the base) or None")
        if self.overburden == "mass" and not self.cap > 0:
            raise ValueError(f"CavingCase.overburden = 'mass' needs a cap layer to carry it; cap = {self.cap}")

    @staticmethod
    def quick() -> CavingCase:
        """A coarse, fast version for tests and the demo: 4 m elements, joint
        spacings ×4, the undercut advanced every 0.06 s, run to 0.8 s
        (about 15 s on 2 cores, 3 395 elements at the start)."""
        return CavingCase(size=4.0, joint_scale=4.0, support=5.0, until=0.8, interval=0.06, output_every=0.2)

    def to_json(self) -> str:
        """The case as JSON (every field; joint sets as objects)."""
        import json

        return json.dumps(asdict(self), indent=2, sort_keys=True)

    @classmethod
    def from_json(cls, text: str, source: str = "case") -> CavingCase:
        """A case from :meth:`to_json`'s JSON (fields left out take their
        defaults). An unknown field, or a value of the wrong type or out of
        range, is a ValueError that names the field (and ``source``)."""
        import json
        from dataclasses import fields

        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{source}: not JSON ({exc})") from None
        if not isinstance(data, dict):
            raise ValueError(f"{source}: a caving case is a JSON object of fields")
        known = {f.name: f for f in fields(cls)}
        values: dict[str, Any] = {}
        for key, value in data.items():
            if key not in known:
                raise ValueError(f"{source}: unknown field {key!r} (known: {', '.join(sorted(known))})")
            values[key] = _case_value(source, key, value, getattr(cls(), key))
        try:
            return cls(**values)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{source}: {exc}") from None

    def save(self, path: str | os.PathLike[str]) -> None:
        """Writes the case as JSON (:meth:`to_json`)."""
        Path(path).write_text(self.to_json() + "\n")

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> CavingCase:
        """Reads a case written by :meth:`save` (or by hand)."""
        return cls.from_json(Path(path).read_text(), source=os.fspath(path))

    def undercut_width(self, stages: int) -> float:
        """The undercut's width (m) after ``stages`` stages: ``2 step
        stages`` for the symmetric and one-sided schedules; with
        ``regions``, the x-extent of the first ``stages`` regions, clipped
        to the block (what ``stages.csv``, ``metrics.png`` and the Fig. 4
        titles show)."""
        if self.regions is None or stages <= 0:
            return 2 * self.step * max(stages, 0)
        spans = [r.x_range() for r in self.regions[:stages]]
        lo = max(min(a for a, _ in spans), -0.5 * WIDTH)
        hi = min(max(b for _, b in spans), 0.5 * WIDTH)
        return max(hi - lo, 0.0)

    def figure_times(self) -> list[float]:
        """The times (s) of the Fig. 4-like pictures: the start, the third
        undercut stage, half the run and its end, each once (rounded to the
        microsecond: ``0.05 + 3 × 0.2`` and ``1.3 / 2`` are the same
        picture)."""
        times = (0.0, self.start + self.interval * 3, self.until / 2, self.until)
        return sorted({round(t, 6) for t in times})


def _unit_weight(case: CavingCase) -> float:
    """The rock's unit weight (N/m³): 30.41 kN/m³ for Table 1's rock,
    in proportion to the density of another."""
    return UNIT_WEIGHT if case.rock is None else UNIT_WEIGHT * case.rock.rho / ROCK.rho


def paper_joint_sets(scale: float = 1.0) -> list[JointSet]:
    """The paper's joint sets (§3.1): vertical 60 m × 30 m × 2 m and
    horizontal 30 m × 15 m × 3 m (persistence × bridge × spacing), their
    spacings times ``scale``."""
    return [
        JointSet(90.0, 60.0, 30.0, 2.0 * scale, name="vertical"),
        JointSet(0.0, 30.0, 15.0, 3.0 * scale, name="horizontal"),
    ]


def _case_value(source: str, key: str, value: Any, default: Any) -> Any:
    """A JSON value for field ``key`` of a case, checked against the type of
    its default; a mismatch names the field."""
    if key == "joints":
        if value is None:
            return None
        if not isinstance(value, list):
            raise ValueError(f"{source}: joints must be a list of joint sets, got {value!r}")
        out = []
        for i, item in enumerate(value):
            if not isinstance(item, dict):
                raise ValueError(f"{source}: joints[{i}] must be an object, got {item!r}")
            try:
                out.append(JointSet(**item))
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{source}: joints[{i}]: {exc}") from None
        return tuple(out)
    nullable = ("mass_scaling", "renumber", "k0", "rock", "joint_law", "crack_law", "regions", "floor")
    if value is None and key in nullable:
        return None
    if key == "regions":
        if not isinstance(value, list):
            raise ValueError(f"{source}: regions must be a list of stages ({{time, box or polygon}}), got {value!r}")
        # each stage is checked by the case (with its support layer's
        # thickness, for the (time, x_from, x_to) shorthand)
        return tuple(value)
    if key in ("rock", "joint_law", "crack_law"):
        kind = MohrCoulombRankine if key == "rock" else Interface
        if not isinstance(value, dict):
            raise ValueError(f"{source}: {key} must be an object of {kind.__name__} fields, got {value!r}")
        try:
            return kind(**value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{source}: {key}: {exc}") from None
    if isinstance(default, bool) or key == "uniform_mesh":
        if not isinstance(value, bool):
            raise ValueError(f"{source}: {key} must be true or false, got {value!r}")
        return value
    if isinstance(default, str):
        if not isinstance(value, str):
            raise ValueError(f"{source}: {key} must be a string, got {value!r}")
        return value
    if isinstance(default, int) and key == "check_every":
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{source}: {key} must be a whole number >= 1, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{source}: {key} must be a finite number, got {value!r}")
    if value < 0 or (value == 0 and key not in ("start", "cap", "k0", "top_pressure", "floor")):
        raise ValueError(f"{source}: {key} = {value!r} must be positive")
    return float(value)


def caving_model(case: CavingCase | None = None) -> Model:
    """The paper's block-caving model (DESIGN §5) for ``case`` (default: the
    paper's scale): jointed mesh, Table 1 rock, gravity 30.41 kN/m³,
    15.2 MPa on the top face, rollers on the sides, a support layer on a
    fixed base, geostatic initial stress (K0 = ν/(1 − ν)), contact on joints
    and cracks, crack insertion, and the undercut as excavation stages.

    Element sets: ``support`` (the layer), ``cap`` (the elastic top layer),
    ``rock``, and ``undercut_k`` for
    stage k = 1, 2, … (the support elements first removed by that stage)."""
    case = case or CavingCase()
    sets = list(case.joints) if case.joints is not None else paper_joint_sets(case.joint_scale)
    mesh = jointed_rectangle(WIDTH, HEIGHT, case.size, sets, origin=(-WIDTH / 2, BOTTOM), uniform=case.uniform_mesh)
    c = mesh.centroids()
    support = np.flatnonzero(c[:, 1] < BOTTOM + case.support)
    cap = np.flatnonzero(c[:, 1] > TOP - case.cap)
    rock = np.setdiff1d(np.arange(mesh.n_elements), np.union1d(support, cap))
    element_sets: dict[str, Any] = {"support": support, "rock": rock, "cap": cap}
    stages = len(case.regions) if case.regions is not None else int(round(case.undercut / (2 * case.step)))
    times = []
    done = np.zeros(mesh.n_elements, dtype=bool)
    for k in range(1, stages + 1):
        if case.regions is not None:
            # any element in the stage's region, support or rock
            at = case.regions[k - 1].time
            ids = np.flatnonzero(case.regions[k - 1].contains(c) & ~done)
            if len(ids) == 0:
                raise ValueError(
                    f"CavingCase.regions[{k - 1}]: undercut stage {k} removes no element (no centroid left standing "
                    "in its region; the block spans x from -100 to 100 m and y from -534 to -434 m)"
                )
        else:
            at = case.start + (k - 1) * case.interval
            if case.schedule == "symmetric":
                reach = np.abs(c[support, 0]) < k * case.step
            else:
                left = -0.5 * case.undercut
                reach = (c[support, 0] > left) & (c[support, 0] < left + 2 * k * case.step)
            ids = support[reach & ~done[support]]
            if len(ids) == 0:
                raise ValueError(
                    f"CavingCase: undercut stage {k} removes no support element (nothing left in its reach)"
                )
        done[ids] = True
        element_sets[f"undercut_{k}"] = ids
        times.append(at)
    mesh = block = mesh.with_sets(element_sets=element_sets)
    if case.floor is not None:
        mesh = with_trough(block, width=WIDTH, bottom=BOTTOM, undercut=case.undercut, size=case.size, depth=case.floor)
    g = UNIT_WEIGHT / ROCK.rho
    # the rock's material (``rock`` above holds its element ids)
    material, p = case.rock or ROCK, case.top_pressure
    # the overburden as the cap's weight: p W = (ρ' − ρ) g A, with A the
    # area of the elements that make the cap (whole rows: 4 m of a 5 m cap
    # on the quick mesh)
    cap_area = float(mesh.areas()[cap].sum())
    rho_cap = material.rho + (p * WIDTH / (g * cap_area) if case.overburden == "mass" else 0.0)
    elastic = Elastic(E=material.E, nu=material.nu, rho=rho_cap)
    materials: dict[str, Any] = {"rock": material, "support": material, "cap": elastic}
    if case.floor is not None:
        materials["trough"] = Elastic(E=material.E, nu=material.nu, rho=material.rho)
    model = Model(mesh, materials=materials).set_gravity(0.0, -g)
    model.fix("left", x=True, y=False).fix("right", x=True, y=False).fix("bottom")
    if case.floor is not None:
        model.fix("trough")
    model.set_geostatic_stress(top=TOP, pressure=p, k0=case.k0)
    if case.overburden == "pressure":
        model.pressure("top", p)
    else:
        # the heavy cap's own lithostatic state; below it the same as
        # with the pressure
        model.set_geostatic_stress(top=TOP, pressure=0.0, k0=case.k0, where="cap")
    laws = [Interface(damping=0.5), case.joint_law or JOINTS, case.crack_law or CRACKS]
    if case.floor is not None:
        model.set_initial_stress((0.0, 0.0, 0.0, 0.0), where="trough")
        laws = [block_penalty(law, block, max(material.E, elastic.E)) for law in laws]
    model.contact(laws[0], interfaces={"joints": laws[1]}, cracks=laws[2])
    model.fracture(insert_at=case.insert_at, min_size=case.min_size, check_every=case.check_every)
    for k, at in enumerate(times, start=1):
        model.excavate(f"undercut_{k}", at=at)
    return model


def area_below(corners: NDArray[np.float64], height: float) -> NDArray[np.float64]:
    """Area (m²) of each triangle below the line ``y = height``.

    ``corners`` has shape (n, 3, 2). With the corners' heights sorted
    ``y_a ≤ y_b ≤ y_c`` and A the area, the part below h is
    ``A (h − y_a)² / ((y_b − y_a)(y_c − y_a))`` up to ``y_b`` and
    ``A [1 − (y_c − h)² / ((y_c − y_a)(y_c − y_b))]`` above it (the cut-off
    triangles are similar to the halves the line through the middle corner
    makes).
    """
    y = np.sort(corners[:, :, 1], axis=1)
    ya, yb, yc = y[:, 0], y[:, 1], y[:, 2]
    d1, d2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    # a zero denominator belongs to a branch that is never taken (a flat
    # bottom or top); 1 keeps the unused value finite
    d_low, d_high = (yb - ya) * (yc - ya), (yc - ya) * (yc - yb)
    low = area * (height - ya) ** 2 / np.where(d_low > 0, d_low, 1.0)
    high = area * (1.0 - (yc - height) ** 2 / np.where(d_high > 0, d_high, 1.0))
    return np.where(height <= ya, 0.0, np.where(height <= yb, low, np.where(height < yc, high, area)))


def strip_means(
    corners: NDArray[np.float64], values: NDArray[np.float64], edges: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean of an element-wise constant field over horizontal strips.

    ``corners`` (n, 3, 2) are the triangles, ``values`` (n,) the field,
    ``edges`` (k + 1,) the strips' bounding heights, ascending. Each element
    counts with the part of its area inside the strip, so a strip's mean is
    the field's integral over the strip divided by the strip's area. That
    is what statics fixes: with frictionless sides, the integral of σ_yy
    along any horizontal cut is the load above it, and a strip's mean is
    the average of its cuts. Binning whole elements by centroid instead
    reads 5 m strips of 4 m elements 4.8% off the lithostatic value
    (docs/caving.md). Returns the means and the strips' areas (m²).
    """
    below = np.stack([area_below(corners, float(h)) for h in edges])
    share = np.diff(below, axis=0)
    area = share.sum(axis=1)
    return (share @ values) / area, area


def _plot_energy(csv_path: Path, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return
    t = np.array([float(r["time"]) for r in rows])
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    for key, label in (
        ("kinetic", "kinetic"),
        ("external_work", "work of gravity and loads"),
        ("fracture", "fracture"),
        ("plastic", "plastic (Mohr–Coulomb)"),
        ("friction", "friction"),
        ("contact_damping", "contact damping"),
        ("excavated", "removed by excavation"),
        ("mass_scaling", "taken by mass scaling"),
        ("residual", "balance residual"),
    ):
        ax.plot(t, [float(r[key]) / 1e6 for r in rows], label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("energy (MJ per m thickness)")
    ax.set_title("Energy account since equilibrium")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)


def _plot_fragments(area: NDArray[np.float64], png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    d = np.sqrt(4 * area / np.pi)  # equivalent diameter
    order = np.argsort(d)
    passing = np.cumsum(area[order]) / area.sum()
    fig, ax = plt.subplots(figsize=(6.5, 4.5), dpi=110)
    ax.semilogx(d[order], 100 * passing, drawstyle="steps-post")
    ax.set_xlabel("equivalent diameter √(4A/π) (m)")
    ax.set_ylabel("area passing (%)")
    ax.set_title(f"Fragment sizes: {len(area)} fragments")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)


def run_caving(
    out: str | os.PathLike[str],
    case: CavingCase | None = None,
    *,
    threads: int | None = None,
    progress: bool = True,
    resume: bool = False,
    model: Model | None = None,
) -> dict[str, Any]:
    """Builds, equilibrates and runs the caving case, writing all results
    into ``out`` (see the module docstring); returns the summary as a dict.

    ``model`` runs a model the user built or changed instead of
    :func:`caving_model` of ``case`` (the same 200 m × 100 m block in the
    same place: the probes, abutment line and metrics read it there; its
    own materials, joints, loads and excavation stages); ``case`` still
    gives the run's times, sizes for the metrics and output. A resume
    needs the same model again.

    The run keeps ``out/caving.ckpt`` up to date after every 0.05 s of
    simulated time, at every frame, on Ctrl-C and after a failure (then the
    step before it), as :meth:`Simulation.run` does, with the probe table
    and counters inside. With ``resume=True`` it continues from that
    checkpoint instead of starting afresh, bit for bit the run that was not
    interrupted; ``case`` must be the one the run was started with, except
    for ``until``, which may be raised to run on (the Fig. 4 times then
    follow the new ``until`` from the resume on). A Ctrl-C leaves the frame
    of the moment it stopped in the series.

    Raises
    ------
    FileNotFoundError
        ``resume`` and there is no checkpoint in ``out``.
    ValueError
        ``resume`` and the checkpoint was written for another case (the
        differing fields are named) or not by this function.
    """
    case = case or CavingCase()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    ckpt = out / "caving.ckpt"
    wall0 = _time.perf_counter()
    if model is None:
        model = caving_model(case)
    elif not isinstance(model, Model):
        raise ValueError(f"model must be a fdem.Model, got {type(model).__name__}")
    if resume:
        sim = _resumed(ckpt, model, case, threads)
        book = sim.user_data["caving"]
        if progress:
            print(f"resuming at t = {sim.time:.4f} s (step {sim.steps}) from {ckpt}", flush=True)
    else:
        sim, book = _started(model, case, threads, progress, wall0)
    n0 = int(book["elements_initial"])
    figure_times = case.figure_times()
    points = probe_points(case.probe_frame, WIDTH)
    mirror = points * np.array([-1.0, 1.0])
    lithostatic = -(case.top_pressure + _unit_weight(case) * (TOP - ABUTMENT_LINE))
    book.setdefault("abutment", [])
    book.setdefault("metrics", [])
    sample = min(0.05, case.output_every)
    figures: list[str] = book["figures"]
    run0 = _time.perf_counter()
    # where the loop's time goes, per phase of the step (checkpoints of runs
    # from before this was kept start it at the resume)
    phases: dict[str, float] = book.setdefault("phases", {})
    phases0 = sim.phase_times()

    def next_sample() -> float:
        """The sample time after the last one taken: the next multiple of
        ``sample``, or ``until``."""
        if book["samples"] == 0:
            return 0.0
        k = math.floor(book["sampled"] / sample + 1e-9) + 1
        return min(case.until, round(k * sample, 12))

    def mark() -> None:
        """Brings the counters up to the current state; they travel with
        the run (``book`` is ``sim.user_data["caving"]``) into its
        checkpoints."""
        nonlocal run0, phases0
        now = _time.perf_counter()
        book["updates"] += 0.5 * (book["mark_elements"] + sim.n_elements) * (sim.steps - book["mark_steps"])
        book["wall"] += now - run0
        run0 = now
        clocks = sim.phase_times()
        for k, v in clocks.items():
            phases[k] = phases.get(k, 0.0) + v - phases0[k]
        phases0 = clocks
        book["mark_elements"], book["mark_steps"] = sim.n_elements, sim.steps

    # The checkpoints are written by ``sim.run`` at the end of each stretch
    # (and at frames, Ctrl-C and failures), with the bookkeeping of the last
    # sample before it; a resume at the end of a stretch takes the sample
    # the interruption left untaken, from the same state.
    # Frames every ``output_every`` and at the end; the stops between (for
    # the probe table) go into the energy history and the checkpoint only.
    def advance(until: float, overwrite: bool) -> None:
        sim.run(
            until=until,
            output_every=case.output_every,
            output=out,
            name="caving",
            overwrite=overwrite,
            progress=progress and until > sim.time,
            checkpoint=ckpt,
            final_frame=until >= case.until - 1e-12,
        )

    try:
        if not resume:
            # a fresh run replaces what an earlier run left in ``out``: its
            # series starts here (frame 0), and so does its checkpoint
            advance(sim.time, overwrite=True)
        while book["samples"] == 0 or book["sampled"] < case.until - 1e-12:
            t = next_sample()
            if sim.time < t - 1e-12:
                advance(t, overwrite=False)
                continue
            for ft in figure_times:
                if abs(ft - t) < 0.5 * sample:
                    path = out / f"fig4_principal_stress_{t:.2f}s.png"
                    plot_field(
                        sim,
                        "principal_stress_1",
                        path,
                        title=f"First principal stress σ1, t = {sim.time:.2f} s"
                        f" (undercut {case.undercut_width(sim.stages_done):.0f} m)",
                        limits=(-40.0, 2.0),
                    )
                    figures.append(path.name)
            sig = probe_stress(sim, points) / 1e6
            # the mirror image's shear stress, read in the mirrored frame
            sig_m = probe_stress(sim, mirror) * np.array([1.0, 1.0, 1.0, -1.0]) / 1e6
            rows = [
                [sim.time, float(name), xp, yp, *xy.tolist(), *st.tolist(), *sm.tolist()]
                for (name, xp, yp), xy, st, sm in zip(PAPER_PROBES, points, sig, sig_m, strict=True)
            ]
            # rows of a sample cut short before it was counted are dropped
            # by ``_trim``
            book["probes"].extend(rows)
            peaks = abutment_peaks(sim, width=WIDTH, undercut=case.undercut, size=case.size, lithostatic=lithostatic)
            book["abutment"].append([sim.time, sim.stages_done, *peaks.values()])
            metrics = caving_metrics(
                sim,
                width=WIDTH,
                bottom=BOTTOM,
                top=TOP,
                support=case.support,
                undercut=case.undercut,
                size=case.size,
            )
            book["metrics"].append([sim.time, sim.stages_done, *metrics.values()])
            book["samples"] += 1
            book["sampled"] = t
            mark()
    except KeyboardInterrupt as stop:
        # a Ctrl-C while a failure was being handled leaves the failed
        # state: the checkpoint written before it stays
        if isinstance(stop.__context__, SimulationError):
            raise
        # the state is good: keep it with its counters (a sample that was
        # interrupted is dropped and taken again)
        _trim(book)
        mark()
        sim.save_checkpoint(ckpt)
        raise
    wall = book["wall"]
    updates = book["updates"]
    rest = book["rest"]
    probe_rows = book["probes"]
    figures = list(dict.fromkeys(figures))
    fig5 = out / f"fig5_caving_{sim.time:.1f}s.png"
    plot_field(sim, "velocity", fig5, title=f"Fractured, caving rock at t = {sim.time:.2f} s (speed)")
    figures.append(fig5.name)
    abutment = _write_stress_tables(out, sim, case, probe_rows, book["abutment"], points, lithostatic)
    final_metrics = _write_metrics(out, sim, book["metrics"], case)
    # the rock's (a floor's trough starts below the block's base)
    y_ref = sim.reference_positions()[sim.triangles()].mean(axis=1)[:, 1]
    frags = sim.fragments(where=y_ref >= BOTTOM)
    with open(out / "fragments.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["fragment", "area_m2", "mass_kg_per_m", "x_m", "y_m", "elements"])
        for k in range(len(frags["area"])):
            w.writerow([k, frags["area"][k], frags["mass"][k], *frags["centroid"][k], int(frags["elements"][k])])
    _plot_fragments(frags["area"], out / "fragments.png")
    _plot_energy(out / "caving_energy.csv", out / "energy.png")
    e = sim.energies()
    x = sim.positions()
    y = x[sim.triangles()].mean(axis=1)[:, 1]
    caved = sim.active() & (y < BOTTOM) & (y_ref >= BOTTOM)
    # rock (not support) that has fallen into the undercut: below the top of
    # the support layer, which every rock element started above
    level = BOTTOM + case.support
    fallen = sim.active() & (y_ref >= level) & (y < level)
    # what the balance is measured against: the energy put in since
    # equilibrium (work of gravity, the top pressure and the supports)
    supplied = abs(e["external_work"]) + abs(e["support_work"]) + e["kinetic_initial"] + e["elastic_initial"]
    summary = {
        "elements_initial": n0,
        "elements_final": sim.n_elements,
        "steps": sim.steps - int(book["steps_start"]),
        "simulated_s": sim.time,
        "wall_s": wall,
        "element_updates_per_s": updates / wall if wall > 0 else float("nan"),
        "threads": sim.threads,
        "cracks_inserted": sim.insertions,
        "undercut_stages": sim.stages_done,
        "fragments": int(len(frags["area"])),
        "largest_fragment_m2": float(frags["area"][0]) if len(frags["area"]) else 0.0,
        "fallen_area_m2": float(sim.areas()[fallen].sum()),
        "caved_area_m2": float(sim.areas()[caved].sum()),
        "time_step_s": sim.time_step,
        "fracture_check_steps": sim.check_every,
        "added_mass_fraction": sim.added_mass / (sim.masses().sum() - sim.added_mass),
        "energy_residual_J": e["residual"],
        "energy_supplied_J": supplied,
        **abutment,
        **final_metrics,
        **rest,
        # the contact's assembly runs beside the element pass on more than
        # one thread: their clocks overlap
        **{f"phase_{k}_s": v for k, v in phases.items()},
    }
    lines = [f"{k}: {v:.6g}" if isinstance(v, float) else f"{k}: {v}" for k, v in summary.items()]
    lines.append("figures: " + ", ".join(figures + ["fragments.png", "energy.png"]))
    (out / "summary.txt").write_text("\n".join(lines) + "\n")
    if progress:
        print("\n".join(lines), flush=True)
    summary["figures"] = figures
    summary["simulation"] = sim
    return summary


def _started(
    model: Model, case: CavingCase, threads: int | None, progress: bool, wall0: float
) -> tuple[Simulation, dict[str, Any]]:
    """A fresh run: the simulation after its equilibrium stage, with mass
    scaling set, and its bookkeeping (kept in the checkpoints)."""
    n0 = model.mesh.n_elements
    sim = Simulation(model, threads=threads, stiffness_damping=2e-6, renumber=case.renumber, safety=case.safety)
    built = _time.perf_counter() - wall0
    if progress:
        print(f"{n0} elements, {model.mesh.n_nodes} nodes, built in {built:.1f} s; equilibrating…", flush=True)
    eq = sim.equilibrate(max_velocity=1e-3)
    rest = {
        "equilibrium_time": eq["time"],
        "equilibrium_steps": eq["steps"],
        "equilibrium_speed": eq["max_velocity"],
    }
    # the stress state the undercut starts from, against the lithostatic
    # one: σ_yy averaged over 5 m horizontal strips across the whole width,
    # which statics fixes at −(p + γ depth) at the strip's middle whatever
    # the joints do locally (the sides are frictionless rollers)
    # strips below the cap's lowest corner (its elements are whole rows,
    # so its underside is ragged; with the overburden as its weight the
    # cap's own stress is not the lithostatic one of the rock)
    cap = model.mesh.elements("cap") if "cap" in model.mesh.group_names() else np.zeros(0, dtype=np.int64)
    below_cap = float(model.mesh.points[model.mesh.triangles[cap], 1].min()) if len(cap) else TOP
    edges = np.arange(BOTTOM + case.support, below_cap + 1e-9, 5.0)
    active = sim.active()
    mean_syy, _ = strip_means(sim.positions()[sim.triangles()[active]], sim.stress()[active, 1], edges)
    syy_lith = -(case.top_pressure + _unit_weight(case) * (TOP - 0.5 * (edges[1:] + edges[:-1])))
    rest["lithostatic_error"] = float(np.max(np.abs(mean_syy / syy_lith - 1)))
    if progress:
        print(
            f"at rest after {eq['time']:.3f} s ({int(eq['steps'])} steps): largest speed {eq['max_velocity']:.1e} m/s,"
            f" σyy (5 m strips) within {100 * rest['lithostatic_error']:.2f}% of lithostatic",
            flush=True,
        )
    rest["intact_time_step_s"] = sim.time_step
    if case.mass_scaling is not None:
        # from here on no element or contact node may shorten the step below
        # this fraction of the intact model's: the masses that would are
        # raised instead
        sim.configure(mass_scaling=case.mass_scaling * sim.time_step)
    book: dict[str, Any] = {
        "case": asdict(case),
        "elements_initial": n0,
        "rest": rest,
        "steps_start": sim.steps,
        "samples": 0,  # sample times recorded
        "sampled": 0.0,  # the last of them (s)
        "probes": [],
        "figures": [],
        "updates": 0.0,  # element-updates of the loop so far
        "wall": 0.0,  # loop wall time so far (s)
        "mark_elements": sim.n_elements,
        "mark_steps": sim.steps,
    }
    sim.user_data["caving"] = book
    return sim, book


#: What runs made before a field of :class:`CavingCase` existed did, where
#: that differs from the field's default now.
_BEFORE_FIELD = {"uniform_mesh": False, "probe_frame": "centred"}


def _resumed(ckpt: Path, model: Model, case: CavingCase, threads: int | None) -> Simulation:
    """The run continued from ``ckpt``, after checking that it is this
    case's."""
    if not ckpt.is_file():
        raise FileNotFoundError(f"{ckpt}: no checkpoint to resume from (run once without resume)")
    sim = Simulation.from_checkpoint(ckpt, model, threads=threads)
    book = sim.user_data.get("caving")
    if not isinstance(book, dict):
        raise ValueError(f"{ckpt}: not written by run_caving (no caving bookkeeping in it)")
    # a field the checkpoint does not name (added since) had the value that
    # reproduces the runs made before it: its default, or what the default
    # was then (the uniform mesh became the default after the field came)
    # as the checkpoint keeps it (JSON: tuples become lists)
    saved, mine = dict(book["case"]), json.loads(json.dumps(asdict(case)))
    if saved.get("regions"):
        # runs from before the stages had regions kept (time, x_from, x_to)
        thick = saved.get("support", CavingCase.support)
        stages = [asdict(_stage(f"regions[{i}]", r, thick)) for i, r in enumerate(saved["regions"])]
        saved["regions"] = json.loads(json.dumps(stages))
    default = {**asdict(CavingCase()), **_BEFORE_FIELD}
    differ = [
        f"{k} = {mine[k]!r} (the run: {saved.get(k, default[k])!r})"
        for k in mine
        if k != "until" and saved.get(k, default[k]) != mine[k]
    ]
    if differ:
        raise ValueError(f"{ckpt}: written for another case: " + ", ".join(differ) + "; only until may change")
    book["case"] = mine
    # probe rows from before the mirror points and the model coordinates
    # were kept (time, node, x, y and four stresses, centred frame)
    book["probes"] = [r if len(r) == 14 else [*r[:4], *r[2:4], *r[4:8], *[float("nan")] * 4] for r in book["probes"]]
    _trim(book)
    return sim


def _trim(book: dict[str, Any]) -> None:
    """Drops probe rows of a sample that was interrupted before it was
    counted (it is taken again)."""
    del book["probes"][book["samples"] * len(PAPER_PROBES) :]
    del book.setdefault("abutment", [])[book["samples"] :]
    del book.setdefault("metrics", [])[book["samples"] :]


_METRIC_KEYS = (
    "cave_back_m",
    "angle_of_break_left_deg",
    "angle_of_break_right_deg",
    "subsidence_max_m",
    "yielded_area_m2",
    "fragments_free",
    "p20_m",
    "p50_m",
    "p80_m",
    "energy_kinetic",
    "energy_plastic",
    "energy_fracture",
    "energy_friction",
    "energy_damping",
)


def _write_metrics(out: Path, sim: Simulation, rows: list[list[float]], case: CavingCase) -> dict[str, float]:
    """Writes ``metrics.csv`` (the caving metrics at every sample),
    ``stages.csv`` (the metrics at the first sample after each undercut
    stage, against the undercut's width),
    ``metrics.png`` (cave back height and yielded area against time) and
    ``subsidence.csv`` (the top face's settlement against x at the end);
    returns the last sample's metrics for the summary."""
    plt = pyplot()

    with open(out / "metrics.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", "stages_done", *_METRIC_KEYS])
        w.writerows(rows)
    with open(out / "stages.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["stage", "undercut_width_m", "time_s", *_METRIC_KEYS])
        for k in sorted({int(r[1]) for r in rows if r[1] > 0}):
            first = next(r for r in rows if int(r[1]) == k)
            w.writerow([k, case.undercut_width(k), first[0], *first[2:]])
    x0, x = sim.reference_positions(), sim.positions()
    top = np.flatnonzero(np.abs(x0[:, 1] - TOP) < 1e-6 * abs(TOP))
    edges = np.arange(-0.5 * WIDTH, 0.5 * WIDTH + 1e-9, 5.0)
    profile = subsidence_profile(x0[top, 0], x0[top, 1] - x[top, 1], edges)
    with open(out / "subsidence.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x_from_m", "x_to_m", "settlement_m"])
        w.writerows(zip(edges[:-1], edges[1:], profile, strict=True))
    if not rows:
        return {}
    data = np.array(rows, dtype=float)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5), dpi=110)
    ax[0].plot(data[:, 0], data[:, 2], label="cave back above the undercut level")
    ax[0].set_xlabel("time (s)")
    ax[0].set_ylabel("height (m)")
    ax[0].grid(alpha=0.3)
    twin = ax[0].twinx()
    widths = [case.undercut_width(int(k)) for k in data[:, 1]]
    twin.plot(data[:, 0], widths, "k:", lw=1, label="undercut width")
    twin.set_ylabel("undercut width (m)")
    ax[0].set_title("Cave back over the midline (solid) and undercut (dotted)")
    ax[1].plot(data[:, 0], data[:, 6] / 1e3, label="yielded area")
    ax[1].set_xlabel("time (s)")
    ax[1].set_ylabel("yielded or fractured area (10³ m²)")
    ax[1].grid(alpha=0.3)
    ax[1].set_title("Rock that has flowed or fractured")
    fig.tight_layout()
    fig.savefig(out / "metrics.png")
    plt.close(fig)
    return {f"metric_{k}": float(v) for k, v in zip(_METRIC_KEYS, rows[-1][2:], strict=True)}


def _write_stress_tables(
    out: Path,
    sim: Simulation,
    case: CavingCase,
    probe_rows: list[list[float]],
    abutment_rows: list[list[float]],
    points: NDArray[np.float64],
    lithostatic: float,
) -> dict[str, float]:
    """Writes the probe table, Table 2 beside ours, and the abutment stress
    (over time and along the line at the end) with their pictures; returns
    the abutment concentration factors for the summary: at the end, and at
    the first sample once the last undercut stage is done."""
    with open(out / "probes.csv", "w", newline="") as f:
        w = csv.writer(f)
        head = ["time_s", "node", "x_paper_m", "y_paper_m", "x_m", "y_m"]
        head += [f"{k}_MPa" for k in ("sxx", "syy", "szz", "sxy")]
        head += [f"{k}_mirror_MPa" for k in ("sxx", "syy", "szz", "sxy")]
        w.writerow(head)
        w.writerows(probe_rows)
    write_table2(out, probe_rows, case.probe_frame, points)
    plot_table2(out, probe_rows, case.probe_frame)
    keys = ["left_syy_Pa", "left_x_m", "left_factor", "right_syy_Pa", "right_x_m", "right_factor"]
    with open(out / "abutment.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["# y_m", ABUTMENT_LINE, "lithostatic_syy_Pa", lithostatic])
        w.writerow(["time_s", "stages_done", *keys])
        w.writerows(abutment_rows)
    edges = np.arange(-0.5 * WIDTH, 0.5 * WIDTH + 0.5 * case.size, case.size)
    x = 0.5 * (edges[1:] + edges[:-1])
    profile = stress_profile(sim, ABUTMENT_LINE, edges, case.size)
    with open(out / "abutment_profile.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x_m", "sxx_Pa", "syy_Pa", "szz_Pa", "sxy_Pa", "lithostatic_syy_Pa"])
        w.writerows([[xi, *p, lithostatic] for xi, p in zip(x, profile.tolist(), strict=True)])
    near = [
        (sign * xm, syy)
        for (_, _, yp, _, syy, _, _), (xm, _) in zip(PAPER_TABLE2, points, strict=True)
        if abs(yp - ABUTMENT_LINE) <= 6.0
        for sign in (1.0, -1.0)
    ]
    plot_abutments(
        out, x, profile[:, 1], lithostatic, time=sim.time, undercut=case.undercut, y=ABUTMENT_LINE, paper=near
    )
    result = {}
    if abutment_rows:
        last = abutment_rows[-1]
        result["abutment_factor_left"], result["abutment_factor_right"] = last[4], last[7]
        stages = max(r[1] for r in abutment_rows)
        done = next(r for r in abutment_rows if r[1] == stages)
        result["abutment_factor_undercut_done_left"] = done[4]
        result["abutment_factor_undercut_done_right"] = done[7]
        result["undercut_done_s"] = done[0]
    return result
