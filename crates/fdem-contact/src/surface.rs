//! The free surfaces of a mesh: boundary facets with their interface law,
//! the boundary nodes, and per node its own facets.

use fdem_mesh::Csr;
use rayon::prelude::*;

use crate::{Vec2, CHUNK, NONE};

/// One boundary facet, oriented with the body on its left (outward normal
/// `(dy, −dx)/L`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceFacet {
    /// Start and end node (mesh ids).
    pub nodes: [u32; 2],
    /// Index of the interface law.
    pub law: u16,
    /// Reference length (m), for tributary lengths.
    pub length: f64,
    /// Deepest penetration accepted behind this facet (m): half the height
    /// of its element over it. A node deeper than this is on the far side.
    pub depth: f64,
    /// A stable identity that survives rebuilds of the surface (the solver
    /// uses `3 e + k`, edge `k` of element `e`), ascending along `facets`:
    /// lets the broad phase and the friction memory follow a facet through
    /// topology changes.
    pub key: u32,
    /// The boundary-node indices of `nodes` (derived, not saved: set by
    /// [`Surface::derive`]), so that a contact on this facet finds its
    /// nodes' rows without two more random reads of `index_of`.
    #[serde(skip)]
    pub ends: [u32; 2],
    /// The mesh id of the third node of the facet's element, [`NONE`] where
    /// the builder did not give it (derived, not saved: set by
    /// [`Surface::set_apexes`] after building or restoring). A node found
    /// behind the facet is inside that body only if it is inside this
    /// triangle: the depth rectangle behind a facet reaches past the
    /// triangle's sides, into whatever lies beside it.
    #[serde(skip, default = "no_apex")]
    pub apex: u32,
}

fn no_apex() -> u32 {
    NONE
}

/// The free surfaces of the current mesh.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Surface {
    /// All boundary facets.
    pub facets: Vec<SurfaceFacet>,
    /// Mesh ids of the nodes on any facet, ascending.
    pub nodes: Vec<u32>,
    /// For every mesh node its index in `nodes`, or [`NONE`].
    pub index_of: Vec<u32>,
    /// For every boundary node (index in `nodes`) the facets it belongs to.
    pub node_facets: Csr,
    /// For every boundary node at a corner of its body (its two facets'
    /// normals more than 30° apart in the reference configuration, see
    /// [`Surface::derive`]) the facet ending at it and the facet starting
    /// from it: each face bears on the other bodies by itself (two contacts
    /// per corner node). `[NONE, NONE]` for a node on a smooth stretch of
    /// surface (one contact, along the node's mean normal) or on more than
    /// two facets. Derived data: not saved, rebuilt on restore.
    #[serde(skip)]
    pub faces: Vec<[u32; 2]>,
    /// For every facet the facet that precedes it along the surface (ends
    /// at its first node) and the one that follows it (starts at its second
    /// node): [`NONE`] where there is none, [`MANY`] where more than one
    /// does (a node where the body touches itself). The narrow phase's
    /// corner test reads them instead of searching the end node's facets
    /// (several dependent random reads per candidate: 8% of a fragmenting
    /// impact's run). Derived data: not saved, rebuilt on restore.
    #[serde(skip)]
    pub links: Vec<[u32; 2]>,
}

/// [`Surface::links`] of a facet end that more than one facet continues.
pub const MANY: u32 = NONE - 1;

/// Fills `out` (resized to `len`, at least every key + 1) with each
/// key's facet index in `facets` (ascending keys), [`NONE`] for keys not
/// there. In parallel over fixed chunks of keys, each chunk's facets found
/// by a binary search: topology changes rebuild these maps at every crack
/// insertion, and a serial scatter over every facet was a serial pass of
/// each (docs/performance.md, "16 threads on the current code").
pub fn index_by_key(facets: &[SurfaceFacet], len: usize, out: &mut Vec<u32>) {
    // the serial scatter this replaced failed on a key out of range
    debug_assert!(facets.last().is_none_or(|f| (f.key as usize) < len), "a facet key beyond the map");
    debug_assert!(facets.windows(2).all(|w| w[0].key < w[1].key), "facet keys not ascending");
    out.clear();
    out.resize(len, NONE);
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, part)| {
        let lo = (c * CHUNK) as u64;
        let hi = lo + part.len() as u64;
        let start = facets.partition_point(|f| u64::from(f.key) < lo);
        for (i, f) in facets[start..].iter().enumerate().take_while(|(_, f)| u64::from(f.key) < hi) {
            part[(u64::from(f.key) - lo) as usize] = (start + i) as u32;
        }
    });
}

