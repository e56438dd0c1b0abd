//! A reduced Example 1 Monte Carlo study (the paper's Section 4.1): mean targets, noise-free
//! exactness and the ratio of the spread to the Cramér–Rao bound. The full 50-run study of all
//! seven settings is the ignored test `full_study_meets_targets` (run with `--ignored`, release).

use hammerstein::study::crlb::{SnrDefinition, crlb_from_information, expected_information};
use hammerstein::study::monte_carlo::{Setting, Strategy, StudyConfig, Table};
use hammerstein::study::targets::{CRLB_RATIO_TARGET, TargetKind, mean_target};
use hammerstein::study::{Example1, check_targets, paper_settings, run_study};

fn config(settings: Vec<Setting>, runs: usize, strategy: Strategy) -> StudyConfig {
    StudyConfig {
        runs,
        seed: 100,
        strategy,
        settings,
        ..StudyConfig::default()
    }
}

#[test]
fn exact_sh_is_unbiased_and_near_the_bound() {
    let runs = 16;
    let settings = vec![
        Setting {
            table: Table::Table3,
            snr_db: None,
        },
        Setting {
            table: Table::Table3,
            snr_db: Some(10.0),
        },
    ];
    let res = run_study::<f64>(&config(settings, runs, Strategy::PaperLoop), &|| {}).unwrap();
    let design = Example1::new(Some(10.0));
    let (info, var_y) = expected_information(&design, 10, 77).unwrap();
    let bound = crlb_from_information(&info, var_y, 2000, 10.0, SnrDefinition::Power).unwrap();
    // noise-free: every run exact
    assert_eq!(res[0].successes, runs, "{:?}", res[0].failures);
    for p in &res[0].params {
        assert!(
            p.max_abs_error < 1e-6,
            "{} error {}",
            p.name,
            p.max_abs_error
        );
    }
    // 10 dB: unbiased within 2 % or 3 SE; the spread at the bound
    let r = &res[1];
    assert_eq!(r.successes, runs, "{:?}", r.failures);
    // with M runs a std estimate has relative standard error ≈ 1/√(2M): allow two of them
    let allowance = 1.0 + 2.0 / (2.0 * runs as f64).sqrt();
    let mut ratios = Vec::new();
    for p in &r.params {
        let (ok, detail) = mean_target(p.truth, p.mean, p.std, runs);
        assert!(ok, "{}: {detail}", p.name);
        if let Some(b) = bound.get(&p.name) {
            let ratio = p.std / b;
            eprintln!("{} std {:.4} CRLB {:.4} ratio {ratio:.2}", p.name, p.std, b);
            assert!(
                ratio < CRLB_RATIO_TARGET * allowance,
                "{}: ratio {ratio}",
                p.name
            );
            ratios.push(ratio);
        }
    }
    let rms = (ratios.iter().map(|x| x * x).sum::<f64>() / ratios.len() as f64).sqrt();
    assert!(rms < CRLB_RATIO_TARGET, "RMS ratio {rms}");
}

/// Table 2's best configuration: BIC picks SH over the 16 UDN subsets, absent effects are 0.
/// (The paper's loop alone with the full UDN is biased here: b ≥ 0 sits on its boundary and the
/// dead-zone/preload confounding pulls z2; see docs/paper-reproduction.md.)
#[test]
fn udn_structure_decision_finds_sh_at_10_db() {
    let runs = 4;
    let settings = vec![Setting {
        table: Table::Table2,
        snr_db: Some(10.0),
    }];
    let res = run_study::<f64>(&config(settings, runs, Strategy::Best), &|| {}).unwrap();
    let r = &res[0];
    assert_eq!(r.successes, runs, "{:?}", r.failures);
    assert_eq!(
        r.structures,
        vec![("hysteresis,saturation".to_string(), runs)]
    );
    for p in &r.params {
        let (ok, detail) = mean_target(p.truth, p.mean, p.std, runs);
        assert!(ok, "{}: {detail}", p.name);
    }
}

/// The full study (50 runs × 7 settings, best configuration): every acceptance target.
#[test]
#[ignore = "full study: run with --release -- --ignored"]
fn full_study_meets_targets() {
    let res = run_study::<f64>(&config(paper_settings(), 50, Strategy::Best), &|| {}).unwrap();
    let design = Example1::new(Some(10.0));
    let (info, var_y) = expected_information(&design, 20, 77).unwrap();
    let crlb = |s: f64| crlb_from_information(&info, var_y, 2000, s, SnrDefinition::Power).ok();
    let checks = check_targets(&res, &crlb);
    let missed: Vec<_> = checks.iter().filter(|c| !c.met).collect();
    assert!(
        checks.iter().any(|c| c.kind == TargetKind::CrlbRatio),
        "no CRLB check ran"
    );
    assert!(missed.is_empty(), "missed targets: {missed:#?}");
}
