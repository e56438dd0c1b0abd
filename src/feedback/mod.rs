//! A linear block with a static nonlinearity in feedback (a nonlinear LFR, or Lur'e system):
//! stiffness on the output (the Silverbox's Duffing oscillator), friction on the velocity
//! (EMPS), clearance (F-16). The model is in [`model`], the built-in bases of f in [`basis`]
//! (any [`StaticNonlinearity`](crate::regressors::StaticNonlinearity) plugs in), the fit:
//!
//! 1. the linear model by subspace identification (PO-MOESP, order by the singular-value gap
//!    unless fixed);
//! 2. the feedback coefficients by one linear least squares on the linear model's states with
//!    the measured feedback variable ([`init`](self::init): Van Mulders et al., Automatica 49,
//!    2013; Vanbeylen, IEEE TIM 62, 2013);
//! 3. the output-error Levenberg–Marquardt refinement of all parameters with exact
//!    sensitivities (`refine.rs`, `simulate.rs`), which refuses a step whose simulation
//!    diverges.
//!
//! An input nonlinearity before the loop (`input_side.rs`) and an output map after it
//! (`output_side.rs`) are each fitted nested in the model without them.
//!
//! Validation simulates from an initial state estimated on the validation record
//! ([`FeedbackModel::compare`]); a model whose simulation diverges there is an error
//! ([`Error::Diverged`]), never a silent result.

pub mod basis;
mod file;
mod init;
pub mod input_side;
mod linear_start;
mod model;
mod nested;
mod output_side;
mod refine;
mod simulate;
mod state;
mod uncertainty;

pub use basis::{FeedbackKind, feedback_basis, feedback_from_spec};
pub use file::{FEEDBACK_FILE_VERSION, FeedbackModelFile};
pub use model::FeedbackModel;
pub use refine::RefineReport;
pub use simulate::DIVERGED;
pub use uncertainty::FeedbackBand;

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::regressors::{OutputMap, StaticNonlinearity};
use crate::solvers::Faer;
use crate::subspace::{Moesp, Order, SubspaceOptions, identify};
use rayon::prelude::*;

/// What the feedback variable z is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FeedbackOn {
    /// The output without its feed-through and offset, C x (the linear block's output, before
    /// an output map): stiffness.
    Output,
    /// The output's first difference: friction on the velocity.
    Velocity,
    /// A combination z = F x of the states, F estimated by the fit (its scale such that z has
    /// the RMS of C x on the training record).
    State,
}

impl std::str::FromStr for FeedbackOn {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "output" => Ok(Self::Output),
            "velocity" => Ok(Self::Velocity),
            "state" => Ok(Self::State),
            _ => Err(Error::InvalidParameter(format!(
                "--feedback-on takes 'output', 'velocity' or 'state', got '{s}'"
            ))),
        }
    }
}

impl FeedbackOn {
    /// The command line's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Self::Output => "output",
            Self::Velocity => "velocity",
            Self::State => "state",
        }
    }
    /// What z is, in words ("output", "velocity", "state combination z = F x").
    pub fn variable(self) -> &'static str {
        match self {
            Self::Output => "output",
            Self::Velocity => "velocity",
            Self::State => "state combination z = F x",
        }
    }
}

/// How a feedback model is fitted.
#[derive(Debug, Clone)]
pub struct FeedbackSettings {
    /// The built-in basis (ignored when `basis` is set).
    pub kind: FeedbackKind,
    /// A user's basis instead of the built-in one.
    pub basis: Option<Box<dyn StaticNonlinearity<f64>>>,
    /// What z is.
    pub on: FeedbackOn,
    /// The linear block's order (`Auto`: the singular-value gap).
    pub order: Order,
    /// The subspace horizon.
    pub horizon: usize,
    /// Estimate a feed-through D (refused for `velocity`: the loop would be algebraic).
    pub with_d: bool,
    /// The refinement's iteration limit.
    pub max_iterations: usize,
    /// The refinement stops when a step taken with little damping (λ at or below its start)
    /// lowers N ln(MSE) (twice the negative log-likelihood of Gaussian errors, up to a
    /// constant; N the record's length) by less than this. The default 0.1 is a twentieth of
    /// one parameter's Akaike penalty: a smaller gain cannot change which model the order
    /// choice keeps.
    pub tolerance: f64,
    /// An input nonlinearity N before the loop (Hammerstein with feedback; an input-side
    /// basis such as the UDN's saturation or dead-zone, acting on the normalised input); the
    /// fit is nested in the loop without it ([`input_side`](self::input_side)).
    pub input: Option<Box<dyn StaticNonlinearity<f64>>>,
    /// An output map g after the loop (`fit --output-nonlinearity`'s family: polyK,
    /// saturation, pwl:K, acting on the normalised linear output); z is the linear output
    /// before it. The fit is nested in the model without it (`output_side.rs`).
    pub output: Option<Box<dyn OutputMap<f64>>>,
}

