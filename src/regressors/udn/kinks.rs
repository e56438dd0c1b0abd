//! Where the UDN's saturation limits meet the samples of a record.
//!
//! v = clamp(p·w, p·z2, p·z1) + …: sample k is clipped by the upper limit when w(k) > z1 and by
//! the lower one when w(k) < z2, so the values of w over the record are the positions of both
//! limits (the record resolves a limit only to the interval between two of them, as for a
//! threshold: Chan 1993, Ann. Statist. 21(1), 520–533).

use super::Udn;
use crate::real::Real;
use crate::regressors::{Effect, StaticNonlinearity};

/// The indices of z1 and z2 when the saturation is active; none otherwise.
pub(super) fn params<T: Real>(udn: &Udn<T>) -> Vec<usize> {
    if !udn.has(Effect::Saturation) {
        return Vec::new();
    }
    StaticNonlinearity::<T>::param_names(udn)
        .iter()
        .enumerate()
        .filter(|(_, n)| *n == "z1" || *n == "z2")
        .map(|(i, _)| i)
        .collect()
}

/// The dead-zone output w at every sample of `u` (the signal both limits clip) when `index` is
/// a saturation limit; empty otherwise.
pub(super) fn positions<T: Real>(udn: &Udn<T>, index: usize, u: &[T]) -> Vec<T> {
    if !params(udn).contains(&index) {
        return Vec::new();
    }
    let mut w = vec![T::zero(); u.len()];
    udn.for_each(u, |k, _, _, p, _| w[k] = p.w);
    w
}

#[cfg(test)]
mod tests {
    use crate::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};

    /// Samples whose position lies above z1 are the ones the upper limit clips: moving z1
    /// between two consecutive positions moves v only on the samples above it, by p·Δz1.
    #[test]
    fn positions_are_the_clipped_signal() {
        let set = EffectSet::of(&[Effect::DeadZone, Effect::Saturation]);
        let (p, b, z1, z2) = (1.5, 0.2, 0.9, -0.7);
        let udn = Udn::<f64>::with_params(set, &[p, b, z1, z2]).unwrap();
        let u: Vec<f64> = (0..500).map(|k| 1.5 * (0.05 * k as f64).sin()).collect();
        let kinks = udn.kink_params();
        assert_eq!(kinks.len(), 2);
        let iz1 = kinks[0];
        let w = udn.kink_positions(iz1, &u);
        assert_eq!(w.len(), u.len());
        let v = udn.eval(&u);
        for (k, (&wk, &vk)) in w.iter().zip(&v).enumerate() {
            if wk > z1 {
                assert!((vk - p * z1).abs() < 1e-12, "sample {k} not clipped high");
            } else if wk < z2 {
                assert!((vk - p * z2).abs() < 1e-12, "sample {k} not clipped low");
            } else {
                assert!((vk - p * wk).abs() < 1e-12, "sample {k} clipped");
            }
        }
        // a parameter that places no kink, and a UDN without saturation, have no positions
        assert!(udn.kink_positions(0, &u).is_empty());
        let dz = Udn::<f64>::with_params(EffectSet::of(&[Effect::DeadZone]), &[1.5, 0.2]).unwrap();
        assert!(dz.kink_params().is_empty());
    }
}