/// For each facet of `a`, the index of the facet of `b` with the same key
/// and the same nodes (both ascending by key), or [`NONE`]: which facets a
/// topology change kept. In parallel over fixed chunks of `a`, each
/// starting by a binary search in `b`; keys being unique (`3 e + k`), the
/// same result as one walk over both.
pub fn match_by_key(a: &[SurfaceFacet], b: &[SurfaceFacet], out: &mut Vec<u32>) {
    out.clear();
    out.resize(a.len(), NONE);
    out.par_chunks_mut(CHUNK).zip(a.par_chunks(CHUNK)).for_each(|(part, fa)| {
        let mut j = b.partition_point(|f| f.key < fa[0].key);
        for (o, f) in part.iter_mut().zip(fa) {
            while j < b.len() && b[j].key < f.key {
                j += 1;
            }
            if j < b.len() && b[j].key == f.key && b[j].nodes == f.nodes {
                *o = j as u32;
            }
        }
    });
}

impl Surface {
    /// Builds the surface of a mesh with `n_nodes` nodes from its boundary
    /// facets `(nodes, law)`, the reference positions and, per facet, the
    /// reference position of its element's third node.
    /// Facets are keyed by their position; see [`Surface::with_keys`].
    pub fn new(n_nodes: usize, facets: &[([u32; 2], u16)], x_ref: &[Vec2], apex: &[Vec2]) -> Self {
        let keys: Vec<u32> = (0..facets.len() as u32).collect();
        Self::with_keys(n_nodes, facets, x_ref, apex, &keys)
    }

    /// [`Surface::new`] with a stable key per facet (strictly ascending).
    pub fn with_keys(n_nodes: usize, facets: &[([u32; 2], u16)], x_ref: &[Vec2], apex: &[Vec2], keys: &[u32]) -> Self {
        debug_assert!(keys.windows(2).all(|w| w[0] < w[1]));
        // parallel (surfaces are rebuilt at every crack insertion); an
        // indexed collect keeps the order
        let surface_facets = facets
            .par_iter()
            .enumerate()
            .with_min_len(crate::CHUNK)
            .map(|(k, &([a, b], law))| {
                let (pa, pb) = (x_ref[a as usize], x_ref[b as usize]);
                let d = [pb[0] - pa[0], pb[1] - pa[1]];
                // a plain square root: `hypot` (careful about overflow, which
                // reference lengths never approach) is several times slower
                let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
                let c = apex[k];
                let height = ((c[0] - pa[0]) * d[1] - (c[1] - pa[1]) * d[0]).abs() / length;
                SurfaceFacet {
                    nodes: [a, b],
                    law,
                    length,
                    depth: 0.5 * height,
                    key: keys[k],
                    ends: [NONE; 2],
                    apex: NONE,
                }
            })
            .collect();
        Self::indexed(n_nodes, surface_facets, x_ref)
    }

