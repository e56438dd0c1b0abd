//! A feedback fit (nonlinear LFR) of 10 000 samples with a cubic stiffness on the output of a
//! second-order block, 40 dB: the default fit (gap order and the next, each from two starts,
//! refined) and the fixed-order one. Target (release): < 1 s.

use criterion::{Criterion, criterion_group, criterion_main};
use hammerstein::IoData;
use hammerstein::feedback::{self, FeedbackKind, FeedbackOn, FeedbackSettings};
use std::hint::black_box;

/// x+ = A x + B (u + w), y = x₁, w = −0.02 y³; the input a seeded filtered noise.
fn record(n: usize) -> IoData<f64> {
    let mut state = 12345u64;
    let mut rnd = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let (a1, a2) = (2.0 * 0.95 * 0.3f64.cos(), -0.95 * 0.95);
    let (mut x1, mut x2, mut s) = (0.0f64, 0.0f64, 0.0f64);
    let mut u = Vec::with_capacity(n);
    let mut y = Vec::with_capacity(n);
    for _ in 0..n {
        s = 0.7 * s + 0.08 * rnd();
        let w = -0.02 * x1.powi(3);
        u.push(s);
        y.push(x1 + 0.01 * rnd());
        let n1 = a1 * x1 + x2 + s + w;
        let n2 = a2 * x1 + 0.5 * (s + w);
        (x1, x2) = (n1, n2);
    }
    IoData::siso(&u, &y).unwrap()
}

fn bench(c: &mut Criterion) {
    let data = record(10_000);
    let default = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    let mut fixed = default.clone();
    fixed.order = hammerstein::Order::Fixed(2);
    let mut g = c.benchmark_group("feedback");
    g.sample_size(10);
    g.bench_function("fit_poly3_10000_default", |b| {
        b.iter(|| black_box(feedback::fit(&default, black_box(&data)).unwrap()))
    });
    g.bench_function("fit_poly3_10000_order2", |b| {
        b.iter(|| black_box(feedback::fit(&fixed, black_box(&data)).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
