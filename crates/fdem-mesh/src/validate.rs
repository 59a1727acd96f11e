//! Checks of a user's mesh, each failure naming the offending node or element.

use crate::edges::edge_adjacency;
use crate::Point;

/// Why a mesh was rejected.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshError {
    /// A coordinate is NaN or infinite.
    NonFiniteCoordinate {
        /// The node.
        node: u32,
    },
    /// An element refers to a node that does not exist.
    NodeOutOfRange {
        /// The element.
        element: u32,
        /// The missing node id.
        node: u64,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// An element uses the same node twice.
    RepeatedVertex {
        /// The element.
        element: u32,
    },
    /// Clockwise element (negative area).
    Clockwise {
        /// The element.
        element: u32,
        /// Its signed area (m²).
        area: f64,
    },
    /// Zero-area element, or one with an area below round-off of its size.
    Degenerate {
        /// The element.
        element: u32,
        /// Its signed area (m²).
        area: f64,
    },
    /// Two nodes at the same place that are not declared as an interface.
    DuplicateNode {
        /// The later node.
        node: u32,
        /// The earlier node at the same place.
        other: u32,
    },
    /// A node no element uses.
    OrphanNode {
        /// The node.
        node: u32,
    },
    /// Two elements with the same three nodes.
    DuplicateElement {
        /// The later element.
        element: u32,
        /// The earlier element.
        other: u32,
    },
    /// An edge shared by more than two elements, or by two that run along it
    /// the same way (the elements overlap).
    Overlap {
        /// One of the elements involved.
        element: u32,
        /// Another.
        other: u32,
    },
}

impl std::fmt::Display for MeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use MeshError::*;
        match self {
            NonFiniteCoordinate { node } => write!(f, "node {node} has a NaN or infinite coordinate"),
            NodeOutOfRange { element, node, n_nodes } => {
                write!(f, "element {element} refers to node {node}, but the mesh has {n_nodes} nodes")
            }
            RepeatedVertex { element } => write!(f, "element {element} uses the same node twice"),
            Clockwise { element, area } => write!(
                f,
                "element {element} is clockwise (signed area {area:.3e} m²); triangles must be counter-clockwise"
            ),
            Degenerate { element, area } => write!(f, "element {element} has zero area (signed area {area:.3e} m²)"),
            DuplicateNode { node, other } => write!(
                f,
                "node {node} coincides with node {other}; merge them, or declare them an interface if the split is intended"
            ),
            OrphanNode { node } => write!(f, "node {node} belongs to no element"),
            DuplicateElement { element, other } => write!(f, "element {element} repeats element {other}"),
            Overlap { element, other } => write!(f, "elements {other} and {element} overlap (non-conforming or folded mesh)"),
        }
    }
}

impl std::error::Error for MeshError {}

/// Validates a mesh: finite coordinates, node ids in range, no repeated
/// vertex, counter-clockwise elements of non-negligible area, no coincident
/// nodes (except where `may_coincide[node]` is true for both), no orphan
/// nodes, no duplicate or overlapping elements. Returns the first problem in
/// node/element order, so the report is deterministic.
pub fn validate(points: &[Point], triangles: &[[u64; 3]], may_coincide: &[bool]) -> Result<(), MeshError> {
    let n = points.len();
    for (i, p) in points.iter().enumerate() {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(MeshError::NonFiniteCoordinate { node: i as u32 });
        }
    }
    let mut used = vec![false; n];
    for (e, t) in triangles.iter().enumerate() {
        let element = e as u32;
        for &v in t {
            if v as usize >= n {
                return Err(MeshError::NodeOutOfRange { element, node: v, n_nodes: n });
            }
            used[v as usize] = true;
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(MeshError::RepeatedVertex { element });
        }
        let x = [points[t[0] as usize], points[t[1] as usize], points[t[2] as usize]];
        let twice = (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
        let scale = (0..3)
            .map(|k| {
                let (a, b) = (x[k], x[(k + 1) % 3]);
                (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)
            })
            .fold(0.0, f64::max);
        let area = 0.5 * twice;
        if twice.abs() <= 1e-12 * scale || scale == 0.0 {
            return Err(MeshError::Degenerate { element, area });
        }
        if twice < 0.0 {
            return Err(MeshError::Clockwise { element, area });
        }
    }
    if let Some(node) = used.iter().position(|u| !u) {
        return Err(MeshError::OrphanNode { node: node as u32 });
    }
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_unstable_by(|&a, &b| {
        let (pa, pb) = (points[a as usize], points[b as usize]);
        pa[0].total_cmp(&pb[0]).then(pa[1].total_cmp(&pb[1])).then(a.cmp(&b))
    });
    let mut first_dup: Option<(u32, u32)> = None;
    for w in order.windows(2) {
        let (a, b) = (w[0] as usize, w[1] as usize);
        if points[a] == points[b] && !(may_coincide.get(a) == Some(&true) && may_coincide.get(b) == Some(&true)) {
            let pair = (a.max(b) as u32, a.min(b) as u32);
            if first_dup.is_none_or(|d| pair < d) {
                first_dup = Some(pair);
            }
        }
    }
    if let Some((node, other)) = first_dup {
        return Err(MeshError::DuplicateNode { node, other });
    }
    let mut sorted: Vec<([u64; 3], u32)> = triangles
        .iter()
        .enumerate()
        .map(|(e, t)| {
            let mut s = *t;
            s.sort_unstable();
            (s, e as u32)
        })
        .collect();
    sorted.sort_unstable();
    for w in sorted.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(MeshError::DuplicateElement { element: w[1].1, other: w[0].1 });
        }
    }
    let tris: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|v| v as u32)).collect();
    for edge in edge_adjacency(&tris) {
        if let Some((extra, _)) = edge.extra {
            return Err(MeshError::Overlap { element: extra, other: edge.first.0 });
        }
        if let Some((second, k2)) = edge.second {
            let (first, k1) = edge.first;
            let start = |e: u32, k: u8| tris[e as usize][k as usize];
            if start(first, k1) == start(second, k2) {
                return Err(MeshError::Overlap { element: second, other: first });
            }
        }
    }
    if let Some((element, other)) = first_overlap(points, &tris) {
        return Err(MeshError::Overlap { element, other });
    }
    Ok(())
}

