//! Where the UDN's preload jumps meet the samples of a record, as values of a or b.
//!
//! With preload the UDN's output steps by e1 (e2) where x = u − a·s crosses +b (−b), s the
//! direction of motion (the non-play form). Sample k therefore changes side of a jump when b
//! passes |u(k) − a·s(k)| (a held), or when a passes s(k)·(u(k) ∓ b) (b held). Between two
//! consecutive such values no sample changes side: the record resolves the parameter only to
//! that interval (the least-squares estimate of a threshold is an interval between order
//! statistics: Chan 1993, Ann. Statist. 21(1), 520–533).

use super::Udn;
use crate::real::Real;
use crate::regressors::direction::DirectionTracker;
use crate::regressors::{Effect, StaticNonlinearity};

/// The values of parameter `index` (a or b) at which some sample of `u` crosses a preload jump,
/// the other parameters held; empty when the parameter moves no jump or the form is not covered
/// (the play operator's state, a dead-zone tied to the hysteresis width).
pub(super) fn positions<T: Real>(udn: &Udn<T>, index: usize, u: &[T]) -> Vec<T> {
    if !udn.has(Effect::Preload) || udn.play() || udn.tied {
        return Vec::new();
    }
    let names = StaticNonlinearity::<T>::param_names(udn);
    let Some(name) = names.get(index) else {
        return Vec::new();
    };
    let (a, b) = (udn.a_eff(), udn.b_eff());
    let mut dir = DirectionTracker::<T>::with_initial(udn.s0);
    match name.as_str() {
        "b" if udn.has(Effect::DeadZone) => {
            u.iter().map(|&uk| (uk - a * dir.next(uk)).abs()).collect()
        }
        "a" if udn.has(Effect::Hysteresis) => u
            .iter()
            .flat_map(|&uk| {
                let s = dir.next(uk);
                [s * (uk - b), s * (uk + b)]
            })
            .collect(),
        _ => Vec::new(),
    }
}

/// The step of v where a sample crosses a preload jump that parameter `index` moves: e1 or e2
/// at x = ±b (the larger) with a dead-zone, e1 − e2 at x = 0 without; zero when it moves none.
pub(super) fn step<T: Real>(udn: &Udn<T>, index: usize) -> T {
    if !StaticNonlinearity::<T>::jump_params(udn).contains(&index) {
        return T::zero();
    }
    if udn.has(Effect::DeadZone) {
        udn.e1.abs().max(udn.e2.abs())
    } else {
        (udn.e1 - udn.e2).abs()
    }
}

#[cfg(test)]
mod tests {
    use crate::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};

    /// The step is what v changes by as a sample crosses the jump: e1 − e2 at x = 0 without a
    /// dead-zone, the larger preload with one; zero for a parameter that moves no jump.
    #[test]
    fn step_is_the_change_of_v_across_the_jump() {
        let set = EffectSet::of(&[Effect::Hysteresis, Effect::Preload]);
        let udn = Udn::<f64>::with_params(set, &[1.5, 0.2, 0.3, -0.4]).unwrap();
        let ia = 1;
        // a rising ramp crosses x = u − a = 0 once, between two samples (none exactly on it):
        // the largest change between samples
        let u: Vec<f64> = (0..4000).map(|k| (k as f64 + 0.5) * 1e-4).collect();
        let v = udn.eval(&u);
        let across = v
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        let s = udn.jump_step(ia).unwrap();
        assert!((s - across).abs() < 1e-3, "{s} vs {across}");
        assert_eq!(udn.jump_step(0), Some(0.0));
        let set = EffectSet::of(&[Effect::DeadZone, Effect::Preload]);
        let udn = Udn::<f64>::with_params(set, &[1.5, 0.5, 0.3, -0.4]).unwrap();
        assert_eq!(udn.jump_step(1), Some(0.4));
    }

    /// Between two consecutive positions of b no sample changes side (v moves by at most p·Δb);
    /// across one, the sample sitting there jumps by about a preload step.
    #[test]
    fn b_positions_are_where_samples_change_side() {
        let set = EffectSet::of(&[Effect::Hysteresis, Effect::DeadZone, Effect::Preload]);
        let (p, a, b, e1, e2) = (1.5, 0.2, 0.5, 0.3, -0.4);
        let udn = Udn::<f64>::with_params(set, &[p, a, b, e1, e2]).unwrap();
        let u: Vec<f64> = (0..400).map(|k| 2.0 * (0.037 * k as f64).sin()).collect();
        let names = StaticNonlinearity::<f64>::param_names(&udn);
        let ib = names.iter().position(|n| n == "b").unwrap();
        let mut pos = udn.jump_positions(ib, &u);
        assert_eq!(pos.len(), u.len());
        pos.sort_by(f64::total_cmp);
        let above = *pos.iter().find(|&&x| x > b).unwrap();
        let below = *pos.iter().rev().find(|&&x| x <= b).unwrap();
        let at = |bb: f64| {
            let mut m = udn.clone();
            let mut th = m.params();
            th[ib] = bb;
            m.set_params(&th).unwrap();
            m.eval(&u)
        };
        let v0 = at(below + 0.25 * (above - below));
        let v1 = at(below + 0.75 * (above - below));
        let inside = v0
            .iter()
            .zip(&v1)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(inside <= p * (above - below) + 1e-12, "{inside}");
        let v2 = at(above + 1e-9);
        let across = v1
            .iter()
            .zip(&v2)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(across > 0.5 * e1.abs().min(e2.abs()), "{across}");
    }
}
