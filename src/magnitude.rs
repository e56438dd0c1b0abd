//! The magnitudes a record's computations hold in its scalar type. Identification sums squares
//! and lag products of the record's values over its samples (the subspace step's Hankel
//! products, variances, least squares): values beyond √(max/N) overflow those sums, and
//! subnormal values (below the type's smallest normal number) have lost their digits and
//! underflow to 0 when squared. Either way the failure shows far from its cause (a Cholesky
//! factor with an infinite entry, "all singular values are zero", a simulation said to
//! diverge at its first sample); [`IoData::check_magnitude`] (the fit's limits: it normalises
//! the record first) and [`IoData::check_magnitude_unscaled`] (computations on the values as
//! they are) name it first.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;

/// Headroom below √(max) of the scalar type that [`IoData::check_magnitude`] keeps for a
/// fitted model's simulation (whose values beyond √(max) are said to diverge).
const SIMULATION_HEADROOM: f64 = 10.0;

impl<T: Real> IoData<T> {
    /// [`Error::Magnitude`] when the fit cannot work on this record: a channel's largest |value|
    /// beyond √(f64 max / N) (N samples: the normalisation's sums of squares, taken in f64,
    /// overflow) or beyond √(max)/10 of the scalar type (the model's simulation in its units
    /// would be said to diverge); or, not being 0, below the type's smallest normal number
    /// (subnormal values). Ok otherwise. The fit normalises the record before computing on it,
    /// so wider ranges pass than [`check_magnitude_unscaled`](Self::check_magnitude_unscaled)'s.
    pub fn check_magnitude(&self) -> Result<()> {
        let n = self.len().max(1) as f64;
        let big = (f64::MAX / n)
            .sqrt()
            .min(T::max_value().as_f64().sqrt() / SIMULATION_HEADROOM);
        self.check_magnitude_below(big)
    }

    /// [`check_magnitude`](Self::check_magnitude) for computations on the record's own values
    /// in its scalar type (the `subspace` command's): a channel's largest |value| beyond
    /// √(max / N) of the type overflows their sums of squares.
    pub fn check_magnitude_unscaled(&self) -> Result<()> {
        self.check_magnitude_below((T::max_value().as_f64() / self.len().max(1) as f64).sqrt())
    }

    fn check_magnitude_below(&self, big: f64) -> Result<()> {
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
        // f32: 1e30 is a valid f32 value, but its squares are not; 9e17 passes the fit's check
        // (it normalises in f64) but not the one of computations in f32 on 10 000 samples
        let u: Vec<f64> = (0..10_000).map(|k| ((k % 7) as f64 - 3.0) * 3e17).collect();
        let y: Vec<f64> = (0..10_000).map(|k| (k % 5) as f64 - 2.0).collect();
        let mid = IoData::siso(&u, &y).unwrap().cast::<f32>();
        assert!(mid.check_magnitude().is_ok());
        assert!(mid.check_magnitude_unscaled().is_err());
        assert!(record(1.0, 1.0).cast::<f32>().check_magnitude().is_ok());
        let big = record(1e30, 1.0).cast::<f32>();
        let e = big.check_magnitude().unwrap_err();
        assert!(e.to_string().contains("--precision f64"), "{e}");
    }
}
