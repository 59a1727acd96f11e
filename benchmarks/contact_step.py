"""Throughput of steps with contact in a jointed rock mass: the paper's two
joint sets (vertical 60 m × 30 m × 2 m, horizontal 30 m × 15 m × 3 m) in a
block under gravity and 15.2 MPa on top, contact on every joint face.
Reports element-updates per second, candidate pairs evaluated per second,
broad-phase builds, and the share of step time spent in each phase.

Run: python benchmarks/contact_step.py [--size 0.85] [--threads 1 2 4 8 16] [--steps 300]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see elastic_step.py

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import fdem  # noqa: E402


def build(size: float, width: float, height: float) -> fdem.Model:
    sets = [
        fdem.JointSet(90, 60.0, 30.0, 2.0, name="vertical"),
        fdem.JointSet(0, 30.0, 15.0, 3.0, name="horizontal"),
    ]
    mesh = fdem.jointed_rectangle(width, height, size, sets)
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0.0, -30.41e3 / 3100.0)
    model.fix("left", x=True, y=False).fix("right", x=True, y=False).fix("bottom", x=False, y=True)
    model.pressure("top", 15.2e6)
    model.contact(interfaces={"joints": fdem.Interface(friction=33.0, cohesion=50e3, damping=0.5)})
    return model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=float, default=0.85, help="element size (m)")
    ap.add_argument("--width", type=float, default=200.0)
    ap.add_argument("--height", type=float, default=100.0)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--steps", type=int, default=300)
    args = ap.parse_args()
    t0 = time.perf_counter()
    model = build(args.size, args.width, args.height)
    built = time.perf_counter() - t0
    print(f"fdem {fdem.__version__}, {platform.machine()}, {os.cpu_count()} cores; model built in {built:.1f} s")
    m = model.mesh
    print(f"{m.n_elements} elements, {len(m.facet_sets['joints'])} joint faces")
    header = ["threads:7", "updates/s:10", "E(n):5", "pairs/s:10", "builds:6"]
    header += ["nodes:6", "elements:8", "broad:6", "narrow+p:8"]
    print(" ".join(f"{h.split(':')[0]:>{int(h.split(':')[1])}}" for h in header), f"{'dt':>5}")
    base: tuple[float, int] | None = None
    for threads in args.threads:
        sim = fdem.Simulation(model, threads=threads, mass_damping=20.0)
        sim.step(20)
        p0, s0, b0 = sim.phase_times(), sim.contact_stats(), sim.steps
        w0 = time.perf_counter()
        sim.step(args.steps)
        wall = time.perf_counter() - w0
        p1, s1 = sim.phase_times(), sim.contact_stats()
        share = {k: (p1[k] - p0[k]) / wall for k in p1}
        pairs = s1["pairs_evaluated"] - s0["pairs_evaluated"]
        rate = m.n_elements * args.steps / wall
        base = base or (rate, threads)
        eff = (rate / base[0]) * base[1] / threads  # against the first thread count listed
        print(
            f"{threads:>7} {rate:>10.3e} {eff:>5.2f} {pairs / wall:>10.3e} "
            f"{s1['broad_phase_builds'] - s0['broad_phase_builds']:>6} "
            f"{share['nodes']:>6.1%} {share['elements']:>8.1%} "
            f"{share['broad_phase']:>6.1%} {share['surface']:>8.1%} {share['time_step']:>5.1%}",
            flush=True,
        )
        assert sim.steps - b0 == args.steps


if __name__ == "__main__":
    main()
