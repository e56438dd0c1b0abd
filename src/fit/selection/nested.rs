//! A fit that starts from a fitted model: the diagnosis' nested refits.
//!
//! Adding an effect to a model at its null value (a hysteresis or dead-zone half-width 0, a
//! preload 0) leaves the model's output unchanged, so the extended model's optimum is at least as
//! good as the model it extends. A fit from the default start does not know that: on real records
//! it can end in a worse local optimum (MR damper ensaio01, saturation + preload at order 7:
//! adding hysteresis from the default start raised the training MSE from 37.9 to 60.1), and the
//! diagnosis would then reject an effect only because the start led elsewhere. This start keeps
//! the model's poles (A, C), takes the extended θ, re-estimates B, D, x0 and the offset by least
//! squares (step 6 of the paper's loop, `Problem::evaluate`) and runs the output-error refinement
//! (`refine.rs`) from there; no loop iterations. The record is not normalised (the model is in
//! the record's units already; the refinement scales its own columns).

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::fit_report::FitReport;
use crate::fit::fitted::model::{HammersteinModel, check_siso};
use crate::fit::iteration::initial_direction::try_other_direction;
use crate::fit::iteration::problem::{Problem, Workspace, normalise_iterate, to_statespace};
use crate::fit::refinement::refine;
use crate::fit::selection::order_selection::{simulated_mse, training_mse};
use crate::fit::settings::Hammerstein;
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use faer::{Mat, MatRef};

/// (A, C) of order `n` ≥ A's: the extra states a chain of unit delays of the block's input
/// (poles at 0) seen by the output through its first state, A = [[A, 0], [0, J]], C = [C, e₁ᵀ]
/// with J the shift matrix; with their B entries 0 the output is the original block's, so the
/// least squares for B starts a nested search (extra FIR taps on the nonlinearity's output).
fn augmented<T: Real>(a: MatRef<'_, T>, c: MatRef<'_, T>, n: usize) -> (Mat<T>, Mat<T>) {
    let n0 = a.nrows();
    let aa = Mat::from_fn(n, n, |i, j| {
        if i < n0 && j < n0 {
            a[(i, j)]
        } else if i >= n0 && j >= n0 && j + 1 == i {
            T::one()
        } else {
            T::zero()
        }
    });
    let cc = Mat::from_fn(c.nrows(), n, |i, j| {
        if j < n0 {
            c[(i, j)]
        } else if j == n0 {
            T::one()
        } else {
            T::zero()
        }
    });
    (aa, cc)
}

/// Fits `settings` to `data` from `base`: its linear block's (A, C), augmented with poles at 0
/// up to the settings' fixed order, with the nonlinearity parameters `theta` (in the order of the
/// settings' nonlinearity), then the refinement. A Hammerstein–Wiener `base` at the same or a
/// higher order is also refitted from its own point, map included (`kept_start`), and the
/// start that ends at the lower training MSE is kept — or the kept start itself, when neither
/// ends below it ([`no_worse_than_start`]): the kept start cannot end above `base`,
/// but it can stay in `base`'s basin where the two-stage start (the Hammerstein part refitted,
/// the map initialised on top) finds a lower optimum (cascaded tanks, the saturation candidate
/// on the order-2 model with a cubic output map: training MSE 0.1792 with the kept start alone,
/// 0.1773 with both; `docs/case-studies.md`). Local optima of a nonconvex fit are met by several
/// starts, the best kept (multi-start, as the search for the output-error minimum usually is).
pub(crate) fn fit_nested<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    base: &HammersteinModel<T>,
    theta: &[f64],
) -> Result<HammersteinModel<T>> {
    let order = match settings.options.order {
        crate::subspace::Order::Fixed(n) => n,
        _ => base.linear().order(),
    };
    settings.validate()?;
    check_siso(data)?;
    let nl = nonlinearity_at(settings, theta, base, data)?;
    let kept = if order >= base.linear().order() {
        kept_start(settings, base, nl.as_ref(), order)
    } else {
        None
    };
    let augmented = fit_augmented(settings, data, base, nl.clone_box(), order);
    let best = match kept.as_ref().filter(|start| start.output_map().is_some()) {
        None => augmented,
        // Hammerstein–Wiener: the joint refinement from the base's own point, map included
        Some(start) => better_fit(
            crate::fit::refinement::output_fit::refit_with_map(settings, data, start.clone()).map(
                |mut m| {
                    crate::fit::uncertainty::attach(&mut m, data);
                    m
                },
            ),
            augmented,
        ),
    };
    // the start is a candidate when it meets the settings' constraint (a stable block when
    // asked: an unstable base's block is pulled inside by the refits, not kept)
    let admissible = |m: &HammersteinModel<T>| {
        !settings.options.stable || m.linear().spectral_radius().is_ok_and(|r| r < 1.0)
    };
    let best = match kept {
        Some(start) if admissible(&start) => no_worse_than_start(best, start, data),
        _ => best,
    };
    // the report says the horizon stands raised when these settings raised it (a refit at a
    // model's structure), not because the base's report did
    best.map(|mut m| {
        m.report.horizon_raised_from = m.settings.raised_claim(m.linear.order());
        m
    })
}

