//! Battery of random Hammerstein records fitted with the default settings and the true effects
//! (issue "Right by default"): random linear blocks of order 1–4 (lightly damped, slow, fast,
//! anywhere, non-minimum-phase zeros), random UDN parameters and effect subsets, four input kinds,
//! SNR 15–40 dB, N 1000–5000, an output offset.
//!
//! `cargo test` runs a fast slice. The full battery:
//! `BATTERY_SEEDS=200 cargo test --release --test fit_battery -- --ignored --nocapture`
//! prints the table of `docs/battery.md` (and appends it to the file `BATTERY_WRITE` names);
//! `BATTERY_OFFSET=200` runs seeds 201–400 instead (development seeds: the documented 1–200 stay
//! a held-out check).
//! `BATTERY_MODE` = `default` (the default fit), `true-order` (the true order given),
//! `no-refine` (the subspace loop alone, order selection on), `gap` (the loop alone with the
//! singular-value gap rule: the old default), `truth-start` (the true order, the loop started at
//! the true nonlinearity parameters: what the fit reaches from the truth's basin), `stable` (the
//! default fit with the stability constraint, `Hammerstein::stable`).
//! `BATTERY_TRAIN=1` prints each record's training and validation MSE over the noise and whether
//! the refinement lowered the loop's MSE (a training MSE far above the noise is a local minimum;
//! a validation MSE above it with the training one at the floor is what the training part does
//! not determine).

mod common;

use common::random_system::{RandomRecord, Ranges, random_record};
use hammerstein::diagnosis::compare;
use hammerstein::fit::Hammerstein;
use hammerstein::{IoData, Order};
use rayon::prelude::*;

/// Outcome of one record.
#[derive(Debug, Clone)]
struct Outcome {
    rec_seed: u64,
    order: usize,
    chosen: Option<usize>,
    excitation: &'static str,
    poles: &'static str,
    effects: String,
    snr: f64,
    n: usize,
    ratio: f64,
    error: Option<String>,
    /// Wall time of the fit, seconds.
    secs: f64,
    /// The order was chosen below the truth and the training record's evidence for the true
    /// order is below what a 5 % test needs (`undetectable`).
    undetectable: bool,
}

/// The size of the Markov parameter the fit's normalisation sets to one (`MarkovOne`: the first
/// of h₀ = D, h₁ = CB, h₂ = CAB, … above 5 % of the largest), over the first 40.
fn reference_markov(rec: &RandomRecord) -> f64 {
    let h: Vec<f64> = std::iter::once(rec.block.d[(0, 0)])
        .chain(rec.block.markov_parameters(40).iter().map(|m| m[(0, 0)]))
        .collect();
    let max = h.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    h.iter()
        .find(|x| x.abs() > 0.05 * max)
        .map_or(1.0, |x| x.abs())
}

/// The true nonlinearity's parameters in the model's normalisation (the reference Markov
/// parameter moved into the gains), in the UDN's parameter order.
fn truth_theta(rec: &RandomRecord) -> Vec<f64> {
    use hammerstein::regressors::{StaticNonlinearity, Udn};
    let h1 = reference_markov(rec);
    let t = rec.truth;
    let all = [t.p * h1, t.a, t.b, t.z1, t.z2, t.e1 * h1, t.e2 * h1];
    let names = ["p", "a", "b", "z1", "z2", "e1", "e2"];
    Udn::<f64>::new(rec.effects)
        .param_names()
        .iter()
        .filter_map(|n| names.iter().position(|m| m == n).map(|i| all[i]))
        .collect()
}

fn settings(rec: &RandomRecord, mode: &str) -> Hammerstein<f64> {
    let s = Hammerstein::udn(rec.effects).seed(rec.seed);
    match mode {
        "true-order" => s.order(Order::Fixed(rec.order)),
        "truth-start" => s
            .order(Order::Fixed(rec.order))
            .init(hammerstein::Init::Given(truth_theta(rec))),
        "no-refine" => s.refine(false),
        "gap" => s.refine(false).order(Order::Gap),
        "gap-refine" => s.refine(true).order(Order::Gap),
        "true-refine" => s.refine(true).order(Order::Fixed(rec.order)),
        "true-no-refine" => s.refine(false).order(Order::Fixed(rec.order)),
        // the stability constraint on (`--stable`): every block of the battery is stable, so
        // the constraint should change nothing but the blocks an estimate put outside
        "stable" => s.stable(true),
        _ => s,
    }
}

