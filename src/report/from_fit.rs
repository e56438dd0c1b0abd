//! Building a [`ReportInput`] from a fitted model and its diagnosis (the one place the report
//! knows the loop's and the diagnosis' types; the plots themselves only see plain data).

use super::input::{
    Correlation, DiagnosisRow, NonlinearityCurve, OrderChoice, OutputMapCurve, Parameter, Record,
    ReportInput, Step, TestRow, Units,
};
use crate::diagnosis::Diagnosis;
use crate::error::Result;
use crate::fit::HammersteinModel;
use crate::real::Real;
use crate::regressors::directions;

/// Largest lag of the correlation plots.
pub const MAX_LAG: usize = 25;
/// Confidence level of the correlation bands.
pub const LEVEL: f64 = 0.99;
/// Two-sided standard-normal quantile of [`LEVEL`].
const Z_99: f64 = 2.575_829_303_548_901;

/// What the caller knows beyond the model: names, units, the sequence of steps, the noise floor.
#[derive(Debug, Clone, Default)]
pub struct Context {
    /// Page title.
    pub title: String,
    /// Data-set name and source.
    pub dataset: String,
    /// Units and sampling time.
    pub units: Units,
    /// Validation error of each step so far (the last one is this model).
    pub steps: Vec<Step>,
    /// Noise variance, when known (simulated data).
    pub noise_floor: Option<f64>,
    /// Notes on data handling.
    pub notes: Vec<String>,
}

fn centred(x: &[f64]) -> Vec<f64> {
    let m = x.iter().sum::<f64>() / x.len().max(1) as f64;
    x.iter().map(|v| v - m).collect()
}

/// Normalised cross-correlation r_ab(τ) = Σ a(k+τ) b(k) / sqrt(Σa² Σb²) of centred series.
fn xcorr(a: &[f64], b: &[f64], tau: i64) -> f64 {
    let n = a.len().min(b.len()) as i64;
    let (sa, sb): (f64, f64) = (a.iter().map(|x| x * x).sum(), b.iter().map(|x| x * x).sum());
    let den = (sa * sb).sqrt();
    if den <= 0.0 {
        return 0.0;
    }
    let mut s = 0.0;
    for k in 0..n {
        let j = k + tau;
        if (0..n).contains(&j) {
            s += a[j as usize] * b[k as usize];
        }
    }
    s / den
}

/// Residual autocorrelation at lags 1..=`max_lag` with the ±z/√N band of a white sequence.
pub fn autocorrelation(e: &[f64], max_lag: usize) -> Correlation {
    let ec = centred(e);
    let lags: Vec<i64> = (1..=max_lag as i64).collect();
    Correlation {
        values: lags.iter().map(|&l| xcorr(&ec, &ec, l)).collect(),
        lags,
        bound: Z_99 / (e.len() as f64).sqrt(),
        level: LEVEL,
    }
}

/// Cross-correlation of the residual with the input, lags −`max_lag`..=`max_lag` (τ > 0: the
/// input leads), with the ±z/√N band valid when the residual is white and independent of u
/// (Ljung, System Identification, 2nd ed., §16.6).
pub fn cross_correlation(e: &[f64], u: &[f64], max_lag: usize) -> Correlation {
    let (ec, uc) = (centred(e), centred(u));
    let m = max_lag as i64;
    let lags: Vec<i64> = (-m..=m).collect();
    Correlation {
        values: lags.iter().map(|&l| xcorr(&ec, &uc, l)).collect(),
        lags,
        bound: Z_99 / (e.len() as f64).sqrt(),
        level: LEVEL,
    }
}

/// The two branches of a model's nonlinearity on a grid over [lo, hi]: the input sweeps down,
/// up, and down again, so a nonlinearity with memory (play operator) is on its branches.
fn branches<T: Real>(
    model: &HammersteinModel<T>,
    lo: f64,
    hi: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let m = 201;
    let grid: Vec<f64> = (0..m)
        .map(|i| lo + (hi - lo) * i as f64 / (m - 1) as f64)
        .collect();
    let mut sweep: Vec<T> = grid.iter().rev().map(|&x| T::lit(x)).collect();
    sweep.extend(grid.iter().map(|&x| T::lit(x)));
    sweep.extend(grid.iter().rev().map(|&x| T::lit(x)));
    let v: Vec<f64> = model
        .nonlinearity()
        .eval(&sweep)
        .iter()
        .map(|x| x.as_f64())
        .collect();
    let rising = v[m..2 * m].to_vec();
    let mut falling = v[2 * m..].to_vec();
    falling.reverse();
    (grid, rising, falling)
}

