//! Embeds hammerstein (no default features) as an external crate: a user-defined nonlinearity
//! basis (cubic stiffening, v = a·u + c·u³) fitted by the loop, a user-defined residual test
//! (u³ in the residual) registered next to the built-in tests, and a user-defined missing-effect
//! candidate reading its evidence from that test, registered next to the built-in candidates.
//! Exits non-zero (a panic) when one of them does not work.

use hammerstein::diagnosis::{
    CandidateId, Diagnoser, Domain, Estimates, Evidence, MissingEffect, Registry,
    ResidualAnalysis, ResidualTest, TestId, TestResult,
};
use hammerstein::faer::Mat;
use hammerstein::fit::HammersteinModel;
use hammerstein::regressors::{NonlinearitySpec, StaticNonlinearity};
use hammerstein::{Error, Hammerstein, IoData, Result, StateSpace};

/// v = a·u + c·u³: a gain with a cubic stiffening term.
#[derive(Debug, Clone)]
struct Cubic {
    a: f64,
    c: f64,
}

impl StaticNonlinearity<f64> for Cubic {
    fn name(&self) -> String {
        "cubic".into()
    }
    fn effects(&self) -> Vec<String> {
        vec!["stiffening".into()]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["a".into(), "c".into()]
    }
    fn params(&self) -> Vec<f64> {
        vec![self.a, self.c]
    }
    fn set_params(&mut self, theta: &[f64]) -> Result<()> {
        let &[a, c] = theta else {
            return Err(Error::InvalidParameter("cubic has two parameters".into()));
        };
        (self.a, self.c) = (a, c);
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        vec!["u".into(), "u^3".into()]
    }
    fn regressors(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), 2, |k, j| if j == 0 { u[k] } else { u[k].powi(3) })
    }
    fn gains(&self) -> Vec<f64> {
        vec![self.a, self.c]
    }
    fn update_from_gains(&mut self, g: &[f64], _u: &[f64]) -> Result<()> {
        self.set_params(g)
    }
    fn initialize(&mut self, _u: &[f64]) {
        (self.a, self.c) = (1.0, 0.0);
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "cubic".into(),
            config: Default::default(),
            param_names: self.param_names(),
            params: self.params(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<f64>> {
        Box::new(self.clone())
    }
}

/// The user's residual test: the raw u³ (not centred) in the residual, input-referred.
struct CubeTest;

impl ResidualTest for CubeTest {
    fn id(&self) -> TestId {
        TestId::User("raw-cube".into())
    }
    fn run(&self, a: &ResidualAnalysis) -> TestResult {
        let cube: Vec<f64> = a.u.iter().map(|x| x.powi(3)).collect();
        a.signature_test(self.id(), "u³ in the residual", &[cube], Domain::Input)
    }
    fn model_classes(&self) -> Vec<String> {
        vec!["a stiffening (cubic) input nonlinearity".into()]
    }
}

/// The user's candidate: u³ left in the residual means stiffening; refit with the cubic basis.
struct Stiffening;

impl MissingEffect<f64> for Stiffening {
    fn id(&self) -> CandidateId {
        CandidateId::user("stiffening")
    }
    fn applies_to(&self, model: &HammersteinModel<f64>) -> bool {
        model.nonlinearity().name() != "cubic"
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test(CubeTest.id())?;
        let sentence = format!("a cubic term in the residual ({})", t.detail);
        Some(Evidence::from_test(t, sentence, Estimates::new()))
    }
    fn apply(
        &self,
        model: &HammersteinModel<f64>,
        _a: &ResidualAnalysis,
    ) -> Result<Hammerstein<f64>> {
        let s = model.settings();
        Ok(Hammerstein::new(Box::new(Cubic { a: 1.0, c: 0.0 }))
            .horizon(s.options().horizon)
            .order(s.options().order.clone()))
    }
}

/// Uniform numbers in [lo, hi) from a small LCG (no rand dependency needed).
fn uniform(n: usize, lo: f64, hi: f64, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64)
        })
        .collect()
}

fn main() -> Result<()> {
    // truth: v = u + 0.3·u³ into G(z) = z⁻¹(1 + 0.5z⁻¹)/(1 − 0.2z⁻¹ + 0.35z⁻²), a little noise
    let g = StateSpace::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )?;
    let u = uniform(3000, -2.0, 2.0, 1);
    let y0 = g.simulate_siso(&Cubic { a: 1.0, c: 0.3 }.eval(&u), None)?;
    let noise = uniform(u.len(), -0.05, 0.05, 2);
    let y: Vec<f64> = y0.iter().zip(&noise).map(|(a, b)| a + b).collect();
    let data = IoData::siso(&u, &y)?;
    let (train, valid) = data.split_validation(0.3)?;

    // 1. the user basis, fitted by the loop
    let model = Hammerstein::new(Box::new(Cubic { a: 1.0, c: 0.0 })).fit(&train)?;
    let p = model.nonlinearity().params();
    println!(
        "cubic basis: a = {:.4}, c = {:.4}, train MSE {:.2e}",
        p[0],
        p[1],
        model.report().train_mse
    );
    assert!(
        (p[0] - 1.0).abs() < 0.02 && (p[1] - 0.3).abs() < 0.01,
        "cubic basis fit: {p:?}"
    );

    // 2. the user test and candidate, diagnosed next to the built-ins from a linear model
    let linear = Hammerstein::linear().fit(&train)?;
    let mut registry = Registry::builtin();
    registry.register(Box::new(Stiffening));
    let d = Diagnoser::new()
        .registry(registry)
        .register_test(Box::new(CubeTest))
        .diagnose(&linear, &train, &valid)?;
    let test = d
        .tests
        .iter()
        .find(|t| t.name == CubeTest.id())
        .expect("user test run");
    println!("raw-cube test: {}", test.detail);
    assert!(test.significant, "{test:?}");
    let outcome = d
        .candidates
        .iter()
        .find(|c| c.effect == CandidateId::user("stiffening"))
        .expect("candidate tried");
    let evidence = outcome.evidence.as_ref().expect("evidence computed");
    let refit = outcome.refit.as_ref().expect("refitted");
    println!(
        "stiffening: p = {:.1e}, validation MSE {:.2e} -> {:.2e}",
        evidence.p_value, refit.reference_mse, refit.validation_mse
    );
    assert!(evidence.significant, "{evidence:?}");
    assert!(
        refit.validation_mse < 0.1 * refit.reference_mse,
        "{refit:?}"
    );
    assert!(
        d.suggestions.iter().any(|s| s.effect == "stiffening"),
        "{:?}",
        d.suggestions
    );
    println!("ok: hammerstein embedded without default features");
    Ok(())
}
