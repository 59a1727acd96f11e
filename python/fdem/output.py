"""Result files: one VTU per output step plus a ``.pvd`` index (DESIGN §6),
and an energy history as CSV.

Every file is written to a temporary name and renamed into place, so a frame
listed in the index is always complete and an interrupted run leaves a valid
series behind.
"""

from __future__ import annotations

import contextlib
import csv
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import quoteattr

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from .simulation import Simulation

__all__ = ["VtuSeries", "write_vtu", "principal_stresses"]


def principal_stresses(stress: NDArray[np.float64]) -> NDArray[np.float64]:
    """Principal stresses ``σ1 ≥ σ2 ≥ σ3`` (Pa) of ``[xx, yy, zz, xy]`` rows,
    with ``σ_zz`` as one of the three, shape (n, 3)."""
    stress = np.asarray(stress, dtype=float)
    if stress.ndim != 2 or stress.shape[1] != 4:
        raise ValueError(f"stress must have shape (n, 4) ([xx, yy, zz, xy] rows), got {stress.shape}")
    mean = 0.5 * (stress[:, 0] + stress[:, 1])
    r = np.hypot(0.5 * (stress[:, 0] - stress[:, 1]), stress[:, 3])
    p = np.column_stack([mean + r, mean - r, stress[:, 2]])
    return -np.sort(-p, axis=1)