/// The first pair of elements (larger id, smaller id) whose interiors
/// overlap although they share no edge: an edge of one properly crosses an
/// edge of the other, or a vertex or the centroid of one lies strictly
/// inside the other. Touching along an edge or at a vertex (conforming
/// neighbours, the two sides of a joint) is not overlap. Candidate pairs
/// come from a uniform grid of cells about the mean longest edge; each
/// pair is tested once, in the cell of its bounding boxes' common lower
/// corner. Linear in the element count for meshes of even element size.
fn first_overlap(points: &[Point], tris: &[[u32; 3]]) -> Option<(u32, u32)> {
    let n = tris.len();
    if n < 2 {
        return None;
    }
    let corners = |e: usize| tris[e].map(|v| points[v as usize]);
    let mut boxes = Vec::with_capacity(n);
    let mut sum = 0.0;
    for e in 0..n {
        let x = corners(e);
        let lo = [x[0][0].min(x[1][0]).min(x[2][0]), x[0][1].min(x[1][1]).min(x[2][1])];
        let hi = [x[0][0].max(x[1][0]).max(x[2][0]), x[0][1].max(x[1][1]).max(x[2][1])];
        sum += (hi[0] - lo[0]).max(hi[1] - lo[1]);
        boxes.push((lo, hi));
    }
    let origin = boxes.iter().fold([f64::INFINITY; 2], |o, b| [o[0].min(b.0[0]), o[1].min(b.0[1])]);
    // cells of about the mean box size, coarsened until no more than 32
    // entries per element on average (a graded mesh's large elements)
    let mut cell = (sum / n as f64).max(f64::MIN_POSITIVE);
    // cells a box of extent x0..x1 can touch (at most)
    let span = |x0: f64, x1: f64, c: f64| ((x1 - x0) / c).floor() + 2.0;
    loop {
        let total: f64 = boxes.iter().map(|(lo, hi)| span(lo[0], hi[0], cell) * span(lo[1], hi[1], cell)).sum();
        if total <= 32.0 * n as f64 {
            break;
        }
        cell *= 2.0;
    }
    let index = |x: f64, o: f64| ((x - o) / cell).floor().clamp(0.0, 1e15) as i64;
    // (cell, element) for every cell an element's box touches
    let mut entries: Vec<(i64, i64, u32)> = Vec::new();
    for (e, (lo, hi)) in boxes.iter().enumerate() {
        let (i0, i1) = (index(lo[0], origin[0]), index(hi[0], origin[0]));
        let (j0, j1) = (index(lo[1], origin[1]), index(hi[1], origin[1]));
        for i in i0..=i1 {
            for j in j0..=j1 {
                entries.push((i, j, e as u32));
            }
        }
    }
    entries.sort_unstable();
    let mut found: Option<(u32, u32)> = None;
    let mut start = 0;
    while start < entries.len() {
        let key = (entries[start].0, entries[start].1);
        let mut end = start + 1;
        while end < entries.len() && (entries[end].0, entries[end].1) == key {
            end += 1;
        }
        for a in start..end {
            for b in a + 1..end {
                let (ea, eb) = (entries[a].2 as usize, entries[b].2 as usize);
                let (la, lb) = (boxes[ea].0, boxes[eb].0);
                let corner = [la[0].max(lb[0]), la[1].max(lb[1])];
                if (index(corner[0], origin[0]), index(corner[1], origin[1])) != key {
                    continue;
                }
                if interiors_overlap(&corners(ea), &corners(eb)) {
                    let pair = (ea.max(eb) as u32, ea.min(eb) as u32);
                    if found.is_none_or(|f| pair < f) {
                        found = Some(pair);
                    }
                }
            }
        }
        start = end;
    }
    found
}

