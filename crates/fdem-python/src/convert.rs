//! Conversions at the boundary: numpy arrays and dicts into the solver's
//! types, its results into numpy arrays, its errors into `fdem.errors`
//! exceptions.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use fdem_solver::{CheckpointError, CrackBand, LawSpec, MaterialSpec, RunError, Softening};

/// A `ValueError` with this message.
pub(crate) fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// Rows of a 2D float array with `N` columns, as fixed-size arrays.
pub(crate) fn rows<const N: usize>(name: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[f64; N]>> {
    let v = a.as_array();
    if v.ncols() != N {
        return Err(value_error(format!("{name} must have shape (n, {N}), got {:?}", v.shape())));
    }
    Ok(v.rows().into_iter().map(|r| std::array::from_fn(|k| r[k])).collect())
}

/// Rows of a 2D integer array with `N` columns, as fixed-size arrays.
pub(crate) fn int_rows<const N: usize>(name: &str, a: &PyReadonlyArray2<'_, i64>) -> PyResult<Vec<[i64; N]>> {
    let v = a.as_array();
    if v.ncols() != N {
        return Err(value_error(format!("{name} must have shape (n, {N}), got {:?}", v.shape())));
    }
    Ok(v.rows().into_iter().map(|r| std::array::from_fn(|k| r[k])).collect())
}

/// Entry `i` of the id array `name` as a `u32` id, or a `ValueError`.
pub(crate) fn to_u32(name: &str, i: usize, x: i64) -> PyResult<u32> {
    u32::try_from(x).map_err(|_| value_error(format!("{name}[{i}] = {x} is not a valid id")))
}

/// Entry `i` of the amplitude index array `name`: `None` when negative.
pub(crate) fn amp_index(name: &str, i: usize, x: i64) -> PyResult<Option<u32>> {
    if x < 0 {
        Ok(None)
    } else {
        to_u32(name, i, x).map(Some)
    }
}

/// An `(n, 2)` numpy copy of `v`.
pub(crate) fn vec2_array<'py>(py: Python<'py>, v: &[[f64; 2]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flatten().copied().collect();
    Array2::from_shape_vec((v.len(), 2), flat).expect("shape").into_pyarray(py)
}

/// An `(n, 4)` numpy copy of `v`.
pub(crate) fn vec4_array<'py>(py: Python<'py>, v: &[[f64; 4]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flatten().copied().collect();
    Array2::from_shape_vec((v.len(), 4), flat).expect("shape").into_pyarray(py)
}

/// Parameter `key` of material `index`'s dict, as a number.
pub(crate) fn get_f64(d: &Bound<'_, PyDict>, index: usize, key: &str) -> PyResult<f64> {
    d.get_item(key)?
        .ok_or_else(|| value_error(format!("material {index}: missing parameter {key}")))?
        .extract::<f64>()
        .map_err(|_| value_error(format!("material {index}: parameter {key} must be a number")))
}

/// A material from the dict the Python layer builds (`Material._kernel_dict`):
/// `kind`, `rho`, `E`, `nu`, and for `mohr_coulomb_rankine` also `c`, `phi`
/// and `psi` (degrees; converted to radians here), `ft`, `Gf`, `GII`,
/// `crack_band` and `softening_kink` (`None` for linear softening, else
/// the kink `(s_k, F_k)` of a bilinear curve).
pub(crate) fn material_from_dict(index: usize, d: &Bound<'_, PyDict>) -> PyResult<MaterialSpec> {
    let kind: String =
        d.get_item("kind")?.ok_or_else(|| value_error(format!("material {index}: missing kind")))?.extract()?;
    let law = match kind.as_str() {
        "elastic" => LawSpec::Elastic,
        "mohr_coulomb_rankine" => {
            let band: String = d.get_item("crack_band")?.map(|v| v.extract()).transpose()?.unwrap_or("oliver".into());
            let kink: Option<(f64, f64)> = match d.get_item("softening_kink")? {
                Some(v) if !v.is_none() => Some(v.extract()?),
                _ => None,
            };
            LawSpec::MohrCoulombRankine {
                cohesion: get_f64(d, index, "c")?,
                friction: get_f64(d, index, "phi")?.to_radians(),
                dilation: get_f64(d, index, "psi")?.to_radians(),
                tensile_strength: get_f64(d, index, "ft")?,
                fracture_energy: get_f64(d, index, "Gf")?,
                shear_fracture_energy: get_f64(d, index, "GII")?,
                crack_band: match band.as_str() {
                    "oliver" => CrackBand::Oliver,
                    "equivalent" => CrackBand::Equivalent,
                    other => {
                        return Err(value_error(format!(
                            "material {index}: crack_band must be 'oliver' or 'equivalent', got '{other}'"
                        )))
                    }
                },
                softening: match kink {
                    None => Softening::Linear,
                    Some((kink_stress, kink_opening)) => Softening::Bilinear { kink_stress, kink_opening },
                },
            }
        }
        other => return Err(value_error(format!("material {index}: unknown kind '{other}'"))),
    };
    Ok(MaterialSpec {
        density: get_f64(d, index, "rho")?,
        young: get_f64(d, index, "E")?,
        poisson: get_f64(d, index, "nu")?,
        law,
    })
}

/// Converts a run error into the matching `fdem.errors` exception.
pub(crate) fn run_error(py: Python<'_>, e: RunError) -> PyErr {
    let msg = e.to_string();
    let made = (|| -> PyResult<PyErr> {
        let errors = py.import("fdem.errors")?;
        let exc = match e {
            RunError::InvertedElement { element, step, time } => {
                errors.getattr("InvertedElementError")?.call1((msg.clone(), element, step, time))?
            }
            RunError::NonFinite { node, quantity, step, time } => {
                errors.getattr("NonFiniteError")?.call1((msg.clone(), node, quantity, step, time))?
            }
            RunError::EnergyGrowth { created, largest, step, time, .. } => {
                errors.getattr("EnergyGrowthError")?.call1((msg.clone(), created, largest, step, time))?
            }
        };
        Ok(PyErr::from_value(exc))
    })();
    made.unwrap_or_else(|_| PyRuntimeError::new_err(msg))
}

/// Converts a checkpoint error into `fdem.errors.CheckpointError`.
pub(crate) fn checkpoint_error(py: Python<'_>, source: &str, e: CheckpointError) -> PyErr {
    let msg = format!("{source}: {e}");
    let made = (|| -> PyResult<PyErr> {
        let errors = py.import("fdem.errors")?;
        Ok(PyErr::from_value(errors.getattr("CheckpointError")?.call1((msg.clone(), source))?))
    })();
    made.unwrap_or_else(|_| PyValueError::new_err(msg))
}
