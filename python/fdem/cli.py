"""The ``fdem`` command.

fdem demo [--out DIR] [--full]   run the demonstration case, write results and a picture
fdem run MODEL --until T [...]   run a model saved with Model.save
fdem info                        version, threads, optional extras
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


def _info(_: argparse.Namespace) -> int:
    import fdem

    print(f"fdem {fdem.__version__}")
    print(f"cores available: {os.cpu_count()}")
    for extra in ("gmsh", "matplotlib", "meshio", "rich"):
        try:
            __import__(extra)
            print(f"{extra}: yes")
        except ImportError:
            print(f"{extra}: no")
    return 0


def _demo(args: argparse.Namespace) -> int:
    from .demos import run_demo

    run_demo(Path(args.out), quick=not args.full, progress=not args.quiet)
    return 0


def _run(args: argparse.Namespace) -> int:
    import fdem

    model = fdem.Model.load(args.model)
    sim = fdem.Simulation(model, threads=args.threads, mass_damping=args.mass_damping)
    sim.run(
        until=args.until,
        output_every=args.output_every,
        output=args.out,
        name=Path(args.model).stem,
        overwrite=args.overwrite,
        progress=not args.quiet,
    )
    print(f"finished at t = {sim.time:.6g} s after {sim.steps} steps; results in {args.out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``fdem`` command."""
    ap = argparse.ArgumentParser(prog="fdem", description="2D combined finite-discrete element simulator")
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="run the demonstration case")
    p.add_argument("--out", default="demo_output", help="output directory (default: demo_output)")
    p.add_argument("--full", action="store_true", help="full size instead of the quick one")
    p.add_argument("--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=_demo)
    p = sub.add_parser("run", help="run a model saved with Model.save")
    p.add_argument("model")
    p.add_argument("--until", type=float, required=True, help="end time (s)")
    p.add_argument("--output-every", type=float, default=None, help="output interval (s)")
    p.add_argument("--out", default="results", help="output directory")
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--mass-damping", type=float, default=0.0, help="alpha (1/s)")
    p.add_argument("--overwrite", action="store_true")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=_run)
    p = sub.add_parser("info", help="version and environment")
    p.set_defaults(func=_info)
    args = ap.parse_args(argv)
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print("interrupted; results written so far are valid", file=sys.stderr)
        return 130
    except (ValueError, FileExistsError) as exc:
        print(f"fdem: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