/// The residual referred to the input: w = G⁻¹e by the recursion N'(q⁻¹)w(k) = A(q⁻¹)e(k), where
/// G(z) = z⁻ʳN'(z⁻¹)/A(z⁻¹) (r = relative degree), then aligned so that entry j pairs with the input
/// u(j) that produced v(j + nk). `None` when the inverse is unstable (non-minimum-phase block) or
/// undefined.
fn referred_residual<T: Real>(
    model: &HammersteinModel<T>,
    e: &[f64],
) -> Option<(Vec<f64>, String)> {
    let tf = model.transfer_function().ok()?;
    let bmax = tf.numerator.iter().fold(0.0f64, |m, b| m.max(b.abs()));
    if bmax.is_nan() || bmax <= 0.0 {
        return None;
    }
    let r = tf.numerator.iter().position(|b| b.abs() > 1e-8 * bmax)?;
    let np = &tf.numerator[r..];
    let a = &tf.denominator;
    let n = e.len();
    let mut w = vec![0.0; n];
    for k in 0..n {
        let mut s = 0.0;
        for (i, ai) in a.iter().enumerate() {
            if k >= i {
                s += ai * e[k - i];
            }
        }
        for (j, nj) in np.iter().enumerate().skip(1) {
            if k >= j {
                s -= nj * w[k - j];
            }
        }
        w[k] = s / np[0];
    }
    // an unstable inverse grows: compare the first and the last quarter
    let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt();
    let q = (n / 4).max(1);
    let (first, last) = (rms(&w[..q]), rms(&w[n - q..]));
    let shift = model.delay() + r;
    if w.iter().any(|x| !x.is_finite()) || last > 10.0 * first.max(1e-300) && last > 1e3 * rms(e) {
        // non-minimum-phase block (wrong models often have one): no stable causal inverse; refer
        // through the static gain, shifted by the relative degree and the delay
        let g = static_gain(model)?;
        return Some((
            (0..n)
                .map(|j| e.get(j + shift).copied().unwrap_or(0.0) / g)
                .collect(),
            format!(
                "the residual shifted by {shift} sample(s) (delay + relative degree) and divided by \
                 the static gain G(1) = {g:.4}: a rough referral (the block has a zero outside the \
                 unit circle, so it cannot be inverted causally)"
            ),
        ));
    }
    // w(k) = Δv(k − r); Δv(m) belongs to u(m − nk): entry j = w(j + nk + r)
    Some((
        (0..n)
            .map(|j| w.get(j + shift).copied().unwrap_or(0.0))
            .collect(),
        "the residual filtered through the inverse of the linear block and aligned with the input \
         that caused it"
            .to_string(),
    ))
}

/// The output map's curve over the range of the linear block's output on the training record
/// (`None` when the record cannot be simulated).
fn output_map_curve<T: Real>(
    model: &HammersteinModel<T>,
    g: &dyn crate::regressors::OutputMap<T>,
    u: &[f64],
    y: &[f64],
) -> Option<OutputMapCurve> {
    let ut: Vec<T> = u.iter().map(|&x| T::lit(x)).collect();
    let yt: Vec<T> = y.iter().map(|&x| T::lit(x)).collect();
    let data = crate::data::IoData::siso(&ut, &yt).ok()?;
    let sim = model.simulate_on(&data).ok()?;
    let x: Vec<f64> = model
        .linear_output(&sim.v, &sim.x0)
        .iter()
        .map(|v| v.as_f64())
        .collect();
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let pad = 0.05 * (hi - lo).max(f64::MIN_POSITIVE);
    let grid: Vec<f64> = (0..=200)
        .map(|i| lo - pad + (hi - lo + 2.0 * pad) * i as f64 / 200.0)
        .collect();
    let gt: Vec<T> = grid.iter().map(|&v| T::lit(v)).collect();
    let c = model.output_offset();
    Some(OutputMapCurve {
        name: g.name(),
        y_grid: g.eval(&gt).iter().map(|v| v.as_f64() + c).collect(),
        x_grid: grid,
        data_x: x,
        data_y: y.to_vec(),
    })
}

/// Static gain G(1) of the linear block, when defined.
fn static_gain<T: Real>(model: &HammersteinModel<T>) -> Option<f64> {
    let tf = model.transfer_function().ok()?;
    let den: f64 = tf.denominator.iter().sum();
    let num: f64 = tf.numerator.iter().sum();
    let g = num / den;
    (den.abs() > 1e-9 && g.is_finite() && g != 0.0).then_some(g)
}

