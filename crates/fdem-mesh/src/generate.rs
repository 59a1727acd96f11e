//! Quality triangle meshes that conform to line segments (joint traces),
//! by constrained Delaunay triangulation with Delaunay refinement (spade).
//!
//! Segments may cross each other and the outline; crossings become mesh
//! nodes. The result is deterministic (spade inserts in a fixed order; we
//! number nodes and triangles in spade's order).

use spade::handles::FixedVertexHandle;
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation as _};

use crate::{Csr, Point};

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

/// Checks the input of a mesher; returns twice the outline's signed area.
fn check(outline: &[Point], segments: &[[Point; 2]], size_name: &str, size: f64) -> Result<f64, GenerateError> {
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
    if let Some(i) = segments.iter().position(|s| s[0] == s[1]) {
        return bad(format!("segment {i} has zero length"));
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
    if !(size > 0.0 && size.is_finite()) {
        return bad(format!("{size_name} = {size} must be positive"));
    }
    Ok(area2)
}

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

fn insert(cdt: &mut Cdt, p: Point) -> Result<FixedVertexHandle, GenerateError> {
    cdt.insert(Point2::new(p[0], p[1]))
        .map_err(|e| GenerateError::BadGeometry(format!("cannot insert point {p:?}: {e:?}")))
}

/// Adds the outline's sides and the segments as constraints; with `piece`
/// (m), each is first divided into equal parts of about `piece` (at least
/// one) between the corners and segment ends that lie on it, so that the
/// nodes along it are evenly spaced and no division point falls a
/// round-off away from such an end (a trace that stops on the outline).
fn constrain(
    cdt: &mut Cdt,
    outline: &[Point],
    segments: &[[Point; 2]],
    piece: Option<f64>,
) -> Result<(), GenerateError> {
    let sides = (0..outline.len()).map(|k| [outline[k], outline[(k + 1) % outline.len()]]);
    let lines: Vec<[Point; 2]> = sides.chain(segments.iter().copied()).collect();
    let Some(h) = piece else {
        for [a, b] in lines {
            let (a, b) = (insert(cdt, a)?, insert(cdt, b)?);
            if a != b {
                cdt.add_constraint_and_split(a, b, |p| p);
            }
        }
        return Ok(());
    };
    let mut ends: Vec<Point> = lines.iter().flatten().copied().collect();
    let extent = ends.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs())).max(h);
    let tol = 1e-9 * extent;
    // ends a round-off apart (a trace end snapped onto another trace's end)
    // become one point, the first in x order: spade would keep both and
    // make a triangle of no area between them
    let mut order: Vec<usize> = (0..ends.len()).collect();
    order.sort_by(|&i, &j| ends[i][0].total_cmp(&ends[j][0]).then(ends[i][1].total_cmp(&ends[j][1])));
    for (r, &i) in order.iter().enumerate() {
        for &j in order[..r].iter().rev() {
            if ends[i][0] - ends[j][0] > tol {
                break;
            }
            if (ends[i][0] - ends[j][0]).hypot(ends[i][1] - ends[j][1]) <= tol {
                ends[i] = ends[j];
                break;
            }
        }
    }
    let lines: Vec<[Point; 2]> = ends.chunks(2).map(|c| [c[0], c[1]]).filter(|l| l[0] != l[1]).collect();
    let ends: Vec<Point> = lines.iter().flatten().copied().collect();
    // the ends sorted by x and by y: a line looks at those within its own
    // extent along the axis where that extent is the smaller
    let by_axis = [0, 1].map(|k| {
        let mut order: Vec<usize> = (0..ends.len()).collect();
        order.sort_by(|&i, &j| ends[i][k].total_cmp(&ends[j][k]));
        order
    });
    for [a, b] in lines {
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = d[0].hypot(d[1]);
        let k = usize::from(d[1].abs() < d[0].abs());
        let (lo, hi) = (a[k].min(b[k]) - tol, a[k].max(b[k]) + tol);
        let order = &by_axis[k];
        let first = order.partition_point(|&i| ends[i][k] < lo);
        let last = order.partition_point(|&i| ends[i][k] <= hi);
        // the parameters of the ends lying on this line, in order
        // (parameter, the end's own coordinates)
        let mut stops: Vec<(f64, Point)> = order[first..last]
            .iter()
            .map(|&i| ends[i])
            .filter_map(|p| {
                let w = [p[0] - a[0], p[1] - a[1]];
                let t = (w[0] * d[0] + w[1] * d[1]) / (len * len);
                let off = (w[0] * d[1] - w[1] * d[0]).abs() / len;
                (off <= tol && t * len > tol && (1.0 - t) * len > tol).then_some((t, p))
            })
            .collect();
        stops.push((0.0, a));
        stops.push((1.0, b));
        // by parameter, then by coordinates (a total order: the result does
        // not depend on the order of the input)
        stops.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1[0].total_cmp(&y.1[0])).then(x.1[1].total_cmp(&y.1[1])));
        // ends a round-off apart are one point, the first (none lies within
        // `tol` of the line's own ends: filtered above)
        stops.dedup_by(|x, y| (x.0 - y.0) * len <= tol);
        let mut prev = insert(cdt, a)?;
        for w in stops.windows(2) {
            let ((t0, _), (t1, p1)) = (w[0], w[1]);
            let n = ((t1 - t0) * len / h).round().max(1.0) as usize;
            for k in 1..=n {
                let next = if k < n {
                    let t = t0 + (t1 - t0) * k as f64 / n as f64;
                    insert(cdt, [a[0] + t * d[0], a[1] + t * d[1]])?
                } else {
                    insert(cdt, p1)?
                };
                if prev != next {
                    cdt.add_constraint_and_split(prev, next, |p| p);
                }
                prev = next;
            }
        }
    }
    Ok(())
}

