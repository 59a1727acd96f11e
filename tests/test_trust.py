"""Runs that can be trusted (issue 7): checkpoint and restart, the energy
audit, the watchdog, safe interruption and durable output."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path

import fdem
import meshio
import numpy as np
import pytest
from conftest import assembled_critical_step
from fdem.caving import CavingCase, caving_model

ROOT = Path(__file__).resolve().parent.parent

# A small caving case with everything a step reads: joints and contact
# history, crack insertion, excavation stages, geostatic stress, gravity and
# pressure (3 064 elements; 0.16 s gives ~1 000 cracks and 4 undercut stages).
CASE = "CavingCase(size=5.0, joint_scale=5.0, support=6.0, until=0.3, interval=0.04, start=0.02)"


def small_caving(threads: int) -> fdem.Simulation:
    case = eval(CASE, {"CavingCase": CavingCase})
    sim = fdem.Simulation(caving_model(case), threads=threads, stiffness_damping=2e-6, safety=case.safety)
    sim.equilibrate(max_velocity=1e-3)
    sim.configure(mass_scaling=case.mass_scaling * sim.time_step)  # as run_caving does
    return sim


def state(sim: fdem.Simulation) -> dict[str, np.ndarray]:
    e = sim.energies()
    return {
        "x": sim.positions(),
        "v": sim.velocities(),
        "stress": sim.stress(),
        "tri": sim.triangles(),
        "active": sim.active(),
        "kappa": sim.element_state()["kappa"],
        "mass": sim.masses(),
        "mass_scale": sim.mass_scale(),
        "contacts": sim.contacts()["normal_force"],
        "bonds": sim.bonds()["max_opening"],
        "energies": np.array([e[k] for k in sorted(e)]),
        "clock": np.array([sim.time, sim.steps, sim.time_step, sim.insertions, sim.stages_done]),
    }


def frames_listed(pvd: Path) -> list[tuple[float, str]]:
    root = ET.parse(pvd).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def test_restart_in_a_new_process_on_another_thread_count_is_bit_for_bit(tmp_path):
    """Run A: equilibrium, then to 0.08 s with output (checkpoint at each
    frame), then on to 0.16 s, on 2 threads. Run B, in a new process on one
    thread: from A's checkpoint at 0.08 s to 0.16 s into the same series.
    Every array and every energy term must be bit-for-bit equal, and the
    continued series must list each frame once, complete, in time order."""
    out = tmp_path / "out"
    sim = small_caving(threads=2)
    sim.run(0.08, output_every=0.04, output=out, name="run", progress=False)
    mid = tmp_path / "mid.ckpt"
    mid.write_bytes((out / "run.ckpt").read_bytes())
    assert sim.stages_done >= 2 and sim.insertions > 0
    sim.run(0.16, output_every=0.04, output=out, name="run", progress=False)
    # many insertions between the restart and the end (the count itself
    # varies with round-off: 190 on 2026-11-25, over 200 before)
    assert sim.insertions > 150 and sim.stages_done >= 4, (sim.insertions, sim.stages_done)
    assert sim.added_mass > 0  # the scaled path, checkpointed mid-way
    reference = state(sim)
    frames_a = frames_listed(out / "run.pvd")

    child = textwrap.dedent(
        f"""
        import sys, numpy as np, fdem
        sys.path.insert(0, {str(ROOT / "tests")!r})
        from test_trust import CASE, state
        from fdem.caving import CavingCase, caving_model
        model = caving_model(eval(CASE))
        sim = fdem.Simulation.from_checkpoint({str(mid)!r}, model, threads=1)
        assert sim.threads == 1
        sim.run(0.16, output_every=0.04, output={str(out)!r}, name="run", progress=False)
        np.savez({str(tmp_path / "b.npz")!r}, **state(sim))
        """
    )
    subprocess.run([sys.executable, "-c", child], check=True, cwd=tmp_path)
    b = np.load(tmp_path / "b.npz")
    for key, value in reference.items():
        assert b[key].dtype == value.dtype and b[key].shape == value.shape, key
        assert np.array_equal(b[key], value), f"{key} differs after the restart"
    frames_b = frames_listed(out / "run.pvd")
    times = [t for t, _ in frames_b]
    assert times == sorted(times) and len({f for _, f in frames_b}) == len(frames_b)
    assert [t for t, _ in frames_a] == times, "the continued series differs from the uninterrupted one"
    for _, f in frames_b:
        meshio.read(out / f)
    energy = np.genfromtxt(out / "run_energy.csv", delimiter=",", names=True)
    assert np.all(np.diff(energy["step"]) > 0), "energy rows after the checkpoint were not replaced"


def test_checkpoint_of_another_model_or_a_damaged_file_is_refused(tmp_path):
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 4, 4)
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0, -9.81).fix("bottom")
    sim = fdem.Simulation(model, threads=1)
    sim.step(10)
    path = sim.save_checkpoint(tmp_path / "a.ckpt")
    assert not (tmp_path / "a.ckpt.tmp").exists()
    good = path.read_bytes()
    restored = fdem.Simulation.from_checkpoint(path, model)
    assert restored.steps == 10 and restored.time == sim.time

    def refused(data: bytes | None, match: str, m: fdem.Model = model) -> None:
        p = tmp_path / "bad.ckpt"
        if data is not None:
            p.write_bytes(data)
        with pytest.raises(fdem.CheckpointError, match=match) as info:
            fdem.Simulation.from_checkpoint(p, m)
        assert "bad.ckpt" in str(info.value) and info.value.source.endswith("bad.ckpt")

    refused(good[: len(good) // 2], "truncated")
    refused(good[:30], "truncated")
    flipped = bytearray(good)
    flipped[len(good) // 2] ^= 1
    refused(bytes(flipped), "corrupted")
    refused(b"PK\x03\x04 a zip file, not a checkpoint", "not an fdem checkpoint")
    newer = bytearray(good)
    newer[8:12] = (99).to_bytes(4, "little")
    newer[36:40] = zlib.crc32(bytes(newer[:36])).to_bytes(4, "little")
    refused(bytes(newer), "newer fdem")
    other = fdem.Model(mesh, material=rock).set_gravity(0, -9.0).fix("bottom")
    refused(good, "another model", m=other)
    (tmp_path / "bad.ckpt").unlink()
    refused(None, "bad.ckpt")


def test_the_energy_audit_is_a_csv_per_frame_with_a_warning_and_an_optional_stop(tmp_path):
    """Each frame's row closes the balance: external and support work plus
    the initial energies equal kinetic + elastic + every dissipated or held
    term + the residual (to round-off, recomputed here from the columns);
    above the tolerance a warning, or with ``stop_on_energy_error`` an
    exception after the checkpoint."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 8, 8)
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0, -9.81).fix("bottom")
    sim = fdem.Simulation(model, threads=1, mass_damping=200.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.run(2e-3, output_every=2e-4, output=tmp_path, name="col", progress=False, energy_tolerance=0.05)
    e = np.genfromtxt(tmp_path / "col_energy.csv", delimiter=",", names=True)
    assert len(e) == 11
    supplied = e["external_work"] + e["support_work"] + e["kinetic_initial"] + e["elastic_initial"]
    held = e["kinetic"] + e["elastic"]
    lost = sum(
        e[k]
        for k in (
            "mass_damping",
            "viscous_damping",
            "plastic",
            "fracture",
            "friction",
            "contact_damping",
            "contact_elastic",
            "cohesive_elastic",
            "remeshing",
            "resurfacing",
            "excavated",
            "mass_scaling",
        )
    )
    assert np.allclose(supplied - held - lost, e["residual"], rtol=0, atol=1e-12 * np.abs(supplied).max())
    some = e["largest_term"] > 0
    assert np.allclose(e["relative_residual"][some], np.abs(e["residual"][some]) / e["largest_term"][some])
    assert e["relative_residual"][-1] < 0.01  # the damped column balances to 1%

    with pytest.warns(fdem.EnergyBalanceWarning, match="% of the largest term"):
        sim.run(3e-3, progress=False, energy_tolerance=1e-9)
    with pytest.raises(fdem.EnergyBalanceError, match="largest term") as info:
        sim.run(4e-3, output=tmp_path, name="col", progress=False, energy_tolerance=1e-9, stop_on_energy_error=True)
    assert info.value.checkpoint is not None
    assert fdem.Simulation.from_checkpoint(info.value.checkpoint, model).steps == sim.steps


def unstable(energy_growth: float, factor: float) -> tuple[fdem.Model, fdem.Simulation]:
    """A supported plate under gravity stepped at ``factor`` times the
    critical step of its assembled system (the highest mode's energy grows
    ×1.29 per step at 1.002, ×1.76 at 1.01)."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 6, 6)
    rock = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
    model = fdem.Model(mesh, material=rock).set_gravity(0, -9.81).fix("bottom")
    dt = factor * assembled_critical_step(mesh, rock)
    return model, fdem.Simulation(model, threads=1, dt=dt, energy_growth=energy_growth)


@pytest.mark.parametrize("factor", [1.002, 1.01])
def test_the_watchdog_stops_energy_growth_within_100_steps_and_keeps_the_last_good_state(tmp_path, factor):
    """The step at which created energy first exceeds 10% of the largest
    term is found by stepping a twin with the watchdog off; the watched run
    must stop within 100 steps of it, with an EnergyGrowthError (before the
    growth inverts an element), set back to the step before, with that
    state written as a frame and a checkpoint."""
    model, twin = unstable(0.0, factor)
    first = None
    for _ in range(1000):
        twin.step(1)
        e = twin.energies()
        if -e["residual"] > 0.1 * e["largest_term"]:
            first = twin.steps
            break
    assert first is not None, "the plate did not go unstable"

    _, sim = unstable(0.1, factor)
    with pytest.raises(fdem.EnergyGrowthError, match=r"energy grew without a source at step \d+") as info:
        sim.run(1.0, output_every=1e-3, output=tmp_path, name="u", progress=False)
    err = info.value
    assert first <= err.step <= first + 100, (first, err.step)
    assert err.created > 0.1 * err.largest
    assert sim.steps == err.step - 1, "not set back to the last good state"
    assert err.checkpoint and err.frame and Path(err.frame).exists()
    assert frames_listed(tmp_path / "u.pvd")[-1][1] == Path(err.frame).name
    again = fdem.Simulation.from_checkpoint(err.checkpoint, model)
    assert again.steps == err.step - 1
    with pytest.raises(fdem.EnergyGrowthError) as info2:
        again.step(1)  # the failing step again: same step, same numbers
    assert info2.value.step == err.step and info2.value.created == err.created


def test_an_infinite_velocity_stops_the_run_naming_node_and_quantity_after_the_last_good_state(tmp_path):
    """A prescribed velocity of 1e308 m/s scaled by an amplitude that rises
    from 0 after 1 ms overflows to infinity in the first step past 1 ms:
    NonFiniteError naming that node and ``velocity``, the simulation set
    back to the step before, written as a frame and a checkpoint."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)).fix("bottom")
    node = int(mesh.node_sets["upper_left"][0])
    model.prescribe_velocity([node], vy=1e308, amplitude=fdem.Amplitude((0.0, 1e-3, 2e-3), (0.0, 0.0, 1e308)))
    sim = fdem.Simulation(model, threads=1)
    with pytest.raises(fdem.NonFiniteError) as info:
        sim.run(1.0, output=tmp_path, name="n", progress=False)
    err = info.value
    assert (err.node, err.quantity) == (node, "velocity")
    assert f"velocity of node {node} became NaN or infinite at step {err.step}" in str(err)
    # amplitudes are taken at mid-step: the first step whose middle is past 1 ms
    dt = sim.time_step
    assert err.time - 0.5 * dt > 1e-3 >= err.time - 1.5 * dt
    assert sim.steps == err.step - 1 and sim.time == pytest.approx(err.time - dt, rel=1e-12)
    assert np.isfinite(sim.positions()).all() and np.isfinite(sim.stress()).all()
    assert fdem.Simulation.from_checkpoint(err.checkpoint, model).steps == err.step - 1
    meshio.read(err.frame)


def test_inverted_element_is_named_and_the_state_before_is_kept(tmp_path):
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 4, 4)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)).fix("bottom")
    model.prescribe_velocity("upper_left", vx=0.0, vy=-3000.0)
    sim = fdem.Simulation(model, threads=1)
    with pytest.raises(fdem.InvertedElementError) as info:
        sim.run(1.0, output=tmp_path, name="inv", progress=False)
    err = info.value
    assert f"element {err.element} inverted" in str(err) and f"step {err.step}" in str(err)
    assert sim.steps == err.step - 1 and (sim.areas() > 0).all()
    assert Path(err.frame).exists() and Path(err.checkpoint).exists()
    again = fdem.Simulation.from_checkpoint(err.checkpoint, model)
    with pytest.raises(fdem.InvertedElementError) as info2:
        again.step(1)
    assert (info2.value.step, info2.value.element) == (err.step, err.element)


