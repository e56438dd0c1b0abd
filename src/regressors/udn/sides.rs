//! Which limits the UDN's saturation has: both (z1 above, z2 below), or one of them only.
//!
//! A system that clips on one side only (a diode, an end stop on one side) has no second limit:
//! a two-sided fit places it at the training input's extreme, where no sample measures it, and
//! credits the model with a parameter the record does not determine. The one-sided saturation
//! has the absent limit at ±∞ and not as a parameter: no regressor column (its indicator would be
//! 0 on every sample), no entry in the parameters, no standard error, nothing in the model file.

use crate::regressors::NonlinearitySpec;
use serde::{Deserialize, Serialize};

/// The limits of the UDN's saturation v = clamp(p·w, p·z2, p·z1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SaturationSides {
    /// Both limits, z1 > z2 (the paper's saturation).
    #[default]
    Both,
    /// The upper limit z1 only: v = min(p·w, p·z1), z2 = −∞.
    Upper,
    /// The lower limit z2 only: v = max(p·w, p·z2), z1 = +∞.
    Lower,
}

impl SaturationSides {
    /// Name as spelled in model files ("both", "upper" or "lower").
    pub fn name(self) -> &'static str {
        match self {
            SaturationSides::Both => "both",
            SaturationSides::Upper => "upper",
            SaturationSides::Lower => "lower",
        }
    }

    /// Parses [`name`](Self::name)'s spelling; `None` for anything else.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "both" => Some(SaturationSides::Both),
            "upper" => Some(SaturationSides::Upper),
            "lower" => Some(SaturationSides::Lower),
            _ => None,
        }
    }

    /// True when the upper limit z1 is a parameter.
    pub fn upper(self) -> bool {
        self != SaturationSides::Lower
    }

    /// True when the lower limit z2 is a parameter.
    pub fn lower(self) -> bool {
        self != SaturationSides::Upper
    }

    /// The saturation's limits in `spec` (a UDN's, or a Prandtl–Ishlinskii operator's around
    /// one): its `saturation_sides` key, [`Both`](Self::Both) when absent or unreadable.
    pub fn of_spec(spec: &NonlinearitySpec) -> Self {
        let udn = match spec.kind.as_str() {
            "prandtl-ishlinskii" => spec.config.get("base").and_then(|b| b.get("config")),
            _ => Some(&spec.config),
        };
        udn.and_then(|c| c.get("saturation_sides"))
            .and_then(|x| x.as_str())
            .and_then(Self::parse)
            .unwrap_or_default()
    }

    /// The absent limit's name and value ("z2", −∞ for [`Upper`](Self::Upper); "z1", +∞ for
    /// [`Lower`](Self::Lower)); `None` with both limits.
    pub fn absent(self) -> Option<(&'static str, f64)> {
        match self {
            SaturationSides::Both => None,
            SaturationSides::Upper => Some(("z2", f64::NEG_INFINITY)),
            SaturationSides::Lower => Some(("z1", f64::INFINITY)),
        }
    }

    /// The suffix of a UDN's name that says a one-sided saturation ("-upper-only",
    /// "-lower-only"; empty for both limits).
    pub fn suffix(self) -> &'static str {
        match self {
            SaturationSides::Both => "",
            SaturationSides::Upper => "-upper-only",
            SaturationSides::Lower => "-lower-only",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::SaturationSides;
    use crate::real::Real;
    use crate::regressors::{Effect, EffectSet, StaticNonlinearity, Udn, from_spec};
    use faer::Mat;
    use faer::linalg::solvers::SolveLstsq;

    fn set() -> EffectSet {
        EffectSet::of(&[Effect::DeadZone, Effect::Saturation])
    }

    /// An input over about [−2, 2] rising and falling through every level: two sines of
    /// incommensurate frequencies.
    fn input<T: Real>(n: usize) -> Vec<T> {
        (0..n)
            .map(|k| {
                let t = k as f64;
                T::lit(1.2 * (0.05 * t).sin() + 0.8 * (0.173 * t).sin())
            })
            .collect()
    }

    /// The one-sided layouts drop the absent limit's column and parameter; the kept limit acts,
    /// the absent one never clips (a far input passes on the slope).
    #[test]
    fn a_one_sided_saturation_has_one_limit_column_and_parameter() {
        let cases = [
            (
                SaturationSides::Both,
                vec!["p", "b", "z1", "z2"],
                "sat_high sat_low",
            ),
            (SaturationSides::Upper, vec!["p", "b", "z1"], "sat_high"),
            (SaturationSides::Lower, vec!["p", "b", "z2"], "sat_low"),
        ];
        for (sides, names, sat_cols) in cases {
            let udn = Udn::<f64>::new(set()).with_saturation_sides(sides).unwrap();
            assert_eq!(udn.saturation_sides(), sides);
            assert_eq!(udn.param_names(), names, "{sides:?}");
            let cols = udn.regressor_names();
            let sat: Vec<&str> = cols
                .iter()
                .map(String::as_str)
                .filter(|c| c.starts_with("sat_"))
                .collect();
            assert_eq!(sat.join(" "), sat_cols, "{sides:?}");
            assert_eq!(udn.n_regressors(), udn.regressors(&[0.5, -0.5]).ncols());
            let theta = match sides {
                SaturationSides::Both => vec![2.0, 0.1, 0.8, -0.6],
                SaturationSides::Upper => vec![2.0, 0.1, 0.8],
                SaturationSides::Lower => vec![2.0, 0.1, -0.6],
            };
            let mut m = udn.clone();
            m.set_params(&theta).unwrap();
            let v = m.eval(&[-1e6, 1e6]);
            let want_low = if sides.lower() {
                2.0 * -0.6
            } else {
                2.0 * (-1e6 + 0.1)
            };
            let want_high = if sides.upper() {
                2.0 * 0.8
            } else {
                2.0 * (1e6 - 0.1)
            };
            assert!((v[0] - want_low).abs() < 1e-6, "{sides:?}: {}", v[0]);
            assert!((v[1] - want_high).abs() < 1e-6, "{sides:?}: {}", v[1]);
            // the gains are finite (the absent limit is no column) and match the columns
            assert_eq!(m.gains().len(), m.n_regressors());
            assert!(m.gains().iter().all(|g| g.is_finite()));
        }
        // one-sided without a saturation, an unknown spelling: refused
        let dz = Udn::<f64>::new(EffectSet::of(&[Effect::DeadZone]));
        assert!(dz.with_saturation_sides(SaturationSides::Upper).is_err());
        assert_eq!(
            SaturationSides::parse("upper"),
            Some(SaturationSides::Upper)
        );
        assert_eq!(SaturationSides::parse("none"), None);
    }

    /// Names: the suffix is in the name, `by_name` reads it back (with the play suffix too).
    #[test]
    fn a_one_sided_saturation_is_named_and_found_by_name() {
        for (name, sides) in [
            ("dn7-upper-only", SaturationSides::Upper),
            ("dn8-lower-only", SaturationSides::Lower),
            ("sh-upper-only-play", SaturationSides::Upper),
            ("udn-lower-only", SaturationSides::Lower),
        ] {
            let u = Udn::<f64>::by_name(name).unwrap();
            assert_eq!(u.saturation_sides(), sides, "{name}");
            assert_eq!(StaticNonlinearity::<f64>::name(&u), name);
        }
        assert!(Udn::<f64>::by_name("linear-upper-only").is_err());
        assert!(Udn::<f64>::by_name("dn8-upper-only-lower-only").is_err());
    }

    /// The spec records the sides and holds the kept limit only (no infinity as a number);
    /// it rebuilds the same UDN, and a spec without the key (a two-sided file) reads as both.
    #[test]
    fn a_one_sided_spec_round_trips() {
        let mut u = Udn::<f64>::new(set())
            .with_saturation_sides(SaturationSides::Lower)
            .unwrap();
        u.set_params(&[1.3, 0.05, -0.7]).unwrap();
        let spec = u.spec();
        assert_eq!(spec.config["saturation_sides"], "lower");
        assert_eq!(SaturationSides::of_spec(&spec), SaturationSides::Lower);
        assert_eq!(SaturationSides::Lower.absent(), Some(("z1", f64::INFINITY)));
        let pi = crate::regressors::PrandtlIshlinskii::new(Box::new(u.clone()), 3).unwrap();
        assert_eq!(
            SaturationSides::of_spec(&StaticNonlinearity::<f64>::spec(&pi)),
            SaturationSides::Lower
        );
        assert_eq!(spec.param_names, ["p", "b", "z2"]);
        assert!(spec.params.iter().all(|x| x.is_finite()));
        let text = serde_json::to_string(&spec).unwrap();
        let back: crate::regressors::NonlinearitySpec = serde_json::from_str(&text).unwrap();
        let nl = from_spec::<f64>(&back).unwrap();
        assert_eq!(nl.spec(), spec);
        let x = input::<f64>(300);
        assert_eq!(nl.eval(&x), u.eval(&x));
        let mut two = back.clone();
        two.config
            .as_object_mut()
            .unwrap()
            .remove("saturation_sides");
        assert!(from_spec::<f64>(&two).is_err(), "three parameters for four");
        let mut odd = back;
        odd.config["saturation_sides"] = "left".into();
        assert!(from_spec::<f64>(&odd).is_err());
    }

    /// Least squares on the one-sided columns: with z1 anywhere between the two samples of w
    /// around the truth's limit the columns are the truth's, so the gains — and z1 = g_high / p —
    /// are the truth's to rounding, although z1 was set elsewhere.
    fn recovered_by_least_squares<T: Real>(tol: f64) {
        let (p, b, z1) = (1.5, 0.2, 0.9);
        let u = input::<T>(2000);
        let truth = Udn::<T>::new(set())
            .with_saturation_sides(SaturationSides::Upper)
            .and_then(|m| {
                let mut m = m;
                m.set_params(&[T::lit(p), T::lit(b), T::lit(z1)])?;
                Ok(m)
            })
            .unwrap();
        let v = truth.eval(&u);
        // w at the samples next to z1 (w = sign(u)·max(|u| − b, 0))
        let w: Vec<f64> = u
            .iter()
            .map(|x| {
                let x = x.as_f64();
                x.signum() * (x.abs() - b).max(0.0)
            })
            .collect();
        let above = w
            .iter()
            .copied()
            .filter(|&x| x > z1)
            .fold(f64::INFINITY, f64::min);
        let below = w
            .iter()
            .copied()
            .filter(|&x| x <= z1)
            .fold(f64::NEG_INFINITY, f64::max);
        let start = z1 + 0.5 * (above - z1).min(z1 - below);
        let mut m = truth.clone();
        m.set_params(&[T::one(), T::lit(b), T::lit(start)]).unwrap();
        let phi = m.regressors(&u);
        assert_eq!(phi.ncols(), 3);
        let rhs = Mat::<T>::from_fn(u.len(), 1, |k, _| v[k]);
        let g = phi.qr().solve_lstsq(&rhs);
        let g: Vec<T> = (0..phi.ncols()).map(|j| g[(j, 0)]).collect();
        m.update_from_gains(&g, &u).unwrap();
        let got = m.params();
        for (name, (x, want)) in ["p", "b", "z1"].iter().zip(got.iter().zip([p, b, z1])) {
            assert!(
                (x.as_f64() - want).abs() <= tol * want.abs(),
                "{name} = {x} vs {want} (start z1 {start})"
            );
        }
        assert!(!m.param_names().iter().any(|n| n == "z2"));
    }

    #[test]
    fn a_one_sided_saturation_is_recovered_by_least_squares_f64() {
        recovered_by_least_squares::<f64>(1e-12);
    }

    #[test]
    fn a_one_sided_saturation_is_recovered_by_least_squares_f32() {
        recovered_by_least_squares::<f32>(1e-5);
    }

    /// The zone guard keeps the absent limit at ±∞ (it would move a finite one inside the
    /// data) and the kept one inside the 3 %/97 % quantiles of w.
    #[test]
    fn the_zone_guard_leaves_the_absent_limit_out() {
        let u = input::<f64>(1000);
        for sides in [SaturationSides::Upper, SaturationSides::Lower] {
            let mut m = Udn::<f64>::new(set()).with_saturation_sides(sides).unwrap();
            m.initialize(&u);
            // gains that place the kept limit far outside the data: the guard brings it back
            let g = match sides {
                SaturationSides::Upper => vec![1.0, 0.1, 50.0],
                _ => vec![1.0, 0.1, -50.0],
            };
            m.update_from_gains(&g, &u).unwrap();
            let (z1, z2) = (m.z1, m.z2);
            if sides.upper() {
                assert!(
                    z1 < 1.9 && z1.is_finite() && z2 == f64::NEG_INFINITY,
                    "{z1} {z2}"
                );
            } else {
                assert!(
                    z2 > -1.9 && z2.is_finite() && z1 == f64::INFINITY,
                    "{z1} {z2}"
                );
            }
        }
    }
}