    /// The surface of `facets` (ascending keys) on a mesh of `n_nodes`
    /// nodes: its boundary nodes, their facets and the derived data.
    ///
    /// In parallel, with the result of the serial passes it replaced (each
    /// node's facets in facet order; built serially this was 0.37% of the
    /// 10⁴ fragmenting impact at one thread, at every insertion check):
    /// the facet ends counted per node with atomic adds (integers: any
    /// order gives the same counts), the boundary nodes numbered by a
    /// prefix sum over fixed chunks of nodes, each node's facets placed in
    /// its row in any order and the row then sorted, which is facet order.
    fn indexed(n_nodes: usize, surface_facets: Vec<SurfaceFacet>, x_ref: &[Vec2]) -> Self {
        use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
        let degree: Vec<AtomicU32> = (0..n_nodes).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        surface_facets.par_iter().with_min_len(CHUNK).for_each(|f| {
            for n in f.nodes {
                degree[n as usize].fetch_add(1, Relaxed);
            }
        });
        let degree: Vec<u32> = degree.into_par_iter().map(AtomicU32::into_inner).collect();
        // boundary nodes before each fixed chunk of mesh nodes
        let mut before: Vec<u32> =
            degree.par_chunks(CHUNK).map(|c| c.iter().filter(|&&d| d > 0).count() as u32).collect();
        let mut total = 0;
        for b in &mut before {
            (*b, total) = (total, total + *b);
        }
        let mut index_of = vec![NONE; n_nodes];
        index_of.par_chunks_mut(CHUNK).zip(degree.par_chunks(CHUNK)).zip(&before).for_each(|((ix, d), &first)| {
            let mut next = first;
            for (i, &d) in ix.iter_mut().zip(d) {
                if d > 0 {
                    *i = next;
                    next += 1;
                }
            }
        });
        // (a parallel filter collects in order)
        let nodes: Vec<u32> = (0..n_nodes as u32).into_par_iter().filter(|&v| degree[v as usize] > 0).collect();
        debug_assert_eq!(nodes.len(), total as usize);
        // rows: offsets by a prefix sum of the boundary nodes' degrees over
        // fixed chunks, items placed through atomic cursors (any order),
        // then each row sorted (facet order)
        let nb = nodes.len();
        let mut first: Vec<u32> =
            nodes.par_chunks(CHUNK).map(|c| c.iter().map(|&v| degree[v as usize]).sum::<u32>()).collect();
        let mut end = 0;
        for f in &mut first {
            (*f, end) = (end, end + *f);
        }
        let mut offsets = vec![0u32; nb + 1];
        offsets[1..].par_chunks_mut(CHUNK).zip(nodes.par_chunks(CHUNK)).zip(&first).for_each(|((o, c), &f)| {
            let mut at = f;
            for (o, &v) in o.iter_mut().zip(c) {
                at += degree[v as usize];
                *o = at;
            }
        });
        let cursor: Vec<AtomicU32> = offsets[..nb].par_iter().map(|&o| AtomicU32::new(o)).collect();
        let items: Vec<AtomicU32> = (0..end).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        surface_facets.par_iter().enumerate().with_min_len(CHUNK).for_each(|(k, f)| {
            for n in f.nodes {
                let at = cursor[index_of[n as usize] as usize].fetch_add(1, Relaxed);
                items[at as usize].store(k as u32, Relaxed);
            }
        });
        let mut items: Vec<u32> = items.into_par_iter().map(AtomicU32::into_inner).collect();
        {
            // the items of each chunk of rows, then each row in it sorted
            let mut parts: Vec<(&mut [u32], usize)> = Vec::with_capacity(first.len());
            let mut rest = &mut items[..];
            for (c, &f) in first.iter().enumerate() {
                let to = offsets[((c + 1) * CHUNK).min(nb)];
                let (part, tail) = rest.split_at_mut((to - f) as usize);
                parts.push((part, c));
                rest = tail;
            }
            parts.par_iter_mut().for_each(|(part, c)| {
                let (lo, hi) = (*c * CHUNK, ((*c + 1) * CHUNK).min(nb));
                let base = offsets[lo];
                for b in lo..hi {
                    part[(offsets[b] - base) as usize..(offsets[b + 1] - base) as usize].sort_unstable();
                }
            });
        }
        let node_facets = Csr { offsets, items };
        let mut surface =
            Self { facets: surface_facets, nodes, index_of, node_facets, faces: Vec::new(), links: Vec::new() };
        surface.derive(x_ref);
        surface
    }

