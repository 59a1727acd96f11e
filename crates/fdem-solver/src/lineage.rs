//! Lineage of elements: the element each piece was cut from (issue 32,
//! docs/fracture.md "What a crack's pieces inherit").
//!
//! Crack insertion splits an element into pieces: one keeps the element's
//! id, the others get new ids and record the element as their parent.
//! Element sets are given as ids of the model's elements, and a set means
//! the rock its elements were: an excavation stage or
//! [`Simulation::deactivate`] removes the named elements and every piece
//! cut from them since. Each element keeps its parent's id (an element of
//! the model is its own parent), stored per internal index like every
//! per-element array, so renumbering moves it and never changes it. A
//! parent was created before its pieces, so its id is smaller: one pass
//! in id order finds every element's origin, or every descendant of a
//! group.

use std::borrow::Cow;

use fdem_element::Vec2;

use crate::error::SetupError;
use crate::simulation::Simulation;

impl Simulation {
    /// For every element (by id) its parent: the element (id) crack
    /// insertion cut it from, itself for an element of the model.
    pub fn element_parents(&self) -> Cow<'_, [u32]> {
        self.layout.elems_by_id(&self.elems.parent)
    }

    /// For every element (by id) its origin: the element of the model it
    /// descends from (itself for an element of the model). The model's
    /// element sets hold origins: an element is in every set its origin
    /// is in.
    pub fn element_origins(&self) -> Vec<u32> {
        let parent = self.element_parents();
        let mut origin: Vec<u32> = Vec::with_capacity(parent.len());
        for (id, &p) in parent.iter().enumerate() {
            // a parent's id is below its piece's
            origin.push(if p as usize == id { p } else { origin[p as usize] });
        }
        origin
    }

    /// By id: whether each element is one of `ids` or was cut from one of
    /// them (directly or from a piece of it). `ids` must exist.
    pub(crate) fn descendants(&self, ids: &[u32]) -> Vec<bool> {
        let parent = self.element_parents();
        let mut marked = vec![false; parent.len()];
        for &e in ids {
            marked[e as usize] = true;
        }
        for (id, &p) in parent.iter().enumerate() {
            if p as usize != id && marked[p as usize] {
                marked[id] = true;
            }
        }
        marked
    }

    /// Recovers the lineage of a run restored from a checkpoint older than
    /// format 7, which did not keep it (there, every element is its own
    /// parent): every element with an id at or past the model's element
    /// count that is its own parent is a piece of unknown origin, and gets
    /// as parent the model element whose reference triangle holds its
    /// reference centroid (a piece lies inside the element it was cut
    /// from, in the reference configuration, where cracks neither open nor
    /// move). `points` and `triangles` are the model's mesh. Returns how
    /// many pieces were placed; does nothing to a run that kept its lineage.
    /// A piece that lies in no model triangle (another model's mesh) keeps
    /// itself as parent.
    pub fn recover_lineage(&mut self, points: &[Vec2], triangles: &[[u32; 3]]) -> Result<usize, SetupError> {
        let (mm, m) = (triangles.len(), self.elems.conn.len());
        if mm > m {
            return Err(SetupError::Invalid(format!("the model has {mm} elements, the run only {m}")));
        }
        if let Some(t) = triangles.iter().position(|t| t.iter().any(|&v| v as usize >= points.len())) {
            return Err(SetupError::Invalid(format!("model element {t} refers to a missing node")));
        }
        let orphans: Vec<u32> = (mm as u32..m as u32).filter(|&id| self.parent_of(id) == id).collect();
        if orphans.is_empty() {
            return Ok(0);
        }
        let grid = TriangleGrid::new(points, triangles);
        let mut placed = 0;
        for id in orphans {
            let e = self.layout.elem_index(id) as usize;
            let t = self.elems.conn[e].map(|v| self.nodes.x0[v as usize]);
            let c = [0, 1].map(|d| (t[0][d] + t[1][d] + t[2][d]) / 3.0);
            if let Some(host) = grid.locate(points, triangles, c) {
                self.elems.parent[e] = host;
                placed += 1;
            }
        }
        Ok(placed)
    }

    fn parent_of(&self, id: u32) -> u32 {
        self.elems.parent[self.layout.elem_index(id) as usize]
    }
}

/// Triangles bucketed by the cells of a uniform grid their bounding boxes
/// overlap, for point location.
struct TriangleGrid {
    lo: Vec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// CSR: the triangles of cell `i + nx j`.
    offsets: Vec<usize>,
    items: Vec<u32>,
}

