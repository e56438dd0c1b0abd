//! Screening of long records (issue 13): above the threshold the structure is chosen on a
//! leading window and the parameters are polished on the whole record; the fit and the
//! diagnosis must then match the whole-record ones closely. The threshold is lowered so that the
//! records stay small and the test fast.

mod hammerstein_common;
// the command-line file helpers alone: `common` whole would load `common/paper.rs` a second time
#[cfg(feature = "cli")]
#[allow(dead_code)]
#[path = "common/cli_io.rs"]
mod cli_io;

use hammerstein::IoData;
use hammerstein::diagnosis::{Diagnoser, compare, diagnose};
use hammerstein::fit::{Hammerstein, IterationRecord, Observer, Screening};
use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::subspace::Order;
use hammerstein_common::{example1_input, example1_linear};
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Records the stages reported and counts the iterations seen.
#[derive(Default)]
struct Watch {
    stages: Mutex<Vec<String>>,
    iterations: AtomicUsize,
}

impl Watch {
    /// The distinct stages, in the order first reported.
    fn stages(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for s in self.stages.lock().unwrap().iter() {
            if !out.contains(s) {
                out.push(s.clone());
            }
        }
        out
    }
}

impl Observer for Watch {
    fn observe_iteration(&self, _: usize, _: &IterationRecord) {
        self.iterations.fetch_add(1, Ordering::Relaxed);
    }
    fn progress(&self, stage: &str, _: usize, _: usize) {
        self.stages.lock().unwrap().push(stage.to_string());
    }
}

/// The saturation (limits 3 and −2) with hysteresis (a = 0.3, gain 2) of the records below.
fn saturated_hysteresis(u: &[f64]) -> Vec<f64> {
    let mut s = 1.0;
    (0..u.len())
        .map(|k| {
            if k > 0 && u[k] != u[k - 1] {
                s = if u[k] > u[k - 1] { 1.0 } else { -1.0 };
            }
            (2.0 * (u[k] - 0.3 * s)).clamp(-2.0, 3.0)
        })
        .collect()
}

/// Example 1's linear block after [`saturated_hysteresis`], 20 dB output noise, `n` samples.
fn noisy_record(n: usize, seed: u64) -> IoData<f64> {
    let u = example1_input::<f64>(n, seed);
    let y = example1_linear::<f64>()
        .simulate_siso(&saturated_hysteresis(&u), None)
        .unwrap();
    let var = y.iter().map(|v| v * v).sum::<f64>() / n as f64;
    let noise = Normal::new(0.0, (var / 100.0).sqrt()).unwrap();
    let mut rng = StdRng::seed_from_u64(seed + 100);
    let y: Vec<f64> = y.iter().map(|v| v + noise.sample(&mut rng)).collect();
    IoData::siso(&u, &y).unwrap()
}

/// A threshold below the training record's length, a window of a third of it.
fn lowered() -> Screening {
    Screening {
        threshold: 6_000,
        window: 3_000,
        ..Screening::default()
    }
}

