"""The block-caving case's definition (DESIGN §5; paper sections 3–4 and
Table 1): the paper's constants, the undercut schedule
(:class:`UndercutStage`), the case's settings (:class:`CavingCase`) and the
model they make (:func:`caving_model`). :mod:`fdem.caving` runs it and
writes the results, and re-exports these names.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .caving_floor import block_penalty, with_trough
from .caving_stress import (
    FRAMES,
    PAPER_TABLE2,
)
from .contact import Interface
from .joints import JointSet, jointed_rectangle
from .materials import Elastic, MohrCoulombRankine
from .model import Model

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
    "What differs, and why"). ``ramp`` (s) releases each undercut stage
    gradually (:meth:`Model.excavate`): the removed elements' forces on
    the rock that stays fall linearly to zero over it. 0, the paper's
    staging and the default, removes them at once; the release of the
    abutment stress then launches loose pieces of the new cave back at
    several m/s beyond what their fall gives (docs/caving.md, "Fragments
    faster than free fall"). The case round-trips through JSON
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
    ramp: float = 0.0

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
        if not (math.isfinite(self.ramp) and self.ramp >= 0):
            raise ValueError(f"CavingCase.ramp = {self.ramp} must be a finite release time >= 0 (s)")
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

        return json.dumps(asdict(self), indent=2, sort_keys=True)

    @classmethod
    def from_json(cls, text: str, source: str = "case") -> CavingCase:
        """A case from :meth:`to_json`'s JSON (fields left out take their
        defaults). An unknown field, or a value of the wrong type or out of
        range, is a ValueError that names the field (and ``source``)."""
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
    if value < 0 or (value == 0 and key not in ("start", "cap", "k0", "top_pressure", "floor", "ramp")):
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
        model.excavate(f"undercut_{k}", at=at, ramp=case.ramp)
    return model
