//! The parallel passes of one step. Each works on fixed chunks of
//! [`CHUNK`](crate::CHUNK) entities and writes one partial per chunk.

use fdem_element::batch::{corotational_frames, TriLanes, LANES};
use fdem_element::kinematics::{deformation_gradient, polar_rotation, ReferenceShape};
use fdem_element::stability::max_frequency_deformed;
use fdem_element::tensor::rotate;
use fdem_element::{internal_forces, Vec2};
use fdem_material::{Elastic, Geometry, MohrCoulombRankine, PlasticState};
use fdem_mesh::Csr;
use rayon::prelude::*;

use crate::energy::{ElementPartial, NodePartial};
use crate::loads::Constraint;
use crate::{CHUNK, NONE};

/// Marks a node without constraint in `Nodes::bc`.
pub(crate) const NO_BC: u32 = NONE;

/// A material as the element pass uses it.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Material {
    pub density: f64,
    pub elastic: Elastic,
    pub plastic: Option<MohrCoulombRankine>,
    /// Mode-II fracture energy `G_II` (J/m²) of the bonds across its
    /// young cracks (0 for an elastic material). Checkpoints keep it
    /// beside the materials (format 9).
    #[serde(skip)]
    pub shear_fracture_energy: f64,
}

/// The reference edge vectors of an element (its shape in the co-rotational
/// frame) from its stored `Dm⁻¹`.
#[inline]
pub(crate) fn reference_geometry(reference: &ReferenceShape) -> Geometry {
    let m = reference.dm_inv;
    let r = 1.0 / (m[0] * m[3] - m[1] * m[2]);
    // Dm = (Dm⁻¹)⁻¹; its columns are X1 − X0 and X2 − X0
    Geometry { e1: [m[3] * r, -m[2] * r], e2: [-m[1] * r, m[0] * r] }
}

/// Read-only inputs of the node pass.
pub(crate) struct NodeInputs<'a> {
    pub mass: &'a [f64],
    /// Index of each node among the boundary nodes, or `NONE`.
    pub bnode: &'a [u32],
    /// Surface-load (pressure) forces per boundary node (N).
    pub pressure: &'a [Vec2],
    /// Contact forces per boundary node (N), or empty without contact.
    pub contact: &'a [Vec2],
    /// The contact-dashpot parts of `contact` (N).
    pub contact_damping: &'a [Vec2],
    pub bc: &'a [u32],
    pub node_elems: &'a Csr,
    pub elem_force: &'a [Vec2],
    pub constraints: &'a [Constraint],
    pub amplitude_values: &'a [f64],
    pub gravity: Vec2,
    pub alpha: f64,
    /// Local damping coefficient `α_L` ([`Settings::local_damping`](crate::Settings)).
    pub local: f64,
    /// Loads of gradual excavations per node (N), or empty.
    pub release: &'a [Vec2],
    /// Step of the velocity update, `(Δt^{n−½} + Δt^{n+½}) / 2` (s).
    pub dt_avg: f64,
    /// Step of the position update, `Δt^{n+½}` (s).
    pub dt: f64,
    /// Previous position step `Δt^{n−½}` (s).
    pub dt_prev: f64,
}

