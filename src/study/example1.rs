//! The paper's Example 1 (Section 4.1): SH nonlinearity followed by a second-order linear block,
//! uniform random input and white output noise at a given SNR — the data generator of the study.
//!
//! Model (NOTES.md, "Example 1"): DN4 / SH with p = 2, a = 0.5, b = 0, z1 = 1.5, z2 = −1,
//! e1 = e2 = 0 (hysteresis direction: the previous direction when the input is held);
//! G(z) = z⁻¹(1 + 0.5 z⁻¹)/(1 − 0.2 z⁻¹ + 0.35 z⁻²); N = 2000, u ~ U[−3, 3];
//! SNR = 10·log10(var(y_clean)/var(ε)) with var(y_clean) the sample variance of the run's clean output.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::{StaticNonlinearity, Udn};
use crate::statespace::StateSpace;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, StandardNormal};

/// Names of every parameter the paper's Table 2 reports (Table 3 omits b, e1, e2); the paper's
/// Table 3 numerator "b0, b1" is called b1, b2 here as in its Table 2 and eq. (22).
pub const PARAM_NAMES: [&str; 11] = [
    "p", "a", "b", "z1", "z2", "e1", "e2", "a1", "a2", "b1", "b2",
];

/// True values of [`PARAM_NAMES`].
pub const TRUE_VALUES: [f64; 11] = [2.0, 0.5, 0.0, 1.5, -1.0, 0.0, 0.0, -0.2, 0.35, 1.0, 0.5];

/// True value of a parameter by name (`None` for an unknown name).
pub fn true_value(name: &str) -> Option<f64> {
    PARAM_NAMES
        .iter()
        .position(|&n| n == name)
        .map(|i| TRUE_VALUES[i])
}

/// Numerator b1, b2 of G(z) = z⁻¹(b1 + b2 z⁻¹)/(1 + a1 z⁻¹ + a2 z⁻²).
pub const TRUE_NUMERATOR: [f64; 2] = [1.0, 0.5];
/// Denominator a1, a2 of G(z).
pub const TRUE_DENOMINATOR: [f64; 2] = [-0.2, 0.35];
/// True SH parameters in the UDN's order for {hysteresis, saturation}: p, a, z1, z2.
pub const TRUE_SH: [f64; 4] = [2.0, 0.5, 1.5, -1.0];

/// Settings of one Example 1 data set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Example1 {
    /// Number of samples N (paper: 2000).
    pub n: usize,
    /// Input amplitude: u ~ U[−amplitude, amplitude] (paper: 3).
    pub amplitude: f64,
    /// Output SNR in dB (`None`: noise-free).
    pub snr_db: Option<f64>,
}

/// One generated record with what the estimator does not see.
#[derive(Debug, Clone)]
pub struct Example1Data<T: Real> {
    /// The measured record (u, y = y_clean + ε).
    pub data: IoData<T>,
    /// The noise-free output.
    pub y_clean: Vec<f64>,
    /// Standard deviation σ of the added noise (0 when noise-free).
    pub noise_std: f64,
}

impl Example1 {
    /// The paper's design (N = 2000, |u| ≤ 3) at the given SNR (`None`: noise-free).
    pub fn new(snr_db: Option<f64>) -> Self {
        Self {
            n: 2000,
            amplitude: 3.0,
            snr_db,
        }
    }

    /// The true nonlinearity (SH = DN4 of the UDN).
    pub fn true_nonlinearity<T: Real>() -> Result<Udn<T>> {
        let mut nl = Udn::<T>::sh();
        let theta: Vec<T> = TRUE_SH.iter().map(|&x| T::lit(x)).collect();
        nl.set_params(&theta)?;
        Ok(nl)
    }

    /// The true linear block in controllable canonical form (D = 0, C·B = b1 = 1).
    pub fn true_linear() -> Result<StateSpace<f64>> {
        let [a1, a2] = TRUE_DENOMINATOR;
        let [b1, b2] = TRUE_NUMERATOR;
        StateSpace::from_rows(
            &[&[-a1, -a2], &[1.0, 0.0]],
            &[&[1.0], &[0.0]],
            &[&[b1, b2]],
            &[&[0.0]],
        )
    }

    /// Noise-free intermediate signal v = N(u) and output y = G(q) v from zero initial state.
    pub fn clean_output(u: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let v = Self::true_nonlinearity::<f64>()?.eval(u);
        let y = Self::true_linear()?.simulate_siso(&v, None)?;
        Ok((v, y))
    }

