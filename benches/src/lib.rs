//! Shared set-up for the criterion benchmarks: structured test models built
//! directly in Rust, so a bench measures the kernel and nothing else.

use fdem_solver::{Constraint, LawSpec, MaterialSpec, ModelSpec, PressureLoad};

/// A block of `nx × ny` cells (2 triangles each, 1 m cells) of rock under
/// gravity with rollers on the sides and base and a pressure on top.
pub fn block(nx: usize, ny: usize) -> ModelSpec {
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut points = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            points.push([i as f64, j as f64]);
        }
    }
    let mut triangles = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                triangles.push([a, b, c].map(u64::from));
                triangles.push([a, c, d].map(u64::from));
            } else {
                triangles.push([a, b, d].map(u64::from));
                triangles.push([b, c, d].map(u64::from));
            }
        }
    }
    let roller = |node, fixed| Constraint { node, fixed, value: [0.0; 2], amplitude: None };
    let mut constraints = Vec::new();
    for i in 0..=nx {
        constraints.push(roller(id(i, 0), [false, true]));
    }
    for j in 0..=ny {
        constraints.push(roller(id(0, j), [true, false]));
        constraints.push(roller(id(nx, j), [true, false]));
    }
    let pressures =
        (0..nx).map(|i| PressureLoad { nodes: [id(i, ny), id(i + 1, ny)], pressure: 1e6, amplitude: None }).collect();
    let m = triangles.len();
    ModelSpec {
        points,
        triangles,
        materials: vec![MaterialSpec { density: 3100.0, young: 60e9, poisson: 0.25, law: LawSpec::Elastic }],
        element_material: vec![0; m],
        gravity: [0.0, -9.81],
        constraints,
        pressures,
        ..Default::default()
    }
}

/// A grid of `nx × ny` separate unit squares (each two triangles, its own
/// four nodes), touching their neighbours node on node: every square side
/// is a contact interface. Returns node positions and the boundary facets
/// (counter-clockwise per square), `4 nx ny` of them.
#[allow(clippy::type_complexity)]
pub fn block_grid(nx: usize, ny: usize) -> (Vec<[f64; 2]>, Vec<[u32; 2]>, Vec<[f64; 2]>) {
    let mut x = Vec::with_capacity(4 * nx * ny);
    let mut facets = Vec::with_capacity(4 * nx * ny);
    let mut apex = Vec::with_capacity(4 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let base = x.len() as u32;
            let (x0, y0) = (i as f64, j as f64);
            x.extend_from_slice(&[[x0, y0], [x0 + 1.0, y0], [x0 + 1.0, y0 + 1.0], [x0, y0 + 1.0]]);
            for k in 0..4u32 {
                facets.push([base + k, base + (k + 1) % 4]);
                apex.push([x0 + 0.5, y0 + 0.5]);
            }
        }
    }
    (x, facets, apex)
}
