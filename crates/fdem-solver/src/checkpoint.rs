//! Checkpoints: the complete state of a [`Simulation`] in a versioned,
//! checksummed file, written atomically (docs/checkpoints.md).
//!
//! A checkpoint holds everything a step reads: nodes, elements and their
//! plastic state and lineage, the current topology and its adjacency, surfaces, contact
//! history and the broad phase's candidate list and build positions, bonds,
//! the fracture check's memory, loads, supports, the excavation schedule and
//! its position, the time-step history (`Δt^{n−½}`, `Δt^{n+½}`, the critical
//! step) and the energy account. Scratch buffers, the thread pool and the
//! profiling clocks are not kept. A run continued from a checkpoint is
//! therefore bit-for-bit the run that was not interrupted, for any thread
//! count (the chunking that fixes the summation order does not depend on it).
//!
//! File layout (all integers little-endian):
//!
//! | bytes   | content                                            |
//! |---------|----------------------------------------------------|
//! | 0–7     | magic `FDEMCKPT`                                   |
//! | 8–11    | format version ([`FORMAT_VERSION`])                |
//! | 12–15   | flags (0)                                          |
//! | 16–23   | length `S` of the state block                      |
//! | 24–31   | length `U` of the caller's block                   |
//! | 32–35   | CRC-32 (IEEE) of the `S + U` bytes that follow     |
//! | 36–39   | CRC-32 of bytes 0–35                               |
//! | 40–     | state (postcard), then the caller's block          |
//!
//! The caller's block is opaque to the kernel; the Python package keeps the
//! model fingerprint and the output series there.

use std::fs::File;
use std::io::{Read, Write};
use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::clock::Clock;
use crate::contact::{ContactModel, NodeForces};
use crate::energy::EnergyLedger;
use crate::excavation::Staging;
use crate::fracture::FractureModel;
use crate::loads::{Amplitude, Constraint, Loads, PressureLoad};
use crate::model::{ExcavationStage, Settings};
use crate::passes::{Material, PressureFacet};
use crate::renumber::Layout;
use crate::simulation::{ContactStats, Diagnostics, Elements, Nodes, PhaseTimes, Simulation};
use crate::stable_step::Frequencies;
use fdem_contact::{ContactState, Dashpot, NodeContact, Surface};
use fdem_element::Vec2;
use fdem_mesh::Csr;

/// The first eight bytes of every checkpoint file.
pub const MAGIC: &[u8; 8] = b"FDEMCKPT";
/// The checkpoint format this build writes; it reads this one and older.
/// Format 2 appends [`Format2`] (mass scaling) to the format-1 state,
/// format 3 then [`Format3`] (the second contacts of corner nodes),
/// format 4 then [`Format4`] (spatial renumbering). Format 5 keeps each
/// material point's crack direction as a
/// [`DirectionCode`](fdem_material::principal::DirectionCode) where formats
/// 1–4 kept its angle (rad): an older file's angles are converted as it is
/// read, so its run continues with that direction (not bit for bit the run
/// an older build would continue: its arithmetic differs in the last bits).
/// Format 6 appends [`Format6`] (the contact dashpots of the node pass),
/// format 7 then [`Format7`] (the elements' lineage), format 8 then
/// [`Format8`] (the bonds' offsets and the local damping), format 9 then
/// [`Format9`] (the bonds' mixed-mode laws and the materials' `G_II`),
/// format 10 then [`Format10`] (the materials' softening curves and the
/// bonds' kinks), format 11 then [`Format11`] (the renumbering interval),
/// format 12 then [`Format12`] (the contact memories' offsets).
pub const FORMAT_VERSION: u32 = 12;
const HEADER: usize = 40;

