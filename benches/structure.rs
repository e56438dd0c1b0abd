//! BLA and structure verdict of a 1e6-sample multisine record: random odd, 8192 samples per
//! period, 3 levels x 4 realizations x (1 transient + 9 steady) periods = 983 040 samples, a
//! Wiener–Hammerstein plant (second-order blocks around a cubic) with output noise.

use criterion::{Criterion, criterion_group, criterion_main};
use hammerstein::structure::{
    MultisineDesign, MultisineKind, Record, StructureOptions, analyze, bla,
};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::hint::black_box;

fn filter(b: [f64; 3], a: [f64; 3], x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; x.len()];
    for t in 0..x.len() {
        let mut v = b[0] * x[t];
        if t >= 1 {
            v += b[1] * x[t - 1] - a[1] * y[t - 1];
        }
        if t >= 2 {
            v += b[2] * x[t - 2] - a[2] * y[t - 2];
        }
        y[t] = v;
    }
    y
}

fn record() -> Record {
    let design = MultisineDesign {
        kind: MultisineKind::RandomOdd { group: 4 },
        samples: 8192,
        band: (0.01, 0.2),
        levels: vec![0.25, 0.5, 1.0],
        realizations: 4,
        periods: 9,
        seed: 5,
    };
    let r = design.generate().unwrap();
    let mut rng = StdRng::seed_from_u64(6);
    r.replayed(|b| {
        let x = filter([0.2, 0.1, 0.0], [1.0, -1.2, 0.6], &b.u);
        let x: Vec<f64> = x.iter().map(|v| v + 0.3 * v * v * v).collect();
        filter([0.3, 0.2, 0.0], [1.0, -0.5, 0.3], &x)
            .into_iter()
            .map(|v| v + 1e-3 * rng.random_range(-1.0..1.0))
            .collect()
    })
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let r = record();
    assert!(r.blocks().iter().map(|b| b.u.len()).sum::<usize>() > 980_000);
    let mut g = c.benchmark_group("structure");
    g.sample_size(10);
    g.bench_function("bla_1e6", |b| b.iter(|| black_box(bla(&r).unwrap())));
    let bl = bla(&r).unwrap();
    g.bench_function("structure_from_bla_1e6", |b| {
        b.iter(|| black_box(analyze(&bl, &StructureOptions::default()).unwrap()))
    });
    g.bench_function("bla_and_structure_1e6", |b| {
        b.iter(|| black_box(analyze(&bla(&r).unwrap(), &StructureOptions::default()).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
