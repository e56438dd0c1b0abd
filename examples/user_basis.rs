//! A user-defined nonlinearity in a few lines: the saturation-with-hysteresis UDN (SH) augmented
//! with an asymmetric gain u·[u > 0] and a Coulomb-friction-like term s(k) (the input direction),
//! and a basis made only of user columns.
//!
//! Uses the regressors API only (the iterative Hammerstein loop lives in `hammerstein::fit`):
//! it builds a synthetic actuator output v = φ·g, then recovers g from (φ, v) by least squares,
//! which is exactly what the loop's linear step does once the linear block is factored out.
//!
//! Run: `cargo run --example user_basis`

use hammerstein::regressors::{Augmented, StaticNonlinearity, Udn, UserBasis, UserColumn};
use hammerstein::solvers::{BackendKind, backend};
use rand::{RngExt, SeedableRng, rngs::StdRng};

fn main() -> hammerstein::Result<()> {
    let mut rng = StdRng::seed_from_u64(7);
    let u: Vec<f64> = (0..2000).map(|_| rng.random_range(-3.0..3.0)).collect();

    // 1. A built-in UDN (SH: p, a, z1, z2) plus two user columns of (u(k), s(k)).
    let extra = vec![
        UserColumn::new("u_pos", |u: f64, _s| if u > 0.0 { u } else { 0.0 }),
        UserColumn::new("coulomb", |_u, s| s),
    ];
    let mut truth = Augmented::new(Udn::sh(), extra.clone())?;
    truth.set_params(&[2.0, 0.5, 1.5, -1.0, 0.4, 0.15])?;
    println!(
        "model {}: parameters {:?}",
        truth.name(),
        truth.param_names()
    );
    println!("regressor columns {:?}", truth.regressor_names());

    // Synthetic actuator output v = φ·g.
    let v = truth.eval(&u);
    for k in 0..5 {
        println!("u = {:+.3}  v = {:+.3}", u[k], v[k]);
    }

    // 2. Recover the gains from (φ, v) with the thresholds fixed at the truth (the loop's linear
    //    step), then map them back to parameters (with the zone guard).
    let la = backend::<f64>(BackendKind::Faer)?;
    let phi = truth.regressors(&u);
    let vm = faer::Mat::from_fn(u.len(), 1, |k, _| v[k]);
    let g = la.lstsq(phi.as_ref(), vm.as_ref())?;
    let g: Vec<f64> = (0..g.nrows()).map(|i| g[(i, 0)]).collect();
    let mut model = Augmented::new(Udn::sh(), extra)?;
    model.initialize(&u);
    model.update_from_gains(&g, &u)?;
    println!("recovered parameters:");
    for (name, value) in model.param_names().iter().zip(model.params()) {
        println!("  {name:>8} = {value:.6}");
    }

    // 3. A basis of user columns only: linear gain + odd cubic + direction-dependent offset.
    let cols = vec![
        UserColumn::new("u", |u: f64, _s| u),
        UserColumn::new("u3", |u: f64, _s| u * u * u),
        UserColumn::new("sign_s", |_u, s| s),
    ];
    let mut basis = UserBasis::new("cubic-friction", &["friction"], cols)?;
    basis.set_params(&[1.0, -0.05, 0.2])?;
    let vb = basis.eval(&u[..3]);
    println!("{} on the first samples: {vb:?}", basis.name());
    println!(
        "spec: {}",
        serde_json::to_string(&basis.spec()).unwrap_or_default()
    );
    Ok(())
}