/// A record's fit ended without error at the noise floor (validation MSE ≤ 1.2× the noise).
fn assert_at_floor(o: &Outcome) {
    assert!(o.error.is_none(), "{:?}", o.error);
    assert!(o.ratio <= 1.2, "not at the noise floor: {o:#?}");
}

fn run(seed: u64, mode: &str) -> Outcome {
    let rec = random_record(seed, &Ranges::default());
    let mut out = Outcome {
        rec_seed: seed,
        order: rec.order,
        chosen: None,
        excitation: rec.excitation.name(),
        poles: rec.poles.name(),
        effects: rec.effects.label(),
        snr: rec.snr_db,
        n: rec.n,
        ratio: f64::NAN,
        error: None,
        secs: 0.0,
        undetectable: false,
    };
    let res = (|| -> hammerstein::Result<(usize, f64)> {
        let data = IoData::siso(&rec.u, &rec.y)?;
        let (train, valid) = data.split_validation(0.3)?;
        let t0 = std::time::Instant::now();
        let model = settings(&rec, mode).fit(&train)?;
        out.secs = t0.elapsed().as_secs_f64();
        let c = compare(&model, &valid)?;
        if std::env::var("BATTERY_TRAIN").is_ok() {
            let r = model.report();
            println!(
                "train {seed} train/noise {:.3} val/noise {:.3} refinement (accepted, iterations) {:?}",
                r.train_mse / rec.noise_var,
                c.metrics.mse / rec.noise_var,
                r.refinement.as_ref().map(|f| (f.accepted, f.iterations))
            );
        }
        if mode == "default" && model.report().order < rec.order {
            out.undetectable = undetectable(&rec, &model, &train);
        }
        Ok((model.report().order, c.metrics.mse / rec.noise_var))
    })();
    match res {
        Ok((n, r)) => {
            out.chosen = Some(n);
            out.ratio = r;
        }
        Err(e) => out.error = Some(e.to_string()),
    }
    out
}

/// 95 % quantiles of χ² with 3, 6, 9 and 12 degrees of freedom (one to four orders: a pole, a
/// numerator coefficient and an initial state each).
const CHI2_95: [f64; 4] = [7.815, 12.592, 16.919, 21.026];