    /// The same surface under new node and element numbers (the solver's
    /// spatial renumbering, docs/renumbering.md): node `i` becomes
    /// `node_map[i]`, a facet keyed `k` is keyed `new_key(k)` (the solver
    /// maps `3 e + k` to `3 e' + k`), laws, lengths and depths are kept, and
    /// facets are put in ascending new keys, so that the result is what a
    /// fresh build on the renumbered mesh gives. `x_ref` are the reference
    /// positions in the new numbering. Also returns, per old facet, its new
    /// index, and per old boundary node, its new boundary index.
    pub fn relabel(
        &self,
        node_map: &[u32],
        new_key: impl Fn(u32) -> u32,
        x_ref: &[Vec2],
    ) -> (Self, Vec<u32>, Vec<u32>) {
        let mut order: Vec<(u32, u32)> =
            self.facets.iter().enumerate().map(|(k, f)| (new_key(f.key), k as u32)).collect();
        order.sort_unstable();
        let mut facet_map = vec![NONE; self.facets.len()];
        let facets = order
            .iter()
            .enumerate()
            .map(|(k, &(key, old))| {
                facet_map[old as usize] = k as u32;
                let f = &self.facets[old as usize];
                let apex = if f.apex == NONE { NONE } else { node_map[f.apex as usize] };
                SurfaceFacet { nodes: f.nodes.map(|n| node_map[n as usize]), key, ends: [NONE; 2], apex, ..*f }
            })
            .collect();
        let surface = Self::indexed(node_map.len(), facets, x_ref);
        let node_map_b = self.nodes.iter().map(|&n| surface.index_of[node_map[n as usize] as usize]).collect();
        (surface, facet_map, node_map_b)
    }

    /// Sets every facet's [`SurfaceFacet::apex`] from its key: `apex(key)`
    /// is the mesh id of the third node of the facet's element (the key's
    /// meaning is the builder's).
    pub fn set_apexes(&mut self, apex: impl Fn(u32) -> u32 + Sync) {
        self.facets.par_iter_mut().with_min_len(CHUNK).for_each(|f| f.apex = apex(f.key));
    }

    /// Sets the derived data that is not saved ([`SurfaceFacet::ends`],
    /// [`Surface::faces`], [`Surface::links`]) from the rest and the
    /// reference positions `x_ref`: after building or restoring.
    pub fn derive(&mut self, x_ref: &[Vec2]) {
        let index_of = &self.index_of;
        self.facets.par_iter_mut().with_min_len(crate::CHUNK).for_each(|f| {
            f.ends = f.nodes.map(|n| index_of[n as usize]);
        });
        // per boundary node, the facet ending at it and the one starting
        // from it ([`NONE`] or [`MANY`] where not one): both the corners and
        // the links read them
        let (nodes, facets, node_facets) = (&self.nodes, &self.facets, &self.node_facets);
        let at: Vec<[u32; 2]> = (0..nodes.len())
            .into_par_iter()
            .with_min_len(crate::CHUNK)
            .map(|b| {
                let mut io = [NONE; 2];
                for &k in node_facets.row(b) {
                    let slot = usize::from(facets[k as usize].nodes[1] != nodes[b]);
                    io[slot] = if io[slot] == NONE { k } else { MANY };
                }
                io
            })
            .collect();
        self.links = facets
            .par_iter()
            .with_min_len(crate::CHUNK)
            .map(|f| [at[f.ends[0] as usize][0], at[f.ends[1] as usize][1]])
            .collect();
        self.find_faces(x_ref, &at);
    }

    /// Fills [`Surface::faces`] from the reference positions `x_ref` and
    /// each boundary node's facets ending and starting there (`at`): a
    /// boundary node with exactly two facets, one ending and one starting at
    /// it, whose outward normals differ by more than 30° (`n₁·n₂ <
    /// cos 30°`) is a corner. The test is on the reference configuration,
    /// so a node's kind changes only with the topology (its angle changes
    /// only with strain).
    fn find_faces(&mut self, x_ref: &[Vec2], at: &[[u32; 2]]) {
        let normal = |k: u32| self.facet_normal(x_ref, k);
        // parallel (rebuilt at every crack insertion); the indexed collect
        // keeps the order
        self.faces = (0..self.nodes.len())
            .into_par_iter()
            .with_min_len(crate::CHUNK)
            .map(|b| {
                let [into, from] = at[b];
                if self.node_facets.row(b).len() != 2 || into >= MANY || from >= MANY {
                    return [NONE; 2];
                }
                let (m, n) = (normal(into), normal(from));
                if m[0] * n[0] + m[1] * n[1] < crate::SMOOTH_COS {
                    [into, from]
                } else {
                    [NONE; 2]
                }
            })
            .collect();
    }