CTRL_C_CHILD = """
import signal, sys, time, fdem, numpy as np
out = sys.argv[1]
mesh = fdem.Mesh.rectangle(2.0, 1.0, 80, 40)
model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)).set_gravity(0, -9.81).fix("bottom")
sim = fdem.Simulation(model, threads=1)
hit = []
def on_int(signum, frame):
    hit.append(time.perf_counter())
    raise KeyboardInterrupt
signal.signal(signal.SIGINT, on_int)
print("ready", flush=True)
try:
    sim.run(10.0, output_every=1e-4, output=out, name="c", progress=False)
except KeyboardInterrupt:
    print("stopped", time.perf_counter() - hit[0], sim.steps, flush=True)
"""


def test_ctrl_c_stops_within_a_second_with_valid_output_and_a_checkpoint(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-c", CTRL_C_CHILD, str(tmp_path)], stdout=subprocess.PIPE, text=True, cwd=tmp_path
    )
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "ready"
    deadline = time.time() + 60
    while not (tmp_path / "c_00002.vtu").exists() and time.time() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=60)
    word, seconds, steps = out.split()
    assert word == "stopped"
    # from the signal to run() returning: the step under way, the frame and
    # the checkpoint written
    assert float(seconds) < 1.0, f"took {seconds} s to stop"
    listed = frames_listed(tmp_path / "c.pvd")
    for _, f in listed:
        meshio.read(tmp_path / f)
    mesh = fdem.Mesh.rectangle(2.0, 1.0, 80, 40)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)).set_gravity(0, -9.81).fix("bottom")
    sim = fdem.Simulation.from_checkpoint(tmp_path / "c.ckpt", model, threads=1)
    assert sim.steps == int(steps)
    assert abs(listed[-1][0] - sim.time) < 1e-12  # the last frame is the stopped state


