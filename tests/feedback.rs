//! The feedback model (nonlinear LFR) on simulated records: the fit recovers a cubic
//! stiffness, a Coulomb friction on the velocity and a clearance; the model file round-trips;
//! bad input gets clear errors.

use hammerstein::IoData;
use hammerstein::feedback::{
    self, FeedbackKind, FeedbackModel, FeedbackModelFile, FeedbackOn, FeedbackSettings,
};
use rand::{SeedableRng, rngs::StdRng};

mod feedback_common;
use feedback_common::{add_noise, filtered_noise};

/// A second-order block x+ = A x + B u + B w, y = C x, w = f(z) with z = C x or its difference,
/// simulated independently of the crate.
fn truth(u: &[f64], poles: (f64, f64), f: impl Fn(f64) -> f64, velocity: bool) -> Vec<f64> {
    let (r, th) = poles;
    // companion form of (z − r e^{iθ})(z − r e^{−iθ})
    let a1 = 2.0 * r * th.cos();
    let a2 = -r * r;
    let (mut x1, mut x2, mut prev) = (0.0f64, 0.0f64, 0.0f64);
    let mut y = Vec::with_capacity(u.len());
    for &uk in u {
        let cx = x1;
        let z = if velocity { cx - prev } else { cx };
        let w = f(z);
        y.push(cx);
        prev = cx;
        let n1 = a1 * x1 + x2 + uk + w;
        let n2 = a2 * x1 + 0.5 * (uk + w);
        x1 = n1;
        x2 = n2;
    }
    y
}

fn mse(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64
}

#[test]
fn cubic_stiffness_is_recovered_to_the_noise_floor() {
    let mut rng = StdRng::seed_from_u64(7);
    let n = 3000;
    let u = filtered_noise(2 * n, &mut rng, 0.04);
    let y0 = truth(&u, (0.95, 0.3), |z| -0.02 * z.powi(3), false);
    let (y, s2) = add_noise(&y0, 40.0, &mut rng);
    let train = IoData::siso(&u[..n], &y[..n]).unwrap();
    let val = IoData::siso(&u[n..], &y[n..]).unwrap();
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    s.order = hammerstein::Order::Fixed(2);
    let fit = feedback::fit(&s, &train).unwrap();
    let cmp = fit.model.compare(&val).unwrap();
    let lin_mse = fit.linear_rms.powi(2);
    eprintln!(
        "linear {:.3e} start {:?} train {:.3e} val {:.3e} noise {:.3e} {:?}",
        lin_mse,
        fit.start_rms.map(|r| r * r),
        fit.rms.powi(2),
        cmp.rms.powi(2),
        s2,
        fit.refine
    );
    assert!(
        cmp.rms.powi(2) < 1.5 * s2,
        "validation MSE {} vs noise {}",
        cmp.rms.powi(2),
        s2
    );
    assert!(
        lin_mse > 3.0 * s2,
        "the record is not nonlinear enough to test anything"
    );
    // the true state-free values of f: w = −0.5 z³ in input units (E normalised to B's gain)
    let (lo, hi) = fit.model.z_range();
    let z = [0.8 * lo, 0.8 * hi];
    let w = fit.model.eval_physical(&z);
    for (zi, wi) in z.iter().zip(&w) {
        let t = -0.02 * zi.powi(3);
        assert!(
            (wi - t).abs() < 0.1 * t.abs() + 1e-6,
            "f({zi}) = {wi}, truth {t}"
        );
    }
}

fn stiffness_records(seed: u64) -> (IoData<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let u = filtered_noise(2000, &mut rng, 0.04);
    let y0 = truth(&u, (0.95, 0.3), |z| -0.02 * z.powi(3), false);
    let (y, _) = add_noise(&y0, 40.0, &mut rng);
    (IoData::siso(&u, &y).unwrap(), u, y)
}

#[test]
fn the_model_file_round_trips_and_simulates_alike() {
    let (data, u, y) = stiffness_records(3);
    let mut s = FeedbackSettings::new(FeedbackKind::Poly5, FeedbackOn::Output);
    s.order = hammerstein::Order::Fixed(2);
    let fit = feedback::fit(&s, &data).unwrap();
    let text = serde_json::to_string(&fit.model.to_file()).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(FeedbackModelFile::is_feedback_value(&value));
    let back = FeedbackModel::from_file(&FeedbackModelFile::from_value(value).unwrap(), |_| {
        unreachable!("a built-in basis")
    })
    .unwrap();
    let x0 = fit.model.training_x0().to_vec();
    let a = fit.model.simulate(&u, Some(&x0)).unwrap();
    let b = back.simulate(&u, Some(&x0)).unwrap();
    assert_eq!(a, b);
    // and the simulation from the training state is the fit's
    assert!((mse(&a, &y).sqrt() - fit.rms).abs() < 1e-9 * (1.0 + fit.rms));
    // a Hammerstein model file is not a feedback one
    let other = serde_json::json!({"version": 3, "nonlinearity": {}});
    assert!(!FeedbackModelFile::is_feedback_value(&other));
    // a newer version is refused with the version named
    let mut newer: serde_json::Value = serde_json::from_str(&text).unwrap();
    newer["version"] = serde_json::json!(99);
    let e = FeedbackModelFile::from_value(newer).unwrap_err();
    assert!(e.to_string().contains("99"), "{e}");
}

#[test]
fn velocity_feedback_with_a_feedthrough_is_refused() {
    let (data, _, _) = stiffness_records(4);
    let mut s = FeedbackSettings::new(FeedbackKind::Coulomb, FeedbackOn::Velocity);
    s.with_d = true;
    let e = feedback::fit(&s, &data).unwrap_err().to_string();
    assert!(e.contains("algebraic"), "{e}");
}

#[test]
fn a_basis_constant_over_the_visited_range_is_refused() {
    use hammerstein::regressors::{UserBasis, UserColumn};
    let (data, _, _) = stiffness_records(5);
    // a user basis whose only column is zero wherever z goes
    let zero = UserBasis::new(
        "zero",
        &[],
        vec![UserColumn::new("0", |_z: f64, _s: f64| 0.0)],
    )
    .unwrap();
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    s.basis = Some(Box::new(zero));
    s.order = hammerstein::Order::Fixed(2);
    let e = feedback::fit(&s, &data).unwrap_err().to_string();
    assert!(e.contains("cannot represent"), "{e}");
}

#[test]
fn a_model_diverging_on_the_validation_input_is_an_error() {
    let (data, u, _) = stiffness_records(6);
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    s.order = hammerstein::Order::Fixed(2);
    let fit = feedback::fit(&s, &data).unwrap();
    // far beyond the training amplitude a cubic loop of a discrete-time model blows up
    let big: Vec<f64> = u.iter().map(|v| v * 200.0).collect();
    let y: Vec<f64> = (0..big.len()).map(|k| (k % 7) as f64).collect();
    let val = IoData::siso(&big, &y).unwrap();
    let e = fit.model.compare(&val).unwrap_err().to_string();
    assert!(e.contains("diverges"), "{e}");
    let e = fit.model.simulate(&big, None).unwrap_err();
    assert!(matches!(e, hammerstein::Error::Diverged { .. }), "{e}");
}