/// A record whose output drifts slowly (a sensor's zero moving by twice the output's spread over
/// the record, half a period of a sine): a window of an eighth of it sees a short, nearly
/// straight piece of the drift, and the model fitted there explains the window but not the
/// record. The screened fit must notice (`screening::carries_over`), fit on longer windows, and
/// end with a model that explains the whole record far better than the window's model does.
#[test]
fn a_window_that_does_not_carry_over_to_the_record_is_lengthened() {
    let n = 24_000;
    let data = noisy_record(n, 7);
    let y = data.output_slice(0);
    let spread = (y.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let drifting: Vec<f64> = y
        .iter()
        .enumerate()
        .map(|(k, v)| v + 2.0 * spread * (std::f64::consts::PI * k as f64 / n as f64).sin())
        .collect();
    let data = IoData::siso(data.input_slice(0), &drifting).unwrap();
    let screening = Screening {
        threshold: 6_000,
        window: 3_000,
        ..Screening::default()
    };
    let settings = Hammerstein::<f64>::linear().screening(screening);
    let watch = Watch::default();
    let model = settings.fit_observed(&data, &watch).unwrap();
    let w = model.report().screening_window.unwrap();
    assert!(w > 3_000, "the window stayed at {w}");
    assert!(
        watch
            .stages()
            .iter()
            .any(|s| s.starts_with("fitting on a longer window")),
        "{:?}",
        watch.stages()
    );
    // the model's settings start a refit (a diagnosis' candidate) at the longer window, also
    // once saved and loaded
    assert_eq!(model.settings().options().screening.window, w);
    let path = std::env::temp_dir().join(format!("screening-window-{}.json", std::process::id()));
    model.save(&path).unwrap();
    let loaded = hammerstein::fit::HammersteinModel::<f64>::load(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(loaded.report().screening_window, Some(w));
    assert_eq!(loaded.settings().options().screening.window, w);
    // the model of the first window alone (the input is excited from the start: the leading
    // window), on the whole record
    let window = data.slice(0, 3_000).unwrap();
    let window_model = settings
        .clone()
        .screening(Screening::off())
        .fit(&window)
        .unwrap();
    let (m_window, m_final) = (
        compare(&window_model, &data).unwrap().metrics.mse,
        compare(&model, &data).unwrap().metrics.mse,
    );
    assert!(
        m_final < 0.5 * m_window,
        "whole-record MSE {m_final} against the window model's {m_window}"
    );
}

#[test]
fn screened_fit_matches_the_whole_fit_on_validation() {
    let data = noisy_record(12_000, 3);
    let (train, val) = data.split_validation(0.3).unwrap();
    assert!(lowered().applies(train.len()));
    for settings in [
        Hammerstein::<f64>::sh().order(Order::Fixed(2)),
        Hammerstein::<f64>::linear(),
    ] {
        let whole = settings
            .clone()
            .screening(Screening::off())
            .fit(&train)
            .unwrap();
        let screened = settings.clone().screening(lowered()).fit(&train).unwrap();
        let (mw, ms) = (
            compare(&whole, &val).unwrap().metrics.mse,
            compare(&screened, &val).unwrap().metrics.mse,
        );
        assert!(
            ms <= mw * 1.03,
            "{}: screened validation MSE {ms} against the whole fit's {mw}",
            settings.nonlinearity_name()
        );
        // the polish used the whole record: the training MSE is that of the whole record
        assert!(screened.report().refinement.is_some());
    }
}

/// A screened Hammerstein–Wiener fit keeps its window's parameters (its joint refinement is
/// not polished on the whole record), but its report's training MSE is the whole record's, as
/// every other fit's is: the diagnosis compares it with refits on that record.
#[test]
fn a_screened_fit_with_an_output_map_reports_the_whole_records_mse() {
    use hammerstein::regressors::{OutputMap, PolynomialMap};
    let train = noisy_record(12_000, 5);
    let model = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation]))
        .order(Order::Fixed(2))
        .output_nonlinearity(Some(
            Box::new(PolynomialMap::<f64>::new(3).unwrap()) as Box<dyn OutputMap<f64>>
        ))
        .screening(lowered())
        .fit(&train)
        .unwrap();
    assert!(model.report().screening_window.is_some());
    let whole = compare(&model, &train).unwrap().metrics.mse;
    let reported = model.report().train_mse;
    assert!(
        (reported - whole).abs() <= 1e-9 * whole,
        "reported {reported} against the whole record's {whole}"
    );
}

#[test]
fn screened_diagnosis_names_the_same_missing_effect() {
    let data = noisy_record(12_000, 5);
    let (train, val) = data.split_validation(0.3).unwrap();
    let settings = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Hysteresis]))
        .order(Order::Fixed(2))
        .with_d(false);
    let whole = settings
        .clone()
        .screening(Screening::off())
        .fit(&train)
        .unwrap();
    let d_whole = diagnose(&whole, &train, &val).unwrap();
    // observers attached at run time: the screened fit's and diagnosis' stages, the refits'
    // iterations
    let fit_watch = Watch::default();
    let screened_model = settings
        .screening(lowered())
        .fit_observed(&train, &fit_watch)
        .unwrap();
    assert_eq!(
        fit_watch.stages(),
        [
            "fitting on the screening window",
            "polishing on the whole record",
            "fitted"
        ]
    );
    let watch = Watch::default();
    let d = Diagnoser::new()
        .diagnose_observed(&screened_model, &train, &val, &watch)
        .unwrap();
    assert_eq!(
        watch.stages(),
        [
            "screening the candidates on the screening window",
            "refitting the candidates",
            "comparing on the whole record",
            "re-checking the best suggestions on the whole record",
            "diagnosed"
        ]
    );
    // each refit on the window is reported once when it ends
    let refits = d
        .candidates
        .iter()
        .filter(|c| c.refit.is_some() || c.refit_error.is_some())
        .count();
    let reported = watch
        .stages
        .lock()
        .unwrap()
        .iter()
        .filter(|s| *s == "refitting the candidates")
        .count();
    assert!(
        refits > 0 && reported == refits,
        "{reported} reported, {refits} refitted"
    );
    // every candidate's refit on the window ran the loop with the observer
    assert!(watch.iterations.load(Ordering::Relaxed) > d.candidates.len());
    assert_eq!(d_whole.screening_window, None);
    assert_eq!(d.screening_window, Some(3_000));
    let top = |d: &hammerstein::diagnosis::Diagnosis<f64>| {
        d.suggestions.first().map(|s| s.effect.to_string())
    };
    assert_eq!(top(&d_whole).as_deref(), Some("saturation"));
    assert_eq!(top(&d), top(&d_whole));
    // the re-checked suggestion's numbers are the whole record's: its reference is the model's
    // training MSE on the whole training record, its validation on the whole validation record
    let s = &d.suggestions[0];
    assert_eq!(d.train.y.len(), train.len());
    assert!(
        (s.validation_mse_before - d.validation.metrics.mse).abs()
            <= 1e-12 * s.validation_mse_before
    );
    let w = &d_whole.suggestions[0];
    assert!(
        (s.train_mse_after - w.train_mse_after).abs() <= 0.03 * w.train_mse_after,
        "screened {} against whole {}",
        s.train_mse_after,
        w.train_mse_after
    );
}

