"""fdem.ensemble: caving runs as tasks on a local Dask cluster (issue 35,
points 3 and 5). The runs are tiny (4 m elements, 0.1 s, about 2 s each)."""

from __future__ import annotations

import dataclasses
import math

import pytest

pytest.importorskip("distributed")
pd = pytest.importorskip("pandas")
pytest.importorskip("pyarrow")

from fdem.caving import CavingCase, paper_joint_sets, run_caving  # noqa: E402
from fdem.ensemble import TIMING_COLUMNS, run_ensemble, run_key, seeded, sweep  # noqa: E402

TINY = CavingCase(size=4.0, joint_scale=5.0, support=5.0, until=0.1, interval=0.03, output_every=0.05)
# jittered joints, so that a seed gives a realisation of its own
JITTERED = dataclasses.replace(
    TINY, joints=tuple(dataclasses.replace(j, jitter=1.0, angle_jitter=3.0) for j in paper_joint_sets(5.0))
)
# 10 m elements are beyond the rock's snap-back limit (8.96 m): the
# Simulation refuses them inside the task
TOO_COARSE = dataclasses.replace(TINY, size=10.0, joint_scale=10.0, support=10.0)
CASES = [TINY, seeded(JITTERED, 7), TOO_COARSE]


def _timing(column: str) -> bool:
    """Whether ``column`` measures the machine rather than the model."""
    return column in TIMING_COLUMNS or (column.startswith("phase_") and column.endswith("_s"))


@pytest.fixture(scope="module")
def ensemble(tmp_path_factory):
    """The three cases on a LocalCluster of 2 worker processes."""
    out = tmp_path_factory.mktemp("ensemble") / "runs.parquet"
    table = run_ensemble(CASES, out, workers=2, quiet=True)
    return out, table


def test_three_rows_one_failed(ensemble):
    out, table = ensemble
    assert list(table["key"]) == [run_key(c) for c in CASES]  # the order given
    assert list(table["status"]) == ["ok", "ok", "error"]
    assert list(table["error"][:2]) == ["", ""]
    assert "snap-back" in table["error"].iloc[2]
    metrics = [c for c in table.columns if c.startswith("metric_")]
    assert "metric_cave_back_m" in metrics and "metric_p50_m" in metrics
    for column in metrics:
        assert math.isnan(table[column].iloc[2]), column
    # an angle of break is NaN where nothing has moved or cracked enough
    for column in ("metric_cave_back_m", "metric_p50_m", "element_updates_per_s", "wall_s", "cracks_inserted"):
        assert table[column].iloc[:2].notna().all(), column
    assert (table["element_updates_per_s"].iloc[:2] > 0).all()
    assert table["task_wall_s"].notna().all()
    # the case's parameters, and the whole case to run it again
    assert list(table["size"]) == [4.0, 4.0, 10.0]
    assert CavingCase.from_json(table["case_json"].iloc[1]) == CASES[1]
    on_disk = pd.read_parquet(out)
    pd.testing.assert_frame_equal(on_disk, table)


def test_rerun_skips_the_runs_done(ensemble, tmp_path):
    out, table = ensemble
    copy = tmp_path / "runs.parquet"
    copy.write_bytes(out.read_bytes())
    again = run_ensemble(CASES, copy, workers=1, quiet=True)
    assert list(again["key"]) == list(table["key"])
    # the two that succeeded are the rows from before; the failed one ran again
    assert list(again["task_wall_s"].iloc[:2]) == list(table["task_wall_s"].iloc[:2])
    assert again["task_wall_s"].iloc[2] != table["task_wall_s"].iloc[2]
    assert again["status"].iloc[2] == "error"
    # nothing left to run: no cluster, the file as it was
    before = pd.read_parquet(copy)
    done = run_ensemble(CASES[:2], copy, quiet=True)
    assert len(done) == 3
    pd.testing.assert_frame_equal(pd.read_parquet(copy), before)


def test_same_answer_as_the_case_run_alone(ensemble, tmp_path):
    """Issue 35 (5): in the ensemble (1 kernel thread, a worker process) and
    alone (all cores, this process), the same numbers, bit for bit."""
    _, table = ensemble
    row = table.iloc[1]
    alone = run_caving(tmp_path, CASES[1], progress=False)
    compared = 0
    for key, value in alone.items():
        if _timing(key) or not isinstance(value, (int, float)):
            continue
        mine = row[key]
        assert mine == value or (math.isnan(mine) and math.isnan(value)), key
        compared += 1
    assert compared > 30
    assert row["threads"] == 1


