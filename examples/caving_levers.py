"""One change at a time to the caving case, and what the abutments carry
(docs/caving.md, "What differs, and why").

Runs a caving case (the quick one by default) with one lever moved and
samples, every ``--sample`` s, the stress in the abutments: the mean σxx
and σyy over the boxes x ∈ [−100, −80] m and [80, 100] m, |y + 501| ≤ 6 m
(:func:`fdem.caving_stress.stress_profile`), and σ at the paper's four
abutment points of Table 2 (nodes 16475, 12485, 11496, 1911, frame
``"left"``) and at their mirror points. Levers:

- ``--floor D``: ``CavingCase.floor = D``, a rigid floor D m below the
  block's base with walls under the abutments up to the base
  (:mod:`fdem.caving_floor`), so that the caved rock piles up in the cave
  instead of falling without limit. A floor too deep to be reached in the
  run (``--floor 150``) is the control: the same bodies and numbering,
  nothing touched.
- ``--walls pinned``: the side walls fixed in x and y instead of rollers.
- ``--renumber off``: no Hilbert renumbering, another numbering's
  round-off (the spread a lever must exceed).

``--paper`` runs the paper's scale instead (about 30 min on one thread).
``--wall-check`` only compares the stress at node 1911 (the left wall,
44 m below the top) in an elastic block under roller and pinned walls
with the closed form (:func:`wall_stress`, seconds).

    python examples/caving_levers.py --until 3.5                   # the quick case to 3.5 s
    python examples/caving_levers.py --until 3.5 --floor 0         # with a floor under the support layer
    python examples/caving_levers.py --until 3.5 --floor 150       # the control
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from fdem import Elastic, Mesh, Model
from fdem.caving import BOTTOM, WIDTH, CavingCase, caving_model, probe_stress, run_caving
from fdem.caving_stress import ABUTMENT_LINE, PAPER_TABLE2, probe_points, stress_profile

#: The paper's Table 2 nodes in the left abutment (frame ``"left"``).
ABUTMENT_NODES = ("16475", "12485", "11496", "1911")

#: The side-wall conditions and starts of the elastic check (:func:`wall_stress`).
WALL_CASES = (
    ("roller", "geostatic", False),
    ("pinned", "geostatic", False),
    ("pinned", "zero", False),
    ("roller", "geostatic", True),
    ("pinned", "geostatic", True),
    ("pinned", "zero", True),
)


def sample(sim: Any, frame: str = "left") -> dict[str, Any]:
    """The abutment boxes' mean stresses and the stresses at the paper's
    abutment points and their mirror points (MPa)."""
    row: dict[str, Any] = {"time": sim.time}
    for side, edges in (("left", [-100.0, -80.0]), ("right", [80.0, 100.0])):
        s = stress_profile(sim, ABUTMENT_LINE, np.array(edges), 6.0)[0] / 1e6
        row[f"{side}_box_sxx"], row[f"{side}_box_syy"] = float(s[0]), float(s[1])
    pts = probe_points(frame, WIDTH)
    for (node, *_), p in zip(PAPER_TABLE2, pts, strict=True):
        tags = (("", p), ("m", p * np.array([-1.0, 1.0]))) if node in ABUTMENT_NODES else (("", p),)
        for tag, q in tags:
            s = probe_stress(sim, q[None, :])[0] / 1e6
            if tag == "m":  # the mirror point's shear, read in the mirrored frame
                s[3] = -s[3]
            for k, name in enumerate(("sxx", "syy", "szz", "sxy")):
                row[f"{node}{tag}_{name}"] = float(s[k])
    # the rock (the trough starts below the block's base, the rock above it)
    ref = sim.reference_positions()[sim.triangles()].mean(axis=1)[:, 1]
    rock = sim.active() & (ref >= BOTTOM)
    cen = sim.positions()[sim.triangles()[rock]].mean(axis=1)
    row["lowest_rock_y"] = float(cen[:, 1].min())
    row["below_base_m2"] = float(sim.areas()[rock][cen[:, 1] < BOTTOM].sum())
    return row


def _mean(values: list[float]) -> float:
    """Mean of the finite values (NaN where a point lay in a void)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if len(v) else float("nan")


