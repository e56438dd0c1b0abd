//! The Cramér–Rao bound of Example 1: the smallest standard deviation an unbiased estimator of the
//! SH and linear parameters can reach with N = 2000 samples at a given SNR.
//!
//! Output-error model ŷ(k) = G(q) v(k; θ), G(q) = B(q)/A(q), B = b1 q⁻¹ + b2 q⁻², A = 1 + a1 q⁻¹ + a2 q⁻²,
//! with b1 = 1 fixing the scale shared by N and G. Parameters ϑ = (p, a, z1, z2, a1, a2, b2).
//! With white Gaussian output noise of variance σ² the Fisher information is
//! J = Σ_k ψ(k) ψ(k)ᵀ / σ², ψ = ∂ŷ/∂ϑ (e.g. Ljung, *System Identification*, 2nd ed., §9.3), where
//!
//! ```text
//! ∂ŷ/∂θ_j  = G(q) · ∂v/∂θ_j          θ = (p, a, z1, z2): the SH's analytic Jacobian (a.e.)
//! ∂ŷ/∂a_i  = −q⁻ⁱ / A(q) · ŷ          from A ŷ = B v differentiated in a_i
//! ∂ŷ/∂b_2  =  q⁻² / A(q) · v
//! ```
//!
//! The bound is the expectation over the random input: J is averaged over several seeded input
//! draws, and σ² is set from the expected clean-output variance and the SNR definition.
//! The computation is in `f64` on purpose: it is a reference value, not an estimator.

use super::example1::{Example1, TRUE_DENOMINATOR, TRUE_NUMERATOR, variance};
use crate::error::{Error, Result};
use crate::regressors::StaticNonlinearity;
use crate::solvers::recursion::TfFilter;
use crate::solvers::{BackendKind, backend};
use faer::Mat;
use rand::{SeedableRng, rngs::StdRng};

/// Names of the bounded parameters, in the order of [`Crlb::std`].
pub const CRLB_PARAMS: [&str; 7] = ["p", "a", "z1", "z2", "a1", "a2", "b2"];

/// How an SNR in dB maps to the noise variance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SnrDefinition {
    /// SNR = 10·log10(var(y)/var(ε)) (NOTES.md's reading, the study's default).
    #[default]
    Power,
    /// SNR = 10·log10(std(y)/std(ε)), an amplitude ratio read as if it were a power ratio.
    Amplitude,
}

impl SnrDefinition {
    /// Noise variance σ² for a clean-output variance and an SNR in dB.
    pub fn noise_variance(self, var_y: f64, snr_db: f64) -> f64 {
        match self {
            SnrDefinition::Power => var_y / 10f64.powf(snr_db / 10.0),
            SnrDefinition::Amplitude => var_y / 10f64.powf(snr_db / 5.0),
        }
    }
}

/// The Cramér–Rao bound of Example 1 at one SNR.
#[derive(Debug, Clone, PartialEq)]
pub struct Crlb {
    /// SNR in dB.
    pub snr_db: f64,
    /// The SNR definition used.
    pub definition: SnrDefinition,
    /// Number of samples N of one record.
    pub n: usize,
    /// Noise standard deviation σ.
    pub noise_std: f64,
    /// Lower bound on the standard deviation of each parameter of [`CRLB_PARAMS`].
    pub std: Vec<f64>,
}

impl Crlb {
    /// The bound on the std of parameter `name` (`None` when it is not bounded, e.g. b1 = 1 fixed).
    pub fn get(&self, name: &str) -> Option<f64> {
        CRLB_PARAMS
            .iter()
            .position(|&p| p == name)
            .map(|i| self.std[i])
    }
}

/// Filters x through num(q)/den(q) (coefficients in powers of q⁻¹, `den[0]` ≠ 0), zero initial state.
///
/// Runs the crate's transfer-function filter (`solvers::recursion::TfFilter`) on the
/// coefficients divided by `den[0]` (exact for the monic denominators of this module).
pub fn filter(num: &[f64], den: &[f64], x: &[f64]) -> Vec<f64> {
    let n = num.len().max(den.len()).max(1) - 1;
    let d0 = den.first().copied().unwrap_or(1.0);
    let mut a = vec![0.0; n + 1];
    a[0] = 1.0;
    for (ai, &di) in a.iter_mut().zip(den).skip(1) {
        *ai = di / d0;
    }
    let b: Vec<f64> = num.iter().map(|&v| v / d0).collect();
    let mut y = TfFilter::new(n).run(&a, &b, x);
    y.drain(..n);
    y
}

