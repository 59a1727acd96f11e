"""Throughput of the elastic explicit step: element-updates per second
(elements × steps / wall seconds) on structured meshes of about 10^4, 10^5
and 10^6 triangles, at 1 and 2 threads.

Run: python benchmarks/elastic_step.py [--sizes 1e4 1e5 1e6] [--threads 1 2 4 8 16]

E(n) is the parallel efficiency, (rate at n / rate at the first thread count
listed) × (first count / n).

Each case builds a block with gravity, rollers and a pressure load (so the
node pass does the same work as in a real model), takes a warm-up chunk of
steps, then times enough steps for about `--seconds` of wall time.
"""

from __future__ import annotations

import os

# numpy's OpenBLAS threads spin after start-up and steal time from the kernel's
# own threads on small machines; they are not needed here.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import fdem  # noqa: E402
import numpy as np  # noqa: E402


def build(n_elements: float) -> fdem.Model:
    nx = int(round(np.sqrt(n_elements)))
    ny = max(1, int(round(n_elements / (2 * nx))))
    mesh = fdem.Mesh.rectangle(2.0 * nx, 1.0 * ny, nx, ny)
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0.0, -9.81)
    model.fix("bottom", x=False, y=True).fix("left", x=True, y=False).fix("right", x=True, y=False)
    model.pressure("top", 1e6)
    return model


def measure(model: fdem.Model, threads: int, seconds: float, repeats: int) -> tuple[float, float]:
    """Best of ``repeats`` timings: (element-updates per wall second,
    element-updates per CPU second of the whole process). CPU time leaves
    out time the machine gave to other tenants, so on a shared machine it is
    the steadier per-core figure."""
    sim = fdem.Simulation(model, threads=threads)
    sim.step(20)
    n = 20
    while True:
        t0 = time.perf_counter()
        sim.step(n)
        wall = time.perf_counter() - t0
        if wall > 0.2 * seconds:
            break
        n *= 2
    n = max(1, int(n * seconds / wall))
    best_wall, best_cpu = 0.0, 0.0
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        sim.step(n)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        updates = model.mesh.n_elements * n
        best_wall, best_cpu = max(best_wall, updates / wall), max(best_cpu, updates / cpu)
    return best_wall, best_cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seconds", type=float, default=1.0, help="wall time of one timing")
    ap.add_argument("--repeats", type=int, default=5, help="timings per case; the best is reported")
    args = ap.parse_args()
    print(f"fdem {fdem.__version__}, {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}")
    print(
        f"{'elements':>10} {'threads':>7} {'updates/s (wall)':>17} {'per thread':>11} "
        f"{'updates/CPU-s':>14} {'speed-up':>9} {'E(n)':>6}"
    )
    for size in args.sizes:
        model = build(size)
        base: tuple[float, int] | None = None
        for t in args.threads:
            wall_rate, cpu_rate = measure(model, t, args.seconds, args.repeats)
            base = base or (wall_rate, t)
            # parallel efficiency against the first thread count measured
            eff = (wall_rate / base[0]) * base[1] / t
            print(
                f"{model.mesh.n_elements:>10d} {t:>7d} {wall_rate:>17.3e} {wall_rate / t:>11.3e} "
                f"{cpu_rate:>14.3e} {wall_rate / base[0]:>9.2f} {eff:>6.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