/// Refines `cdt` (area bound, angle limit), then returns the mesh of the
/// faces inside `outline`.
fn refine_and_extract(
    mut cdt: Cdt,
    outline: &[Point],
    params: RefinementParameters<f64>,
    max_nodes: usize,
) -> Result<Generated, GenerateError> {
    let params = params.with_max_additional_vertices(max_nodes.saturating_sub(cdt.num_vertices()));
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
    let area2 = check(outline, segments, "max_area", max_area)?;
    let mut cdt = Cdt::new();
    constrain(&mut cdt, outline, segments, None)?;
    let estimate = (area2.abs() / 2.0 / max_area * 1.5) as usize + 4 * cdt.num_vertices() + 100;
    if estimate > max_nodes.saturating_mul(4) {
        return Err(GenerateError::TooManyNodes(max_nodes));
    }
    let params = RefinementParameters::<f64>::new()
        .with_max_allowed_area(max_area)
        .with_angle_limit(AngleLimit::from_deg(min_angle.clamp(0.0, 33.0)));
    refine_and_extract(cdt, outline, params, max_nodes)
}

/// Meshes the polygon `outline` like [`triangulate`], but with triangles as
/// nearly equilateral with edge `size` (m) as the constraints allow: the
/// outline's sides and the segments are divided into equal parts of about
/// `size`, the inside is filled with an equilateral lattice of spacing
/// `size`, each point moved a little at random (`LATTICE_JITTER`, seeded
/// by its place: deterministic), minus the points closer than
/// `LATTICE_CLEARANCE · size` to a constraint; the gaps along the
/// constraints are filled by refinement (constraint edges kept whole, area
/// at most `1.3 · √3/4 size²`, angles of at least `min_angle` where that
/// does not need a split constraint), and the free nodes are smoothed
/// ([`smooth`]).
///
/// Why: an explicit run's step is set by its worst element, and Delaunay
/// refinement from the constraints alone leaves triangles of every size
/// down to a fifth of `size` (docs/meshing.md).
pub fn triangulate_uniform(
    outline: &[Point],
    segments: &[[Point; 2]],
    size: f64,
    min_angle: f64,
    max_nodes: usize,
) -> Result<Generated, GenerateError> {
    let area2 = check(outline, segments, "size", size)?;
    let a0 = 3f64.sqrt() / 4.0 * size * size;
    if (area2.abs() / 2.0 / a0 * 0.6) as usize > max_nodes {
        return Err(GenerateError::TooManyNodes(max_nodes));
    }
    let mut cdt = Cdt::new();
    constrain(&mut cdt, outline, segments, Some(size))?;
    let pieces: Vec<[Point; 2]> = cdt
        .undirected_edges()
        .filter(|e| cdt.is_constraint_edge(e.fix()))
        .map(|e| e.vertices().map(|h| [h.position().x, h.position().y]))
        .collect();
    for p in lattice(outline, &pieces, size) {
        insert(&mut cdt, p)?;
    }
    if cdt.num_vertices() > max_nodes {
        return Err(GenerateError::TooManyNodes(max_nodes));
    }
    let params = RefinementParameters::<f64>::new()
        .with_max_allowed_area(LATTICE_MAX_AREA * a0)
        .with_min_required_area(0.1 * a0)
        .keep_constraint_edges()
        .with_angle_limit(AngleLimit::from_deg(min_angle.clamp(0.0, 33.0)));
    let mut g = refine_and_extract(cdt, outline, params, max_nodes)?;
    let mut fixed = vec![false; g.points.len()];
    for e in &g.constraint_edges {
        fixed[e[0] as usize] = true;
        fixed[e[1] as usize] = true;
    }
    smooth(&mut g.points, &g.triangles, &fixed, SMOOTH_SWEEPS);
    Ok(g)
}

