"""The demonstration case run by ``fdem demo``: the quick block-caving run."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from .caving import CavingCase, run_caving

__all__ = ["run_demo"]


def run_demo(out: Path, *, quick: bool = True, progress: bool = True) -> dict[str, Any]:
    """The paper's block-caving case (sections 3–4, :mod:`fdem.caving`): a
    200 m × 100 m jointed rock block under its own weight and 15.2 MPa on
    its top face, brought to rest, then undercut from the midline outwards
    until it caves. ``quick`` runs :meth:`CavingCase.quick` (about a minute
    on 2 cores); otherwise the paper's scale. Writes everything
    :func:`run_caving` writes (``caving.pvd``, Fig. 4/5 pictures, probe,
    fragment and energy tables, ``summary.txt``) into ``out`` and copies the
    Fig. 5 picture to ``demo.png``. Returns the run's summary (with the
    ``simulation``)."""
    out = Path(out)
    case = CavingCase.quick() if quick else CavingCase()
    summary = run_caving(out, case, progress=progress)
    fig5 = next(f for f in summary["figures"] if f.startswith("fig5_"))
    picture = out / "demo.png"
    shutil.copyfile(out / fig5, picture)
    print(
        f"caved: {summary['cracks_inserted']} cracks, {summary['fragments']} fragments,"
        f" {summary['fallen_area_m2']:.0f} m² of rock fallen into the undercut"
        f" ({summary['caved_area_m2']:.0f} m² below its floor) at t = {summary['simulated_s']:.2f} s;"
        f" energy balance residual {100 * summary['energy_residual_J'] / summary['energy_supplied_J']:.2f}%"
        f" of the work supplied"
    )
    print(f"wrote {out}/caving.pvd (open in ParaView), {picture} and summary.txt")
    return summary
