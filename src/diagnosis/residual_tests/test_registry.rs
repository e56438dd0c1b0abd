//! The registry of residual tests an analysis runs: the built-ins by default, extendable with a
//! user's own [`ResidualTest`]; and the analysis' constructors that run them.

use super::analysis::{AnalysisOptions, ResidualAnalysis, ResidualTest};
use super::builtin_tests::BuiltinTest;
use crate::diagnosis::ids::TestId;
use crate::error::Result;
use crate::statespace::StateSpace;

/// An ordered list of residual tests, keyed by [`TestId`].
pub struct TestRegistry {
    tests: Vec<Box<dyn ResidualTest>>,
}

impl Default for TestRegistry {
    fn default() -> Self {
        Self::builtin()
    }
}

impl std::fmt::Debug for TestRegistry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.ids()).finish()
    }
}

impl TestRegistry {
    /// No test at all.
    pub fn empty() -> Self {
        Self { tests: Vec::new() }
    }

    /// The built-in tests: whiteness, input-cross-correlation, dynamics, delay, input-level,
    /// input-direction, input-extremes, input-near-zero, input-zero-step, input-square,
    /// input-cube, output-level.
    pub fn builtin() -> Self {
        let mut r = Self::empty();
        for id in TestId::BUILTIN {
            if id != TestId::PrandtlIshlinskii && id != TestId::FeedbackNonlinearity {
                r.register(Box::new(BuiltinTest(id)));
            }
        }
        r
    }

    /// Adds a test (a later one with the same id replaces the earlier).
    pub fn register(&mut self, t: Box<dyn ResidualTest>) -> &mut Self {
        let id = t.id();
        self.tests.retain(|x| x.id() != id);
        self.tests.push(t);
        self
    }

    /// Removes the test `id` (a [`TestId`] or its name); true when one was removed.
    pub fn remove(&mut self, id: impl Into<TestId>) -> bool {
        let id = id.into();
        let n = self.tests.len();
        self.tests.retain(|x| x.id() != id);
        n != self.tests.len()
    }

    /// The registered tests' ids, in order.
    pub fn ids(&self) -> Vec<TestId> {
        self.tests.iter().map(|t| t.id()).collect()
    }

    /// The tests.
    pub fn tests(&self) -> &[Box<dyn ResidualTest>] {
        &self.tests
    }

    /// The model classes that would address a failure of test `id` (its
    /// [`ResidualTest::model_classes`]; the default one for a test not registered here).
    pub fn model_classes(&self, id: &TestId) -> Vec<String> {
        self.tests.iter().find(|t| t.id() == *id).map_or_else(
            || BuiltinTest(id.clone()).model_classes(),
            |t| t.model_classes(),
        )
    }
}

impl ResidualAnalysis {
    /// Runs every built-in test on the residual of a model with linear block `linear` (SISO).
    pub fn new(
        u: &[f64],
        y: &[f64],
        y_hat: &[f64],
        v_hat: &[f64],
        linear: &StateSpace<f64>,
        options: AnalysisOptions,
    ) -> Result<Self> {
        Self::with_tests(
            u,
            y,
            y_hat,
            v_hat,
            linear,
            options,
            &TestRegistry::builtin(),
        )
    }

    /// Runs the tests of `tests` (in its order, Bonferroni over all of them) on the residual of
    /// a model with linear block `linear` (SISO).
    pub fn with_tests(
        u: &[f64],
        y: &[f64],
        y_hat: &[f64],
        v_hat: &[f64],
        linear: &StateSpace<f64>,
        options: AnalysisOptions,
        tests: &TestRegistry,
    ) -> Result<Self> {
        let mut a = Self::prepare(u, y, y_hat, v_hat, linear, options)?;
        a.run_tests(tests.tests());
        Ok(a)
    }
}
