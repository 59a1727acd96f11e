"""All-in throughput of a fragmenting impact (issue 5): a jointless
1 m × 0.5 m block (E 30 GPa, ν 0.25, ρ 2700 kg/m³, f_t 5 MPa, G_f 30 N/m,
Mohr–Coulomb c 10 MPa, φ 35°) hits a fixed platen at 10 m/s; contact
friction 0.6, penalty 10 E (normal stiffness 10 E / mean edge length).

Reports all-in element-updates per second (Σ over steps of the elements of
that step, divided by wall time: forces, fracture checks, insertions,
contact and all), at each thread count, with the cracks inserted and the
share of time in each phase: insertion (topology edits and the rebuilds
they trigger), fracture checks, contact, element pass.

Run: python benchmarks/fracture_impact.py [--elements 1e4 1e5] [--threads 1 2 4 8 16] [--duration 4e-4]

E(n) is the parallel efficiency against the first thread count listed.
Each run has a process of its own (a run leaves the allocator's state to
the next one in the same process).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see elastic_step.py

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import fdem  # noqa: E402
import numpy as np  # noqa: E402

WIDTH, HEIGHT, GAP, SPEED = 1.0, 0.5, 1e-3, 10.0


def build(elements: float) -> fdem.Model:
    """Block above a platen, meshed to about ``elements`` triangles in all."""
    area = WIDTH * HEIGHT
    # the mesher's triangles average about 2/3 of the largest area allowed
    size = math.sqrt(4 * area / (math.sqrt(3) * elements) * 1.5)
    block = fdem.jointed_rectangle(WIDTH, HEIGHT, size, origin=(0.0, GAP))
    block = block.with_sets(element_sets={"rock": np.arange(block.n_elements)})
    nx = max(4, round(1.4 * WIDTH / (4 * size)))
    platen = fdem.Mesh.rectangle(1.4 * WIDTH, 4 * size, nx, 1, origin=(-0.2 * WIDTH, -4 * size))
    platen = platen.with_sets(element_sets={"platen": np.arange(platen.n_elements)})
    mesh = fdem.Mesh.combine(block, platen, prefixes=["block_", "platen_"])
    rock = fdem.MohrCoulombRankine(E=30e9, nu=0.25, rho=2700.0, c=10e6, phi=35.0, psi=5.0, ft=5e6, Gf=30.0)
    model = fdem.Model(mesh, materials={"block_rock": rock, "platen_platen": fdem.Elastic(E=30e9, nu=0.25, rho=2700.0)})
    model.fix("platen_bottom").fix("platen_left").fix("platen_right")
    model.set_initial_velocity((0.0, -SPEED), where=np.arange(block.n_nodes))  # the block's nodes come first
    friction = math.degrees(math.atan(0.6))
    model.contact(fdem.Interface(friction=friction, damping=0.5, penalty_factor=10.0)).fracture(check_every=5)
    return model


def measure(elements: float, threads: int, duration: float) -> dict[str, float]:
    """One run: the impact of ``elements`` on ``threads`` threads, timed
    from just before contact for ``duration`` simulated seconds."""
    model = build(elements)
    sim = fdem.Simulation(model, threads=threads, stiffness_damping=2e-7)
    # fly to the platen (the gap closes at GAP / SPEED), then time the impact
    sim.run(until=0.8 * GAP / SPEED, progress=False)
    p0, s0 = sim.phase_times(), sim.steps
    updates, wall = 0.0, 0.0
    end = sim.time + duration
    while sim.time < end:
        n = sim.n_elements
        w0 = time.perf_counter()
        sim.step(20)
        wall += time.perf_counter() - w0
        updates += 20 * 0.5 * (n + sim.n_elements)
    p1 = sim.phase_times()
    out = {f"share_{k}": (p1[k] - p0[k]) / wall for k in p1}
    out.update(
        elements=model.mesh.n_elements,
        steps=sim.steps - s0,
        cracks=sim.insertions,
        final=sim.n_elements,
        rate=updates / wall,
    )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--elements", type=float, nargs="+", default=[1e4, 1e5])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--duration", type=float, default=4e-4, help="simulated time after first contact (s)")
    ap.add_argument("--one", action="store_true", help=argparse.SUPPRESS)  # one run, as JSON (internal)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(measure(args.elements[0], args.threads[0], args.duration)))
        return
    print(f"fdem {fdem.__version__}, {platform.machine()}, {os.cpu_count()} cores")
    header = (
        "elements",
        "threads",
        "steps",
        "cracks",
        "final el.",
        "updates/s",
        "E(n)",
        "insertion",
        "checks",
        "contact",
        "elements%",
        "nodes%",
        "broad%",
    )
    print(" ".join(f"{h:>10}" for h in header))
    for target in args.elements:
        base: tuple[float, int] | None = None
        for threads in args.threads:
            # each run in its own process: a run leaves the allocator's
            # arenas to the next (measured: 2 threads after 1 thread in one
            # process ran at 3.7-3.8e6 updates/s, alone at 4.9e6)
            cmd = [sys.executable, __file__, "--one", "--elements", str(target), "--threads", str(threads)]
            cmd += ["--duration", str(args.duration)]
            r = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.splitlines()[-1])
            rate = r["rate"]
            base = base or (rate, threads)
            eff = (rate / base[0]) * base[1] / threads  # against the first thread count listed
            print(
                f"{r['elements']:>10} {threads:>10} {r['steps']:>10} {r['cracks']:>10} "
                f"{r['final']:>10} {rate:>10.3e} {eff:>10.2f} {r['share_topology']:>10.1%} "
                f"{r['share_fracture']:>10.1%} {r['share_surface']:>10.1%} {r['share_elements']:>10.1%} "
                f"{r['share_nodes']:>10.1%} {r['share_broad_phase']:>10.1%}",
                flush=True,
            )


if __name__ == "__main__":
    main()