/// Sensitivities ψ(k) = ∂ŷ(k)/∂ϑ of the true Example 1 model for input `u`, N×7 in the order of
/// [`CRLB_PARAMS`], together with the clean output ŷ.
pub fn sensitivities(u: &[f64]) -> Result<(Mat<f64>, Vec<f64>)> {
    let nl = Example1::true_nonlinearity::<f64>()?;
    let v = nl.eval(u);
    let dv = nl.param_jacobian(u); // N×4: p, a, z1, z2
    if dv.ncols() != 4 {
        return Err(Error::Dimension(format!(
            "SH Jacobian has {} columns, expected 4 (p, a, z1, z2)",
            dv.ncols()
        )));
    }
    let [b1, b2] = TRUE_NUMERATOR;
    let [a1, a2] = TRUE_DENOMINATOR;
    let num = [0.0, b1, b2];
    let den = [1.0, a1, a2];
    let y = filter(&num, &den, &v);
    let n = u.len();
    let mut psi = Mat::<f64>::zeros(n, 7);
    for j in 0..4 {
        let col: Vec<f64> = (0..n).map(|k| dv[(k, j)]).collect();
        let f = filter(&num, &den, &col);
        for k in 0..n {
            psi[(k, j)] = f[k];
        }
    }
    let da1 = filter(&[0.0, -1.0], &den, &y);
    let da2 = filter(&[0.0, 0.0, -1.0], &den, &y);
    let db2 = filter(&[0.0, 0.0, 1.0], &den, &v);
    for k in 0..n {
        psi[(k, 4)] = da1[k];
        psi[(k, 5)] = da2[k];
        psi[(k, 6)] = db2[k];
    }
    Ok((psi, y))
}

/// Expected per-sample information `E[ψψᵀ]` (7×7) and expected clean-output variance, averaged over
/// `draws` seeded input records of the design `design` (seeds `seed`, `seed + 1`, …).
pub fn expected_information(design: &Example1, draws: usize, seed: u64) -> Result<(Mat<f64>, f64)> {
    if draws == 0 {
        return Err(Error::InvalidParameter(
            "the bound needs at least one input draw".into(),
        ));
    }
    let mut info = Mat::<f64>::zeros(7, 7);
    let mut var_y = 0.0;
    let mut count = 0usize;
    for d in 0..draws {
        let mut rng = StdRng::seed_from_u64(seed.wrapping_add(d as u64));
        let u = design.draw_input(&mut rng);
        let (psi, y) = sensitivities(&u)?;
        for i in 0..7 {
            for j in 0..=i {
                let s: f64 = (0..u.len()).map(|k| psi[(k, i)] * psi[(k, j)]).sum();
                info[(i, j)] += s;
            }
        }
        var_y += variance(&y);
        count += u.len();
    }
    for i in 0..7 {
        for j in 0..=i {
            info[(i, j)] /= count as f64;
            info[(j, i)] = info[(i, j)];
        }
    }
    Ok((info, var_y / draws as f64))
}

/// The Cramér–Rao bound sqrt(diag(J⁻¹)), `J = N·E[ψψᵀ]/σ²`, for Example 1's design at `snr_db`.
///
/// `draws` input records (seeds from `seed`) give the expectation over the input; 20 draws of
/// 2000 samples fix the bound to about 1 %.
pub fn example1_crlb(
    design: &Example1,
    snr_db: f64,
    definition: SnrDefinition,
    draws: usize,
    seed: u64,
) -> Result<Crlb> {
    let (info, var_y) = expected_information(design, draws, seed)?;
    crlb_from_information(&info, var_y, design.n, snr_db, definition)
}