/// Node pass: `v^{n+½}` and `x^{n+1}` from the forces at `xⁿ`.
///
/// Modified central difference with mass damping α (DESIGN §4.2):
/// `v^{n+½} = [(1 − αΔt/2) v^{n−½} + Δt f/m] / (1 + αΔt/2)`.
///
/// With `damped` non-empty (per boundary node: a contact dashpot acts on
/// it) this is the first of two stages: a damped node is not moved; its
/// velocity without its dashpot forces (the prediction, held components at
/// their prescribed values) goes into `pred_v` and that net force into
/// `pred_f` (both by node, as long as `x`), from which the contact's
/// dashpot forces are worked out (`fdem_contact::narrow::dashpot_forces`)
/// before [`node_pass_damped`] finishes those nodes.
pub(crate) fn node_pass(
    inp: &NodeInputs<'_>,
    x: &mut [Vec2],
    v: &mut [Vec2],
    partials: &mut [NodePartial],
    damped: &[u16],
    pred_v: &mut [Vec2],
    pred_f: &mut [Vec2],
) {
    let split = !damped.is_empty();
    let (keep, scale) = inp.damping_factors();
    x.par_chunks_mut(CHUNK)
        .zip(v.par_chunks_mut(CHUNK))
        .zip(partials.par_iter_mut())
        .zip(pred_v.par_chunks_mut(CHUNK).zip(pred_f.par_chunks_mut(CHUNK)))
        .enumerate()
        .for_each(|(c, (((xc, vc), part), (pvc, pfc)))| {
            let mut acc = NodePartial::default();
            let base = c * CHUNK;
            for j in 0..xc.len() {
                let i = base + j;
                let m = inp.mass[i];
                if m <= 0.0 {
                    continue;
                }
                let bn = inp.bnode[i];
                let (f_ext, fc, fd) = inp.surface_terms(i, m);
                let mut f = [f_ext[0] + fc[0], f_ext[1] + fc[1]];
                for &item in inp.node_elems.row(i) {
                    let fe = inp.elem_force[item as usize];
                    f[0] -= fe[0];
                    f[1] -= fe[1];
                }
                if split && bn != NONE && damped[bn as usize] > 0 {
                    // the prediction: every force but the dashpots' estimate
                    let f = [f[0] - fd[0], f[1] - fd[1]];
                    let r = inp.dt_avg / m;
                    let v_old = vc[j];
                    let mut vp = [(keep * v_old[0] + r * f[0]) * scale, (keep * v_old[1] + r * f[1]) * scale];
                    inp.hold(i, &mut vp);
                    pvc[j] = vp;
                    pfc[j] = f;
                    continue;
                }
                advance(inp, (keep, scale), i, m, [f, f_ext, fc, fd], &mut xc[j], &mut vc[j], &mut acc);
            }
            *part = acc;
        });
}

/// The second stage of [`node_pass`] with dashpots: every damped node
/// (`damped`, per boundary node) moves with its predicted net force
/// `pred_f` (by node) plus its dashpot forces `dashpot` (per boundary node,
/// as applied on the predicted velocities); its terms are added to the
/// partial sums of the first stage.
pub(crate) fn node_pass_damped(
    inp: &NodeInputs<'_>,
    x: &mut [Vec2],
    v: &mut [Vec2],
    partials: &mut [NodePartial],
    damped: &[u16],
    pred_f: &[Vec2],
    dashpot: &[Vec2],
) {
    let factors = inp.damping_factors();
    x.par_chunks_mut(CHUNK).zip(v.par_chunks_mut(CHUNK)).zip(partials.par_iter_mut()).enumerate().for_each(
        |(c, ((xc, vc), part))| {
            let mut acc = NodePartial::default();
            let base = c * CHUNK;
            for j in 0..xc.len() {
                let i = base + j;
                let bn = inp.bnode[i];
                let m = inp.mass[i];
                if bn == NONE || damped[bn as usize] == 0 || m <= 0.0 {
                    continue;
                }
                let (f_ext, fc, fd) = inp.surface_terms(i, m);
                let d = dashpot[bn as usize];
                let p = pred_f[i];
                let f = [p[0] + d[0], p[1] + d[1]];
                // the contact force as applied: the dashpots' estimate
                // replaced by their forces
                let fc = [fc[0] - fd[0] + d[0], fc[1] - fd[1] + d[1]];
                advance(inp, factors, i, m, [f, f_ext, fc, d], &mut xc[j], &mut vc[j], &mut acc);
            }
            part.merge(&acc);
        },
    );
}

impl NodeInputs<'_> {
    /// `(1 − αΔt/2, 1 / (1 + αΔt/2))` of the velocity update.
    fn damping_factors(&self) -> (f64, f64) {
        let a = 0.5 * self.alpha * self.dt_avg;
        (1.0 - a, 1.0 / (1.0 + a))
    }

    /// Node `i`'s (mass `m`) external force (gravity and surface loads),
    /// contact force and that force's dashpot part (N).
    #[inline]
    fn surface_terms(&self, i: usize, m: f64) -> (Vec2, Vec2, Vec2) {
        let bn = self.bnode[i];
        let (fp, fc, fd) = if bn == NONE {
            ([0.0; 2], [0.0; 2], [0.0; 2])
        } else {
            let b = bn as usize;
            let zero = [0.0; 2];
            (
                self.pressure[b],
                self.contact.get(b).copied().unwrap_or(zero),
                self.contact_damping.get(b).copied().unwrap_or(zero),
            )
        };
        let r = self.release.get(i).copied().unwrap_or([0.0; 2]);
        ([m * self.gravity[0] + fp[0] + r[0], m * self.gravity[1] + fp[1] + r[1]], fc, fd)
    }

    /// Sets node `i`'s held velocity components to their prescribed values.
    #[inline]
    fn hold(&self, i: usize, v: &mut Vec2) {
        let b = self.bc[i];
        if b != NO_BC {
            let con = &self.constraints[b as usize];
            let amp = con.amplitude.map_or(1.0, |k| self.amplitude_values[k as usize]);
            for d in 0..2 {
                if con.fixed[d] {
                    v[d] = con.value[d] * amp;
                }
            }
        }
    }
}

