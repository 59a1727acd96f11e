//! Broad phase: which (node, facet) pairs can touch before the next
//! rebuild, from a parry2d BVH of facet boxes enlarged by a margin.
//!
//! A facet box enlarged by `margin` holds every node within `margin` of the
//! facet (in the box sense). Until some boundary node has moved more than
//! `margin / 2` since the last build, no pair outside the list can have come
//! into contact, so the list is reused step after step (a Verlet list). The
//! list holds, per boundary node, its candidate facets in ascending order,
//! whatever the tree layout, so results do not depend on the thread count
//! or on whether the tree was rebuilt or refitted.
//!
//! Tree leaves are the facets' stable keys ([`SurfaceFacet::key`]), so a
//! topology change (crack insertion, excavation) removes and inserts only
//! the leaves that changed and refits, instead of rebuilding the tree.
//!
//! [`SurfaceFacet::key`]: crate::SurfaceFacet::key

use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};
use rayon::prelude::*;

use fdem_mesh::Csr;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::surface::Surface;
use crate::{Vec2, CHUNK};

/// Refits between full rebuilds (a refit keeps the tree's topology, whose
/// quality decays as facets move).
const REFITS_PER_REBUILD: u32 = 16;

/// The broad phase and its candidate list.
pub struct BroadPhase {
    /// Box enlargement (m).
    pub margin: f64,
    bvh: Bvh,
    boxes: Vec<Aabb>,
    /// Positions of the boundary nodes at the last build.
    built_at: Vec<Vec2>,
    /// Candidate facets of every boundary node.
    pub candidates: Csr,
    chunk_lists: Vec<Vec<u32>>,
    chunk_counts: Vec<Vec<u32>>,
    refits: u32,
    /// Builds (rebuilds and refits) so far.
    pub builds: u64,
    fresh: bool,
    /// The surface changed since the last build.
    changed: bool,
    /// Keys of the leaves in the tree, ascending.
    keys: Vec<u32>,
    /// Facet index of each key in the current surface, or `NONE`.
    facet_of_key: Vec<u32>,
}

impl BroadPhase {
    /// An empty broad phase with box enlargement `margin` (m); the first
    /// [`update`](Self::update) builds it.
    pub fn new(margin: f64) -> Self {
        Self {
            margin,
            bvh: Bvh::new(),
            boxes: Vec::new(),
            built_at: Vec::new(),
            candidates: Csr::default(),
            chunk_lists: Vec::new(),
            chunk_counts: Vec::new(),
            refits: 0,
            builds: 0,
            fresh: true,
            changed: false,
            keys: Vec::new(),
            facet_of_key: Vec::new(),
        }
    }

    /// Notes a change of the surface (a topology change): the next update
    /// brings the tree and the candidate list up to date.
    pub fn invalidate(&mut self) {
        self.changed = true;
    }

    /// Whether some boundary node has moved more than half the margin since
    /// the last build.
    pub fn needs_update(&self, surface: &Surface, x: &[Vec2]) -> bool {
        if self.fresh || self.changed || self.built_at.len() != surface.nodes.len() {
            return true;
        }
        let limit = 0.25 * self.margin * self.margin;
        surface.nodes.par_iter().zip(self.built_at.par_iter()).with_min_len(CHUNK).any(|(&n, b)| {
            let p = x[n as usize];
            let (dx, dy) = (p[0] - b[0], p[1] - b[1]);
            let d2 = dx * dx + dy * dy;
            d2.is_nan() || d2 > limit
        })
    }

    /// Rebuilds (or refits) the tree and the candidate list if needed;
    /// returns whether it did.
    pub fn update(&mut self, surface: &Surface, x: &[Vec2]) -> bool {
        if !self.needs_update(surface, x) {
            return false;
        }
        self.build(surface, x);
        true
    }