/// Why a checkpoint could not be written or read.
#[derive(Clone, Debug, PartialEq)]
pub enum CheckpointError {
    /// The file could not be read or written (the operating system's
    /// message).
    Io(String),
    /// Not a checkpoint of fdem (wrong magic bytes).
    NotACheckpoint,
    /// Written by a newer fdem in a format this build cannot read.
    NewerFormat {
        /// The file's format version.
        found: u32,
        /// The newest this build reads.
        supported: u32,
    },
    /// The file is shorter than its header says (an interrupted copy).
    Truncated {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// A checksum does not match: the file was altered or damaged.
    Corrupted(String),
    /// The checksums match but the content is not a consistent state.
    Invalid(String),
}

impl std::fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CheckpointError::Io(s) => f.write_str(s),
            CheckpointError::NotACheckpoint => f.write_str("not an fdem checkpoint (wrong magic bytes)"),
            CheckpointError::NewerFormat { found, supported } => write!(
                f,
                "checkpoint format {found} was written by a newer fdem; this version reads formats up to \
                 {supported}; upgrade fdem to read it"
            ),
            CheckpointError::Truncated { expected, found } => write!(
                f,
                "checkpoint is truncated: {found} bytes present, {expected} expected (an interrupted write \
                 or copy)"
            ),
            CheckpointError::Corrupted(s) => write!(f, "checkpoint is corrupted: {s}"),
            CheckpointError::Invalid(s) => write!(f, "checkpoint holds an inconsistent state: {s}"),
        }
    }
}

impl std::error::Error for CheckpointError {}

/// Generates the borrowed (written) and owned (read) forms of the saved state
/// from one field list, so the two can never disagree on order or type. Each
/// entry names the saved field, its type and where it lives in a
/// [`Simulation`] (postcard writes fields in order with no names, so the
/// layout is the list's, whichever part of the simulation owns a field).
macro_rules! saved_state {
    ($($field:ident : $ty:ty => $($path:ident).+),* $(,)?) => {
        #[derive(Serialize)]
        struct StateRef<'a> {
            version: &'a str,
            $($field: &'a $ty,)*
        }

        #[derive(Deserialize)]
        struct StateOwned {
            #[allow(dead_code)]
            version: String,
            $($field: $ty,)*
        }

        fn state_ref(s: &Simulation) -> StateRef<'_> {
            StateRef { version: env!("CARGO_PKG_VERSION"), $($field: &s.$($path).+,)* }
        }
    };
}

saved_state! {
    nodes: Nodes => nodes,
    elems: Elements => elems,
    materials: Vec<Material> => materials,
    node_elems: Csr => node_elems,
    constraints: Vec<Constraint> => loads.constraints,
    amplitudes: Vec<Amplitude> => loads.amplitudes,
    amplitude_values: Vec<f64> => loads.amplitude_values,
    pressure_loads: Vec<PressureLoad> => loads.pressure_loads,
    ancestor: Vec<u32> => ancestor,
    surface: Surface => surface,
    pressure: Vec<PressureFacet> => loads.pressure,
    pressure_force: Vec<Vec2> => loads.pressure_force,
    contact_force: Vec<Vec2> => node_forces.contact_force,
    contact_damping_force: Vec<Vec2> => node_forces.contact_damping_force,
    contact: Option<ContactModel> => contact,
    fracture: Option<FractureModel> => fracture,
    stages: Vec<ExcavationStage> => staging.stages,
    next_stage: usize => staging.next_stage,
    elastic_stage: bool => staging.elastic_stage,
    contact_stats: ContactStats => diagnostics.contact_stats,
    omega: Vec<f64> => frequencies.omega,
    gravity: Vec2 => loads.gravity,
    settings: Settings => settings,
    // written as its five fields (`Clock`): time, step, dt, dt_prev,
    // dt_critical
    clock: Clock => clock,
    // written as the account and the held energy (`EnergyLedger`)
    ledger: EnergyLedger => ledger,
}

