//! The blocks later formats appended to the format-1 state, in file order
//! (the module notes of `checkpoint.rs` give the layout): each says what
//! it holds, how a simulation writes it and what an older file restores
//! in its place.

use serde::{Deserialize, Serialize};

use super::*;

/// What format 2 added, written after the format-1 state (so a format-1
/// file still decodes, with every mass physical): the elements' density
/// factors, the mass-scaling setting and its energy term.
#[derive(Serialize, Deserialize)]
pub(super) struct Format2 {
    pub(super) mass_scale: Vec<f64>,
    pub(super) mass_scaling: Option<f64>,
    pub(super) mass_scaling_energy: f64,
}

impl Format2 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format2 {
            mass_scale: s.elems.mass_scale.clone(),
            mass_scaling: s.settings.mass_scaling,
            mass_scaling_energy: s.ledger.account.mass_scaling,
        }
    }

    pub(super) fn apply(self, o: &mut StateOwned) {
        o.elems.mass_scale = self.mass_scale;
        o.settings.mass_scaling = self.mass_scaling;
        o.ledger.account.mass_scaling = self.mass_scaling_energy;
    }
}

/// What format 3 added, written after [`Format2`]: the second contact of
/// every corner node (empty without contact). A file of an older format
/// restores with none: a corner node's second face takes up contact anew
/// (through the facet's line, so no energy appears).
#[derive(Serialize, Deserialize)]
pub(super) struct Format3 {
    pub(super) corner_states: Vec<ContactState>,
    pub(super) corner_out: Vec<NodeContact>,
}

impl Format3 {
    pub(super) fn of(s: &Simulation) -> Self {
        let (corner_states, corner_out) =
            s.contact.as_ref().map_or_else(Default::default, |c| (c.corner_states.clone(), c.corner_out.clone()));
        Format3 { corner_states, corner_out }
    }

    pub(super) fn apply(self, o: &mut StateOwned) {
        if let Some(c) = o.contact.as_mut() {
            c.corner_states = self.corner_states;
            c.corner_out = self.corner_out;
        }
    }

    /// No second contacts: what an older file restores with.
    pub(super) fn none(o: &StateOwned) -> Self {
        let nb = if o.contact.is_some() { o.surface.nodes.len() } else { 0 };
        Format3 {
            corner_states: vec![ContactState::default(); nb],
            corner_out: vec![NodeContact { facet: fdem_contact::NONE, ..Default::default() }; nb],
        }
    }
}

/// What format 4 added, written after [`Format3`]: the renumbering
/// setting and the layout (internal index ↔ id) it has made. A file of an
/// older format restores in creation order, with renumbering off.
#[derive(Serialize, Deserialize)]
pub(super) struct Format4 {
    pub(super) renumber: Option<f64>,
    pub(super) layout: Layout,
}

impl Format4 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format4 { renumber: s.settings.renumber, layout: s.layout.clone() }
    }

    /// Creation order, no renumbering: what an older file restores with.
    pub(super) fn none(o: &StateOwned) -> Self {
        Format4 { renumber: None, layout: Layout::new(o.elems.conn.len()) }
    }
}

/// What format 6 added, written after [`Format4`]: the dashpot of every
/// contact (first and corner), which the next node pass applies
/// ([`Dashpot`], docs/contact.md). A file of an older format restores with
/// none (its contacts' normals and spring forces are recovered from their
/// saved forces): its first step has its dashpots' estimate only.
#[derive(Serialize, Deserialize)]
pub(super) struct Format6 {
    pub(super) dashpots: [Vec<Dashpot>; 2],
}

impl Format6 {
    pub(super) fn of(s: &Simulation) -> Self {
        let of = |list: &[NodeContact]| list.iter().map(|c| c.dashpot).collect();
        let dashpots = s.contact.as_ref().map_or_else(Default::default, |c| [of(&c.out), of(&c.corner_out)]);
        Format6 { dashpots }
    }
}

/// What format 7 added, written after [`Format6`]: every element's parent
/// (`lineage.rs`), per internal index. A file of an older format restores
/// with every element its own parent, so a piece that cracks made before
/// the file was written is in no element set until
/// [`Simulation::recover_lineage`] places it inside its model element
/// (`fdem.Simulation.from_checkpoint` does, with the model it is given).
#[derive(Serialize, Deserialize)]
pub(super) struct Format7 {
    pub(super) parent: Vec<u32>,
}

impl Format7 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format7 { parent: s.elems.parent.clone() }
    }

    /// Every element its own parent: what an older file restores with.
    pub(super) fn none(m: usize, layout: &Layout) -> Self {
        Format7 { parent: (0..m as u32).map(|e| layout.elem_id(e)).collect() }
    }
}

/// What format 8 added, written after [`Format7`]: each bond's offset
/// ([`Bond::offset`](fdem_contact::Bond::offset), the opening with which a
/// bond took over the force through its node when its crack was
/// inserted), in the order of the bonds, the local damping coefficient
/// ([`Settings::local_damping`]), each excavation stage's release time and
/// the loads of gradual excavations still acting ([`crate::Release`]). A
/// file of an older format restores its bonds slack (offset zero), as
/// they were made, no local damping and instantaneous stages.
#[derive(Serialize, Deserialize)]
pub(super) struct Format8 {
    pub(super) offsets: Vec<Vec2>,
    pub(super) local_damping: f64,
    pub(super) stage_ramps: Vec<f64>,
    pub(super) released: Vec<crate::Release>,
}

