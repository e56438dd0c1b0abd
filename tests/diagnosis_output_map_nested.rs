//! The output-nonlinearity candidate's refit never ends above the model it extends: besides the
//! fit from scratch at the model's order, the current model extended by the map (the map starting
//! at its two-stage initialisation on the model's own output) is refitted, and the lower training
//! MSE kept. Seen on the real MR damper record ensaio04 (`tests/data/mr_damper/`): from the
//! order-9 linear model the order selection picks there, the fit from scratch with a cubic or a
//! saturating output map ended 26 % above the linear model's training MSE, so the diagnosis
//! reported that an output nonlinearity made the model worse.

use hammerstein::diagnosis::{CandidateId, diagnose};
use hammerstein::{Hammerstein, IoData, Order};

/// The committed MR damper record ensaio04 (velocity → force), split 70/30 as the command line's
/// `--validate 0.3` does.
fn ensaio04() -> (IoData<f64>, IoData<f64>) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/mr_damper/ensaio04.csv"
    );
    let data = IoData::<f64>::from_csv(path, &["vel_mm_s"], &["force_N"]).unwrap();
    data.split_validation(0.3).unwrap()
}

#[test]
fn output_map_refit_is_not_worse_than_the_model_it_extends() {
    let (train, val) = ensaio04();
    // the command line's default linear start: order selected automatically (9 here)
    let model = Hammerstein::<f64>::linear()
        .order(Order::Auto)
        .fit(&train)
        .unwrap();
    let d = diagnose(&model, &train, &val).unwrap();
    let c = d
        .candidates
        .iter()
        .find(|c| c.effect == CandidateId::OutputNonlinearity)
        .expect("the output-nonlinearity candidate is tried");
    let r = c.refit.as_ref().expect("the output map is refitted");
    assert!(
        r.train_mse <= r.reference_train_mse * (1.0 + 1e-9),
        "output map refit {} above the model's {}",
        r.train_mse,
        r.reference_train_mse
    );
}

/// The same record followed two steps as `hammerstein diagnose --follow` does (the output map
/// first, then what the diagnosis suggests): every UDN candidate's refit of the Hammerstein–Wiener model at the last step
/// starts at that model (its map, block, initial state and offset kept), so none ends above it.
/// Before that start existed, after the output map and a saturation, the hysteresis refit ended
/// at 84.5 against 81.1 and the preload's 132 % above (the Hammerstein part refitted
/// without the map, the map initialised again on top). The dynamics candidate's refit at a
/// higher order starts there too.
#[test]
fn udn_candidates_on_a_hammerstein_wiener_model_are_not_worse() {
    use hammerstein::diagnosis::Diagnoser;
    use hammerstein::regressors::Effect;
    let (train, val) = ensaio04();
    let followed = Diagnoser::<f64>::new()
        .follow(&Hammerstein::linear(), &train, &val, 2)
        .unwrap();
    let last = followed.last().unwrap();
    assert!(
        last.model.output_map().is_some(),
        "the path takes the output map: {:?}",
        followed.steps.iter().map(|s| &s.change).collect::<Vec<_>>()
    );
    let mut checked = 0;
    for c in &last.diagnosis.candidates {
        let udn = matches!(
            c.effect,
            CandidateId::Effect(Effect::Hysteresis | Effect::DeadZone | Effect::Preload)
        );
        if let (true, Some(r)) = (udn, c.refit.as_ref()) {
            checked += 1;
            assert!(
                r.train_mse <= r.reference_train_mse * (1.0 + 1e-9),
                "{:?} refit {} above the model's {}",
                c.effect,
                r.train_mse,
                r.reference_train_mse
            );
        }
    }
    assert!(checked >= 2, "{checked} UDN candidates refitted");
    // the dynamics candidate raises the order: its start is the model's block augmented by
    // states the input does not reach, map kept, so it cannot end above the model either
    // (`fit/selection/nested.rs`, `kept_map_start`; from the two-stage start alone the order-10 refit of
    // another order-9 model of this record, hysteresis + saturation, ended 3.4 % above it)
    let dynamics = last
        .diagnosis
        .candidates
        .iter()
        .find(|c| c.effect == CandidateId::Dynamics)
        .and_then(|c| c.refit.as_ref())
        .expect("the dynamics candidate is refitted");
    assert!(
        dynamics.train_mse <= dynamics.reference_train_mse * (1.0 + 1e-9),
        "dynamics refit {} above the model's {}",
        dynamics.train_mse,
        dynamics.reference_train_mse
    );
}
