//! Structure selection over the 16 UDN effect subsets on Example 1 (SH truth).

mod hammerstein_common;
use hammerstein::fit::{Criterion, select_structure};
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein::{Hammerstein, IoData};
use hammerstein_common::*;

fn sh_set() -> EffectSet {
    EffectSet::of(&[Effect::Hysteresis, Effect::Saturation])
}

fn example1() -> IoData<f64> {
    let truth = Udn::<f64>::with_params(sh_set(), &[2.0, 0.5, 1.5, -1.0]).unwrap();
    record(&truth, &example1_input(2000, 7), 0.0)
}

#[test]
fn bic_picks_sh_on_noise_free_data() {
    let rep = select_structure(
        &Hammerstein::udn(EffectSet::all()),
        &example1(),
        Criterion::Bic,
    )
    .unwrap();
    for c in &rep.candidates {
        eprintln!(
            "{:40} {:?} mse {:.3e} score {:.1} k {}",
            c.effects.label(),
            c.dn_type,
            c.mse,
            c.score,
            c.n_params
        );
    }
    assert_eq!(rep.chosen, sh_set());
    assert_eq!(rep.dn_type, Some(4));
    assert_eq!(rep.candidates.len(), 16);
}

#[test]
fn bic_picks_sh_at_10_db() {
    let data = add_noise(&example1(), 10.0, 11);
    let rep = select_structure(&Hammerstein::udn(EffectSet::all()), &data, Criterion::Bic).unwrap();
    for c in &rep.candidates {
        eprintln!(
            "{:40} {:?} mse {:.4e} score {:.1} k {}",
            c.effects.label(),
            c.dn_type,
            c.mse,
            c.score,
            c.n_params
        );
    }
    assert_eq!(rep.chosen, sh_set());
}

#[test]
fn structure_selection_needs_a_udn() {
    let base = Hammerstein::new(Box::new(UserSh::<f64>::new(1.0, 0.0, 1.0, -1.0)));
    assert!(select_structure(&base, &example1(), Criterion::Bic).is_err());
}