/// The simulation a decoded state describes, on `pool`: the saved fields
/// put back into the parts that own them (the list above says where), the
/// scratch empty, and the data derived from the saved fields worked out.
fn assemble(o: StateOwned, pool: Arc<rayon::ThreadPool>) -> Simulation {
    let n = o.nodes.x.len();
    let m = o.elems.conn.len();
    let mut sim = Simulation {
        nodes: o.nodes,
        elems: o.elems,
        materials: o.materials,
        node_elems: o.node_elems,
        loads: Loads {
            constraints: o.constraints,
            amplitudes: o.amplitudes,
            amplitude_values: o.amplitude_values,
            pressure_loads: o.pressure_loads,
            pressure: o.pressure,
            pressure_force: o.pressure_force,
            gravity: o.gravity,
            released: Vec::new(),
            release_force: Vec::new(),
        },
        ancestor: o.ancestor,
        surface: o.surface,
        node_forces: NodeForces {
            contact_force: o.contact_force,
            contact_damping_force: o.contact_damping_force,
            ..Default::default()
        },
        contact: o.contact,
        fracture: o.fracture,
        staging: Staging { stages: o.stages, next_stage: o.next_stage, elastic_stage: o.elastic_stage },
        diagnostics: Diagnostics { contact_stats: o.contact_stats, phase_times: PhaseTimes::default() },
        frequencies: Frequencies { omega: o.omega, ..Default::default() },
        settings: o.settings,
        clock: o.clock,
        ledger: o.ledger,
        layout: Layout::default(),
        pool,
    };
    // derived data, not saved
    sim.surface.derive(&sim.nodes.x0);
    crate::topology::set_apexes(&mut sim.surface, &sim.elems.conn);
    if let Some(c) = sim.contact.as_mut() {
        for o in c.out.iter_mut().chain(c.corner_out.iter_mut()) {
            o.locate(&sim.surface);
        }
        c.mark_busy();
    }
    // per-chunk partial sums are sized, never resized, by the passes
    sim.ledger.size_partials(n, m);
    if let Some(c) = sim.contact.as_mut() {
        c.size_scratch(&sim.surface);
    }
    sim
}

mod blocks;
use blocks::*;

fn le_u32(b: &[u8]) -> u32 {
    u32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

fn le_u64(b: &[u8]) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[..8]);
    u64::from_le_bytes(a)
}

impl Simulation {
    /// The complete state as checkpoint bytes, with `user` (any bytes the
    /// caller wants back on restore) appended under the same checksum.
    pub fn checkpoint_bytes(&self, user: &[u8]) -> Vec<u8> {
        // postcard serialises plain data into a Vec; it fails only on
        // types it does not support, which a unit test rules out.
        let mut state = postcard::to_stdvec(&state_ref(self)).expect("simulation state is serialisable");
        state.extend(postcard::to_stdvec(&Format2::of(self)).expect("format-2 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format3::of(self)).expect("format-3 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format4::of(self)).expect("format-4 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format6::of(self)).expect("format-6 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format7::of(self)).expect("format-7 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format8::of(self)).expect("format-8 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format9::of(self)).expect("format-9 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format10::of(self)).expect("format-10 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format11::of(self)).expect("format-11 data is serialisable"));
        state.extend(postcard::to_stdvec(&Format12::of(self)).expect("format-12 data is serialisable"));
        let mut out = Vec::with_capacity(HEADER + state.len() + user.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(state.len() as u64).to_le_bytes());
        out.extend_from_slice(&(user.len() as u64).to_le_bytes());
        let mut body = crc32fast::Hasher::new();
        body.update(&state);
        body.update(user);
        out.extend_from_slice(&body.finalize().to_le_bytes());
        let head = crc32fast::hash(&out[..36]);
        out.extend_from_slice(&head.to_le_bytes());
        out.extend_from_slice(&state);
        out.extend_from_slice(user);
        out
    }