/// Whether two counter-clockwise triangles overlap in their interiors
/// (see [`first_overlap`]); orientation tests carry a tolerance of 1e-12
/// of the squared size so that shared and collinear edges do not count.
fn interiors_overlap(a: &[Point; 3], b: &[Point; 3]) -> bool {
    let size2 =
        a.iter().chain(b.iter()).fold(0.0f64, |m, p| m.max((p[0] - a[0][0]).powi(2) + (p[1] - a[0][1]).powi(2)));
    let eps = 1e-12 * size2;
    let orient = |p: Point, q: Point, r: Point| (q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]);
    let strictly_inside = |p: Point, t: &[Point; 3]| (0..3).all(|k| orient(t[k], t[(k + 1) % 3], p) > eps);
    for i in 0..3 {
        let (p, q) = (a[i], a[(i + 1) % 3]);
        for j in 0..3 {
            let (r, s) = (b[j], b[(j + 1) % 3]);
            let (d1, d2) = (orient(p, q, r), orient(p, q, s));
            let (d3, d4) = (orient(r, s, p), orient(r, s, q));
            let crosses = |u: f64, v: f64| (u > eps && v < -eps) || (u < -eps && v > eps);
            if crosses(d1, d2) && crosses(d3, d4) {
                return true;
            }
        }
    }
    let centroid = |t: &[Point; 3]| [(t[0][0] + t[1][0] + t[2][0]) / 3.0, (t[0][1] + t[1][1] + t[2][1]) / 3.0];
    a.iter().any(|&p| strictly_inside(p, b))
        || b.iter().any(|&p| strictly_inside(p, a))
        || strictly_inside(centroid(a), b)
        || strictly_inside(centroid(b), a)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> (Vec<Point>, Vec<[u64; 3]>) {
        (vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn good_mesh_passes() {
        let (p, t) = square();
        assert_eq!(validate(&p, &t, &[]), Ok(()));
    }

    #[test]
    fn each_defect_is_named() {
        let (mut p, mut t) = square();
        t[1] = [0, 3, 2];
        assert_eq!(validate(&p, &t, &[]), Err(MeshError::Clockwise { element: 1, area: -0.5 }));
        let (_, mut t2) = square();
        t2[0] = [0, 1, 7];
        assert!(matches!(validate(&p, &t2, &[]), Err(MeshError::NodeOutOfRange { element: 0, node: 7, .. })));
        p[2] = [f64::NAN, 1.0];
        assert_eq!(validate(&p, &square().1, &[]), Err(MeshError::NonFiniteCoordinate { node: 2 }));
        let (mut p, t) = square();
        p.push([5.0, 5.0]);
        assert_eq!(validate(&p, &t, &[]), Err(MeshError::OrphanNode { node: 4 }));
        let (p, _) = square();
        assert_eq!(validate(&p, &[[0, 1, 1]], &[]), Err(MeshError::RepeatedVertex { element: 0 }));
        let line = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        assert!(matches!(validate(&line, &[[0, 1, 2]], &[]), Err(MeshError::Degenerate { element: 0, .. })));
    }

    #[test]
    fn coincident_nodes_need_a_declared_interface() {
        // two triangles meeting along x = 1 with the edge nodes duplicated
        let p = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 0.0], [2.0, 0.0], [1.0, 1.0]];
        let t = vec![[0, 1, 2], [3, 4, 5]];
        assert_eq!(validate(&p, &t, &[]), Err(MeshError::DuplicateNode { node: 3, other: 1 }));
        let allowed = vec![false, true, true, true, false, true];
        assert_eq!(validate(&p, &t, &allowed), Ok(()));
    }

    /// Triangles that overlap without sharing an edge (crossing, one
    /// inside the other, one poking a vertex into the other) are found;
    /// conforming neighbours and the two sides of a joint (coincident
    /// nodes, edges on one line) are not overlap.
    #[test]
    fn overlap_without_a_shared_edge() {
        let p = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.2, 0.2], [1.2, 0.2], [0.2, 1.2]];
        assert!(matches!(validate(&p, &[[0, 1, 2], [3, 4, 5]], &[]), Err(MeshError::Overlap { element: 1, other: 0 })));
        let inner = vec![[0.0, 0.0], [4.0, 0.0], [0.0, 4.0], [1.0, 1.0], [2.0, 1.0], [1.0, 2.0]];
        assert!(matches!(validate(&inner, &[[0, 1, 2], [3, 4, 5]], &[]), Err(MeshError::Overlap { .. })));
        let (q, t) = square();
        assert!(validate(&q, &t, &[]).is_ok());
        // two squares side by side along x = 1 with their own nodes there
        let joint =
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]];
        let tris = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let coincide = [false, true, true, false, true, false, false, true];
        assert!(validate(&joint, &tris, &coincide).is_ok());
    }

    #[test]
    fn overlapping_and_duplicate_elements() {
        let (p, _) = square();
        assert_eq!(
            validate(&p, &[[0, 1, 2], [1, 2, 0], [0, 2, 3]], &[]),
            Err(MeshError::DuplicateElement { element: 1, other: 0 })
        );
        // two triangles folded over the same edge, both counter-clockwise
        let p = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, 0.5]];
        assert!(matches!(validate(&p, &[[0, 1, 2], [0, 1, 3]], &[]), Err(MeshError::Overlap { .. })));
    }
}
