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
    Ok(())
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