/// A long record that starts with a silent stretch longer than the window (the piezo record's
/// input is 0 V for its first third): the leading window's input is constant, and the screened
/// fit refused the record ("input … is constant"). The window is now one whose input moves, and
/// the screened fit matches the whole fit on validation as for any record.
#[test]
fn a_record_starting_silent_is_screened_on_a_window_that_moves() {
    let n = 12_000;
    let data = noisy_record(n, 7);
    let silent = 4_000;
    let u: Vec<f64> = (0..n)
        .map(|k| {
            if k < silent {
                0.0
            } else {
                data.input_slice(0)[k]
            }
        })
        .collect();
    // the output of the silenced input: the same block after the same nonlinearity
    let clean = example1_linear::<f64>()
        .simulate_siso(&saturated_hysteresis(&u), None)
        .unwrap();
    let mut rng = StdRng::seed_from_u64(8);
    let noise = Normal::new(0.0, 0.05).unwrap();
    let y: Vec<f64> = clean.iter().map(|c| c + noise.sample(&mut rng)).collect();
    let data = IoData::siso(&u, &y).unwrap();
    let (train, val) = data.split_validation(0.3).unwrap();
    assert!(lowered().applies(train.len()));
    let settings = Hammerstein::<f64>::sh().order(Order::Fixed(2));
    let screened = settings
        .clone()
        .screening(lowered())
        .fit(&train)
        .unwrap_or_else(|e| panic!("screened fit of a record starting silent: {e}"));
    let whole = settings.screening(Screening::off()).fit(&train).unwrap();
    let (mw, ms) = (
        compare(&whole, &val).unwrap().metrics.mse,
        compare(&screened, &val).unwrap().metrics.mse,
    );
    assert!(
        ms <= mw * 1.03,
        "screened validation MSE {ms} against the whole fit's {mw}"
    );
    // the diagnosis screens the same way
    diagnose(&screened, &train, &val)
        .unwrap_or_else(|e| panic!("screened diagnosis of a record starting silent: {e}"));
}

/// The command line says where a screened model's parameters come from: polished on the whole
/// record, or, for a model with an output map (its joint refinement is not polished), fitted on
/// the window.
#[cfg(feature = "cli")]
#[test]
fn the_command_line_says_where_a_screened_models_parameters_come_from() {
    let data = noisy_record(60_000, 9);
    let dir = cli_io::temp_dir("screening-cli");
    let path = dir.join("long.csv");
    cli_io::write_csv(
        &path,
        &["u", "y"],
        &[data.input_slice(0), data.output_slice(0)],
    );
    let fit = |extra: &[&str]| {
        let mut args = vec!["fit", path.to_str().unwrap(), "--effects", "saturation"];
        args.extend(["--order", "2"]);
        args.extend(extra);
        cli_io::run_cli(&args)
    };
    let plain = fit(&[]);
    let mapped = fit(&["--output-nonlinearity", "poly3"]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        plain.contains("the parameters polished on the whole record"),
        "{plain}"
    );
    assert!(
        mapped.contains("a model with an output map is not polished on the whole record")
            && !mapped.contains("parameters polished on the whole record"),
        "{mapped}"
    );
}
