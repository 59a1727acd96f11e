"""Memory held by contact: bytes per contact, per boundary node and per
candidate pair (issue 34 (6)).

A pack of ``nx × ny`` square blocks (two triangles each, 1 m, 0.1 mm
apart) squeezed together from all sides (initial velocity −(x, y) × 1/s
about the pack's centre) so that, after a few steps, every block presses
on its neighbours: every node is a boundary node, and most are in contact.
The same pack is built twice in fresh processes, with and without contact,
and each reports the resident memory the simulation added (after the model
is built, after 40 steps); the difference is what contact holds: the free
surfaces, the broad phase (facet boxes, tree, candidate lists), the
contact memory and records, and their scratch buffers.

Run: python benchmarks/contact_memory.py [--elements 1e5 1e6] [--threads 2]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see elastic_step.py

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402

import numpy as np  # noqa: E402

SIDE, GAP, RATE = 1.0, 1e-4, 1.0


def resident() -> int:
    """Resident set size of this process (bytes), from /proc."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def pack(elements: float):
    """Points and triangles of about ``elements`` triangles as separate
    square blocks (the pack as square as it can be)."""
    blocks = int(elements) // 2
    nx = int(np.sqrt(blocks))
    ny = blocks // nx
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    x0 = (i.ravel() * (SIDE + GAP))[:, None]
    y0 = (j.ravel() * (SIDE + GAP))[:, None]
    corners = np.array([[0.0, 0.0], [SIDE, 0.0], [SIDE, SIDE], [0.0, SIDE]])
    points = np.stack([x0 + corners[:, 0], y0 + corners[:, 1]], axis=-1).reshape(-1, 2)
    base = 4 * np.arange(nx * ny)[:, None]
    triangles = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=1).reshape(-1, 3)
    return points, triangles


def child(elements: float, contact: bool, threads: int) -> dict:
    """One measurement, in this (fresh) process."""
    import fdem

    points, triangles = pack(elements)
    mesh = fdem.Mesh(points, triangles)
    model = fdem.Model(mesh, material=fdem.Elastic(E=10e9, nu=0.25, rho=2700.0))
    centre = points.mean(axis=0)
    model.set_initial_velocity(-RATE * (points - centre))
    if contact:
        model.contact(fdem.Interface(friction=30, damping=0.1))
    before = resident()
    sim = fdem.Simulation(model, threads=threads)
    sim.step(40)
    held = resident() - before
    stats = sim.contact_stats() if contact else {}
    boundary = len(np.unique(sim.surface_facets()[0])) if contact else 0
    return {"elements": sim.n_elements, "held": held, "boundary_nodes": boundary, **stats}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--elements", type=float, nargs="+", default=[1e5, 1e6])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(float(args.child[0]), args.child[1] == "1", args.threads)))
        return
    print(f"{platform.machine()}, {os.cpu_count()} cores, {args.threads} threads")
    print(
        f"{'elements':>10} {'contacts':>9} {'boundary':>9} {'pairs':>10} {'held, no contact':>17} "
        f"{'held':>10} {'B/element':>10} {'B/contact':>10} {'B/bnode':>8} {'B/pair':>7}"
    )
    for n in args.elements:
        runs = {}
        for flag in ("0", "1"):
            cmd = [sys.executable, __file__, "--threads", str(args.threads), "--child", str(n), flag]
            runs[flag] = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        bare, full = runs["0"], runs["1"]
        extra = full["held"] - bare["held"]
        print(
            f"{full['elements']:>10} {full['contacts']:>9} {full['boundary_nodes']:>9} {full['candidate_pairs']:>10} "
            f"{bare['held'] / 1e6:>14.1f} MB {full['held'] / 1e6:>7.1f} MB {bare['held'] / full['elements']:>10.0f} "
            f"{extra / max(full['contacts'], 1):>10.0f} {extra / max(full['boundary_nodes'], 1):>8.0f} "
            f"{extra / max(full['candidate_pairs'], 1):>7.0f}"
        )


if __name__ == "__main__":
    main()
