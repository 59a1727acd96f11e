"""Overlap left by the contact law: nodes that lie inside an element they
are not a node of, at the end of the fragmenting impact
(`fracture_impact.py`), by depth as a share of the mean element size `h`,
with and without a contact on the node (docs/contact.md, "What the entry
rule costs").

Run: python benchmarks/overlaps.py [--elements 1e4] [--duration 4e-4] [--threads 2]
     python benchmarks/overlaps.py --caving caving_output_quick/caving.ckpt [--full]

With ``--caving`` it reads the caving run's last checkpoint instead (the
quick case's unless ``--full``); nodes left only by excavated elements are
not counted.

The depth of a node inside a triangle is its distance to the nearest edge.
A node in contact lies a little inside (the penalty's penetration); a node
without one should not lie inside at all.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import fdem  # noqa: E402
import fracture_impact  # noqa: E402


def overlaps(sim: fdem.Simulation) -> tuple[float, list[tuple[float, int, int]]]:
    """Mean element size `h` (m) and, for every node of an active element
    inside an element it is not a node of, `(depth / h, node, element)` (deepest first; the element
    is an index into the active elements)."""
    x = sim.positions()
    tri = sim.triangles()[sim.active()]
    p = x[tri]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area2 = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    h = float(np.sqrt(np.abs(area2)).mean())
    cell = 2.0 * h
    lo = np.floor(p.min(axis=1) / cell).astype(np.int64)
    hi = np.floor(p.max(axis=1) / cell).astype(np.int64)
    grid: dict[tuple[int, int], list[int]] = collections.defaultdict(list)
    for e in range(len(tri)):
        for i in range(lo[e, 0], hi[e, 0] + 1):
            for j in range(lo[e, 1], hi[e, 1] + 1):
                grid[(i, j)].append(e)
    sign = np.where(area2 < 0.0, -1.0, 1.0)
    # nodes of excavated elements only are no longer part of the model
    live = np.zeros(len(x), dtype=bool)
    live[tri.ravel()] = True
    found = []
    for n, q in enumerate(x):
        if not live[n]:
            continue
        elems = [e for e in grid.get((int(q[0] // cell), int(q[1] // cell)), ()) if n not in tri[e]]
        if not elems:
            continue
        a = p[elems]
        depth = np.full(len(elems), np.inf)
        for k in range(3):
            u, v = a[:, k], a[:, (k + 1) % 3]
            d = v - u
            # signed distance to the edge, positive inside a counter-clockwise triangle
            s = (d[:, 0] * (q[1] - u[:, 1]) - d[:, 1] * (q[0] - u[:, 0])) / np.hypot(d[:, 0], d[:, 1])
            depth = np.minimum(depth, s * sign[elems])
        for e, dep in zip(elems, depth, strict=True):
            if dep > 0.0:
                found.append((float(dep) / h, n, e))
    found.sort(reverse=True)
    return h, found


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--elements", type=float, default=1e4)
    ap.add_argument("--duration", type=float, default=4e-4, help="simulated time after first contact (s)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--caving", default=None, help="a caving run's checkpoint to read instead of the impact")
    ap.add_argument("--full", action="store_true", help="with --caving: the paper-scale case, not the quick one")
    args = ap.parse_args()
    if args.caving:
        from fdem.caving import CavingCase, caving_model

        case = CavingCase() if args.full else CavingCase.quick()
        sim = fdem.Simulation.from_checkpoint(args.caving, caving_model(case), threads=args.threads)
    else:
        model = fracture_impact.build(args.elements)
        sim = fdem.Simulation(model, threads=args.threads, stiffness_damping=2e-7)
        sim.run(until=0.8 * fracture_impact.GAP / fracture_impact.SPEED, progress=False)
        end = sim.time + args.duration
        while sim.time < end:
            sim.step(20)
    h, found = overlaps(sim)
    touching = set(np.asarray(sim.contacts()["node"]).tolist())
    active = sim.active()
    tri = sim.triangles()[active]
    labels = sim.fragment_labels()[active]
    size = np.bincount(labels)
    # nodes of one-element fragments (lone triangles, debris)
    lone = set(tri[size[labels] == 1].ravel().tolist())
    print(f"t = {sim.time:.4g} s, {sim.n_elements} elements, mean size h = {h:.4g} m, {len(touching)} nodes in contact")
    print(f"{'depth at least':>16} {'in contact':>11} {'no contact':>11} {'of which in a lone triangle':>28}")
    for lim in (1e-4, 1e-3, 1e-2, 1e-1):
        deep = [f for f in found if f[0] >= lim]
        free = [f for f in deep if f[1] not in touching]
        print(f"{lim:>14g} h {len(deep) - len(free):>11} {len(free):>11} {sum(f[1] in lone for f in free):>28}")
    if found:
        print(f"deepest: {found[0][0]:.4f} h (node {found[0][1]})")


if __name__ == "__main__":
    main()
