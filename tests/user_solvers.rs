//! The Hammerstein loop with a subspace method and a linear-algebra backend defined here, outside
//! the library: both are called, and the fit equals the built-in MOESP/faer fit.

mod hammerstein_common;
use hammerstein::faer::{Mat, MatRef};
use hammerstein::fit::HammersteinModel;
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein::solvers::Svd;
use hammerstein::subspace::{Compression, Decomposition, Moesp, SubspaceMethod};
use hammerstein::{Faer, Hammerstein, IoData, LinAlg, Result};
use hammerstein_common::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// PO-MOESP that counts its decompositions (shares the counter with its horizon variants).
#[derive(Debug, Clone)]
struct CountingMoesp {
    inner: Moesp,
    calls: Arc<AtomicUsize>,
}

impl SubspaceMethod<f64> for CountingMoesp {
    fn name(&self) -> &'static str {
        "counting-moesp"
    }
    fn horizon(&self) -> usize {
        self.inner.horizon
    }
    fn decompose(
        &self,
        la: &dyn LinAlg<f64>,
        data: &[hammerstein::IoView<'_, f64>],
    ) -> Result<Decomposition<f64>> {
        self.calls.fetch_add(1, Ordering::Relaxed);
        self.inner.decompose(la, data)
    }
    fn realize_ac(
        &self,
        la: &dyn LinAlg<f64>,
        dec: &Decomposition<f64>,
        n: usize,
    ) -> Result<(Mat<f64>, Mat<f64>)> {
        self.inner.realize_ac(la, dec, n)
    }
    fn with_horizon(&self, horizon: usize) -> Option<Box<dyn SubspaceMethod<f64>>> {
        Some(Box::new(CountingMoesp {
            inner: Moesp {
                horizon,
                ..self.inner
            },
            calls: Arc::clone(&self.calls),
        }))
    }
}

/// The faer backend behind a counter of every call.
#[derive(Debug, Default)]
struct CountingFaer {
    inner: Faer,
    calls: AtomicUsize,
}

impl CountingFaer {
    fn tick(&self) {
        self.calls.fetch_add(1, Ordering::Relaxed);
    }
}