def test_the_index_is_replaced_atomically_and_lists_complete_frames_only(tmp_path, monkeypatch):
    """A failure while the index is being replaced (here: the rename)
    leaves the previous index, whose frames are all complete."""
    import fdem.output as output

    mesh = fdem.Mesh.rectangle(1.0, 1.0, 4, 4)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)).set_gravity(0, -9.81).fix("bottom")
    sim = fdem.Simulation(model, threads=1)
    series = fdem.VtuSeries(tmp_path, "s")
    series.write(sim)
    sim.step(5)
    series.write(sim)
    before = (tmp_path / "s.pvd").read_text()

    real = os.replace

    def failing(src, dst):
        if str(dst).endswith(".pvd"):
            raise OSError("disk full")
        return real(src, dst)

    monkeypatch.setattr(output.os, "replace", failing)
    sim.step(5)
    with pytest.raises(OSError, match="disk full"):
        series.write(sim)
    assert (tmp_path / "s.pvd").read_text() == before
    for _, f in frames_listed(tmp_path / "s.pvd"):
        assert meshio.read(tmp_path / f).points.shape[0] == sim.n_nodes


def test_a_restored_run_checkpointed_before_it_runs_keeps_its_series(tmp_path):
    """A run restored from a checkpoint reopens its output series only at its
    first `run()`; a checkpoint written before that must still list the
    series, or the next restore would start a new one over the existing
    `.pvd` and refuse (found in review of the caving resume)."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)).set_gravity(0.0, -9.81)
    sim = fdem.Simulation(model, threads=1)
    sim.run(until=2e-4, output_every=1e-4, output=tmp_path, name="s", progress=False)
    back = fdem.Simulation.from_checkpoint(tmp_path / "s.ckpt", model)
    back.save_checkpoint(tmp_path / "s.ckpt")  # before any run()
    again = fdem.Simulation.from_checkpoint(tmp_path / "s.ckpt", model)
    again.run(until=4e-4, output_every=1e-4, output=tmp_path, name="s", progress=False)
    times = [t for t, _ in frames_listed(tmp_path / "s.pvd")]
    assert times == sorted(times) and len(times) == len(set(times)) and times[-1] >= 4e-4


def test_checkpoint_metadata_is_plain_json():
    """The run description in a checkpoint is JSON (never pickle: loading a
    checkpoint cannot run code)."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0))
    sim = fdem.Simulation(model, threads=1)
    data = sim._core.checkpoint_bytes(sim._meta())
    s_len, u_len = int.from_bytes(data[16:24], "little"), int.from_bytes(data[24:32], "little")
    meta = json.loads(data[40 + s_len : 40 + s_len + u_len])
    assert set(meta) == {"fdem", "fingerprint", "settings", "series", "user"}
    assert meta["user"] == {}


