"""Restart with cohesive bonds (issue 32, point 4): a checkpoint taken while
bonds across young cracks are intact continues bit for bit, in a new
process on another thread count, like one taken before the first crack or
after bonds have failed (docs/checkpoints.md)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
from test_fracture import tension_bar
from test_trust import state

ROOT = Path(__file__).resolve().parent.parent
SIZE = 0.02  # 435 elements; the first cracks at about step 1 800
END = 20_000  # steps: cracks at 1 800–2 100, bonds failing from 13 000


def bond_count(sim) -> int:
    return len(sim.bonds()["length"])


def test_restart_with_intact_and_failed_bonds_is_bit_for_bit(tmp_path):
    """Run A (2 threads) pulls the tension bar apart (cracks are inserted
    with a cohesive bond, ``insert_at`` 0.02) and writes three checkpoints:
    before the first crack, right after the first cracks opened with their
    bonds intact, and just after a bond failed (fewer bonds, no insertion
    since). A new process restores each on one thread and compares, right
    after the restore and after running to the same final step, every
    array and energy term with ``==``."""
    sim, _, _ = tension_bar(SIZE, threads=2)
    labels: list[str] = []

    def checkpoint(label: str) -> None:
        sim.save_checkpoint(tmp_path / f"{label}.ckpt")
        np.savez(tmp_path / f"{label}_at.npz", **state(sim))
        labels.append(label)

    # (a) before any crack
    sim.step(1000)
    assert sim.insertions == 0 and bond_count(sim) == 0
    checkpoint("before")
    # (b) the first cracks, their bonds intact and opening
    while sim.insertions == 0 and sim.steps < END:
        sim.step(10)
    bonds = sim.bonds()
    assert sim.insertions > 0 and len(bonds["length"]) > 0, "no bonded crack"
    assert np.any(bonds["max_opening"] > 0) and np.all(bonds["damage"] < 1)
    checkpoint("intact")
    # (c) a bond has failed: fewer bonds after steps without an insertion
    most = bond_count(sim)
    while sim.steps < END:
        insertions = sim.insertions
        sim.step(10)
        if sim.insertions == insertions and bond_count(sim) < most:
            break
        most = max(most, bond_count(sim))
    assert 0 < bond_count(sim) < most, "no bond failed while others held"
    checkpoint("failed")
    sim.step(END - sim.steps)
    np.savez(tmp_path / "end.npz", **state(sim))

    child = textwrap.dedent(
        f"""
        import sys, numpy as np, fdem
        sys.path.insert(0, {str(ROOT / "tests")!r})
        from test_fracture import tension_bar
        from test_trust import state
        _, model, _ = tension_bar({SIZE!r})
        for label in {labels!r}:
            sim = fdem.Simulation.from_checkpoint({str(tmp_path)!r} + f"/{{label}}.ckpt", model, threads=1)
            assert sim.threads == 1
            np.savez({str(tmp_path)!r} + f"/{{label}}_restored.npz", **state(sim))
            sim.step({END} - sim.steps)
            np.savez({str(tmp_path)!r} + f"/{{label}}_end.npz", **state(sim))
        """
    )
    subprocess.run([sys.executable, "-c", child], check=True, cwd=tmp_path)
    end = np.load(tmp_path / "end.npz")
    differ = []
    for label in labels:
        for when, reference in (("restored", np.load(tmp_path / f"{label}_at.npz")), ("end", end)):
            b = np.load(tmp_path / f"{label}_{when}.npz")
            for key in reference.files:
                same = b[key].dtype == reference[key].dtype and b[key].shape == reference[key].shape
                if not (same and np.array_equal(b[key], reference[key])):
                    differ.append(f"{label} checkpoint, {when}: {key}")
    assert not differ, "the restored runs differ: " + "; ".join(differ)
