//! The multisine design and the record format: lines, levels, round trip, and the BLA of a
//! linear system against its true frequency response.

mod structure_common;

use hammerstein::structure::{BlaMethod, MultisineDesign, MultisineKind, Record, bla};
use structure_common::{Family, Iir, Plant, replay};

#[test]
fn random_odd_design_leaves_one_odd_line_per_group_and_scales_levels() {
    let d = MultisineDesign::default();
    let lines = d.excited_lines();
    assert!(lines.iter().all(|k| k % 2 == 1));
    let odd_in_band: Vec<usize> = (11..=204).filter(|k| k % 2 == 1).collect();
    // one line out per full group of 4
    assert_eq!(lines.len(), odd_in_band.len() - odd_in_band.len() / 4);
    let r = d.generate().unwrap();
    assert_eq!(r.levels(), 3);
    assert_eq!(r.blocks().len(), 12);
    for (l, want) in d.levels.iter().enumerate() {
        assert!(
            (r.rms(l) - want).abs() < 1e-9 * want,
            "level {l}: {}",
            r.rms(l)
        );
    }
    // every block repeats its period
    let n = r.period();
    for b in r.blocks() {
        assert_eq!(b.u.len(), 3 * n);
        assert!((0..n).all(|i| (b.u[i] - b.u[i + 2 * n]).abs() < 1e-12));
    }
    // the same seed gives the same design, another seed another one
    assert_eq!(d.generate().unwrap(), r);
    let other = MultisineDesign {
        seed: 8,
        ..d.clone()
    }
    .generate()
    .unwrap();
    assert_ne!(other, r);
    // the excited lines are those the analysis finds in the record
    assert_eq!(
        hammerstein::structure::bla::excited_lines(&r).unwrap(),
        lines
    );
}

#[test]
fn bad_designs_are_refused() {
    let d = MultisineDesign::default();
    for bad in [
        MultisineDesign {
            band: (0.2, 0.1),
            ..d.clone()
        },
        MultisineDesign {
            band: (0.1, 0.6),
            ..d.clone()
        },
        MultisineDesign {
            levels: vec![1.0, 0.5],
            ..d.clone()
        },
        MultisineDesign {
            levels: vec![],
            ..d.clone()
        },
        MultisineDesign {
            kind: MultisineKind::RandomOdd { group: 1 },
            ..d.clone()
        },
        MultisineDesign {
            band: (0.1001, 0.1002),
            ..d.clone()
        },
    ] {
        assert!(bad.generate().is_err(), "{bad:?}");
    }
}

#[test]
fn record_round_trips_through_csv() {
    let d = MultisineDesign {
        samples: 64,
        band: (0.05, 0.3),
        levels: vec![0.5, 1.0],
        realizations: 2,
        periods: 2,
        kind: MultisineKind::Full,
        seed: 3,
    };
    let r = d.generate().unwrap();
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(1);
    let plant = Plant::random(Family::Linear, &mut rng, 1.0, 1.0);
    let m = replay(&r, &plant, 40.0, 2).unwrap();
    let mut bytes = Vec::new();
    m.write_csv(&mut bytes).unwrap();
    let t = hammerstein::data::CsvTable::parse(&bytes, "mem").unwrap();
    let back = Record::from_columns(&t.names, &t.columns, "u", Some("y"), "mem").unwrap();
    assert_eq!(back.period(), 64);
    assert_eq!(back.blocks().len(), 4);
    for (a, b) in back.blocks().iter().zip(m.blocks()) {
        assert_eq!((a.level, a.realization), (b.level, b.realization));
        assert!(
            a.u.iter()
                .zip(&b.u)
                .all(|(x, y)| (x - y).abs() <= 1e-12 * y.abs().max(1.0))
        );
    }
    // a record written by level with swapped RMS is renumbered by merge
    let lo = Record::from_periodic(&m.blocks()[0].u, m.blocks()[0].y.as_ref().unwrap(), 64, "a")
        .unwrap();
    let hi = Record::from_periodic(&m.blocks()[2].u, m.blocks()[2].y.as_ref().unwrap(), 64, "b")
        .unwrap();
    let joined = Record::merge(vec![hi, lo]).unwrap();
    assert!(joined.rms(0) < joined.rms(1));
}

#[test]
fn bla_of_a_linear_system_matches_its_frequency_response_within_its_errors() {
    let d = MultisineDesign::default();
    let r = d.generate().unwrap();
    let g = Iir {
        b: [0.2, 0.1, 0.0],
        a: [1.0, -1.2, 0.6],
    };
    let plant = Plant {
        family: Family::Linear,
        g1: g.clone(),
        g2: g.clone(),
        f: structure_common::Poly {
            c2: 0.0,
            c3: 0.0,
            sigma: 1.0,
        },
    };
    let m = replay(&r, &plant, 40.0, 9).unwrap();
    let b = bla(&m).unwrap();
    for l in &b.levels {
        assert_eq!(l.method, BlaMethod::Robust);
        let mut z2 = 0.0;
        for line in &l.lines {
            let z = hammerstein::structure::bla::C64::from_polar(
                1.0,
                -std::f64::consts::TAU * line.freq,
            );
            let h = (z * z * 0.0 + z * 0.1 + 0.2) / (z * z * 0.6 + z * -1.2 + 1.0);
            z2 += (line.value() - h).norm_sqr() / line.var_total;
        }
        // E|G − G0|²/σ̂² ≈ 1 per line (σ̂² from 4 realizations: mean 3/2 for an inverse χ²₆/6)
        let mean = z2 / l.lines.len() as f64;
        assert!(mean > 0.5 && mean < 3.0, "level {}: {mean}", l.level);
        let nl = l.nonlinearity.as_ref().unwrap();
        assert!(!nl.detected, "linear system called nonlinear: {nl:?}");
    }
}
