//! The free functions of `fdem._core`: mesh validation and meshing helpers,
//! the single material point driver, and the panic self-test.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use fdem_solver::material_point::{material_point as drive_point, Path};

use crate::convert::{int_rows, material_from_dict, rows, value_error, vec2_array, vec4_array};
use crate::guard;

/// Checks a mesh (`fdem_mesh::validate`): raises `ValueError` naming the
/// first offending node or element.
#[pyfunction]
pub(crate) fn validate_mesh(
    points: PyReadonlyArray2<'_, f64>,
    triangles: PyReadonlyArray2<'_, i64>,
    may_coincide: PyReadonlyArray1<'_, bool>,
) -> PyResult<()> {
    guard(|| {
        let points = rows::<2>("points", &points)?;
        let triangles: Vec<[u64; 3]> =
            int_rows::<3>("triangles", &triangles)?.into_iter().map(|t| t.map(|v| v.max(0) as u64)).collect();
        let may = may_coincide.as_array().to_vec();
        fdem_solver::validate_mesh(&points, &triangles, &may).map_err(|e| value_error(e.to_string()))
    })
}

/// Drives one material point (see `fdem.material_point`): exactly one of
/// `strain_increments` (n, 3: xx, yy, xy tensor shear) or
/// `deformation_gradients` (n, 4: F11, F12, F21, F22). Returns a dict of
/// history arrays.
#[pyfunction]
#[pyo3(signature = (material, initial_stress, crack_band, strain_increments=None, deformation_gradients=None))]
pub(crate) fn material_point<'py>(
    py: Python<'py>,
    material: Bound<'py, PyDict>,
    initial_stress: (f64, f64, f64, f64),
    crack_band: f64,
    strain_increments: Option<PyReadonlyArray2<'py, f64>>,
    deformation_gradients: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    guard(|| {
        let spec = material_from_dict(0, &material)?;
        let path = match (strain_increments, deformation_gradients) {
            (Some(a), None) => Path::StrainIncrements(rows::<3>("strain_increments", &a)?),
            (None, Some(f)) => Path::DeformationGradients(rows::<4>("deformation_gradients", &f)?),
            _ => return Err(value_error("give exactly one of strain_increments and deformation_gradients")),
        };
        let (a, b, c, e) = initial_stress;
        let h = drive_point(&spec, [a, b, c, e], &path, crack_band).map_err(|e| value_error(e.to_string()))?;
        let d = PyDict::new(py);
        d.set_item("stress", vec4_array(py, &h.stress))?;
        d.set_item("plastic_strain", vec4_array(py, &h.state.iter().map(|s| s.plastic_strain).collect::<Vec<_>>()))?;
        d.set_item("kappa", h.state.iter().map(|s| s.kappa).collect::<Vec<_>>().into_pyarray(py))?;
        d.set_item(
            "equivalent_plastic_strain",
            h.state.iter().map(|s| s.equivalent_plastic_strain).collect::<Vec<_>>().into_pyarray(py),
        )?;
        d.set_item("failure_factor", h.failure_factor.into_pyarray(py))?;
        d.set_item("active", h.active.into_pyarray(py))?;
        d.set_item("plastic_dissipation", h.plastic_dissipation.into_pyarray(py))?;
        d.set_item("fracture_dissipation", h.fracture_dissipation.into_pyarray(py))?;
        Ok(d)
    })
}

/// Meshes a polygon with line segments embedded (constrained Delaunay with
/// refinement): returns `(points (n, 2), triangles (m, 3), constraint edges
/// (k, 2))`. `size` > 0 gives nearly equilateral triangles of that edge
/// (m) (`fdem_mesh::generate::triangulate_uniform`); otherwise triangles
/// have an area of at most `max_area` (`fdem_mesh::generate::triangulate`).
#[pyfunction]
#[pyo3(signature = (outline, segments, max_area, min_angle, max_nodes, size=0.0))]
#[allow(clippy::type_complexity)]
pub(crate) fn triangulate<'py>(
    py: Python<'py>,
    outline: PyReadonlyArray2<'py, f64>,
    segments: PyReadonlyArray2<'py, f64>,
    max_area: f64,
    min_angle: f64,
    max_nodes: usize,
    size: f64,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>, Bound<'py, PyArray2<i64>>)> {
    guard(|| {
        let outline = rows::<2>("outline", &outline)?;
        let segs: Vec<[[f64; 2]; 2]> =
            rows::<4>("segments", &segments)?.into_iter().map(|[a, b, c, d]| [[a, b], [c, d]]).collect();
        let g = if size > 0.0 {
            fdem_solver::mesh::triangulate_uniform(&outline, &segs, size, min_angle, max_nodes)
        } else {
            fdem_solver::mesh::triangulate(&outline, &segs, max_area, min_angle, max_nodes)
        }
        .map_err(|e| value_error(e.to_string()))?;
        let tri: Vec<i64> = g.triangles.iter().flatten().map(|&v| v as i64).collect();
        let ce: Vec<i64> = g.constraint_edges.iter().flatten().map(|&v| v as i64).collect();
        Ok((
            vec2_array(py, &g.points),
            Array2::from_shape_vec((g.triangles.len(), 3), tri).expect("shape").into_pyarray(py),
            Array2::from_shape_vec((g.constraint_edges.len(), 2), ce).expect("shape").into_pyarray(py),
        ))
    })
}

/// Opens edges into interfaces by duplicating nodes: returns the new
/// triangles and, for every appended node, its parent. See
/// `fdem_mesh::split::split_along_edges`.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub(crate) fn split_along_edges<'py>(
    py: Python<'py>,
    n_nodes: usize,
    triangles: PyReadonlyArray2<'py, i64>,
    cut: PyReadonlyArray2<'py, i64>,
) -> PyResult<(Bound<'py, PyArray2<i64>>, Bound<'py, PyArray1<i64>>)> {
    guard(|| {
        let mut t: Vec<[u32; 3]> = int_rows::<3>("triangles", &triangles)?
            .into_iter()
            .enumerate()
            .map(|(e, r)| {
                let ok = r.iter().all(|&v| v >= 0 && (v as usize) < n_nodes);
                if ok {
                    Ok(r.map(|v| v as u32))
                } else {
                    Err(value_error(format!("element {e} refers to a node out of range")))
                }
            })
            .collect::<PyResult<_>>()?;
        let cut: Vec<[u32; 2]> = int_rows::<2>("cut", &cut)?
            .into_iter()
            .enumerate()
            .map(|(i, r)| {
                if r.iter().all(|&v| v >= 0 && (v as usize) < n_nodes) {
                    Ok(r.map(|v| v as u32))
                } else {
                    Err(value_error(format!("cut edge {i} refers to a node out of range")))
                }
            })
            .collect::<PyResult<_>>()?;
        let parents = fdem_solver::mesh::split_along_edges(n_nodes, &mut t, &cut);
        let flat: Vec<i64> = t.iter().flatten().map(|&v| v as i64).collect();
        Ok((
            Array2::from_shape_vec((t.len(), 3), flat).expect("shape").into_pyarray(py),
            parents.into_iter().map(|p| p as i64).collect::<Vec<_>>().into_pyarray(py),
        ))
    })
}

/// Diagnostic: panics inside the guard, to show that a kernel panic reaches
/// Python as `RuntimeError` (used by the test suite).
#[pyfunction]
pub(crate) fn _panic_selftest() -> PyResult<()> {
    guard(|| -> PyResult<()> { panic!("deliberate panic from _panic_selftest") })
}