    /// Rebuilds a simulation from checkpoint bytes on `threads` worker
    /// threads (0: all cores); returns it with the caller's block.
    pub fn from_checkpoint_bytes(bytes: &[u8], threads: usize) -> Result<(Self, Vec<u8>), CheckpointError> {
        if bytes.len() < 8 || &bytes[..8] != MAGIC {
            return Err(CheckpointError::NotACheckpoint);
        }
        if bytes.len() < HEADER {
            return Err(CheckpointError::Truncated { expected: HEADER as u64, found: bytes.len() as u64 });
        }
        if crc32fast::hash(&bytes[..36]) != le_u32(&bytes[36..40]) {
            return Err(CheckpointError::Corrupted("header checksum mismatch".into()));
        }
        let version = le_u32(&bytes[8..12]);
        if version > FORMAT_VERSION {
            return Err(CheckpointError::NewerFormat { found: version, supported: FORMAT_VERSION });
        }
        if version == 0 {
            return Err(CheckpointError::Corrupted("format version 0".into()));
        }
        let (s_len, u_len) = (le_u64(&bytes[16..24]), le_u64(&bytes[24..32]));
        let expected = (HEADER as u64).saturating_add(s_len).saturating_add(u_len);
        let found = bytes.len() as u64;
        if found < expected {
            return Err(CheckpointError::Truncated { expected, found });
        }
        if found > expected {
            return Err(CheckpointError::Corrupted(format!("{} bytes after the end of the data", found - expected)));
        }
        let body = &bytes[HEADER..];
        if crc32fast::hash(body) != le_u32(&bytes[32..36]) {
            return Err(CheckpointError::Corrupted("data checksum mismatch".into()));
        }
        let (state, user) = body.split_at(s_len as usize);
        let decode = |e: postcard::Error| CheckpointError::Invalid(format!("cannot decode the state: {e}"));
        let (mut owned, rest): (StateOwned, &[u8]) = postcard::take_from_bytes(state).map_err(decode)?;
        let (added, rest) = if version >= 2 {
            postcard::take_from_bytes::<Format2>(rest).map_err(decode)?
        } else {
            let m = owned.elems.conn.len();
            (Format2 { mass_scale: vec![1.0; m], mass_scaling: None, mass_scaling_energy: 0.0 }, rest)
        };
        added.apply(&mut owned);
        let (corners, rest) = if version >= 3 {
            postcard::take_from_bytes::<Format3>(rest).map_err(decode)?
        } else {
            (Format3::none(&owned), rest)
        };
        let (renumbering, rest) = if version >= 4 {
            postcard::take_from_bytes::<Format4>(rest).map_err(decode)?
        } else {
            (Format4::none(&owned), rest)
        };
        // an older file has no dashpots: its contacts keep the normals and
        // spring forces recovered from their saved forces, without a
        // dashpot (`NodeContact`'s conversion from the saved record)
        let (dashpots, rest) = if version >= 6 {
            let (d, rest) = postcard::take_from_bytes::<Format6>(rest).map_err(decode)?;
            (Some(d), rest)
        } else {
            (None, rest)
        };
        let (lineage, rest) = if version >= 7 {
            let (l, rest) = postcard::take_from_bytes::<Format7>(rest).map_err(decode)?;
            (Some(l), rest)
        } else {
            (None, rest)
        };
        let (offsets, rest) = if version >= 8 {
            let (o, rest) = postcard::take_from_bytes::<Format8>(rest).map_err(decode)?;
            (Some(o), rest)
        } else {
            (None, rest)
        };
        let (modes, rest) = if version >= 9 {
            let (o, rest) = postcard::take_from_bytes::<Format9>(rest).map_err(decode)?;
            (Some(o), rest)
        } else {
            (None, rest)
        };
        let (curves, rest) = if version >= 10 {
            let (o, rest) = postcard::take_from_bytes::<Format10>(rest).map_err(decode)?;
            (Some(o), rest)
        } else {
            (None, rest)
        };
        // an older file renumbered periodically whenever it renumbered
        let (interval, rest) = if version >= 11 {
            postcard::take_from_bytes::<Format11>(rest).map_err(decode)?
        } else {
            (Format11 { renumber_every: renumbering.renumber.map(|_| crate::RENUMBER_INTERVAL) }, rest)
        };
        let (contact_offsets, rest) = if version >= 12 {
            let (o, rest) = postcard::take_from_bytes::<Format12>(rest).map_err(decode)?;
            (Some(o), rest)
        } else {
            (None, rest)
        };
        if !rest.is_empty() {
            return Err(CheckpointError::Invalid(format!("{} bytes after the state", rest.len())));
        }
        match modes {
            Some(Format9 { modes, shear_fracture_energy }) => {
                let bonds = owned.fracture.as_mut().map_or(&mut [][..], |f| &mut f.bonds[..]);
                let valid = |m: &fdem_contact::MixedMode| {
                    let unit = (m.normal[0].hypot(m.normal[1]) - 1.0).abs() < 1e-9;
                    unit && m.cohesion >= 0.0
                        && m.friction >= 0.0
                        && m.shear_energy > 0.0
                        && m.shear_energy.is_finite()
                        && (0.0..=1.0).contains(&m.damage)
                };
                if modes.len() != bonds.len() || modes.iter().flatten().any(|m| !valid(m)) {
                    return Err(CheckpointError::Invalid("the bonds' mixed-mode laws do not match the bonds".into()));
                }
                for (b, m) in bonds.iter_mut().zip(modes) {
                    b.mode = m;
                }
                if shear_fracture_energy.len() != owned.materials.len()
                    || shear_fracture_energy.iter().any(|g| !(*g >= 0.0 && g.is_finite()))
                {
                    return Err(CheckpointError::Invalid(
                        "the materials' mode-II fracture energies are invalid".into(),
                    ));
                }
                for (m, g) in owned.materials.iter_mut().zip(shear_fracture_energy) {
                    m.shear_fracture_energy = g;
                }
            }
            None => {
                for m in &mut owned.materials {
                    m.shear_fracture_energy = m.plastic.as_ref().map_or(0.0, |l| l.fracture_energy);
                }
            }
        }
        if let Some(Format10 { softening, kinks }) = curves {
            if softening.len() != owned.materials.len() {
                return Err(CheckpointError::Invalid(
                    "the materials' softening curves do not match the materials".into(),
                ));
            }
            for (m, s) in owned.materials.iter_mut().zip(softening) {
                if let Some(law) = m.plastic.as_mut() {
                    *law = law.with_softening(s).map_err(|e| CheckpointError::Invalid(e.to_string()))?;
                }
            }
            let bonds = owned.fracture.as_mut().map_or(&mut [][..], |f| &mut f.bonds[..]);
            let inside = |v: f64| v > 0.0 && v < 1.0;
            if kinks.len() != bonds.len()
                || kinks.iter().flatten().any(|k| !(inside(k.at) && inside(k.traction)))
                || bonds.iter().zip(&kinks).any(|(b, k)| k.is_some() && b.mode.is_none())
            {
                return Err(CheckpointError::Invalid("the bonds' kinks do not match the bonds".into()));
            }
            for (b, k) in bonds.iter_mut().zip(kinks) {
                if let Some(m) = b.mode.as_mut() {
                    m.kink = k;
                }
            }
        }
        let mut released = Vec::new();
        if let Some(Format8 { offsets, local_damping, stage_ramps, released: r }) = offsets {
            if !(0.0..1.0).contains(&local_damping) {
                return Err(CheckpointError::Invalid(format!("local damping {local_damping} must lie in [0, 1)")));
            }
            owned.settings.local_damping = local_damping;
            let n = owned.nodes.x.len();
            if stage_ramps.len() != owned.stages.len()
                || stage_ramps.iter().any(|t| !(*t >= 0.0 && t.is_finite()))
                || r.iter().any(|r| {
                    r.nodes.len() != r.forces.len()
                        || !(r.ramp > 0.0 && r.ramp.is_finite() && r.start.is_finite())
                        || r.nodes.iter().any(|&v| v as usize >= n)
                })
            {
                return Err(CheckpointError::Invalid("the gradual excavations do not match the model".into()));
            }
            for (st, t) in owned.stages.iter_mut().zip(stage_ramps) {
                st.ramp = t;
            }
            released = r;
            let bonds = owned.fracture.as_mut().map_or(&mut [][..], |f| &mut f.bonds[..]);
            if offsets.len() != bonds.len() || offsets.iter().any(|o| !(o[0].is_finite() && o[1].is_finite())) {
                return Err(CheckpointError::Invalid("the bonds' offsets do not match the bonds".into()));
            }
            for (b, o) in bonds.iter_mut().zip(offsets) {
                b.offset = o;
            }
        }
        corners.apply(&mut owned);
        if let Some(o) = contact_offsets {
            o.apply(&mut owned)?;
        }
        if version < 5 {
            for st in &mut owned.elems.state {
                st.direction_code = fdem_material::principal::DirectionCode::of_angle(st.direction_code);
            }
        }
        check_consistent(&owned)?;
        if dashpots.as_ref().is_some_and(|d| d.dashpots.iter().any(|d| d.len() != owned.contact_force.len())) {
            return Err(CheckpointError::Invalid("the contact dashpots do not match the surface".into()));
        }
        if !renumbering.layout.is_consistent(owned.nodes.x.len(), owned.elems.conn.len()) {
            return Err(CheckpointError::Invalid("the node and element numbering is not a permutation".into()));
        }
        let m = owned.elems.conn.len();
        let lineage = lineage.unwrap_or_else(|| Format7::none(m, &renumbering.layout));
        // a parent is an element made before its piece (or the element
        // itself): a smaller or equal id
        let layout = &renumbering.layout;
        if lineage.parent.len() != m || (0..m as u32).any(|e| lineage.parent[e as usize] > layout.elem_id(e)) {
            return Err(CheckpointError::Invalid("the element lineage is inconsistent".into()));
        }
        owned.elems.parent = lineage.parent;
        if let Some(f) = renumbering.renumber {
            if !(f > 0.0 && f.is_finite()) {
                return Err(CheckpointError::Invalid(format!("renumbering fraction {f} must be positive")));
            }
        }
        owned.settings.renumber = renumbering.renumber;
        if interval.renumber_every == Some(0) {
            return Err(CheckpointError::Invalid("renumbering interval 0 steps".into()));
        }
        owned.settings.renumber_every = interval.renumber_every;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| CheckpointError::Io(format!("cannot start {threads} threads: {e}")))?;
        let mut sim = assemble(owned, Arc::new(pool));
        sim.layout = renumbering.layout;
        sim.loads.released = released;
        sim.update_release();
        if let Some(c) = sim.contact.as_mut() {
            if let Some(saved) = dashpots {
                for (list, saved) in [&mut c.out, &mut c.corner_out].into_iter().zip(saved.dashpots) {
                    for (o, d) in list.iter_mut().zip(saved) {
                        o.dashpot = d;
                    }
                }
            }
            sim.node_forces.contact_damped = vec![0; sim.node_forces.contact_force.len()];
        }
        // the assembly again, which also finds the damped nodes, and the
        // bonds' forces on top, as the step added them: the same forces,
        // in the same order, as the saved ones (without the bonds' the
        // restored run lost their forces for a step and diverged)
        sim.reassemble_surface_forces();
        Ok((sim, user.to_vec()))
    }

    /// Writes a checkpoint to `path` atomically: to `path` + `.tmp`, flushed
    /// to disk, then renamed over `path`, so an interruption leaves the
    /// previous checkpoint intact.
    pub fn write_checkpoint(&self, path: &Path, user: &[u8]) -> Result<(), CheckpointError> {
        let io = |what: &str, p: &Path, e: std::io::Error| CheckpointError::Io(format!("{what} {}: {e}", p.display()));
        let bytes = self.checkpoint_bytes(user);
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let tmp = std::path::PathBuf::from(tmp);
        {
            let mut f = File::create(&tmp).map_err(|e| io("cannot create", &tmp, e))?;
            f.write_all(&bytes).map_err(|e| io("cannot write", &tmp, e))?;
            f.sync_all().map_err(|e| io("cannot flush", &tmp, e))?;
        }
        std::fs::rename(&tmp, path).map_err(|e| io("cannot rename onto", path, e))?;
        Ok(())
    }

    /// Reads a checkpoint file written by [`write_checkpoint`](Self::write_checkpoint).
    pub fn read_checkpoint(path: &Path, threads: usize) -> Result<(Self, Vec<u8>), CheckpointError> {
        let mut bytes = Vec::new();
        File::open(path)
            .and_then(|mut f| f.read_to_end(&mut bytes))
            .map_err(|e| CheckpointError::Io(format!("cannot read {}: {e}", path.display())))?;
        Self::from_checkpoint_bytes(&bytes, threads)
    }
}

