//! The Prandtl–Ishlinskii basis in the Hammerstein loop: recovery of the play-operator weights on
//! noise-free data (alone and with saturation), save/load round trip, scale invariance.

mod common;
use common::{InputKind, input};
use hammerstein::fit::HammersteinModel;
use hammerstein::regressors::{
    DEFAULT_PLAYS, Effect, EffectSet, PrandtlIshlinskii, StaticNonlinearity, Udn, play_grid,
};
use hammerstein::{Hammerstein, IoData, StateSpace};

/// G(z) = (z⁻¹ + 0.5 z⁻²)/(1 − 1.2 z⁻¹ + 0.45 z⁻²) (first Markov parameter 1, as the fit's
/// normalisation has it).
fn block() -> StateSpace<f64> {
    StateSpace::from_rows(
        &[&[1.2, 1.0], &[-0.45, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap()
}

/// A smooth input whose amplitude varies (slow envelope), so that reversals of every size occur.
fn varying_input(n: usize, seed: u64) -> Vec<f64> {
    let base = input(InputKind::Smooth, n, 1.0, seed);
    (0..n)
        .map(|k| base[k] * (0.35 + 0.65 * (0.5 + 0.5 * (k as f64 * 0.004).sin())))
        .collect()
}

/// Truth: `base` plus play operators on the grid the fit will choose (the input's own grid).
fn truth(base: Udn<f64>, u: &[f64], w: &[f64]) -> PrandtlIshlinskii<f64> {
    let (r, c) = play_grid(u, w.len()).unwrap();
    let mut pi = PrandtlIshlinskii::with_grid(Box::new(base), r, c).unwrap();
    let mut th = pi.base().params();
    th.extend_from_slice(w);
    pi.set_params(&th).unwrap();
    pi
}

fn record(nl: &dyn StaticNonlinearity<f64>, u: &[f64]) -> IoData<f64> {
    let y = block().simulate_siso(&nl.eval(u), None).unwrap();
    IoData::siso(u, &y).unwrap()
}

/// True play weights (the first K of a fixed list).
fn weights() -> Vec<f64> {
    [0.5, -0.3, 0.4, 0.25, -0.2, 0.3, 0.15, -0.1, 0.2, 0.1][..DEFAULT_PLAYS].to_vec()
}

fn param(m: &HammersteinModel<f64>, name: &str) -> f64 {
    m.parameters()
        .into_iter()
        .find(|(n, _)| n == name)
        .unwrap()
        .1
}

#[test]
fn fit_recovers_the_play_weights_noise_free() {
    let u = varying_input(2000, 1);
    let t = truth(
        Udn::with_params(EffectSet::empty(), &[1.5]).unwrap(),
        &u,
        &weights(),
    );
    let data = record(&t, &u);
    let m = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::PrandtlIshlinskii]))
        .fit(&data)
        .unwrap();
    assert_eq!(m.linear().order(), 2);
    assert!(
        (param(&m, "p") - 1.5).abs() < 1e-6,
        "p = {}",
        param(&m, "p")
    );
    for (j, w) in weights().iter().enumerate() {
        let got = param(&m, &format!("w{}", j + 1));
        assert!((got - w).abs() < 1e-6, "w{}: {got} vs {w}", j + 1);
    }
    assert!(
        m.nonlinearity()
            .effects()
            .contains(&"prandtl-ishlinskii".to_string())
    );
}

#[test]
fn fit_recovers_saturation_plus_play_weights_noise_free() {
    let u = varying_input(3000, 2);
    let set = EffectSet::of(&[Effect::Saturation]);
    let umax = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let base = Udn::with_params(set, &[1.5, 0.7 * umax, -0.6 * umax]).unwrap();
    let t = truth(base, &u, &weights());
    let data = record(&t, &u);
    let m = Hammerstein::<f64>::udn(set.with(Effect::PrandtlIshlinskii))
        .fit(&data)
        .unwrap();
    let tol = 1e-4;
    assert!((param(&m, "p") - 1.5).abs() < tol, "p = {}", param(&m, "p"));
    assert!(
        (param(&m, "z1") - 0.7 * umax).abs() < tol * umax,
        "z1 = {}",
        param(&m, "z1")
    );
    assert!(
        (param(&m, "z2") + 0.6 * umax).abs() < tol * umax,
        "z2 = {}",
        param(&m, "z2")
    );
    for (j, w) in weights().iter().enumerate() {
        let got = param(&m, &format!("w{}", j + 1));
        assert!((got - w).abs() < tol, "w{}: {got} vs {w}", j + 1);
    }
}