    /// Outward normal (unit) of facet `f` at positions `x`: `(dy, −dx)/L`.
    /// (A plain square root: `hypot`'s care for overflow, which lengths of
    /// metres never approach, is several times slower, and topology
    /// changes compute this for every boundary node.)
    pub fn facet_normal(&self, x: &[Vec2], f: u32) -> Vec2 {
        let [a, b] = self.facets[f as usize].nodes;
        let (pa, pb) = (x[a as usize], x[b as usize]);
        let d = [pb[0] - pa[0], pb[1] - pa[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        [d[1] / len, -d[0] / len]
    }

    /// Mean outward normal (unit) of boundary node `b` at positions `x`:
    /// the normalised sum of its facets' normals (zero where they cancel).
    /// The same numbers as the narrow phase's node normal from the facet
    /// frames at `x`.
    pub fn mean_normal(&self, x: &[Vec2], b: usize) -> Vec2 {
        let mut n = [0.0; 2];
        for &f in self.node_facets.row(b) {
            let m = self.facet_normal(x, f);
            n = [n[0] + m[0], n[1] + m[1]];
        }
        let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
        if len > 0.0 {
            [n[0] / len, n[1] / len]
        } else {
            n
        }
    }

    /// Largest tributary length (m) boundary node `b` can have: half of each
    /// of its facets (for the stable step).
    pub fn tributary_max(&self, b: usize) -> f64 {
        self.node_facets.row(b).iter().map(|&k| 0.5 * self.facets[k as usize].length).sum()
    }

    /// Whether two facets share a node.
    pub fn adjacent(&self, f: u32, g: u32) -> bool {
        let (a, b) = (self.facets[f as usize].nodes, self.facets[g as usize].nodes);
        a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boundary nodes, their numbering and each node's facets (in
    /// facet order) that the parallel [`Surface::indexed`] builds are those
    /// of one serial pass over the facets, on 1, 2 and 3 threads: 900
    /// unit squares, counter-clockwise, their nodes numbered in a scrambled
    /// order among unused node ids, so that rows span several chunks and a
    /// row's facets arrive out of order.
    #[test]
    fn the_parallel_indexing_is_the_serial_passes() {
        let squares = 900;
        let n = 5 * squares;
        // a scrambled permutation of the node ids (7 919 is prime and does
        // not divide n); every fifth unused
        let ids: Vec<u32> = (0..n).map(|i| ((i * 7919) % n) as u32).collect();
        let mut x = vec![[0.0; 2]; n];
        let (mut facets, mut apex) = (Vec::new(), Vec::new());
        for q in 0..squares {
            let v: [u32; 4] = std::array::from_fn(|i| ids[5 * q + i]);
            let o = [2.0 * (q % 30) as f64, 2.0 * (q / 30) as f64];
            let corners = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
            for i in 0..4 {
                x[v[i] as usize] = [o[0] + corners[i][0], o[1] + corners[i][1]];
            }
            for i in 0..4 {
                facets.push(([v[i], v[(i + 1) % 4]], 0));
                apex.push(x[v[(i + 2) % 4] as usize]);
            }
        }
        let want = {
            let mut index_of = vec![NONE; n];
            let mut nodes = Vec::new();
            let on: Vec<bool> = (0..n as u32).map(|v| facets.iter().any(|(f, _)| f.contains(&v))).collect();
            for (v, &o) in on.iter().enumerate() {
                if o {
                    index_of[v] = nodes.len() as u32;
                    nodes.push(v as u32);
                }
            }
            let rows = Csr::from_pairs(
                nodes.len(),
                facets.iter().enumerate().flat_map(|(k, (f, _))| f.map(|v| (index_of[v as usize] as usize, k as u32))),
            );
            (index_of, nodes, rows)
        };
        assert!(want.1.len() > 3 * CHUNK && want.1.len() < n);
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let s = pool.install(|| Surface::new(n, &facets, &x, &apex));
            assert_eq!((&s.index_of, &s.nodes, &s.node_facets), (&want.0, &want.1, &want.2), "{threads} threads");
        }
    }

    #[test]
    fn square_surface() {
        // unit square, nodes 0..4 counter-clockwise, bottom facet a joint (law 1)
        let x = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let facets = [([0, 1], 1), ([1, 2], 0), ([2, 3], 0), ([3, 0], 0)];
        let apex = [[1.0, 1.0], [0.0, 0.0], [0.0, 0.0], [1.0, 1.0]];
        let s = Surface::new(4, &facets, &x, &apex);
        assert_eq!(s.nodes, vec![0, 1, 2, 3]);
        assert_eq!(s.tributary_max(0), 1.0);
        assert!(s.adjacent(0, 1) && !s.adjacent(0, 2));
        assert!((s.facets[0].depth - 0.5).abs() < 1e-15);
        // around the square: each facet's previous and next facet
        assert_eq!(s.links, vec![[3, 1], [0, 2], [1, 3], [2, 0]]);
    }

    /// Two triangles of one body meeting at a vertex (a bow tie: the body
    /// touches itself at node 2): two facets end there and two start
    /// there, so the links at that vertex are [`MANY`]; a lone facet has
    /// none.
    #[test]
    fn links_at_a_vertex_where_the_body_touches_itself() {
        let x = [[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [1.0, 1.0], [0.0, 1.0], [5.0, 5.0], [6.0, 5.0]];
        let facets = [([0, 1], 0), ([1, 2], 0), ([2, 0], 0), ([2, 3], 0), ([3, 4], 0), ([4, 2], 0), ([5, 6], 0)];
        let apex = [x[2], x[0], x[1], x[4], x[2], x[3], [5.5, 6.0]];
        let s = Surface::new(x.len(), &facets, &x, &apex);
        assert_eq!(s.links[0], [2, 1]);
        assert_eq!(s.links[1], [0, MANY]); // past node 2: facets 2 and 3 start there
        assert_eq!(s.links[2], [MANY, 0]); // before node 2: facets 1 and 5 end there
        assert_eq!(s.links[4], [3, 5]);
        assert_eq!(s.links[6], [NONE, NONE]);
    }

    /// The surface of separate triangles (every edge free), keyed `3 e + k`
    /// like the solver's, with edge 1 of each triangle on law 1.
    fn triangles_surface(x: &[Vec2], tris: &[[u32; 3]]) -> Surface {
        let mut list = Vec::new();
        let (mut apex, mut keys) = (Vec::new(), Vec::new());
        for (e, t) in tris.iter().enumerate() {
            for k in 0..3 {
                list.push(([t[k], t[(k + 1) % 3]], u16::from(k == 1)));
                apex.push(x[t[(k + 2) % 3] as usize]);
                keys.push((3 * e + k) as u32);
            }
        }
        Surface::with_keys(x.len(), &list, x, &apex, &keys)
    }

    #[test]
    fn relabelled_surface_is_the_surface_of_the_relabelled_mesh() {
        let x = [
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [3.0, 0.0],
            [4.0, 0.0],
            [3.0, 2.0],
            [0.0, 5.0],
            [1.0, 4.0],
            [1.0, 6.0],
        ];
        let tris = [[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        let old = triangles_surface(&x, &tris);
        // new node i is old node_order[i]; new element j is old elem_order[j]
        let node_order = [5u32, 8, 0, 3, 7, 1, 4, 2, 6];
        let elem_order = [2u32, 0, 1];
        let inv = |order: &[u32]| {
            let mut map = vec![0u32; order.len()];
            order.iter().enumerate().for_each(|(new, &o)| map[o as usize] = new as u32);
            map
        };
        let (node_map, elem_map) = (inv(&node_order), inv(&elem_order));
        let x_new: Vec<Vec2> = node_order.iter().map(|&o| x[o as usize]).collect();
        let tris_new: Vec<[u32; 3]> =
            elem_order.iter().map(|&o| tris[o as usize].map(|v| node_map[v as usize])).collect();
        let (relabelled, facet_map, b_map) = old.relabel(&node_map, |k| 3 * elem_map[(k / 3) as usize] + k % 3, &x_new);
        assert_eq!(relabelled, triangles_surface(&x_new, &tris_new));
        for (f, facet) in old.facets.iter().enumerate() {
            let moved = &relabelled.facets[facet_map[f] as usize];
            assert_eq!(moved.nodes, facet.nodes.map(|v| node_map[v as usize]));
            assert_eq!(moved.law, facet.law);
        }
        for (b, &node) in old.nodes.iter().enumerate() {
            assert_eq!(relabelled.nodes[b_map[b] as usize], node_map[node as usize]);
        }
    }
}
