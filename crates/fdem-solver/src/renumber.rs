//! Spatial renumbering of nodes and elements during a run
//! (docs/renumbering.md).
//!
//! Crack insertion appends the nodes and elements it creates at the end of
//! their arrays, so after tens of thousands of insertions a crack face's
//! node, the facet it presses on and the elements around both lie far
//! apart in memory and the passes wait on it. A renumbering puts nodes and
//! elements back in the order of a Hilbert curve through their current
//! positions. It is a pure relabelling: every stored number moves with its
//! entity and none is recomputed, so the next step computes the same
//! physics, up to the order of floating-point sums.
//!
//! Ids do not change. Everything the simulation reports or takes (node and
//! element rows, ids inside results, error messages, `deactivate`,
//! prescribed velocities) is by id, the creation order: the ids of the
//! model, then crack insertion's new nodes and elements in the order they
//! were made. [`Layout`] maps ids to the solver's internal indices.

use std::borrow::Cow;

use fdem_element::Vec2;

use crate::simulation::Simulation;
use crate::topology::active_node_elements;
use crate::NONE;

/// Where each node and element sits inside the solver: internal index ↔
/// id. Both maps cover the entities that existed at the last renumbering;
/// any entity made since sits at the index equal to its id (insertion
/// appends, and there are as many indices as ids). Empty: no renumbering
/// yet, every index is the id.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Layout {
    /// Id of the node at each internal index.
    node_id: Vec<u32>,
    /// Internal index of each node id.
    node_index: Vec<u32>,
    /// Id of the element at each internal index.
    elem_id: Vec<u32>,
    /// Internal index of each element id.
    elem_index: Vec<u32>,
    /// Element count after the last renumbering (or at the start): the
    /// next one is due once insertion has grown it by the set fraction.
    pub base: u64,
    /// Renumberings so far.
    pub count: u64,
}

fn lookup(map: &[u32], i: u32) -> u32 {
    map.get(i as usize).copied().unwrap_or(i)
}

/// `rows` (one per internal index) in id order.
fn by_id<'a, T: Clone>(ids: &[u32], rows: &'a [T]) -> Cow<'a, [T]> {
    if ids.is_empty() {
        return Cow::Borrowed(rows);
    }
    let mut out = rows.to_vec();
    for (i, &id) in ids.iter().enumerate() {
        out[id as usize] = rows[i].clone();
    }
    Cow::Owned(out)
}

impl Layout {
    /// A layout in creation order for a model of `elements` elements.
    pub fn new(elements: usize) -> Self {
        Self { base: elements as u64, ..Self::default() }
    }

    /// Id of the node at internal index `i`.
    #[inline]
    pub fn node_id(&self, i: u32) -> u32 {
        lookup(&self.node_id, i)
    }

    /// Internal index of node `id`.
    #[inline]
    pub fn node_index(&self, id: u32) -> u32 {
        lookup(&self.node_index, id)
    }

    /// Id of the element at internal index `i`.
    #[inline]
    pub fn elem_id(&self, i: u32) -> u32 {
        lookup(&self.elem_id, i)
    }

    /// Internal index of element `id`.
    #[inline]
    pub fn elem_index(&self, id: u32) -> u32 {
        lookup(&self.elem_index, id)
    }

    /// Per-node rows (internal order) in id order.
    pub fn nodes_by_id<'a, T: Clone>(&self, rows: &'a [T]) -> Cow<'a, [T]> {
        by_id(&self.node_id, rows)
    }

    /// Per-element rows (internal order) in id order.
    pub fn elems_by_id<'a, T: Clone>(&self, rows: &'a [T]) -> Cow<'a, [T]> {
        by_id(&self.elem_id, rows)
    }

    /// Whether every index is its id.
    pub fn is_identity(&self) -> bool {
        self.node_id.is_empty() && self.elem_id.is_empty()
    }

    /// Whether the maps are inverse permutations of each other (restore
    /// check): `n` nodes and `m` elements.
    pub fn is_consistent(&self, n: usize, m: usize) -> bool {
        let ok = |ids: &[u32], index: &[u32], len: usize| {
            ids.len() == index.len()
                && ids.len() <= len
                && ids.iter().enumerate().all(|(i, &id)| (id as usize) < ids.len() && index[id as usize] == i as u32)
        };
        ok(&self.node_id, &self.node_index, n) && ok(&self.elem_id, &self.elem_index, m)
    }

    /// Follows a renumbering (`order[new] = old` internal index, nodes
    /// and elements): the maps compose with it, and the next renumbering is
    /// due from the element count now.
    fn follow(&mut self, node_order: &[u32], elem_order: &[u32]) {
        Self::reorder(&mut self.node_id, &mut self.node_index, node_order);
        Self::reorder(&mut self.elem_id, &mut self.elem_index, elem_order);
        self.base = elem_order.len() as u64;
        self.count += 1;
    }

    /// Composes one map pair with a reordering: `order[new] = old` internal
    /// index.
    fn reorder(ids: &mut Vec<u32>, index: &mut Vec<u32>, order: &[u32]) {
        let new_ids: Vec<u32> = order.iter().map(|&old| lookup(ids, old)).collect();
        let mut new_index = vec![NONE; order.len()];
        for (i, &id) in new_ids.iter().enumerate() {
            new_index[id as usize] = i as u32;
        }
        *ids = new_ids;
        *index = new_index;
    }
}