/// Moves node `i` (mass `m`) under the net force `f` of which `f_ext` is
/// external, `fc` contact and `fd` that contact force's dashpot part (N,
/// `[f, f_ext, fc, fd]`): its velocity `v` to `v^{n+½}`, its position `x`
/// to `x^{n+1}`, and its work terms, largest speed and any non-finite value
/// into `acc`. `(keep, scale)` are [`NodeInputs::damping_factors`], worked
/// out once per pass.
#[inline]
fn advance(
    inp: &NodeInputs<'_>,
    (keep, scale): (f64, f64),
    i: usize,
    m: f64,
    forces: [Vec2; 4],
    x: &mut Vec2,
    v: &mut Vec2,
    acc: &mut NodePartial,
) {
    let [f, f_ext, fc, fd] = forces;
    let v_old = *v;
    let b = inp.bc[i];
    // local damping: −α_L |f| sign(v^{n−½}) on each free component
    let mut f_local = [0.0; 2];
    if inp.local > 0.0 {
        let held = if b != NO_BC { inp.constraints[b as usize].fixed } else { [false; 2] };
        for d in 0..2 {
            if !held[d] && v_old[d] != 0.0 {
                f_local[d] = -inp.local * f[d].abs() * v_old[d].signum();
            }
        }
    }
    let f = if inp.local > 0.0 { [f[0] + f_local[0], f[1] + f_local[1]] } else { f };
    let r = inp.dt_avg / m;
    let mut v_new = [(keep * v_old[0] + r * f[0]) * scale, (keep * v_old[1] + r * f[1]) * scale];
    let dxc =
        |vn: Vec2| [0.5 * (inp.dt * vn[0] + inp.dt_prev * v_old[0]), 0.5 * (inp.dt * vn[1] + inp.dt_prev * v_old[1])];
    if b != NO_BC {
        inp.hold(i, &mut v_new);
        // reaction R = m a + damping force − f on the held components
        let con = &inp.constraints[b as usize];
        let dx = dxc(v_new);
        for d in 0..2 {
            if con.fixed[d] {
                let damp = inp.alpha * m * 0.5 * (v_old[d] + v_new[d]);
                let reaction = m * (v_new[d] - v_old[d]) / inp.dt_avg + damp - f[d];
                acc.support += reaction * dx[d];
            }
        }
    }
    let dx = dxc(v_new);
    acc.external += f_ext[0] * dx[0] + f_ext[1] * dx[1];
    acc.contact += fc[0] * dx[0] + fc[1] * dx[1];
    acc.contact_damping += fd[0] * dx[0] + fd[1] * dx[1];
    if inp.alpha > 0.0 {
        let vm = [0.5 * (v_old[0] + v_new[0]), 0.5 * (v_old[1] + v_new[1])];
        acc.damping += inp.alpha * m * (vm[0] * dx[0] + vm[1] * dx[1]);
    }
    if inp.local > 0.0 {
        acc.damping -= f_local[0] * dx[0] + f_local[1] * dx[1];
    }
    x[0] += inp.dt * v_new[0];
    x[1] += inp.dt * v_new[1];
    *v = v_new;
    let speed2 = v_new[0] * v_new[0] + v_new[1] * v_new[1];
    // a NaN is kept (`max` would drop it)
    if speed2 > acc.max_speed2 || speed2.is_nan() {
        acc.max_speed2 = speed2;
    }
    if acc.bad_node.is_none() {
        if !(v_new[0].is_finite() && v_new[1].is_finite()) {
            acc.bad_node = Some((i as u32, "velocity"));
        } else if !(x[0].is_finite() && x[1].is_finite()) {
            acc.bad_node = Some((i as u32, "position"));
        }
    }
}

