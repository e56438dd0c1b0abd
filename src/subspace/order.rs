//! Order selection from the singular values of the subspace decomposition.

use crate::error::{Error, Result};
use crate::real::Real;

/// How the model order is chosen.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Order {
    /// A fixed order.
    Fixed(usize),
    /// The tool's automatic choice: for a linear subspace identification the largest logarithmic
    /// gap of the singular values (as [`Gap`](Order::Gap)); for a Hammerstein fit every candidate
    /// order is fitted and the one with the lowest information criterion on the training
    /// record is kept (see `docs/algorithm.md`).
    Auto,
    /// The largest logarithmic gap between consecutive singular values (SLICOT IB01AD's default
    /// rule), applied to the first subspace step.
    Gap,
    /// The number of singular values above `threshold · σ₁`.
    Threshold(f64),
}

impl std::str::FromStr for Order {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        if s == "auto" {
            return Ok(Order::Auto);
        }
        if s == "gap" {
            return Ok(Order::Gap);
        }
        if let Some(t) = s.strip_prefix("threshold:") {
            return t.parse::<f64>().map(Order::Threshold).map_err(|_| {
                Error::InvalidParameter(format!("bad threshold '{t}' in order '{s}'"))
            });
        }
        s.parse::<usize>().map(Order::Fixed).map_err(|_| {
            Error::InvalidParameter(format!(
                "order must be a number, 'auto', 'gap' or 'threshold:T', got '{s}'"
            ))
        })
    }
}

/// Applies the order rule to non-increasing singular values; `max` is the largest admissible order.
pub fn select_order<T: Real>(sv: &[T], rule: &Order, max: usize) -> Result<usize> {
    // an order n is read against the singular value after it: one value supports no order
    if sv.len() < 2 {
        return Err(Error::Identification(format!(
            "order selection needs at least two singular values, got {} (a horizon of at least \
             2 block rows gives them)",
            sv.len()
        )));
    }
    let max = max.min(sv.len() - 1).max(1);
    match *rule {
        Order::Fixed(n) => {
            if n == 0 {
                Err(Error::ZeroOrder)
            } else if n > max {
                Err(Error::OrderTooLarge { requested: n, max })
            } else {
                Ok(n)
            }
        }
        Order::Auto | Order::Gap => {
            // SLICOT IB01AD (TOL <= 0): order at the largest gap of log10(σ_k) - log10(σ_{k+1}),
            // ignoring singular values at round-off level.
            let s0 = sv.first().map(|s| s.as_f64()).unwrap_or(0.0);
            if s0 <= 0.0 {
                return Err(Error::Identification("all singular values are zero".into()));
            }
            let floor = s0 * 1e3 * T::epsilon().as_f64();
            let mut best = (1usize, f64::NEG_INFINITY);
            // with a single singular value there is no gap to compare: order 1
            for k in 1..=max.min(sv.len().saturating_sub(1)) {
                let a = sv[k - 1].as_f64().max(floor);
                let b = sv[k].as_f64().max(floor);
                let gap = a.log10() - b.log10();
                if gap > best.1 {
                    best = (k, gap);
                }
            }
            Ok(best.0)
        }
        Order::Threshold(t) => {
            if !(t > 0.0 && t < 1.0) {
                return Err(Error::InvalidParameter(format!(
                    "order threshold must lie in (0, 1), got {t}"
                )));
            }
            let s0 = sv.first().map(|s| s.as_f64()).unwrap_or(0.0);
            let n = sv.iter().filter(|s| s.as_f64() > t * s0).count();
            Ok(n.clamp(1, max))
        }
    }
}