/// The fit with the lower training MSE of the kept-map start and the augmented one (the kept
/// one on a tie), whichever succeeded; the kept one's error when both failed.
fn better_fit<T: Real>(
    kept: Result<HammersteinModel<T>>,
    augmented: Result<HammersteinModel<T>>,
) -> Result<HammersteinModel<T>> {
    match (kept, augmented) {
        (Ok(k), Ok(a)) => Ok(if a.report.train_mse < k.report.train_mse {
            a
        } else {
            k
        }),
        (Ok(m), Err(_)) | (Err(_), Ok(m)) => Ok(m),
        (Err(e), Err(_)) => Err(e),
    }
}

/// `fit`, or the start it came from when that trains lower (its simulation on `data`, x0 and
/// the nonlinearity's memory before the record estimated, as [`training_mse`] judges `fit`),
/// with its standard errors attached: a nested fit never returns above its start. The
/// refinements are local searches in their own parametrisation (the block as a transfer
/// function, the free response by least squares, the nonlinearity from its default memory) and
/// keep a result by their own cost, not by the start's simulation; this makes the guarantee
/// hold by construction.
fn no_worse_than_start<T: Real>(
    fit: Result<HammersteinModel<T>>,
    mut start: HammersteinModel<T>,
    data: &IoData<T>,
) -> Result<HammersteinModel<T>> {
    // its report's MSE is `base`'s, on the record `base` was fitted on (a screened fit's whole
    // record, not the window a candidate is refitted on): the simulation alone judges it
    let from_start = simulated_mse(&start, data).unwrap_or(f64::INFINITY);
    match fit {
        Ok(m) if training_mse(&m, data) <= from_start => Ok(m),
        Ok(_) if from_start.is_finite() => {
            start.report.train_mse = from_start;
            start.report.refinement = None;
            crate::fit::uncertainty::attach(&mut start, data);
            Ok(start)
        }
        other => other,
    }
}

/// The nested fit from `base`'s (A, C) augmented to `order` (poles at 0), the nonlinearity `nl`
/// (the start's, [`nonlinearity_at`]): B, D, x0 and the offset by least squares, the refinement, and the settings' output
/// map fitted on top (as `fit` does).
fn fit_augmented<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    base: &HammersteinModel<T>,
    mut nl: Box<dyn StaticNonlinearity<T>>,
    order: usize,
) -> Result<HammersteinModel<T>> {
    let la = settings.linalg_backend()?;
    let method = settings.subspace_at(settings.options.horizon)?;
    let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data);
    let lin = base.linear();
    let (a, c) = augmented(lin.a.as_ref(), lin.c.as_ref(), order.max(lin.order()));
    let mut ws = Workspace::default();
    let mut start = problem.evaluate(&mut ws, nl.as_ref(), a.as_ref(), c.as_ref())?;
    // the initial direction estimated for this start as the loop does (a nuisance parameter,
    // like x0): the refinement then minimises the criterion `compare` judges the fit by, the
    // better of the two starts (`initial_direction.rs`)
    try_other_direction(&problem, &mut ws, nl.as_mut(), &mut start);
    if !start.mse.is_finite() {
        return Err(Error::Identification(
            "the nested start does not simulate to a finite output".into(),
        ));
    }
    let mut report = nested_report(base);
    report.order = a.nrows();
    let mut it = start.clone();
    if settings.options.refine {
        let (refined, mut rep) = refine::refine(&problem, nl.as_ref(), &start)?;
        if let Some(rf) = refined.filter(|rf| rf.mse < start.mse) {
            rep.mse_before = start.mse;
            rep.mse_after = rf.mse;
            rep.accepted = true;
            // the jumps centred where the record leaves them most likely, unless that ends above
            // the model this fit extends (its start): a nested fit never trains worse than it
            let centred = refine::centre_jumps(&problem, nl.as_ref(), rf.clone());
            it = if centred.mse <= start.mse {
                centred
            } else {
                rf
            };
        }
        report.refinement = Some(rep);
    }
    // an unstable base's block pulled inside when the settings ask for a stable one
    let (mut it, stabilised) =
        crate::fit::refinement::stability::stabilised_iterate(&problem, nl.as_ref(), it)?;
    report.stabilised = stabilised;
    nl.set_params(&it.theta)?;
    normalise_iterate(&problem, nl.as_mut(), &mut it);
    report.train_mse = it.mse;
    let mut linear = to_statespace(&it)?;
    linear.ts = data.sample_time();
    let mut model = HammersteinModel {
        nl,
        linear,
        offset: it.offset,
        x0: it.x0.clone(),
        settings: settings.clone(),
        report,
        output_map: None,
    };
    // Hammerstein–Wiener: the settings' output map on top, as `fit` does
    if let Some(map) = &settings.output_map {
        model = crate::fit::refinement::output_fit::fit_output_map(
            settings,
            data,
            model,
            map.as_ref(),
        )?;
    }
    crate::fit::uncertainty::attach(&mut model, data);
    Ok(model)
}