/// Read-only inputs of the element pass.
pub(crate) struct ElementInputs<'a> {
    pub x: &'a [Vec2],
    pub v: &'a [Vec2],
    pub conn: &'a [[u32; 3]],
    pub reference: &'a [ReferenceShape],
    pub material: &'a [u32],
    pub active: &'a [bool],
    pub materials: &'a [Material],
    /// Active elements per node: an element that holds its nodes alone is
    /// a fragment ([`fragment`]).
    pub node_elems: &'a Csr,
    /// Whether crack insertion is on: only then are fragments and bands
    /// opened by their own width elastic (a crack the planner could have
    /// cut); without it the softened band is the crack.
    pub insertion: bool,
    pub beta: f64,
    /// The step just taken, `Δt^{n+½}` (s); zero to only recompute forces.
    pub dt: f64,
    /// Whether plastic laws apply; off in an elastic (equilibrium) stage.
    pub plastic: bool,
}

/// The [`ElementInputs`] of the [`Simulation`](crate::simulation::Simulation)
/// `sim` (its nodes' positions and velocities, its elements' shapes and
/// materials, the node→element lists, whether crack insertion is on,
/// whether plastic laws apply), with stiffness damping `beta` and step
/// `dt`: the one place they are gathered, so that the element pass, the
/// force refreshes and the stable step read the same inputs.
///
/// A macro, not a method: every caller writes the results (stresses,
/// forces, partial sums, frequencies) into other fields of the same
/// `Simulation` while the inputs are borrowed. The macro's expansion
/// borrows field by field, which the borrow checker lets live beside
/// those writes; a method borrows the whole `Simulation`, and would need
/// the written arrays moved out and back at each call (at the element
/// pass also the contact model and its force buffers, which the contact
/// assembly beside it writes).
macro_rules! element_inputs {
    ($sim:ident, beta: $beta:expr, dt: $dt:expr) => {
        $crate::passes::ElementInputs {
            x: &$sim.nodes.x,
            v: &$sim.nodes.v,
            conn: &$sim.elems.conn,
            reference: &$sim.elems.reference,
            material: &$sim.elems.material,
            active: &$sim.elems.active,
            materials: &$sim.materials,
            node_elems: &$sim.node_elems,
            insertion: $sim.fracture.is_some(),
            beta: $beta,
            dt: $dt,
            plastic: !$sim.staging.elastic_stage,
        }
    };
}
pub(crate) use element_inputs;

#[inline(always)]
fn gather<T: Copy>(a: &[T], t: [u32; 3]) -> [T; 3] {
    [a[t[0] as usize], a[t[1] as usize], a[t[2] as usize]]
}

/// Fracturing strain `κ` (−) at which a crack band has opened by its own
/// width (`w = κ h_c`): from there the element is elastic, when crack
/// insertion is on. A crack open
/// that wide should have been inserted; where the planner did not cut the
/// element (stretched triangles in clumps of softened debris), the
/// softened band let its nodes drift apart without bound: 79 elements of
/// the paper-scale caving run stretched 5 to 20 times by 3.5 s
/// (docs/fracture.md, "Fragments of one element").
pub(crate) const OPEN_BAND: f64 = 1.0;

/// Whether the element with nodes `t` is a fragment of its own: a lone
/// triangle, each of whose nodes belongs to it alone. With crack
/// insertion on, such an element is elastic (its plastic law is not
/// applied): it cannot be split any more
/// (a split would leave pieces under the size limit), so softening would
/// only let its nodes drift apart as particles joined by nothing in
/// tension (docs/fracture.md, "Fragments of one element").
#[inline(always)]
pub(crate) fn fragment(node_elems: &Csr, t: [u32; 3]) -> bool {
    let private = |v: u32| node_elems.offsets[v as usize + 1] - node_elems.offsets[v as usize] == 1;
    private(t[0]) && private(t[1]) && private(t[2])
}

