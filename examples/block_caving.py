"""Block caving at the paper's scale (Ecsi & Élesztős 2003, sections 3–4).

A 200 m × 100 m block of jointed rock (Table 1: E 60 GPa, ν 0.25,
ρ 3100 kg/m³, c 8 MPa, φ 55°, ψ 9°, f_t 1 MPa, G_f 70 N/m; joints 33°,
50 kPa; contact damping 0.5) under 30.41 kN/m³ and 15.2 MPa on its top face,
rollers on its sides, resting on a support layer over a fixed base. After a
damped equilibrium stage from the geostatic stress, the support layer is
removed in 10 m steps both ways from the midline up to a 160 m undercut;
the rock above fractures and falls freely into the void, simulated to 3.5 s.

Results (VTU series, the paper's Fig. 4 and Fig. 5 kinds of pictures, probe
stresses at the Table 2 points, fragment sizes, the energy history and a
summary) go into one directory; see ``fdem.caving``.

    python examples/block_caving.py            # the paper's scale (1.0 m elements, 54 746 triangles)
    python examples/block_caving.py --quick    # a coarse version (4 m elements, to 0.8 s)
    python examples/block_caving.py --resume   # go on after Ctrl-C or a lost machine

The run keeps its checkpoint (``caving.ckpt``) current after every 0.05 s of
simulated time; ``--resume`` continues from it bit for bit.

Watch ``energy_residual_J`` in the summary and ``caving_energy.csv``: the
energy balance is audited as the run goes (docs/caving.md). Wall time and
element-updates per second of the paper-scale run are in the README.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from fdem.caving import CavingCase, run_caving


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="coarse mesh and joints, shorter run")
    ap.add_argument("--out", default=None, help="output directory (default: caving_output[_quick])")
    ap.add_argument("--until", type=float, default=None, help="simulated time (s); default 3.5 (quick: 0.8)")
    ap.add_argument("--size", type=float, default=None, help="element size (m); default 1.0 (quick: 4)")
    ap.add_argument(
        "--min-size",
        type=float,
        default=None,
        help="smallest altitude of a triangle a crack may create, as a fraction of the mesh's smallest (default 0.6)",
    )
    ap.add_argument(
        "--mass-scaling",
        default=None,
        help="the step to hold after cracks, as a fraction of the intact model's, by selective mass scaling "
        "(default 0.7; 'off': physical masses, the step falls with the fragments)",
    )
    ap.add_argument(
        "--refined-mesh",
        action="store_true",
        help="Delaunay refinement from the joint traces instead of the uniform mesh (docs/meshing.md): "
        "1.4x the elements, 0.65x the intact step",
    )
    ap.add_argument(
        "--probe-frame",
        choices=("left", "centred"),
        default=None,
        help="where the paper's Table 2 x is measured from: the block's left side (default) or its midline",
    )
    ap.add_argument(
        "--floor",
        type=float,
        default=None,
        help="a rigid floor this many m below the block's base that keeps the caved rock in the cave "
        "(default: none, free fall; docs/caving.md)",
    )
    ap.add_argument("--threads", type=int, default=None, help="worker threads (default: all cores)")
    ap.add_argument("--quiet", action="store_true", help="no progress display")
    ap.add_argument(
        "--resume",
        action="store_true",
        help="continue a stopped run from OUT/caving.ckpt (the same options; --until may be raised)",
    )
    args = ap.parse_args(argv)
    case = CavingCase.quick() if args.quick else CavingCase()
    if args.until is not None:
        case = replace(case, until=args.until)
    if args.size is not None:
        case = replace(case, size=args.size)
    if args.min_size is not None:
        case = replace(case, min_size=args.min_size)
    if args.refined_mesh:
        case = replace(case, uniform_mesh=False)
    if args.mass_scaling is not None:
        off = args.mass_scaling.lower() in ("off", "none")
        case = replace(case, mass_scaling=None if off else float(args.mass_scaling))
    if args.probe_frame is not None:
        case = replace(case, probe_frame=args.probe_frame)
    if args.floor is not None:
        case = replace(case, floor=args.floor)
    out = args.out or ("caving_output_quick" if args.quick else "caving_output")
    try:
        return run_caving(out, case, threads=args.threads, progress=not args.quiet, resume=args.resume)
    except KeyboardInterrupt:
        ckpt = Path(out) / "caving.ckpt"
        if ckpt.is_file():
            print(f"\nstopped; the state is in {ckpt}: add --resume to go on", file=sys.stderr)
        else:
            print(f"\nstopped before the first checkpoint (no {ckpt}): run again without --resume", file=sys.stderr)
        raise SystemExit(130) from None


if __name__ == "__main__":
    main()