impl FeedbackSettings {
    /// Defaults for a built-in basis on z: order by the gap, horizon 10, no feed-through,
    /// 100 iterations, tolerance 0.1.
    pub fn new(kind: FeedbackKind, on: FeedbackOn) -> Self {
        Self {
            kind,
            basis: None,
            on,
            order: Order::Auto,
            horizon: 10,
            with_d: false,
            max_iterations: 100,
            tolerance: 0.1,
            input: None,
            output: None,
        }
    }
}

/// A fitted feedback model and how the fit went.
#[derive(Debug, Clone)]
pub struct FeedbackFit {
    /// The model.
    pub model: FeedbackModel,
    /// The linear model's training RMS error (record units), the start.
    pub linear_rms: f64,
    /// The training RMS error after the linear-in-parameters step (record units; `None` when
    /// that start diverged and the refinement began from a weakened loop).
    pub start_rms: Option<f64>,
    /// The training RMS error of the refined model (record units).
    pub rms: f64,
    /// The refinement's report.
    pub refine: RefineReport,
    /// Stated warnings (e.g. a start whose loop diverged).
    pub warnings: Vec<String>,
}

/// How a model simulates on a record.
#[derive(Debug, Clone, PartialEq)]
pub struct FeedbackComparison {
    /// The simulated output (record units).
    pub simulated: Vec<f64>,
    /// RMS of y − ŷ (record units).
    pub rms: f64,
    /// The fit 100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖) in per cent.
    pub fit_percent: f64,
    /// The initial state used.
    pub x0: Vec<f64>,
}