impl TriangleGrid {
    fn new(points: &[Vec2], triangles: &[[u32; 3]]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for t in triangles {
            for &v in t {
                for d in 0..2 {
                    lo[d] = lo[d].min(points[v as usize][d]);
                    hi[d] = hi[d].max(points[v as usize][d]);
                }
            }
        }
        // about one triangle per cell, at most 2^11 cells a side
        let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
        let cell = ((w * h / triangles.len().max(1) as f64).sqrt()).max(w.max(h) / 2048.0).max(f64::MIN_POSITIVE);
        let nx = ((w / cell) as usize + 1).min(2048);
        let ny = ((h / cell) as usize + 1).min(2048);
        let mut grid = TriangleGrid { lo, cell, nx, ny, offsets: vec![0; nx * ny + 1], items: Vec::new() };
        // the cells a triangle's bounding box overlaps
        let cells = |g: &TriangleGrid, t: &[u32; 3]| -> Vec<usize> {
            let p = t.map(|v| points[v as usize]);
            let (i0, j0) = g.cell_of([p[0][0].min(p[1][0]).min(p[2][0]), p[0][1].min(p[1][1]).min(p[2][1])]);
            let (i1, j1) = g.cell_of([p[0][0].max(p[1][0]).max(p[2][0]), p[0][1].max(p[1][1]).max(p[2][1])]);
            (i0..=i1).flat_map(|i| (j0..=j1).map(move |j| i + g.nx * j)).collect()
        };
        for t in triangles {
            for c in cells(&grid, t) {
                grid.offsets[c + 1] += 1;
            }
        }
        for c in 0..nx * ny {
            grid.offsets[c + 1] += grid.offsets[c];
        }
        let mut next = grid.offsets.clone();
        grid.items = vec![0; grid.offsets[nx * ny]];
        for (k, t) in triangles.iter().enumerate() {
            for c in cells(&grid, t) {
                grid.items[next[c]] = k as u32;
                next[c] += 1;
            }
        }
        grid
    }

    fn cell_of(&self, p: Vec2) -> (usize, usize) {
        let at = |d: usize, n: usize| (((p[d] - self.lo[d]) / self.cell).max(0.0) as usize).min(n - 1);
        (at(0, self.nx), at(1, self.ny))
    }

    /// The triangle holding `p`: of the triangles of its cell, the one
    /// whose smallest barycentric coordinate of `p` is largest, if that is
    /// not below −1e-9 (on an edge to round-off).
    fn locate(&self, points: &[Vec2], triangles: &[[u32; 3]], p: Vec2) -> Option<u32> {
        let (i, j) = self.cell_of(p);
        let c = i + self.nx * j;
        let mut best: Option<(f64, u32)> = None;
        for &k in &self.items[self.offsets[c]..self.offsets[c + 1]] {
            let [a, b, d] = triangles[k as usize].map(|v| points[v as usize]);
            let (u, v, w) = ([b[0] - a[0], b[1] - a[1]], [d[0] - a[0], d[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            let det = u[0] * v[1] - u[1] * v[0];
            if det == 0.0 {
                continue;
            }
            let l1 = (w[0] * v[1] - w[1] * v[0]) / det;
            let l2 = (u[0] * w[1] - u[1] * w[0]) / det;
            let least = l1.min(l2).min(1.0 - l1 - l2);
            if best.is_none_or(|(b, _)| least > b) {
                best = Some((least, k));
            }
        }
        best.filter(|&(b, _)| b >= -1e-9).map(|(_, k)| k)
    }
}

#[cfg(test)]
mod tests {
    use super::TriangleGrid;

    #[test]
    fn the_grid_finds_the_triangle_holding_a_point() {
        // a 3 × 2 grid of unit squares, two triangles each
        let points: Vec<[f64; 2]> = (0..3).flat_map(|j| (0..4).map(move |i| [i as f64, j as f64])).collect();
        let id = |i: u32, j: u32| 4 * j + i;
        let triangles: Vec<[u32; 3]> = (0..2)
            .flat_map(|j| {
                (0..3).flat_map(move |i| {
                    [[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]
                })
            })
            .collect();
        let grid = TriangleGrid::new(&points, &triangles);
        for (k, t) in triangles.iter().enumerate() {
            let c = [0, 1].map(|d| t.iter().map(|&v| points[v as usize][d]).sum::<f64>() / 3.0);
            assert_eq!(grid.locate(&points, &triangles, c), Some(k as u32));
        }
        // on a shared edge: one of the two; outside: none
        let on_edge = grid.locate(&points, &triangles, [1.5, 1.5]).unwrap();
        assert!(on_edge == 8 || on_edge == 9, "{on_edge}");
        assert_eq!(grid.locate(&points, &triangles, [3.5, 0.5]), None);
        assert_eq!(grid.locate(&points, &triangles, [-0.1, 1.0]), None);
    }
}
