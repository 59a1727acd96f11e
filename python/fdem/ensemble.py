"""Many caving runs at once: parameter sweeps and joint realisations as
tasks on a Dask distributed cluster (DESIGN §9, docs/ensembles.md).

A run is a :class:`~fdem.caving.CavingCase` and, optionally, a seed for
its joint network (:func:`seeded`). :func:`run_row` runs one in a
temporary folder and returns its row, a pure function of the case and
seed; :func:`run_ensemble` runs a list of them on a ``LocalCluster`` of
worker processes (or on the scheduler of a cluster of several machines)
and writes the rows to Parquet as they arrive::

    from fdem.caving import CavingCase
    from fdem.ensemble import run_ensemble, sweep

    cases = sweep(CavingCase.quick(), insert_at=[0.9, 1.0])
    table = run_ensemble(cases, "runs.parquet")

A row holds the case's fields (nested values as ``field.sub`` columns,
joint sets and regions as JSON), the seed, ``key`` (a hash of both),
``case_json`` (the whole case, for :meth:`CavingCase.from_json`),
``status`` (``"ok"`` or ``"error"``), ``error`` (the exception, ``""``
when none), ``task_wall_s`` (s) and every number of :func:`run_caving`'s
summary: the caving metrics (``metric_*``), cracks, fragments, fallen and
caved area, abutment factors, energies, ``wall_s`` and
``element_updates_per_s`` of the run's loop.

Needs the ``ensemble`` extra: ``pip install "fdem[ensemble]"``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import os
import socket
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from itertools import product
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .caving import CavingCase, paper_joint_sets, run_caving
from .output import atomic_path

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["TIMING_COLUMNS", "case_columns", "run_ensemble", "run_key", "run_row", "seeded", "sweep"]

#: Columns of a row that measure the machine, not the model: they differ
#: between two runs of the same case; every other column is the same
#: wherever and with however many threads the case ran (``phase_*_s``,
#: the time spent in each phase of the step, are timings too).
TIMING_COLUMNS = ("task_wall_s", "wall_s", "element_updates_per_s", "threads", "host")

_NEEDS = 'fdem.ensemble needs dask[distributed], pandas and pyarrow: pip install "fdem[ensemble]"'


def seeded(case: CavingCase, seed: int) -> CavingCase:
    """Joint realisation ``seed`` of ``case``: its joint sets (``case.joints``,
    or the paper's two scaled by ``case.joint_scale``) with their random
    perturbations drawn from ``seed`` (each set from its own stream, derived
    from ``seed`` and the set's place in the list).

    Raises
    ------
    ValueError
        ``seed`` is not a whole number >= 0, or no joint set of the case
        has a perturbation (``jitter``, ``length_jitter``, ``angle_jitter``
        of :class:`fdem.JointSet`), so that every seed gives the same joints.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a whole number >= 0, got {seed!r}")
    sets = list(case.joints) if case.joints is not None else paper_joint_sets(case.joint_scale)
    if not any(j.jitter or j.length_jitter or j.angle_jitter for j in sets):
        raise ValueError(
            f"seed = {seed}: no joint set of the case is perturbed (jitter, length_jitter or angle_jitter of "
            "fdem.JointSet are all 0), so every seed gives the same joints; give the case jittered joint sets"
        )
    streams = [int(np.random.SeedSequence([int(seed), k]).generate_state(1)[0]) for k in range(len(sets))]
    return dataclasses.replace(
        case, joints=tuple(dataclasses.replace(j, seed=s) for j, s in zip(sets, streams, strict=True))
    )


def sweep(case: CavingCase, **values: Iterable[Any]) -> list[CavingCase]:
    """Every combination of the values given for fields of ``case`` (the
    last field varying fastest), e.g. ``sweep(case, insert_at=[0.9, 1.0],
    joint_law=[Interface(friction=f) for f in (25, 33)])``: four cases.

    Raises
    ------
    ValueError
        A name is not a field of :class:`CavingCase`, a list is empty, or a
        value is not valid for its field (the field is named).
    """
    known = {f.name for f in dataclasses.fields(CavingCase)}
    lists = {}
    for name, options in values.items():
        if name not in known:
            raise ValueError(f"sweep: {name!r} is not a field of CavingCase (fields: {', '.join(sorted(known))})")
        options = list(options)
        if not options:
            raise ValueError(f"sweep: {name} has no values")
        lists[name] = options
    cases = []
    for combo in product(*lists.values()):
        try:
            cases.append(dataclasses.replace(case, **dict(zip(lists, combo, strict=True))))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"sweep: {exc}") from None
    return cases


def run_key(case: CavingCase, seed: int | None = None) -> str:
    """The run's identity: 16 hex digits of the SHA-256 of the case's JSON
    and the seed, the same on every machine and in every session."""
    text = case.to_json() + f"\nseed={seed}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def case_columns(case: CavingCase) -> dict[str, Any]:
    """The case's fields as a row's columns: numbers, strings and flags as
    they are (``None`` for an unset optional number), a material or law as
    one column per property (``rock.E``, ``joint_law.friction``; none when
    unset), joint sets and regions as JSON (``null`` when unset)."""
    out: dict[str, Any] = {}
    for name, value in dataclasses.asdict(case).items():
        if isinstance(value, dict):
            out.update({f"{name}.{k}": v for k, v in value.items()})
        elif name in ("rock", "joint_law", "crack_law"):
            continue
        elif isinstance(value, (list, tuple)) or name in ("joints", "regions"):
            out[name] = json.dumps(value, sort_keys=True)
        else:
            out[name] = value
    return out


def run_row(
    case: CavingCase,
    seed: int | None = None,
    *,
    threads: int | None = 1,
    keep: str | os.PathLike[str] | None = None,
) -> dict[str, Any]:
    """Runs ``case`` (realisation ``seed`` of its joints, :func:`seeded`,
    when a seed is given) with :func:`fdem.caving.run_caving` and returns
    its row (the module docstring lists the columns). A run that raises is
    a row with ``status = "error"`` and the exception in ``error``; this
    function itself does not raise for it.

    ``threads`` is the kernel's thread count for the run (``None``: all
    cores); it changes the timings only. The run writes into a temporary
    folder, removed afterwards, unless ``keep`` names a folder: then into
    ``keep/<key>``, which stays."""
    t0 = time.perf_counter()
    key = run_key(case, seed)
    row: dict[str, Any] = {
        "key": key,
        "seed": seed,
        **case_columns(case),
        "case_json": case.to_json(),
        "status": "ok",
        "error": "",
        "host": socket.gethostname(),
    }
    try:
        run = case if seed is None else seeded(case, seed)
        with contextlib.ExitStack() as stack:
            if keep is None:
                folder = stack.enter_context(tempfile.TemporaryDirectory(prefix="fdem-run-"))
            else:
                folder = os.path.join(os.fspath(keep), key)
            summary = run_caving(folder, run, threads=threads, progress=False)
        for k, v in summary.items():
            if isinstance(v, (bool, int, float, np.integer, np.floating)):
                row[k] = v.item() if isinstance(v, (np.integer, np.floating)) else v
    except Exception as exc:  # the row reports it; the ensemble goes on
        row["status"] = "error"
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["task_wall_s"] = time.perf_counter() - t0
    return row


def _read(path: Path) -> list[dict[str, Any]]:
    """The rows of an earlier ensemble's Parquet file (none if there is no
    file)."""
    import pandas as pd

    if not path.exists():
        return []
    return pd.read_parquet(path).to_dict("records")


def _write(path: Path, rows: Sequence[dict[str, Any]]) -> pd.DataFrame:
    """Writes ``rows`` to ``path`` as Parquet, atomically; returns them as a
    DataFrame."""
    import pandas as pd

    table = pd.DataFrame(list(rows))
    with atomic_path(path) as tmp:
        table.to_parquet(tmp, engine="pyarrow", index=False)
    return table


def _progress(total: int, quiet: bool) -> Any:
    """A bar on stderr of runs done of ``total``, failures and ETA (rich);
    ``None`` when ``quiet``."""
    if quiet:
        return None
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress(
        TextColumn("[bold]fdem ensemble[/]"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("runs, {task.fields[failed]} failed"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        console=Console(stderr=True),
    )


def run_ensemble(
    cases: CavingCase | Sequence[CavingCase],
    out: str | os.PathLike[str],
    *,
    seeds: Sequence[int] | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    threads: int | None = None,
    keep: str | os.PathLike[str] | None = None,
    quiet: bool = False,
) -> pd.DataFrame:
    """Runs every case (with every seed of ``seeds``, :func:`seeded`, when
    given: cases × seeds runs) as a task on a Dask cluster, and returns the
    table of their rows (:func:`run_row`), which is also written to the
    Parquet file ``out`` after each run that ends.

    Parameters
    ----------
    cases
        One case or a list (e.g. from :func:`sweep`); a run listed twice
        runs once.
    out
        The Parquet file. If it exists, its rows are kept and the runs it
        holds with ``status = "ok"`` are not run again (the key is
        :func:`run_key`); failed runs are run again and their rows replaced.
    seeds
        Joint realisations to run of each case (whole numbers >= 0).
    scheduler
        ``None``: a ``LocalCluster`` of worker processes on this machine,
        closed at the end. A scheduler address (``"tcp://host:8786"``) or a
        ``distributed.Client``: that cluster (docs/ensembles.md); its
        workers need fdem installed.
    workers
        Worker processes of the local cluster, one task each at a time
        (default: one per core, at most one per run).
    threads
        Kernel threads per run (default: the cores divided among the local
        workers; 1 on a given scheduler). The results do not depend on it.
    keep
        A folder to keep each run's output in (``keep/<key>``, everything
        :func:`run_caving` writes); by default runs write nothing that stays.
    quiet
        No progress display (runs done, failures, ETA on stderr) and no
        cluster log below errors.

    Returns
    -------
    pandas.DataFrame
        The rows of this call's runs in the order given, then any other
        rows ``out`` held.

    A worker that dies during a run (killed, out of memory) makes that run
    a row with the error; the other runs go on. Ctrl-C cancels the runs
    not finished, leaves ``out`` with those that were, and raises
    ``KeyboardInterrupt``.

    Raises
    ------
    ValueError
        ``cases`` is empty or holds something else than a CavingCase, a seed
        is invalid (:func:`seeded`), or ``workers`` or ``threads`` is not
        a whole number >= 1.
    ImportError
        The ``ensemble`` extra is not installed.
    """
    try:
        import distributed  # noqa: F401
        import pandas  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as exc:
        raise ImportError(f"{_NEEDS} ({exc})") from None
    from distributed import Client, LocalCluster, as_completed

    listed = [cases] if isinstance(cases, CavingCase) else list(cases)
    if not listed:
        raise ValueError("cases: no case to run")
    for i, c in enumerate(listed):
        if not isinstance(c, CavingCase):
            raise ValueError(f"cases[{i}] must be a fdem.caving.CavingCase, got {type(c).__name__}")
    for name, value in (("workers", workers), ("threads", threads)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise ValueError(f"{name} must be a whole number >= 1, got {value!r}")
    realisations = list(seeds) if seeds is not None else [None]
    runs: dict[str, tuple[CavingCase, int | None]] = {}
    for c in listed:
        for s in realisations:
            if s is not None:
                seeded(c, s)  # a bad seed is the caller's error, before anything runs
            runs.setdefault(run_key(c, s), (c, s))
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = {r["key"]: r for r in _read(path)}
    todo = {k: v for k, v in runs.items() if rows.get(k, {}).get("status") != "ok"}

    def table() -> list[dict[str, Any]]:
        """This call's rows in the order of the runs, then the others."""
        mine = [rows[k] for k in runs if k in rows]
        return mine + [r for k, r in rows.items() if k not in runs]

    if not todo:
        return _write(path, table())
    cores = os.cpu_count() or 1
    with contextlib.ExitStack() as stack:
        if scheduler is None:
            n = workers or max(1, min(cores, len(todo)))
            per_run = threads or max(1, cores // n)
            cluster = stack.enter_context(
                LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=":0",
                    silence_logs=logging.ERROR if quiet else logging.WARNING,
                )
            )
            client = stack.enter_context(Client(cluster))
        elif isinstance(scheduler, Client):
            client, per_run = scheduler, threads or 1
        else:
            client = stack.enter_context(Client(scheduler))
            per_run = threads or 1
        futures = {
            client.submit(
                run_row, case, seed, threads=per_run, keep=keep, key=f"fdem-run-{key}", pure=False, retries=0
            ): key
            for key, (case, seed) in todo.items()
        }
        bar = _progress(len(todo), quiet)
        failed = finished = 0
        try:
            if bar is not None:
                stack.enter_context(bar)
                task = bar.add_task("runs", total=len(todo), failed=0)
            for future in as_completed(futures):
                key = futures[future]
                try:
                    row = future.result()
                except Exception as exc:  # the worker died or the task was lost
                    case, seed = todo[key]
                    row = {
                        "key": key,
                        "seed": seed,
                        **case_columns(case),
                        "case_json": case.to_json(),
                        "status": "error",
                        "error": f"{type(exc).__name__}: {exc}",
                    }
                rows[key] = row
                finished += 1
                failed += row["status"] != "ok"
                _write(path, table())
                if bar is not None:
                    bar.update(task, advance=1, failed=failed)
        except KeyboardInterrupt:
            client.cancel(list(futures))
            if not quiet:
                print(f"interrupted: {finished} of {len(todo)} runs kept in {path}", file=sys.stderr, flush=True)
            raise
    return _write(path, table())
