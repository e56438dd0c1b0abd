//! The 1-D search over the UDN's dead-zone width b (not determined by the gains when preload is
//! modelled): noise-free records are fitted exactly whether the true b is zero or not.

mod hammerstein_common;
use hammerstein::Hammerstein;
use hammerstein::IoData;
use hammerstein::regressors::{EffectSet, Udn};
use hammerstein::study::Example1;
use hammerstein::study::example1::variance;
use hammerstein::study::monte_carlo::{Strategy, Table, estimator};
use hammerstein::subspace::MethodKind;
use hammerstein_common::{example1_input, record};
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

#[test]
fn full_udn_with_a_dead_zone_and_preloads_is_fitted_exactly() {
    let truth = [1.5, 0.2, 0.6, 2.0, -1.5, 0.4, -0.3];
    let nl = Udn::<f64>::with_params(EffectSet::all(), &truth).unwrap();
    let data = record(&nl, &example1_input(2000, 4), 0.0);
    let y = data.output(0);
    let model = Hammerstein::<f64>::udn(EffectSet::all())
        .fit(&data)
        .unwrap();
    // an exact fit (round-off level); b itself is only determined up to the gap between the
    // input samples around ±b, so the other parameters are checked tightly and b loosely
    let mse = model.report().train_mse;
    assert!(mse <= 1e-20 * variance(&y), "mse {mse:e}");
    let th = model.nonlinearity().params();
    assert!((th[0] - truth[0]).abs() < 1e-6, "p = {}", th[0]);
    assert!((th[1] - truth[1]).abs() < 1e-6, "a = {}", th[1]);
    assert!((th[2] - truth[2]).abs() < 5e-3, "b = {}", th[2]);
}

#[test]
fn among_exact_fits_the_loop_prefers_no_dead_zone() {
    // Example 1 (true b = 0), noise-free, record 31: the loop's fixed point was an exact fit with
    // b ≈ 1e-3 (no sample inside that band) before the lower-end check was added.
    let data = Example1::new(None).generate::<f64>(31).unwrap().data;
    let model = estimator::<f64>(Table::Table2, Strategy::PaperLoop, MethodKind::Moesp)
        .fit(&data)
        .unwrap();
    let th = model.nonlinearity().params();
    assert_eq!(th[2], 0.0, "b = {}", th[2]);
    for (v, t) in th.iter().zip([2.0, 0.5, 0.0, 1.5, -1.0, 0.0, 0.0]) {
        assert!((v - t).abs() < 1e-6, "{th:?}");
    }
}

#[test]
fn the_search_side_by_side_gives_the_fit_of_the_search_in_turn() {
    // the search evaluates its independent candidates two at a time and golden section's next
    // point ahead when rayon's pool has a second thread: the fit must be the one-thread fit,
    // bit for bit (noisy record, full UDN, order 2: the bench's fit; with and without the
    // refinement, whose two starts also run side by side)
    let truth = [2.0, 0.5, 0.3, 1.5, -1.0, 0.2, -0.1];
    let nl = Udn::<f64>::with_params(EffectSet::all(), &truth).unwrap();
    let u = example1_input(2000, 11);
    let clean = record(&nl, &u, 0.5);
    let mut rng = StdRng::seed_from_u64(12);
    let normal = Normal::new(0.0, 0.5).unwrap();
    let y: Vec<f64> = clean
        .output(0)
        .iter()
        .map(|v| v + normal.sample(&mut rng))
        .collect();
    let data = IoData::siso(&u, &y).unwrap();
    for refine in [true, false] {
        let settings = Hammerstein::<f64>::udn(EffectSet::all())
            .order(hammerstein::Order::Fixed(2))
            .refine(refine);
        let fit_in = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| settings.fit(&data).unwrap())
        };
        let (one, two) = (fit_in(1), fit_in(2));
        let bits = |m: &hammerstein::HammersteinModel<f64>| {
            let mut v: Vec<u64> = m
                .nonlinearity()
                .params()
                .iter()
                .map(|x| x.to_bits())
                .collect();
            v.push(m.report().train_mse.to_bits());
            v.extend(m.report().iterations.iter().map(|r| r.mse.to_bits()));
            v.extend(
                m.linear()
                    .a
                    .col_iter()
                    .flat_map(|c| c.iter().map(|x| x.to_bits()).collect::<Vec<_>>()),
            );
            v
        };
        assert_eq!(bits(&one), bits(&two), "refine {refine}");
    }
}