/// Element pass: stress update to `σ̂^{n+1}` and internal forces at `x^{n+1}`.
///
/// `force` holds three nodal forces per element (`3e + k`), so that a
/// node→element CSR item indexes it directly.
pub(crate) fn element_pass(
    inp: &ElementInputs<'_>,
    stress: &mut [[f64; 4]],
    state: &mut [PlasticState],
    force: &mut [Vec2],
    partials: &mut [ElementPartial],
) {
    stress
        .par_chunks_mut(CHUNK)
        .zip(state.par_chunks_mut(CHUNK))
        .zip(force.par_chunks_mut(3 * CHUNK))
        .zip(partials.par_iter_mut())
        .enumerate()
        .for_each(|(c, (((sc, stc), fc), part))| {
            let mut acc = ElementPartial::default();
            let base = c * CHUNK;
            for j0 in (0..sc.len()).step_by(LANES) {
                // Lanes past the end of the chunk repeat its last element; their
                // results are discarded.
                let last = sc.len() - 1;
                let lane_elem = |l: usize| base + (j0 + l).min(last);
                let conn: [[u32; 3]; LANES] = std::array::from_fn(|l| inp.conn[lane_elem(l)]);
                let dm_inv = std::array::from_fn(|k| std::array::from_fn(|l| inp.reference[lane_elem(l)].dm_inv[k]));
                let x: TriLanes =
                    std::array::from_fn(|k| std::array::from_fn(|l| inp.x[conn[l][k / 2] as usize][k % 2]));
                let v: TriLanes =
                    std::array::from_fn(|k| std::array::from_fn(|l| inp.v[conn[l][k / 2] as usize][k % 2]));
                let frames = corotational_frames(&dm_inv, &x, &v, inp.dt);
                for l in 0..LANES.min(sc.len() - j0) {
                    let j = j0 + l;
                    let e = base + j;
                    let f_out = &mut fc[3 * j..3 * j + 3];
                    if !inp.active[e] {
                        continue;
                    }
                    if frames.is_inverted(l) {
                        acc.bad_element.get_or_insert(e as u32);
                        f_out.copy_from_slice(&[[0.0; 2]; 3]);
                        continue;
                    }
                    let mat = &inp.materials[inp.material[e] as usize];
                    let dh = frames.d_hat(l);
                    let old = sc[j];
                    let mut new = mat.elastic.trial(old, dh, inp.dt);
                    let half_area = 0.5 * frames.twice_area_mid[l];
                    // debris (with crack insertion on) is elastic; tested
                    // only for plastic laws, so that elastic materials and
                    // the equilibrium stage read no connectivity
                    let plastic = mat.plastic.as_ref().filter(|_| {
                        inp.plastic
                            && !(inp.insertion && (stc[j].kappa >= OPEN_BAND || fragment(inp.node_elems, conn[l])))
                    });
                    if let Some(law) = plastic {
                        let u = law.update(old, new, &mut stc[j], || reference_geometry(&inp.reference[e]));
                        new = u.stress;
                        acc.plastic += half_area * u.plastic_dissipation;
                        acc.fracture += half_area * u.fracture_dissipation;
                    }
                    sc[j] = new;
                    let power =
                        0.5 * ((old[0] + new[0]) * dh[0] + (old[1] + new[1]) * dh[1] + 2.0 * (old[3] + new[3]) * dh[2]);
                    acc.internal += half_area * inp.dt * power;
                    let mut sigma = rotate(new, frames.cos_new[l], frames.sin_new[l]);
                    if inp.beta > 0.0 {
                        let d = frames.d(l);
                        let sv = mat.elastic.viscous(d, inp.beta);
                        acc.viscous += half_area * inp.dt * (sv[0] * d[0] + sv[1] * d[1] + 2.0 * sv[3] * d[2]);
                        for k in 0..4 {
                            sigma[k] += sv[k];
                        }
                    }
                    let xe = [[x[0][l], x[1][l]], [x[2][l], x[3][l]], [x[4][l], x[5][l]]];
                    f_out.copy_from_slice(&internal_forces(&xe, &sigma));
                }
            }
            *part = acc;
        });
}

/// A pressure-loaded facet, resolved: its nodes (body on the left), their
/// boundary-node indices, the pressure (Pa) and its amplitude.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct PressureFacet {
    pub nodes: [u32; 2],
    pub bnodes: [u32; 2],
    pub pressure: f64,
    pub amplitude: Option<u32>,
}

