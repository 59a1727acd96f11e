"""Progress display of a run: simulated time, steps per second, ETA."""

from __future__ import annotations

import time
from types import TracebackType

__all__ = ["RunProgress"]


class RunProgress:
    """A progress bar over simulated time (rich), or nothing when disabled.

    Parameters
    ----------
    start, until : float
        Simulated time span of the run (s).
    enabled : bool
        Show the bar.
    """

    def __init__(self, start: float, until: float, enabled: bool = True) -> None:
        self.start, self.until, self.enabled = start, until, enabled
        self._progress = None
        self._task = None
        self._t0 = time.perf_counter()
        self._steps0: int | None = None

    def __enter__(self) -> RunProgress:
        if self.enabled:
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            self._progress = Progress(
                TextColumn("[bold]fdem[/]"),
                BarColumn(),
                TextColumn("t = {task.fields[t]:.4g} / {task.fields[until]:.4g} s"),
                TextColumn("{task.fields[rate]:>9.0f} steps/s"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                transient=False,
            )
            self._progress.__enter__()
            self._task = self._progress.add_task(
                "run", total=max(self.until - self.start, 1e-300), t=self.start, until=self.until, rate=0.0
            )
        return self

    def update(self, t: float, steps: int) -> None:
        """Reports simulated time ``t`` (s) after ``steps`` total steps."""
        if self._steps0 is None:
            self._steps0 = steps
        if self._progress is not None and self._task is not None:
            wall = max(time.perf_counter() - self._t0, 1e-9)
            self._progress.update(
                self._task, completed=min(t, self.until) - self.start, t=t, rate=(steps - self._steps0) / wall
            )

    def __exit__(self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None) -> None:
        if self._progress is not None:
            self._progress.__exit__(et, ev, tb)
