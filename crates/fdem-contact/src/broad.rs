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
//! the leaves that changed, and [`BroadPhase::carry_over`] keeps the
//! candidate lists of the unchanged nodes and facets instead of querying
//! every boundary node again.
//!
//! Over 800 lines with its unit tests; the code itself is about 620.
//!
//! [`SurfaceFacet::key`]: crate::SurfaceFacet::key

use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
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
    /// Scratch of the tree's periodic rebuild, kept so that the rebuild
    /// reuses its buffers (and the tree's) instead of allocating.
    workspace: BvhWorkspace,
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
    /// A bound (m) on how far any node has moved since the last scan of
    /// the boundary nodes' positions ([`BroadPhase::note_motion`]).
    moved: f64,
    /// How far (m) every boundary node could still move after that scan
    /// without any having moved more than half the margin since the build:
    /// while `moved` stays below it, [`update`](Self::update) need not scan.
    /// Not saved: a restored run scans at its first update.
    slack: f64,
}

/// Relative and absolute (m) allowances for round-off in the motion bound:
/// the positions' own updates and the distances computed from them.
const SLACK_REL: f64 = 1e-9;
const SLACK_ABS: f64 = 1e-9;

impl BroadPhase {
    /// An empty broad phase with box enlargement `margin` (m); the first
    /// [`update`](Self::update) builds it.
    pub fn new(margin: f64) -> Self {
        Self {
            margin,
            bvh: Bvh::new(),
            workspace: BvhWorkspace::default(),
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
            moved: 0.0,
            slack: 0.0,
        }
    }

    /// Notes a change of the surface (a topology change): the next update
    /// brings the tree and the candidate list up to date.
    pub fn invalidate(&mut self) {
        self.changed = true;
    }

    /// Forgets the tree and the lists: the next update builds both from
    /// scratch (after the facets were relabelled, when the old tree's
    /// layout no longer follows the facets' order).
    pub fn reset(&mut self) {
        self.fresh = true;
    }

    /// Whether some boundary node has moved more than half the margin since
    /// the last build.
    pub fn needs_update(&self, surface: &Surface, x: &[Vec2]) -> bool {
        self.stale(surface) || self.farthest(surface, x) > 0.25 * self.margin * self.margin
    }

    /// Whether the list must be rebuilt whatever the positions: never built,
    /// reset, or the surface has changed since.
    fn stale(&self, surface: &Surface) -> bool {
        self.fresh || self.changed || self.built_at.len() != surface.nodes.len()
    }

    /// The largest squared distance (m²) of a boundary node from where it
    /// was at the last build; infinite if any is NaN.
    fn farthest(&self, surface: &Surface, x: &[Vec2]) -> f64 {
        surface
            .nodes
            .par_iter()
            .zip(self.built_at.par_iter())
            .with_min_len(CHUNK)
            .map(|(&n, b)| {
                let p = x[n as usize];
                let (dx, dy) = (p[0] - b[0], p[1] - b[1]);
                let d2 = dx * dx + dy * dy;
                if d2.is_nan() {
                    f64::INFINITY
                } else {
                    d2
                }
            })
            .reduce(|| 0.0, f64::max)
    }

    /// Notes that no node has moved more than `distance` (m) in a step:
    /// the time loop passes `Δt max|v|` of each step's node update (an
    /// infinite or NaN distance forces the next scan).
    pub fn note_motion(&mut self, distance: f64) {
        self.moved =
            if distance.is_finite() { self.moved + distance * (1.0 + SLACK_REL) + 1e-12 } else { f64::INFINITY };
    }

    /// Rebuilds (or refits) the tree and the candidate list if needed;
    /// returns whether it did. The same decision as
    /// [`needs_update`](Self::needs_update), without its scan of every
    /// boundary node while the motion noted since the last scan
    /// ([`note_motion`](Self::note_motion)) cannot have taken any node past
    /// half the margin: at the paper's scale the list is rebuilt about
    /// every hundred late steps, and the scan ran at every one of them.
    pub fn update(&mut self, surface: &Surface, x: &[Vec2]) -> bool {
        if !self.stale(surface) {
            if self.moved < self.slack {
                return false;
            }
            let far = self.farthest(surface, x);
            if far <= 0.25 * self.margin * self.margin {
                self.moved = 0.0;
                self.slack = 0.5 * self.margin * (1.0 - SLACK_REL) - far.sqrt() * (1.0 + SLACK_REL) - SLACK_ABS;
                return false;
            }
        }
        self.build(surface, x);
        true
    }

