//! A fuzzed CSV record all the way through identification: parsed, validated, split, then the
//! subspace identification and a linear Hammerstein fit with a short horizon. Ok or a typed
//! error, never a panic (slower per input than `csv_table`; the parser itself is fuzzed there).
#![no_main]

use hammerstein::data::CsvTable;
use hammerstein::subspace::{MethodKind, Order, SubspaceOptions, identify};
use hammerstein::{Faer, Hammerstein, IoData};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(t) = CsvTable::parse(data, "fuzz.csv") else {
        return;
    };
    let Ok(d) = t.io_data::<f64>(&["u"], &["y"]) else {
        return;
    };
    // the first byte picks the horizon, the order rule and the method
    let b = data.first().copied().unwrap_or(0) as usize;
    let horizon = 2 + b % 4;
    let order = if b & 0x10 != 0 {
        Order::Auto
    } else {
        Order::Fixed(1 + (b >> 5) % 3)
    };
    let kind = if b & 0x80 != 0 {
        MethodKind::N4sid
    } else {
        MethodKind::Moesp
    };
    if let Ok(m) = kind.build::<f64>(horizon) {
        let opts = SubspaceOptions {
            order: order.clone(),
            ..Default::default()
        };
        let _ = identify(m.as_ref(), &Faer::default(), &[d.view()], &opts);
    }
    let fit = Hammerstein::<f64>::linear()
        .horizon(horizon)
        .order(order)
        .method(kind)
        .max_iter(3);
    if let Ok(model) = fit.fit(&d) {
        let _ = hammerstein::diagnosis::compare(&model, &d);
    }
    let _: Result<IoData<f32>, _> = t.io_data::<f32>(&["u"], &["y"]);
});