/// The bound from a per-sample information matrix `E[ψψᵀ]` and the clean-output variance.
pub fn crlb_from_information(
    info: &Mat<f64>,
    var_y: f64,
    n: usize,
    snr_db: f64,
    definition: SnrDefinition,
) -> Result<Crlb> {
    if !snr_db.is_finite() {
        return Err(Error::InvalidParameter(
            "the Cramér–Rao bound needs a finite SNR (it is 0 without noise)".into(),
        ));
    }
    let sigma2 = definition.noise_variance(var_y, snr_db);
    let la = backend::<f64>(BackendKind::Faer)?;
    let j = Mat::from_fn(7, 7, |r, c| info[(r, c)] * n as f64 / sigma2);
    let inv = la.solve(j.as_ref(), Mat::<f64>::identity(7, 7).as_ref())?;
    let std = (0..7)
        .map(|i| {
            let v = inv[(i, i)];
            if v > 0.0 && v.is_finite() {
                Ok(v.sqrt())
            } else {
                Err(Error::LinAlg(format!(
                    "Fisher information is singular ({} has variance {v})",
                    CRLB_PARAMS[i]
                )))
            }
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Crlb {
        snr_db,
        definition,
        n,
        noise_std: sigma2.sqrt(),
        std,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ψ against central differences of the simulated output in each parameter.
    #[test]
    fn sensitivities_match_finite_differences() {
        let design = Example1 {
            n: 400,
            ..Example1::new(None)
        };
        let mut rng = StdRng::seed_from_u64(3);
        let u = design.draw_input(&mut rng);
        let (psi, _) = sensitivities(&u).unwrap();
        let sim = |th: &[f64; 7]| {
            let mut nl = crate::regressors::Udn::<f64>::sh();
            nl.set_params(&th[..4]).unwrap();
            let v = nl.eval(&u);
            filter(&[0.0, 1.0, th[6]], &[1.0, th[4], th[5]], &v)
        };
        let th0 = [2.0, 0.5, 1.5, -1.0, -0.2, 0.35, 0.5];
        for j in 0..7 {
            let h = 1e-6;
            let (mut tp, mut tm) = (th0, th0);
            tp[j] += h;
            tm[j] -= h;
            let (yp, ym) = (sim(&tp), sim(&tm));
            let (mut err, mut norm) = (0.0, 0.0);
            for k in 0..u.len() {
                let fd = (yp[k] - ym[k]) / (2.0 * h);
                err += (fd - psi[(k, j)]).powi(2);
                norm += psi[(k, j)].powi(2);
            }
            assert!(
                err.sqrt() < 1e-4 * norm.sqrt(),
                "{}: relative error {}",
                CRLB_PARAMS[j],
                (err / norm).sqrt()
            );
        }
    }

    /// The difference equation as this module wrote it before it used `TfFilter`.
    fn filter_reference(num: &[f64], den: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for k in 0..x.len() {
            let mut acc = 0.0;
            for (j, &b) in num.iter().enumerate() {
                if j <= k {
                    acc += b * x[k - j];
                }
            }
            for (i, &a) in den.iter().enumerate().skip(1) {
                if i <= k {
                    acc -= a * y[k - i];
                }
            }
            y[k] = acc / den[0];
        }
        y
    }

    #[test]
    fn filter_is_bit_identical_to_the_plain_loop() {
        let x: Vec<f64> = (0..500)
            .map(|k| ((k * 7919 % 211) as f64 - 105.0) / 37.0)
            .collect();
        let y = filter(&[0.0, 1.0, 0.5], &[1.0, -0.2, 0.35], &x);
        for (num, den) in [
            (&[0.0, 1.0, 0.5][..], &[1.0, -0.2, 0.35][..]),
            (&[0.0, -1.0], &[1.0, -0.2, 0.35]),
            (&[0.0, 0.0, 1.0], &[1.0, -0.2, 0.35]),
            (&[0.3, 1.0, 0.5, 0.25], &[1.0, -0.5]),
        ] {
            for sig in [&x, &y] {
                let got = filter(num, den, sig);
                let want = filter_reference(num, den, sig);
                assert!(
                    got.iter()
                        .zip(&want)
                        .all(|(g, w)| g.to_bits() == w.to_bits() || g == w)
                );
            }
        }
    }

    #[test]
    fn filter_is_the_difference_equation() {
        let x = [1.0, 0.0, 0.0, 0.0];
        let h = filter(&[0.0, 1.0, 0.5], &[1.0, -0.2, 0.35], &x);
        // impulse response of z⁻¹(1 + 0.5 z⁻¹)/(1 − 0.2 z⁻¹ + 0.35 z⁻²)
        assert_eq!(h[0], 0.0);
        assert!((h[1] - 1.0).abs() < 1e-15);
        assert!((h[2] - 0.7).abs() < 1e-15);
        assert!((h[3] - (0.2 * 0.7 - 0.35)).abs() < 1e-15);
    }
}

#[cfg(test)]
mod value_tests {
    use super::*;

    /// NOTES.md's values (std at 10 dB, power SNR) and their scaling with the SNR.
    #[test]
    fn bound_matches_reference_values() {
        let design = Example1::new(Some(10.0));
        let (info, var_y) = expected_information(&design, 20, 1000).unwrap();
        let c10 = crlb_from_information(&info, var_y, 2000, 10.0, SnrDefinition::Power).unwrap();
        let reference = [0.032, 0.014, 0.027, 0.020, 0.014, 0.0074, 0.023];
        for (i, &r) in reference.iter().enumerate() {
            let rel = c10.std[i] / r;
            eprintln!(
                "{} {:.5} (ref {r}) ratio {rel:.3}",
                CRLB_PARAMS[i], c10.std[i]
            );
        }
        for (i, &r) in reference.iter().enumerate() {
            let rel = c10.std[i] / r;
            assert!(
                (rel - 1.0).abs() < 0.04,
                "{}: {} vs {r}",
                CRLB_PARAMS[i],
                c10.std[i]
            );
        }
        let c8 = crlb_from_information(&info, var_y, 2000, 8.0, SnrDefinition::Power).unwrap();
        let c5 = crlb_from_information(&info, var_y, 2000, 5.0, SnrDefinition::Power).unwrap();
        let amp =
            crlb_from_information(&info, var_y, 2000, 10.0, SnrDefinition::Amplitude).unwrap();
        for i in 0..7 {
            assert!((c8.std[i] / c10.std[i] - 1.2589).abs() < 1e-3);
            assert!((c5.std[i] / c10.std[i] - 1.7783).abs() < 1e-3);
            assert!((amp.std[i] / c10.std[i] - 0.3162).abs() < 1e-3);
        }
    }
}
