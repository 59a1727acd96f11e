"""A rigid floor under the caving block (:attr:`fdem.caving.CavingCase.floor`;
docs/caving.md, "What differs, and why").

The paper removes its support layer "at the bottom of the model" and lets
the caved rock "fall freely" (§3.1, §4.1); by default fdem does the same
and the rock falls without limit. With a floor, the block stands on a
rigid trough: a floor one element thick whose top lies ``depth`` m below
the block's base and, for ``depth`` > 0, walls under the abutments (x
outside the undercut) from the floor up to the base, so that the caved
rock piles up in the cave instead of leaving it. The trough is separate
bodies (they meet the rock by contact) whose nodes are all fixed, with no
initial stress. It leaves the block as it is: its elements and nodes come
after the block's, and the contact penalty stays the block's own (the
default k_n = p E / h takes h, the mean boundary-facet length, from the
block's facets, not the trough's long ones).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .contact import Interface
from .mesh import Mesh

__all__ = ["with_trough", "block_penalty"]


def _part(mesh: Mesh) -> Mesh:
    return mesh.with_sets(element_sets={"all": np.arange(mesh.n_elements)})


def with_trough(block: Mesh, *, width: float, bottom: float, undercut: float, size: float, depth: float) -> Mesh:
    """``block`` (``width`` m wide, centred on x = 0, its base at
    y = ``bottom``) with the trough under it: a floor ``size`` m thick
    whose top lies ``depth`` m below the base, and walls from it up to the
    base outside the undercut (``|x| > undercut / 2``). Element set
    ``trough``; the block's elements and nodes keep their ids."""
    half = 0.5 * undercut
    nx = int(round(width / size))
    parts = [_part(Mesh.rectangle(width, size, nx, 1, origin=(-0.5 * width, bottom - depth - size)))]
    if depth > 0:
        wx = 0.5 * width - half
        nx, ny = max(1, int(round(wx / size))), max(1, int(round(depth / size)))
        for x0 in (-0.5 * width, half):
            parts.append(_part(Mesh.rectangle(wx, depth, nx, ny, origin=(x0, bottom - depth))))
    mesh = Mesh.combine(block, *parts, prefixes=["", *(f"trough{i}_" for i in range(len(parts)))])
    return mesh.with_sets(element_sets={"trough": np.arange(block.n_elements, mesh.n_elements)})


def block_penalty(law: Interface, block: Mesh, young: float) -> Interface:
    """``law`` with the normal (and, when it has none, shear) stiffness it
    would take by default on ``block`` alone: k_n = p E / h with h the mean
    length of the block's boundary facets (:class:`fdem.Interface`)."""
    if law.normal_stiffness is not None:
        return law
    bf = block.boundary_facets()
    h = float(np.linalg.norm(np.diff(block.points[bf], axis=1), axis=2).mean())
    k_n = law.penalty_factor * young / h
    return replace(law, normal_stiffness=k_n, shear_stiffness=law.shear_stiffness or k_n)