/// Each lattice point is moved by up to this many `size`, in a direction
/// and by a distance drawn from its row and column (deterministic): a
/// perfect lattice has edges in three directions only, which a crack
/// path would follow, and fails everywhere at once under a uniform
/// stress. With 0.3 the edge directions spread (the largest of twelve 15°
/// bins holds 4.0 times the smallest against 5.7 without; refinement's
/// mesh 5.0, the joints' own directions included) for 4% off the worst
/// triangle and 7% more triangles (docs/meshing.md).
const LATTICE_JITTER: f64 = 0.3;
/// Lattice points closer than this many `size` to a constraint are left out.
const LATTICE_CLEARANCE: f64 = 0.55;
/// Area bound of the refinement after the lattice, in equilateral areas.
const LATTICE_MAX_AREA: f64 = 1.3;
/// Sweeps of smoothing after a uniform mesh.
const SMOOTH_SWEEPS: usize = 8;

/// The points of an equilateral lattice of spacing `size` (rows along x)
/// inside `outline` and at least `LATTICE_CLEARANCE · size` from every
/// segment of `pieces`, in row order.
fn lattice(outline: &[Point], pieces: &[[Point; 2]], size: f64) -> Vec<Point> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in outline {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let r = LATTICE_CLEARANCE * size;
    // pieces by grid cell (cell = size), each listed in every cell its box
    // padded by r touches
    let cell = size;
    let nx = ((hi[0] - lo[0]) / cell).floor() as usize + 1;
    let ny = ((hi[1] - lo[1]) / cell).floor() as usize + 1;
    let at = |v: f64, k: usize, n: usize| (((v - lo[k]) / cell).floor().max(0.0) as usize).min(n - 1);
    let mut pairs = Vec::new();
    for (i, s) in pieces.iter().enumerate() {
        let (i0, i1) = (at(s[0][0].min(s[1][0]) - r, 0, nx), at(s[0][0].max(s[1][0]) + r, 0, nx));
        let (j0, j1) = (at(s[0][1].min(s[1][1]) - r, 1, ny), at(s[0][1].max(s[1][1]) + r, 1, ny));
        for j in j0..=j1 {
            for ii in i0..=i1 {
                pairs.push((j * nx + ii, i as u32));
            }
        }
    }
    let grid = Csr::from_pairs(nx * ny, pairs.iter().copied());
    let clear = |p: Point| {
        grid.row(at(p[1], 1, ny) * nx + at(p[0], 0, nx)).iter().all(|&i| {
            let [a, b] = pieces[i as usize];
            let (d, w) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            let t = ((w[0] * d[0] + w[1] * d[1]) / (d[0] * d[0] + d[1] * d[1])).clamp(0.0, 1.0);
            (w[0] - t * d[0]).hypot(w[1] - t * d[1]) >= r
        })
    };
    let h = 0.5 * 3f64.sqrt() * size;
    let mut out = Vec::new();
    let rows = ((hi[1] - lo[1]) / h).ceil() as usize;
    for j in 1..rows {
        let y = lo[1] + j as f64 * h;
        let shift = if j % 2 == 1 { 0.5 * size } else { 0.0 };
        let mut x = lo[0] + shift;
        let mut i = 0u64;
        while x < hi[0] {
            let [u, v] = unit_pair((j as u64) << 32 | i);
            let (rad, ang) = (LATTICE_JITTER * size * u.sqrt(), std::f64::consts::TAU * v);
            let p = [x + rad * ang.cos(), y + rad * ang.sin()];
            if x > lo[0] && point_in_polygon(p, outline) && clear(p) {
                out.push(p);
            }
            x += size;
            i += 1;
        }
    }
    out
}