    /// Builds the tree and candidate list now.
    pub fn build(&mut self, surface: &Surface, x: &[Vec2]) {
        let m = self.margin;
        let nf = surface.facets.len();
        self.boxes.resize(nf, Aabb::new_invalid());
        self.boxes
            .par_iter_mut()
            .zip(surface.facets.par_iter())
            .with_min_len(CHUNK)
            .for_each(|(bx, f)| *bx = facet_box(x, f.nodes, m));
        if self.fresh || self.changed {
            // key → facet of the new surface
            let max_key = surface.facets.last().map_or(0, |f| f.key as usize + 1);
            let len = max_key.max(self.keys.last().map_or(0, |&k| k as usize + 1));
            crate::surface::index_by_key(&surface.facets, len, &mut self.facet_of_key);
        }
        if self.fresh || nf < 3 {
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
            if self.refits + 1 >= REFITS_PER_REBUILD {
                // the same leaves in a new tree, in the buffers of the old
                // (the candidate lists are sorted by facet, so they do not
                // depend on the tree's shape)
                self.bvh.rebuild(&mut self.workspace, BvhBuildStrategy::Binned);
                self.refits = 0;
            } else {
                self.bvh.refit_without_opt();
                self.refits += 1;
            }
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
        // every node is where it was built
        self.moved = 0.0;
        self.slack = 0.5 * self.margin * (1.0 - SLACK_REL) - SLACK_ABS;
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
                        if f[0] != n && f[1] != n && near(x, f, p, m) {
                            list.push(k);
                        }
                    }
                    list[start..].sort_unstable();
                    counts.push((list.len() - start) as u32);
                }
            });
        self.join_chunk_lists();
    }

    /// Carries the tree and the candidate list over a topology change from
    /// `old` to `new` (the same mesh nodes, renumbered facets and boundary
    /// nodes) at positions `x`, instead of rebuilding and re-querying every
    /// boundary node. With `T` the last build and `m` the margin, every
    /// node stays within `m/2` of where it was at `T` until the next build,
    /// so within `m` of where it is now; a node created now stays within
    /// `m/2` of here. Then:
    ///
    /// - a pair of a facet kept (same key, same two nodes) and a node that
    ///   was on the surface keeps its standing from `T`;
    /// - a new facet (new key, or a key whose nodes changed) can reach a
    ///   node only if their boxes are within `2m` now: it enters the tree
    ///   with its box enlarged by `2m` and every boundary node is tested
    ///   against that box;
    /// - a node new to the surface is queried against the whole tree (kept
    ///   facets' boxes from `T` enlarged by `m`, new ones by `2m`) and
    ///   remembered at its position now.
    ///
    /// The lists are supersets of what a fresh build would give (extra
    /// pairs are never in contact; the narrow phase only acts on
    /// penetrations), sorted per node, and depend on nothing but the saved
    /// state, so a restored run continues bit for bit. Falls back to a full
    /// rebuild at the next [`update`](Self::update) when the list is not
    /// built yet or the margin grew.
    pub fn carry_over(&mut self, old: &Surface, new: &Surface, x: &[Vec2], margin: f64) {
        let built = !self.fresh
            && !self.changed
            && self.built_at.len() == old.nodes.len()
            && self.candidates.offsets.len() == old.nodes.len() + 1
            && self.boxes.len() == old.facets.len()
            && margin <= self.margin;
        self.margin = margin;
        if !built {
            self.changed = true;
            return;
        }
        // the kept nodes keep their build positions: scan at the next update
        self.slack = 0.0;
        let m = margin;
        let max_key = new.facets.last().map_or(0, |f| f.key as usize + 1);
        // old facet → new facet where it is kept (same key, same nodes),
        // else NONE, and back: walks, both lists ascending by key (binary
        // searches took most of this function at the paper's scale), in
        // parallel over chunks, each started by a binary search
        let (mut old_to_new, mut new_to_old) = (Vec::new(), Vec::new());
        crate::surface::match_by_key(&old.facets, &new.facets, &mut old_to_new);
        crate::surface::match_by_key(&new.facets, &old.facets, &mut new_to_old);
        for (j, f) in old.facets.iter().enumerate() {
            if old_to_new[j] == crate::NONE {
                self.bvh.remove(f.key);
            }
        }
        // the kept facets' boxes copied and the new ones' made in parallel;
        // the new ones go into the tree in facet order (serial: few)
        let mut boxes = Vec::with_capacity(new.facets.len());
        boxes.par_extend(new.facets.par_iter().zip(&new_to_old).with_min_len(CHUNK).map(|(f, &j)| {
            if j != crate::NONE {
                self.boxes[j as usize]
            } else {
                facet_box(x, f.nodes, 2.0 * m)
            }
        }));
        let fresh: Vec<u32> =
            (0..new.facets.len() as u32).into_par_iter().filter(|&i| new_to_old[i as usize] == crate::NONE).collect();
        let fresh_boxes: Vec<Aabb> = fresh.iter().map(|&i| boxes[i as usize]).collect();
        for (&i, bx) in fresh.iter().zip(&fresh_boxes) {
            self.bvh.insert(*bx, new.facets[i as usize].key);
        }
        self.boxes = boxes;
        // the fresh boxes in a grid, so that a node tests only those of its
        // cell (every node against every fresh box took 6% of a
        // fragmenting impact's run, two binary searches per node over the
        // boxes sorted by their left side 1.6%); the node's list is sorted
        // after, so the order they are found in does not matter
        let grid = BoxGrid::new(&fresh_boxes);
        crate::surface::index_by_key(&new.facets, max_key, &mut self.facet_of_key);
        self.keys.clear();
        self.keys.par_extend(new.facets.par_iter().map(|f| f.key));
        // every boundary node's list, chunk by chunk, into reused buffers
        let n_chunks = new.nodes.len().div_ceil(CHUNK);
        self.chunk_lists.resize_with(n_chunks, Vec::new);
        self.chunk_counts.resize_with(n_chunks, Vec::new);
        let mut built_at = vec![[0.0; 2]; new.nodes.len()];
        let (bvh, facet_of_key, old_cand, old_at) = (&self.bvh, &self.facet_of_key, &self.candidates, &self.built_at);
        let (fresh, fresh_boxes, old_to_new, grid) = (&fresh, &fresh_boxes, &old_to_new, &grid);
        new.nodes
            .par_chunks(CHUNK)
            .zip(built_at.par_chunks_mut(CHUNK))
            .zip(self.chunk_lists.par_iter_mut().zip(self.chunk_counts.par_iter_mut()))
            .for_each(|((nodes, at), (list, counts))| {
                list.clear();
                counts.clear();
                for (&n, at) in nodes.iter().zip(at) {
                    let p = x[n as usize];
                    // not the node's own facet, and (for a facet new to
                    // the tree, or a node new to the surface) within `2m`
                    // of it now: their relative motion until the next
                    // build is at most `1.5m`
                    let keep = |k: u32| {
                        let f = new.facets[k as usize].nodes;
                        f[0] != n && f[1] != n && near(x, f, p, 2.0 * m)
                    };
                    let start = list.len();
                    let ob = old.index_of.get(n as usize).copied().unwrap_or(crate::NONE);
                    if ob == crate::NONE {
                        let q = Aabb::new(Vector::new(p[0], p[1]), Vector::new(p[0], p[1]));
                        list.extend(
                            bvh.intersect_aabb(&q).map(|leaf| facet_of_key[leaf as usize]).filter(|&k| keep(k)),
                        );
                        *at = p;
                    } else {
                        list.extend(
                            old_cand
                                .row(ob as usize)
                                .iter()
                                .map(|&j| old_to_new[j as usize])
                                .filter(|&k| k != crate::NONE),
                        );
                        for &i in grid.at(p) {
                            let (k, bx) = (fresh[i as usize], &fresh_boxes[i as usize]);
                            let inside =
                                bx.mins.x <= p[0] && p[0] <= bx.maxs.x && bx.mins.y <= p[1] && p[1] <= bx.maxs.y;
                            if inside && keep(k) {
                                list.push(k);
                            }
                        }
                        *at = old_at[ob as usize];
                    }
                    list[start..].sort_unstable();
                    counts.push((list.len() - start) as u32);
                }
            });
        self.built_at = built_at;
        self.join_chunk_lists();
    }

    /// The candidate list from the per-chunk lists and counts, in node
    /// order (reusing the list's buffers). Serial: it runs at broad-phase
    /// rebuilds inside the time loop too, where nothing may be allocated
    /// (a parallel copy needs the chunks' slices listed; its gain at
    /// insertions was not measurable on 16 threads, 2026-11-28).
    fn join_chunk_lists(&mut self) {
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

/// Boxes binned in a uniform grid of square cells at least as wide as
/// the largest box side (so a box overlaps at most four cells; coarser
/// when the boxes are spread so thinly that the grid would have more than
/// about four cells per box): [`BoxGrid::at`] gives the boxes whose extent
/// overlaps the cell of a point, a superset of those that contain it.
struct BoxGrid {
    origin: Vec2,
    cell: f64,
    dims: [usize; 2],
    /// Box indices per cell (row-major), ascending within a cell.
    cells: Csr,
}

impl BoxGrid {
    fn new(boxes: &[Aabb]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut side = 0.0_f64;
        for b in boxes {
            lo = [lo[0].min(b.mins.x), lo[1].min(b.mins.y)];
            hi = [hi[0].max(b.maxs.x), hi[1].max(b.maxs.y)];
            side = side.max(b.maxs.x - b.mins.x).max(b.maxs.y - b.mins.y);
        }
        if boxes.is_empty() || side <= 0.0 || !side.is_finite() {
            return Self { origin: [0.0; 2], cell: 1.0, dims: [0, 0], cells: Csr::from_pairs(0, std::iter::empty()) };
        }
        let span = [hi[0] - lo[0], hi[1] - lo[1]];
        let most = 4 * boxes.len() + 64;
        let mut cell = side;
        while (span[0] / cell + 1.0) * (span[1] / cell + 1.0) > most as f64 {
            cell *= 2.0;
        }
        let dims = [(span[0] / cell) as usize + 1, (span[1] / cell) as usize + 1];
        let index = |v: f64, o: f64, n: usize| (((v - o) / cell) as usize).min(n - 1);
        let cells = Csr::from_pairs(
            dims[0] * dims[1],
            boxes.iter().enumerate().flat_map(|(i, b)| {
                let (x0, x1) = (index(b.mins.x, lo[0], dims[0]), index(b.maxs.x, lo[0], dims[0]));
                let (y0, y1) = (index(b.mins.y, lo[1], dims[1]), index(b.maxs.y, lo[1], dims[1]));
                (y0..=y1).flat_map(move |y| (x0..=x1).map(move |x| (y * dims[0] + x, i as u32)))
            }),
        );
        Self { origin: lo, cell, dims, cells }
    }

    /// The boxes binned in the cell of `p` (none outside the grid).
    fn at(&self, p: Vec2) -> &[u32] {
        let (fx, fy) = ((p[0] - self.origin[0]) / self.cell, (p[1] - self.origin[1]) / self.cell);
        // (a NaN fails both tests)
        if !(fx >= 0.0 && fy >= 0.0) || fx >= self.dims[0] as f64 || fy >= self.dims[1] as f64 {
            return &[];
        }
        self.cells.row(fy as usize * self.dims[0] + fx as usize)
    }
}

/// The box of facet `nodes` at `x`, extended past both ends by the
/// narrow phase's end slack ([`XI_SLACK`](crate::narrow::XI_SLACK)) of its
/// length, then enlarged by `margin (1 + XI_SLACK)`: a node just past a
/// facet's end that the narrow phase would take is listed however long the
/// facet (without the extension, a node past the end of a long facet was
/// listed or not depending on when the list was made). The extra
/// `XI_SLACK · margin` covers the extension's own motion while the
/// endpoints move by up to `margin / 2` each (stretching or turning the
/// facet) before the next build.
fn facet_box(x: &[Vec2], nodes: [u32; 2], margin: f64) -> Aabb {
    let s = crate::narrow::XI_SLACK;
    let (a, b) = (x[nodes[0] as usize], x[nodes[1] as usize]);
    let d = [s * (b[0] - a[0]), s * (b[1] - a[1])];
    let (p, q) = ([a[0] - d[0], a[1] - d[1]], [b[0] + d[0], b[1] + d[1]]);
    let pad = margin * (1.0 + s);
    Aabb::new(
        Vector::new(p[0].min(q[0]) - pad, p[1].min(q[1]) - pad),
        Vector::new(p[0].max(q[0]) + pad, p[1].max(q[1]) + pad),
    )
}

/// Whether point `p` is within `margin (1 + XI_SLACK)` of facet `nodes` at
/// `x`, the facet extended past both ends by the end slack: the region that
/// [`facet_box`] stands for, without the box's corners. The box holds up to
/// 2.3 times the area for a diagonal facet (a 1 m facet, 0.2 m margin), so
/// this halves the candidate pairs the narrow phase tests there. A pair
/// farther apart at a build cannot touch before the next one: their
/// relative motion stays below the margin.
#[inline]
fn near(x: &[Vec2], nodes: [u32; 2], p: Vec2, margin: f64) -> bool {
    let s = crate::narrow::XI_SLACK;
    let (a, b) = (x[nodes[0] as usize], x[nodes[1] as usize]);
    let d = [b[0] - a[0], b[1] - a[1]];
    let r = [p[0] - a[0], p[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = if l2 > 0.0 { ((r[0] * d[0] + r[1] * d[1]) / l2).clamp(-s, 1.0 + s) } else { 0.0 };
    let q = [r[0] - t * d[0], r[1] - t * d[1]];
    let pad = margin * (1.0 + s);
    q[0] * q[0] + q[1] * q[1] <= pad * pad
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
            workspace: BvhWorkspace::default(),
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
            moved: 0.0,
            slack: 0.0,
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

    /// The grid of boxes lists, at any point, every box that contains it
    /// (random boxes of very different sizes, spread thinly and densely,
    /// points inside, on the edges and outside them).
    #[test]
    fn the_box_grid_lists_every_box_containing_a_point() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for (count, extent) in [(1, 1.0), (30, 0.2), (300, 50.0), (2000, 3.0)] {
            let boxes: Vec<Aabb> = (0..count)
                .map(|_| {
                    let (x, y, w, h) = (next() * extent, next() * extent, 0.2 * next() * next(), 0.1 * next());
                    Aabb::new(Vector::new(x, y), Vector::new(x + w, y + h))
                })
                .collect();
            let grid = BoxGrid::new(&boxes);
            let mut found = 0;
            for i in 0..4000 {
                let b = &boxes[i % count];
                // inside, at a corner, or anywhere
                let p = match i % 3 {
                    0 => [b.mins.x + next() * (b.maxs.x - b.mins.x), b.mins.y + next() * (b.maxs.y - b.mins.y)],
                    1 => [b.maxs.x, b.maxs.y],
                    _ => [next() * extent * 1.2 - 0.1 * extent, next() * extent * 1.2 - 0.1 * extent],
                };
                let listed = grid.at(p);
                for (k, c) in boxes.iter().enumerate() {
                    if c.mins.x <= p[0] && p[0] <= c.maxs.x && c.mins.y <= p[1] && p[1] <= c.maxs.y {
                        assert!(listed.contains(&(k as u32)), "box {k} {c:?} holds {p:?}, not listed");
                        found += 1;
                    }
                }
            }
            assert!(found >= 2666, "{found}");
        }
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
        // but a node past a facet's end by up to 5% of its length (the
        // narrow phase's slack) is listed: node 4 put at (1.005, -0.04), below
        // the end (1, 0) of facet 1, (1, 0)-(1, 1)
        let mut below: Vec<Vec2> = x.clone();
        below[4] = [1.005, -0.04];
        tight.build(&s, &below);
        assert!(tight.candidates.row(s.index_of[4] as usize).contains(&1));
        // no rebuild until something moves half the margin
        assert!(!bp.update(&s, &x));
        let mut moved = x.clone();
        moved[5][0] += 0.049;
        assert!(!bp.needs_update(&s, &moved));
        moved[5][0] += 0.002;
        // (without the motion noted, the update trusts that nothing moved)
        assert!(!bp.update(&s, &moved));
        bp.note_motion(0.051);
        assert!(bp.update(&s, &moved));
    }

    /// `update` decides as `needs_update` would, step after step, whether
    /// it scans or skips the scan on the motion noted: nodes drift by
    /// random steps up to `a` (noted as `a √2`), some fast, some at rest,
    /// through many rebuilds and a carry-over.
    #[test]
    fn update_skips_its_scan_only_when_no_node_can_be_past_half_the_margin() {
        let margin = 0.1;
        let (facets, keys, x0, apex) = row_of_squares(4);
        let s = Surface::with_keys(x0.len(), &facets, &x0, &apex, &keys);
        let mut bp = BroadPhase::new(margin);
        let mut x = x0.clone();
        assert!(bp.update(&s, &x));
        let (mut seed, mut builds, mut skipped) = (11u64, 0, 0);
        for step in 0..4000 {
            // a steady drift of node 5, jiggles of everything, quiet spells
            let a = if (step / 500) % 2 == 0 { 2e-3 } else { 1e-4 };
            let mut next = jiggle(&x, a, &mut seed);
            next[5][0] = x[5][0] + 0.8 * a;
            next[5][1] = x[5][1];
            x = next;
            bp.note_motion(a * 2f64.sqrt());
            if step == 2500 {
                // a topology change carried over: the next update scans
                bp.carry_over(&s, &s, &x, margin);
            }
            let expected = bp.needs_update(&s, &x);
            let slack_before = bp.moved < bp.slack;
            assert_eq!(bp.update(&s, &x), expected, "step {step}");
            builds += usize::from(expected);
            skipped += usize::from(slack_before && !expected);
        }
        assert!(builds > 20 && skipped > 2000, "{builds} builds, {skipped} scans skipped");
        // an unbounded step forces the scan
        bp.note_motion(f64::NAN);
        assert!(bp.moved >= bp.slack);
    }

    /// Facets with laws, their keys, node positions, facet apexes.
    type Squares = (Vec<([u32; 2], u16)>, Vec<u32>, Vec<Vec2>, Vec<Vec2>);

    /// A row of `k` unit squares 0.05 m apart; the facets of square `i`
    /// carry keys `10 i + side`.
    fn row_of_squares(k: usize) -> Squares {
        let (mut facets, mut keys, mut x, mut apex) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..k {
            let x0 = 1.05 * i as f64;
            let b = x.len() as u32;
            x.extend([[x0, 0.0], [x0 + 1.0, 0.0], [x0 + 1.0, 1.0], [x0, 1.0]]);
            for side in 0..4u32 {
                facets.push(([b + side, b + (side + 1) % 4], 0));
                keys.push(10 * i as u32 + side);
                apex.push([x0 + 0.5, 0.5]);
            }
        }
        (facets, keys, x, apex)
    }

    /// Deterministic displacements in `[-a, a]²`.
    fn jiggle(x: &[Vec2], a: f64, seed: &mut u64) -> Vec<Vec2> {
        let mut r = || {
            *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        x.iter().map(|p| [p[0] + a * r(), p[1] + a * r()]).collect()
    }

    /// Node `n` inside facet `f`'s box enlarged by `eps`: with every node
    /// within 0.49 m of where the list was made, such a pair must be listed
    /// for `eps` up to 0.02 m (the slack left from m/2).
    fn touching(s: &Surface, x: &[Vec2], n: u32, f: usize, eps: f64) -> bool {
        let [a, b] = s.facets[f].nodes.map(|v| x[v as usize]);
        let p = x[n as usize];
        let nodes = s.facets[f].nodes;
        nodes[0] != n
            && nodes[1] != n
            && a[0].min(b[0]) - eps <= p[0]
            && p[0] <= a[0].max(b[0]) + eps
            && a[1].min(b[1]) - eps <= p[1]
            && p[1] <= a[1].max(b[1]) + eps
    }

    #[test]
    fn carried_over_lists_cover_every_pair_that_can_touch_before_the_next_build() {
        let margin = 0.1;
        let mut seed = 7;
        let mut checked = 0;
        for trial in 0..40 {
            let (facets, keys, x0, apex) = row_of_squares(4);
            let n0 = x0.len();
            let old = Surface::with_keys(n0 + 1, &facets, &x0, &apex, &keys);
            let mut bp = BroadPhase::new(margin);
            let x0: Vec<Vec2> = x0.into_iter().chain([[0.0, 0.0]]).collect();
            bp.build(&old, &x0);
            // everything moves, up to just under half the margin
            let mut x1 = jiggle(&x0, 0.49 * margin / 2f64.sqrt(), &mut seed);
            // a crack: the top facet of square 1 (nodes 6, 7) is split by a
            // new node at its middle, and square 2's left side gets a copy
            // of its lower node (node 8 → the new node n0)
            x1[n0] = [0.5 * (x1[6][0] + x1[7][0]), 0.5 * (x1[6][1] + x1[7][1])];
            let mut nf = facets.clone();
            let mut nk = keys.clone();
            let top = nf.iter().position(|f| f.0 == [6, 7]).unwrap();
            nf[top] = ([6, n0 as u32], 0);
            nf.push(([n0 as u32, 7], 0));
            nk.push(1000);
            let left = nf.iter().position(|f| f.0 == [11, 8]).unwrap();
            nf[left] = ([11, 8], 0);
            if trial % 2 == 1 {
                // the other change: a facet keeps its key but not its nodes
                nf[left] = ([11, n0 as u32], 0);
            }
            let mut napex = apex.clone();
            napex.push(apex[top]);
            let new = Surface::with_keys(n0 + 1, &nf, &x1, &napex, &nk);
            assert!(!bp.needs_update(&old, &x1));
            bp.carry_over(&old, &new, &x1, margin);
            // a superset of a fresh build here
            let mut fresh = BroadPhase::new(margin);
            fresh.build(&new, &x1);
            for b in 0..new.nodes.len() {
                let row = bp.candidates.row(b);
                for f in fresh.candidates.row(b) {
                    assert!(row.contains(f), "trial {trial}: node {} lost facet {f}", new.nodes[b]);
                }
                assert!(row.windows(2).all(|w| w[0] < w[1]));
            }
            // and any motion that does not trigger a rebuild finds every
            // touching pair listed
            for _ in 0..50 {
                let mut x2 = x1.clone();
                for (b, &n) in new.nodes.iter().enumerate() {
                    let at = bp.built_at[b];
                    let p = jiggle(&[at], 0.49 * margin / 2f64.sqrt(), &mut seed)[0];
                    x2[n as usize] = p;
                }
                assert!(!bp.needs_update(&new, &x2));
                for (b, &n) in new.nodes.iter().enumerate() {
                    for f in 0..new.facets.len() {
                        if touching(&new, &x2, n, f, 0.01 * margin) {
                            assert!(bp.candidates.row(b).contains(&(f as u32)), "trial {trial}: node {n}, facet {f}");
                            checked += 1;
                        }
                    }
                }
            }
        }
        // pairs across the 0.05 m gaps and the new facets' own neighbours
        assert!(checked > 1_000, "{checked}");
    }
}
