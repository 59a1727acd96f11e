"""Throughput of the explicit step with Mohr–Coulomb + Rankine plasticity
active in every element: element-updates per second at 1 and 2 threads.

Every node follows a uniform compressive velocity field from a stress
already on the Mohr–Coulomb plateau, so every element returns to the yield
surface on every step (checked: every element's plastic strain grows).

Run: python benchmarks/plastic_step.py [--sizes 1e5] [--threads 1 2 4 8 16]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see elastic_step.py

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import fdem  # noqa: E402
import numpy as np  # noqa: E402

ROCK = fdem.MohrCoulombRankine(E=60e9, nu=0.25, rho=3100.0, c=8e6, phi=55.0, psi=9.0, ft=1e6, Gf=70.0)


def build(n_elements: float) -> fdem.Model:
    nx = int(round(np.sqrt(n_elements)))
    ny = max(1, int(round(n_elements / (2 * nx))))
    mesh = fdem.Mesh.rectangle(1.0 * nx, 1.0 * ny, nx, ny)
    model = fdem.Model(mesh, material=ROCK)
    rate = 1.0  # 1/s axial, a steady plastic flow
    model.prescribe_velocity(np.arange(mesh.n_nodes), vx=lambda x, y: 0.5 * rate * x, vy=lambda x, y: -rate * y)
    model.set_initial_stress((0.0, -ROCK.ucs, -ROCK.nu * ROCK.ucs, 0.0))
    return model


def measure(model: fdem.Model, threads: int, seconds: float, repeats: int) -> tuple[float, float, float]:
    sim = fdem.Simulation(model, threads=threads)
    sim.step(10)
    before = sim.element_state()["equivalent_plastic_strain"]
    n = 10
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
    plastic = float((sim.element_state()["equivalent_plastic_strain"] > before).mean())
    return best_wall, best_cpu, plastic


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e5])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    print(f"fdem {fdem.__version__}, {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}")
    print(
        f"{'elements':>10} {'threads':>7} {'updates/s (wall)':>17} {'per thread':>11} "
        f"{'updates/CPU-s':>14} {'plastic':>8} {'E(n)':>6}"
    )
    for size in args.sizes:
        model = build(size)
        base: tuple[float, int] | None = None
        for t in args.threads:
            wall_rate, cpu_rate, plastic = measure(model, t, args.seconds, args.repeats)
            base = base or (wall_rate, t)
            eff = (wall_rate / base[0]) * base[1] / t  # against the first thread count listed
            print(
                f"{model.mesh.n_elements:>10d} {t:>7d} {wall_rate:>17.3e} {wall_rate / t:>11.3e} "
                f"{cpu_rate:>14.3e} {plastic:>8.0%} {eff:>6.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
