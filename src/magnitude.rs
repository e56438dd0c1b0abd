//! The magnitudes a record's computations hold in its scalar type. Identification sums squares
//! and lag products of the record's values over its samples (the subspace step's Hankel
//! products, variances, least squares): values beyond √(max/N) overflow those sums, and
//! subnormal values (below the type's smallest normal number) have lost their digits and
//! underflow to 0 when squared. Either way the failure shows far from its cause (a Cholesky
//! factor with an infinite entry, "all singular values are zero", a simulation said to
//! diverge at its first sample); [`IoData::check_magnitude`] names it first.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;

impl<T: Real> IoData<T> {
    /// [`Error::Magnitude`] when a channel's largest |value| exceeds √(max / N) of the scalar
    /// type (N samples: the sums of squares overflow) or, not being 0, lies below its smallest
    /// normal number (subnormal values); Ok otherwise.
    pub fn check_magnitude(&self) -> Result<()> {
        let big = (T::max_value().as_f64() / self.len().max(1) as f64).sqrt();
        let small = T::min_positive_value().as_f64();
        let channels = (0..self.n_inputs())
            .map(|j| ("input", &self.input_names()[j], self.input_slice(j)))
            .chain(
                (0..self.n_outputs())
                    .map(|j| ("output", &self.output_names()[j], self.output_slice(j))),
            );
        for (channel, name, values) in channels {
            let peak = values.iter().fold(0.0f64, |m, v| m.max(v.as_f64().abs()));
            let why = if peak > big {
                let hint = if T::NAME == "f32" {
                    "use --precision f64 (or `IoData<f64>`), or rescale it"
                } else {
                    "rescale it (e.g. to values of order 1)"
                };
                format!(
                    "beyond what {} computations on {} samples hold ({big:.1e}: their sums of \
                     squares overflow); {hint} before identification",
                    T::NAME,
                    self.len()
                )
            } else if peak > 0.0 && peak < small {
                format!(
                    "below the smallest normal {} number ({small:.1e}): its values are subnormal, \
                     their digits lost and their squares 0; rescale it (e.g. to values of order \
                     1) before identification",
                    T::NAME
                )
            } else {
                continue;
            };
            return Err(Error::Magnitude {
                channel: channel.into(),
                name: name.clone(),
                magnitude: peak,
                why,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(scale_u: f64, scale_y: f64) -> IoData<f64> {
        let u: Vec<f64> = (0..50).map(|k| ((k * 7) % 11) as f64 - 5.0).collect();
        let y: Vec<f64> = (0..50).map(|k| ((k * 3) % 13) as f64 - 6.0).collect();
        let u: Vec<f64> = u.iter().map(|v| v * scale_u).collect();
        let y: Vec<f64> = y.iter().map(|v| v * scale_y).collect();
        IoData::siso(&u, &y).unwrap()
    }

    #[test]
    fn ordinary_and_wide_records_pass() {
        for s in [1.0, 1e-200, 1e100] {
            assert!(record(s, s).check_magnitude().is_ok(), "{s}");
        }
    }

    #[test]
    fn huge_and_subnormal_records_are_named() {
        let e = record(1e300, 1.0).check_magnitude().unwrap_err();
        assert!(
            matches!(&e, Error::Magnitude { channel, .. } if channel == "input"),
            "{e:?}"
        );
        assert!(e.to_string().contains("overflow"), "{e}");
        let e = record(1.0, 1e-310).check_magnitude().unwrap_err();
        assert!(
            matches!(&e, Error::Magnitude { channel, .. } if channel == "output"),
            "{e:?}"
        );
        assert!(e.to_string().contains("subnormal"), "{e}");
        // f32: 1e30 is a valid f32 value, but its squares are not
        assert!(record(1.0, 1.0).cast::<f32>().check_magnitude().is_ok());
        let big = record(1e30, 1.0).cast::<f32>();
        let e = big.check_magnitude().unwrap_err();
        assert!(e.to_string().contains("--precision f64"), "{e}");
    }
}