def test_interrupt_keeps_what_finished(tmp_path, monkeypatch):
    """Ctrl-C while runs are pending (simulated after the first row is
    written): the finished row stays in the file, the rest are cancelled."""
    import fdem.ensemble as ens

    real = ens._write

    def write_then_interrupt(path, rows):
        real(path, rows)
        raise KeyboardInterrupt

    monkeypatch.setattr(ens, "_write", write_then_interrupt)
    out = tmp_path / "runs.parquet"
    with pytest.raises(KeyboardInterrupt):
        run_ensemble([TOO_COARSE, TINY], out, workers=1, quiet=True)
    kept = pd.read_parquet(out)
    assert len(kept) == 1
    assert kept["key"].iloc[0] in {run_key(TOO_COARSE), run_key(TINY)}


def test_seeded_realisations():
    a, b = seeded(JITTERED, 1), seeded(JITTERED, 2)
    assert a == seeded(JITTERED, 1)
    assert a.joints != b.joints
    # each set draws from its own stream
    assert a.joints[0].seed != a.joints[1].seed
    assert run_key(JITTERED, 1) != run_key(JITTERED, 2) != run_key(JITTERED)
    assert run_key(JITTERED, 1) == run_key(CavingCase.from_json(JITTERED.to_json()), 1)
    with pytest.raises(ValueError, match="no joint set of the case is perturbed"):
        seeded(TINY, 1)
    with pytest.raises(ValueError, match="seed must be a whole number"):
        seeded(JITTERED, -1)


def test_sweep():
    cases = sweep(TINY, insert_at=[0.9, 1.0], until=[0.1, 0.2, 0.3])
    assert [(c.insert_at, c.until) for c in cases[:4]] == [(0.9, 0.1), (0.9, 0.2), (0.9, 0.3), (1.0, 0.1)]
    assert len(cases) == 6
    with pytest.raises(ValueError, match="'frition' is not a field"):
        sweep(TINY, frition=[30.0])
    with pytest.raises(ValueError, match="schedule"):
        sweep(TINY, schedule=["sideways"])
    with pytest.raises(ValueError, match="until has no values"):
        sweep(TINY, until=[])


def test_bad_arguments(tmp_path):
    out = tmp_path / "runs.parquet"
    with pytest.raises(ValueError, match="cases: no case"):
        run_ensemble([], out)
    with pytest.raises(ValueError, match=r"cases\[1\] must be a fdem.caving.CavingCase"):
        run_ensemble([TINY, {"size": 5.0}], out)
    with pytest.raises(ValueError, match="workers must be a whole number"):
        run_ensemble(TINY, out, workers=0)
    with pytest.raises(ValueError, match="threads must be a whole number"):
        run_ensemble(TINY, out, threads=1.5)
    with pytest.raises(ValueError, match="no joint set of the case is perturbed"):
        run_ensemble(TINY, out, seeds=[1, 2])
    assert not out.exists()


def _die(case, seed=None, **options):
    """In a worker process (where fdem.ensemble.run_row is the real one):
    the run of the 10 m case kills the process, as the system would one
    out of memory; the others run."""
    import os

    from fdem.ensemble import run_row

    if case.size == 10.0:
        os._exit(1)
    return run_row(case, seed, **options)


def test_a_dead_worker_is_a_row(tmp_path, monkeypatch):
    """A worker that dies during a run makes that run a row with the error;
    the other run finishes. The task (this module's ``_die``, sent by
    value) stands in for run_row."""
    import sys

    import cloudpickle
    import dask
    import fdem.ensemble as ens

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    monkeypatch.setattr(ens, "run_row", _die)
    out = tmp_path / "runs.parquet"
    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
            table = run_ensemble([TINY, TOO_COARSE], out, workers=2, quiet=True)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert list(table["status"]) == ["ok", "error"], list(table["error"])
    assert "KilledWorker" in table["error"].iloc[1]
    assert len(pd.read_parquet(out)) == 2