def wall_stress(walls: str, start: str, undercut: bool, size: float = 2.0) -> dict[str, Any]:
    """The stress (MPa) at the paper's node 1911 (x = 0 on the left wall,
    y = −478 m: 44 m below the top) in an elastic, unjointed block of the
    caving case's size, rock and loads (gravity and 15.2 MPa on the top
    face), brought to rest; with ``undercut``, then with the 160 m undercut
    opened in a 4 m support layer at once and brought to rest again (an
    elastic span: nothing caves). ``walls``: ``"roller"`` (x fixed) or
    ``"pinned"`` (x and y fixed); ``start``: ``"geostatic"`` (the caving
    case's K0 = ν/(1 − ν) state) or ``"zero"`` (a stress-free block with
    the loads switched on). Returns σ at the point and the closed form of
    the lithostatic state there."""
    from fdem import Simulation
    from fdem.caving import HEIGHT, ROCK, TOP, TOP_PRESSURE, UNIT_WEIGHT
    from fdem.output import stress_at

    rock = Elastic(E=ROCK.E, nu=ROCK.nu, rho=ROCK.rho)
    mesh = Mesh.rectangle(WIDTH, HEIGHT, int(WIDTH / size), int(HEIGHT / size), origin=(-0.5 * WIDTH, BOTTOM))
    model = Model(mesh, material=rock).set_gravity(0.0, -UNIT_WEIGHT / ROCK.rho)
    for side in ("left", "right"):
        model.fix(side, x=True, y=walls == "pinned")
    model.fix("bottom").pressure("top", TOP_PRESSURE)
    if start == "geostatic":
        model.set_geostatic_stress(top=TOP, pressure=TOP_PRESSURE)
    if undercut:
        c = mesh.centroids()
        model.excavate(np.flatnonzero((c[:, 1] < BOTTOM + 4.0) & (np.abs(c[:, 0]) < 80.0)), at=1e-4)
    sim = Simulation(model, threads=1)
    sim.equilibrate(max_velocity=1e-4, max_time=20.0)
    if undercut:
        sim.run(until=2e-3, output=None, checkpoint=False, progress=False, final_frame=False)
        sim.equilibrate(max_velocity=1e-4, max_time=20.0)
    x, y = probe_points("left", WIDTH)[[p[0] for p in PAPER_TABLE2].index("1911")]
    s = stress_at(sim, np.array([[x + 1e-3, y]]))[0] / 1e6
    syy = -(TOP_PRESSURE + UNIT_WEIGHT * (TOP - y)) / 1e6
    k0 = ROCK.nu / (1 - ROCK.nu)
    return {
        "sxx": float(s[0]),
        "syy": float(s[1]),
        "szz": float(s[2]),
        "sxy": float(s[3]),
        "closed_form_sxx": k0 * syy,
        "closed_form_syy": syy,
    }


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--floor", type=float, default=None, help="a rigid floor this many m below the block's base")
    ap.add_argument("--walls", choices=("roller", "pinned"), default="roller")
    ap.add_argument("--until", type=float, default=3.5)
    ap.add_argument("--sample", type=float, default=0.05)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--renumber", choices=("on", "off"), default="on", help="off: another numbering's round-off")
    ap.add_argument("--paper", action="store_true", help="the paper's scale (CavingCase()) instead of the quick case")
    ap.add_argument("--out", default=None)
    ap.add_argument("--wall-check", action="store_true", help="only the elastic side-wall check at node 1911")
    args = ap.parse_args(argv)
    if args.wall_check:
        print("node 1911 (x = 0, y = -478 m), elastic block, MPa: sxx syy szz sxy")
        for walls, start, undercut in WALL_CASES:
            r = wall_stress(walls, start, undercut)
            what = f"{walls}, {start} start" + (", undercut open" if undercut else "")
            print(f"  {what:40s} {r['sxx']:7.2f} {r['syy']:7.2f} {r['szz']:7.2f} {r['sxy']:7.2f}")
        print(f"  closed form (lithostatic, K0 = 1/3): {r['closed_form_sxx']:.2f} {r['closed_form_syy']:.2f}")
        print("  the paper at 3.5 s: -21.64 -0.27 -5.48 1.54")
        return []
    case = CavingCase() if args.paper else CavingCase.quick()
    if args.renumber == "off":
        case = replace(case, renumber=None)
    tag = f"floor{args.floor:g}" if args.floor is not None else "base"
    if args.paper:
        tag = "paper_" + tag
    if args.walls != "roller":
        tag += f"_{args.walls}"
    if args.renumber == "off":
        tag += "_renumber_off"
    out = Path(args.out or f"levers_{tag}")
    if args.floor is not None:
        case = replace(case, floor=args.floor)
    model = caving_model(case)
    if args.walls == "pinned":
        model.fix("left").fix("right")
    wall0 = time.perf_counter()
    first = min(args.sample, args.until)
    summary = run_caving(out, replace(case, until=first), model=model, threads=args.threads, progress=False)
    sim = summary["simulation"]
    rows = [sample(sim)]
    t = first
    while t < args.until - 1e-9:
        t = min(args.until, round(t + args.sample, 9))
        sim.run(until=t, output=None, checkpoint=False, progress=False, final_frame=False)
        rows.append(sample(sim))
    wall = time.perf_counter() - wall0
    late = [r for r in rows if r["time"] >= args.until - 1.0 - 1e-9]
    late_mean = {k: _mean([r[k] for r in late]) for k in rows[-1] if k != "time"}
    result = {
        "lever": tag,
        "wall_s": wall,
        "steps": sim.steps,
        "cracks": sim.insertions,
        "late_mean": late_mean,
        "rows": rows,
    }
    (out / "levers.json").write_text(json.dumps(result, indent=1))
    print(f"{tag}: wall {wall:.0f} s, {sim.steps} steps, {sim.insertions} cracks")
    end = rows[-1]
    print(f"abutment boxes at {end['time']:.2f} s (mean over the last 1 s), MPa:")
    for k in ("left_box_sxx", "right_box_sxx", "left_box_syy", "right_box_syy"):
        print(f"  {k}: {end[k]:.1f} ({late_mean[k]:.1f})")
    print(f"  lowest rock y {end['lowest_rock_y']:.1f} m, rock below the base {end['below_base_m2']:.0f} m²")
    print("Table 2 points: paper σxx, σyy | ours at the end (mean over the last 1 s) | mirror")
    for node, _x, _y, pxx, pyy, *_ in PAPER_TABLE2:
        line = f"  {node:>5}: {pxx:6.1f} {pyy:6.1f} | {end[node + '_sxx']:6.1f} {end[node + '_syy']:6.1f}"
        line += f" ({late_mean[node + '_sxx']:6.1f} {late_mean[node + '_syy']:6.1f})"
        if node in ABUTMENT_NODES:
            line += f" | {end[node + 'm_sxx']:6.1f} {end[node + 'm_syy']:6.1f}"
        print(line)
    return rows


if __name__ == "__main__":
    main()