/// The cross-checks that keep a decoded state from indexing out of range in
/// the next step (the checksums already rule out damage; this guards against
/// a hand-made file).
fn check_consistent(s: &StateOwned) -> Result<(), CheckpointError> {
    let bad = |m: String| Err(CheckpointError::Invalid(m));
    let n = s.nodes.x.len();
    let m = s.elems.conn.len();
    let nodes_ok = [s.nodes.x0.len(), s.nodes.v.len(), s.nodes.mass.len(), s.nodes.bc.len(), s.ancestor.len()]
        .iter()
        .all(|&k| k == n);
    if !nodes_ok {
        return bad(format!("node arrays disagree on the node count ({n})"));
    }
    let elems_ok = [
        s.elems.reference.len(),
        s.elems.material.len(),
        s.elems.active.len(),
        s.elems.stress.len(),
        s.elems.mass_scale.len(),
    ]
    .iter()
    .all(|&k| k == m)
        && s.elems.state.len() == m
        && s.elems.force.len() == 3 * m
        && s.omega.len() == m;
    if !elems_ok {
        return bad(format!("element arrays disagree on the element count ({m})"));
    }
    if let Some(e) = s.elems.conn.iter().position(|t| t.iter().any(|&v| v as usize >= n)) {
        return bad(format!("element {e} refers to a missing node"));
    }
    if let Some(e) = s.elems.mass_scale.iter().position(|&f| !(f >= 1.0 && f.is_finite())) {
        return bad(format!(
            "element {e} has a mass-scaling factor {} (must be finite and >= 1)",
            s.elems.mass_scale[e]
        ));
    }
    if let Some(e) = s.elems.material.iter().position(|&k| k as usize >= s.materials.len()) {
        return bad(format!("element {e} refers to a missing material"));
    }
    // rows of `c` hold ids below `items` (node_elems holds force slots 3e + k)
    let csr_ok = |c: &Csr, rows: usize, items: usize| {
        c.offsets.len() == rows + 1
            && c.offsets.windows(2).all(|w| w[0] <= w[1])
            && c.offsets.last().is_some_and(|&e| e as usize == c.items.len())
            && c.items.iter().all(|&i| (i as usize) < items)
    };
    if !csr_ok(&s.node_elems, n, 3 * m) {
        return bad("the node-to-element lists are inconsistent".into());
    }
    let nb = s.surface.nodes.len();
    if s.surface.nodes.iter().any(|&v| v as usize >= n)
        || s.surface.facets.iter().any(|f| f.nodes.iter().any(|&v| v as usize >= n))
        || s.surface.index_of.len() != n
        || s.pressure_force.len() != nb
        || !csr_ok(&s.surface.node_facets, nb, s.surface.facets.len())
    {
        return bad("the surface is inconsistent with the nodes".into());
    }
    if s.amplitude_values.len() != s.amplitudes.len() || s.next_stage > s.stages.len() {
        return bad("the load or excavation schedule is inconsistent".into());
    }
    if let Some(c) = &s.contact {
        if [c.states.len(), c.out.len(), c.corner_states.len(), c.corner_out.len(), s.contact_force.len()]
            .iter()
            .any(|&l| l != nb)
        {
            return bad("the contact history does not match the surface".into());
        }
        let cand = &c.broad.candidates;
        let fresh = cand.offsets.is_empty() && cand.items.is_empty();
        if !fresh && !csr_ok(cand, cand.offsets.len() - 1, s.surface.facets.len()) {
            return bad("the contact candidate list refers to missing facets".into());
        }
    }
    Ok(())
}
