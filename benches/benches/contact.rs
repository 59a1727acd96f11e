//! Contact kernels on a grid of touching blocks (node-on-node interfaces
//! everywhere): broad-phase build cost per facet, and node-to-segment pair
//! evaluations per second (every candidate pair counted), at 1 and 2
//! threads, for 10^4 to 10^6 facets.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use fdem_benches::block_grid;
use fdem_contact::narrow::{self, ContactPartial, Contacts, FacetFrame, NarrowInputs};
use fdem_contact::{BroadPhase, ContactState, InterfaceLaw, NodeContact, Surface};

fn contact(c: &mut Criterion) {
    let law = InterfaceLaw::new(3e10, 3e10, 0.6, 0.0, 0.5).unwrap();
    let mut build = c.benchmark_group("broad_phase_build");
    build.sample_size(10);
    for side in [50usize, 158, 500] {
        let (mut x, facets, apex) = block_grid(side, side);
        // a small compression so that every interface is in contact
        for p in &mut x {
            p[0] *= 0.99999;
            p[1] *= 0.99999;
        }
        let list: Vec<([u32; 2], u16)> = facets.iter().map(|&f| (f, 0)).collect();
        let surface = Surface::new(x.len(), &list, &x, &apex);
        let nf = surface.facets.len() as u64;
        build.throughput(Throughput::Elements(nf));
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut bp = BroadPhase::new(0.2);
            build.bench_function(BenchmarkId::new(format!("facets_{nf}"), threads), |b| {
                b.iter(|| {
                    bp.invalidate();
                    pool.install(|| bp.build(&surface, &x));
                })
            });
        }
    }
    build.finish();
    let mut narrow_g = c.benchmark_group("narrow_phase");
    narrow_g.sample_size(10);
    for side in [50usize, 158, 500] {
        let (mut x, facets, apex) = block_grid(side, side);
        for p in &mut x {
            p[0] *= 0.99999;
            p[1] *= 0.99999;
        }
        let list: Vec<([u32; 2], u16)> = facets.iter().map(|&f| (f, 0)).collect();
        let surface = Surface::new(x.len(), &list, &x, &apex);
        let v = vec![[0.0; 2]; x.len()];
        let mass = vec![1.0; x.len()];
        let mut bp = BroadPhase::new(0.2);
        bp.build(&surface, &x);
        let pairs = bp.pairs() as u64;
        narrow_g.throughput(Throughput::Elements(pairs));
        let nb = surface.nodes.len();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (mut states, mut corner_states) =
                (vec![ContactState::default(); nb], vec![ContactState::default(); nb]);
            // empty contacts, as the solver starts them (`facet: NONE`)
            let empty = NodeContact { facet: fdem_contact::NONE, ..Default::default() };
            let (mut out, mut corner_out) = (vec![empty; nb], vec![empty; nb]);
            let mut partials = vec![ContactPartial::default(); nb.div_ceil(fdem_contact::CHUNK)];
            let mut busy = vec![0; nb];
            let laws = [law];
            let mut frames = vec![FacetFrame::default(); surface.facets.len()];
            // one evaluation as the solver does it: the facets' frames, then
            // the candidates
            narrow_g.bench_function(BenchmarkId::new(format!("pairs_{pairs}"), threads), |b| {
                b.iter(|| {
                    pool.install(|| {
                        narrow::facet_frames(&surface, &x, &mut frames);
                        let inp = NarrowInputs {
                            x: &x,
                            x_ref: &x,
                            v: &v,
                            mass: &mass,
                            surface: &surface,
                            frames: &frames,
                            candidates: &bp.candidates,
                            laws: &laws,
                            resumed: &[],
                            dt: 1e-6,
                        };
                        let c = Contacts {
                            states: &mut states,
                            corner_states: &mut corner_states,
                            out: &mut out,
                            corner_out: &mut corner_out,
                            busy: &mut busy,
                        };
                        narrow::evaluate(&inp, c, &mut partials)
                    })
                })
            });
        }
    }
    narrow_g.finish();
}

criterion_group!(benches, contact);
criterion_main!(benches);