#[test]
fn save_and_load_round_trip() {
    let u = varying_input(1500, 3);
    let t = truth(
        Udn::with_params(EffectSet::empty(), &[1.0]).unwrap(),
        &u,
        &weights(),
    );
    let data = record(&t, &u);
    let m = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::PrandtlIshlinskii]))
        .fit(&data)
        .unwrap();
    let dir = std::env::temp_dir().join(format!("hammerstein-pi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("pi.json");
    m.save(&path).unwrap();
    let back = HammersteinModel::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    // (the file stores decimal text: the last bit may differ)
    for ((na, a), (nb, b)) in back.parameters().iter().zip(m.parameters().iter()) {
        assert_eq!(na, nb);
        assert!(
            (a - b).abs() <= 1e-12 * b.abs().max(1.0),
            "{na}: {a} vs {b}"
        );
    }
    assert_eq!(back.parameters().len(), m.parameters().len());
    assert_eq!(back.settings().effects(), m.settings().effects());
    // the grid travels with the file: a new input gives the same output
    let u2 = varying_input(800, 9);
    let (a, b) = (m.simulate(&u2).unwrap(), back.simulate(&u2).unwrap());
    let d = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-12, "{d}");
}

#[test]
fn scaled_records_give_the_scaled_model() {
    let u = varying_input(2000, 4);
    let set = EffectSet::of(&[Effect::Saturation]);
    let umax = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let base = Udn::with_params(set, &[1.0, 0.6 * umax, -0.7 * umax]).unwrap();
    let data = record(&truth(base, &u, &weights()), &u);
    let settings = Hammerstein::<f64>::udn(set.with(Effect::PrandtlIshlinskii));
    let m = settings.fit(&data).unwrap();
    for (su, sy) in [(1e3, 1e-2), (1e-4, 50.0)] {
        let us: Vec<f64> = data.input(0).iter().map(|x| x * su).collect();
        let ys: Vec<f64> = data.output(0).iter().map(|x| x * sy).collect();
        let ms = settings.fit(&IoData::siso(&us, &ys).unwrap()).unwrap();
        // weights and p carry output/input units; thresholds input units
        for (name, v) in m.parameters() {
            let want = if name.starts_with('z') {
                v * su
            } else {
                v * sy / su
            };
            let got = param(&ms, &name);
            assert!(
                (got - want).abs() <= 1e-6 * want.abs().max(1e-3 * sy / su),
                "{name} at scales ({su}, {sy}): {got} vs {want}"
            );
        }
        let (a, b) = (
            m.simulate(&data.input(0)).unwrap(),
            ms.simulate(&us).unwrap(),
        );
        let e = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x * sy - y).abs())
            .fold(0.0, f64::max);
        assert!(e < 1e-6 * sy, "{e}");
    }
}

/// A record whose truth has play weights of both signs: the unconstrained PI refit of the
/// diagnosis has weights of both signs, the candidate's refit (an outer active set on the grid)
/// keeps only plays whose weights have the sign of the gain p, and says which it removed.
#[test]
fn pi_refit_has_weights_of_one_sign() {
    use hammerstein::diagnosis::Diagnoser;
    let u = varying_input(2000, 3);
    let t = truth(
        Udn::with_params(EffectSet::empty(), &[1.5]).unwrap(),
        &u,
        &weights(),
    );
    let (train, valid) = record(&t, &u).split_validation(0.3).unwrap();
    let model = Hammerstein::<f64>::linear().fit(&train).unwrap();
    let weights_of = |m: &HammersteinModel<f64>| -> Vec<f64> {
        m.parameters()
            .into_iter()
            .filter(|(n, _)| n.starts_with('w'))
            .map(|(_, v)| v)
            .collect()
    };
    let unconstrained = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::PrandtlIshlinskii]))
        .at_structure_of(&model)
        .fit(&train)
        .unwrap();
    let w = weights_of(&unconstrained);
    assert!(
        w.iter().any(|&x| x > 0.0) && w.iter().any(|&x| x < 0.0),
        "the unconstrained refit should have weights of both signs: {w:?}"
    );
    let d = Diagnoser::new().diagnose(&model, &train, &valid).unwrap();
    let outcome = d
        .candidates
        .iter()
        .find(|c| c.effect == "prandtl-ishlinskii")
        .expect("the PI candidate is tried");
    let refit = outcome
        .refit
        .as_ref()
        .expect("the PI candidate is refitted");
    let m = refit.model.as_ref().expect("the refit keeps its model");
    let (p, w) = (param(m, "p"), weights_of(m));
    assert!(
        !w.is_empty() && w.len() < DEFAULT_PLAYS,
        "plays should be removed: {w:?}"
    );
    assert!(
        w.iter().all(|&x| x * p >= 0.0),
        "every kept weight has the sign of p = {p}: {w:?}"
    );
    assert!(refit.change.contains("removed"), "{}", refit.change);
}

