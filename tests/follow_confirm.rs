//! The guided loop's steps are confirmed on the held-back part of the training record
//! (`diagnosis/confirm.rs`), and `FollowOptions::time_budget` stops it after the step in
//! progress. Records: a hidden saturation (and a hysteresis) before the paper's block, random
//! inputs, 30 dB, random seeds.

mod common;

use common::{InputKind, Udn, input, output, paper::paper_block};
use hammerstein::diagnosis::confirm::diebold_mariano;
use hammerstein::diagnosis::{ConfirmRule, Diagnoser, FollowOptions, FollowStop};
use hammerstein::fit::Hammerstein;
use hammerstein::{IoData, Order};
use std::time::Duration;

/// A record of `n` samples with a saturation and a hysteresis the linear start does not have.
fn record(n: usize, seed: u64) -> (IoData<f64>, IoData<f64>) {
    let u = input(InputKind::Uniform, n, 2.0, seed);
    let truth = Udn {
        a: 0.25,
        z1: 1.2,
        z2: -1.0,
        ..Udn::linear(1.0)
    };
    let (y, _) = output(&paper_block(), &truth.eval(&u), 30.0, seed);
    IoData::siso(&u, &y).unwrap().split_validation(0.3).unwrap()
}

fn start() -> Hammerstein<f64> {
    Hammerstein::<f64>::linear()
        .order(Order::Fixed(2))
        .with_d(false)
}

/// Every step taken carries a check that confirms it (its held-back MSE falls, DM < z); a loop
/// stopped by a refusal names the refused step with its check, which does not confirm it.
#[test]
fn every_step_taken_is_confirmed_on_the_held_back_part() {
    let z = ConfirmRule::default().z;
    for seed in [3u64, 11, 29] {
        let (train, val) = record(1600, seed);
        let f = Diagnoser::<f64>::new()
            .follow(&start(), &train, &val, 3)
            .unwrap();
        assert!(f.steps[0].confirmation.is_none(), "seed {seed}: the start");
        assert!(
            f.steps.len() >= 2,
            "seed {seed}: the hidden effects give a step"
        );
        for (i, st) in f.steps.iter().enumerate().skip(1) {
            let c = st
                .confirmation
                .as_ref()
                .expect("a taken step carries its check");
            assert!(c.note.is_none(), "seed {seed} step {i}: checked ({c:?})");
            assert!(
                c.confirmed && c.statistic < z && c.mse_after < c.mse_before,
                "seed {seed} step {i}: {c:?}"
            );
            assert_eq!(
                c.held_back, 560,
                "the last and the first 280 training samples"
            );
        }
        match (&f.stop, &f.refused) {
            (FollowStop::NotConfirmed(_), Some((_, c))) => {
                assert!(
                    !c.confirmed && c.mse_after >= c.mse_before,
                    "seed {seed}: {c:?}"
                )
            }
            (FollowStop::NotConfirmed(_), None) => panic!("seed {seed}: refusal without its step"),
            (_, None) => {}
            (stop, Some(_)) => panic!("seed {seed}: a refused step but stop {stop:?}"),
        }
    }
}

/// A rule no step can pass (z = −∞) refuses the first step: the loop ends on its start and
/// says which step it refused; without the check the same loop takes it.
#[test]
fn an_unconfirmed_step_is_not_taken() {
    let (train, val) = record(1600, 5);
    let d = Diagnoser::<f64>::new();
    let strict = FollowOptions {
        max_steps: 2,
        confirm: Some(ConfirmRule {
            z: f64::NEG_INFINITY,
            ..ConfirmRule::default()
        }),
        time_budget: None,
    };
    let f = d
        .follow_with(&start(), &train, &val, &strict, None)
        .unwrap();
    assert_eq!(f.steps.len(), 1);
    assert!(
        matches!(f.stop, FollowStop::NotConfirmed(_)),
        "{:?}",
        f.stop
    );
    let (label, c) = f.refused.as_ref().expect("the refused step");
    assert!(
        label.starts_with('+') || label.starts_with("order"),
        "{label}"
    );
    assert!(!c.confirmed && c.held_back > 0);
    let free = FollowOptions {
        confirm: None,
        ..strict
    };
    let g = d.follow_with(&start(), &train, &val, &free, None).unwrap();
    assert!(g.steps.len() >= 2 && g.refused.is_none());
    assert!(g.steps.iter().all(|s| s.confirmation.is_none()));
}

/// A training record too short to hold back the rule's fewest samples: steps are taken and
/// each says it was not checked.
#[test]
fn a_short_record_says_its_steps_were_not_checked() {
    let (train, val) = record(1600, 7);
    let d = Diagnoser::<f64>::new();
    let opts = FollowOptions {
        max_steps: 1,
        confirm: Some(ConfirmRule {
            min_held_back: 10_000,
            ..ConfirmRule::default()
        }),
        time_budget: None,
    };
    let f = d.follow_with(&start(), &train, &val, &opts, None).unwrap();
    assert!(f.steps.len() == 2, "{:?}", f.stop);
    let c = f.steps[1].confirmation.as_ref().unwrap();
    assert!(c.confirmed && c.note.as_deref().unwrap_or("").contains("too short"));
}

