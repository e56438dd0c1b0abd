//! The registry of missing-effect candidates a diagnosis tries: the built-ins by default, extendable
//! with a user's own [`MissingEffect`].

use super::candidate::{Delay, Dynamics, MissingEffect, OutputNonlinearity, UdnEffect};
use super::pi_candidate::PrandtlIshlinskiiCandidate;
use crate::diagnosis::ids::CandidateId;
use crate::real::Real;
use crate::regressors::Effect;

/// An ordered list of candidates, keyed by [`CandidateId`].
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
    /// prandtl-ishlinskii, dynamics, delay, output-nonlinearity, feedback-nonlinearity.
    pub fn builtin() -> Self {
        let mut r = Self::empty();
        for e in Effect::ALL {
            r.register(Box::new(UdnEffect(e)));
        }
        r.register(Box::new(PrandtlIshlinskiiCandidate));
        r.register(Box::new(Dynamics));
        r.register(Box::new(Delay));
        r.register(Box::new(OutputNonlinearity));
        r.register(Box::new(super::feedback_candidate::FeedbackNonlinearity));
        r
    }

    /// Adds a candidate (a later one with the same id replaces the earlier).
    pub fn register(&mut self, c: Box<dyn MissingEffect<T>>) -> &mut Self {
        let id = c.id();
        self.candidates.retain(|x| x.id() != id);
        self.candidates.push(c);
        self
    }

    /// Removes the candidate `id` (a [`CandidateId`] or its name); true when one was removed.
    pub fn remove(&mut self, id: impl Into<CandidateId>) -> bool {
        let id = id.into();
        let n = self.candidates.len();
        self.candidates.retain(|x| x.id() != id);
        n != self.candidates.len()
    }

    /// The registered candidates' ids, in order.
    pub fn ids(&self) -> Vec<CandidateId> {
        self.candidates.iter().map(|c| c.id()).collect()
    }

    /// Names of the registered candidates, in order.
    pub fn names(&self) -> Vec<String> {
        self.candidates.iter().map(|c| c.id().to_string()).collect()
    }

    /// The candidate `id`, when registered.
    pub fn get(&self, id: &CandidateId) -> Option<&dyn MissingEffect<T>> {
        self.candidates
            .iter()
            .find(|c| c.id() == *id)
            .map(|c| c.as_ref())
    }

    /// The candidates.
    pub fn candidates(&self) -> &[Box<dyn MissingEffect<T>>] {
        &self.candidates
    }
}
