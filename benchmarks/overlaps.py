"""Overlap left by the contact law (`Simulation.overlaps`): nodes that lie
inside an element they are not a node of, at the end of the fragmenting
impact (`fracture_impact.py`), by depth as a share of the mean element
size `h` (√(2A) averaged), with and without a contact on the node
(docs/contact.md, "Which facet a node touches", item 7).

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
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import fdem  # noqa: E402
import fracture_impact  # noqa: E402


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
    active = sim.active()
    h = float(np.sqrt(2.0 * sim.areas()[active]).mean())
    o = sim.overlaps()
    # nodes of one-element fragments (lone triangles, debris)
    tri = sim.triangles()[active]
    labels = sim.fragment_labels()[active]
    lone = set(tri[np.bincount(labels)[labels] == 1].ravel().tolist())
    in_contact = len(np.unique(sim.contacts()["node"]))
    print(f"t = {sim.time:.4g} s, {sim.n_elements} elements, mean size h = {h:.4g} m, {in_contact} nodes in contact")
    print(f"{'depth at least':>16} {'in contact':>11} {'no contact':>11} {'of which in a lone triangle':>28}")
    for lim in (1e-4, 1e-3, 1e-2, 1e-1):
        deep = o["depth"] >= lim * h
        touching = np.unique(o["node"][deep & o["in_contact"]])
        free = np.unique(o["node"][deep & ~o["in_contact"]])
        print(f"{lim:>14g} h {len(touching):>11} {len(free):>11} {sum(n in lone for n in free.tolist()):>28}")
    if len(o["depth"]):
        print(f"deepest: {o['depth'][0] / h:.4f} h (node {o['node'][0]})")


if __name__ == "__main__":
    main()