/// `base` with the start's nonlinearity `nl` ([`nonlinearity_at`]) in place of its own, when
/// `base` and the settings carry the same output map (none, or one of the same kind): its
/// block, initial state, offset and map kept. A Hammerstein–Wiener fit is refined jointly from
/// it; without it, the Hammerstein part would be refitted without the map and the map
/// initialised again on top, which does not start from the base (the MR damper's preload
/// candidate ended 132 % above the model it extends, `docs/case-studies.md`). At an `order`
/// above `base`'s the block is augmented as `augmented` does, with the new states' B and
/// initial values 0: the start's output is still `base`'s, so a higher order (the dynamics
/// candidate) cannot end above it either (MR damper ensaio04: from the two-stage start alone,
/// the order-10 refit of an order-9 hysteresis + saturation model with a cubic map ended 3.4 %
/// above it; `docs/case-studies.md`). Every nested fit is compared with it
/// ([`no_worse_than_start`]).
fn kept_start<T: Real>(
    settings: &Hammerstein<T>,
    base: &HammersteinModel<T>,
    nl: &dyn StaticNonlinearity<T>,
    order: usize,
) -> Option<HammersteinModel<T>> {
    match (&settings.output_map, base.output_map()) {
        (None, None) => {}
        (Some(want), Some(have))
            if want.name() == have.name() && want.params().len() == have.params().len() => {}
        _ => return None,
    }
    let lin = base.linear();
    let n0 = lin.order();
    let mut linear = lin.clone();
    let mut x0 = base.x0.clone();
    if order > n0 {
        let (a, c) = augmented(lin.a.as_ref(), lin.c.as_ref(), order);
        let b = &lin.b;
        linear.b = Mat::from_fn(
            order,
            b.ncols(),
            |i, j| {
                if i < n0 { b[(i, j)] } else { T::zero() }
            },
        );
        linear.a = a;
        linear.c = c;
        x0.resize(order, T::zero());
    }
    Some(HammersteinModel {
        nl: nl.clone_box(),
        linear,
        offset: base.offset,
        x0,
        settings: settings.clone(),
        report: nested_report(base),
        output_map: base.output_map().map(|g| g.clone_box()),
    })
}

/// The settings' nonlinearity configured on `data` as a fit configures it, with the parameters
/// `theta`, at `base`'s initial direction (the hysteresis' memory before the record, which
/// `theta` does not carry). Built once per nested fit; both starts take a copy.
fn nonlinearity_at<T: Real>(
    settings: &Hammerstein<T>,
    theta: &[f64],
    base: &HammersteinModel<T>,
    data: &IoData<T>,
) -> Result<Box<dyn StaticNonlinearity<T>>> {
    let mut nl = settings.build_nonlinearity()?;
    // configured on the record as the fit configures it (a Prandtl–Ishlinskii grid is fixed
    // from the input the loop sees), so that θ means what it meant in `base`; then θ itself
    let u = crate::fit::numerics::linear_ls::delayed(data.input_slice(0), settings.options.delay);
    nl.initialize(&u);
    // where `base` fixed the same configuration on another part of the record (a fit screened
    // on a window), its configuration
    nl.carry_configuration(&base.nonlinearity().spec());
    let th: Vec<T> = theta.iter().map(|&t| T::lit(t)).collect();
    nl.set_params(&th)?;
    nl.set_initial_falling(base.nonlinearity().initial_falling());
    Ok(nl)
}

/// The report a fit from `base` starts with: `base`'s, without its loop's iterations and its
/// order-selection table (the nested fit has neither).
fn nested_report<T: Real>(base: &HammersteinModel<T>) -> FitReport {
    let mut report = base.report().clone();
    report.iterations.clear();
    report.order_selection.clear();
    report.stabilised = None;
    report.departs_from_rest = None;
    report
}

