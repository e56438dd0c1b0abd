//! The registry of missing-effect candidates a diagnosis tries: the built-ins by default, extendable
//! with a user's own [`MissingEffect`].

use super::candidate::{Delay, Dynamics, MissingEffect, OutputNonlinearity, UdnEffect};
use super::pi_candidate::PrandtlIshlinskiiCandidate;
use crate::real::Real;
use crate::regressors::Effect;

/// An ordered list of candidates.
pub struct Registry<T: Real> {
    candidates: Vec<Box<dyn MissingEffect<T>>>,
}

impl<T: Real> Default for Registry<T> {
    fn default() -> Self {
        Self::builtin()
    }
}

impl<T: Real> std::fmt::Debug for Registry<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.names()).finish()
    }
}

impl<T: Real> Registry<T> {
    /// No candidate at all.
    pub fn empty() -> Self {
        Self {
            candidates: Vec::new(),
        }
    }

    /// The built-in candidates: hysteresis, dead-zone, saturation, preload,
    /// prandtl-ishlinskii, dynamics, delay, output-nonlinearity.
    pub fn builtin() -> Self {
        let mut r = Self::empty();
        for e in Effect::ALL {
            r.register(Box::new(UdnEffect(e)));
        }
        r.register(Box::new(PrandtlIshlinskiiCandidate));
        r.register(Box::new(Dynamics));
        r.register(Box::new(Delay));
        r.register(Box::new(OutputNonlinearity));
        r
    }

    /// Adds a candidate (a later one with the same name replaces the earlier).
    pub fn register(&mut self, c: Box<dyn MissingEffect<T>>) -> &mut Self {
        let name = c.name();
        self.candidates.retain(|x| x.name() != name);
        self.candidates.push(c);
        self
    }

    /// Removes the candidate of that name; true when one was removed.
    pub fn remove(&mut self, name: &str) -> bool {
        let n = self.candidates.len();
        self.candidates.retain(|x| x.name() != name);
        n != self.candidates.len()
    }

    /// Names of the registered candidates, in order.
    pub fn names(&self) -> Vec<String> {
        self.candidates.iter().map(|c| c.name()).collect()
    }

    /// The candidates.
    pub fn candidates(&self) -> &[Box<dyn MissingEffect<T>>] {
        &self.candidates
    }
}