fn scale_of(v: &[f64]) -> f64 {
    let s = (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    if s > 0.0 && s.is_finite() { s } else { 1.0 }
}

fn siso(data: &IoData<f64>) -> Result<(Vec<f64>, Vec<f64>)> {
    if data.n_inputs() != 1 || data.n_outputs() != 1 {
        return Err(Error::InvalidParameter(format!(
            "a feedback model has one input and one output; the record has {} and {}",
            data.n_inputs(),
            data.n_outputs()
        )));
    }
    Ok((data.input(0), data.output(0)))
}

/// Fits a feedback model to a single-input single-output record. With the order left to the
/// fit (`Order::Auto` or `Order::Gap`), the singular-value gap's order n and n + 1 are both
/// fitted, and the order of the output-error linear model `fit --nonlinearity linear` returns
/// (by BIC) from that model; the candidate with the lower Akaike criterion N ln(MSE) + 2p among
/// those not worse on training than the linear model is kept: a loop's own dynamics (the
/// viscous friction's previous output, a stiffness that moves the resonance) can hide a pole
/// from the linear model's gap. The linear model and the gap's candidates are fitted in
/// parallel (rayon); the choice does not depend on the threads.
pub fn fit(settings: &FeedbackSettings, data: &IoData<f64>) -> Result<FeedbackFit> {
    if settings.output.is_some() {
        return output_side::fit(settings, data);
    }
    if settings.input.is_some() {
        return input_side::fit(settings, data);
    }
    if !matches!(settings.order, Order::Auto | Order::Gap) {
        return fit_fixed(settings, data, None);
    }
    let (u, y) = siso(data)?;
    let (su, sy) = (scale_of(&u), scale_of(&y));
    let us: Vec<f64> = u.iter().map(|v| v / su).collect();
    let ys: Vec<f64> = y.iter().map(|v| v / sy).collect();
    let scaled = IoData::siso(&us, &ys)?;
    let dec = crate::subspace::SubspaceMethod::decompose(
        &Moesp::new(settings.horizon),
        &Faer::default(),
        &[scaled.view()],
    )?;
    let max = crate::subspace::max_order(dec.horizon, 1);
    let n = crate::subspace::select_order(&dec.singular_values, &Order::Gap, max)?;
    let fit_at = |order: usize, lin: Option<&crate::fit::HammersteinModel<f64>>| {
        let mut s = settings.clone();
        s.order = Order::Fixed(order);
        fit_fixed(&s, data, lin)
    };
    let gap_orders: Vec<usize> = [n, n + 1].into_iter().filter(|&o| o <= max).collect();
    // the linear model (its order by BIC) and the gap's candidates, each from its own
    // output-error linear start, at once
    let (linear, gap_fits) = rayon::join(
        || linear_start::linear_fit(Order::Auto, settings.with_d, &us, &ys).ok(),
        || {
            gap_orders
                .par_iter()
                .map(|&o| (o, fit_at(o, None)))
                .collect::<Vec<_>>()
        },
    );
    let linear_mse = linear.as_ref().and_then(|l| {
        let yh = l.simulate_on(&scaled).ok()?.y_hat;
        Some(
            ys.iter()
                .zip(&yh)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                / ys.len() as f64,
        )
    });
    let worse_than_linear = |f: &FeedbackFit| {
        let mse = (f.rms / sy).powi(2);
        linear_mse.is_some_and(|l| mse > l * (1.0 + 1e-9))
    };
    let mut fits = gap_fits;
    if let Some(l) = &linear {
        let o = l.linear().order();
        match fits.iter().position(|c| c.0 == o) {
            // a gap candidate of the linear model's order that is worse than it on training
            // (its own linear start ended elsewhere) is refitted from the linear model
            Some(i) => {
                if fits[i].1.as_ref().is_ok_and(worse_than_linear) {
                    fits[i].1 = fit_at(o, Some(l));
                }
            }
            None => fits.push((o, fit_at(o, Some(l)))),
        }
    }
    let mut best: Option<(f64, FeedbackFit)> = None;
    let mut first_err = None;
    for (_, fitted) in fits {
        match fitted {
            Ok(f) => {
                if worse_than_linear(&f) {
                    continue;
                }
                let nn = data.len() as f64;
                let p = simulate::Layout::of(&f.model, true).len() as f64;
                let mse = (f.rms / sy).powi(2).max(1e-300);
                let aic = nn * mse.ln() + 2.0 * p;
                if best.as_ref().is_none_or(|b| aic < b.0) {
                    best = Some((aic, f));
                }
            }
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    match best {
        Some((_, f)) => Ok(f),
        None => Err(first_err.unwrap_or(Error::ZeroOrder)),
    }
}

/// The fit at a fixed order; `linear` is the output-error linear model of that order when the
/// caller has it (otherwise it is fitted here).
fn fit_fixed(
    settings: &FeedbackSettings,
    data: &IoData<f64>,
    linear: Option<&crate::fit::HammersteinModel<f64>>,
) -> Result<FeedbackFit> {
    if settings.on == FeedbackOn::Velocity && settings.with_d {
        return Err(Error::InvalidParameter(
            "feedback on the velocity with a feed-through D makes the loop algebraic: a force acting where the \
             input does would reach the velocity in the same sample; fit without the feed-through"
                .into(),
        ));
    }
    let (u, y) = siso(data)?;
    let (su, sy) = (scale_of(&u), scale_of(&y));
    let us: Vec<f64> = u.iter().map(|v| v / su).collect();
    let ys: Vec<f64> = y.iter().map(|v| v / sy).collect();
    let scaled = IoData::siso(&us, &ys)?;
    let opts = SubspaceOptions {
        order: settings.order.clone(),
        with_d: settings.with_d,
        estimate_x0: true,
        stable: true,
    };
    // a fixed order above the horizon's reach raises the horizon to it
    let horizon = match settings.order {
        Order::Fixed(n) => settings.horizon.max(n + 1),
        _ => settings.horizon,
    };
    let id = identify(
        &Moesp::new(horizon),
        &Faer::default(),
        &[scaled.view()],
        &opts,
    )?;
    let lin = id.model;
    let x0_lin = id.x0.first().cloned().unwrap_or_default();
    let ylin = lin.simulate_siso(&us, Some(&x0_lin))?;
    let rms_of = |yh: &[f64]| {
        (ys.iter().zip(yh).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / ys.len() as f64).sqrt() * sy
    };
    let linear_rms = rms_of(&ylin);
    // two starts: z measured (noisy, but with the loop's own shape), and z simulated by the
    // linear model (noise-free, the states of Van Mulders et al.); each refined, the better kept
    let z_meas = init::measured_z(&us, &ys, 0.0, settings.on);
    let ylin_free: Vec<f64> = ylin
        .iter()
        .zip(&us)
        .map(|(y, u)| y - lin.d[(0, 0)] * u)
        .collect();
    let z_sim = init::measured_z(&us, &ylin_free, 0.0, settings.on);
    // the basis made for the measured z (the Coulomb width and the hinges from its spread)
    let f = match &settings.basis {
        Some(b) => b.clone_box(),
        None => feedback_basis(settings.kind, &z_meas)?,
    };
    // the starts: the linear-in-parameters step on each z, each with its loop weakened until
    // it simulates, and the linear optimum of the same order with the loop open (E = 0: the
    // nested start, so that the fit is never worse on training than the linear model)
    let mut starts: Vec<(FeedbackModel, Option<f64>, Vec<String>)> = Vec::new();
    let mut first_err = None;
    // the feedback variables of the starts, with F for `state` (each its own basis there)
    let zs: Vec<(Vec<f64>, Option<Vec<f64>>)> = if settings.on == FeedbackOn::State {
        state::candidates(&lin, &us, &x0_lin)?
            .into_iter()
            .map(|(fz, z)| (z, Some(fz)))
            .collect()
    } else {
        vec![(z_meas.clone(), None), (z_sim, None)]
    };
    for (z, fz) in &zs {
        let fb = match fz {
            Some(_) => match state::basis_for(settings.basis.as_deref(), settings.kind, z) {
                Ok(b) => b,
                Err(e) => {
                    first_err.get_or_insert(e);
                    continue;
                }
            },
            None => f.clone_box(),
        };
        let mut model = match init::start(
            &lin,
            fb,
            settings.on,
            settings.with_d,
            &us,
            &ys,
            z,
            (su, sy),
        ) {
            Ok(m) => m,
            Err(e) => {
                first_err.get_or_insert(e);
                continue;
            }
        };
        if let Some(fz) = fz {
            model.fz = fz.clone();
        }
        let mut warnings = Vec::new();
        let x0 = model.x0.clone();
        let mut start_rms = None;
        // a start whose loop diverges at the record's amplitude: the loop weakened (E halved)
        // until it simulates
        let mut tries = 0;
        loop {
            match simulate::run(&model, &us, &x0, None) {
                Ok(yh) => {
                    if tries == 0 {
                        start_rms = Some(rms_of(&yh));
                    }
                    break;
                }
                Err(_) if tries < 30 => {
                    model.e.iter_mut().for_each(|e| *e *= 0.5);
                    tries += 1;
                }
                Err(_) => {
                    model.e.iter_mut().for_each(|e| *e = 0.0);
                    break;
                }
            }
        }
        if tries > 0 {
            warnings.push(format!(
                "a linear-in-parameters start diverges at the record's amplitude; the refinement started from its \
                 loop weakened {}×",
                1u64 << tries.min(60)
            ));
        }
        starts.push((model, start_rms, warnings));
    }
    if settings.on == FeedbackOn::State {
        state::keep_best(&mut starts);
    }
    // the nested start's shape (and F) from the best start
    let best_start = starts
        .iter()
        .min_by(|a, b| {
            a.1.unwrap_or(f64::INFINITY)
                .total_cmp(&b.1.unwrap_or(f64::INFINITY))
        })
        .map(|s| (s.0.f.clone_box(), s.0.fz.clone()));
    let Some((shape, shape_fz)) = best_start else {
        return Err(first_err.unwrap_or_else(|| Error::Identification("no feedback start".into())));
    };
    let mut linear_rms = linear_rms;
    let own;
    let linear = match linear {
        Some(l) => Some(l),
        None => {
            own = linear_start::linear_fit(settings.order.clone(), settings.with_d, &us, &ys).ok();
            own.as_ref()
        }
    };
    if let Some(l) = linear
        && let Ok(m) = linear_start::linear_start(l, settings.on, shape, (su, sy))
            .map(|m| FeedbackModel { fz: shape_fz, ..m })
        && let Ok(yh) = simulate::run(&m, &us, &m.x0, None)
    {
        linear_rms = rms_of(&yh);
        starts.push((m, Some(linear_rms), Vec::new()));
    }
    let mut best: Option<(
        FeedbackModel,
        Vec<f64>,
        RefineReport,
        Option<f64>,
        Vec<String>,
    )> = None;
    // a start refined from its own initial state (the tolerance counted in N ln(MSE))
    let refine_on = |model: &mut FeedbackModel, x0: &[f64], len: usize| {
        refine::refine(
            model,
            x0,
            &us[..len],
            &ys[..len],
            true,
            settings.max_iterations,
            settings.tolerance / len as f64,
        )
    };
    let refine_start = |model: &mut FeedbackModel| {
        let x0 = model.x0.clone();
        refine_on(model, &x0, us.len())
    };
    // the same start refined over prefixes of the record that grow fourfold from a sixteenth
    // to the whole, each stage from the last one's model and x0 (a stage whose model diverges
    // on the whole record is skipped)
    let refine_growing = |model: &mut FeedbackModel| {
        let mut x0 = model.x0.clone();
        let mut len = us.len() / 16;
        while len < us.len() && len >= 50 {
            let mut m2 = model.clone();
            if let Ok((x, _)) = refine_on(&mut m2, &x0, len)
                && simulate::run(&m2, &us, &x, None).is_ok()
            {
                *model = m2;
                x0 = x;
            }
            len *= 4;
        }
        refine_on(model, &x0, us.len())
    };
    // friction on the velocity: each start is refined twice, over the whole record and over
    // growing prefixes of it, the lower training error kept. A friction that sticks makes the
    // output-error cost of a long simulation rugged in the parameters (the model's stick and
    // slip episodes drift against the record's), while over a short prefix the cost is
    // smooth enough for the start to reach the basin of the record's own friction: the
    // shortened simulation horizon of Ribeiro, Tiels, Umenberger, Schön & Aguirre, "On the
    // smoothness of nonlinear system identification", Automatica 121, 2020, continued to the
    // whole record (the x0 estimate of `compare` continues the same way)
    let growing: &[bool] = if settings.on == FeedbackOn::Velocity {
        &[false, true]
    } else {
        &[false]
    };
    let runs: Vec<_> = starts
        .into_iter()
        .flat_map(|s| growing.iter().map(move |&g| (s.clone(), g)))
        .collect();
    // each start refined on its own thread; the best kept in the starts' order
    let refined: Vec<_> = runs
        .into_par_iter()
        .map(|((mut model, start_rms, warnings), g)| {
            let r = if g {
                refine_growing(&mut model)
            } else {
                refine_start(&mut model)
            };
            r.map(|(x0r, rep)| (model, x0r, rep, start_rms, warnings))
        })
        .collect();
    for r in refined {
        match r {
            Ok(r) => {
                if best.as_ref().is_none_or(|b| r.2.mse_end < b.2.mse_end) {
                    best = Some(r);
                }
            }
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    let Some((mut model, x0r, mut rep, start_rms, warnings)) = best else {
        return Err(first_err.unwrap_or_else(|| Error::Identification("no feedback start".into())));
    };
    model.x0 = x0r;
    if settings.on == FeedbackOn::State {
        state::normalise_scale(&mut model, &us)?;
    }
    // friction on the velocity: a second linear-in-parameters start on the refined model's
    // own block (A, C) and its simulated, noise-free z, refined and kept when lower on
    // training. The first starts take A from the linear model, which folds the friction into
    // its poles' damping, and z from the noisy output, whose noise on the velocity is often
    // wider than the sign's width; the refined model supplies both (the estimated states of
    // Van Mulders et al., Automatica 49, 2013, taken from the nonlinear model)
    if settings.on == FeedbackOn::Velocity
        && let Ok(yh) = simulate::run(&model, &us, &model.x0, None)
        && let Ok(ss) = model.linear()
    {
        let free: Vec<f64> = yh.iter().zip(&us).map(|(y, u)| y - model.d * u).collect();
        let z2 = init::measured_z(&us, &free, 0.0, settings.on);
        if let Ok(m2) = init::start(
            &ss,
            f.clone_box(),
            settings.on,
            settings.with_d,
            &us,
            &ys,
            &z2,
            (su, sy),
        ) {
            // a start whose simulation diverges is refused by the refinement itself; refined
            // over the whole record and over growing prefixes, as the first starts are
            let tried: Vec<_> = [false, true]
                .par_iter()
                .map(|&g| {
                    let mut m = m2.clone();
                    let r = if g {
                        refine_growing(&mut m)
                    } else {
                        refine_start(&mut m)
                    };
                    r.map(|(x0r, rep)| (m, x0r, rep))
                })
                .collect();
            for (m, x0r2, rep2) in tried.into_iter().flatten() {
                if rep2.mse_end < rep.mse_end {
                    model = FeedbackModel { x0: x0r2, ..m };
                    rep = rep2;
                }
            }
        }
    }
    // the visited z range of the refined model
    let zs = z_visited(&model, &us)?;
    model.z_range = zs;
    model.normalise_e()?;
    let yh = simulate::run(&model, &us, &model.x0, None)?;
    let rms = rms_of(&yh);
    Ok(FeedbackFit {
        model,
        linear_rms,
        start_rms,
        rms,
        refine: rep,
        warnings,
    })
}

/// The range of z the model visits on the normalised input.
fn z_visited(m: &FeedbackModel, us: &[f64]) -> Result<(f64, f64)> {
    let mut fx = Vec::new();
    let y = simulate::run_z(m, us, &m.x0, None, Some(&mut fx))?;
    Ok(range(&z_along(m, &y, us, fx)))
}

/// The feedback variable z along a simulation `y` of `m` on the normalised input `us`: the
/// output without its feed-through and offset, y − D u − y₀ (`output`), its difference
/// (`velocity`), or F x as [`simulate::run_z`] recorded it in `fx` (`state`, and any model
/// with an output map or an input nonlinearity, whose y does not give C x by subtraction;
/// for `velocity` its first value, which depends on the initial state's C x(−1), is left out).
pub(crate) fn z_along(m: &FeedbackModel, y: &[f64], us: &[f64], fx: Vec<f64>) -> Vec<f64> {
    if m.output.is_some() || m.input.is_some() {
        return match m.on {
            FeedbackOn::Velocity => fx.into_iter().skip(1).collect(),
            _ => fx,
        };
    }
    let v = || -> Vec<f64> {
        y.iter()
            .zip(us)
            .map(|(y, u)| y - m.d * u - m.y_offset)
            .collect()
    };
    match m.on {
        FeedbackOn::Output => v(),
        FeedbackOn::Velocity => {
            let v = v();
            (1..v.len()).map(|k| v[k] - v[k - 1]).collect()
        }
        FeedbackOn::State => fx,
    }
}

/// The smallest and largest value of `z` (∞ and −∞ when it is empty).
pub(crate) fn range(z: &[f64]) -> (f64, f64) {
    z.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        })
}

impl FeedbackModel {
    /// Simulates the model on a record from an initial state estimated on that record (a
    /// Levenberg–Marquardt fit of x₀ alone, from the zero state and from the training record's
    /// initial state, each also continued over growing prefixes of the record, the best kept:
    /// `refine::estimate_x0`), as `compare` does for Hammerstein models. Errors with
    /// [`Error::Diverged`] (said in the user's terms) when the model's simulation blows up on
    /// the record.
    pub fn compare(&self, data: &IoData<f64>) -> Result<FeedbackComparison> {
        let (u, y) = siso(data)?;
        let us: Vec<f64> = u.iter().map(|v| v / self.u_scale).collect();
        let ys: Vec<f64> = y.iter().map(|v| v / self.y_scale).collect();
        let explain = |e: Error| match e {
            Error::Diverged { index, .. } => Error::Identification(format!(
                "the feedback model's simulation diverges on this record at sample {index}: the loop is unstable at \
                 the record's amplitude (the model is not valid there)"
            )),
            e => e,
        };
        let zero = vec![0.0; self.state_len()];
        let best = refine::estimate_x0(self, &[zero, self.x0.clone()], &us, &ys);
        let x0 = match best {
            Some((_, x0)) => x0,
            None => {
                // both starts diverge: say where
                simulate::run(self, &us, &vec![0.0; self.state_len()], None).map_err(explain)?;
                vec![0.0; self.state_len()]
            }
        };
        let yh = simulate::run(self, &us, &x0, None).map_err(explain)?;
        let simulated: Vec<f64> = yh.iter().map(|v| v * self.y_scale).collect();
        let n = y.len() as f64;
        let sse = y
            .iter()
            .zip(&simulated)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>();
        let mean = y.iter().sum::<f64>() / n;
        let sst = y.iter().map(|a| (a - mean).powi(2)).sum::<f64>();
        Ok(FeedbackComparison {
            rms: (sse / n).sqrt(),
            fit_percent: 100.0 * (1.0 - (sse / sst.max(1e-300)).sqrt()),
            simulated,
            x0,
        })
    }
}
