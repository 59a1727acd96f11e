//! The element kernel alone (data in cache): co-rotational frame, elastic
//! trial stress, rotation to Cauchy stress, internal forces; and the
//! Mohr–Coulomb–Rankine update alone on a mix of material points like those
//! of caved rock. Reports element-updates (material-point updates) per
//! second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fdem_element::corotational::corotational_frame;
use fdem_element::kinematics::reference_inverse;
use fdem_element::tensor::rotate;
use fdem_element::{internal_forces, Tri, Vec2};
use fdem_material::{CrackBand, Elastic, Geometry, MohrCoulombRankine, PlasticState};
use std::hint::black_box;

fn kernel(c: &mut Criterion) {
    let n = 1024;
    let mat = Elastic::new(60e9, 0.25).unwrap();
    let xs: Vec<Tri<Vec2>> = (0..n)
        .map(|k| {
            let s = 1.0 + 1e-3 * (k % 7) as f64;
            [[0.0, 0.0], [s, 0.01], [0.02, s]]
        })
        .collect();
    let reference: Vec<_> = xs
        .iter()
        .map(|x| reference_inverse(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap_or_else(|| panic!("{x:?}")))
        .collect();
    let vs: Vec<Tri<Vec2>> = (0..n).map(|k| [[0.0, 0.0], [1e-3 * k as f64, 0.0], [0.0, -1e-3]]).collect();
    let mut stress = vec![[1e6, -2e6, 0.0, 3e5]; n];
    let mut forces = vec![[[0.0; 2]; 3]; n];
    let mut g = c.benchmark_group("element");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("elastic_update", |b| {
        b.iter(|| {
            for e in 0..n {
                let f = corotational_frame(&reference[e], &xs[e], &vs[e], 1e-5);
                let s = mat.trial(stress[e], f.d_hat, 1e-5);
                stress[e] = s;
                forces[e] = internal_forces(&xs[e], &rotate(s, f.cos_new, f.sin_new));
            }
            black_box(&forces);
        })
    });
    g.bench_function("elastic_update_batched", |b| {
        use fdem_element::batch::{corotational_frames, LANES};
        b.iter(|| {
            for e0 in (0..n).step_by(LANES) {
                let dm_inv = std::array::from_fn(|k| std::array::from_fn(|l| reference[e0 + l].dm_inv[k]));
                let x = std::array::from_fn(|k| std::array::from_fn(|l| xs[e0 + l][k / 2][k % 2]));
                let v = std::array::from_fn(|k| std::array::from_fn(|l| vs[e0 + l][k / 2][k % 2]));
                let f = corotational_frames(&dm_inv, &x, &v, 1e-5);
                for l in 0..LANES {
                    let e = e0 + l;
                    let s = mat.trial(stress[e], f.d_hat(l), 1e-5);
                    stress[e] = s;
                    forces[e] = internal_forces(&xs[e], &rotate(s, f.cos_new[l], f.sin_new[l]));
                }
            }
            black_box(&forces);
        })
    });
    g.finish();
}

/// The plastic update alone on 1 024 material points with the paper's
/// Table 1 rock (`fdem.caving.ROCK`), mixed as in the caving run at 3.5 s
/// (docs/caving.md: about half the elements plastic there, nearly all on
/// the σ1 tension plane): 30% elastic in compression, 50% cracked points
/// in tension on the σ1 plane (softening or fully softened), 10% cracked
/// points in biaxial tension (σ1 and σ2 planes), 10% uncracked points in
/// shear on the main Mohr–Coulomb plane. Every iteration starts from the
/// same states.
fn plastic(c: &mut Criterion) {
    let n = 1024;
    let law = MohrCoulombRankine::new(
        Elastic::new(60e9, 0.25).unwrap(),
        8e6,
        55f64.to_radians(),
        9f64.to_radians(),
        1e6,
        70.0,
        CrackBand::Oliver,
    )
    .unwrap();
    let geometry = Geometry { e1: [1.0, 0.0], e2: [0.5, 0.9] };
    let points: Vec<([f64; 4], PlasticState)> = (0..n)
        .map(|k| {
            let w = 1.0 + 0.01 * (k % 13) as f64;
            let cracked = PlasticState { kappa: 5e-5 * (k % 5) as f64, crack_band: 1.0, ..Default::default() };
            match k % 10 {
                0..=2 => ([-5e6 * w, -8e6, -3e6, 1e6], PlasticState::default()),
                3..=7 => ([1.5e6 * w, -1e6, 0.1e6, 0.3e6], cracked),
                8 => ([1e6 * w, 0.8e6, 0.3e6, 0.1e6], cracked),
                _ => ([-2e6, -60e6 * w, -15e6, 5e6], PlasticState::default()),
            }
        })
        .collect();
    let mut states: Vec<PlasticState> = points.iter().map(|p| p.1).collect();
    let mut stress = vec![[0.0; 4]; n];
    let mut g = c.benchmark_group("element");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("plastic_update", |b| {
        b.iter(|| {
            for (e, (trial, state)) in points.iter().enumerate() {
                states[e] = *state;
                let old = trial.map(|t| 0.9 * t);
                stress[e] = law.update(old, *trial, &mut states[e], || geometry).stress;
            }
            black_box((&stress, &states));
        })
    });
    g.finish();
}

criterion_group!(benches, kernel, plastic);
criterion_main!(benches);
