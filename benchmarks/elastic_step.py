"""Throughput of the elastic explicit step: element-updates per second
(elements × steps / wall seconds) on structured meshes of about 10^4, 10^5
and 10^6 triangles, at 1 and 2 threads.

Run: python benchmarks/elastic_step.py [--sizes 1e4 1e5 1e6] [--threads 1 2]

Each case builds a block with gravity, rollers and a pressure load (so the
node pass does the same work as in a real model), takes a warm-up chunk of
steps, then times enough steps for about `--seconds` of wall time.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import fdem


def build(n_elements: float) -> fdem.Model:
    nx = int(round(np.sqrt(n_elements)))
    ny = max(1, int(round(n_elements / (2 * nx))))
    mesh = fdem.Mesh.rectangle(2.0 * nx, 1.0 * ny, nx, ny)
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0.0, -9.81)
    model.fix("bottom", x=False, y=True).fix("left", x=True, y=False).fix("right", x=True, y=False)
    model.pressure("top", 1e6)
    return model


def measure(model: fdem.Model, threads: int, seconds: float) -> float:
    sim = fdem.Simulation(model, threads=threads)
    sim.step(20)
    n = 20
    while True:
        t0 = time.perf_counter()
        sim.step(n)
        wall = time.perf_counter() - t0
        if wall > seconds:
            break
        n = max(2 * n, int(n * seconds / max(wall, 1e-6) * 1.2))
    return model.mesh.n_elements * n / wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seconds", type=float, default=2.0)
    args = ap.parse_args()
    print(f"fdem {fdem.__version__}, {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print(f"{'elements':>10} {'threads':>7} {'element-updates/s':>18} {'per thread':>12} {'speed-up':>9}")
    for size in args.sizes:
        model = build(size)
        base = None
        for t in args.threads:
            rate = measure(model, t, args.seconds)
            base = base or rate
            print(f"{model.mesh.n_elements:>10d} {t:>7d} {rate:>18.3e} {rate / t:>12.3e} {rate / base:>9.2f}", flush=True)


if __name__ == "__main__":
    main()
