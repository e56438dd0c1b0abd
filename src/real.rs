//! The scalar trait every generic algorithm in the crate is written against.

use std::fmt::{Debug, Display};

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// A real floating-point scalar the crate computes in: `f32` or `f64`.
///
/// Backend-specific bounds (nalgebra, LAPACK) are deliberately kept out of this trait so that
/// `abs()`, `sqrt()` and friends resolve unambiguously to `num_traits::Float`.
pub trait Real:
    faer::traits::RealField
    + num_traits::Float
    + Copy
    + Send
    + Sync
    + Debug
    + Display
    + Default
    + 'static
    + sealed::Sealed
{
    /// Name of the type as the command line spells it ("f32" or "f64").
    const NAME: &'static str;
    /// Converts an `f64` literal or value (rounding for `f32`).
    fn lit(x: f64) -> Self;
    /// Widens (or keeps) the value as `f64`.
    fn as_f64(self) -> f64;
    /// Converts a count or index.
    fn from_usize(n: usize) -> Self {
        Self::lit(n as f64)
    }
}

impl Real for f32 {
    const NAME: &'static str = "f32";
    fn lit(x: f64) -> Self {
        x as f32
    }
    fn as_f64(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    const NAME: &'static str = "f64";
    fn lit(x: f64) -> Self {
        x
    }
    fn as_f64(self) -> f64 {
        self
    }
}