/// Follower pressure forces on the current configuration into `out` (one
/// entry per boundary node, zeroed first). Sequential: the loaded facets are
/// few, and the order stays fixed.
pub(crate) fn pressure_forces(x: &[Vec2], facets: &[PressureFacet], amplitude_values: &[f64], out: &mut [Vec2]) {
    out.iter_mut().for_each(|f| *f = [0.0; 2]);
    for pf in facets {
        let p = pf.pressure * pf.amplitude.map_or(1.0, |k| amplitude_values[k as usize]);
        let (xa, xb) = (x[pf.nodes[0] as usize], x[pf.nodes[1] as usize]);
        // outward normal × length = (dy, −dx); the force pushes inward
        let f = [-0.5 * p * (xb[1] - xa[1]), 0.5 * p * (xb[0] - xa[0])];
        for b in pf.bnodes {
            out[b as usize][0] += f[0];
            out[b as usize][1] += f[1];
        }
    }
}

/// Internal forces of the listed elements at `x` from their stored
/// co-rotational stress (no stress update, no viscous part): what a
/// topology change needs for the elements it created or reshaped; the
/// others keep theirs.
pub(crate) fn element_forces_of(inp: &ElementInputs<'_>, elems: &[u32], stress: &[[f64; 4]], force: &mut [Vec2]) {
    for &e in elems {
        let e = e as usize;
        let out = &mut force[3 * e..3 * e + 3];
        if !inp.active[e] {
            out.copy_from_slice(&[[0.0; 2]; 3]);
            continue;
        }
        let x = gather(inp.x, inp.conn[e]);
        let (c, s) = polar_rotation(deformation_gradient(&inp.reference[e], &x));
        out.copy_from_slice(&internal_forces(&x, &rotate(stress[e], c, s)));
    }
}

/// `ω_e` of the listed elements into `omega` (0 for inactive ones), with
/// their density times their mass-scaling factor `scale`.
pub(crate) fn element_frequencies_of(inp: &ElementInputs<'_>, scale: &[f64], elems: &[u32], omega: &mut [f64]) {
    for &e in elems {
        let e = e as usize;
        omega[e] = if inp.active[e] {
            let mat = &inp.materials[inp.material[e] as usize];
            let rho = mat.density * scale[e];
            let x = gather(inp.x, inp.conn[e]);
            max_frequency_deformed(&x, &inp.reference[e], mat.elastic.lambda, mat.elastic.mu, rho)
        } else {
            0.0
        };
    }
}

/// The smallest critical step `2/ω_e` over `omega`, reduced for stiffness
/// damping `beta` (s); order-independent.
pub(crate) fn critical_from_frequencies(omega: &[f64], beta: f64) -> f64 {
    omega
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&w| {
            if w <= 0.0 {
                return f64::INFINITY;
            }
            let xi = 0.5 * beta * w;
            2.0 / w * ((1.0 + xi * xi).sqrt() - xi)
        })
        .reduce(|| f64::INFINITY, |a, b| if b < a || a.is_nan() { b } else { a })
}

/// Highest frequency `ω_e` of every active element (0 for inactive ones),
/// with its density times its mass-scaling factor `scale`, into `omega`,
/// and the smallest critical step `2/ω_e` reduced for stiffness damping
/// (s), before the safety factor. `min` is exact and order-independent, so
/// the result does not depend on the thread count.
pub(crate) fn element_frequencies(inp: &ElementInputs<'_>, scale: &[f64], omega: &mut [f64]) -> f64 {
    omega
        .par_iter_mut()
        .enumerate()
        .with_min_len(CHUNK)
        .map(|(e, w)| {
            if !inp.active[e] {
                *w = 0.0;
                return f64::INFINITY;
            }
            let mat = &inp.materials[inp.material[e] as usize];
            let x = gather(inp.x, inp.conn[e]);
            *w = max_frequency_deformed(
                &x,
                &inp.reference[e],
                mat.elastic.lambda,
                mat.elastic.mu,
                mat.density * scale[e],
            );
            let xi = 0.5 * inp.beta * *w;
            2.0 / *w * ((1.0 + xi * xi).sqrt() - xi)
        })
        .reduce(|| f64::INFINITY, |a, b| if b < a || a.is_nan() { b } else { a })
}