impl Format8 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format8 {
            offsets: s.fracture.as_ref().map_or_else(Vec::new, |f| f.bonds.iter().map(|b| b.offset).collect()),
            local_damping: s.settings.local_damping,
            stage_ramps: s.staging.stages.iter().map(|st| st.ramp).collect(),
            released: s.loads.released.clone(),
        }
    }
}

/// What format 9 added, written after [`Format8`]: each bond's mixed-mode
/// law and damage ([`Bond::mode`](fdem_contact::Bond::mode)), in the order
/// of the bonds, and each material's mode-II fracture energy. A file of an
/// older format restores its bonds with the isotropic law they were made
/// with (so a run continues as the older build ran it) and gives its
/// materials `G_II = G_f` (the default of `fdem.MohrCoulombRankine`) for
/// the bonds of cracks inserted after the restore.
#[derive(Serialize, Deserialize)]
pub(super) struct Format9 {
    pub(super) modes: Vec<Option<fdem_contact::MixedMode>>,
    pub(super) shear_fracture_energy: Vec<f64>,
}

impl Format9 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format9 {
            modes: s.fracture.as_ref().map_or_else(Vec::new, |f| f.bonds.iter().map(|b| b.mode).collect()),
            shear_fracture_energy: s.materials.iter().map(|m| m.shear_fracture_energy).collect(),
        }
    }
}

/// What format 10 added, written after [`Format9`]: each material's
/// softening curve ([`MohrCoulombRankine::softening`](fdem_material::MohrCoulombRankine::softening);
/// `Linear` for a material without a plastic law) and each bond's kink
/// ([`MixedMode::kink`](fdem_contact::MixedMode::kink); `None` for a
/// straight envelope or an isotropic bond), in the order of the bonds. A
/// file of an older format restores linear softening and straight
/// envelopes, the only ones older builds had.
#[derive(Serialize, Deserialize)]
pub(super) struct Format10 {
    pub(super) softening: Vec<fdem_material::Softening>,
    pub(super) kinks: Vec<Option<fdem_contact::Kink>>,
}

impl Format10 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format10 {
            softening: s
                .materials
                .iter()
                .map(|m| m.plastic.as_ref().map_or_else(Default::default, |l| l.softening))
                .collect(),
            kinks: s
                .fracture
                .as_ref()
                .map_or_else(Vec::new, |f| f.bonds.iter().map(|b| b.mode.and_then(|m| m.kink)).collect()),
        }
    }
}

/// What format 11 added: the steps between periodic renumberings
/// ([`Settings::renumber_every`](crate::Settings::renumber_every)). An
/// older file renumbered every
/// [`RENUMBER_INTERVAL`](crate::RENUMBER_INTERVAL) steps whenever its
/// renumbering was on, and restores that.
#[derive(Serialize, Deserialize)]
pub(super) struct Format11 {
    pub(super) renumber_every: Option<u64>,
}

impl Format11 {
    pub(super) fn of(s: &Simulation) -> Self {
        Format11 { renumber_every: s.settings.renumber_every }
    }
}

/// What format 12 added, written after [`Format11`]: the non-zero offsets
/// of the contact memories ([`ContactState::offset`]: the depth a node
/// found already inside a facet's element does not count), as (boundary
/// index, offset) for the first and the second memory per boundary node:
/// most memories have none, so a file without any grows by two bytes. A
/// file of an older format restores with none.
#[derive(Serialize, Deserialize)]
pub(super) struct Format12 {
    pub(super) offsets: [Vec<(u32, f64)>; 2],
}

impl Format12 {
    pub(super) fn of(s: &Simulation) -> Self {
        let sparse = |m: &[ContactState]| -> Vec<(u32, f64)> {
            m.iter().enumerate().filter(|(_, m)| m.offset != 0.0).map(|(b, m)| (b as u32, m.offset)).collect()
        };
        let offsets =
            s.contact.as_ref().map_or_else(Default::default, |c| [sparse(&c.states), sparse(&c.corner_states)]);
        Format12 { offsets }
    }

    /// Sets the offsets of the restored memories (after [`Format3`] set
    /// the second ones); refuses an index past the memories, one given
    /// twice or out of order, and an offset that is not finite and
    /// positive.
    pub(super) fn apply(self, o: &mut StateOwned) -> Result<(), CheckpointError> {
        let [first, second] = self.offsets;
        let Some(c) = o.contact.as_mut() else {
            return if first.is_empty() && second.is_empty() {
                Ok(())
            } else {
                Err(CheckpointError::Invalid("contact offsets in a model without contact".into()))
            };
        };
        for (memories, offsets) in [(&mut c.states, first), (&mut c.corner_states, second)] {
            let ascending = offsets.windows(2).all(|w| w[0].0 < w[1].0);
            if !ascending || offsets.iter().any(|&(b, d)| b as usize >= memories.len() || !(d.is_finite() && d > 0.0)) {
                return Err(CheckpointError::Invalid("the contact offsets do not match the contacts".into()));
            }
            for (b, d) in offsets {
                memories[b as usize].offset = d;
            }
        }
        Ok(())
    }
}