    /// Draws the input u ~ U[−amplitude, amplitude] (N samples) from `rng`.
    pub fn draw_input(&self, rng: &mut StdRng) -> Vec<f64> {
        (0..self.n)
            .map(|_| rng.random_range(-self.amplitude..=self.amplitude))
            .collect()
    }

    /// Generates the record of seed `seed`: first N uniform inputs, then N standard normal noise
    /// samples scaled to the SNR, so that records of equal seed share input and noise shape
    /// across SNRs (common random numbers).
    pub fn generate<T: Real>(&self, seed: u64) -> Result<Example1Data<T>> {
        if self.n < 10 {
            return Err(Error::TooFewSamples {
                needed: 10,
                got: self.n,
                reason: "Example 1 needs a few samples".into(),
            });
        }
        if !(self.amplitude.is_finite() && self.amplitude > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "input amplitude must be positive and finite, got {}",
                self.amplitude
            )));
        }
        if let Some(s) = self.snr_db
            && !s.is_finite()
        {
            return Err(Error::InvalidParameter(format!(
                "SNR must be finite (use no SNR for noise-free data), got {s}"
            )));
        }
        let mut rng = StdRng::seed_from_u64(seed);
        let u = self.draw_input(&mut rng);
        let (_, y_clean) = Self::clean_output(&u)?;
        let noise_std = match self.snr_db {
            None => 0.0,
            Some(snr) => (variance(&y_clean) / 10f64.powf(snr / 10.0)).sqrt(),
        };
        let y: Vec<T> = y_clean
            .iter()
            .map(|&yc| {
                let e: f64 = StandardNormal.sample(&mut rng);
                T::lit(yc + noise_std * e)
            })
            .collect();
        let ut: Vec<T> = u.iter().map(|&x| T::lit(x)).collect();
        Ok(Example1Data {
            data: IoData::siso(&ut, &y)?,
            y_clean,
            noise_std,
        })
    }
}

/// Sample variance with divisor N.
pub fn variance(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n
}

/// Parses an SNR as the command line and JSON spell it: "inf" (noise-free) or a number of dB.
pub fn parse_snr(s: &str) -> Result<Option<f64>> {
    let t = s.trim();
    if t.eq_ignore_ascii_case("inf") || t.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    match t.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(Some(x)),
        _ => Err(Error::InvalidParameter(format!(
            "SNR must be a number of dB or 'inf', got '{s}'"
        ))),
    }
}

/// The SNR as the JSON output keys it: "inf" or the number without a trailing ".0".
pub fn snr_key(snr_db: Option<f64>) -> String {
    match snr_db {
        None => "inf".into(),
        Some(x) if x.fract() == 0.0 => format!("{}", x as i64),
        Some(x) => format!("{x}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snr_and_seed_are_honoured() {
        let d1 = Example1::new(Some(10.0)).generate::<f64>(7).unwrap();
        let d2 = Example1::new(Some(10.0)).generate::<f64>(7).unwrap();
        let d3 = Example1::new(Some(10.0)).generate::<f64>(8).unwrap();
        assert_eq!(d1.data.output(0), d2.data.output(0));
        assert_ne!(d1.data.input(0), d3.data.input(0));
        let y = d1.data.output(0);
        let e: Vec<f64> = y.iter().zip(&d1.y_clean).map(|(a, b)| a - b).collect();
        let snr = 10.0 * (variance(&d1.y_clean) / variance(&e)).log10();
        assert!((snr - 10.0).abs() < 0.3, "realised SNR {snr}");
        let u = d1.data.input(0);
        assert!(u.iter().all(|x| x.abs() <= 3.0));
        assert!(u.iter().cloned().fold(0.0, f64::max) > 2.9);
        let clean = Example1::new(None).generate::<f64>(7).unwrap();
        assert_eq!(clean.data.output(0), clean.y_clean);
        assert_eq!(clean.data.input(0), u);
    }

    #[test]
    fn transfer_function_is_the_papers() {
        let tf = Example1::true_linear()
            .unwrap()
            .transfer_function(0, 0)
            .unwrap();
        let expect_num = [0.0, 1.0, 0.5];
        let expect_den = [1.0, -0.2, 0.35];
        for k in 0..3 {
            assert!((tf.numerator[k] - expect_num[k]).abs() < 1e-12);
            assert!((tf.denominator[k] - expect_den[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn snr_parsing() {
        assert_eq!(parse_snr("inf").unwrap(), None);
        assert_eq!(parse_snr("8").unwrap(), Some(8.0));
        assert!(parse_snr("loud").is_err());
        assert_eq!(snr_key(Some(10.0)), "10");
        assert_eq!(snr_key(None), "inf");
    }
}
