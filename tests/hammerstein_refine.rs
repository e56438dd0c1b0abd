//! What the Levenberg–Marquardt refinement adds: on noisy Example 1 data it lowers the training
//! MSE of the loop's result (the loop's iterates are not the output-error optimum under noise)
//! and keeps the parameters at the truth.

mod hammerstein_common;
use hammerstein::Hammerstein;
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein_common::*;

#[test]
fn refinement_lowers_the_mse_on_noisy_data() {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let clean = record(&truth, &example1_input(2000, 7), 1.0);
    let data = add_noise(&clean, 10.0, 21);
    let plain = Hammerstein::sh().fit(&data).unwrap();
    let refined = Hammerstein::sh().refine(true).fit(&data).unwrap();
    let rep = refined.report().refinement.clone().expect("refinement ran");
    eprintln!(
        "{rep:?}\nloop {:?}\nrefined {:?}",
        plain.parameters(),
        refined.parameters()
    );
    assert!(rep.accepted);
    assert!(rep.mse_after < rep.mse_before, "{rep:?}");
    assert_eq!(rep.mse_before, plain.report().train_mse);
    assert_eq!(refined.report().train_mse, rep.mse_after);
    // the refined model's own simulation reproduces the reported MSE
    let sim = refined.simulate_on(&data).unwrap();
    let y = data.output(0);
    let mse = y
        .iter()
        .zip(&sim.y_hat)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / y.len() as f64;
    assert!(
        mse <= rep.mse_after * (1.0 + 1e-6),
        "{mse} vs {}",
        rep.mse_after
    );
    // still at the truth within a few Cramér–Rao standard deviations (10 dB: p 0.032, a 0.014)
    let p = refined.parameters();
    close("p", p[0].1, 2.0, 0.1);
    close("a", p[1].1, 0.5, 0.05);
    close("z1", p[2].1, 1.5, 0.1);
    close("z2", p[3].1, -1.0, 0.1);
    let tf = refined.transfer_function().unwrap();
    close("b1", tf.numerator[1], 1.0, 1e-9);
    close("a1", tf.denominator[1], -0.2, 0.05);
    close("a2", tf.denominator[2], 0.35, 0.03);
    close("offset", refined.output_offset(), 1.0, 0.1);
}

#[test]
fn refinement_keeps_an_exact_fit() {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let data = record(&truth, &example1_input(2000, 7), 0.0);
    let m = Hammerstein::sh().refine(true).fit(&data).unwrap();
    let p = m.parameters();
    close("p", p[0].1, 2.0, 1e-6);
    close("a", p[1].1, 0.5, 1e-6);
    assert!(m.report().train_mse < 1e-12);
}