/// Index of the cell `(x, y)` along a Hilbert curve through a square of
/// `2^16` cells a side (the classic bit-by-bit construction).
fn hilbert(mut x: u32, mut y: u32) -> u64 {
    const N: u32 = 1 << 16;
    let mut d = 0u64;
    let mut s = N / 2;
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        d += u64::from(s) * u64::from(s) * u64::from((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = N - 1 - x;
                y = N - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    d
}

/// Hilbert indices of points in a bounding square.
struct Curve {
    lo: Vec2,
    scale: f64,
}

impl Curve {
    /// The curve through the bounding square of `points`.
    fn around(points: &[Vec2]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let side = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let scale = if side > 0.0 { f64::from((1u32 << 16) - 1) / side } else { 0.0 };
        Self { lo, scale }
    }

    /// The index of the cell holding `p`.
    fn key(&self, p: Vec2) -> u64 {
        let cell = |d: usize| ((p[d] - self.lo[d]) * self.scale).clamp(0.0, f64::from((1u32 << 16) - 1)) as u32;
        hilbert(cell(0), cell(1))
    }
}

/// `v` in the new order: `v_new[i] = v[order[i]]`.
pub(crate) fn permute<T: Clone>(v: &mut Vec<T>, order: &[u32]) {
    *v = order.iter().map(|&o| v[o as usize].clone()).collect();
}

/// `v` with its rows moved by `map` (old index → new index); an empty `v`
/// (a per-boundary-node array of a model without contact) stays empty.
pub(crate) fn scatter<T: Clone + Default>(v: &mut Vec<T>, map: &[u32]) {
    if v.is_empty() {
        return;
    }
    let mut out = vec![T::default(); v.len()];
    for (old, &new) in map.iter().enumerate() {
        out[new as usize] = v[old].clone();
    }
    *v = out;
}

/// The inverse of a permutation `order[new] = old`: `map[old] = new`.
fn inverse(order: &[u32]) -> Vec<u32> {
    let mut map = vec![NONE; order.len()];
    for (new, &old) in order.iter().enumerate() {
        map[old as usize] = new as u32;
    }
    map
}

impl Simulation {
    /// Renumbers, when [`Settings::renumber`](crate::Settings::renumber)
    /// is set, once crack insertion has grown the element count by that
    /// fraction since the last renumbering (checked after a topology change:
    /// `changed`), and at every multiple of
    /// [`Settings::renumber_every`](crate::Settings::renumber_every) steps
    /// if that is set, its time counted as topology's. The tests read saved state only, so a
    /// restored run renumbers at the same steps.
    pub(crate) fn renumber_if_due(&mut self, changed: bool) {
        let Some(f) = self.settings.renumber else { return };
        let grown = changed && (self.elems.conn.len() as f64) >= (1.0 + f) * self.layout.base as f64;
        if !grown && !self.settings.renumber_every.is_some_and(|k| self.clock.every(k)) {
            return;
        }
        let clock = std::time::Instant::now();
        self.renumber();
        self.diagnostics.phase_times.topology += clock.elapsed().as_secs_f64();
    }

    /// Renumbers now ([`Self::renumber`]), whatever the setting: e.g. after
    /// restoring a run made without renumbering.
    pub fn renumber_now(&mut self) {
        let pool = std::sync::Arc::clone(&self.pool);
        pool.install(|| self.renumber());
    }

    /// Puts nodes and elements in the order of a Hilbert curve through
    /// their current positions (elements by centroid), ties by id; removed
    /// elements and nodes without mass go last. Moves every per-node,
    /// per-element and per-boundary-node value with its entity and maps
    /// every stored index; the forces of the step are kept, so the next step
    /// goes on as if nothing had happened (bar the order of sums). The order
    /// depends on ids and positions only, not on the present layout.
    pub(crate) fn renumber(&mut self) {
        let n = self.nodes.x.len();
        let m = self.elems.conn.len();
        let curve = Curve::around(&self.nodes.x);
        let key = |p: Vec2| curve.key(p);
        let x = &self.nodes.x;
        let mut node_keys: Vec<(bool, u64, u32, u32)> =
            (0..n).map(|i| (self.nodes.mass[i] <= 0.0, key(x[i]), self.layout.node_id(i as u32), i as u32)).collect();
        node_keys.sort_unstable();
        let node_order: Vec<u32> = node_keys.iter().map(|k| k.3).collect();
        let mut elem_keys: Vec<(bool, u64, u32, u32)> = (0..m)
            .map(|e| {
                let t = self.elems.conn[e];
                let c = [0, 1].map(|d| (x[t[0] as usize][d] + x[t[1] as usize][d] + x[t[2] as usize][d]) / 3.0);
                (!self.elems.active[e], key(c), self.layout.elem_id(e as u32), e as u32)
            })
            .collect();
        elem_keys.sort_unstable();
        let elem_order: Vec<u32> = elem_keys.iter().map(|k| k.3).collect();
        drop((node_keys, elem_keys));
        let node_map = inverse(&node_order);
        let elem_map = inverse(&elem_order);
        let to_node = |v: u32| node_map[v as usize];

        // per node
        let nodes = &mut self.nodes;
        for v in [&mut nodes.x0, &mut nodes.x, &mut nodes.v] {
            permute(v, &node_order);
        }
        permute(&mut nodes.mass, &node_order);
        permute(&mut nodes.bc, &node_order);
        permute(&mut self.ancestor, &node_order);
        for c in &mut self.loads.constraints {
            c.node = to_node(c.node);
        }
        // per element
        let elems = &mut self.elems;
        permute(&mut elems.conn, &elem_order);
        for t in &mut elems.conn {
            *t = t.map(to_node);
        }
        permute(&mut elems.reference, &elem_order);
        permute(&mut elems.material, &elem_order);
        permute(&mut elems.active, &elem_order);
        permute(&mut elems.stress, &elem_order);
        permute(&mut elems.mass_scale, &elem_order);
        permute(&mut elems.state, &elem_order);
        permute(&mut elems.parent, &elem_order);
        permute(&mut self.frequencies.omega, &elem_order);
        elems.force = elem_order.iter().flat_map(|&o| [0, 1, 2].map(|k| elems.force[3 * o as usize + k])).collect();
        if let Some(fr) = &mut self.fracture {
            fr.renumber(&node_order, &elem_order, &node_map);
        }
        for r in &mut self.loads.released {
            r.nodes.iter_mut().for_each(|v| *v = node_map[*v as usize]);
        }
        self.loads.release_force.clear();
        self.update_release();
        self.node_elems = active_node_elements(n, &self.elems.conn, &self.elems.active);
        // by the old boundary indices: worked out again at the next
        // evaluation
        self.frequencies.contact_omega.clear();

        // the surface and what hangs on its boundary nodes and facets
        let key_map = |k: u32| 3 * elem_map[(k / 3) as usize] + k % 3;
        let (surface, facet_map, b_map) = self.surface.relabel(&node_map, key_map, &self.nodes.x0);
        for p in &mut self.loads.pressure {
            p.nodes = p.nodes.map(to_node);
            p.bnodes = p.bnodes.map(|b| b_map[b as usize]);
        }
        scatter(&mut self.loads.pressure_force, &b_map);
        if let Some(c) = &mut self.contact {
            c.relabel(&surface, &facet_map, &b_map);
        }
        self.surface = surface;
        // the contact forces added up again in the new order, with the list
        // of dashpots and their counts per node, and the bonds' forces (the
        // same forces up to the order of the sums)
        self.reassemble_surface_forces();

        self.layout.follow(&node_order, &elem_order);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_curve_visits_every_cell_of_a_small_square_once_by_neighbours() {
        // the 2^16 curve restricted to the 4×4 corner square at the origin
        // is the order-2 curve: 16 consecutive indices, each step to an
        // edge neighbour
        let mut cells: Vec<(u64, u32, u32)> = (0..4).flat_map(|x| (0..4).map(move |y| (hilbert(x, y), x, y))).collect();
        cells.sort_unstable();
        assert_eq!(cells.last().unwrap().0 - cells[0].0, 15);
        for w in cells.windows(2) {
            let (dx, dy) = (w[0].1.abs_diff(w[1].1), w[0].2.abs_diff(w[1].2));
            assert_eq!(dx + dy, 1, "{w:?}");
        }
    }

    #[test]
    fn layout_composes_reorderings_and_maps_rows_to_ids() {
        let mut l = Layout::new(4);
        Layout::reorder(&mut l.node_id, &mut l.node_index, &[2, 0, 3, 1]);
        assert_eq!((0..4).map(|i| l.node_id(i)).collect::<Vec<_>>(), vec![2, 0, 3, 1]);
        Layout::reorder(&mut l.node_id, &mut l.node_index, &[1, 0, 3, 2]);
        assert_eq!((0..4).map(|i| l.node_id(i)).collect::<Vec<_>>(), vec![0, 2, 1, 3]);
        assert!((0..4).all(|id| l.node_id(l.node_index(id)) == id));
        // entities made after a renumbering sit at their id
        assert_eq!((l.node_id(7), l.node_index(7)), (7, 7));
        assert_eq!(&*l.nodes_by_id(&[10, 12, 11, 13, 14]), &[10, 11, 12, 13, 14]);
        assert!(l.is_consistent(5, 0));
    }
}
