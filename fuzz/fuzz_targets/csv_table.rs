//! The CSV reader on arbitrary bytes, and everything a caller does with a parsed table:
//! Ok or a typed error, never a panic.
#![no_main]

use hammerstein::data::CsvTable;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(t) = CsvTable::parse(data, "fuzz.csv") {
        assert_eq!(t.columns.len(), t.names.len());
        let _ = t.data_columns();
        let _ = t.sample_time();
        let _ = t.column("u");
        if let Ok(d) = t.io_data::<f64>(&["u"], &["y"]) {
            let _ = d.split_validation(0.3);
            let _ = d.check_horizon(5);
            let _ = d.detrend_mean();
        }
        let _ = t.io_data::<f32>(&["u"], &["y"]);
        // every column as input and the last as output, as `subspace --inputs` may ask
        let names: Vec<&str> = t.names.iter().map(|s| s.as_str()).collect();
        if let Some((last, rest)) = names.split_last() {
            let _ = t.io_data::<f64>(rest, &[last]);
        }
    }
});
