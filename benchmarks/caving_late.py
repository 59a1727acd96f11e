"""Throughput of late block-caving steps: fractured, flowing rock with tens
of thousands of contacts and a crack insertion check every 6 steps
(`CavingCase.check_every`; 10 before 2026-11-24 evening).
Restarts from a checkpoint that `examples/block_caving.py` wrote at the end
of its run (``<out>/caving.ckpt``), steps it at each thread count and
reports element-updates per second, the parallel efficiency E(n) against
the first thread count listed ((rate at n / rate at the first) × (first / n)),
and the share of each phase (the
contact's assembly runs beside the element pass, so on more than one
thread their shares overlap and may add up to more than 100%); checks that
every thread count ends on the same bits.

Make the checkpoint, then time it (paper scale, 1.0 m elements):

    python examples/block_caving.py --until 1.25 --threads 2
    python benchmarks/caving_late.py caving_output/caving.ckpt

For the quick case: ``--quick`` on both (the case must match the run that
wrote the checkpoint; a mismatch is refused by name). ``--renumber``
renumbers nodes and elements along a Hilbert curve once after restoring,
as a run with ``CavingCase.renumber`` would have done (for checkpoints of
runs made before renumbering existed).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see elastic_step.py

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import fdem  # noqa: E402
import numpy as np  # noqa: E402
from fdem.caving import CavingCase, caving_model  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="caving.ckpt written by examples/block_caving.py")
    ap.add_argument("--quick", action="store_true", help="the checkpoint is of the quick case")
    ap.add_argument("--size", type=float, default=None, help="element size (m) the run used, if not the default")
    ap.add_argument("--refined-mesh", action="store_true", help="the run used the refined mesh (--refined-mesh)")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument(
        "--renumber",
        action="store_true",
        help="renumber nodes and elements once after restoring (a checkpoint of a run without renumbering)",
    )
    args = ap.parse_args()
    case = CavingCase.quick() if args.quick else CavingCase()
    if args.size is not None:
        case = replace(case, size=args.size)
    if args.refined_mesh:
        case = replace(case, uniform_mesh=False)
    t0 = time.perf_counter()
    model = caving_model(case)
    built = time.perf_counter() - t0
    print(f"fdem {fdem.__version__}, {platform.machine()}, {os.cpu_count()} cores; model built in {built:.1f} s")
    ends = []
    first_rate = None
    for threads in args.threads:
        sim = fdem.Simulation.from_checkpoint(args.checkpoint, model, threads=threads)
        if args.renumber:
            sim.renumber()
        if not ends:
            stats = sim.contact_stats()
            print(
                f"t = {sim.time:.3f} s: {sim.n_elements} elements, {sim.insertions} cracks, "
                f"{stats['contacts']} contacts, {stats['candidate_pairs']} candidate pairs, dt {sim.time_step:.3e} s"
            )
        p0, e0, c0, s0 = sim.phase_times(), sim.n_elements, sim.insertions, sim.steps
        wall = time.perf_counter()
        sim.step(args.steps)
        wall = time.perf_counter() - wall
        p1 = sim.phase_times()
        updates = 0.5 * (e0 + sim.n_elements) * (sim.steps - s0)
        shares = ", ".join(f"{k} {100 * (p1[k] - p0[k]) / wall:.0f}%" for k in p1 if p1[k] - p0[k] > 0.005 * wall)
        rate = updates / wall
        if first_rate is None:
            first_rate = rate
        efficiency = (rate / first_rate) * (args.threads[0] / threads)
        print(
            f"{threads} thread(s): {args.steps} steps in {wall:.2f} s, {rate:.3e} element-updates/s, "
            f"E(n) {efficiency:.2f}, {sim.insertions - c0} cracks inserted; {shares}"
        )
        ends.append(sim.positions())
    same = all(np.array_equal(ends[0], e) for e in ends[1:])
    print(
        "positions at the end: " + ("identical bits for every thread count" if same else "DIFFER between thread counts")
    )
    if not same:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
