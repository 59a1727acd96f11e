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
- ``fragments.csv`` and ``fragments.png``: fragment sizes at the end (and
  each fragment's centre-of-mass velocity and displacement);
- ``caving_energy.csv`` and ``energy.png``: the energy account over time;
- ``summary.txt``: what happened, in numbers.
"""

from __future__ import annotations

import csv
import json
import math
import os
import time as _time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .caving_case import (  # noqa: F401 (the case's public names stay importable from here)
    BOTTOM,
    CRACKS,
    HEIGHT,
    JOINTS,
    OVERBURDEN,
    PAPER_PROBES,
    ROCK,
    SCHEDULES,
    TOP,
    TOP_PRESSURE,
    UNIT_WEIGHT,
    WIDTH,
    CavingCase,
    UndercutStage,
    _stage,
    _unit_weight,
    caving_model,
    paper_joint_sets,
)
from .caving_metrics import caving_metrics, subsidence_profile
from .caving_stress import (
    ABUTMENT_LINE,
    PAPER_TABLE2,
    abutment_peaks,
    plot_abutments,
    plot_table2,
    probe_points,
    probe_stress,
    stress_profile,
    write_table2,
)
from .errors import SimulationError
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
        columns = ["fragment", "area_m2", "mass_kg_per_m", "x_m", "y_m", "elements"]
        w.writerow([*columns, "vx_m_s", "vy_m_s", "ux_m", "uy_m"])
        for k in range(len(frags["area"])):
            w.writerow(
                [
                    k,
                    frags["area"][k],
                    frags["mass"][k],
                    *frags["centroid"][k],
                    int(frags["elements"][k]),
                    *frags["velocity"][k],
                    *frags["displacement"][k],
                ]
            )
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
        **_fragment_launch(frags),
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


def _fragment_launch(frags: dict[str, Any]) -> dict[str, float]:
    """The fastest fragment's centre-of-mass speed (m/s) and the most
    kinetic energy per unit mass any fragment holds beyond what its fall
    paid for (J/kg, :meth:`Simulation.fragments`'s ``energy_beyond_fall``;
    docs/caving.md, "Fragments faster than free fall")."""
    v = frags["velocity"]
    if len(v) == 0:
        return {"fragment_speed_max_m_s": 0.0, "fragment_energy_beyond_fall_J_per_kg": 0.0}
    return {
        "fragment_speed_max_m_s": float(np.hypot(v[:, 0], v[:, 1]).max()),
        "fragment_energy_beyond_fall_J_per_kg": float(frags["energy_beyond_fall"].max()),
    }


def _started(
    model: Model, case: CavingCase, threads: int | None, progress: bool, wall0: float
) -> tuple[Simulation, dict[str, Any]]:
    """A fresh run: the simulation after its equilibrium stage, with mass
    scaling set, and its bookkeeping (kept in the checkpoints)."""
    n0 = model.mesh.n_elements
    # with renumbering on, also every 1000th step: falling rock spoils the
    # order as surely as cracks do (docs/renumbering.md)
    every = None if case.renumber is None else 1000
    sim = Simulation(
        model,
        threads=threads,
        stiffness_damping=2e-6,
        renumber=case.renumber,
        renumber_every=every,
        safety=case.safety,
    )
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
