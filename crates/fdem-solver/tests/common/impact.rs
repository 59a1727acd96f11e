//! The fragmenting impact of `benchmarks/fracture_impact.py` on a
//! structured mesh, as a `ModelSpec`: shared by the determinism test and the
//! `state_hash` example (which includes this file by path).

use fdem_solver::{Constraint, ContactSpec, CrackBand, FractureSpec, InterfaceSpec, LawSpec, MaterialSpec, ModelSpec};

/// A 1 m × 0.5 m block of `2·nx·ny` right triangles 1 mm above a fixed
/// platen one cell high, the block's nodes moving down at 10 m/s.
pub fn impact(nx: usize, ny: usize) -> ModelSpec {
    let (width, height, gap, speed) = (1.0, 0.5, 1e-3, 10.0);
    let h = width / nx as f64;
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    grid(&mut points, &mut triangles, [0.0, gap], [nx, ny], [h, height / ny as f64]);
    let block_nodes = points.len();
    let block_elements = triangles.len();
    let platen_nx = (1.4 * nx as f64) as usize;
    grid(&mut points, &mut triangles, [-0.2 * width, -h], [platen_nx, 1], [1.4 * width / platen_nx as f64, h]);
    let young = 30e9;
    let rock = MaterialSpec {
        density: 2700.0,
        young,
        poisson: 0.25,
        law: LawSpec::MohrCoulombRankine {
            cohesion: 10e6,
            friction: 35f64.to_radians(),
            dilation: 5f64.to_radians(),
            tensile_strength: 5e6,
            fracture_energy: 30.0,
            shear_fracture_energy: 30.0,
            crack_band: CrackBand::Oliver,
            softening: fdem_solver::Softening::Linear,
        },
    };
    let platen = MaterialSpec { density: 2700.0, young, poisson: 0.25, law: LawSpec::Elastic };
    let n = points.len();
    let constraints = (block_nodes..n)
        .filter(|&i| i < block_nodes + platen_nx + 1)
        .map(|i| Constraint { node: i as u32, fixed: [true, true], value: [0.0; 2], amplitude: None })
        .collect();
    let mut element_material = vec![0; block_elements];
    element_material.resize(triangles.len(), 1);
    let mut s = ModelSpec {
        points,
        triangles,
        materials: vec![rock, platen],
        element_material,
        constraints,
        initial_velocity: Some((0..n).map(|i| if i < block_nodes { [0.0, -speed] } else { [0.0; 2] }).collect()),
        contact: Some(ContactSpec {
            laws: vec![InterfaceSpec {
                normal_stiffness: 10.0 * young / h,
                shear_stiffness: 10.0 * young / h,
                friction: 0.6,
                cohesion: 0.0,
                damping_ratio: 0.5,
            }],
            facet_laws: Vec::new(),
            crack_law: 0,
            margin: None,
        }),
        fracture: Some(FractureSpec { params: Default::default(), interval: 5, insert_at: 0.02 }),
        ..Default::default()
    };
    s.settings.stiffness_damping = 2e-7;
    s.settings.renumber = Some(0.1);
    s
}

/// Appends a grid of `n[0] × n[1]` cells of size `h`, each split into two
/// counter-clockwise right triangles, with its lower left corner at `origin`.
fn grid(points: &mut Vec<[f64; 2]>, triangles: &mut Vec<[u64; 3]>, origin: [f64; 2], n: [usize; 2], h: [f64; 2]) {
    let base = points.len() as u64;
    let [nx, ny] = n;
    points.extend(
        (0..=ny).flat_map(|j| (0..=nx).map(move |i| [origin[0] + i as f64 * h[0], origin[1] + j as f64 * h[1]])),
    );
    let id = |i: usize, j: usize| base + (j * (nx + 1) + i) as u64;
    for j in 0..ny {
        for i in 0..nx {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
}
