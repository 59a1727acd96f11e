"""Type stubs of the native module ``fdem._core`` (hand-written; checked by
``python -m mypy.stubtest fdem._core`` in the test suite)."""

from typing import Any, final

import numpy as np
from numpy.typing import NDArray

__version__: str
__all__ = [
    "Simulation",
    "validate_mesh",
    "material_point",
    "triangulate",
    "split_along_edges",
    "_panic_selftest",
    "__version__",
]

def validate_mesh(
    points: NDArray[np.float64], triangles: NDArray[np.int64], may_coincide: NDArray[np.bool_]
) -> None: ...
def _panic_selftest() -> None: ...
def triangulate(
    outline: NDArray[np.float64], segments: NDArray[np.float64], max_area: float, min_angle: float, max_nodes: int
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]: ...
def split_along_edges(
    n_nodes: int, triangles: NDArray[np.int64], cut: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.int64]]: ...
def material_point(
    material: dict[str, Any],
    initial_stress: tuple[float, float, float, float],
    crack_band: float,
    strain_increments: NDArray[np.float64] | None = None,
    deformation_gradients: NDArray[np.float64] | None = None,
) -> dict[str, Any]: ...

@final
class Simulation:
    def __new__(
        cls,
        points: NDArray[np.float64],
        triangles: NDArray[np.int64],
        materials: list[dict[str, Any]],
        element_material: NDArray[np.int64],
        *,
        may_coincide: NDArray[np.bool_] | None = None,
        gravity: tuple[float, float] = ...,
        constraint_nodes: NDArray[np.int64] | None = None,
        constraint_fixed: NDArray[np.bool_] | None = None,
        constraint_values: NDArray[np.float64] | None = None,
        constraint_amplitude: NDArray[np.int64] | None = None,
        pressure_facets: NDArray[np.int64] | None = None,
        pressure_values: NDArray[np.float64] | None = None,
        pressure_amplitude: NDArray[np.int64] | None = None,
        amplitudes: list[tuple[list[float], list[float]]] = ...,
        initial_velocity: NDArray[np.float64] | None = None,
        initial_stress: NDArray[np.float64] | None = None,
        contact_laws: NDArray[np.float64] | None = None,
        contact_facets: NDArray[np.int64] | None = None,
        contact_facet_laws: NDArray[np.int64] | None = None,
        crack_law: int = 0,
        contact_margin: float | None = None,
        fracture_interval: int = 0,
        fracture_edge_tolerance: float = 15.0,
        fracture_crack_tolerance: float = 30.0,
        fracture_min_quality: float = 0.2,
        fracture_min_altitude: float = 0.0,
        fracture_insert_at: float = 0.02,
        mass_damping: float = 0.0,
        stiffness_damping: float = 0.0,
        safety: float = 0.8,
        fixed_dt: float | None = None,
        dt_interval: int = 100,
        threads: int = 0,
    ) -> Simulation: ...
    def advance(self, until: float, max_steps: int = ...) -> int: ...
    def step(self, steps: int) -> None: ...
    def set_settings(
        self, *, mass_damping: float, stiffness_damping: float, safety: float, fixed_dt: float | None, dt_interval: int
    ) -> None: ...
    def set_prescribed_velocity(self, nodes: NDArray[np.int64], values: NDArray[np.float64]) -> None: ...
    @property
    def time(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def time_step(self) -> float: ...
    @property
    def critical_time_step(self) -> float: ...
    @property
    def threads(self) -> int: ...
    @property
    def insertions(self) -> int | None: ...
    @property
    def n_nodes(self) -> int: ...
    @property
    def n_elements(self) -> int: ...
    def positions(self) -> NDArray[np.float64]: ...
    def reference_positions(self) -> NDArray[np.float64]: ...
    def velocities(self) -> NDArray[np.float64]: ...
    def stress(self) -> NDArray[np.float64]: ...
    def triangles(self) -> NDArray[np.int64]: ...
    def masses(self) -> NDArray[np.float64]: ...
    def areas(self) -> NDArray[np.float64]: ...
    def active(self) -> NDArray[np.bool_]: ...
    def element_state(self) -> dict[str, Any]: ...
    def contact_stats(self) -> dict[str, int]: ...
    def phase_times(self) -> dict[str, float]: ...
    def contacts(self) -> dict[str, Any]: ...
    def bonds(self) -> dict[str, NDArray[Any]]: ...
    def insertion_audit(self) -> dict[str, float] | None: ...
    def surface_facets(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]: ...
    def energies(self) -> dict[str, Any]: ...