/// A spent time budget stops the loop after the step in progress (the start's diagnosis),
/// with its model kept.
#[test]
fn a_spent_time_budget_stops_after_the_step_in_progress() {
    let (train, val) = record(1600, 3);
    let opts = FollowOptions {
        max_steps: 4,
        time_budget: Some(Duration::ZERO),
        ..FollowOptions::default()
    };
    let f = Diagnoser::<f64>::new()
        .follow_with(&start(), &train, &val, &opts, None)
        .unwrap();
    assert_eq!(f.stop, FollowStop::TimeBudget);
    assert_eq!(f.steps.len(), 1);
    assert!(
        f.last()
            .unwrap()
            .diagnosis
            .validation
            .metrics
            .mse
            .is_finite()
    );
}

/// The Diebold–Mariano statistic of equal losses is 0 and its sign follows the difference.
#[test]
fn the_statistic_follows_the_loss_difference() {
    let e: Vec<f64> = (0..300)
        .map(|k| ((k * 37 % 101) as f64 - 50.0) / 50.0)
        .collect();
    let smaller: Vec<f64> = e.iter().map(|x| 0.9 * x).collect();
    assert_eq!(diebold_mariano(&e, &e).1, 0.0);
    assert!(diebold_mariano(&e, &smaller).1 < -2.0);
    assert!(diebold_mariano(&smaller, &e).1 > 2.0);
}

/// The step that adds the Prandtl–Ishlinskii plays with some removed (a play subset, a
/// nonlinearity outside the UDN's effects, at the model's order fixed) is labelled by the effect
/// it adds, not as an order change (the piezo record's chain labelled it "order 9").
#[test]
fn a_step_adding_a_play_subset_is_labelled_by_its_effect() {
    use hammerstein::diagnosis::{Action, CandidateId};
    use hammerstein::regressors::{DEFAULT_PLAYS, Effect, PrandtlIshlinskii};
    let from = Hammerstein::<f64>::linear();
    let base = from.build_nonlinearity().unwrap();
    let subset = PrandtlIshlinskii::on_subset(base, DEFAULT_PLAYS, &[1, 2, 4]).unwrap();
    let to = Hammerstein::<f64>::new(Box::new(subset)).order(Order::Fixed(9));
    let pi = CandidateId::Effect(Effect::PrandtlIshlinskii);
    let action = Action::between(&from, &to, &pi);
    assert_eq!(action.label(), "+ prandtl-ishlinskii", "{action:?}");
    // an order change between two play subsets stays an order change
    let to2 = Hammerstein::<f64>::new(Box::new(
        PrandtlIshlinskii::on_subset(
            from.build_nonlinearity().unwrap(),
            DEFAULT_PLAYS,
            &[1, 2, 4],
        )
        .unwrap(),
    ))
    .order(Order::Fixed(10));
    let dynamics = CandidateId::Dynamics;
    assert_eq!(Action::between(&to, &to2, &dynamics).label(), "order 10");
}

/// A training record that starts at rest (its first quarter's input constant, as the piezo
/// record's first seconds) cannot give that quarter as a held-back part: the steps are checked
/// on the last quarter alone, not left unchecked.
#[test]
fn a_record_starting_at_rest_is_checked_on_its_other_quarter() {
    for seed in [5u64, 17] {
        let n = 1600;
        let mut u = input(InputKind::Uniform, n, 2.0, seed);
        u[..n * 3 / 10].iter_mut().for_each(|x| *x = 0.0);
        let truth = Udn {
            a: 0.25,
            z1: 1.2,
            z2: -1.0,
            ..Udn::linear(1.0)
        };
        let (y, _) = output(&paper_block(), &truth.eval(&u), 30.0, seed);
        let (train, val) = IoData::siso(&u, &y).unwrap().split_validation(0.3).unwrap();
        let f = Diagnoser::<f64>::new()
            .follow(&start(), &train, &val, 2)
            .unwrap();
        assert!(
            f.steps.len() >= 2,
            "seed {seed}: the hidden effects give a step"
        );
        let held = train.len() / 4;
        for (i, st) in f.steps.iter().enumerate().skip(1) {
            let c = st
                .confirmation
                .as_ref()
                .expect("a taken step carries its check");
            assert!(c.note.is_none(), "seed {seed} step {i}: checked ({c:?})");
            assert!(c.confirmed, "seed {seed} step {i}: {c:?}");
            assert_eq!(c.held_back, held, "seed {seed}: the last quarter only");
        }
    }
}
