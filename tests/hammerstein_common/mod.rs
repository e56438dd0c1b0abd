//! Shared test helpers: the paper's Example 1 system and a user-defined SH basis written against the
//! public `StaticNonlinearity` trait only (it also serves as the "user-defined basis" of the tests).
#![allow(dead_code)]

use faer::Mat;
use hammerstein::regressors::{NonlinearitySpec, StaticNonlinearity};
use hammerstein::{Error, IoData, Real, Result, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};

#[path = "../common/paper.rs"]
mod paper;

/// Example 1's linear block (`paper::paper_block`) in the scalar type T.
pub fn example1_linear<T: Real>() -> StateSpace<T> {
    paper::paper_block().cast()
}

/// 2000 samples u ~ U[−3, 3] (seeded).
pub fn example1_input<T: Real>(n: usize, seed: u64) -> Vec<T> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| T::lit(rng.random_range(-3.0..3.0)))
        .collect()
}

/// Noise-free record: y = G(N(u)) from a zero state, plus `offset`.
pub fn record<T: Real>(nl: &dyn StaticNonlinearity<T>, u: &[T], offset: f64) -> IoData<T> {
    let v = nl.eval(u);
    let y: Vec<T> = example1_linear::<T>()
        .simulate_siso(&v, None)
        .unwrap()
        .into_iter()
        .map(|x| x + T::lit(offset))
        .collect();
    IoData::siso(u, &y).unwrap()
}

/// Adds white Gaussian noise at `snr_db` (10·log10(var y / var ε)), seeded.
pub fn add_noise<T: Real>(data: &IoData<T>, snr_db: f64, seed: u64) -> IoData<T> {
    use rand_distr::{Distribution, Normal};
    let y = data.output(0);
    let n = y.len() as f64;
    let mean = y.iter().map(|v| v.as_f64()).sum::<f64>() / n;
    let var = y.iter().map(|v| (v.as_f64() - mean).powi(2)).sum::<f64>() / n;
    let sd = (var / 10f64.powf(snr_db / 10.0)).sqrt();
    let normal = Normal::new(0.0, sd).unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    let yn: Vec<T> = y
        .iter()
        .map(|&v| v + T::lit(normal.sample(&mut rng)))
        .collect();
    IoData::siso(&data.input(0), &yn).unwrap()
}

/// Input direction: +1 rising, −1 falling, the previous direction when held (+1 at the start).
pub fn directions<T: Real>(u: &[T]) -> Vec<T> {
    let mut s = T::one();
    let mut out = Vec::with_capacity(u.len());
    for k in 0..u.len() {
        if k > 0 {
            if u[k] > u[k - 1] {
                s = T::one();
            } else if u[k] < u[k - 1] {
                s = -T::one();
            }
        }
        out.push(s);
    }
    out
}

/// A user-defined saturation-with-hysteresis basis: θ = (p, a, z1, z2),
/// g = [p, p·a, p·z1, p·z2], φ = [u·L, −s·L, H1, H2] with x = u − a·s.
#[derive(Debug, Clone)]
pub struct UserSh<T: Real> {
    pub theta: [T; 4],
}

impl<T: Real> UserSh<T> {
    pub fn new(p: f64, a: f64, z1: f64, z2: f64) -> Self {
        Self {
            theta: [T::lit(p), T::lit(a), T::lit(z1), T::lit(z2)],
        }
    }
}

fn quantile<T: Real>(x: &[T], q: f64) -> T {
    let mut v = x.to_vec();
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[((v.len() - 1) as f64 * q).round() as usize]
}

impl<T: Real> StaticNonlinearity<T> for UserSh<T> {
    fn name(&self) -> String {
        "user-sh".into()
    }
    fn effects(&self) -> Vec<String> {
        vec!["hysteresis".into(), "saturation".into()]
    }
    fn param_names(&self) -> Vec<String> {
        ["p", "a", "z1", "z2"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }
    fn params(&self) -> Vec<T> {
        self.theta.to_vec()
    }
    fn set_params(&mut self, theta: &[T]) -> Result<()> {
        if theta.len() != 4 || theta.iter().any(|t| !t.is_finite()) {
            return Err(Error::InvalidParameter(
                "user-sh needs 4 finite parameters".into(),
            ));
        }
        if theta[1] < T::zero()
            || theta[2].partial_cmp(&theta[3]) != Some(std::cmp::Ordering::Greater)
        {
            return Err(Error::InvalidParameter(
                "user-sh needs a ≥ 0 and z1 > z2".into(),
            ));
        }
        self.theta.copy_from_slice(theta);
        Ok(())
    }
    fn regressor_names(&self) -> Vec<String> {
        ["u·L", "-s·L", "H1", "H2"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }
    fn regressors(&self, u: &[T]) -> Mat<T> {
        let [_, a, z1, z2] = self.theta;
        let s = directions(u);
        Mat::from_fn(u.len(), 4, |k, j| {
            let x = u[k] - a * s[k];
            let h1 = x >= z1;
            let h2 = x <= z2;
            let l = !h1 && !h2;
            let one = |b: bool| if b { T::one() } else { T::zero() };
            match j {
                0 => u[k] * one(l),
                1 => -s[k] * one(l),
                2 => one(h1),
                _ => one(h2),
            }
        })
    }
    fn gains(&self) -> Vec<T> {
        let [p, a, z1, z2] = self.theta;
        vec![p, p * a, p * z1, p * z2]
    }
    fn update_from_gains(&mut self, g: &[T], u: &[T]) -> Result<()> {
        let p = g[0];
        if p == T::zero() {
            return Err(Error::Identification("zero gain".into()));
        }
        let a = (g[1] / p).max(T::zero());
        // zone guard: keep at least 3 % of the samples in each saturation zone and on the slope
        let s = directions(u);
        let x: Vec<T> = u.iter().zip(&s).map(|(&u, &s)| u - a * s).collect();
        let hi = quantile(&x, 0.97);
        let lo = quantile(&x, 0.03);
        let z1 = (g[2] / p).min(hi);
        let z2 = (g[3] / p).max(lo);
        if z1.partial_cmp(&z2) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Identification("saturation limits crossed".into()));
        }
        self.theta = [p, a, z1, z2];
        Ok(())
    }
    fn initialize(&mut self, u: &[T]) {
        self.theta = [T::one(), T::zero(), quantile(u, 0.9), quantile(u, 0.1)];
    }
    fn spec(&self) -> NonlinearitySpec {
        NonlinearitySpec {
            kind: "user-sh".into(),
            config: serde_json::Value::Null,
            param_names: self.param_names(),
            params: self.theta.iter().map(|t| t.as_f64()).collect(),
        }
    }
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>> {
        Box::new(self.clone())
    }
}

/// Rebuilds a `UserSh` from its spec (for `load_with`).
pub fn user_sh_from_spec(spec: &NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<f64>>> {
    if spec.kind != "user-sh" || spec.params.len() != 4 {
        return Err(Error::ModelFormat(format!(
            "not a user-sh spec: {}",
            spec.kind
        )));
    }
    let p = &spec.params;
    Ok(Box::new(UserSh::<f64>::new(p[0], p[1], p[2], p[3])))
}

/// Asserts |got − want| ≤ tol with a message.
pub fn close(name: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{name}: got {got}, want {want} (tolerance {tol})"
    );
}