def _pad3(a: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.column_stack([a, np.zeros(len(a))])


def stress_at(sim: Simulation, points: Any) -> NDArray[np.float64]:
    """Stress ``[xx, yy, zz, xy]`` (Pa) of the active element containing
    each point (m, current configuration), shape (k, 4); NaN where no
    element does (a void). The CST stress is constant in an element."""
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    keep = np.flatnonzero(sim.active())
    p = sim.positions()[sim.triangles()[keep]]
    s = sim.stress()
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    out = np.full((len(pts), 4), np.nan)
    for i, q in enumerate(pts):
        l1 = ((b[:, 1] - c[:, 1]) * (q[0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (q[1] - c[:, 1])) / d
        l2 = ((c[:, 1] - a[:, 1]) * (q[0] - c[:, 0]) + (a[:, 0] - c[:, 0]) * (q[1] - c[:, 1])) / d
        inside = np.flatnonzero((l1 >= -1e-9) & (l2 >= -1e-9) & (1 - l1 - l2 >= -1e-9))
        if len(inside):
            out[i] = s[keep[inside[0]]]
    return out


def write_csv(path: str | os.PathLike[str], header: Sequence[str], rows: Any) -> Path:
    """Writes a table (a header and rows) as CSV; returns its path."""
    target = Path(path)
    with open(target, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(list(header))
        w.writerows(rows)
    return target


def cell_fields(sim: Simulation) -> dict[str, NDArray[Any]]:
    """The element fields written to each frame."""
    stress = sim.stress()
    state = sim.element_state()
    principal = principal_stresses(stress)
    return {
        "stress": stress,
        "principal_stress_1": principal[:, 0],
        "principal_stress_2": principal[:, 1],
        "principal_stress_3": principal[:, 2],
        # the in-plane direction of the larger in-plane principal stress,
        # degrees from x in (−90, 90]
        "principal_direction": np.degrees(0.5 * np.arctan2(2 * stress[:, 3], stress[:, 0] - stress[:, 1])),
        "active": sim.active().astype(np.uint8),
        "fragment": sim.fragment_labels(),
        # κ H / f_t reaches 1 when the band has softened through; beyond it
        # only the raw value says more (how far past)
        "failure_factor": np.minimum(state["failure_factor"], 1.0),
        "failure_factor_raw": state["failure_factor"],
        # the names of Simulation.element_state: one name per field
        "equivalent_plastic_strain": state["equivalent_plastic_strain"],
        "plastic_strain": state["plastic_strain"],
        "kappa": state["kappa"],
        "crack_band": state["crack_band"],
        "crack_direction": state["crack_direction"],
        # density factor of mass scaling (1: physical; docs/mass_scaling.md)
        "mass_scale": sim.mass_scale(),
    }


def interface_tractions(sim: Simulation, lines: NDArray[np.int64]) -> dict[str, NDArray[Any]]:
    """Per interface face (``lines``, node pairs): the normal and shear
    tractions (Pa: the contact forces of the nodes pressing on the face
    over its length, compression positive) and whether any of them slips
    (1) — for the line cells of a frame."""
    n = len(lines)
    normal, shear, slip = np.zeros(n), np.zeros(n), np.zeros(n, dtype=np.uint8)
    if n == 0:
        return {"normal_traction": normal, "shear_traction": shear, "slipping": slip}
    c = sim.contacts()
    if len(c["node"]):
        key = {(int(min(a, b)), int(max(a, b))): i for i, (a, b) in enumerate(lines.tolist())}
        for (a, b), fn, ft, sl in zip(
            c["facet"].tolist(), c["normal_force"], c["tangential_force"], c["slipping"], strict=True
        ):
            i = key.get((min(a, b), max(a, b)))
            if i is not None:
                normal[i] += float(fn)
                shear[i] += float(ft)
                slip[i] |= bool(sl)
        x = sim.positions()
        length = np.linalg.norm(x[lines[:, 1]] - x[lines[:, 0]], axis=1)
        normal /= np.maximum(length, 1e-300)
        shear /= np.maximum(length, 1e-300)
    return {"normal_traction": normal, "shear_traction": shear, "slipping": slip}


def _interface_legend(sim: Simulation) -> dict[str, NDArray[Any]]:
    """The meaning of the ``interface`` index of line cells, as field data
    (``interface_<k>_<name>``: ``[k, 1]``): 0 free surface, the named
    interfaces, the cracks."""
    contact = getattr(sim.model, "_contact", None)
    if not contact:
        return {}
    names = {0: "default"}
    names.update({k: name for name, k in contact["named"].items()})
    names[contact["crack"]] = "cracks"
    return {f"interface_{k}_{v}": np.array([k, 1]) for k, v in sorted(names.items())}


def _add_field_data(path: str, values: dict[str, NDArray[Any]]) -> None:
    """Adds ``values`` as the VTU file's FieldData (meshio's writer leaves
    it out): integer arrays, written as ASCII right after the
    ``<UnstructuredGrid>`` tag, which ParaView and meshio read."""
    if not values:
        return
    with open(path, "rb") as f:
        text = f.read()
    tag = b"<UnstructuredGrid>"
    at = text.find(tag)
    if at < 0:
        return
    arrays = "".join(
        f'<DataArray type="Int64" Name={quoteattr(k)} NumberOfTuples="{len(v)}" format="ascii">'
        + " ".join(str(int(x)) for x in v)
        + "</DataArray>"
        for k, v in values.items()
    )
    text = text[: at + len(tag)] + f"<FieldData>{arrays}</FieldData>".encode() + text[at + len(tag) :]
    with open(path, "wb") as f:
        f.write(text)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[str]:
    """A temporary path beside ``path`` to write the new file to: once the
    ``with`` block ends it replaces ``path`` in one step (``os.replace``).
    If the block fails or is interrupted (a full disk, Ctrl-C), the
    temporary file is removed, ``path`` is left as it was, and an
    ``OSError`` says which file could not be written."""
    target = os.fspath(path)
    tmp = target + ".tmp"
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        if isinstance(exc, OSError) and target not in str(exc):
            raise OSError(exc.errno, f"{target}: could not be written ({exc.strerror or exc})") from exc
        raise


def write_vtu(sim: Simulation, path: str | os.PathLike[str]) -> None:
    """Writes the current state as one VTU file (atomically).

    Cell blocks: the triangles with their fields, and (if any) the faces of
    joints and cracks as lines (cell data ``interface``: the index of their
    contact law; triangle fields are zero on lines and ``interface`` is -1 on
    triangles), so ParaView can show or threshold them. The folder is
    made if it does not exist.
    """
    import meshio

    path = os.fspath(path)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    x = sim.positions()
    # excavated elements are left out: they are no longer part of the model
    keep = sim.active()
    tri = sim.triangles()[keep]
    facets, laws = sim.surface_facets()
    lines = facets[laws > 0]
    cells = {k: np.asarray(v)[keep] for k, v in cell_fields(sim).items()}
    blocks: list[tuple[str, NDArray[Any]]] = [("triangle", tri)]
    cell_data: dict[str, list[NDArray[Any]]] = {k: [np.asarray(v)] for k, v in cells.items()}
    cell_data["interface"] = [np.full(len(tri), -1, dtype=np.int32)]
    if len(lines):
        blocks.append(("line", lines))
        for key, value in cells.items():
            value = np.asarray(value)
            cell_data[key].append(np.zeros((len(lines),) + value.shape[1:], dtype=value.dtype))
        cell_data["interface"].append(laws[laws > 0].astype(np.int32))
    tractions = interface_tractions(sim, lines)
    for key, value in tractions.items():
        cell_data[key] = [np.zeros(len(tri), dtype=value.dtype)] + ([value] if len(lines) else [])
    mesh = meshio.Mesh(
        _pad3(x),
        blocks,
        point_data={
            "displacement": _pad3(x - sim.reference_positions()),
            "velocity": _pad3(sim.velocities()),
        },
        cell_data=cell_data,
    )
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
        _add_field_data(tmp, _interface_legend(sim))
        with open(tmp, "rb+") as f:  # on disk before the index lists it
            os.fsync(f.fileno())


class VtuSeries:
    """A time series of VTU frames with a ``.pvd`` index and an energy CSV.

    Parameters
    ----------
    directory : path
        Where the files go (created if needed).
    name : str
        Base name: frames are ``{name}_{k:05d}.vtu``, the index
        ``{name}.pvd``, the energy history ``{name}_energy.csv`` and, with
        ``reactions``, the load–displacement history
        ``{name}_reactions.csv``.
    overwrite : bool
        Replace an existing series of the same name. Without it an existing
        index is an error, so earlier results are never lost by accident.
    reactions : sequence of str
        Node groups of the model whose support load and mean displacement
        (:meth:`fdem.Simulation.reaction`) go into ``{name}_reactions.csv``
        at every frame and energy row: columns ``{group}_fx``, ``_fy``
        (N per unit thickness, the force the model exerts on the group's
        supports), ``{group}_ux``, ``_uy`` (m).
    """

    def __init__(
        self,
        directory: str | os.PathLike[str],
        name: str = "fdem",
        *,
        overwrite: bool = False,
        reactions: Sequence[str] = (),
        probes: dict[str, Any] | None = None,
    ) -> None:
        self._place(directory, name)
        self.reactions = list(reactions)
        self.probes = dict(probes or {})
        if self.index.exists() and not overwrite:
            raise FileExistsError(f"{self.index} already exists; pass overwrite=True or choose another output name")
        for old in self.directory.glob(f"{name}_[0-9][0-9][0-9][0-9][0-9].vtu"):
            old.unlink()
        self.frames: list[tuple[float, str]] = []
        self._energy_keys: list[str] | None = None
        #: Simulated time of the first frame: output times are ``origin + k
        #: output_every``, also after a restart.
        self.origin: float | None = None
        for old_csv in (self.energy_csv, self.reactions_csv, self.probes_csv):
            if old_csv.exists():
                old_csv.unlink()

    def _place(self, directory: str | os.PathLike[str], name: str) -> None:
        self.directory = Path(directory)
        self.name = name
        self.directory.mkdir(parents=True, exist_ok=True)
        self.index = self.directory / f"{name}.pvd"
        self.energy_csv = self.directory / f"{name}_energy.csv"
        self.reactions_csv = self.directory / f"{name}_reactions.csv"
        self.probes_csv = self.directory / f"{name}_probes.csv"

    def state(self) -> dict[str, Any]:
        """What a checkpoint keeps of the series to continue it."""
        return {
            "directory": os.fspath(self.directory),
            "name": self.name,
            "frames": [[t, f] for t, f in self.frames],
            "origin": self.origin,
            "reactions": self.reactions,
            "probes": self.probes,
        }

    @classmethod
    def resume(cls, state: dict[str, Any], step: int) -> VtuSeries:
        """Reopens a series saved in a checkpoint taken at ``step``: keeps
        the frames the checkpoint lists, deletes frames and energy rows a run
        wrote after it (they will be written again), rewrites the index."""
        self = cls.__new__(cls)
        self._place(state["directory"], str(state["name"]))
        frames: list[tuple[float, str]] = []
        for t, f in state["frames"]:
            # a frame listed twice by a run interrupted while writing it
            # (before this was guarded) is listed once
            if not frames or frames[-1][0] != float(t):
                frames.append((float(t), str(f)))
        self.frames = frames
        self.origin = None if state["origin"] is None else float(state["origin"])
        self.reactions = [str(g) for g in state.get("reactions", [])]
        self.probes = dict(state.get("probes", {}))
        kept = {f for _, f in self.frames}
        # refuse before deleting anything
        missing = [f for f in kept if not (self.directory / f).exists()]
        if missing:
            raise FileNotFoundError(
                f"cannot continue the series {self.index}: frame {sorted(missing)[0]} "
                "listed in the checkpoint is missing"
            )
        for old in self.directory.glob(f"{self.name}_[0-9][0-9][0-9][0-9][0-9].vtu"):
            if old.name not in kept:
                old.unlink()
        self._write_index()
        self._energy_keys = _truncate_history(self.energy_csv, step)
        _truncate_history(self.reactions_csv, step)
        _truncate_history(self.probes_csv, step)
        return self

    def write(self, sim: Simulation, energies: dict[str, float] | None = None) -> Path:
        """Writes the current state as the next frame and updates the index
        and the energy history (``energies``: ``sim.energies()``, if the
        caller has it already)."""
        if self.frames and self.frames[-1][0] == sim.time:
            # the same state again (a write interrupted by Ctrl-C and taken
            # up by the run's handler): replace that frame, list it once
            fname = self.frames[-1][1]
            write_vtu(sim, self.directory / fname)
            self._write_index()
            if self._history_step != sim.steps:
                self._append_energy(sim, sim.energies() if energies is None else energies)
                self._append_reactions(sim)
                self._append_probes(sim)
            return self.directory / fname
        k = len(self.frames)
        fname = f"{self.name}_{k:05d}.vtu"
        write_vtu(sim, self.directory / fname)
        if self.origin is None:
            self.origin = sim.time
        self.frames.append((sim.time, fname))
        self._write_index()
        self._append_energy(sim, sim.energies() if energies is None else energies)
        self._append_reactions(sim)
        self._append_probes(sim)
        return self.directory / fname

    def record_energy(self, sim: Simulation, energies: dict[str, float] | None = None) -> None:
        """Adds the current state to the energy history only, without a
        frame (``energies``: ``sim.energies()``, if the caller has it)."""
        self._append_energy(sim, sim.energies() if energies is None else energies)
        self._append_reactions(sim)
        self._append_probes(sim)

    def _write_index(self) -> None:
        lines = [
            '<?xml version="1.0"?>',
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
            "  <Collection>",
        ]
        for t, f in self.frames:
            lines.append(f'    <DataSet timestep="{t:.9g}" group="" part="0" file={quoteattr(f)}/>')
        lines += ["  </Collection>", "</VTKFile>", ""]
        with atomic_path(self.index) as tmp, open(tmp, "w") as out:
            out.write("\n".join(lines))
            out.flush()
            os.fsync(out.fileno())

    #: The step of the last energy row written (None: none yet this session).
    _history_step: int | None = None

    def _append_energy(self, sim: Simulation, e: dict[str, float]) -> None:
        self._history_step = sim.steps
        rel = abs(e["residual"]) / e["largest_term"] if e["largest_term"] > 0 else 0.0
        row = {"time": sim.time, "step": sim.steps, **e, "relative_residual": rel}
        new = self._energy_keys is None
        if new:
            self._energy_keys = list(row)
        with open(self.energy_csv, "a", newline="") as f:
            w = csv.DictWriter(f, fieldnames=self._energy_keys)
            if new:
                w.writeheader()
            w.writerow(row)
            f.flush()
            os.fsync(f.fileno())

    def _append_probes(self, sim: Simulation) -> None:
        if not self.probes:
            return
        head, row = ["time", "step"], [sim.time, float(sim.steps)]
        for name, where in self.probes.items():
            for key, values in sim.probe(where).items():
                parts = ("xx", "yy", "zz", "xy") if key == "stress" else ("x", "y")
                head += [f"{name}_{key}_{p}" for p in parts]
                row += np.asarray(values, dtype=float).tolist()
        _append_row(self.probes_csv, head, row)

    def _append_reactions(self, sim: Simulation) -> None:
        if not self.reactions:
            return
        head, row = ["time", "step"], [sim.time, float(sim.steps)]
        for group in self.reactions:
            r = sim.reaction(group)
            head += [f"{group}_fx", f"{group}_fy", f"{group}_ux", f"{group}_uy"]
            row += [*r["force"].tolist(), *r["displacement"].tolist()]
        _append_row(self.reactions_csv, head, row)


def _append_row(path: Path, head: list[str], row: list[float]) -> None:
    """Appends a row to a history CSV, with its header if the file is new."""
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.writer(f)
        if new:
            w.writerow(head)
        w.writerow(row)
        f.flush()
        os.fsync(f.fileno())


def _truncate_history(path: Path, step: int) -> list[str] | None:
    """Drops the rows of a history CSV (with a ``step`` column) written
    after ``step`` (a resumed run writes them again); returns its header,
    or None if there is no file or it is empty."""
    if not path.exists():
        return None
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return None
    head, body = rows[0], rows[1:]
    col = head.index("step")
    body = [r for r in body if len(r) == len(head) and int(float(r[col])) <= step]
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        csv.writer(f).writerows([head, *body])
    return head
