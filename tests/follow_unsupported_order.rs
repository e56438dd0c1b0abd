//! The guided loop says when an order is not supported by the record and keeps a supported one:
//! an order raise whose refit's block is unstable (spectral radius above 1) is not taken, the
//! final check says "order n is not supported by the record (N training samples)", and the
//! model keeps the order it had. Seen on the MR damper sine tests: 525 training samples, where
//! the loop raised the order to 10–14 with unstable blocks. The record is the committed
//! ensaio04 (`tests/data/mr_damper/`, 751 samples, `--validate 0.3`).

use hammerstein::diagnosis::final_check::TRAINING_SLACK;
use hammerstein::diagnosis::{Diagnoser, FollowOptions};
use hammerstein::fit::order_selection::training_mse;
use hammerstein::regressors::{Effect, EffectSet, output_map_from_name};
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
fn an_order_the_record_does_not_support_is_said_and_not_taken() {
    let (train, val) = ensaio04();
    // where `diagnose --follow --no-confirm` stands after three steps on this record: a
    // hysteresis and a saturation, a cubic output map, order 9; its diagnosis suggests raising
    // the order first
    let start = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]))
        .output_nonlinearity(Some(output_map_from_name("poly3").unwrap()))
        .order(Order::Fixed(9));
    let options = FollowOptions {
        max_steps: 1,
        confirm: None,
        time_budget: None,
    };
    let followed = Diagnoser::<f64>::new()
        .follow_with(&start, &train, &val, &options, None)
        .unwrap();
    let changes: Vec<&str> = followed.steps.iter().map(|s| s.change.as_str()).collect();
    let note = followed
        .final_check
        .iter()
        .find(|n| n.contains("is not supported by the record"))
        .unwrap_or_else(|| {
            panic!(
                "no unsupported-order note: steps {changes:?}, final check {:?}",
                followed.final_check
            )
        });
    assert!(
        note.contains(&format!("({} training samples)", train.len()))
            && note.contains("spectral radius")
            && note.contains("the model keeps order 9"),
        "{note}"
    );
    // the refused order raise is no step; every model keeps the supported order 9
    for s in &followed.steps {
        assert_eq!(
            s.model.linear().order(),
            9,
            "step '{}' at order {} ({changes:?}; {note})",
            s.change,
            s.model.linear().order()
        );
    }
    assert!(
        !changes.iter().any(|c| c.starts_with("order")),
        "an order step was taken: {changes:?}"
    );
    // a step the loop takes (before its final check) trains no worse than the model it extends
    for w in followed.steps.windows(2) {
        if w[1].change.starts_with("- ") {
            break;
        }
        let (before, after) = (
            training_mse(&w[0].model, &train),
            training_mse(&w[1].model, &train),
        );
        assert!(
            after <= before * (1.0 + TRAINING_SLACK),
            "step '{}' trains at {after} above {before}",
            w[1].change
        );
    }
}
