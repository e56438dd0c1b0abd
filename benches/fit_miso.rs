//! A two-input fit of 2000 samples with one UDN per input (issue 12: < 50 ms): input 1 through
//! the paper's saturation with hysteresis into its second-order block, input 2 through a
//! dead-zone into a first-order block, summed, 30 dB. Default settings per branch (order
//! selection, feed-through decision, refinement) and with each branch's order given.

#[path = "common/miso_record.rs"]
mod miso_record;

use criterion::{Criterion, criterion_group, criterion_main};
use hammerstein::miso::MisoHammerstein;
use hammerstein::{Hammerstein, Order};
use miso_record::{default_settings, effects, record};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let data = record();
    let (sh, dz) = effects();
    let default = default_settings();
    let fixed = MisoHammerstein::new(vec![
        Hammerstein::udn(sh).order(Order::Fixed(2)).with_d(false),
        Hammerstein::udn(dz).order(Order::Fixed(1)).with_d(false),
    ]);
    let model = default.fit(&data).unwrap();
    eprintln!(
        "default: orders {:?}, sweeps {}, train MSE {:.3e}",
        model
            .branches()
            .iter()
            .map(|b| b.linear().order())
            .collect::<Vec<_>>(),
        model.report().sweeps.len(),
        model.report().train_mse
    );
    c.bench_function("fit_two_inputs_2000_default", |b| {
        b.iter(|| black_box(default.fit(black_box(&data)).unwrap()))
    });
    c.bench_function("fit_two_inputs_2000_orders_given", |b| {
        b.iter(|| black_box(fixed.fit(black_box(&data)).unwrap()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
