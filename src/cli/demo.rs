//! `hammerstein demo`: the main job on built-in data. A record with a hidden actuator effect
//! (saturation + hysteresis, the paper's Example 1 system, smooth random input, 25 dB SNR, an
//! output offset) is fitted with a linear model, diagnosed, the named effect added, refitted, and so
//! on until the diagnosis finds nothing missing; then the HTML report is written.

use super::common::{effects_text, top_suggestion_text};
use crate::cli::Failure;
use hammerstein::diagnosis::{Diagnoser, FollowStop};
use hammerstein::fit::Hammerstein;
use hammerstein::regressors::{Effect, StaticNonlinearity, Udn};
use hammerstein::report::{Context, Step, Units, report_input, write_report};
use hammerstein::{IoData, StateSpace};
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `hammerstein demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Directory of the HTML report.
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// Seed of the input and the noise.
    #[arg(long, value_parser = super::common::parse_seed, allow_negative_numbers = true, default_value_t = 1)]
    pub seed: u64,
    /// Number of samples (the last third is validation data).
    #[arg(long, value_parser = super::common::parse_count, allow_negative_numbers = true, default_value_t = 3000)]
    pub samples: usize,
    /// Signal-to-noise ratio in dB, 10·log10(var(y_clean)/var(noise)).
    #[arg(long, allow_negative_numbers = true, default_value_t = 25.0)]
    pub snr: f64,
    /// Largest number of effects to add.
    #[arg(long, value_parser = super::common::parse_count, allow_negative_numbers = true, default_value_t = 5)]
    pub max_steps: usize,
}

/// The hidden system: the paper's Example 1 (SH nonlinearity p = 2, a = 0.5, z1 = 1.5, z2 = −1;
/// G(z) = z⁻¹(1 + 0.5z⁻¹)/(1 − 0.2z⁻¹ + 0.35z⁻²)) plus an output offset.
pub struct HiddenSystem {
    /// The true nonlinearity.
    pub nonlinearity: Udn<f64>,
    /// The true linear block.
    pub linear: StateSpace<f64>,
    /// Constant added to the output (a sensor offset).
    pub output_offset: f64,
}

impl HiddenSystem {
    /// The demo's system.
    pub fn example() -> Result<Self, Failure> {
        let nonlinearity = Udn::with_params(
            hammerstein::regressors::EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]),
            &[2.0, 0.5, 1.5, -1.0],
        )?;
        // controllable canonical form of (z + 0.5)/(z² − 0.2z + 0.35)
        let linear = StateSpace::from_rows(
            &[&[0.2, -0.35], &[1.0, 0.0]],
            &[&[1.0], &[0.0]],
            &[&[1.0, 0.5]],
            &[&[0.0]],
        )?;
        Ok(Self {
            nonlinearity,
            linear,
            output_offset: 0.5,
        })
    }
}

/// A generated record: input, noisy output, and the noise variance.
pub struct Record {
    /// Input u(k).
    pub u: Vec<f64>,
    /// Measured output y(k).
    pub y: Vec<f64>,
    /// Variance of the added noise (the best achievable validation MSE).
    pub noise_variance: f64,
}

/// Smooth random input (first-order low-pass filtered Gaussian noise, std 1.3) through the hidden
/// system, with white Gaussian output noise at `snr` dB; seeded.
pub fn generate(sys: &HiddenSystem, n: usize, snr: f64, seed: u64) -> Result<Record, Failure> {
    // +inf: no noise; NaN or -inf: no noise level at all
    if snr.is_nan() || snr == f64::NEG_INFINITY {
        return Err(format!(
            "--snr {snr}: the signal-to-noise ratio must be a number of dB (inf: no noise)"
        )
        .into());
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).map_err(|e| Failure::Message(e.to_string()))?;
    let pole = 0.7f64;
    let gain = 1.3 * (1.0 - pole * pole).sqrt();
    let mut u = Vec::with_capacity(n);
    let mut x = 0.0;
    for _ in 0..n + 100 {
        x = pole * x + gain * normal.sample(&mut rng);
        u.push(x);
    }
    let u = u.split_off(100);
    let v = sys.nonlinearity.eval(&u);
    let y_clean = sys.linear.simulate_siso(&v, None)?;
    let m = y_clean.iter().sum::<f64>() / n as f64;
    let var = y_clean.iter().map(|y| (y - m).powi(2)).sum::<f64>() / n as f64;
    let noise_variance = var / 10f64.powf(snr / 10.0);
    let sd = noise_variance.sqrt();
    let y = y_clean
        .iter()
        .map(|yc| yc + sys.output_offset + sd * normal.sample(&mut rng))
        .collect();
    Ok(Record {
        u,
        y,
        noise_variance,
    })
}

/// Title, data description and notes of the report of step `step`.
fn context(
    args: &Args,
    sys: &HiddenSystem,
    rec: &Record,
    steps: Vec<Step>,
    step: usize,
) -> Context {
    Context {
        title: format!("hammerstein demo, step {step}: finding the hidden actuator effect"),
        dataset: format!(
            "built-in simulation (paper's Example 1 system, smooth random input, seed {}, \
             SNR {} dB, output offset {})",
            args.seed, args.snr, sys.output_offset
        ),
        units: Units::default(),
        steps,
        noise_floor: Some(rec.noise_variance),
        notes: vec![format!(
            "Hidden system: saturation + hysteresis (p = 2, a = 0.5, z1 = 1.5, z2 = −1) followed \
             by G(z) = z⁻¹(1 + 0.5z⁻¹)/(1 − 0.2z⁻¹ + 0.35z⁻²), plus an output offset of {} that \
             the model estimates. Each step fitted the model, diagnosed it and added the effect \
             the diagnosis ranked first.",
            sys.output_offset
        )],
    }
}

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    let start = Instant::now();
    if args.samples < 600 {
        return Err(format!(
            "--samples {} is too short for a diagnosis (at least 600)",
            args.samples
        )
        .into());
    }
    super::paths::check_output_dir(&args.out, "--out", &[])?;
    let sys = HiddenSystem::example()?;
    let rec = generate(&sys, args.samples, args.snr, args.seed)?;
    let data = IoData::siso(&rec.u, &rec.y)?;
    let (train, val) = data.split_validation(1.0 / 3.0)?;
    outln!(
        "demo data: {} samples ({} training, {} validation), seed {}, SNR {} dB, \
         output offset {}; hidden actuator effect: revealed at the end",
        args.samples,
        train.len(),
        val.len(),
        args.seed,
        args.snr,
        sys.output_offset
    )?;
    outln!("noise floor (noise variance): {:.6}\n", rec.noise_variance)?;
    outln!(
        "{:<5} {:<28} {:>14} {:>8}  top suggestion",
        "step",
        "model effects",
        "val MSE",
        "fit %"
    )?;
    // the library's guided loop: fit, diagnose, apply the top suggestion, refit
    let diagnoser = Diagnoser::<f64>::new();
    let first = Hammerstein::<f64>::linear().seed(args.seed);
    let followed = diagnoser.follow(&first, &train, &val, args.max_steps)?;
    let mut steps: Vec<Step> = Vec::new();
    for (step, st) in followed.steps.iter().enumerate() {
        let d = &st.diagnosis;
        outln!(
            "{:<5} {:<28} {:>14.6} {:>8.2}  {}",
            step,
            effects_text(&st.model),
            d.validation.metrics.mse,
            d.validation.metrics.fit_percent,
            top_suggestion_text(d)
        )?;
        steps.push(Step {
            label: if step == 0 {
                effects_text(&st.model)
            } else {
                st.change.clone()
            },
            validation_mse: d.validation.metrics.mse,
            fit_percent: d.validation.metrics.fit_percent,
        });
        // the report of this step, so the pictures before each added effect can be compared
        let input = report_input(
            &st.model,
            d,
            context(&args, &sys, &rec, steps.clone(), step),
        )?;
        write_report(&args.out.join(format!("step-{step}")), &input)?;
    }
    let stop_note = match &followed.stop {
        stop @ (FollowStop::CannotApply(_)
        | FollowStop::NothingHelps
        | FollowStop::NotConfirmed(_)
        | FollowStop::TimeBudget) => stop.to_string(),
        FollowStop::Adequate | FollowStop::MaxSteps => String::new(),
    };
    let last = followed
        .steps
        .last()
        .map(|s| (s.model.clone(), s.diagnosis.clone()));
    let (model, d) = last.ok_or("no model was fitted")?;
    outln!("\n{}", d.summary)?;
    if !stop_note.is_empty() {
        outln!("stopped: {stop_note}")?;
    }
    outln!(
        "validation MSE: linear {:.6} → final {:.6} (noise floor {:.6})",
        steps[0].validation_mse,
        d.validation.metrics.mse,
        rec.noise_variance
    )?;
    outln!("\nhidden system: saturation + hysteresis, p = 2, a = 0.5, z1 = 1.5, z2 = -1")?;
    let est: Vec<String> = model
        .parameters()
        .into_iter()
        .map(|(k, v)| format!("{k} = {v:.4}"))
        .collect();
    outln!(
        "estimated:     {} ({})",
        effects_text(&model),
        est.join(", ")
    )?;
    let n_steps = steps.len();
    let input = report_input(&model, &d, context(&args, &sys, &rec, steps, n_steps - 1))?;
    let path = write_report(&args.out, &input)?;
    outln!("\nreport: {}", path.display())?;
    outln!(
        "(the report of each step is in {}/step-K/index.html)",
        args.out.display()
    )?;
    outln!("(finished in {:.1} s)", start.elapsed().as_secs_f64())?;
    Ok(())
}