impl<T: Real> Hammerstein<T> {
    /// These settings at `model`'s structure: its order and feed-through kept, and the horizon
    /// raised just enough for that order when the settings' one is too short for it (an
    /// automatically chosen order may exceed what the settings' horizon admits: the order
    /// selection raised the horizon for it). A horizon that admits the order is kept as it is,
    /// so that a refit starts as the model's own fit did.
    pub fn at_structure_of(self, model: &HammersteinModel<T>) -> Self {
        let n = model.linear().order();
        let mut h = self.options.horizon;
        while crate::subspace::max_order(h, 1) < n {
            h += 1;
        }
        self.order(crate::subspace::Order::Fixed(n))
            .raise_horizon(h)
            .with_d(model.has_feedthrough())
    }

    /// Fits from a fitted model: its poles (with poles at 0 added when the settings' fixed order is
    /// higher) and the nonlinearity parameters `theta`, then the refinement — extends `base` by
    /// an effect (at its null value in `theta`) or by states without leaving its optimum.
    pub fn fit_from(
        &self,
        data: &IoData<T>,
        base: &HammersteinModel<T>,
        theta: &[f64],
    ) -> Result<HammersteinModel<T>> {
        if let crate::subspace::Order::Fixed(n) = self.options.order
            && n < base.linear().order()
        {
            return Err(Error::InvalidParameter(format!(
                "fit_from extends the base model (order {}); the settings ask for order {n}",
                base.linear().order()
            )));
        }
        fit_nested(self, data, base, theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regressors::{Effect, EffectSet, OutputMap, PolynomialMap};
    use crate::subspace::Order;

    /// A Hammerstein–Wiener record: a saturation, a second-order block, a cubic output map.
    fn record() -> IoData<f64> {
        let n = 800;
        let mut s = 12345u64;
        let u: Vec<f64> = (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
            })
            .collect();
        let (mut x1, mut x2) = (0.0, 0.0);
        let y: Vec<f64> = u
            .iter()
            .map(|&uk| {
                let v = uk.clamp(-1.2, 1.0);
                let x = x1;
                (x1, x2) = (1.2 * x1 - 0.5 * x2 + v, x1);
                x + 0.05 * x * x * x
            })
            .collect();
        IoData::siso(&u, &y).unwrap()
    }

    #[test]
    fn a_kept_map_start_at_a_higher_order_reproduces_the_model() {
        let data = record();
        let map =
            || Some(Box::new(PolynomialMap::<f64>::new(3).unwrap()) as Box<dyn OutputMap<f64>>);
        let settings = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation]))
            .order(Order::Fixed(2))
            .output_nonlinearity(map());
        let base = settings.fit(&data).unwrap();
        assert!(base.output_map().is_some());
        let theta: Vec<f64> = base
            .nonlinearity()
            .params()
            .iter()
            .map(|t| t.as_f64())
            .collect();
        let higher = settings.clone().order(Order::Fixed(4));
        let nl = nonlinearity_at(&higher, &theta, &base, &data).unwrap();
        let start = kept_start(&higher, &base, nl.as_ref(), 4).expect("a start with the map kept");
        assert_eq!(start.linear().order(), 4);
        assert_eq!(&start.x0[..2], &base.x0[..]);
        assert!(start.x0[2..].iter().all(|&x| x == 0.0));
        let (y0, y1) = (
            base.simulate(data.input_slice(0)).unwrap(),
            start.simulate(data.input_slice(0)).unwrap(),
        );
        let scale = y0.iter().fold(0.0f64, |m, y| m.max(y.abs()));
        for (a, b) in y0.iter().zip(&y1) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} against {b}");
        }
    }

    #[test]
    fn a_nested_fit_never_returns_above_its_start() {
        let data = record();
        let settings =
            Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation])).order(Order::Fixed(2));
        let start = settings.fit(&data).unwrap();
        // a refinement that ended elsewhere: the block's gain off by 10 %
        let mut worse = start.clone();
        let b = worse.linear.b.clone();
        worse.linear.b = Mat::from_fn(b.nrows(), b.ncols(), |i, j| 1.1 * b[(i, j)]);
        let (m_start, m_worse) = (training_mse(&start, &data), training_mse(&worse, &data));
        assert!(m_worse > m_start, "{m_worse} against {m_start}");
        let kept = no_worse_than_start(Ok(worse.clone()), start.clone(), &data).unwrap();
        assert_eq!(training_mse(&kept, &data), m_start);
        assert_eq!(kept.report().train_mse, m_start);
        assert!(
            !kept.report().standard_errors.is_empty(),
            "its errors are attached"
        );
        // a fit that ends lower is returned as it is, whatever the start's report says (a
        // report from the record the base was fitted on, not this one)
        worse.report.train_mse = 0.0;
        let back = no_worse_than_start(Ok(start.clone()), worse, &data).unwrap();
        assert_eq!(back.linear().b, start.linear().b);
    }
}