/// The report of a fitted model and its diagnosis (training and validation comparisons come from
/// the diagnosis).
pub fn report_input<T: Real>(
    model: &HammersteinModel<T>,
    diagnosis: &Diagnosis<T>,
    ctx: Context,
) -> Result<ReportInput> {
    let tr = &diagnosis.train;
    let va = &diagnosis.validation;
    let train = Record::new(tr.u.clone(), tr.y.clone(), tr.y_hat.clone());
    let validation = Record::new(va.u.clone(), va.y.clone(), va.y_hat.clone());
    let e = train.residual();

    let referred = referred_residual(model, &e);
    let nl = model.nonlinearity();
    let effects = nl.effects();
    let nonlinearity = {
        let (lo, hi) =
            tr.u.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
        let (grid, rising, falling) = branches(model, lo, hi);
        // pair v̂(k) = N(u(k − nk)) with the input that produced it
        let nk = model.delay().min(tr.u.len());
        let data_u: Vec<f64> = (nk..tr.u.len()).map(|k| tr.u[k - nk]).collect();
        let dir_all = directions(&tr.u);
        let data_direction: Vec<f64> = (nk..tr.u.len()).map(|k| dir_all[k - nk]).collect();
        let (data_v, data_note) = match &referred {
            Some((w, how)) => (
                (nk..tr.u.len()).map(|k| tr.v_hat[k] + w[k - nk]).collect(),
                format!(
                    "the model's v̂(k) plus the residual referred to the input ({how}). The spread \
                     is noise; a systematic offset from the curve is what the model misses."
                ),
            ),
            None => (
                (nk..tr.u.len()).map(|k| tr.v_hat[k]).collect(),
                "the model's v̂(k) along the training record.".to_string(),
            ),
        };
        NonlinearityCurve {
            name: format!(
                "{} ({})",
                nl.name(),
                if effects.is_empty() {
                    "linear gain".to_string()
                } else {
                    effects.join(", ")
                }
            ),
            u_grid: grid,
            v_rising: rising,
            v_falling: falling,
            data_u,
            data_v,
            data_direction,
            data_note,
        }
    };

    let output_map = model
        .output_map()
        .and_then(|g| output_map_curve(model, g, &tr.u, &tr.y));

    let rep = model.report();
    let order = (!rep.singular_values.is_empty()).then(|| OrderChoice {
        singular_values: rep.singular_values.clone(),
        chosen: model.linear().order().min(rep.singular_values.len()),
        criterion: rep
            .order_selection
            .iter()
            .map(|c| (c.order, c.feedthrough, c.criterion))
            .collect(),
    });

    let mut parameters: Vec<Parameter> = model
        .parameters()
        .into_iter()
        .map(|(name, value)| Parameter {
            note: match name.as_str() {
                "p" => "gain".into(),
                "a" => "hysteresis half-width (input units)".into(),
                "b" => "dead-zone half-width (input units)".into(),
                "z1" => "upper saturation threshold (input units)".into(),
                "z2" => "lower saturation threshold (input units)".into(),
                "e1" | "e2" => "preload step".into(),
                _ => String::new(),
            },
            name,
            value,
        })
        .collect();
    if let Some(g) = model.output_map() {
        for (name, value) in g.param_names().into_iter().zip(g.params()) {
            parameters.push(Parameter {
                name: format!("output {name}"),
                value: value.as_f64(),
                note: format!("output map {} (y = g(x) + offset)", g.name()),
            });
        }
    }
    parameters.push(Parameter {
        name: "order n".into(),
        value: model.linear().order() as f64,
        note: "linear block".into(),
    });
    parameters.push(Parameter {
        name: "delay nk".into(),
        value: model.delay() as f64,
        note: "samples".into(),
    });
    parameters.push(Parameter {
        name: "output offset".into(),
        value: model.output_offset(),
        note: "estimated constant added to the output".into(),
    });
    if let Ok(poles) = model.linear().poles() {
        for (i, (re, im)) in poles.iter().enumerate() {
            parameters.push(Parameter {
                name: format!("pole {}", i + 1),
                value: re.hypot(*im),
                note: format!(
                    "|z| of {re:.4} {} {:.4}i",
                    if *im < 0.0 { "−" } else { "+" },
                    im.abs()
                ),
            });
        }
    }

    let mut steps = ctx.steps;
    if steps.is_empty() {
        steps.push(Step {
            label: if effects.is_empty() {
                "linear".into()
            } else {
                effects.join(" + ")
            },
            validation_mse: va.metrics.mse,
            fit_percent: va.metrics.fit_percent,
        });
    }

    Ok(ReportInput {
        title: ctx.title,
        dataset: ctx.dataset,
        units: ctx.units,
        autocorrelation: Some(autocorrelation(&e, MAX_LAG.min(e.len() / 4).max(1))),
        cross_correlation: Some(cross_correlation(
            &e,
            &train.u,
            MAX_LAG.min(e.len() / 4).max(1),
        )),
        train,
        validation: Some(validation),
        nonlinearity: Some(nonlinearity),
        output_map,
        feedback: None,
        other_inputs: Vec::new(),
        order,
        steps,
        noise_floor: ctx.noise_floor,
        diagnosis_summary: diagnosis.summary.clone(),
        diagnosis: diagnosis
            .suggestions
            .iter()
            .map(|s| DiagnosisRow {
                effect: s.effect.to_string(),
                score: s.score,
                evidence: s.evidence.clone(),
                estimate: s.estimate.text(),
                validation_mse_after: s.validation_mse_after,
            })
            .collect(),
        tests: diagnosis
            .tests
            .iter()
            .map(|t| TestRow {
                name: t.name.to_string(),
                description: t.description.clone(),
                p_adjusted: t.p_adjusted,
                significant: t.significant,
            })
            .collect(),
        parameters,
        notes: ctx.notes,
        referred_residual: referred.map(|(w, _)| w),
    })
}
