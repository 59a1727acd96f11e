"""Property-based fuzzing of the Python API's array inputs (issue 7): any
shape, dtype, memory layout or NaN either works or raises ``ValueError`` or
``TypeError`` naming the problem, never anything else, and never crashes
the interpreter (a Rust panic would surface as ``pyo3_runtime.PanicException``,
which derives from ``BaseException`` and fails these tests)."""

from __future__ import annotations

from typing import Any

import fdem
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

ROCK = fdem.Elastic(E=60e9, nu=0.25, rho=3100.0)
ALLOWED = (ValueError, TypeError, fdem.SimulationError)
FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])

DTYPES = st.sampled_from(
    [np.float64, np.float32, np.int64, np.int32, np.uint8, np.bool_, np.complex128, np.float16, np.int8]
)


@st.composite
def arrays(draw: Any, max_dims: int = 3) -> Any:
    """An array of any small shape and dtype, with NaN, inf, huge and
    negative values where the dtype allows, possibly non-contiguous
    (a strided or transposed view) or a plain nested list."""
    dtype = draw(DTYPES)
    shape = draw(hnp.array_shapes(min_dims=0, max_dims=max_dims, min_side=0, max_side=6))
    elements = None
    if np.issubdtype(dtype, np.floating):
        elements = st.floats(allow_nan=True, allow_infinity=True, width=np.dtype(dtype).itemsize * 8)
    a = draw(hnp.arrays(dtype, shape, elements=elements))
    layout = draw(st.sampled_from(["c", "strided", "transposed", "list", "fortran"]))
    if layout == "strided" and a.ndim >= 1:
        a = np.repeat(a, 2, axis=0)[::2]
    elif layout == "transposed" and a.ndim >= 2:
        a = np.ascontiguousarray(a.T).T
    elif layout == "fortran":
        a = np.asfortranarray(a)
    elif layout == "list":
        return a.tolist()
    return a


@st.composite
def near_valid(draw: Any, shape: tuple[int, ...], high: float = 10.0) -> Any:
    """Mostly the right shape, with a chance of the wrong one, of NaN, of
    an odd dtype or layout: the inputs a user gets almost right."""
    if draw(st.booleans()):
        return draw(arrays())
    dtype = draw(st.sampled_from([np.float64, np.float32, np.int64, np.int32]))
    elements = (
        st.floats(-high, high, allow_nan=False, width=32)
        if np.issubdtype(dtype, np.floating)
        else st.integers(-2, int(high))
    )
    a = draw(hnp.arrays(dtype, shape, elements=elements))
    if np.issubdtype(dtype, np.floating) and a.size and draw(st.booleans()):
        a.flat[draw(st.integers(0, a.size - 1))] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    if a.ndim == 2 and draw(st.booleans()):
        a = np.asfortranarray(a)
    return a


def some_calls(data: Any, calls: list[Any], most: int) -> None:
    """Makes up to ``most`` of ``calls``, drawn with repetition, in a drawn
    order; each may refuse its input with an allowed exception."""
    for k in data.draw(st.lists(st.integers(0, len(calls) - 1), max_size=most)):
        try:
            calls[k]()
        except ALLOWED:
            pass


def steps_or_refuses(model: fdem.Model, steps: int) -> None:
    """Builds a simulation of ``model`` and steps it, or refuses with an
    allowed exception."""
    try:
        fdem.Simulation(model, threads=1).step(steps)
    except ALLOWED:
        pass


def square() -> fdem.Mesh:
    return fdem.Mesh.rectangle(1.0, 1.0, 3, 3)


@FUZZ
@given(points=arrays(), triangles=arrays())
def test_mesh_from_arbitrary_arrays(points, triangles):
    try:
        mesh = fdem.Mesh(points, triangles)
    except ALLOWED:
        return
    assert mesh.points.dtype == np.float64 and mesh.triangles.dtype == np.int64


@FUZZ
@given(data=st.data())
def test_mesh_from_almost_valid_arrays(data):
    base = square()
    points = data.draw(near_valid(base.points.shape, high=1.0))
    triangles = data.draw(near_valid(base.triangles.shape, high=float(base.n_nodes)))
    try:
        model = fdem.Model(fdem.Mesh(points, triangles), material=ROCK)
    except ALLOWED:
        return
    steps_or_refuses(model, 2)


@FUZZ
@given(data=st.data())
def test_model_inputs(data):
    mesh = square()
    model = fdem.Model(mesh, material=ROCK).set_gravity(0.0, -9.81)
    n, m = mesh.n_nodes, mesh.n_elements
    calls = [
        lambda: model.set_initial_velocity(data.draw(near_valid((n, 2)))),
        lambda: model.set_initial_stress(data.draw(near_valid((m, 4), high=1e6))),
        lambda: model.fix(data.draw(near_valid((3,), high=n + 2))),
        lambda: model.prescribe_velocity(data.draw(near_valid((2,), high=n)), vy=data.draw(st.floats())),
        lambda: model.pressure(data.draw(near_valid((2, 2), high=n)), data.draw(st.floats())),
        lambda: model.excavate(data.draw(near_valid((2,), high=m)), at=data.draw(st.floats())),
    ]
    some_calls(data, calls, 4)
    steps_or_refuses(model, 3)


@FUZZ
@given(data=st.data())
def test_simulation_inputs(data):
    mesh = square()
    model = fdem.Model(mesh, material=ROCK).prescribe_velocity("bottom", vx=0.0, vy=0.0)
    sim = fdem.Simulation(model, threads=1)
    n, m = mesh.n_nodes, mesh.n_elements
    calls = [
        lambda: sim.deactivate(data.draw(near_valid((3,), high=m + 2))),
        lambda: sim.set_prescribed_velocity(data.draw(near_valid((2,), high=n)), data.draw(near_valid((2, 2)))),
        lambda: sim.step(
            data.draw(
                st.one_of(
                    st.integers(-3, 3),
                    st.floats(-3, 3),
                    st.sampled_from([np.nan, np.inf, 2**64, 1e300, "1", None, 2.5]),
                )
            )
        ),
        # (a huge valid end time would only run long)
        lambda: sim.run(
            data.draw(st.one_of(st.floats(-1.0, 1e-4), st.sampled_from([np.nan, np.inf, -np.inf]))), progress=False
        ),
        # (a tiny valid safety factor would only run long)
        lambda: sim.configure(
            safety=data.draw(st.one_of(st.floats(0.05, 1.0), st.sampled_from([np.nan, np.inf, 0.0, -1.0, 2.0]))),
            energy_growth=data.draw(st.floats()),
        ),
    ]
    some_calls(data, calls, 5)
    assert np.isfinite(sim.positions()).all()


@FUZZ
@given(E=st.floats(), nu=st.floats(), rho=st.floats())
def test_material_parameters(E, nu, rho):
    try:
        mat = fdem.Elastic(E=E, nu=nu, rho=rho)
    except ALLOWED:
        return
    assert mat.E > 0 and -1 < mat.nu < 0.5 and mat.rho > 0


@pytest.mark.parametrize("bad", [np.nan, np.inf, "x", None])
def test_run_until_is_checked(bad):
    sim = fdem.Simulation(fdem.Model(square(), material=ROCK), threads=1)
    with pytest.raises(ValueError, match="until"):
        sim.run(bad, progress=False)
