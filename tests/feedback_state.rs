//! Feedback on a state combination (`--feedback-on state`, z = F x with F estimated): on a
//! record whose loop acts on a combination of the states that neither the output nor its
//! first difference expresses, the state fit reaches the noise and the output and velocity
//! fits do not; z's scale is the stated one; the model file round-trips.

use hammerstein::IoData;
use hammerstein::feedback::{
    self, FeedbackKind, FeedbackModel, FeedbackModelFile, FeedbackOn, FeedbackSettings,
};
use rand::{SeedableRng, rngs::StdRng};

mod common;
mod feedback_common;
use feedback_common::{add_noise, filtered_noise};

/// x+ = A x + B (u + w), y = x₁, w = c z³ with z = F x, F = (0.5, 1): z holds x₂, which is
/// a₂ y(k−1) + (u(k−1) + w(k−1))/2, so it is neither y nor its difference. Simulated
/// independently of the crate.
fn truth(u: &[f64], c: f64) -> Vec<f64> {
    common::resonant_loop(u, |v| v, |x1, x2| c * (0.5 * x1 + x2).powi(3))
}

fn records(seed: u64, n: usize) -> (IoData<f64>, IoData<f64>, f64, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let u = filtered_noise(2 * n, &mut rng, 0.04);
    let y0 = truth(&u, -0.05);
    assert!(y0.iter().all(|v| v.is_finite() && v.abs() < 100.0));
    let (y, s2) = add_noise(&y0, 40.0, &mut rng);
    (
        IoData::siso(&u[..n], &y[..n]).unwrap(),
        IoData::siso(&u[n..], &y[n..]).unwrap(),
        s2,
        u[..n].to_vec(),
    )
}

fn settings(on: FeedbackOn) -> FeedbackSettings {
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, on);
    s.order = hammerstein::Order::Fixed(2);
    s
}

#[test]
fn a_loop_on_a_state_combination_is_reached_only_by_state_feedback() {
    let (train, val, s2, _) = records(11, 3000);
    let mut val_mse = Vec::new();
    for on in [FeedbackOn::State, FeedbackOn::Output, FeedbackOn::Velocity] {
        let fit = feedback::fit(&settings(on), &train).unwrap();
        let v = fit.model.compare(&val).unwrap().rms.powi(2);
        eprintln!(
            "{}: linear {:.3e} train {:.3e} val {:.3e} noise {s2:.3e} F {:?}",
            on.name(),
            fit.linear_rms.powi(2),
            fit.rms.powi(2),
            v,
            fit.model.state_combination()
        );
        val_mse.push((on, v, fit));
    }
    let (_, state, fit) = &val_mse[0];
    assert!(
        fit.linear_rms.powi(2) > 5.0 * s2,
        "the record is not nonlinear enough to test anything"
    );
    assert!(
        *state < 1.5 * s2,
        "state: validation MSE {state} vs noise {s2}"
    );
    for (on, v, _) in &val_mse[1..] {
        assert!(
            *v > 3.0 * s2,
            "{}: validation MSE {v} within 3× the noise {s2}: the record does not tell",
            on.name()
        );
    }
    assert_eq!(fit.model.state_combination().map(<[f64]>::len), Some(2));
}

#[test]
fn z_has_the_rms_of_the_noise_free_output_and_the_file_round_trips() {
    let (train, _, _, u) = records(12, 2000);
    let fit = feedback::fit(&settings(FeedbackOn::State), &train).unwrap();
    let m = &fit.model;
    // the normalisation: z = F x has the RMS of C x along the training simulation
    let band = m.nonlinearity_band(&train, 20).unwrap();
    let x0 = m.training_x0().to_vec();
    let yh = m.simulate(&u, Some(&x0)).unwrap();
    let mean = yh.iter().sum::<f64>() / yh.len() as f64;
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let cx: Vec<f64> = yh.iter().map(|v| v - mean).collect();
    let (rz, rc) = (rms(&band.data_z), rms(&cx));
    // C x carries the constant y₀ − mean(ŷ) the offset leaves; the record is centred
    assert!((rz / rc - 1.0).abs() < 0.05, "z RMS {rz} vs C x RMS {rc}");
    // the file
    let text = serde_json::to_string(&m.to_file()).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["version"], 2);
    assert_eq!(value["feedback"]["on"], "state");
    assert_eq!(
        value["feedback"]["state_combination"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
    let back = FeedbackModel::from_file(
        &FeedbackModelFile::from_value(value.clone()).unwrap(),
        |_| unreachable!("a built-in basis"),
    )
    .unwrap();
    assert_eq!(back.simulate(&u, Some(&x0)).unwrap(), yh);
    assert_eq!(back.state_combination(), m.state_combination());
    // a state model without its F is refused, naming it
    let mut bad = value.clone();
    bad["feedback"]
        .as_object_mut()
        .unwrap()
        .remove("state_combination");
    let e = FeedbackModel::from_file(
        &FeedbackModelFile::from_value(bad).unwrap(),
        |_| unreachable!(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("state_combination"), "{e}");
    // an output model is still written as version 1, without F
    let out = feedback::fit(&settings(FeedbackOn::Output), &train).unwrap();
    let v = serde_json::to_value(out.model.to_file()).unwrap();
    assert_eq!(v["version"], 1);
    assert!(v["feedback"].get("state_combination").is_none());
}

#[test]
fn the_refinement_moves_f_off_the_output() {
    // from the start (F = C among the candidates) the fit ends with an F that is not C's
    // direction (the truth's z is not the output) and far below the linear model
    let (train, _, _, _) = records(13, 1500);
    let fit = feedback::fit(&settings(FeedbackOn::State), &train).unwrap();
    assert!(fit.refine.iterations > 0);
    assert!(
        fit.rms < 0.5 * fit.linear_rms,
        "{} vs linear {}",
        fit.rms,
        fit.linear_rms
    );
    let f = fit.model.state_combination().unwrap().to_vec();
    let c = fit.model.linear().unwrap().c;
    let cn = (c[(0, 0)].powi(2) + c[(0, 1)].powi(2)).sqrt();
    let fn_ = (f[0].powi(2) + f[1].powi(2)).sqrt();
    let cos = (f[0] * c[(0, 0)] + f[1] * c[(0, 1)]) / (cn * fn_);
    assert!(cos.abs() < 0.999, "F stayed parallel to C: cos {cos}");
}
