"""Stopping and resuming the caving run (`run_caving(..., resume=True)`,
`examples/block_caving.py --resume`): a paper-scale run takes over an
hour, so a stop (Ctrl-C, a lost machine) must not cost it. Checked against
the run that was not stopped: bit for bit."""

from __future__ import annotations

from dataclasses import asdict, replace

import fdem
import numpy as np
import pytest
from fdem.caving import CavingCase, caving_model, run_caving

QUICK = replace(CavingCase.quick(), until=0.3)


def _same_run(a: dict, b: dict) -> None:
    """Two caving runs ended in the same state, bit for bit."""
    for key in ("steps", "elements_final", "cracks_inserted", "fragments", "fallen_area_m2", "energy_residual_J"):
        assert a[key] == b[key], key
    sa, sb = a["simulation"], b["simulation"]
    assert sa.time == sb.time and sa.steps == sb.steps
    assert np.array_equal(sa.positions(), sb.positions())
    assert np.array_equal(sa.velocities(), sb.velocities())
    assert np.array_equal(sa.stress(), sb.stress())


def test_a_stopped_caving_run_resumes_bit_for_bit(tmp_path, monkeypatch):
    """Ctrl-C in the middle of a stretch of the run, then a resume to the
    same end, then a resume with a later end: the state, the counters and
    the probe table are those of one uninterrupted run to that end."""
    ref = run_caving(tmp_path / "ref", QUICK, threads=2, progress=False)

    # stop in the middle of the third stretch (after 0.1 s), as Ctrl-C does:
    # the kernel has stepped part of the way when the interrupt arrives
    original = fdem.Simulation.run
    calls = [0]

    def interrupted(self, until, **kw):
        calls[0] += 1
        if calls[0] == 4:
            original(self, until=0.5 * (self.time + until), **kw)
            raise KeyboardInterrupt
        return original(self, until, **kw)

    monkeypatch.setattr(fdem.Simulation, "run", interrupted)
    first = replace(QUICK, until=0.2)
    with pytest.raises(KeyboardInterrupt):
        run_caving(tmp_path / "run", first, threads=2, progress=False)
    monkeypatch.undo()
    stopped = fdem.Simulation.from_checkpoint(tmp_path / "run" / "caving.ckpt", caving_model(first))
    assert 0.1 < stopped.time < 0.15, "stopped inside the third stretch"

    # on to the first end (a different thread count: the same numbers) ...
    mid = run_caving(tmp_path / "run", first, threads=1, progress=False, resume=True)
    assert mid["simulation"].time >= 0.2 and mid["simulation"].time < 0.21
    # ... and further: the end may be raised on a resume
    done = run_caving(tmp_path / "run", QUICK, threads=2, progress=False, resume=True)
    _same_run(done, ref)
    assert (tmp_path / "run" / "probes.csv").read_text() == (tmp_path / "ref" / "probes.csv").read_text()


def test_resume_names_what_is_wrong(tmp_path):
    """No checkpoint, a checkpoint not written by the caving run, and one
    written for another case: each a clear error naming the file or the
    differing setting."""
    with pytest.raises(FileNotFoundError, match="no checkpoint to resume from"):
        run_caving(tmp_path, QUICK, progress=False, resume=True)
    model = caving_model(QUICK)
    sim = fdem.Simulation(model)
    sim.save_checkpoint(tmp_path / "caving.ckpt")
    with pytest.raises(ValueError, match="not written by run_caving"):
        run_caving(tmp_path, QUICK, progress=False, resume=True)
    # a setting of the run that the model does not show
    sim.user_data["caving"] = {"case": asdict(replace(QUICK, mass_scaling=0.75))}
    sim.save_checkpoint(tmp_path / "caving.ckpt")
    with pytest.raises(ValueError, match=r"mass_scaling = 0\.7 \(the run: 0\.75\)"):
        run_caving(tmp_path, QUICK, progress=False, resume=True)
    # a run from before `uniform_mesh` existed was meshed by refinement,
    # whatever the default is now
    older = asdict(QUICK)
    del older["uniform_mesh"]
    sim.user_data["caving"] = {"case": older}
    sim.save_checkpoint(tmp_path / "caving.ckpt")
    with pytest.raises(ValueError, match=r"uniform_mesh = True \(the run: False\)"):
        run_caving(tmp_path, QUICK, progress=False, resume=True)


def test_user_data_travels_with_the_checkpoint(tmp_path):
    """`Simulation.user_data` is saved in the checkpoint and given back;
    what JSON cannot hold is refused with a clear error, before anything is
    written."""
    model = caving_model(QUICK)
    sim = fdem.Simulation(model)
    sim.user_data["table"] = [[0.0, 1.5], [0.1, -2.0]]
    path = sim.save_checkpoint(tmp_path / "a.ckpt")
    back = fdem.Simulation.from_checkpoint(path, model)
    assert back.user_data == {"table": [[0.0, 1.5], [0.1, -2.0]]}
    sim.user_data["bad"] = object()
    with pytest.raises(ValueError, match="user_data must be JSON-serialisable"):
        sim.save_checkpoint(tmp_path / "b.ckpt")
    assert not (tmp_path / "b.ckpt").exists()
