//! Shared helpers of the subspace tests: known systems, data, invariant comparisons.
#![allow(dead_code)]

use hammerstein::{IoData, Real, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

#[path = "../common/paper.rs"]
mod paper;

/// The paper's G(z) (`paper::paper_block`), the subspace tests' SISO system.
pub fn paper_siso() -> StateSpace<f64> {
    paper::paper_block()
}

/// A 2-input 2-output order-4 system with a feed-through (poles 0.8, −0.5, 0.3 ± 0.4j).
pub fn mimo4() -> StateSpace<f64> {
    StateSpace::from_rows(
        &[
            &[0.8, 0.0, 0.0, 0.0],
            &[0.0, -0.5, 0.0, 0.0],
            &[0.0, 0.0, 0.3, 0.4],
            &[0.0, 0.0, -0.4, 0.3],
        ],
        &[&[1.0, 0.0], &[0.5, 1.0], &[0.0, 0.7], &[1.0, -0.4]],
        &[&[1.0, 0.5, 1.0, 0.0], &[0.0, 1.0, 0.3, 1.0]],
        &[&[0.2, 0.0], &[0.0, -0.1]],
    )
    .unwrap()
}

/// Simulated record (white uniform inputs in [-3, 3], optional output noise std, nonzero x0).
pub fn simulate<T: Real>(sys: &StateSpace<f64>, n: usize, noise: f64, seed: u64) -> IoData<T> {
    let mut rng = StdRng::seed_from_u64(seed);
    let m = sys.n_inputs();
    let u = faer::Mat::from_fn(n, m, |_, _| rng.random_range(-3.0..3.0));
    let x0: Vec<f64> = (0..sys.order()).map(|k| 0.3 - 0.2 * k as f64).collect();
    let mut y = sys.simulate(u.as_ref(), Some(&x0)).unwrap();
    if noise > 0.0 {
        let nd = Normal::new(0.0, noise).unwrap();
        for j in 0..y.ncols() {
            for i in 0..y.nrows() {
                y[(i, j)] += nd.sample(&mut rng);
            }
        }
    }
    IoData::new(
        faer::Mat::from_fn(n, m, |i, j| T::lit(u[(i, j)])),
        faer::Mat::from_fn(n, y.ncols(), |i, j| T::lit(y[(i, j)])),
    )
    .unwrap()
}

/// Largest distance between matched poles (greedy nearest matching).
pub fn pole_error(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    assert_eq!(a.len(), b.len(), "pole counts differ: {a:?} vs {b:?}");
    let mut used = vec![false; b.len()];
    let mut worst: f64 = 0.0;
    for p in a {
        let (k, d) = b
            .iter()
            .enumerate()
            .filter(|(k, _)| !used[*k])
            .map(|(k, q)| (k, (p.0 - q.0).hypot(p.1 - q.1)))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .unwrap();
        used[k] = true;
        worst = worst.max(d);
    }
    worst
}

/// Relative 2-norm error of D and the first `count` Markov parameters C A^k B.
pub fn markov_rel_error<T: Real>(
    est: &StateSpace<T>,
    truth: &StateSpace<f64>,
    count: usize,
) -> f64 {
    let he = est.markov_parameters(count);
    let ht = truth.markov_parameters(count);
    let (mut num, mut den) = (0.0, 0.0);
    for o in 0..truth.n_outputs() {
        for q in 0..truth.n_inputs() {
            let d = est.d[(o, q)].as_f64() - truth.d[(o, q)];
            num += d * d;
            den += truth.d[(o, q)].powi(2);
            for k in 0..count {
                let d = he[k][(o, q)].as_f64() - ht[k][(o, q)];
                num += d * d;
                den += ht[k][(o, q)].powi(2);
            }
        }
    }
    (num / den).sqrt()
}

/// Fit % per output of a simulation from `x0`: 100·(1 − ‖y − ŷ‖/‖y − ȳ‖).
pub fn fit_percent<T: Real>(model: &StateSpace<T>, data: &IoData<T>, x0: Option<&[T]>) -> Vec<f64> {
    let yhat = model.simulate(data.u(), x0).unwrap();
    (0..data.n_outputs())
        .map(|o| {
            let y = data.output(o);
            let mean = y.iter().map(|v| v.as_f64()).sum::<f64>() / y.len() as f64;
            let (mut e2, mut d2) = (0.0, 0.0);
            for (k, v) in y.iter().enumerate() {
                e2 += (v.as_f64() - yhat[(k, o)].as_f64()).powi(2);
                d2 += (v.as_f64() - mean).powi(2);
            }
            100.0 * (1.0 - (e2 / d2).sqrt())
        })
        .collect()
}