/// Whether `model`, of an order below the record's, leaves less evidence for the true order than
/// a likelihood-ratio test at 5 % needs: λ = N·ln(MSE_model / MSE_fit) on the training record,
/// MSE_fit the true-order fit's (initial conditions estimated, as `compare` does), below the χ²
/// quantile of the orders' extra parameters: a 5 % test between the two fits found keeps the
/// lower order. Never when the true-order fit is worse than the true model itself: that fit is
/// then a local minimum, the global one lies below the truth by its own overfit (≈ χ² with as
/// many degrees of freedom as parameters), and the miss is the search's, not the data's.
fn undetectable(
    rec: &RandomRecord,
    model: &hammerstein::HammersteinModel<f64>,
    train: &IoData<f64>,
) -> bool {
    let mse = |m: &hammerstein::HammersteinModel<f64>| {
        compare(m, train).map_or(f64::NAN, |c| c.metrics.mse)
    };
    let fitted = settings(rec, "true-order")
        .fit(train)
        .map_or(f64::INFINITY, |t| mse(&t));
    let truth = truth_model(rec, model).map_or(f64::INFINITY, |t| mse(&t));
    // NaN (a failed simulation) excuses nothing either
    if fitted.partial_cmp(&truth) == Some(std::cmp::Ordering::Greater) || fitted.is_nan() {
        return false;
    }
    let lambda = train.len() as f64 * (mse(model) / fitted).ln();
    let dn = rec.order - model.report().order;
    lambda < CHI2_95[(dn - 1).min(3)]
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Table of shares at the floor per input kind and per order.
fn table(outs: &[Outcome]) -> String {
    let mut s = String::new();
    let row = |name: String, sel: Vec<&Outcome>| -> String {
        let n = sel.len();
        let floor = sel
            .iter()
            .filter(|o| o.error.is_none() && o.ratio <= 1.2)
            .count();
        let right = sel.iter().filter(|o| o.chosen == Some(o.order)).count();
        // a wrong order whose fit still reaches the floor explains the data as well
        let equivalent = sel
            .iter()
            .filter(|o| o.chosen == Some(o.order) || (o.error.is_none() && o.ratio <= 1.2))
            .count();
        let errors = sel.iter().filter(|o| o.error.is_some()).count();
        let detectable = n - sel.iter().filter(|o| o.undetectable).count();
        let med = median(
            sel.iter()
                .filter(|o| o.error.is_none())
                .map(|o| o.ratio)
                .collect(),
        );
        format!(
            "| {name} | {n} | {floor} ({:.0} %) | {right} ({:.0} %) | {right}/{detectable} ({:.0} %) | {equivalent} ({:.0} %) | {med:.3} | {errors} |\n",
            100.0 * floor as f64 / n.max(1) as f64,
            100.0 * right as f64 / n.max(1) as f64,
            100.0 * right as f64 / detectable.max(1) as f64,
            100.0 * equivalent as f64 / n.max(1) as f64
        )
    };
    s.push_str(
        "| records | n | val. MSE ≤ 1.2× noise | order right | order right where a 5 % test could tell | order right or fit at floor | median MSE/noise | errors |\n",
    );
    s.push_str("|---|---|---|---|---|---|---|---|\n");
    s.push_str(&row("all".into(), outs.iter().collect()));
    for k in ["uniform", "smooth", "multisine", "prbs"] {
        s.push_str(&row(
            format!("input {k}"),
            outs.iter().filter(|o| o.excitation == k).collect(),
        ));
    }
    for n in 1..=4 {
        s.push_str(&row(
            format!("order {n}"),
            outs.iter().filter(|o| o.order == n).collect(),
        ));
    }
    for p in ["lightly-damped", "slow", "fast", "anywhere"] {
        s.push_str(&row(
            format!("poles {p}"),
            outs.iter().filter(|o| o.poles == p).collect(),
        ));
    }
    s
}

#[test]
fn default_fit_reaches_the_noise_floor_on_a_random_slice() {
    let outs: Vec<Outcome> = (1..=8u64).map(|s| run(s, "default")).collect();
    println!("{}", table(&outs));
    for o in &outs {
        assert!(o.error.is_none(), "record {}: {:?}", o.rec_seed, o.error);
    }
    let at_floor = outs.iter().filter(|o| o.ratio <= 1.2).count();
    assert!(
        at_floor >= 7,
        "only {at_floor}/8 at the noise floor: {outs:#?}"
    );
}

/// Two development records (seeds 201–400) on which the first candidate's θ was a poor start
/// for every order: seed 368 (order 3, fast poles) ended at 40× the noise at order 2, seed 377
/// (order 4, slow poles, hysteresis) stopped at order 1 with 1387× the noise because orders 2 and
/// 3 failed from that θ. The loop at the best order, the sweep from a better θ and the nested
/// refits of failed orders bring both to the floor.
#[test]
fn order_search_escapes_a_poor_first_candidate() {
    for seed in [368, 377] {
        let o = run(seed, "default");
        assert!(o.error.is_none(), "record {seed}: {:?}", o.error);
        assert!(
            o.ratio <= 1.2,
            "record {seed} not at the noise floor: {o:#?}"
        );
    }
}

/// Preload without dead-zone and an output offset 14× the preload's steps (record 555: order 4,
/// e1 = 0.086, e2 = −0.115, offset −1.17): the preload columns span the constant, and the loop
/// once left the offset in their unidentifiable common mode (e1 ≈ e2 ≈ 25, a mode at z = 1,
/// 451× the noise at the true order). With the offset folded (`fit/numerics/offset_fold.rs`) the fit at
/// the true order reaches the floor.
#[test]
fn preload_with_an_output_offset_fits_at_the_true_order() {
    let o = run(555, "true-order");
    assert_at_floor(&o);
}

/// Four slow real poles (record 591: 0.84–0.94, dead-zone and preload, offset −1.18, 30 dB):
/// at the default horizon (8 block rows) the loop's subspace steps could not separate the
/// clustered slow modes, and the fit at the true order ended in a local minimum with the
/// dead-zone collapsed (3.5× the noise in training, 6.4× on validation; the true model 0.98×).
/// The fit redone at a horizon that spans the slowest time constant (`fit/numerics/slow_horizon.rs`)
/// reaches the floor.
#[test]
fn slow_clustered_poles_fit_at_the_true_order() {
    let o = run(591, "true-order");
    assert_at_floor(&o);
}

/// A saturation limit clipping too much (record 694: order 4, lightly damped with a
/// non-minimum-phase zero, all four effects, smooth input, 30 dB): the loop's zone guard keeps a
/// limit clipping at least 3 % of the samples, and the refinement stopped there with the lower
/// limit at −1.85 for −2.20, the other parameters compensating (1.79× the noise in training,
/// 1.69× on validation; the true model 1.05×). The restarts at other clipped shares
/// (`fit/numerics/kink_scan.rs`), run because the residual is larger near the limit than on the record,
/// reach the floor.
#[test]
fn a_saturation_limit_clipping_too_much_is_restarted() {
    let o = run(694, "true-order");
    assert_at_floor(&o);
}

/// A preload's jump a few samples off the truth's (record 764: order 3, slow real poles, dead-zone
/// and preload, smooth input, 38 dB): the fit ended with b 0.517 for 0.526, 2.05× the noise in
/// training and 3.99× on validation; the jump scan's spread starts are a quantile apart and LM's
/// secant slopes span several intervals. Its starts in the neighbouring intervals
/// (`jump_scan::local_values`) reach the floor.
#[test]
fn a_jump_a_few_samples_off_is_restarted_nearby() {
    let o = run(764, "true-order");
    assert_at_floor(&o);
}

/// A dead-zone beside a preload (record 327: order 1, hysteresis, dead-zone and preload, PRBS,
/// 26 dB): inside the interval the training record leaves b, e1 and e2 follow b exactly and the
/// training error is flat, yet the centring's section (the rest held) peaked at the fitted b,
/// near the interval's edge (b 0.0419 for 0.0384, five validation samples in between: 2.5×
/// the noise). The centring on the profile (`refine::centre_jumps`) places b mid-interval.
#[test]
fn dead_zone_beside_preload_centred_on_its_profile() {
    let o = run(327, "true-order");
    assert_at_floor(&o);
}

#[test]
#[ignore]
fn battery() {
    let seeds = common::env_count("BATTERY_SEEDS", 200);
    // development runs use other seeds: BATTERY_OFFSET=200 runs seeds 201–400
    let offset = common::env_count("BATTERY_OFFSET", 0);
    let mode = std::env::var("BATTERY_MODE").unwrap_or_else(|_| "default".into());
    let started = std::time::Instant::now();
    let outs: Vec<Outcome> = (offset + 1..=offset + seeds)
        .into_par_iter()
        .map(|s| run(s, &mode))
        .collect();
    let elapsed = started.elapsed().as_secs_f64();
    let verbose = std::env::var("BATTERY_VERBOSE").is_ok();
    for o in &outs {
        if verbose || o.error.is_some() || o.ratio > 1.2 || o.chosen != Some(o.order) {
            println!(
                "seed {} order {} chosen {:?} {} {} [{}] {:.0} dB N {} ratio {:.3} {:.3} s {:?}",
                o.rec_seed,
                o.order,
                o.chosen,
                o.excitation,
                o.poles,
                o.effects,
                o.snr,
                o.n,
                o.ratio,
                o.secs,
                o.error
            );
        }
    }
    let t = table(&outs);
    let per_2000: Vec<f64> = outs.iter().map(|o| o.secs * 2000.0 / o.n as f64).collect();
    println!(
        "fit time: mean {:.1} ms, median per 2000 samples {:.1} ms",
        1e3 * outs.iter().map(|o| o.secs).sum::<f64>() / outs.len().max(1) as f64,
        1e3 * median(per_2000)
    );
    println!(
        "mode {mode}, {seeds} records (seeds {}–{}), {elapsed:.1} s\n{t}",
        offset + 1,
        offset + seeds
    );
    if let Ok(path) = std::env::var("BATTERY_WRITE") {
        let misses: Vec<String> = outs
            .iter()
            .filter(|o| o.error.is_some() || o.ratio > 1.2)
            .map(|o| {
                format!(
                    "| {} | {} | {} | {} | {} | [{}] | {:.0} | {} | {} |",
                    o.rec_seed,
                    o.order,
                    o.chosen.map_or("-".into(), |n| n.to_string()),
                    o.excitation,
                    o.poles,
                    o.effects,
                    o.snr,
                    o.n,
                    o.error.clone().unwrap_or_else(|| format!("{:.3}", o.ratio))
                )
            })
            .collect();
        let text = format!(
            "### mode `{mode}`, {seeds} records (seeds {}–{})\n\n{t}\nRecords above the floor:\n\n\
             | seed | true order | chosen | input | poles | effects | SNR dB | N | val. MSE / noise |\n\
             |---|---|---|---|---|---|---|---|---|\n{}\n\n",
            offset + 1,
            offset + seeds,
            misses.join("\n")
        );
        let mut old = std::fs::read_to_string(&path).unwrap_or_default();
        old.push_str(&text);
        std::fs::write(&path, old).unwrap();
    }
}

/// A higher order that fits better only because the true order's own fits ended in a local
/// minimum (development record 505: order 3, lightly damped, hysteresis, saturation and
/// preload, multisine, 19 dB): the search chose order 4. The lower orders fitted again from the
/// best model's block truncated to them (`Problem::reduced_start`) reach the true order's fit.
#[test]
fn a_higher_order_gives_way_to_its_truncation_at_the_true_order() {
    let o = run(505, "default");
    assert_at_floor(&o);
    assert_eq!(o.chosen, Some(o.order), "{o:#?}");
}

/// An order the record can tell, kept out by BIC's ln N on the initial states (record 692: order
/// 4, fast poles, a linear gain, PRBS, 40 dB): charged ln N each, the fourth state's initial
/// value made order 4 cost 3·ln N over order 3 and the search chose order 3. Charged 2, as a
/// parameter whose information does not grow with N (`order_selection::penalty`), the true
/// order is chosen.
#[test]
fn initial_states_do_not_keep_out_an_order_the_record_can_tell() {
    let o = run(692, "default");
    assert_at_floor(&o);
    assert_eq!(o.chosen, Some(o.order), "{o:#?}");
}

#[test]
#[ignore]
fn debug_one() {
    use hammerstein::Init;
    let seed: u64 = std::env::var("SEED").unwrap().parse().unwrap();
    let rec = random_record(seed, &Ranges::default());
    let data = IoData::siso(&rec.u, &rec.y).unwrap();
    let (train, valid) = data.split_validation(0.3).unwrap();
    println!("{rec:?}");
    let mut base = Hammerstein::udn(rec.effects)
        .order(Order::Fixed(rec.order))
        .refine(true);
    if let Ok(h) = std::env::var("HORIZON") {
        base = base.horizon(h.parse().unwrap());
    }
    let model = base.clone().fit(&train).unwrap();
    let pn: Vec<String> = model.parameters().iter().map(|p| p.0.clone()).collect();
    let given = truth_theta(&rec);
    println!("truth  {pn:?} {given:?} noise {}", rec.noise_var);
    {
        let m = truth_model(&rec, &model).expect("the true model");
        let ct = compare(&m, &train).unwrap();
        let cv = compare(&m, &valid).unwrap();
        println!(
            "truth model: train/noise {:.3} val/noise {:.3}",
            ct.metrics.mse / rec.noise_var,
            cv.metrics.mse / rec.noise_var
        );
    }
    for (name, s) in [
        ("default", base.clone()),
        ("given", base.clone().init(Init::Given(given.clone()))),
        (
            "given-no-refine",
            base.clone().init(Init::Given(given.clone())).refine(false),
        ),
        ("no-refine", base.clone().refine(false)),
        ("coarse", base.clone().init(Init::CoarseSearch)),
        ("horizon-20", base.clone().horizon(20)),
    ] {
        let m = s.fit(&train).unwrap();
        let c = compare(&m, &valid).unwrap();
        println!(
            "{name}: {:?} train {:.4e} val/noise {:.3} term {} iters {} refine {:?}",
            m.parameters(),
            m.report().train_mse / rec.noise_var,
            c.metrics.mse / rec.noise_var,
            m.report().termination,
            m.report().iterations.len(),
            m.report().refinement
        );
        let ctr = compare(&m, &train).unwrap();
        println!(
            "   compare(train)/noise {:.3}",
            ctr.metrics.mse / rec.noise_var
        );
        let cv = compare(&m, &valid).unwrap();
        let nv = cv.residual.len();
        let seg = |a: usize, b: usize| {
            cv.residual[a..b].iter().map(|r| r * r).sum::<f64>() / (b - a) as f64 / rec.noise_var
        };
        let mut idx: Vec<usize> = (0..nv).collect();
        idx.sort_by(|&a, &b| cv.residual[b].abs().total_cmp(&cv.residual[a].abs()));
        for &k in idx.iter().take(5) {
            println!(
                "   k {k} r/σ {:.2} u {:.5} vhat {:.5}",
                cv.residual[k] / rec.noise_var.sqrt(),
                cv.u[k],
                cv.v_hat[k]
            );
        }
        println!(
            "   val segments {:.2} {:.2} {:.2} {:.2}",
            seg(0, 20),
            seg(20, nv / 3),
            seg(nv / 3, 2 * nv / 3),
            seg(2 * nv / 3, nv)
        );
        println!(
            "   poles {:?} truth {:?}",
            m.linear().poles().unwrap(),
            rec.block.poles().unwrap()
        );
        for it in &m.report().iterations {
            println!(
                "   it mse/noise {:.3} {:?}",
                it.mse / rec.noise_var,
                it.params
            );
        }
    }
}

/// The record's true model (its block with the first Markov parameter moved into the gains, the
/// true θ and offset) as a model with `like`'s settings.
fn truth_model(
    rec: &RandomRecord,
    like: &hammerstein::HammersteinModel<f64>,
) -> Option<hammerstein::HammersteinModel<f64>> {
    let h1 = reference_markov(rec);
    let nl =
        hammerstein::regressors::Udn::<f64>::with_params(rec.effects, &truth_theta(rec)).ok()?;
    let mut g = rec.block.clone();
    for i in 0..g.order() {
        g.b[(i, 0)] /= h1;
    }
    g.d[(0, 0)] /= h1;
    let s = settings(rec, "true-order");
    hammerstein::HammersteinModel::from_parts(Box::new(nl), g, rec.offset, s, like.report().clone())
        .ok()
}

/// Evidence for the true order on the records whose order the default fit chose wrong:
/// λ = N·ln(MSE_chosen / MSE_true) on the training part (both fits' simulation errors with the
/// initial state estimated), the number a likelihood-ratio test or an information criterion
/// weighs against its penalty. `BATTERY_SEEDS`, `BATTERY_OFFSET` as for `battery`.
#[test]
#[ignore]
fn order_evidence() {
    let seeds = common::env_count("BATTERY_SEEDS", 200);
    let offset = common::env_count("BATTERY_OFFSET", 0);
    let rows: Vec<Option<String>> = (offset + 1..=offset + seeds)
        .into_par_iter()
        .map(|seed| {
            let rec = random_record(seed, &Ranges::default());
            let data = IoData::siso(&rec.u, &rec.y).ok()?;
            let (train, valid) = data.split_validation(0.3).ok()?;
            let m = settings(&rec, "default").fit(&train).ok()?;
            let chosen = m.report().order;
            if chosen == rec.order && std::env::var("EVIDENCE_ALL").is_err() {
                return None;
            }
            let t = settings(&rec, "true-order").fit(&train).ok()?;
            let mse = |m: &hammerstein::HammersteinModel<f64>, d: &IoData<f64>| {
                compare(m, d).map(|c| c.metrics.mse).unwrap_or(f64::NAN)
            };
            let nt = train.len() as f64;
            let lambda = nt * (mse(&m, &train) / mse(&t, &train)).ln();
            // the true model itself (its block and θ, initial conditions estimated as `compare`
            // does): the global fit at the true order is at least this good
            let truth = truth_model(&rec, &m).map_or(f64::NAN, |tm| mse(&tm, &train));
            let lambda_best = nt * (mse(&m, &train) / mse(&t, &train).min(truth)).ln();
            let table: Vec<String> = m
                .report()
                .order_selection
                .iter()
                .map(|c| {
                    format!(
                        "{}{}:{:.4}",
                        c.order,
                        if c.feedthrough { "d" } else { "" },
                        c.train_mse / rec.noise_var
                    )
                })
                .collect();
            Some(format!(
                "seed {seed} true {} chosen {chosen} {} {} N {} snr {:.0} lambda {:.1} best {:.1} \
                 train {:.4}/{:.4} truth {:.4} val {:.3}/{:.3} d {}/{} [{}]",
                rec.order,
                rec.excitation.name(),
                rec.poles.name(),
                train.len(),
                rec.snr_db,
                lambda,
                lambda_best,
                mse(&m, &train) / rec.noise_var,
                mse(&t, &train) / rec.noise_var,
                truth / rec.noise_var,
                mse(&m, &valid) / rec.noise_var,
                mse(&t, &valid) / rec.noise_var,
                m.has_feedthrough(),
                t.has_feedthrough(),
                table.join(" ")
            ))
        })
        .collect();
    for r in rows.into_iter().flatten() {
        println!("{r}");
    }
}
