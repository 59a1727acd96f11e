//! Unique edges, their adjacent elements, and the free (boundary) facets.

/// A boundary facet: an edge of exactly one element, oriented as in that
/// element (counter-clockwise), so the body lies on its left and the outward
/// normal is `(dy, −dx) / L`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Facet {
    /// Start and end node.
    pub nodes: [u32; 2],
    /// The element the facet bounds.
    pub element: u32,
    /// Local edge index `k` in that element (from vertex `k` to `(k+1) % 3`).
    pub local: u8,
}

/// One undirected edge and the (one or two) elements that share it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeAdjacency {
    /// End nodes, smaller id first.
    pub nodes: [u32; 2],
    /// `(element, local edge)` of the first element, in element order.
    pub first: (u32, u8),
    /// The second element, if the edge is interior.
    pub second: Option<(u32, u8)>,
    /// More than two elements share the edge (a non-manifold mesh).
    pub extra: Option<(u32, u8)>,
}

/// All unique edges, sorted by their node pair, with adjacent elements.
pub fn edge_adjacency(triangles: &[[u32; 3]]) -> Vec<EdgeAdjacency> {
    let mut half: Vec<([u32; 2], u32, u8)> = Vec::with_capacity(triangles.len() * 3);
    for (e, t) in triangles.iter().enumerate() {
        for k in 0..3u8 {
            let (a, b) = (t[k as usize], t[(k as usize + 1) % 3]);
            half.push(([a.min(b), a.max(b)], e as u32, k));
        }
    }
    half.sort_unstable();
    let mut out = Vec::with_capacity(half.len() / 2 + 1);
    let mut i = 0;
    while i < half.len() {
        let key = half[i].0;
        let mut j = i + 1;
        while j < half.len() && half[j].0 == key {
            j += 1;
        }
        let get = |m: usize| (m < j).then(|| (half[m].1, half[m].2));
        out.push(EdgeAdjacency { nodes: key, first: (half[i].1, half[i].2), second: get(i + 1), extra: get(i + 2) });
        i = j;
    }
    out
}

/// The free facets of a triangle mesh, in ascending `(element, local)` order.
pub fn boundary_facets(triangles: &[[u32; 3]]) -> Vec<Facet> {
    let mut facets: Vec<Facet> = edge_adjacency(triangles)
        .into_iter()
        .filter(|e| e.second.is_none())
        .map(|e| {
            let (element, local) = e.first;
            let t = triangles[element as usize];
            Facet { nodes: [t[local as usize], t[(local as usize + 1) % 3]], element, local }
        })
        .collect();
    facets.sort_unstable_by_key(|f| (f.element, f.local));
    facets
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_of_two_triangles() {
        // 3---2
        // | / |
        // 0---1
        let t = [[0, 1, 2], [0, 2, 3]];
        let edges = edge_adjacency(&t);
        assert_eq!(edges.len(), 5);
        let diag = edges.iter().find(|e| e.nodes == [0, 2]).unwrap();
        assert_eq!(diag.first, (0, 2));
        assert_eq!(diag.second, Some((1, 0)));
        let b = boundary_facets(&t);
        assert_eq!(b.len(), 4);
        // each boundary facet runs counter-clockwise around the square
        let dirs: Vec<[u32; 2]> = b.iter().map(|f| f.nodes).collect();
        assert_eq!(dirs, vec![[0, 1], [1, 2], [2, 3], [3, 0]]);
    }
}