def test_a_run_description_from_before_mass_scaling_still_restores(tmp_path):
    """A checkpoint whose run description predates the ``mass_scaling``
    setting (format 1) restores, runs and takes settings changes, with
    mass scaling off."""
    mesh = fdem.Mesh.rectangle(1.0, 1.0, 2, 2)
    model = fdem.Model(mesh, material=fdem.Elastic(E=60e9, nu=0.25, rho=3100.0))
    sim = fdem.Simulation(model, threads=1)
    sim.step(3)
    meta = json.loads(sim._meta())
    del meta["settings"]["mass_scaling"]
    sim._core.write_checkpoint(str(tmp_path / "old.ckpt"), json.dumps(meta).encode())
    back = fdem.Simulation.from_checkpoint(tmp_path / "old.ckpt", model, threads=1)
    back.configure(safety=0.5)
    back.step(2)
    assert back.steps == 5 and back.added_mass == 0.0


def resident_mb() -> float:
    """Resident set size of this process (MB), from /proc (Linux)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def fragmenting_memory_growth(tmp_path: Path, elements: float, warm_up: float, until: float) -> tuple[float, float]:
    """The fragmenting impact of benchmarks/fracture_impact.py: warm up
    through the impact (most cracks form in the first 0.6 ms), then run on
    with a frame and a checkpoint every 0.1 ms, reading resident memory
    after every 0.5 ms; the largest reading of the first half of the long
    part and of the second. Resident memory swings by tens of MB with the
    frame and checkpoint buffers and comes back (docs/performance.md,
    "Resident memory grows after the impact"), so one reading at the end
    tells only where the swing stood; a leak lifts the peaks of the second
    half above those of the first."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from fracture_impact import build
    finally:
        sys.path.pop(0)
    sim = fdem.Simulation(build(elements), threads=2, stiffness_damping=2e-7)
    sim.run(warm_up, output_every=1e-4, output=tmp_path, name="m", progress=False)
    cracks, readings = sim.insertions, []
    while sim.time < until * (1 - 1e-9):
        sim.run(min(until, sim.time + 5e-4), output_every=1e-4, output=tmp_path, name="m", progress=False)
        readings.append(resident_mb())
    assert sim.insertions > cracks > 1000, "not a fragmenting run"
    half = len(readings) // 2
    return max(readings[:half]), max(readings[half:])


