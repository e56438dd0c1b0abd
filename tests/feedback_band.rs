//! The feedback fit's nesting in the linear model and f(z)'s uncertainty band: on a record
//! with a cubic stiffness the band covers the true f over the visited range; on any record the
//! fit is never worse on training than the output-error linear model of its order; the report
//! draws f(z) with its band.

use hammerstein::IoData;
use hammerstein::feedback::{self, FeedbackKind, FeedbackOn, FeedbackSettings};
use hammerstein::report::{FeedbackCurve, Record, ReportInput, write_report};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// x+ = A x + B (u + w), y = x₁ (companion form of a resonant pair), w = f(z), z = y or its
/// difference.
fn truth(u: &[f64], f: impl Fn(f64) -> f64, velocity: bool) -> Vec<f64> {
    let (r, th) = (0.95f64, 0.3f64);
    let (a1, a2) = (2.0 * r * th.cos(), -r * r);
    let (mut x1, mut x2, mut prev) = (0.0f64, 0.0f64, 0.0f64);
    u.iter()
        .map(|&uk| {
            let cx = x1;
            let w = f(if velocity { cx - prev } else { cx });
            prev = cx;
            let n1 = a1 * x1 + x2 + uk + w;
            x2 = a2 * x1 + 0.5 * (uk + w);
            x1 = n1;
            cx
        })
        .collect()
}

fn record(seed: u64, n: usize, f: impl Fn(f64) -> f64, velocity: bool, sd: f64) -> IoData<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut s = 0.0;
    let u: Vec<f64> = (0..n)
        .map(|_| {
            s = 0.7 * s + rng.random_range(-1.0..1.0);
            0.04 * s
        })
        .collect();
    let y: Vec<f64> = truth(&u, f, velocity)
        .into_iter()
        .map(|v| v + sd * ((0..12).map(|_| rng.random_range(0.0..1.0)).sum::<f64>() - 6.0))
        .collect();
    IoData::siso(&u, &y).unwrap()
}

#[test]
fn the_band_covers_the_true_stiffness() {
    let data = record(7, 3000, |z| -0.02 * z.powi(3), false, 0.01);
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    s.order = hammerstein::Order::Fixed(2);
    let fit = feedback::fit(&s, &data).unwrap();
    let band = fit.model.nonlinearity_band(&data, 50).unwrap();
    assert_eq!(band.z.len(), 50);
    assert!(band.se.iter().all(|v| v.is_finite() && *v >= 0.0));
    assert!(band.se.iter().any(|v| *v > 0.0), "a band of zero width");
    let inside = band
        .z
        .iter()
        .zip(band.w.iter().zip(&band.se))
        .filter(|(z, (w, se))| (**w - (-0.02 * z.powi(3))).abs() <= 3.0 * **se + 1e-9)
        .count();
    eprintln!("{inside} of 50 grid points within 3 s.e. of the true f");
    assert!(inside >= 45, "{inside}");
}

#[test]
fn the_fit_is_never_worse_on_training_than_the_linear_model() {
    // friction on the velocity and a linear record: the feedback fit against the linear fit
    // of the same order (both output-error, both on the training record)
    for (seed, f) in [
        (
            3u64,
            Box::new(|v: f64| -0.01 * (v / 0.002).tanh()) as Box<dyn Fn(f64) -> f64>,
        ),
        (4, Box::new(|_| 0.0)),
    ] {
        let data = record(seed, 1500, f, true, 0.005);
        let mut s = FeedbackSettings::new(FeedbackKind::Coulomb, FeedbackOn::Velocity);
        s.order = hammerstein::Order::Fixed(2);
        let fit = feedback::fit(&s, &data).unwrap();
        let lin = hammerstein::fit::Hammerstein::<f64>::linear()
            .order(hammerstein::Order::Fixed(2))
            .with_d(false)
            .fit(&data)
            .unwrap();
        let yh = lin.simulate_on(&data).unwrap().y_hat;
        let y = data.output(0);
        let lin_rms =
            (y.iter().zip(&yh).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
        eprintln!(
            "seed {seed}: feedback {:.4e}, linear {lin_rms:.4e}",
            fit.rms
        );
        assert!(fit.rms <= lin_rms * (1.0 + 1e-6), "{} > {lin_rms}", fit.rms);
    }
}

#[test]
fn the_report_draws_f_with_its_band() {
    let data = record(11, 1500, |z| -0.02 * z.powi(3), false, 0.01);
    let mut s = FeedbackSettings::new(FeedbackKind::Poly3, FeedbackOn::Output);
    s.order = hammerstein::Order::Fixed(2);
    let fit = feedback::fit(&s, &data).unwrap();
    let band = fit.model.nonlinearity_band(&data, 100).unwrap();
    let sim = fit.model.compare(&data).unwrap().simulated;
    let input = ReportInput {
        title: "feedback".into(),
        train: Record::new(data.input(0), data.output(0), sim),
        feedback: Some(FeedbackCurve {
            name: "poly3 on the output".into(),
            z_grid: band.z,
            w: band.w,
            se: band.se,
            data_z: band.data_z,
            method: "delta method".into(),
        }),
        ..Default::default()
    };
    let dir =
        std::env::temp_dir().join(format!("hammerstein-feedback-band-{}", std::process::id()));
    let index = write_report(&dir, &input).unwrap();
    let svg = std::fs::read_to_string(dir.join("feedback-nonlinearity.svg")).unwrap();
    assert!(svg.contains("<polygon"), "no band drawn");
    let html = std::fs::read_to_string(index).unwrap();
    assert!(html.contains("Nonlinearity in feedback"));
    std::fs::remove_dir_all(&dir).ok();
}
