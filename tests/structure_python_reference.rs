//! The BLA against the `best-linear-approximation` Python package (0.1.1, PyPI;
//! `robust.known_input`) on one small committed record: a Wiener–Hammerstein plant excited by
//! `hammerstein design` (4 realizations x 3 steady periods of 256 samples, output noise). The
//! package's numbers were computed once by `tests/data/structure_bla_small.py` and committed in
//! `tests/data/structure_bla_small_reference.csv`; the package is not needed here.

use hammerstein::structure::{BlaMethod, Record, bla};

#[test]
fn bla_matches_the_python_package_on_the_committed_record() {
    let t = hammerstein::data::CsvTable::read("tests/data/structure_bla_small.csv").unwrap();
    let r = Record::from_columns(&t.names, &t.columns, "u", Some("y"), "small").unwrap();
    let b = bla(&r).unwrap();
    let text = std::fs::read_to_string("tests/data/structure_bla_small_reference.csv").unwrap();
    let reference: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('k'))
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let level = &b.levels[0];
    assert_eq!(level.method, BlaMethod::Robust);
    assert_eq!(level.lines.len(), reference.len(), "excited lines differ");
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
    for (line, want) in level.lines.iter().zip(&reference) {
        assert_eq!(line.k, want[0] as usize);
        assert!(
            close(line.g.0, want[1]) && close(line.g.1, want[2]),
            "line {}: {:?} vs {want:?}",
            line.k,
            line.g
        );
        assert!(
            close(line.var_total, want[3]),
            "line {} total variance {} vs {}",
            line.k,
            line.var_total,
            want[3]
        );
        let vn = line.var_noise.unwrap();
        assert!(
            close(vn, want[4]),
            "line {} noise variance {vn} vs {}",
            line.k,
            want[4]
        );
    }
}