def test_a_fragmenting_impact_ends_on_the_same_bits_on_1_2_3_and_16_threads_and_across_a_restart(tmp_path):
    """Issue 34 (3): the fragmenting impact of benchmarks/fracture_impact.py
    (5 000 elements at the start; by 0.35 ms after the block meets the
    platen some 9 000 cracks, 15 000 contacts and 9 000 bonds over about 16
    chunks of boundary nodes) ends on the same bits on 1, 2, 3 and 16
    threads (16 on fewer cores still splits the work 16 ways), and so does
    a run stopped half-way on 3 threads, checkpointed and resumed on 16."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from fracture_impact import GAP, SPEED, build
    finally:
        sys.path.pop(0)
    model = build(5000)
    start, end = 0.8 * GAP / SPEED, 0.8 * GAP / SPEED + 3.5e-4

    def run(threads: int, until: float, sim: fdem.Simulation | None = None) -> fdem.Simulation:
        sim = sim or fdem.Simulation(model, threads=threads, stiffness_damping=2e-7)
        sim.run(until=until, progress=False)
        return sim

    reference = state(run(1, end))
    assert reference["clock"][3] > 5000 and len(reference["contacts"]) > 10_000 and len(reference["bonds"]) > 5000
    assert len(reference["x"]) > 10 * 1024  # many chunks of boundary nodes
    ends = {threads: state(run(threads, end)) for threads in (2, 3, 16)}
    half = run(3, start + 1.75e-4)
    assert 0 < half.insertions < reference["clock"][3]
    resumed = fdem.Simulation.from_checkpoint(half.save_checkpoint(tmp_path / "half.ckpt"), model, threads=16)
    ends["3, then 16 after a restart"] = state(run(16, end, resumed))
    for label, other in ends.items():
        for key, value in reference.items():
            assert np.array_equal(other[key], value), f"{key} differs on {label} threads"


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc")
def test_resident_memory_of_a_fragmenting_run_grows_under_5_percent_after_warm_up(tmp_path):
    """About 10 000 steps and 25 frames and checkpoints after a warm-up of
    0.5 ms (1 000 elements at the start; the block still cracks until about
    0.75 ms, 2 450 cracks at 0.5 ms and 3 540 by 0.75 ms with the default
    renumbering): the peak resident memory of the second half of them
    within 5% of the first half's."""
    first, second = fragmenting_memory_growth(tmp_path, 1000, 5e-4, 3e-3)
    assert second < 1.05 * first, (first, second)


@pytest.mark.slow
def test_resident_memory_of_a_long_fragmenting_run_grows_under_5_percent(tmp_path):
    """The same on 5 000 elements over 9 ms (90 frames and checkpoints)."""
    first, second = fragmenting_memory_growth(tmp_path, 5000, 1e-3, 10e-3)
    assert second < 1.05 * first, (first, second)