/// A fit from a Prandtl–Ishlinskii model at its own parameters (`fit_from`, as the diagnosis'
/// nested refits start) sets the play grid from the record as the fit does, so it starts at
/// that model and cannot end above it on training.
#[test]
fn a_fit_from_a_pi_model_starts_at_it() {
    let u = varying_input(2000, 4);
    let t = truth(
        Udn::with_params(EffectSet::of(&[Effect::Saturation]), &[1.2, 0.9, -0.8]).unwrap(),
        &u,
        &weights(),
    );
    let clean = record(&t, &u);
    let noise = input(InputKind::Smooth, 2000, 0.02, 9);
    let y: Vec<f64> = clean
        .output_slice(0)
        .iter()
        .zip(&noise)
        .map(|(y, e)| y + e)
        .collect();
    let data = IoData::siso(&u, &y).unwrap();
    let settings = Hammerstein::<f64>::udn(EffectSet::of(&[
        Effect::Saturation,
        Effect::PrandtlIshlinskii,
    ]))
    .order(hammerstein::Order::Fixed(2));
    let base = settings.fit(&data).unwrap();
    let mse = |m: &HammersteinModel<f64>| {
        hammerstein::diagnosis::compare(m, &data)
            .unwrap()
            .metrics
            .mse
    };
    let theta: Vec<f64> = base.parameters().into_iter().map(|(_, v)| v).collect();
    let again = settings.fit_from(&data, &base, &theta).unwrap();
    assert!(
        mse(&again) <= mse(&base) * (1.0 + 1e-9),
        "from the model itself: {} against {}",
        mse(&again),
        mse(&base)
    );
}

/// The thresholds and centre of a model's play grid, from its spec.
fn grid_of(m: &HammersteinModel<f64>) -> (Vec<f64>, f64) {
    let spec = m.nonlinearity().spec();
    let r = spec.config["thresholds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    (r, spec.config["centre"].as_f64().unwrap())
}

/// A fit from a Prandtl–Ishlinskii model fitted on another part of the record (as a long
/// record's structure is chosen on a screening window) keeps that model's play grid, a subset of
/// its plays included, instead of one re-derived from the record it is refitted on: only then
/// does it start at that model. The grids of the two parts differ (the input's envelope grows).
#[test]
fn a_fit_from_a_pi_model_keeps_its_grid() {
    let u = varying_input(3000, 5);
    let t = truth(
        Udn::with_params(EffectSet::of(&[Effect::Saturation]), &[1.2, 0.9, -0.8]).unwrap(),
        &u,
        &weights(),
    );
    let whole = record(&t, &u);
    let window = IoData::siso(&u[..800], &whole.output_slice(0)[..800]).unwrap();
    let sat = EffectSet::of(&[Effect::Saturation]);
    let base = Hammerstein::<f64>::udn(EffectSet::of(&[
        Effect::Saturation,
        Effect::PrandtlIshlinskii,
    ]))
    .order(hammerstein::Order::Fixed(2))
    .fit(&window)
    .unwrap();
    let (r_base, c_base) = grid_of(&base);
    let (r_whole, _) = play_grid(&u, DEFAULT_PLAYS).unwrap();
    assert!(
        (r_whole[0] - r_base[0]).abs() > 1e-3 * r_base[0],
        "the parts' grids should differ: {r_whole:?} against {r_base:?}"
    );
    let kept = [1, 2, 3, 5, 6];
    let subset =
        PrandtlIshlinskii::on_subset(Box::new(Udn::<f64>::new(sat)), DEFAULT_PLAYS, &kept).unwrap();
    let settings = Hammerstein::<f64>::new(Box::new(subset)).order(hammerstein::Order::Fixed(2));
    let theta: Vec<f64> = base
        .parameters()
        .into_iter()
        .filter(|(n, _)| n != "w4")
        .map(|(_, v)| v)
        .collect();
    let refit = settings.fit_from(&whole, &base, &theta).unwrap();
    let (r, c) = grid_of(&refit);
    let expected: Vec<f64> = kept.iter().map(|&j| r_base[j - 1]).collect();
    assert_eq!(r, expected, "the refit's thresholds are the base's");
    assert_eq!(c, c_base, "the refit's centre is the base's");
}

/// A fit started at given parameters (`Init::Given`) configures the operator on the record as
/// the default start does: its play grid is the input's, as in the model the parameters come
/// from, not the operator's unit grid.
#[test]
fn a_fit_from_given_parameters_uses_the_records_grid() {
    let u = varying_input(2000, 6);
    let t = truth(
        Udn::with_params(EffectSet::empty(), &[1.5]).unwrap(),
        &u,
        &weights(),
    );
    let data = record(&t, &u);
    let settings = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::PrandtlIshlinskii]))
        .order(hammerstein::Order::Fixed(2));
    let base = settings.fit(&data).unwrap();
    let theta: Vec<f64> = base.parameters().into_iter().map(|(_, v)| v).collect();
    let given = settings
        .clone()
        .init(hammerstein::Init::Given(theta))
        .fit(&data)
        .unwrap();
    let (r, c) = play_grid(&u, DEFAULT_PLAYS).unwrap();
    for m in [&base, &given] {
        let (rm, cm) = grid_of(m);
        for (a, b) in rm.iter().zip(&r) {
            assert!((a - b).abs() <= 1e-12 * b, "{rm:?} against {r:?}");
        }
        assert!((cm - c).abs() <= 1e-12 * r[0], "centre {cm} against {c}");
    }
}
