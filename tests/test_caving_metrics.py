"""Caving metrics (issue 35, point 1), each on a constructed state whose
answer is known, and their output from the quick caving run."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from fdem.caving_metrics import (
    angles_of_break,
    cave_back_height,
    passing_sizes,
    subsidence_profile,
    yielded_area,
)


def test_cave_back_is_the_highest_caved_rock_over_the_midline():
    """A column of elements at x = 0 and y = 0.5, 1.5, …, 9.5 m above the
    undercut level 0: those up to 6.5 m have settled 0.3 m, the one at
    8.5 m is fractured but lies 6 m off the midline (outside a 5 m band):
    the back is at 6.5 m; nothing caved gives 0."""
    y = np.arange(10) + 0.5
    c = np.column_stack([np.zeros(10), y])
    settle = np.where(y <= 6.5, 0.3, 0.0)
    c[8, 0] = 6.0
    fractured = np.zeros(10, dtype=bool)
    fractured[8] = True
    assert cave_back_height(c, settle, fractured, level=0.0, band=5.0, threshold=0.1) == pytest.approx(6.5)
    assert cave_back_height(c, 0 * settle, 0 * fractured, level=0.0, band=5.0, threshold=0.1) == 0.0


def test_angle_of_break_from_the_undercut_edge_to_the_disturbed_surface():
    """A top face 100 m above an undercut from −80 to 80 m that has
    settled out to x = −120 and 100 m: the angles of break are atan(100/40)
    = 68.2° on the left and atan(100/20) = 78.7° on the right; settlement
    only inside the undercut's span gives 90°; none gives NaN."""
    x = np.arange(-150.0, 150.125, 0.25)
    settle = np.where((x >= -120.0) & (x <= 100.0), 0.5, 0.0)
    left, right = angles_of_break(x, settle, edges_x=(-80.0, 80.0), level=0.0, top=100.0, threshold=0.1)
    assert left == pytest.approx(math.degrees(math.atan2(100, 40)), abs=1e-9)
    assert right == pytest.approx(math.degrees(math.atan2(100, 20)), abs=1e-9)
    inside = np.where(np.abs(x) < 50.0, 0.5, 0.0)
    assert angles_of_break(x, inside, edges_x=(-80.0, 80.0), level=0.0, top=100.0, threshold=0.1) == (90.0, 90.0)
    assert all(math.isnan(a) for a in angles_of_break(x, 0 * x, edges_x=(-80, 80), level=0, top=100, threshold=0.1))


def test_subsidence_profile_and_yielded_area():
    """The largest settlement per x bin (NaN in an empty bin); the area of
    elements with plastic strain or a failure factor of 1."""
    prof = subsidence_profile(np.array([0.5, 1.5, 1.7, 3.5]), np.array([0.1, 0.2, 0.4, 0.3]), np.arange(5.0))
    assert prof[:2].tolist() == [0.1, 0.4] and math.isnan(prof[2]) and prof[3] == 0.3
    a = np.array([1.0, 2.0, 3.0, 4.0])
    assert yielded_area(a, np.array([0.0, 0.1, 0.0, 0.0]), np.array([0.2, 0.0, 1.0, 0.99])) == 5.0


def test_passing_sizes_are_area_weighted():
    """Fragments of areas π/4 × (1, 1, 4, 16) m² (diameters 1, 1, 2, 4 m,
    total π/4 × 22): 2/22 of the area is in the 1 m ones, 6/22 up to
    2 m: P20 = 2 m, P50 = P80 = 4 m, P5 = 1 m."""
    areas = np.pi / 4 * np.array([16.0, 1.0, 4.0, 1.0])
    assert passing_sizes(areas, (0.05, 0.2, 0.5, 0.8)) == pytest.approx([1.0, 2.0, 4.0, 4.0])
    assert all(math.isnan(v) for v in passing_sizes(np.zeros(0)))


def test_the_quick_run_writes_its_metrics(quick_caving):
    """The quick case's metrics.csv: one row per sample, the cave back
    zero before the undercut and rising with it (monotone within one
    element, 4 m), above half the block by the end; the summary carries
    the last row."""
    out, summary = quick_caving
    with open(out / "metrics.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    back = np.array([float(r["cave_back_m"]) for r in rows])
    assert back[0] == 0.0 and back[-1] > 50.0
    assert np.all(np.diff(back) > -4.0)
    assert summary["metric_cave_back_m"] == back[-1]
    assert (out / "metrics.png").stat().st_size > 10_000 and (out / "subsidence.csv").exists()


def test_energy_partition_and_the_stage_table(quick_caving):
    """The energy shares of the quick run add up, with what the metrics do
    not list (elastic energy, excavation, mass scaling, contact springs,
    the residual), to the energy supplied: the listed ones lie in [0, 1]
    and sum to at most 1 + 2% (the balance tolerance); stages.csv has one
    row per undercut stage, the width growing 20 m per stage."""
    out, _ = quick_caving
    with open(out / "metrics.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    keys = ("energy_kinetic", "energy_plastic", "energy_fracture", "energy_friction", "energy_damping")
    last = [float(rows[-1][k]) for k in keys]
    assert all(0.0 <= v <= 1.0 for v in last) and sum(last) <= 1.02
    assert float(rows[-1]["energy_kinetic"]) > 0.05
    with open(out / "stages.csv", newline="") as f:
        stages = list(csv.DictReader(f))
    assert [int(r["stage"]) for r in stages] == list(range(1, 9))
    assert [float(r["undercut_width_m"]) for r in stages] == [20.0 * k for k in range(1, 9)]