    /// Builds the tree and candidate list now.
    pub fn build(&mut self, surface: &Surface, x: &[Vec2]) {
        let m = self.margin;
        let nf = surface.facets.len();
        self.boxes.resize(nf, Aabb::new_invalid());
        self.boxes.par_iter_mut().zip(surface.facets.par_iter()).with_min_len(CHUNK).for_each(|(bx, f)| {
            let (a, b) = (x[f.nodes[0] as usize], x[f.nodes[1] as usize]);
            *bx = Aabb::new(
                Vector::new(a[0].min(b[0]) - m, a[1].min(b[1]) - m),
                Vector::new(a[0].max(b[0]) + m, a[1].max(b[1]) + m),
            );
        });
        if self.fresh || self.changed {
            // key → facet of the new surface
            let max_key = surface.facets.last().map_or(0, |f| f.key as usize + 1);
            self.facet_of_key.clear();
            self.facet_of_key.resize(max_key.max(self.keys.last().map_or(0, |&k| k as usize + 1)), crate::NONE);
            for (i, f) in surface.facets.iter().enumerate() {
                self.facet_of_key[f.key as usize] = i as u32;
            }
        }
        if self.fresh || self.refits >= REFITS_PER_REBUILD || nf < 3 {
            self.bvh = if nf < 3 {
                let mut bvh = Bvh::new();
                for (f, bx) in surface.facets.iter().zip(&self.boxes) {
                    bvh.insert(*bx, f.key);
                }
                bvh
            } else {
                Bvh::from_iter(
                    BvhBuildStrategy::Binned,
                    surface.facets.iter().zip(&self.boxes).map(|(f, bx)| (f.key as usize, *bx)),
                )
            };
            self.refits = 0;
        } else {
            if self.changed {
                // leaves whose facet has gone
                for &k in &self.keys {
                    if self.facet_of_key[k as usize] == crate::NONE {
                        self.bvh.remove(k);
                    }
                }
            }
            for (f, bx) in surface.facets.iter().zip(&self.boxes) {
                self.bvh.insert_or_update_partially(*bx, f.key, 0.0);
            }
            self.bvh.refit_without_opt();
            self.refits += 1;
        }
        if self.fresh || self.changed {
            self.keys.clear();
            self.keys.extend(surface.facets.iter().map(|f| f.key));
            // the facet_of_key entries of removed keys are NONE already
        }
        self.changed = false;
        self.fresh = false;
        self.builds += 1;
        self.built_at.clear();
        self.built_at.extend(surface.nodes.iter().map(|&n| x[n as usize]));
        // query every boundary node, chunk by chunk, into reused buffers
        let n_chunks = surface.nodes.len().div_ceil(CHUNK);
        self.chunk_lists.resize_with(n_chunks, Vec::new);
        self.chunk_counts.resize_with(n_chunks, Vec::new);
        let (bvh, facet_of_key) = (&self.bvh, &self.facet_of_key);
        surface
            .nodes
            .par_chunks(CHUNK)
            .zip(self.chunk_lists.par_iter_mut().zip(self.chunk_counts.par_iter_mut()))
            .for_each(|(nodes, (list, counts))| {
                list.clear();
                counts.clear();
                for &n in nodes {
                    let p = x[n as usize];
                    let q = Aabb::new(Vector::new(p[0], p[1]), Vector::new(p[0], p[1]));
                    let start = list.len();
                    for leaf in bvh.intersect_aabb(&q) {
                        let k = facet_of_key[leaf as usize];
                        let f = surface.facets[k as usize].nodes;
                        if f[0] != n && f[1] != n {
                            list.push(k);
                        }
                    }
                    list[start..].sort_unstable();
                    counts.push((list.len() - start) as u32);
                }
            });
        let cand = &mut self.candidates;
        cand.offsets.clear();
        cand.items.clear();
        cand.offsets.push(0);
        let mut total = 0u32;
        for (list, counts) in self.chunk_lists.iter().zip(&self.chunk_counts) {
            for &c in counts {
                total += c;
                cand.offsets.push(total);
            }
            cand.items.extend_from_slice(list);
        }
    }

    /// Number of candidate pairs in the list.
    pub fn pairs(&self) -> usize {
        self.candidates.items.len()
    }
}

