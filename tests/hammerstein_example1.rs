//! Paper Example 1 without noise: SH nonlinearity (p = 2, a = 0.5, z1 = 1.5, z2 = −1) and
//! G(z) = z⁻¹(1 + 0.5 z⁻¹)/(1 − 0.2 z⁻¹ + 0.35 z⁻²), 2000 samples u ~ U[−3, 3].
//! Every parameter must come back to 1e-6 with the SH structure and with the full UDN.

mod hammerstein_common;
use hammerstein::fit::{HammersteinModel, Termination};
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData};
use hammerstein_common::*;

fn sh_set() -> EffectSet {
    EffectSet::of(&[Effect::Hysteresis, Effect::Saturation])
}

fn example1(offset: f64) -> IoData<f64> {
    let truth = Udn::<f64>::with_params(sh_set(), &[2.0, 0.5, 1.5, -1.0]).unwrap();
    record(&truth, &example1_input(2000, 7), offset)
}

fn param(model: &HammersteinModel<f64>, name: &str) -> f64 {
    model
        .parameters()
        .into_iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no parameter {name} in {:?}", model.parameters()))
        .1
}

fn check_linear(model: &HammersteinModel<f64>, tol: f64) {
    let tf = model.transfer_function().unwrap();
    assert_eq!(model.linear().order(), 2, "{tf:?}");
    close("a1", tf.denominator[1], -0.2, tol);
    close("a2", tf.denominator[2], 0.35, tol);
    close("b0", tf.numerator[0], 0.0, tol);
    close("b1", tf.numerator[1], 1.0, tol);
    close("b2", tf.numerator[2], 0.5, tol);
}

fn check_sh(model: &HammersteinModel<f64>, tol: f64) {
    close("p", param(model, "p"), 2.0, tol);
    close("a", param(model, "a"), 0.5, tol);
    close("z1", param(model, "z1"), 1.5, tol);
    close("z2", param(model, "z2"), -1.0, tol);
    check_linear(model, tol);
}

#[test]
fn sh_structure_recovers_every_parameter() {
    let model = Hammerstein::sh().fit(&example1(0.0)).unwrap();
    let rep = model.report();
    eprintln!("{:#?}", rep.iterations);
    check_sh(&model, 1e-6);
    assert_eq!(rep.termination, Termination::Converged);
    assert!(rep.train_mse < 1e-12, "{}", rep.train_mse);
    close("offset", model.output_offset(), 0.0, 1e-8);
}

#[test]
fn sh_with_output_offset() {
    let model = Hammerstein::sh().fit(&example1(3.7)).unwrap();
    check_sh(&model, 1e-6);
    close("offset", model.output_offset(), 3.7, 1e-6);
}

#[test]
fn full_udn_recovers_sh_with_vanishing_extra_effects() {
    let model = Hammerstein::udn(EffectSet::all())
        .fit(&example1(0.0))
        .unwrap();
    let rep = model.report();
    eprintln!("{:?} {:?}", rep.termination, model.parameters());
    check_sh(&model, 1e-6);
    close("b", param(&model, "b"), 0.0, 1e-6);
    close("e1", param(&model, "e1"), 0.0, 1e-6);
    close("e2", param(&model, "e2"), 0.0, 1e-6);
}

#[test]
fn linear_gain_single_pass() {
    let truth = Udn::<f64>::linear();
    let u = example1_input::<f64>(500, 3);
    let v: Vec<f64> = truth.eval(&u).iter().map(|x| 2.5 * x).collect();
    let y = example1_linear::<f64>().simulate_siso(&v, None).unwrap();
    let model = Hammerstein::linear()
        .fit(&IoData::siso(&u, &y).unwrap())
        .unwrap();
    assert!(model.report().converged, "{:?}", model.report().termination);
    close("p", param(&model, "p"), 2.5, 1e-8);
    check_linear(&model, 1e-8);
}
