//! The element kernel alone (data in cache): co-rotational frame, elastic
//! trial stress, rotation to Cauchy stress, internal forces. Reports
//! element-updates per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fdem_element::corotational::corotational_frame;
use fdem_element::kinematics::reference_inverse;
use fdem_element::tensor::rotate;
use fdem_element::{internal_forces, Tri, Vec2};
use fdem_material::Elastic;
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

criterion_group!(benches, kernel);
criterion_main!(benches);