impl LinAlg<f64> for CountingFaer {
    fn name(&self) -> &'static str {
        "counting-faer"
    }
    fn qr_r(&self, a: MatRef<'_, f64>) -> Result<Mat<f64>> {
        self.tick();
        self.inner.qr_r(a)
    }
    fn svd(&self, a: MatRef<'_, f64>) -> Result<Svd<f64>> {
        self.tick();
        self.inner.svd(a)
    }
    fn singular_values(&self, a: MatRef<'_, f64>) -> Result<Vec<f64>> {
        self.tick();
        self.inner.singular_values(a)
    }
    fn lstsq(&self, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Result<Mat<f64>> {
        self.tick();
        self.inner.lstsq(a, b)
    }
    fn solve(&self, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Result<Mat<f64>> {
        self.tick();
        self.inner.solve(a, b)
    }
    fn cholesky_upper(&self, a: MatRef<'_, f64>) -> Result<Option<Mat<f64>>> {
        self.tick();
        self.inner.cholesky_upper(a)
    }
}

fn noisy_sh_record(seed: u64) -> IoData<f64> {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    add_noise(
        &record(&truth, &example1_input(1500, seed), 0.0),
        30.0,
        seed,
    )
}

fn max_param_diff(a: &HammersteinModel<f64>, b: &HammersteinModel<f64>) -> f64 {
    let (pa, pb) = (a.parameters(), b.parameters());
    assert_eq!(pa.len(), pb.len());
    pa.iter()
        .zip(&pb)
        .map(|((na, va), (nb, vb))| {
            assert_eq!(na, nb);
            (va - vb).abs() / vb.abs().max(1.0)
        })
        .fold(0.0, f64::max)
}

#[test]
fn loop_runs_with_a_user_method_and_backend_and_matches_the_builtin_fit() {
    let data = noisy_sh_record(3);
    let calls = Arc::new(AtomicUsize::new(0));
    let method = CountingMoesp {
        inner: Moesp::new(8).with_compression(Compression::Semidefinite),
        calls: Arc::clone(&calls),
    };
    let la = Arc::new(CountingFaer::default());
    let user = Hammerstein::<f64>::sh()
        .subspace_method(Arc::new(method))
        .linalg(la.clone())
        .fit(&data)
        .unwrap();
    let builtin = Hammerstein::<f64>::sh().fit(&data).unwrap();
    let n_method = calls.load(Ordering::Relaxed);
    let n_la = la.calls.load(Ordering::Relaxed);
    // every order candidate's loop decomposes at least once per iteration
    assert!(n_method >= 10, "user method called {n_method} times");
    assert!(n_la > n_method, "user backend called {n_la} times");
    assert_eq!(user.linear().order(), builtin.linear().order());
    let d = max_param_diff(&user, &builtin);
    assert!(d < 1e-9, "parameters differ by {d:e}");
    let (mu, mb) = (user.report().train_mse, builtin.report().train_mse);
    assert!((mu - mb).abs() <= 1e-9 * mb, "{mu} vs {mb}");
    // the settings name the user's solvers
    assert_eq!(user.settings().method_name(), "counting-moesp");
    assert_eq!(
        user.settings().user_linalg().map(|l| l.name()),
        Some("counting-faer")
    );
}

#[test]
fn a_method_without_horizon_changes_is_used_as_it_is() {
    /// MOESP that refuses other horizons (the trait's default `with_horizon`).
    #[derive(Debug)]
    struct Fixed(Moesp, Arc<AtomicUsize>);
    impl SubspaceMethod<f64> for Fixed {
        fn name(&self) -> &'static str {
            "fixed-moesp"
        }
        fn horizon(&self) -> usize {
            self.0.horizon
        }
        fn decompose(
            &self,
            la: &dyn LinAlg<f64>,
            data: &[hammerstein::IoView<'_, f64>],
        ) -> Result<Decomposition<f64>> {
            self.1.fetch_add(1, Ordering::Relaxed);
            self.0.decompose(la, data)
        }
        fn realize_ac(
            &self,
            la: &dyn LinAlg<f64>,
            dec: &Decomposition<f64>,
            n: usize,
        ) -> Result<(Mat<f64>, Mat<f64>)> {
            self.0.realize_ac(la, dec, n)
        }
    }
    let data = noisy_sh_record(5);
    let calls = Arc::new(AtomicUsize::new(0));
    let m = Hammerstein::<f64>::sh()
        .subspace_method(Arc::new(Fixed(Moesp::new(10), Arc::clone(&calls))))
        .fit(&data)
        .unwrap();
    assert!(calls.load(Ordering::Relaxed) > 0);
    assert_eq!(m.settings().options().horizon, 10);
    // the fit is still good: the relative training MSE is at the noise level (30 dB → 1e-3)
    let y = data.output(0);
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64;
    assert!(
        m.report().train_mse / var < 2e-3,
        "{}",
        m.report().train_mse / var
    );
}

#[test]
fn model_file_records_the_user_solvers_and_loads_with_the_enum_fallback() {
    let data = noisy_sh_record(7);
    let calls = Arc::new(AtomicUsize::new(0));
    let m = Hammerstein::<f64>::sh()
        .subspace_method(Arc::new(CountingMoesp {
            inner: Moesp::new(8),
            calls,
        }))
        .linalg(Arc::new(CountingFaer::default()))
        .fit(&data)
        .unwrap();
    let file = m.to_file();
    assert_eq!(
        file.settings.user_method.as_deref(),
        Some("user:counting-moesp")
    );
    assert_eq!(
        file.settings.user_backend.as_deref(),
        Some("user:counting-faer")
    );
    let text = serde_json::to_string(&file).unwrap();
    let back = HammersteinModel::from_json(&text).unwrap();
    assert!(back.settings().user_method().is_none());
    assert_eq!(back.settings().method_name(), "moesp");
    let u = data.input(0);
    let (a, b) = (m.simulate(&u).unwrap(), back.simulate(&u).unwrap());
    let d = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-9, "{d}");
}
