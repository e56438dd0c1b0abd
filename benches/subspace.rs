//! Subspace identification speed: SISO order 2, horizon 10, N = 1e4, 1e5, 1e6 (Cholesky and QR
//! compression), and the Hammerstein loop's inner step (N = 2000, 7 regressor inputs, 1 output).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use hammerstein::subspace::{Compression, MethodKind, Order, SubspaceOptions, identify};
use hammerstein::{Faer, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::hint::black_box;

fn record(n: usize, m: usize, seed: u64) -> IoData<f64> {
    let sys = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    let u = faer::Mat::from_fn(n, m, |_, _| rng.random_range(-3.0..3.0));
    // the system is driven by the sum of the inputs; output noise makes HᵀH well conditioned
    let s: Vec<f64> = (0..n).map(|k| (0..m).map(|j| u[(k, j)]).sum()).collect();
    let y = sys.simulate_siso(&s, None).unwrap();
    let y = faer::Mat::from_fn(n, 1, |k, _| y[k] + 0.7 * rng.random_range(-1.0..1.0));
    IoData::new(u, y).unwrap()
}

fn bench(c: &mut Criterion) {
    let la = Faer::default();
    let opts = SubspaceOptions {
        order: Order::Fixed(2),
        ..Default::default()
    };
    let mut g = c.benchmark_group("siso_n2_i10");
    g.sample_size(10);
    for n in [10_000usize, 100_000, 1_000_000] {
        let d = record(n, 1, 1);
        for comp in [Compression::Cholesky, Compression::Qr] {
            let m = MethodKind::Moesp.build_with::<f64>(10, comp).unwrap();
            g.bench_with_input(BenchmarkId::new(format!("{comp:?}"), n), &d, |b, d| {
                b.iter(|| identify(m.as_ref(), &la, &[black_box(d.view())], &opts).unwrap())
            });
        }
    }
    g.finish();
    let mut g = c.benchmark_group("loop_step_n2000_m7");
    let d = record(2000, 7, 2);
    for i in [5usize, 10] {
        let m = MethodKind::Moesp.build::<f64>(i).unwrap();
        g.bench_with_input(BenchmarkId::new("moesp_cholesky", i), &d, |b, d| {
            b.iter(|| identify(m.as_ref(), &la, &[black_box(d.view())], &opts).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
