"""The quick caving case (the README's demo) over several node and element
numberings: what a change to the contact law or the fracture rules does to
the cave, against the spread that numbering alone gives.

Renumbering changes the order of the sums (docs/renumbering.md), and with
it the last bits of every step; a fracturing, falling rock mass amplifies
that into a different run. A change is only seen when it moves a result
beyond that spread, so each run here is the quick case with
``CavingCase.renumber`` off and at 1%, 2%, ..., 10% (eleven runs, about 8 s
each on two threads of the 2-core VM).

Per run: cracks, fragments, fallen area (m², below the undercut level),
the energy residual as a share of the energy supplied, the largest
fragment energy beyond its fall (J/kg; tests/test_caving.py bounds it by
the stress the undercut releases), the fastest fragment (m/s), and the nodes inside another piece deeper
than 1% of the mean element size `h`: without any contact ("loose", with
the deepest) and in any state ("deep"). Totals and ranges at the end.

Run: python benchmarks/caving_numberings.py [--threads 2] [--renumber off 0.01 0.05]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time

import numpy as np
from fdem.caving import CavingCase, run_caving


def one(renumber: float | None, threads: int) -> dict[str, float]:
    """One quick caving run at this renumbering: the columns above."""
    case = dataclasses.replace(CavingCase.quick(), renumber=renumber)
    with tempfile.TemporaryDirectory() as out:
        wall = time.perf_counter()
        s = run_caving(out, case, threads=threads, progress=False)
        wall = time.perf_counter() - wall
    sim = s["simulation"]
    h = float(np.sqrt(2.0 * sim.areas()[sim.active()]).mean())
    o = sim.overlaps(min_depth=0.01 * h)
    free = ~o["in_contact"]
    return {
        "cracks": s["cracks_inserted"],
        "fragments": s["fragments"],
        "fallen_m2": s["fallen_area_m2"],
        "residual_pct": 100.0 * s["energy_residual_J"] / s["energy_supplied_J"],
        "beyond_fall_J_kg": s["fragment_energy_beyond_fall_J_per_kg"],
        "fastest_m_s": s["fragment_speed_max_m_s"],
        "loose": len(np.unique(o["node"][free])),
        "loose_deepest_cm": 100.0 * float(o["depth"][free].max()) if free.any() else 0.0,
        "deep": len(np.unique(o["node"])),
        "wall_s": wall,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument(
        "--renumber",
        nargs="+",
        default=["off"] + [f"{k / 100:.2f}" for k in range(1, 11)],
        help="renumbering fractions, 'off' for none",
    )
    args = ap.parse_args()
    rows = []
    for r in args.renumber:
        renumber = None if r == "off" else float(r)
        row = one(renumber, args.threads)
        rows.append(row)
        print(
            f"renumber {r:>4}: {row['cracks']} cracks, {row['fragments']} fragments, "
            f"{row['fallen_m2']:.0f} m² fallen, residual {row['residual_pct']:.3f}%, "
            f"beyond fall {row['beyond_fall_J_kg']:.1f} J/kg, fastest {row['fastest_m_s']:.1f} m/s, "
            f"loose {row['loose']} (deepest {row['loose_deepest_cm']:.1f} cm), deep {row['deep']}, "
            f"{row['wall_s']:.0f} s",
            flush=True,
        )

    def span(key: str, fmt: str) -> str:
        values = [row[key] for row in rows]
        return f"{format(min(values), fmt)}–{format(max(values), fmt)}"

    print(
        f"{len(rows)} runs: cracks {span('cracks', 'd')}, fragments {span('fragments', 'd')}, "
        f"fallen {span('fallen_m2', '.0f')} m², residual {span('residual_pct', '.3f')}%, "
        f"beyond fall {span('beyond_fall_J_kg', '.1f')} J/kg; loose nodes {sum(r['loose'] for r in rows)} "
        f"(deepest {max(r['loose_deepest_cm'] for r in rows):.1f} cm), deep nodes {sum(r['deep'] for r in rows)}"
    )


if __name__ == "__main__":
    main()
