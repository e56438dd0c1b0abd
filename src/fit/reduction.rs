//! Order-reduction starts of the automatic order's search (`order_selection.rs`): the chosen
//! model's block with one real mode, or one complex pair or two real modes, dropped (modal
//! truncation, e.g. Ljung 1999, *System Identification*, § 16.7 on model reduction as a start for
//! a lower order). The remaining poles become an observable pair (A, C) in observer canonical
//! form; the reduced block's B, D and x0 are then fitted again by least squares given θ
//! (`Problem::evaluate`), so a mode a zero nearly cancels drops out with its residue spread over
//! the others. An order-n fit can end in a local minimum that a model of higher order, which nests
//! the true one, avoids; the reduced start takes the lower order from there.

use crate::real::Real;
use faer::Mat;

/// Imaginary parts below this (relative to the modulus, at least this absolute) count as real.
const REAL_TOL: f64 = 1e-9;

/// The observable pairs (A, C) of order `k` left when modes of `poles` (the conjugate pairs
/// listed both) are dropped: every way of dropping one real pole (k = n − 1) or one complex pair
/// or two real poles (k = n − 2). Empty for other k.
pub(crate) fn reduced_pairs<T: Real>(poles: &[(f64, f64)], k: usize) -> Vec<(Mat<T>, Mat<T>)> {
    let units = modes(poles);
    let n = poles.len();
    let mut out = Vec::new();
    if k == 0 || k >= n {
        return out;
    }
    let drop = n - k;
    let keep_without = |gone: &[usize]| -> Vec<(f64, f64)> {
        units
            .iter()
            .enumerate()
            .filter(|(i, _)| !gone.contains(i))
            .flat_map(|(_, u)| u.iter().copied())
            .collect()
    };
    for i in 0..units.len() {
        if units[i].len() == drop {
            out.push(observer_form(&keep_without(&[i])));
        }
        if drop == 2 && units[i].len() == 1 {
            for j in i + 1..units.len() {
                if units[j].len() == 1 {
                    out.push(observer_form(&keep_without(&[i, j])));
                }
            }
        }
    }
    out
}

/// The poles grouped into modes: a real pole alone, a complex one with its conjugate (the pole
/// with positive imaginary part and the nearest one with negative imaginary part).
fn modes(poles: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let is_real = |p: &(f64, f64)| p.1.abs() <= REAL_TOL * p.0.hypot(p.1).max(1.0);
    let mut out: Vec<Vec<(f64, f64)>> = poles
        .iter()
        .filter(|p| is_real(p))
        .map(|&p| vec![(p.0, 0.0)])
        .collect();
    let mut lower: Vec<(f64, f64)> = poles
        .iter()
        .filter(|p| !is_real(p) && p.1 < 0.0)
        .copied()
        .collect();
    for &p in poles.iter().filter(|p| !is_real(p) && p.1 > 0.0) {
        let nearest = lower
            .iter()
            .enumerate()
            .min_by(|a, b| {
                let d = |q: &(f64, f64)| (q.0 - p.0).hypot(q.1 + p.1);
                d(a.1).total_cmp(&d(b.1))
            })
            .map(|(i, _)| i);
        if let Some(i) = nearest {
            lower.swap_remove(i);
        }
        out.push(vec![p, (p.0, -p.1)]);
    }
    out
}

/// (A, C) in observer canonical form with the characteristic polynomial whose roots are
/// `poles` (conjugates listed both): A's first column −a₁ … −a_k, ones above the diagonal,
/// C = e₁ᵀ (observable for any polynomial).
fn observer_form<T: Real>(poles: &[(f64, f64)]) -> (Mat<T>, Mat<T>) {
    let k = poles.len();
    // Π (z − p): complex coefficients, highest power first; real up to round-off
    let mut coef: Vec<(f64, f64)> = vec![(1.0, 0.0)];
    for &(pr, pi) in poles {
        let mut next = vec![(0.0, 0.0); coef.len() + 1];
        for (i, &(cr, ci)) in coef.iter().enumerate() {
            next[i].0 += cr;
            next[i].1 += ci;
            next[i + 1].0 -= cr * pr - ci * pi;
            next[i + 1].1 -= cr * pi + ci * pr;
        }
        coef = next;
    }
    let a = Mat::from_fn(k, k, |i, j| {
        if j == 0 {
            T::lit(-coef[i + 1].0)
        } else if j == i + 1 {
            T::one()
        } else {
            T::zero()
        }
    });
    let c = Mat::from_fn(1, k, |_, j| if j == 0 { T::one() } else { T::zero() });
    (a, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::statespace::StateSpace;

    fn poles_of(a: &Mat<f64>) -> Vec<(f64, f64)> {
        let k = a.nrows();
        let ss = StateSpace::new(
            a.clone(),
            Mat::from_fn(k, 1, |_, _| 1.0),
            Mat::from_fn(1, k, |_, j| f64::from(u8::from(j == 0))),
            Mat::zeros(1, 1),
        )
        .unwrap();
        let mut p = ss.poles().unwrap();
        p.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
        p
    }

    #[test]
    fn dropping_one_real_pole_keeps_the_others() {
        let poles = [(0.5, 0.0), (0.6, 0.3), (0.6, -0.3), (-0.2, 0.0)];
        let r = reduced_pairs::<f64>(&poles, 3);
        // two real poles to drop, the pair cannot be dropped alone to reach order 3
        assert_eq!(r.len(), 2);
        let p = poles_of(&r[0].0);
        let want = [(-0.2, 0.0), (0.6, -0.3), (0.6, 0.3)];
        for (x, w) in p.iter().zip(want) {
            assert!(
                (x.0 - w.0).abs() < 1e-9 && (x.1 - w.1).abs() < 1e-9,
                "{p:?}"
            );
        }
    }

    #[test]
    fn order_two_below_drops_the_pair_or_two_reals() {
        let poles = [(0.5, 0.0), (0.6, 0.3), (0.6, -0.3), (-0.2, 0.0)];
        let r = reduced_pairs::<f64>(&poles, 2);
        assert_eq!(r.len(), 2);
        let sets: Vec<Vec<(f64, f64)>> = r.iter().map(|(a, _)| poles_of(a)).collect();
        assert!(
            sets.iter()
                .any(|p| (p[0].0 + 0.2).abs() < 1e-9 && (p[1].0 - 0.5).abs() < 1e-9)
        );
        assert!(sets.iter().any(|p| (p[0].1 + 0.3).abs() < 1e-9));
        assert!(reduced_pairs::<f64>(&poles, 4).is_empty());
        assert!(reduced_pairs::<f64>(&poles, 0).is_empty());
    }
}
