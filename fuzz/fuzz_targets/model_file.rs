//! The model-file loader on arbitrary text; a model that loads is simulated and compared:
//! Ok or a typed error, never a panic.
#![no_main]

use hammerstein::IoData;
use hammerstein::fit::HammersteinModel;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(m) = HammersteinModel::from_json(text) {
        let u: Vec<f64> = (0..64).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
        let _ = m.simulate(&u);
        let _ = m.simulate_finite(&u);
        let _ = m.transfer_function();
        let _ = m.parameters();
        let y: Vec<f64> = u.iter().map(|x| 0.5 * x + 1.0).collect();
        if let Ok(d) = IoData::siso(&u, &y) {
            let _ = hammerstein::diagnosis::compare(&m, &d);
        }
    }
});