/// What a checkpoint keeps of a [`BroadPhase`]: everything its candidate
/// list and its decision to rebuild depend on. The tree itself is not kept:
/// it is rebuilt from the boxes of the last build when the checkpoint is
/// read, and its layout never changes the candidates (they are sorted per
/// node), so a restored run continues bit for bit.
#[derive(Serialize, Deserialize)]
struct SavedBroadPhase {
    margin: f64,
    /// `[min x, min y, max x, max y]` of each facet box at the last build,
    /// in the order of `keys`.
    boxes: Vec<[f64; 4]>,
    built_at: Vec<Vec2>,
    candidates: Csr,
    refits: u32,
    builds: u64,
    fresh: bool,
    changed: bool,
    keys: Vec<u32>,
    facet_of_key: Vec<u32>,
}

impl Serialize for BroadPhase {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        SavedBroadPhase {
            margin: self.margin,
            boxes: self.boxes.iter().map(|b| [b.mins.x, b.mins.y, b.maxs.x, b.maxs.y]).collect(),
            built_at: self.built_at.clone(),
            candidates: self.candidates.clone(),
            refits: self.refits,
            builds: self.builds,
            fresh: self.fresh,
            changed: self.changed,
            keys: self.keys.clone(),
            facet_of_key: self.facet_of_key.clone(),
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for BroadPhase {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let s = SavedBroadPhase::deserialize(deserializer)?;
        if s.boxes.len() != s.keys.len() {
            return Err(D::Error::custom(format!(
                "broad phase: {} boxes for {} tree leaves",
                s.boxes.len(),
                s.keys.len()
            )));
        }
        if s.keys.iter().any(|&k| k as usize >= s.facet_of_key.len()) {
            return Err(D::Error::custom("broad phase: a tree leaf has no facet entry"));
        }
        let boxes: Vec<Aabb> =
            s.boxes.iter().map(|b| Aabb::new(Vector::new(b[0], b[1]), Vector::new(b[2], b[3]))).collect();
        let mut bvh = Bvh::new();
        if boxes.len() < 3 {
            for (&k, bx) in s.keys.iter().zip(&boxes) {
                bvh.insert(*bx, k);
            }
        } else {
            bvh = Bvh::from_iter(BvhBuildStrategy::Binned, s.keys.iter().zip(&boxes).map(|(&k, bx)| (k as usize, *bx)));
        }
        Ok(Self {
            margin: s.margin,
            bvh,
            boxes,
            built_at: s.built_at,
            candidates: s.candidates,
            chunk_lists: Vec::new(),
            chunk_counts: Vec::new(),
            refits: s.refits,
            builds: s.builds,
            fresh: s.fresh,
            changed: s.changed,
            keys: s.keys,
            facet_of_key: s.facet_of_key,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit squares side by side with a 0.05 m gap.
    fn two_squares() -> (Surface, Vec<Vec2>) {
        let x =
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.05, 0.0], [2.05, 0.0], [2.05, 1.0], [1.05, 1.0]];
        let facets: Vec<([u32; 2], u16)> = vec![
            ([0, 1], 0),
            ([1, 2], 0),
            ([2, 3], 0),
            ([3, 0], 0),
            ([4, 5], 0),
            ([5, 6], 0),
            ([6, 7], 0),
            ([7, 4], 0),
        ];
        let apex = vec![[0.5, 0.5]; 8];
        (Surface::new(8, &facets, &x, &apex), x)
    }

    #[test]
    fn candidates_within_margin_only() {
        let (s, x) = two_squares();
        let mut bp = BroadPhase::new(0.1);
        assert!(bp.update(&s, &x));
        // node 1 (1, 0) is within 0.1 of the left facet (7, 4) of the right square
        let row = |n: usize| bp.candidates.row(s.index_of[n] as usize).to_vec();
        assert!(row(1).contains(&7));
        assert!(!row(1).contains(&0) && !row(1).contains(&1));
        // with a small margin, nothing across the gap
        let mut tight = BroadPhase::new(0.01);
        tight.update(&s, &x);
        assert!(!tight.candidates.row(s.index_of[1] as usize).contains(&7));
        // no rebuild until something moves half the margin
        assert!(!bp.update(&s, &x));
        let mut moved = x.clone();
        moved[5][0] += 0.049;
        assert!(!bp.needs_update(&s, &moved));
        moved[5][0] += 0.002;
        assert!(bp.update(&s, &moved));
    }
}
