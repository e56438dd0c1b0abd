//! What the Levenberg–Marquardt refinement adds: on noisy Example 1 data it lowers the training
//! MSE of the loop's result (the loop's iterates are not the output-error optimum under noise)
//! and keeps the parameters at the truth.

mod hammerstein_common;
use hammerstein::Hammerstein;
use hammerstein::Order;
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein_common::*;

#[test]
fn refinement_lowers_the_mse_on_noisy_data() {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let clean = record(&truth, &example1_input(2000, 7), 1.0);
    let data = add_noise(&clean, 10.0, 21);
    let plain = Hammerstein::sh()
        .order(Order::Fixed(2))
        .refine(false)
        .fit(&data)
        .unwrap();
    let refined = Hammerstein::sh()
        .order(Order::Fixed(2))
        .refine(true)
        .fit(&data)
        .unwrap();
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

/// {hysteresis, saturation, preload} contains the true SH structure, but the paper's loop alone
/// stops early along the saturation/preload confounding (the MSE is flat while p, z1, z2, e1, e2
/// still drift), ending above SH's MSE on some records. The refinement reaches an MSE at or
/// below SH's (Example 1 at 10 dB, records 3 and 8, where the loop alone ends above it).
#[cfg(feature = "study")]
#[test]
fn refinement_lets_a_superset_fit_at_least_as_well_as_the_true_structure() {
    use hammerstein::study::Example1;
    use hammerstein::study::monte_carlo::{Strategy, Table, estimator};
    use hammerstein::subspace::MethodKind;
    let sh = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let hsp = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation, Effect::Preload]);
    let base = estimator::<f64>(Table::Table2, Strategy::Best, MethodKind::Moesp);
    let mut loop_above = 0;
    for seed in [3u64, 8] {
        let data = Example1::new(Some(10.0))
            .generate::<f64>(seed)
            .unwrap()
            .data;
        // the refinement's optimum (its report), not the final training MSE: the fit's last
        // step moves the preload's jump positions off the optimum by design (within the 95 %
        // likelihood bound, `fit/numerics/jump_centre.rs`)
        let mse = |set: EffectSet, refine: bool| {
            let m = base
                .clone()
                .refine(refine)
                .with_effects(set)
                .unwrap()
                .fit(&data)
                .unwrap();
            let r = m.report();
            r.refinement
                .as_ref()
                .filter(|rf| rf.accepted)
                .map_or(r.train_mse, |rf| rf.mse_after)
        };
        let (sh_loop, hsp_loop) = (mse(sh, false), mse(hsp, false));
        let (sh_ref, hsp_ref) = (mse(sh, true), mse(hsp, true));
        eprintln!(
            "seed {seed}: loop SH {sh_loop} HSP {hsp_loop}; refined SH {sh_ref} HSP {hsp_ref}"
        );
        if hsp_loop > sh_loop {
            loop_above += 1;
        }
        assert!(
            hsp_ref <= sh_ref * (1.0 + 1e-9),
            "seed {seed}: {hsp_ref} > {sh_ref}"
        );
    }
    // the records were chosen because the loop alone ends above SH there
    assert!(loop_above > 0);
}
