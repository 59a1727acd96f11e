//! The `Simulation` class of `fdem._core`: the kernel state built from the
//! Python layer's arrays, stepped, saved and read out.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::{Duration, Instant};

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use fdem_solver::{
    Amplitude, Bond, Constraint, ContactSpec, ExcavationStage, FractureParams, FractureSpec, InterfaceSpec, ModelSpec,
    PressureLoad, Settings,
};

use crate::convert::{
    amp_index, checkpoint_error, int_rows, material_from_dict, rows, run_error, to_u32, value_error, vec2_array,
    vec4_array,
};
use crate::guard;

/// An explicit FDEM simulation held in Rust. Built by `fdem.Simulation`
/// from a `fdem.Model`; see that class for the user-facing API.
#[pyclass(module = "fdem._core", name = "Simulation")]
pub(crate) struct PySimulation {
    sim: fdem_solver::Simulation,
    /// Set when a panic left the state undefined.
    poisoned: bool,
}

impl PySimulation {
    fn ok(&self) -> PyResult<()> {
        if self.poisoned {
            Err(PyRuntimeError::new_err("this simulation was stopped by an internal error and cannot continue"))
        } else {
            Ok(())
        }
    }
}

#[pymethods]
impl PySimulation {
    /// Builds the kernel state. Arrays must be C-ordered or not, of the
    /// documented dtypes (the Python wrapper converts); every problem raises
    /// `ValueError` naming the node, element, parameter or entry.
    #[new]
    #[pyo3(signature = (
        points, triangles, materials, element_material, *,
        may_coincide=None, gravity=(0.0, 0.0),
        constraint_nodes=None, constraint_fixed=None, constraint_values=None, constraint_amplitude=None,
        pressure_facets=None, pressure_values=None, pressure_amplitude=None,
        amplitudes=Vec::new(), initial_velocity=None, initial_stress=None,
        contact_laws=None, contact_facets=None, contact_facet_laws=None, crack_law=0, contact_margin=None,
        fracture_interval=0, fracture_edge_tolerance=15.0, fracture_crack_tolerance=30.0, fracture_min_quality=0.2, fracture_min_altitude=0.0, fracture_insert_at=0.02,
        stage_times=Vec::new(), stage_elements=Vec::new(), stage_ramps=Vec::new(),
        mass_damping=0.0, stiffness_damping=0.0, safety=0.8, fixed_dt=None, dt_interval=100, energy_growth=0.05, mass_scaling=None, renumber=None, renumber_every=None, threads=0, local_damping=0.0
    ))]
    fn new(
        points: PyReadonlyArray2<'_, f64>,
        triangles: PyReadonlyArray2<'_, i64>,
        materials: Vec<Bound<'_, PyDict>>,
        element_material: PyReadonlyArray1<'_, i64>,
        may_coincide: Option<PyReadonlyArray1<'_, bool>>,
        gravity: (f64, f64),
        constraint_nodes: Option<PyReadonlyArray1<'_, i64>>,
        constraint_fixed: Option<PyReadonlyArray2<'_, bool>>,
        constraint_values: Option<PyReadonlyArray2<'_, f64>>,
        constraint_amplitude: Option<PyReadonlyArray1<'_, i64>>,
        pressure_facets: Option<PyReadonlyArray2<'_, i64>>,
        pressure_values: Option<PyReadonlyArray1<'_, f64>>,
        pressure_amplitude: Option<PyReadonlyArray1<'_, i64>>,
        amplitudes: Vec<(Vec<f64>, Vec<f64>)>,
        initial_velocity: Option<PyReadonlyArray2<'_, f64>>,
        initial_stress: Option<PyReadonlyArray2<'_, f64>>,
        contact_laws: Option<PyReadonlyArray2<'_, f64>>,
        contact_facets: Option<PyReadonlyArray2<'_, i64>>,
        contact_facet_laws: Option<PyReadonlyArray1<'_, i64>>,
        crack_law: u16,
        contact_margin: Option<f64>,
        fracture_interval: u32,
        fracture_edge_tolerance: f64,
        fracture_crack_tolerance: f64,
        fracture_min_quality: f64,
        fracture_min_altitude: f64,
        fracture_insert_at: f64,
        stage_times: Vec<f64>,
        stage_elements: Vec<PyReadonlyArray1<'_, i64>>,
        stage_ramps: Vec<f64>,
        mass_damping: f64,
        stiffness_damping: f64,
        safety: f64,
        fixed_dt: Option<f64>,
        dt_interval: u32,
        energy_growth: f64,
        mass_scaling: Option<f64>,
        renumber: Option<f64>,
        renumber_every: Option<u64>,
        threads: usize,
        local_damping: f64,
    ) -> PyResult<Self> {
        guard(|| {
            let points = rows::<2>("points", &points)?;
            let triangles: Vec<[u64; 3]> = int_rows::<3>("triangles", &triangles)?
                .into_iter()
                .enumerate()
                .map(|(e, t)| {
                    if let Some(v) = t.iter().find(|&&v| v < 0) {
                        Err(value_error(format!("element {e} refers to node {v}; node ids must be >= 0")))
                    } else {
                        Ok(t.map(|v| v as u64))
                    }
                })
                .collect::<PyResult<_>>()?;
            let materials =
                materials.iter().enumerate().map(|(i, d)| material_from_dict(i, d)).collect::<PyResult<Vec<_>>>()?;
            let element_material = element_material
                .as_array()
                .iter()
                .enumerate()
                .map(|(i, &k)| to_u32("element_material", i, k))
                .collect::<PyResult<_>>()?;
            let may_coincide = may_coincide.map(|a| a.as_array().to_vec()).unwrap_or_default();

            let mut constraints = Vec::new();
            if let Some(nodes) = constraint_nodes {
                let nodes = nodes.as_array();
                let c = nodes.len();
                let fixed = constraint_fixed.ok_or_else(|| value_error("constraint_fixed is required"))?;
                let fixed = fixed.as_array();
                let values = constraint_values.ok_or_else(|| value_error("constraint_values is required"))?;
                let values = rows::<2>("constraint_values", &values)?;
                let amp = constraint_amplitude.ok_or_else(|| value_error("constraint_amplitude is required"))?;
                let amp = amp.as_array();
                if fixed.shape() != [c, 2] || values.len() != c || amp.len() != c {
                    return Err(value_error("constraint arrays must have matching lengths"));
                }
                for i in 0..c {
                    constraints.push(Constraint {
                        node: to_u32("constraint_nodes", i, nodes[i])?,
                        fixed: [fixed[[i, 0]], fixed[[i, 1]]],
                        value: values[i],
                        amplitude: amp_index("constraint_amplitude", i, amp[i])?,
                    });
                }
            }
            let mut pressures = Vec::new();
            if let Some(f) = pressure_facets {
                let f = int_rows::<2>("pressure_facets", &f)?;
                let p = pressure_values.ok_or_else(|| value_error("pressure_values is required"))?;
                let p = p.as_array();
                let amp = pressure_amplitude.ok_or_else(|| value_error("pressure_amplitude is required"))?;
                let amp = amp.as_array();
                if p.len() != f.len() || amp.len() != f.len() {
                    return Err(value_error("pressure arrays must have matching lengths"));
                }
                for i in 0..f.len() {
                    pressures.push(PressureLoad {
                        nodes: [to_u32("pressure_facets", i, f[i][0])?, to_u32("pressure_facets", i, f[i][1])?],
                        pressure: p[i],
                        amplitude: amp_index("pressure_amplitude", i, amp[i])?,
                    });
                }
            }
            let contact = match contact_laws {
                None => None,
                Some(laws) => {
                    let laws =
                        rows::<5>("contact_laws", &laws)?
                            .into_iter()
                            .map(|[normal_stiffness, shear_stiffness, friction, cohesion, damping_ratio]| {
                                InterfaceSpec { normal_stiffness, shear_stiffness, friction, cohesion, damping_ratio }
                            })
                            .collect();
                    let mut facet_laws = Vec::new();
                    if let (Some(f), Some(l)) = (contact_facets, contact_facet_laws) {
                        let f = int_rows::<2>("contact_facets", &f)?;
                        let l = l.as_array();
                        if l.len() != f.len() {
                            return Err(value_error("contact_facets and contact_facet_laws must have equal lengths"));
                        }
                        for i in 0..f.len() {
                            let law = u16::try_from(l[i]).map_err(|_| {
                                value_error(format!("contact_facet_laws[{i}] = {} is not a law index", l[i]))
                            })?;
                            facet_laws.push((
                                [to_u32("contact_facets", i, f[i][0])?, to_u32("contact_facets", i, f[i][1])?],
                                law,
                            ));
                        }
                    }
                    Some(ContactSpec { laws, facet_laws, crack_law, margin: contact_margin })
                }
            };
            let spec = ModelSpec {
                points,
                triangles,
                may_coincide,
                materials,
                element_material,
                gravity: [gravity.0, gravity.1],
                constraints,
                pressures,
                amplitudes: amplitudes.into_iter().map(|(times, values)| Amplitude { times, values }).collect(),
                initial_velocity: initial_velocity.map(|a| rows::<2>("initial_velocity", &a)).transpose()?,
                initial_stress: initial_stress.map(|a| rows::<4>("initial_stress", &a)).transpose()?,
                contact,
                fracture: (fracture_interval > 0).then(|| FractureSpec {
                    params: FractureParams {
                        edge_tolerance: fracture_edge_tolerance.to_radians(),
                        crack_tolerance: fracture_crack_tolerance.to_radians(),
                        min_quality: fracture_min_quality,
                        min_altitude: fracture_min_altitude,
                    },
                    interval: fracture_interval,
                    insert_at: fracture_insert_at,
                }),
                stages: {
                    if stage_times.len() != stage_elements.len()
                        || !(stage_ramps.is_empty() || stage_ramps.len() == stage_times.len())
                    {
                        return Err(value_error(
                            "stage_times, stage_elements and stage_ramps (if given) must have the same length",
                        ));
                    }
                    let mut stages = Vec::with_capacity(stage_times.len());
                    for (k, (&time, ids)) in stage_times.iter().zip(&stage_elements).enumerate() {
                        let name = format!("excavation stage {k}");
                        let elements = ids
                            .as_array()
                            .iter()
                            .enumerate()
                            .map(|(i, &e)| to_u32(&name, i, e))
                            .collect::<PyResult<Vec<u32>>>()?;
                        let ramp = stage_ramps.get(k).copied().unwrap_or(0.0);
                        stages.push(ExcavationStage { time, elements, ramp });
                    }
                    stages
                },
                settings: Settings {
                    mass_damping,
                    stiffness_damping,
                    safety,
                    fixed_dt,
                    dt_interval,
                    energy_growth,
                    mass_scaling,
                    renumber,
                    renumber_every,
                    local_damping,
                },
            };
            let sim = fdem_solver::Simulation::new(spec, threads).map_err(|e| value_error(e.to_string()))?;
            Ok(PySimulation { sim, poisoned: false })
        })
    }

    /// Advances until `time >= until` or `max_steps` steps, with the GIL
    /// released; checks for Ctrl-C about every 50 ms (at a step boundary).
    /// Returns the number of steps taken.
    #[pyo3(signature = (until, max_steps=u64::MAX))]
    fn advance(&mut self, py: Python<'_>, until: f64, max_steps: u64) -> PyResult<u64> {
        self.ok()?;
        let mut taken = 0u64;
        let mut chunk = 1u64;
        while self.sim.time() < until && taken < max_steps {
            let n = chunk.min(max_steps - taken);
            let sim = &mut self.sim;
            let start = Instant::now();
            let result = py.detach(|| catch_unwind(AssertUnwindSafe(|| sim.advance(until, n))));
            let elapsed = start.elapsed();
            match result {
                Ok(Ok(k)) => taken += k,
                Ok(Err(e)) => return Err(run_error(py, e)),
                Err(_) => {
                    self.poisoned = true;
                    return Err(PyRuntimeError::new_err(
                        "internal error in the fdem kernel during a step (please report this)",
                    ));
                }
            }
            py.check_signals()?;
            // aim for about 50 ms between signal checks
            if elapsed < Duration::from_millis(25) {
                chunk = (chunk * 2).min(1 << 20);
            } else if elapsed > Duration::from_millis(100) && chunk > 1 {
                chunk /= 2;
            }
        }
        Ok(taken)
    }

    /// Advances exactly `steps` steps (GIL released).
    fn step(&mut self, py: Python<'_>, steps: u64) -> PyResult<()> {
        self.ok()?;
        let start = self.sim.steps();
        self.advance(py, f64::INFINITY, steps)?;
        debug_assert_eq!(self.sim.steps(), start + steps);
        Ok(())
    }

    /// The complete state as checkpoint bytes, with the caller's `user`
    /// block (see `fdem_solver::Simulation::checkpoint_bytes`).
    fn checkpoint_bytes<'py>(&self, py: Python<'py>, user: &[u8]) -> PyResult<Bound<'py, PyBytes>> {
        guard(|| {
            self.ok()?;
            Ok(PyBytes::new(py, &self.sim.checkpoint_bytes(user)))
        })
    }

    /// Writes a checkpoint file atomically (temporary file, flush, rename).
    fn write_checkpoint(&self, py: Python<'_>, path: std::path::PathBuf, user: &[u8]) -> PyResult<()> {
        guard(|| {
            self.ok()?;
            let sim = &self.sim;
            py.detach(|| sim.write_checkpoint(&path, user))
                .map_err(|e| checkpoint_error(py, &path.display().to_string(), e))
        })
    }

    /// A simulation rebuilt from checkpoint bytes on `threads` threads (0:
    /// all cores), and the caller's block.
    #[staticmethod]
    fn from_checkpoint_bytes<'py>(
        py: Python<'py>,
        data: &[u8],
        threads: usize,
    ) -> PyResult<(PySimulation, Bound<'py, PyBytes>)> {
        guard(|| {
            let (sim, user) = fdem_solver::Simulation::from_checkpoint_bytes(data, threads)
                .map_err(|e| checkpoint_error(py, "checkpoint data", e))?;
            Ok((PySimulation { sim, poisoned: false }, PyBytes::new(py, &user)))
        })
    }

    /// A simulation read from a checkpoint file, and the caller's block.
    #[staticmethod]
    fn read_checkpoint<'py>(
        py: Python<'py>,
        path: std::path::PathBuf,
        threads: usize,
    ) -> PyResult<(PySimulation, Bound<'py, PyBytes>)> {
        guard(|| {
            let (sim, user) = py
                .detach(|| fdem_solver::Simulation::read_checkpoint(&path, threads))
                .map_err(|e| checkpoint_error(py, &path.display().to_string(), e))?;
            Ok((PySimulation { sim, poisoned: false }, PyBytes::new(py, &user)))
        })
    }

    /// Switches the elastic (equilibrium) stage on or off.
    fn set_elastic_stage(&mut self, on: bool) {
        self.sim.set_elastic_stage(on);
    }

    /// Replaces the run settings between stages.
    #[pyo3(signature = (*, mass_damping, stiffness_damping, safety, fixed_dt, dt_interval, energy_growth=0.05, mass_scaling=None, renumber=None, renumber_every=None, local_damping=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn set_settings(
        &mut self,
        mass_damping: f64,
        stiffness_damping: f64,
        safety: f64,
        fixed_dt: Option<f64>,
        dt_interval: u32,
        energy_growth: f64,
        mass_scaling: Option<f64>,
        renumber: Option<f64>,
        renumber_every: Option<u64>,
        local_damping: f64,
    ) -> PyResult<()> {
        guard(|| {
            self.ok()?;
            let s = Settings {
                mass_damping,
                stiffness_damping,
                safety,
                fixed_dt,
                dt_interval,
                energy_growth,
                mass_scaling,
                renumber,
                renumber_every,
                local_damping,
            };
            self.sim.set_settings(s).map_err(|e| value_error(e.to_string()))
        })
    }

    /// Steps between fracture checks, or `None` without fracture.
    #[getter]
    fn fracture_interval(&self) -> Option<u32> {
        self.sim.fracture_interval()
    }

    /// Sets the steps between fracture checks from now on.
    fn set_fracture_interval(&mut self, steps: u32) -> PyResult<()> {
        guard(|| {
            self.ok()?;
            self.sim.set_fracture_interval(steps).map_err(|e| value_error(e.to_string()))
        })
    }

    /// Spatial renumberings so far.
    #[getter]
    fn renumberings(&self) -> u64 {
        self.sim.renumberings()
    }

    /// Renumbers nodes and elements along a Hilbert curve now (ids do not
    /// change).
    fn renumber(&mut self) -> PyResult<()> {
        guard(|| {
            self.ok()?;
            self.sim.renumber_now();
            Ok(())
        })
    }

    /// Removes elements now (excavation), with `descendants` also every
    /// piece cracks have cut from them, their forces on the nodes that
    /// stay released over `ramp` (s; 0: at once); returns how many were
    /// removed.
    #[pyo3(signature = (elements, descendants=true, ramp=0.0))]
    fn deactivate(&mut self, elements: PyReadonlyArray1<'_, i64>, descendants: bool, ramp: f64) -> PyResult<usize> {
        guard(|| {
            self.ok()?;
            let ids: Vec<u32> = elements
                .as_array()
                .iter()
                .enumerate()
                .map(|(i, &e)| to_u32("elements", i, e))
                .collect::<PyResult<_>>()?;
            self.sim.deactivate_gradually(&ids, descendants, ramp).map_err(|e| value_error(e.to_string()))
        })
    }

    /// Every element's parent: the element (id) crack insertion cut it
    /// from, itself for an element of the model.
    fn element_parents<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.sim.element_parents().iter().map(|&p| i64::from(p)).collect::<Vec<_>>().into_pyarray(py)
    }

    /// Every element's origin: the element of the model it descends from.
    fn element_origins<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.sim.element_origins().into_iter().map(i64::from).collect::<Vec<_>>().into_pyarray(py)
    }

    /// Places the pieces of a run restored from a checkpoint without
    /// lineage (format < 7) inside the model's elements (`points`,
    /// `triangles`: the model's mesh); returns how many it placed.
    fn recover_lineage(
        &mut self,
        points: PyReadonlyArray2<'_, f64>,
        triangles: PyReadonlyArray2<'_, i64>,
    ) -> PyResult<usize> {
        guard(|| {
            self.ok()?;
            let points = rows::<2>("points", &points)?;
            let triangles: Vec<[u32; 3]> = int_rows::<3>("triangles", &triangles)?
                .into_iter()
                .enumerate()
                .map(|(e, t)| {
                    let mut out = [0u32; 3];
                    for k in 0..3 {
                        out[k] = to_u32("triangles", 3 * e + k, t[k])?;
                    }
                    Ok(out)
                })
                .collect::<PyResult<_>>()?;
            self.sim.recover_lineage(&points, &triangles).map_err(|e| value_error(e.to_string()))
        })
    }

    /// The material index of every element (splits inherit their parent's).
    fn element_materials<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.sim.element_materials().iter().map(|&m| i64::from(m)).collect::<Vec<_>>().into_pyarray(py)
    }

    /// Excavation stages run so far.
    #[getter]
    fn stages_done(&self) -> usize {
        self.sim.stages().1
    }

    /// Restarts the clock at t = 0 from the current state (time, steps,
    /// energy account; stages are timed from the new zero).
    fn restart_clock(&mut self) -> PyResult<()> {
        guard(|| {
            self.ok()?;
            self.sim.restart_clock();
            Ok(())
        })
    }

    /// Fragment of every element (active elements sharing a node belong to
    /// one), numbered from 0 in order of first element; -1 for removed ones.
    fn fragment_labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.sim
            .fragment_labels()
            .into_iter()
            .map(|l| if l == u32::MAX { -1 } else { i64::from(l) })
            .collect::<Vec<_>>()
            .into_pyarray(py)
    }

    /// Changes the values of existing prescribed velocities (m/s).
    fn set_prescribed_velocity(
        &mut self,
        nodes: PyReadonlyArray1<'_, i64>,
        values: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        guard(|| {
            self.ok()?;
            let values = rows::<2>("values", &values)?;
            let nodes: Vec<u32> =
                nodes.as_array().iter().enumerate().map(|(i, &n)| to_u32("nodes", i, n)).collect::<PyResult<_>>()?;
            if nodes.len() != values.len() {
                return Err(value_error("nodes and values must have the same length"));
            }
            self.sim.set_prescribed_velocity(&nodes, &values).map_err(|e| value_error(e.to_string()))
        })
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> u64 {
        self.sim.steps()
    }

    /// The step size in use (s).
    #[getter]
    fn time_step(&self) -> f64 {
        self.sim.time_step()
    }

    /// The mesh's critical step `min_e 2/ω_e` before the safety factor (s).
    #[getter]
    fn critical_time_step(&self) -> f64 {
        self.sim.critical_time_step()
    }

    /// Worker threads.
    #[getter]
    fn threads(&self) -> usize {
        self.sim.threads()
    }

    /// Number of nodes.
    #[getter]
    fn n_nodes(&self) -> usize {
        self.sim.n_nodes()
    }

    /// Number of elements.
    #[getter]
    fn n_elements(&self) -> usize {
        self.sim.n_elements()
    }

    /// Current node coordinates, shape (n_nodes, 2), a copy (m).
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vec2_array(py, &self.sim.positions())
    }

    /// Reference node coordinates, shape (n_nodes, 2), a copy (m).
    fn reference_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vec2_array(py, &self.sim.reference_positions())
    }

    /// Whole-step velocities, shape (n_nodes, 2), a copy (m/s).
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| Ok(vec2_array(py, &self.sim.velocities())))
    }

    /// The model node each node descends from, shape (n_nodes,), int64.
    fn node_origins<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = self.sim.node_origins().into_iter().map(i64::from).collect();
        v.into_pyarray(py)
    }

    /// Reaction forces, shape (n_nodes, 2), a copy (N per unit thickness):
    /// the force each node's support exerts on the model at the current
    /// whole step, zero for free nodes and components.
    fn reaction_forces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| Ok(vec2_array(py, &self.sim.reaction_forces())))
    }

    /// Cauchy stress per element `[xx, yy, zz, xy]`, shape (n_elements, 4) (Pa).
    fn stress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| Ok(vec4_array(py, &self.sim.stress())))
    }

    /// Connectivity, shape (n_elements, 3), int64, a copy.
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let t = self.sim.triangles();
        let flat: Vec<i64> = t.iter().flatten().map(|&v| v as i64).collect();
        Array2::from_shape_vec((t.len(), 3), flat).expect("shape").into_pyarray(py)
    }

    /// Lumped nodal masses (kg per unit thickness), a copy.
    fn masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.sim.masses().to_vec().into_pyarray(py)
    }

    /// Every element's mass-scaling density factor (1: physical), a copy.
    fn mass_scale<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.sim.mass_scale().to_vec().into_pyarray(py)
    }

    /// Mass added by mass scaling to the active elements (kg per unit
    /// thickness).
    fn added_mass(&self) -> f64 {
        self.sim.added_mass()
    }

    /// Current element areas (m²).
    fn areas<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.sim.areas().into_pyarray(py)
    }

    /// Whether each element is active.
    fn active<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        self.sim.active().to_vec().into_pyarray(py)
    }

    /// Contact-search counters: `pairs_evaluated`, `broad_phase_builds`,
    /// `candidate_pairs`, `contacts`.
    fn contact_stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.sim.contact_stats();
        let d = PyDict::new(py);
        d.set_item("pairs_evaluated", c.pairs_evaluated)?;
        d.set_item("broad_phase_builds", c.broad_phase_builds)?;
        d.set_item("candidate_pairs", c.candidate_pairs)?;
        d.set_item("contacts", c.contacts)?;
        Ok(d)
    }

    /// Cracks inserted so far (nodes opened); `None` without fracture.
    #[getter]
    fn insertions(&self) -> Option<u64> {
        self.sim.insertions()
    }

    /// The largest relative change of total mass (`mass`) and of linear
    /// momentum over Σ m|v| (`momentum`) that any crack insertion has caused
    /// so far; `None` without fracture.
    fn insertion_audit<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.sim
            .insertion_audit()
            .map(|a| {
                let d = PyDict::new(py);
                d.set_item("mass", a.mass)?;
                d.set_item("momentum", a.momentum)?;
                Ok(d)
            })
            .transpose()
    }

    /// The intact cohesive bonds across cracks inserted before full softening:
    /// `nodes` (k, 2) int64, `length` (m), `strength` t₀ (Pa),
    /// `final_opening` δ_c = 2 G_I / t₀ (m; where the traction ends in pure
    /// opening on a straight envelope), `max_opening` (m), `damage` (0–1), `offset`
    /// (k, 2) (m, the opening with which each bond took over the force
    /// through its node when its crack was inserted), `normal` (k, 2) (the
    /// crack normal of a mixed-mode bond, zero for the isotropic bonds of
    /// an older checkpoint), as a dict of arrays.
    fn bonds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        guard(|| {
            let b = self.sim.bonds();
            let d = PyDict::new(py);
            let nodes: Vec<i64> = b.iter().flat_map(|b| b.nodes.map(i64::from)).collect();
            d.set_item("nodes", Array2::from_shape_vec((b.len(), 2), nodes).expect("shape").into_pyarray(py))?;
            let col = |f: &dyn Fn(&Bond) -> f64| b.iter().map(f).collect::<Vec<_>>().into_pyarray(py);
            d.set_item("length", col(&|b| b.length))?;
            d.set_item("strength", col(&|b| b.strength))?;
            d.set_item("final_opening", col(&|b| b.final_opening))?;
            d.set_item("max_opening", col(&|b| b.max_opening))?;
            d.set_item("damage", col(&|b| b.damage()))?;
            let offsets: Vec<f64> = b.iter().flat_map(|b| b.offset).collect();
            d.set_item("offset", Array2::from_shape_vec((b.len(), 2), offsets).expect("shape").into_pyarray(py))?;
            // the crack normal of a mixed-mode bond; zero for an isotropic one
            let normals: Vec<f64> = b.iter().flat_map(|b| b.mode.map_or([0.0; 2], |m| m.normal)).collect();
            d.set_item("normal", Array2::from_shape_vec((b.len(), 2), normals).expect("shape").into_pyarray(py))?;
            Ok(d)
        })
    }

    /// Wall-clock seconds spent so far in each phase of the step, each
    /// counted once: `nodes`, `elements`, `broad_phase`, `surface` (narrow
    /// phase, assembly, pressure, bonds), `time_step`, `fracture` (checks and
    /// planning), `topology` (applying insertions: rebuilds, forces and the
    /// stable step of the new mesh).
    fn phase_times<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = self.sim.phase_times();
        let d = PyDict::new(py);
        d.set_item("nodes", t.nodes)?;
        d.set_item("elements", t.elements)?;
        d.set_item("broad_phase", t.broad_phase)?;
        d.set_item("surface", t.surface)?;
        d.set_item("time_step", t.time_step)?;
        d.set_item("fracture", t.fracture)?;
        d.set_item("topology", t.topology)?;
        Ok(d)
    }

    /// The active contacts as a dict of arrays: `node`, `facet` (n, 2), `xi`,
    /// `gap` (m), `normal_force`, `tangential_force` (N/m), `slipping`.
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        guard(|| {
            let c = self.sim.contacts();
            let d = PyDict::new(py);
            d.set_item("node", c.iter().map(|t| t.node as i64).collect::<Vec<_>>().into_pyarray(py))?;
            let facets: Vec<i64> = c.iter().flat_map(|t| [t.facet[0] as i64, t.facet[1] as i64]).collect();
            d.set_item("facet", Array2::from_shape_vec((c.len(), 2), facets).expect("shape").into_pyarray(py))?;
            d.set_item("xi", c.iter().map(|t| t.xi).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("gap", c.iter().map(|t| t.gap).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("normal_force", c.iter().map(|t| t.normal_force).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("tangential_force", c.iter().map(|t| t.tangential_force).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("slipping", c.iter().map(|t| t.slipping).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("offset", c.iter().map(|t| t.offset).collect::<Vec<_>>().into_pyarray(py))?;
            Ok(d)
        })
    }

    /// The free-surface facets (n, 2), oriented with the body on the left,
    /// and the interface law of each.
    fn surface_facets<'py>(&self, py: Python<'py>) -> (Bound<'py, PyArray2<i64>>, Bound<'py, PyArray1<i64>>) {
        let f = self.sim.surface_facets();
        let nodes: Vec<i64> = f.iter().flat_map(|(n, _)| [n[0] as i64, n[1] as i64]).collect();
        (
            Array2::from_shape_vec((f.len(), 2), nodes).expect("shape").into_pyarray(py),
            f.iter().map(|(_, l)| *l as i64).collect::<Vec<_>>().into_pyarray(py),
        )
    }

    /// Per-element material state as a dict of arrays: `kappa` (fracturing
    /// strain), `crack_band` (m), `failure_factor`, `crack_direction` (rad,
    /// current frame), `plastic_strain` (n, 4, current frame),
    /// `equivalent_plastic_strain`.
    fn element_state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        guard(|| {
            let st = self.sim.plastic_states();
            let d = PyDict::new(py);
            d.set_item("kappa", st.iter().map(|s| s.kappa).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("crack_band", st.iter().map(|s| s.crack_band).collect::<Vec<_>>().into_pyarray(py))?;
            d.set_item("failure_factor", self.sim.failure_factors().into_pyarray(py))?;
            d.set_item("crack_direction", self.sim.crack_directions().into_pyarray(py))?;
            d.set_item("plastic_strain", vec4_array(py, &self.sim.plastic_strain()))?;
            d.set_item(
                "equivalent_plastic_strain",
                st.iter().map(|s| s.equivalent_plastic_strain).collect::<Vec<_>>().into_pyarray(py),
            )?;
            Ok(d)
        })
    }

    /// The energy account (J per unit thickness) as a dict.
    fn energies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        guard(|| {
            let e = self.sim.energies();
            let d = PyDict::new(py);
            d.set_item("kinetic", e.kinetic)?;
            d.set_item("elastic", e.elastic)?;
            d.set_item("kinetic_initial", e.kinetic_initial)?;
            d.set_item("elastic_initial", e.elastic_initial)?;
            d.set_item("external_work", e.external_work)?;
            d.set_item("support_work", e.support_work)?;
            d.set_item("mass_damping", e.mass_damping)?;
            d.set_item("viscous_damping", e.viscous_damping)?;
            d.set_item("plastic", e.plastic)?;
            d.set_item("fracture", e.fracture)?;
            d.set_item("internal_work", e.internal_work)?;
            d.set_item("friction", e.friction)?;
            d.set_item("contact_damping", e.contact_damping)?;
            d.set_item("contact_elastic", e.contact_elastic)?;
            d.set_item("contact_work", e.contact_work)?;
            d.set_item("remeshing", e.remeshing)?;
            d.set_item("resurfacing", e.resurfacing)?;
            d.set_item("cohesive_elastic", e.cohesive_elastic)?;
            d.set_item("excavated", e.excavated)?;
            d.set_item("mass_scaling", e.mass_scaling)?;
            d.set_item("residual", e.residual())?;
            d.set_item("largest_term", e.largest_term())?;
            Ok(d)
        })
    }
}
