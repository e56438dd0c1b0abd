//! A user-defined missing effect (Coulomb friction, a sign(u) column) registered next to the
//! built-ins is tested, refitted and ranked like them.

mod common;

use common::{InputKind, add_noise, input, paper_block};
use faer::Mat;
use hammerstein::diagnosis::{
    CandidateId, Diagnoser, Domain, Estimates, Evidence, MissingEffect, Quantity, Registry,
    ResidualAnalysis, Source,
};
use hammerstein::fit::{Hammerstein, HammersteinModel};
use hammerstein::regressors::{NonlinearitySpec, StaticNonlinearity};
use hammerstein::{IoData, Result};

/// v = p·u + c·sign(u): a gain with Coulomb friction.
#[derive(Debug, Clone)]
struct GainCoulomb {
    p: f64,
    c: f64,
}

impl StaticNonlinearity<f64> for GainCoulomb {
    fn name(&self) -> String {
        "gain+coulomb".into()
    }
    fn effects(&self) -> Vec<String> {
        vec!["coulomb".into()]
    }
    fn param_names(&self) -> Vec<String> {
        vec!["p".into(), "c".into()]
    }
    fn params(&self) -> Vec<f64> {
        vec![self.p, self.c]
    }
    fn set_params(&mut self, theta: &[f64]) -> Result<()> {
        if theta.len() != 2 {
            return Err(hammerstein::Error::InvalidParameter(
                "two parameters".into(),
            ));
        }
        self.p = theta[0];
        self.c = theta[1];
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        vec!["u".into(), "sign(u)".into()]
    }
    fn regressors(&self, u: &[f64]) -> Mat<f64> {
        Mat::from_fn(u.len(), 2, |k, j| {
            if j == 0 {
                u[k]
            } else if u[k] > 0.0 {
                1.0
            } else if u[k] < 0.0 {
                -1.0
            } else {
                0.0
            }
        })
    }
    fn gains(&self) -> Vec<f64> {
        vec![self.p, self.c]
    }
    fn update_from_gains(&mut self, g: &[f64], _u: &[f64]) -> Result<()> {
        self.set_params(g)
    }
    fn initialize(&mut self, _u: &[f64]) {
        self.p = 1.0;
        self.c = 0.0;
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "gain+coulomb".into(),
            config: serde_json::Value::Null,
            param_names: self.param_names(),
            params: self.params(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<f64>> {
        Box::new(self.clone())
    }
}

/// The user's candidate: evidence from a sign(u) signature test, refit with the new basis.
struct Coulomb;

impl MissingEffect<f64> for Coulomb {
    fn id(&self) -> CandidateId {
        CandidateId::user("coulomb")
    }
    fn applies_to(&self, model: &HammersteinModel<f64>) -> bool {
        model.nonlinearity().effects().is_empty()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let sign: Vec<f64> = a.u.iter().map(|x| x.signum()).collect();
        let t = a.signature_test("coulomb", "sign(u) in the residual", &[sign], Domain::Input);
        let c = t.coefficients.first().copied();
        let sentence = format!("a Coulomb step ±{:.3} ({})", c.unwrap_or(0.0), t.detail);
        let est = Estimates::residual([(Quantity::User("friction".into()), c)]);
        Some(Evidence::from_test(&t, sentence, est))
    }
    fn apply(
        &self,
        model: &HammersteinModel<f64>,
        _a: &ResidualAnalysis,
    ) -> Result<Hammerstein<f64>> {
        let s = model.settings();
        Ok(Hammerstein::new(Box::new(GainCoulomb { p: 1.0, c: 0.0 }))
            .method(s.options().method)
            .horizon(s.options().horizon)
            .order(s.options().order.clone())
            .delay(s.options().delay)
            .offset(s.options().offset)
            .seed(s.options().seed))
    }
    fn refit_estimate(&self, model: &HammersteinModel<f64>) -> Estimates {
        Estimates::of_parameters(model, &["c"])
    }
}

fn record() -> (IoData<f64>, IoData<f64>, f64) {
    let u = input(InputKind::Uniform, 3000, 3.0, 21);
    let v: Vec<f64> = u.iter().map(|&x| 2.0 * x + 0.6 * x.signum()).collect();
    let y0 = paper_block().simulate_siso(&v, None).unwrap();
    let noise = 0.05;
    let y = add_noise(&y0, noise, 21);
    let d = IoData::siso(&u, &y).unwrap();
    let (a, b) = d.split_validation(0.3).unwrap();
    (a, b, noise)
}

#[test]
fn user_effect_is_tested_refitted_and_ranked() {
    let (train, val, noise) = record();
    let model = Hammerstein::linear().fit(&train).unwrap();
    // without the built-in preload (which can express a sign step with b = 0) the user's effect wins
    let mut reg = Registry::builtin();
    assert!(reg.remove("preload"));
    reg.register(Box::new(Coulomb));
    let d = Diagnoser::new()
        .registry(reg)
        .diagnose(&model, &train, &val)
        .unwrap();
    assert!(!d.adequate);
    let top = &d.suggestions[0];
    assert_eq!(top.effect, "coulomb", "{:#?}", d.suggestions);
    assert!(top.validation_mse_after < 1.5 * noise, "{top:?}");
    let c = top
        .estimate
        .parameter("c")
        .expect("the refit's c is quoted");
    assert!((c.value - 0.6).abs() < 0.1, "{top:?}");
    // with its standard error from the refit, and the residual's own reading of the step
    assert!(
        c.standard_error.is_some_and(|se| se > 0.0 && se < 0.1),
        "{c:?}"
    );
    let friction = top
        .estimate
        .get(Source::Residual, &Quantity::User("friction".into()))
        .expect("the evidence's estimate is quoted");
    assert!(friction.value.abs() > 0.1, "{friction:?}");
    assert_eq!(friction.key(), "residual_friction");
    // with the full registry it is ranked among the built-ins (next to the equivalent preload)
    let d = Diagnoser::new()
        .register(Box::new(Coulomb))
        .diagnose(&model, &train, &val)
        .unwrap();
    let names: Vec<&str> = d.suggestions.iter().map(|s| s.effect.as_str()).collect();
    let pos = names.iter().position(|n| *n == "coulomb");
    assert!(pos.is_some_and(|p| p <= 1), "{names:?}");
}
