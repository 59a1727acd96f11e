//! Quality triangle meshes that conform to line segments (joint traces),
//! by constrained Delaunay triangulation with Delaunay refinement (spade).
//!
//! Segments may cross each other and the outline; crossings become mesh
//! nodes. The result is deterministic (spade inserts in a fixed order; we
//! number nodes and triangles in spade's order).

use spade::handles::FixedVertexHandle;
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation as _};

use crate::Point;

/// A generated mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Generated {
    /// Node coordinates (m).
    pub points: Vec<Point>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Edges that lie on the outline or on a segment (node pairs, smaller
    /// id first, sorted).
    pub constraint_edges: Vec<[u32; 2]>,
}

/// Why a mesh could not be generated.
#[derive(Clone, Debug, PartialEq)]
pub enum GenerateError {
    /// A coordinate is NaN or infinite, or the outline has fewer than three
    /// corners or no area.
    BadGeometry(String),
    /// The refinement needed more nodes than allowed.
    TooManyNodes(usize),
}

impl std::fmt::Display for GenerateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GenerateError::BadGeometry(s) => f.write_str(s),
            GenerateError::TooManyNodes(n) => write!(f, "the mesh needs more than {n} nodes; raise the element size"),
        }
    }
}

impl std::error::Error for GenerateError {}

