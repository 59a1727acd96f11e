//! Building a [`Simulation`] from a [`ModelSpec`]: every input checked, each
//! problem reported with the entity it concerns.

use std::collections::BTreeMap;
use std::sync::Arc;

use fdem_element::kinematics::{reference_inverse, signed_area};
use fdem_element::lumped_mass;
use fdem_material::{Elastic, PlasticState};
use fdem_mesh::{node_elements, validate};

use crate::clock::Clock;
use crate::contact::{ContactModel, NodeForces};
use crate::energy::EnergyLedger;
use crate::error::SetupError;
use crate::excavation::Staging;
use crate::loads::{Constraint, Loads};
use crate::model::{LawSpec, ModelSpec};
use crate::passes::{self, Material, NO_BC};
use crate::simulation::{check_settings, invalid, Elements, Nodes, Simulation};
use crate::stable_step::Frequencies;
use crate::topology::{ancestor_pair, build_surface, resolve_pressures};

impl Simulation {
    /// Builds a simulation from a model description on `threads` worker
    /// threads (0: as many as the machine has). Every input is checked and a
    /// problem is reported with the entity it concerns.
    pub fn new(spec: ModelSpec, threads: usize) -> Result<Self, SetupError> {
        let n = spec.points.len();
        let m = spec.triangles.len();
        if m == 0 {
            return invalid("the mesh has no elements".into());
        }
        if !spec.may_coincide.is_empty() && spec.may_coincide.len() != n {
            return invalid(format!("may_coincide has {} entries for {n} nodes", spec.may_coincide.len()));
        }
        validate(&spec.points, &spec.triangles, &spec.may_coincide)?;
        let conn: Vec<[u32; 3]> = spec.triangles.iter().map(|t| t.map(|v| v as u32)).collect();

        let mut materials = Vec::with_capacity(spec.materials.len());
        for (index, ms) in spec.materials.iter().enumerate() {
            let elastic = Elastic::new(ms.young, ms.poisson).map_err(|error| SetupError::Material { index, error })?;
            let plastic = ms.law.plastic(elastic).map_err(|error| SetupError::Material { index, error })?;
            if !(ms.density > 0.0 && ms.density.is_finite()) {
                let error = fdem_material::ParameterError {
                    parameter: "rho",
                    value: ms.density,
                    requirement: "density must be positive".into(),
                };
                return Err(SetupError::Material { index, error });
            }
            let shear_fracture_energy = match ms.law {
                LawSpec::MohrCoulombRankine { shear_fracture_energy: g, .. } => {
                    if !(g > 0.0 && g.is_finite()) {
                        let error = fdem_material::ParameterError {
                            parameter: "GII",
                            value: g,
                            requirement: "mode-II fracture energy must be positive".into(),
                        };
                        return Err(SetupError::Material { index, error });
                    }
                    g
                }
                LawSpec::Elastic => 0.0,
            };
            materials.push(Material { density: ms.density, elastic, plastic, shear_fracture_energy });
        }
        if spec.element_material.len() != m {
            return invalid(format!("element_material has {} entries for {m} elements", spec.element_material.len()));
        }
        if let Some(e) = spec.element_material.iter().position(|&k| k as usize >= materials.len()) {
            return invalid(format!(
                "element {e} uses material {}, but only {} materials are defined",
                spec.element_material[e],
                materials.len()
            ));
        }
        check_settings(&spec.settings)?;
        if !spec.gravity.iter().all(|g| g.is_finite()) {
            return invalid("gravity must be finite".into());
        }

        let mut reference = Vec::with_capacity(m);
        let mut mass = vec![0.0; n];
        for (e, t) in conn.iter().enumerate() {
            let x = [spec.points[t[0] as usize], spec.points[t[1] as usize], spec.points[t[2] as usize]];
            let shape = reference_inverse(&x).ok_or_else(|| {
                SetupError::Invalid(format!("element {e} has no positive area in the reference configuration"))
            })?;
            if let Some(law) = &materials[spec.element_material[e] as usize].plastic {
                let g = passes::reference_geometry(&shape);
                let size = law.largest_band_width(&g);
                let limit = law.snap_back_size();
                if size > limit {
                    return invalid(format!(
                        "element {e} is {size:.4} m across, larger than the snap-back limit E' w_c / (ft max|s'|) = {limit:.4} m (2 E' Gf / ft^2 for linear softening) \
                         of its material {}: refine the mesh there or raise Gf",
                        spec.element_material[e]
                    ));
                }
            }
            reference.push(shape);
            let nodal = lumped_mass(materials[spec.element_material[e] as usize].density, signed_area(&x));
            for &v in t {
                mass[v as usize] += nodal;
            }
        }

        for (k, a) in spec.amplitudes.iter().enumerate() {
            a.check(k).map_err(SetupError::Invalid)?;
        }
        let n_amp = spec.amplitudes.len();
        let check_amp = |amp: Option<u32>, what: String| match amp {
            Some(k) if k as usize >= n_amp => {
                invalid(format!("{what} refers to amplitude {k}, but only {n_amp} are defined"))
            }
            _ => Ok(()),
        };

        // One constraint per node: merge the components of repeated entries.
        let mut merged: BTreeMap<u32, Constraint> = BTreeMap::new();
        for c in &spec.constraints {
            if c.node as usize >= n {
                return invalid(format!("a support refers to node {}, but the mesh has {n} nodes", c.node));
            }
            if !c.value.iter().all(|v| v.is_finite()) {
                return invalid(format!("prescribed velocity of node {} is not finite", c.node));
            }
            check_amp(c.amplitude, format!("the support of node {}", c.node))?;
            let entry = merged.entry(c.node).or_insert(Constraint { fixed: [false; 2], ..*c });
            for d in 0..2 {
                if c.fixed[d] {
                    if entry.fixed[d] && (entry.value[d] != c.value[d] || entry.amplitude != c.amplitude) {
                        return invalid(format!(
                            "node {} has two different prescribed velocities in direction {}",
                            c.node,
                            ["x", "y"][d]
                        ));
                    }
                    if entry.fixed[1 - d] && entry.amplitude != c.amplitude {
                        return invalid(format!(
                            "node {}: prescribed x and y velocities must share one amplitude",
                            c.node
                        ));
                    }
                    entry.fixed[d] = true;
                    entry.value[d] = c.value[d];
                    entry.amplitude = c.amplitude;
                }
            }
        }
        let constraints: Vec<Constraint> = merged.into_values().collect();
        let mut bc = vec![NO_BC; n];
        for (k, c) in constraints.iter().enumerate() {
            bc[c.node as usize] = k as u32;
        }

        for p in &spec.pressures {
            if !p.pressure.is_finite() {
                return invalid(format!("pressure on facet ({}, {}) is not finite", p.nodes[0], p.nodes[1]));
            }
            check_amp(p.amplitude, format!("the pressure on facet ({}, {})", p.nodes[0], p.nodes[1]))?;
        }
        let mut contact = spec.contact.as_ref().map(|c| ContactModel::new(c, n)).transpose()?;
        let fracture = match spec.fracture {
            None => None,
            Some(crate::model::FractureSpec { params, interval, insert_at }) => {
                if contact.is_none() {
                    return invalid("fracture needs contact (the crack faces are contact surfaces)".into());
                }
                crate::fracture::check_interval(interval)?;
                let ok = |v: f64, lo: f64, hi: f64| v.is_finite() && v >= lo && v <= hi;
                let in_range = ok(params.edge_tolerance, 0.0, std::f64::consts::FRAC_PI_4)
                    && ok(params.crack_tolerance, 0.0, std::f64::consts::FRAC_PI_2)
                    && ok(params.min_quality, 0.0, 0.9)
                    && ok(params.min_altitude, 0.0, f64::MAX)
                    && insert_at > 0.0
                    && insert_at <= 1.0;
                if !in_range {
                    return invalid(format!(
                        "fracture parameters out of range: edge_tolerance in [0, 45] deg, crack_tolerance in [0, 90] \
                         deg, min_quality in [0, 0.9], min_altitude ≥ 0 m, insert_at in (0, 1] (got {params:?}, insert_at {insert_at})"
                    ));
                }
                Some(crate::fracture::FractureModel::new(params, interval, insert_at))
            }
        };
        let mut stages = spec.stages.clone();
        for (k, st) in stages.iter().enumerate() {
            if !st.time.is_finite() {
                return invalid(format!("excavation stage {k}: time {} is not finite", st.time));
            }
            if !(st.ramp >= 0.0 && st.ramp.is_finite()) {
                return invalid(format!("excavation stage {k}: release time {} must be finite and >= 0", st.ramp));
            }
            if let Some(&e) = st.elements.iter().find(|&&e| e as usize >= m) {
                return invalid(format!("excavation stage {k}: element {e} does not exist (the model has {m})"));
            }
        }
        stages.sort_by(|a, b| a.time.total_cmp(&b.time));
        let active = vec![true; m];
        let ancestor: Vec<u32> = (0..n as u32).collect();
        let incidence = node_elements(n, &conn);
        let surface = build_surface(&conn, &active, &incidence, &spec.points, None, None, |a, b| {
            contact.as_ref().map_or(0, |c| c.law_of(ancestor_pair(&ancestor, a, b)))
        });
        let pressure = resolve_pressures(&surface, &spec.pressures, &ancestor, true).map_err(SetupError::Invalid)?;
        if let Some(c) = &mut contact {
            c.adopt(None, &surface, &[], &[], None);
        }

        let mut v = vec![[0.0; 2]; n];
        if let Some(v0) = &spec.initial_velocity {
            if v0.len() != n {
                return invalid(format!("initial velocity has {} rows for {n} nodes", v0.len()));
            }
            if let Some(i) = v0.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
                return invalid(format!("initial velocity of node {i} is not finite"));
            }
            v.copy_from_slice(v0);
        }
        let mut stress = vec![[0.0; 4]; m];
        if let Some(s0) = &spec.initial_stress {
            if s0.len() != m {
                return invalid(format!("initial stress has {} rows for {m} elements", s0.len()));
            }
            if let Some(e) = s0.iter().position(|s| !s.iter().all(|c| c.is_finite())) {
                return invalid(format!("initial stress of element {e} is not finite"));
            }
            stress.copy_from_slice(s0);
        }

        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| SetupError::Invalid(format!("cannot start {threads} threads: {e}")))?;
        let node_elems = incidence;
        let nb = surface.nodes.len();
        let mut sim = Simulation {
            nodes: Nodes { x0: spec.points.clone(), x: spec.points, v, mass, bc },
            elems: Elements {
                conn,
                reference,
                material: spec.element_material,
                active,
                stress,
                mass_scale: vec![1.0; m],
                state: vec![PlasticState::default(); m],
                parent: (0..m as u32).collect(),
                force: vec![[0.0; 2]; 3 * m],
            },
            materials,
            node_elems,
            loads: Loads {
                constraints,
                amplitude_values: vec![1.0; spec.amplitudes.len()],
                amplitudes: spec.amplitudes,
                pressure_loads: spec.pressures,
                pressure,
                pressure_force: vec![[0.0; 2]; nb],
                gravity: spec.gravity,
                released: Vec::new(),
                release_force: Vec::new(),
            },
            ancestor,
            node_forces: NodeForces {
                contact_force: if contact.is_some() { vec![[0.0; 2]; nb] } else { Vec::new() },
                contact_damping_force: if contact.is_some() { vec![[0.0; 2]; nb] } else { Vec::new() },
                contact_damped: if contact.is_some() { vec![0; nb] } else { Vec::new() },
                ..Default::default()
            },
            surface,
            contact,
            fracture,
            staging: Staging { stages, next_stage: 0, elastic_stage: false },
            diagnostics: Default::default(),
            frequencies: Frequencies { omega: vec![0.0; m], ..Default::default() },
            settings: spec.settings,
            clock: Clock::default(),
            ledger: EnergyLedger::new(n, m),
            layout: crate::renumber::Layout::new(m),
            pool: Arc::new(pool),
        };
        let pool = Arc::clone(&sim.pool);
        pool.install(|| {
            sim.apply_prescribed_initial_velocity();
            sim.refresh_forces();
            sim.update_time_step();
        });
        sim.ledger.account.elastic_initial = sim.elastic_energy();
        sim.ledger.account.kinetic_initial = sim.kinetic_energy();
        Ok(sim)
    }
}
