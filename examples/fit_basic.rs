//! Fits a Hammerstein model to simulated data of the paper's Example 1 (SH nonlinearity, second-order
//! linear block) and prints what came back. Run: `cargo run --release --example fit_basic`.

use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};

fn main() -> hammerstein::Result<()> {
    // the true system: p = 2, a = 0.5, z1 = 1.5, z2 = −1; G(z) = z⁻¹(1 + 0.5z⁻¹)/(1 − 0.2z⁻¹ + 0.35z⁻²)
    let sh = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(sh, &[2.0, 0.5, 1.5, -1.0])?;
    let g = StateSpace::<f64>::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )?;
    let mut rng = StdRng::seed_from_u64(1);
    let u: Vec<f64> = (0..2000).map(|_| rng.random_range(-3.0..3.0)).collect();
    let y: Vec<f64> = g
        .simulate_siso(&truth.eval(&u), None)?
        .into_iter()
        .map(|y| y + 0.5 + 0.1 * rng.random_range(-1.0..1.0)) // offset and a little noise
        .collect();
    let data = IoData::siso(&u, &y)?;

    // fit the full UDN: the extra effects (dead-zone, preload) should come back near zero
    let model = Hammerstein::udn(EffectSet::all()).refine(true).fit(&data)?;
    let rep = model.report();
    println!(
        "{} after {} iterations (best {}), order {}, training MSE {:.3e}",
        rep.termination,
        rep.iterations.len(),
        rep.best_iteration,
        rep.order,
        rep.train_mse
    );
    for (name, value) in model.parameters() {
        println!("  {name:>3} = {value:+.4}");
    }
    let tf = model.transfer_function()?;
    println!("  numerator   {:?}", tf.numerator);
    println!("  denominator {:?}", tf.denominator);
    println!("  output offset {:+.4}", model.output_offset());
    Ok(())
}