/// Two numbers in `[0, 1)` from `key` (splitmix64): a deterministic,
/// platform-independent perturbation.
fn unit_pair(key: u64) -> [f64; 2] {
    let mut z = key.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut r = z;
        r = (r ^ (r >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        r = (r ^ (r >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        r ^= r >> 31;
        (r >> 11) as f64 / (1u64 << 53) as f64
    };
    [next(), next()]
}

/// Quality of a triangle for an explicit run: `2A / √(ΣL²)` (m), the
/// length its stable step is proportional to (the lumped CST's highest
/// frequency grows with `Σ|∇N|² = ΣL² / 4A²`); half the edge of an
/// equilateral triangle, negative for an inverted one.
pub fn step_length(a: Point, b: Point, c: Point) -> f64 {
    let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    let l2 = |p: Point, q: Point| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
    area2 / (l2(a, b) + l2(b, c) + l2(c, a)).sqrt()
}

/// Smooths a mesh: each node not `fixed` moves, in `sweeps` passes in
/// node order, to the mean of its neighbours (or part-way there) when that
/// raises the smallest [`step_length`] of its triangles; then the nodes of
/// the worst triangles (below `POLISH` of the median) are moved by a
/// pattern search (eight directions, halving steps) that raises it further.
/// Connectivity is kept; no triangle inverts, the mesh's smallest step
/// length never drops and no edge becomes longer than the longest edge of
/// the mesh before smoothing. Deterministic.
///
/// Why the bound on edges: a triangle on a constraint piece much shorter
/// than the rest (a trace ending just past another) has a step length
/// bounded by that piece, which grows a little as long as its free corner
/// moves away; the pattern search then walked that corner across the mesh
/// and stretched its other triangles to three times their size (16.5 m
/// edges in a 4 m mesh), beyond a crack band's snap-back limit, for a gain
/// in the worst step length of under 1% (docs/meshing.md).
pub fn smooth(points: &mut [Point], triangles: &[[u32; 3]], fixed: &[bool], sweeps: usize) {
    let incident = crate::node_elements(points.len(), triangles);
    let dist2 = |p: Point, q: Point| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
    let longest2 = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| dist2(points[a as usize], points[b as usize]))
        .fold(0.0, f64::max);
    // the smallest step length of `v`'s triangles with `v` at `p`; minus
    // infinity (never taken) where an edge of them would outgrow the bound
    let worst = |points: &[Point], v: usize, p: Point| {
        incident
            .row(v)
            .iter()
            .map(|&ek| {
                let (e, k) = ((ek / 3) as usize, (ek % 3) as usize);
                let t = triangles[e];
                let q = |i: usize| if i == k { p } else { points[t[i] as usize] };
                if (0..3).any(|i| i != k && dist2(p, q(i)) > longest2) {
                    return f64::NEG_INFINITY;
                }
                step_length(q(0), q(1), q(2))
            })
            .fold(f64::INFINITY, f64::min)
    };
    let free = |v: usize| !fixed[v] && !incident.row(v).is_empty();
    for _ in 0..sweeps {
        for v in (0..points.len()).filter(|&v| free(v)) {
            let (mut sum, mut n) = ([0.0; 2], 0.0);
            for &ek in incident.row(v) {
                for &u in &triangles[(ek / 3) as usize] {
                    if u as usize != v {
                        sum[0] += points[u as usize][0];
                        sum[1] += points[u as usize][1];
                        n += 1.0;
                    }
                }
            }
            let (p, target) = (points[v], [sum[0] / n, sum[1] / n]);
            let now = worst(points, v, p);
            for w in [1.0, 0.5, 0.25] {
                let q = [p[0] + w * (target[0] - p[0]), p[1] + w * (target[1] - p[1])];
                if worst(points, v, q) > now {
                    points[v] = q;
                    break;
                }
            }
        }
    }
    // the worst triangles' free nodes: a pattern search on their own worst
    let mut q: Vec<f64> = triangles
        .iter()
        .map(|t| step_length(points[t[0] as usize], points[t[1] as usize], points[t[2] as usize]))
        .collect();
    if q.is_empty() {
        return;
    }
    let mut sorted = q.clone();
    sorted.sort_by(f64::total_cmp);
    let limit = POLISH * sorted[sorted.len() / 2];
    for _ in 0..sweeps {
        let mut moved = false;
        for (e, t) in triangles.iter().enumerate() {
            if q[e] >= limit {
                continue;
            }
            for &v in t {
                let v = v as usize;
                if !free(v) {
                    continue;
                }
                let mut now = worst(points, v, points[v]);
                let mut step = 0.2 * limit;
                while step > 0.01 * limit {
                    let p = points[v];
                    // the best of eight moves that beats the worst now
                    let mut better: Option<(f64, Point)> = None;
                    for k in 0..8 {
                        let a = k as f64 * std::f64::consts::FRAC_PI_4;
                        let c = [p[0] + step * a.cos(), p[1] + step * a.sin()];
                        let w = worst(points, v, c);
                        if w > better.map_or(now, |(bw, _)| bw) {
                            better = Some((w, c));
                        }
                    }
                    match better {
                        Some((w, c)) => {
                            points[v] = c;
                            now = w;
                            moved = true;
                        }
                        None => step *= 0.5,
                    }
                }
                for &ek in incident.row(v) {
                    let t = triangles[(ek / 3) as usize];
                    q[(ek / 3) as usize] =
                        step_length(points[t[0] as usize], points[t[1] as usize], points[t[2] as usize]);
                }
            }
        }
        if !moved {
            break;
        }
    }
}

/// Triangles below this fraction of the median step length are polished
/// by [`smooth`].
const POLISH: f64 = 0.75;

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

    /// Every segment is a chain of constraint edges of `g` (their lengths
    /// add up to the segment's).
    fn assert_conforms(g: &Generated, segments: &[[Point; 2]]) {
        for s in segments {
            let d = [s[1][0] - s[0][0], s[1][1] - s[0][1]];
            let len = d[0].hypot(d[1]);
            let on = |v: u32| {
                let p = g.points[v as usize];
                let w = [p[0] - s[0][0], p[1] - s[0][1]];
                let t = (w[0] * d[0] + w[1] * d[1]) / (len * len);
                (w[0] * d[1] - w[1] * d[0]).abs() / len < 1e-9 && (-1e-12..=1.0 + 1e-12).contains(&t)
            };
            let covered: f64 = g
                .constraint_edges
                .iter()
                .filter(|e| on(e[0]) && on(e[1]))
                .map(|e| {
                    let (a, b) = (g.points[e[0] as usize], g.points[e[1] as usize]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                })
                .sum();
            assert!((covered - len).abs() < 1e-9 * len.max(1.0), "segment {s:?}: {covered} of {len}");
        }
    }

    fn signed_areas(g: &Generated) -> Vec<f64> {
        g.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| g.points[v as usize]);
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
            })
            .collect()
    }

    fn worst(g: &Generated) -> f64 {
        g.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| g.points[v as usize]);
                step_length(a, b, c)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn step_length_closed_forms() {
        // equilateral of edge a: 2A/√(ΣL²) = (√3/2 a²)/(√3 a) = a/2
        let a = 0.8;
        let eq = step_length([0.0, 0.0], [a, 0.0], [0.5 * a, 0.5 * 3f64.sqrt() * a]);
        assert!((eq - 0.5 * a).abs() < 1e-15, "{eq}");
        // right isosceles with legs a: a² / √(4a²) = a/2 as well
        let ri = step_length([0.0, 0.0], [a, 0.0], [0.0, a]);
        assert!((ri - 0.5 * a).abs() < 1e-15, "{ri}");
        // clockwise: negative
        assert!(step_length([0.0, 0.0], [0.0, a], [a, 0.0]) < 0.0);
    }

    #[test]
    fn uniform_mesh_conforms_and_is_nearly_equilateral() {
        let outline = [[0.0, 0.0], [20.0, 0.0], [20.0, 10.0], [0.0, 10.0]];
        // a vertical trace ending 2.7 m from the bottom, a horizontal one
        // across it ending on the right side (a T on the outline), and an
        // inclined one
        let segments =
            [[[5.0, 2.7], [5.0, 9.0]], [[1.3, 6.0], [5.0, 6.0]], [[5.0, 6.0], [20.0, 6.0]], [[9.0, 1.0], [16.0, 4.5]]];
        let size = 0.5;
        let g = triangulate_uniform(&outline, &segments, size, 25.0, 100_000).unwrap();
        let tri: Vec<[u64; 3]> = g.triangles.iter().map(|t| t.map(u64::from)).collect();
        assert_eq!(validate(&g.points, &tri, &[]), Ok(()));
        let area = signed_areas(&g);
        assert!(area.iter().all(|&a| a > 0.0));
        assert!((area.iter().sum::<f64>() - 200.0).abs() < 1e-9);
        assert_conforms(&g, &segments);
        // the T-junction on the right side is one node, not two a
        // round-off apart
        let at_t = g.points.iter().filter(|p| (p[0] - 20.0).abs() < 1e-6 && (p[1] - 6.0).abs() < 1e-6).count();
        assert_eq!(at_t, 1);
        // element count: the equilateral lattice's 200 / (√3/4 size²) plus
        // at most 30% (the jitter and the rows along the constraints; 21%
        // here), and fewer than refinement to the same largest area
        let lattice = 200.0 / (3f64.sqrt() / 4.0 * size * size);
        let n = g.triangles.len() as f64;
        assert!((0.95..1.3).contains(&(n / lattice)), "{n} triangles against {lattice:.0}");
        let refined = triangulate(&outline, &segments, 3f64.sqrt() / 4.0 * size * size, 25.0, 100_000).unwrap();
        assert!(n < 0.85 * refined.triangles.len() as f64, "{n} against {}", refined.triangles.len());
        // the worst triangle: at least 60% of the equilateral's size/2, and
        // better than refinement's
        let (u, r) = (worst(&g), worst(&refined));
        assert!(u >= 0.6 * 0.5 * size, "worst step length {u}");
        assert!(u > r, "uniform {u} against refined {r}");
        // reproducible
        assert_eq!(triangulate_uniform(&outline, &segments, size, 25.0, 100_000).unwrap(), g);
    }

    #[test]
    fn smoothing_never_worsens_the_worst_triangle() {
        // a jittered structured mesh of a unit square, 10 × 10 cells
        let n = 10;
        let mut points = Vec::new();
        let mut fixed = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let edge = i == 0 || j == 0 || i == n || j == n;
                // deterministic jitter of up to 0.3 cells
                let h = ((i * 7919 + j * 104_729) % 1000) as f64 / 1000.0 - 0.5;
                let k = ((i * 15_485_863 + j * 32_452_843) % 1000) as f64 / 1000.0 - 0.5;
                let jit = if edge { 0.0 } else { 0.6 / n as f64 };
                points.push([i as f64 / n as f64 + jit * h, j as f64 / n as f64 + jit * k]);
                fixed.push(edge);
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let before = Generated { points: points.clone(), triangles: triangles.clone(), constraint_edges: vec![] };
        smooth(&mut points, &triangles, &fixed, 8);
        let after = Generated { points: points.clone(), triangles, constraint_edges: vec![] };
        assert!(worst(&after) > worst(&before), "{} -> {}", worst(&before), worst(&after));
        assert!(signed_areas(&after).iter().all(|&a| a > 0.0));
        assert!((signed_areas(&after).iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // fixed nodes stay
        for (k, p) in points.iter().enumerate() {
            if fixed[k] {
                assert_eq!(*p, before.points[k]);
            }
        }
    }

    fn longest_edge(g: &Generated) -> f64 {
        g.triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| {
                let (p, q) = (g.points[a as usize], g.points[b as usize]);
                (q[0] - p[0]).hypot(q[1] - p[1])
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_short_constraint_piece_does_not_stretch_the_uniform_mesh() {
        // a trace ending 0.43 m past the end of another (a T almost at a
        // corner, as perturbed joint sets make them), in a 4 m mesh: the
        // constraints are divided into pieces of at most 1.5 size and the
        // refinement makes triangles of at most 1.3 equilateral areas, so
        // no edge needs to be longer than 1.5 size; chasing the step length
        // of the triangle on the stub, the smoothing stretched edges to
        // 16.5 m before it kept them within the longest edge it was given
        let outline = [[0.0, 0.0], [40.0, 0.0], [40.0, 24.0], [0.0, 24.0]];
        let size = 4.0;
        let segments = [[[20.0, 11.57], [20.0, 12.0]], [[20.0, 12.0], [20.4, 24.0]], [[4.0, 12.1], [20.0, 12.0]]];
        let g = triangulate_uniform(&outline, &segments, size, 25.0, 100_000).unwrap();
        assert_conforms(&g, &segments);
        let longest = longest_edge(&g);
        assert!(longest <= 1.5 * size, "longest edge {longest} m");
        // the worst triangle is the stub's: its step length is bounded by
        // the 0.43 m piece (a/√2 for a short edge a under a tall apex),
        // and smoothing brings it within 1% of that
        let w = worst(&g);
        assert!(w > 0.98 * 0.43 / 2f64.sqrt() && w < 0.43 / 2f64.sqrt(), "worst step length {w}");
    }
}
