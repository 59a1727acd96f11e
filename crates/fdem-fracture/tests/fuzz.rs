//! Randomised insertion fuzz (issue 5): thousands of insertions on random
//! meshes with random crack directions and candidate orders. After every
//! check the mesh must stay valid: no inverted element, no element below
//! the minimum quality or size that was not already there, conforming (no
//! edge shared by more than two elements, no node hanging inside an edge),
//! the same total area, and only copies of split nodes or nodes on split
//! edges added.

use fdem_fracture::{
    insertion::altitude, insertion::quality, plan, plan_in_order, Edits, FractureParams, NewNode, NodeFailure,
    PlanScratch,
};
use fdem_mesh::generate::triangulate;
use fdem_mesh::node_elements;

type V = fdem_fracture::Vec2;

/// xorshift64*: a small deterministic generator (no dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn area2(x: &[V], t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| x[v as usize]);
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// A jittered grid with random diagonals, or a refined Delaunay mesh of a
/// random star-shaped polygon.
fn random_mesh(rng: &mut Rng) -> (Vec<V>, Vec<[u32; 3]>) {
    if rng.next() % 2 == 0 {
        let (nx, ny) = (4 + (rng.next() % 8) as u32, 4 + (rng.next() % 8) as u32);
        let mut x = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                let interior = i > 0 && i < nx && j > 0 && j < ny;
                let jitter = |r: &mut Rng| if interior { 0.25 * (r.uniform() - 0.5) } else { 0.0 };
                x.push([i as f64 + jitter(rng), j as f64 + jitter(rng)]);
            }
        }
        let id = |i: u32, j: u32| j * (nx + 1) + i;
        let mut t = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if rng.next() % 2 == 0 {
                    t.extend([[a, b, c], [a, c, d]]);
                } else {
                    t.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        (x, t)
    } else {
        let k = 5 + (rng.next() % 8) as usize;
        let outline: Vec<V> = (0..k)
            .map(|i| {
                let a = std::f64::consts::TAU * (i as f64 + 0.3 * rng.uniform()) / k as f64;
                let r = 4.0 + 2.0 * rng.uniform();
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let g = triangulate(&outline, &[], 0.3 + 0.5 * rng.uniform(), 25.0, 100_000).expect("mesh");
        (g.points, g.triangles)
    }
}

fn apply(x: &mut Vec<V>, t: &mut Vec<[u32; 3]>, e: &Edits) {
    for nn in &e.new_nodes {
        let p = match *nn {
            NewNode::Copy { of } => x[of as usize],
            NewNode::OnEdge { a, b, t } => {
                let (pa, pb) = (x[a as usize], x[b as usize]);
                [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
            }
        };
        x.push(p);
    }
    for &(id, c) in &e.changed {
        t[id as usize] = c;
    }
    for &(_, c) in &e.added {
        t.push(c);
    }
}

fn pair(anc: &[u32], a: u32, b: u32) -> (u32, u32) {
    let (x, y) = (anc[a as usize], anc[b as usize]);
    (x.min(y), x.max(y))
}

/// Panics unless the mesh is conforming: every edge in at most two
/// elements, and every face (an edge of one element) is an outer boundary
/// edge, a crack face, or a piece of one of these, by ancestor pairs. A node
/// left hanging inside a neighbour's edge would show as a face that is none
/// of these: a spurious crack.
fn check_conforming(t: &[[u32; 3]], anc: &[u32], legit: &std::collections::BTreeSet<(u32, u32)>, round: usize) {
    let mut edges: Vec<(u32, u32)> =
        t.iter().flat_map(|e| (0..3).map(move |k| (e[k].min(e[(k + 1) % 3]), e[k].max(e[(k + 1) % 3])))).collect();
    edges.sort_unstable();
    for w in edges.windows(3) {
        assert!(!(w[0] == w[1] && w[1] == w[2]), "round {round}: edge {:?} in three elements", w[0]);
    }
    let mut i = 0;
    while i < edges.len() {
        let shared = i + 1 < edges.len() && edges[i + 1] == edges[i];
        if !shared {
            let (a, b) = edges[i];
            assert!(legit.contains(&pair(anc, a, b)), "round {round}: face ({a}, {b}) is neither boundary nor crack");
        }
        i += if shared { 2 } else { 1 };
    }
}

#[test]
fn thousands_of_random_insertions_keep_the_mesh_valid() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut insertions = 0usize;
    let mut splits = 0usize;
    let mut round = 0usize;
    while insertions < 3000 {
        round += 1;
        let (mut x, mut t) = random_mesh(&mut rng);
        let params = FractureParams {
            min_quality: 0.1 + 0.2 * rng.uniform(),
            min_altitude: if rng.next() % 2 == 0 { 0.0 } else { 0.05 + 0.1 * rng.uniform() },
            ..FractureParams::default()
        };
        let total: f64 = t.iter().map(|&e| area2(&x, e)).sum();
        let floor_q =
            t.iter().map(|&e| quality(x[e[0] as usize], x[e[1] as usize], x[e[2] as usize])).fold(1.0, f64::min);
        let floor_h =
            t.iter().map(|&e| altitude(x[e[0] as usize], x[e[1] as usize], x[e[2] as usize])).fold(f64::MAX, f64::min);
        let mut cracked: Vec<bool> = vec![false; x.len()];
        let mut anc: Vec<u32> = (0..x.len() as u32).collect();
        let mut legit = std::collections::BTreeSet::new();
        {
            let mut edges: Vec<(u32, u32)> = t
                .iter()
                .flat_map(|e| (0..3).map(move |k| (e[k].min(e[(k + 1) % 3]), e[k].max(e[(k + 1) % 3]))))
                .collect();
            edges.sort_unstable();
            for (k, e) in edges.iter().enumerate() {
                let dup = (k > 0 && edges[k - 1] == *e) || (k + 1 < edges.len() && edges[k + 1] == *e);
                if !dup {
                    legit.insert(*e);
                }
            }
        }
        // one preferred direction per mesh, with scatter, as a load would give
        let base = std::f64::consts::PI * rng.uniform();
        for _check in 0..12 {
            let csr = node_elements(x.len(), &t);
            let active = vec![true; t.len()];
            let normal: Vec<f64> = (0..x.len()).map(|_| base + 0.6 * (rng.uniform() - 0.5)).collect();
            let mut candidates: Vec<u32> = (0..x.len() as u32).filter(|_| rng.next() % 3 == 0).collect();
            for i in (1..candidates.len()).rev() {
                candidates.swap(i, (rng.next() % (i as u64 + 1)) as usize);
            }
            let failure = NodeFailure { normal: &normal, cracked: &cracked };
            let edits = plan(&mut PlanScratch::default(), &t, &active, &csr, &x, &candidates, &failure, &params);
            // planned in parallel, the same edits as one candidate at a time
            assert_eq!(edits, plan_in_order(&t, &active, &csr, &x, &candidates, &failure, &params), "round {round}");
            let n_before = x.len();
            apply(&mut x, &mut t, &edits);
            insertions += edits.inserted_at.len();
            splits += edits.added.len();
            cracked.resize(x.len(), false);
            for &[p, w] in &edits.crack_faces {
                cracked[p as usize] = true;
                cracked[w as usize] = true;
            }
            for (i, nn) in edits.new_nodes.iter().enumerate() {
                match *nn {
                    NewNode::Copy { of } => {
                        assert!((of as usize) < n_before, "round {round}: copy of a node created in the same check");
                        cracked[n_before + i] = true;
                        anc.push(anc[of as usize]);
                    }
                    NewNode::OnEdge { t: s, .. } => {
                        assert!(s > 0.0 && s < 1.0, "round {round}: edge node at {s}");
                        anc.push((n_before + i) as u32);
                    }
                }
            }
            for &([q, r], m) in &edits.split_edges {
                if legit.contains(&pair(&anc, q, r)) {
                    legit.insert(pair(&anc, q, m));
                    legit.insert(pair(&anc, m, r));
                }
            }
            for &[p, w] in &edits.crack_faces {
                legit.insert(pair(&anc, p, w));
            }
            // validity after every check
            let now: f64 = t.iter().map(|&e| area2(&x, e)).sum();
            assert!((now - total).abs() <= 1e-12 * total, "round {round}: area {now} != {total}");
            for (e, &tri) in t.iter().enumerate() {
                let [a, b, c] = tri.map(|v| x[v as usize]);
                assert!(area2(&x, tri) > 0.0, "round {round}: element {e} inverted or flat");
                let q = quality(a, b, c);
                assert!(q >= params.min_quality.min(floor_q) - 1e-12, "round {round}: element {e} quality {q}");
                let h = altitude(a, b, c);
                assert!(h >= params.min_altitude.min(floor_h) - 1e-12, "round {round}: element {e} altitude {h}");
            }
            check_conforming(&t, &anc, &legit, round);
        }
    }
    assert!(splits > 500, "the fuzz must exercise element splits too ({splits})");
    eprintln!("{round} meshes, {insertions} insertions, {splits} split pieces");
}