fn point_in_polygon(p: Point, poly: &[Point]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Meshes the polygon `outline` (counter-clockwise or not, not
/// self-intersecting) so that every segment of `segments` (inside the
/// outline) is a chain of mesh edges. Triangles have an area of at most
/// `max_area` (m²) and, where the geometry allows, no angle below
/// `min_angle` (degrees; ≤ 30 is always reachable). At most `max_nodes`
/// nodes are created.
pub fn triangulate(
    outline: &[Point],
    segments: &[[Point; 2]],
    max_area: f64,
    min_angle: f64,
    max_nodes: usize,
) -> Result<Generated, GenerateError> {
    let bad = |s: String| Err(GenerateError::BadGeometry(s));
    if outline.len() < 3 {
        return bad("the outline needs at least three corners".into());
    }
    let finite = |p: &Point| p[0].is_finite() && p[1].is_finite();
    if let Some(i) = outline.iter().position(|p| !finite(p)) {
        return bad(format!("outline corner {i} is not finite"));
    }
    if let Some(i) = segments.iter().position(|s| !(finite(&s[0]) && finite(&s[1]))) {
        return bad(format!("segment {i} is not finite"));
    }
    let area2: f64 = (0..outline.len())
        .map(|i| {
            let (a, b) = (outline[i], outline[(i + 1) % outline.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum();
    if area2.abs() <= 0.0 {
        return bad("the outline has no area".into());
    }
    if !(max_area > 0.0 && max_area.is_finite()) {
        return bad(format!("max_area = {max_area} must be positive"));
    }
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let insert = |cdt: &mut ConstrainedDelaunayTriangulation<Point2<f64>>,
                  p: Point|
     -> Result<FixedVertexHandle, GenerateError> {
        cdt.insert(Point2::new(p[0], p[1]))
            .map_err(|e| GenerateError::BadGeometry(format!("cannot insert point {p:?}: {e:?}")))
    };
    let corners: Vec<FixedVertexHandle> = outline.iter().map(|&p| insert(&mut cdt, p)).collect::<Result<_, _>>()?;
    for k in 0..corners.len() {
        let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
        if a != b {
            cdt.add_constraint_and_split(a, b, |p| p);
        }
    }
    for (i, s) in segments.iter().enumerate() {
        if s[0] == s[1] {
            return bad(format!("segment {i} has zero length"));
        }
        let a = insert(&mut cdt, s[0])?;
        let b = insert(&mut cdt, s[1])?;
        cdt.add_constraint_and_split(a, b, |p| p);
    }
    let estimate = (area2.abs() / 2.0 / max_area * 1.5) as usize + 4 * cdt.num_vertices() + 100;
    if estimate > max_nodes.saturating_mul(4) {
        return Err(GenerateError::TooManyNodes(max_nodes));
    }
    let params = RefinementParameters::<f64>::new()
        .with_max_allowed_area(max_area)
        .with_angle_limit(AngleLimit::from_deg(min_angle.clamp(0.0, 33.0)))
        .with_max_additional_vertices(max_nodes.saturating_sub(cdt.num_vertices()));
    let result = cdt.refine(params);
    if !result.refinement_complete || cdt.num_vertices() > max_nodes {
        return Err(GenerateError::TooManyNodes(max_nodes));
    }
    // keep the faces inside the outline (the triangulation covers its hull)
    let mut keep = Vec::new();
    for face in cdt.inner_faces() {
        let v = face.vertices().map(|h| h.position());
        let c = [(v[0].x + v[1].x + v[2].x) / 3.0, (v[0].y + v[1].y + v[2].y) / 3.0];
        if point_in_polygon(c, outline) {
            keep.push(face.vertices().map(|h| h.fix().index()));
        }
    }
    let mut id = vec![u32::MAX; cdt.num_vertices()];
    let mut points = Vec::new();
    for f in &keep {
        for &v in f {
            if id[v] == u32::MAX {
                id[v] = 0;
            }
        }
    }
    for (v, slot) in id.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = points.len() as u32;
            let p = cdt.vertex(FixedVertexHandle::from_index(v)).position();
            points.push([p.x, p.y]);
        }
    }
    let triangles: Vec<[u32; 3]> = keep.iter().map(|f| f.map(|v| id[v])).collect();
    let mut constraint_edges: Vec<[u32; 2]> = cdt
        .undirected_edges()
        .filter(|e| cdt.is_constraint_edge(e.fix()))
        .filter_map(|e| {
            let [a, b] = e.vertices().map(|h| id[h.fix().index()]);
            (a != u32::MAX && b != u32::MAX).then(|| [a.min(b), a.max(b)])
        })
        .collect();
    constraint_edges.sort_unstable();
    Ok(Generated { points, triangles, constraint_edges })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validate;

    #[test]
    fn square_with_crossing_segments() {
        let outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let segments = [[[2.0, 1.0], [8.0, 9.0]], [[1.0, 8.0], [9.0, 2.0]]];
        let g = triangulate(&outline, &segments, 0.5, 25.0, 100_000).unwrap();
        let tri: Vec<[u64; 3]> = g.triangles.iter().map(|t| t.map(u64::from)).collect();
        assert_eq!(validate(&g.points, &tri, &[]), Ok(()));
        let area: f64 = g
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| g.points[v as usize]);
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
            })
            .sum();
        assert!((area - 100.0).abs() < 1e-9, "{area}");
        // the crossing point (5, 5) is a node, and edges lie on both segments
        assert!(g.points.iter().any(|p| (p[0] - 5.0).abs() < 1e-12 && (p[1] - 5.0).abs() < 1e-12));
        let on = |e: &[u32; 2], s: &[Point; 2]| {
            e.iter().all(|&v| {
                let p = g.points[v as usize];
                let d = [s[1][0] - s[0][0], s[1][1] - s[0][1]];
                ((p[0] - s[0][0]) * d[1] - (p[1] - s[0][1]) * d[0]).abs() / d[0].hypot(d[1]) < 1e-9
            })
        };
        for s in &segments {
            let len: f64 = g
                .constraint_edges
                .iter()
                .filter(|e| on(e, s))
                .map(|e| {
                    let (a, b) = (g.points[e[0] as usize], g.points[e[1] as usize]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                })
                .sum();
            assert!((len - (6.0f64.hypot(8.0))).abs() < 1e-9, "{len}");
        }
        // reproducible
        assert_eq!(triangulate(&outline, &segments, 0.5, 25.0, 100_000).unwrap(), g);
    }

    #[test]
    fn concave_outline_keeps_only_inside() {
        let outline = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 1.0], [0.0, 4.0]];
        let g = triangulate(&outline, &[], 0.2, 25.0, 100_000).unwrap();
        let area: f64 = g
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| g.points[v as usize]);
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
            })
            .sum();
        assert!((area - 10.0).abs() < 1e-9, "{area}"); // shoelace area of the outline
    }

    #[test]
    fn errors() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(matches!(
            triangulate(&sq, &[[[0.5, 0.5], [0.5, 0.5]]], 0.1, 25.0, 1000),
            Err(GenerateError::BadGeometry(_))
        ));
        assert!(matches!(triangulate(&sq, &[], 1e-8, 25.0, 1000), Err(GenerateError::TooManyNodes(1000))));
    }
}
