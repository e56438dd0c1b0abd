//! Diagnosis: from residual signatures to named, ranked missing effects, each checked by refitting.
//!
//! Decision rule (documented in `docs/`-facing terms in [`Diagnoser::diagnose`]):
//! 1. Compare the model with the training and validation records; run every residual test on the
//!    training residual (Bonferroni over all tests, family-wise level `alpha`, default 1 %).
//! 2. If no test is significant (and no candidate's own evidence is), the residuals are
//!    consistent with noise: `adequate = true`, no refit is made and the suggestion list is empty.
//! 3. Otherwise every applicable candidate is refitted (in parallel; refinement included, as the
//!    current model's own fit) and judged **on the training part only**: it is suggested when
//!    its refit lowers the Bayesian information criterion of the training simulation error,
//!    ΔBIC = N·ln(MSE_after/MSE_before) + (Δk − Δn)·ln N + 2·Δn < 0, Δn the initial states
//!    among the Δk added parameters (the criterion of the order selection,
//!    `hammerstein::order_selection::penalty`), its relative training improvement is at least
//!    `min_improvement` (default 3 %), and its own parameters are not at their null value
//!    within two standard errors (`MissingEffect::null_parameters`: a hysteresis width a ≈ 0,
//!    a preload's jump e1 − e2 ≈ 0, saturation limits outside the input's range, …). The validation part is only reported.
//! 4. Score = relative training improvement × (1 when the candidate's own test is significant,
//!    ½ otherwise): the refit decides, the evidence breaks near-ties between effects that both
//!    help. Suggestions are sorted by score, best first.
//! 5. Adequate only when every residual test passes (step 2). When tests fail and no candidate
//!    helps, `adequate = false`, no suggestion, and `unexplained` lists the failing tests with
//!    the model classes beyond this one that would address them.

use super::whole::Setup;
use crate::data::IoData;
use crate::diagnosis::candidates::candidate::MissingEffect;
use crate::diagnosis::candidates::registry::Registry;
use crate::diagnosis::residual_tests::analysis::{ResidualAnalysis, ResidualTest};
use crate::diagnosis::residual_tests::test_registry::TestRegistry;
use crate::error::{Error, Result};
use crate::fit::{HammersteinModel, Observer};
use crate::real::Real;

pub use super::outcome::{
    Action, CandidateOutcome, Diagnosis, DiagnosisOptions, Suggestion, Unexplained,
};

/// Runs diagnoses with a registry of candidates and a registry of residual tests.
pub struct Diagnoser<T: Real> {
    registry: Registry<T>,
    tests: TestRegistry,
    options: DiagnosisOptions,
}

impl<T: Real> Default for Diagnoser<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> Diagnoser<T> {
    /// The built-in candidates and residual tests with default options.
    pub fn new() -> Self {
        Self {
            registry: Registry::builtin(),
            tests: TestRegistry::builtin(),
            options: DiagnosisOptions::default(),
        }
    }
    /// Uses another registry of candidates.
    pub fn registry(mut self, registry: Registry<T>) -> Self {
        self.registry = registry;
        self
    }
    /// Adds a user's candidate to the registry.
    pub fn register(mut self, c: Box<dyn MissingEffect<T>>) -> Self {
        self.registry.register(c);
        self
    }
    /// Uses another registry of residual tests.
    pub fn residual_tests(mut self, tests: TestRegistry) -> Self {
        self.tests = tests;
        self
    }
    /// Adds a user's residual test to the test registry.
    pub fn register_test(mut self, t: Box<dyn ResidualTest>) -> Self {
        self.tests.register(t);
        self
    }
    /// Sets the options.
    pub fn options(mut self, options: DiagnosisOptions) -> Self {
        self.options = options;
        self
    }
    /// The registry of candidates in use.
    pub fn candidates(&self) -> &Registry<T> {
        &self.registry
    }
    /// The registry of residual tests in use.
    pub fn tests(&self) -> &TestRegistry {
        &self.tests
    }

    fn setup<'a>(&'a self, observer: Option<&'a dyn Observer>) -> Setup<'a, T> {
        Setup {
            registry: &self.registry,
            tests: &self.tests,
            options: &self.options,
            observer,
        }
    }

    /// The residual analysis of `model` on the training record (what the candidates read their
    /// evidence and settings changes from).
    pub fn analysis(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
    ) -> Result<ResidualAnalysis> {
        self.setup(None).analysis(model, train)
    }

    /// Diagnoses `model` (fitted on `train`) with `validation` as hold-out data; a training
    /// record longer than the model's screening threshold is screened on a window of it
    /// ([`super::screen`]).
    pub fn diagnose(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
    ) -> Result<Diagnosis<T>> {
        self.run(model, train, validation, None)
    }

    /// [`diagnose`](Self::diagnose) with `observer` notified by every refit (as
    /// [`Hammerstein::fit_observed`](crate::fit::Hammerstein::fit_observed)) and at the stages
    /// of a screened diagnosis ([`Observer::progress`]). Observers are attached at run time
    /// only: neither the diagnoser nor the model's settings hold one.
    pub fn diagnose_observed(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        observer: &dyn Observer,
    ) -> Result<Diagnosis<T>> {
        self.run(model, train, validation, Some(observer))
    }

    /// The diagnosis, screened on a long record, with `observer` notified.
    pub(crate) fn run(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        observer: Option<&dyn Observer>,
    ) -> Result<Diagnosis<T>> {
        check_validation_length(model, validation)?;
        let setup = self.setup(observer);
        // the model's settings hold the window its fit found representative of the record
        // (the record itself when none was: then the diagnosis is not screened either)
        let s = model.settings().options().screening;
        if s.applies(train.len()) {
            return super::screen::diagnose_screened(&setup, model, train, validation, s);
        }
        // a long record fitted whole (no window's model carried over): its candidates are still
        // screened, on a window of `screen::WHOLE_FIT_WINDOW`, and the best re-checked on the
        // whole record — refitting each on the whole record cost minutes
        if train.len() > s.threshold && train.len() > super::screen::WHOLE_FIT_WINDOW {
            let w = crate::fit::Screening {
                window: super::screen::WHOLE_FIT_WINDOW,
                ..s
            };
            return super::screen::diagnose_screened(&setup, model, train, validation, w);
        }
        setup.diagnose_whole(model, train, validation, true)
    }
}

/// Fewest samples of a validation record the diagnosis judges on: below it the validation MSE
/// of a refit against the model's is noise (their ratio's relative spread is about √(2/N),
/// 30 % at 20 samples), and no model should be called adequate on it.
pub const MIN_VALIDATION_SAMPLES: usize = 20;

/// [`Error::TooFewSamples`] for a validation record shorter than [`MIN_VALIDATION_SAMPLES`] or
/// than a comparison of `model` needs.
fn check_validation_length<T: Real>(
    model: &HammersteinModel<T>,
    validation: &IoData<T>,
) -> Result<()> {
    let needed = MIN_VALIDATION_SAMPLES.max(crate::diagnosis::compare::min_compare_samples(model));
    if validation.len() < needed {
        return Err(Error::TooFewSamples {
            needed,
            got: validation.len(),
            reason: "the validation part of a diagnosis".into(),
        });
    }
    Ok(())
}

/// Diagnoses a model with the built-in candidates and default options.
pub fn diagnose<T: Real>(
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
) -> Result<Diagnosis<T>> {
    Diagnoser::new().diagnose(model, train, validation)
}
