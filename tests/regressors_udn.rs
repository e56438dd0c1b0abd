//! UDN regressors against the piecewise definition (NOTES.md), for all 16 effect subsets, the
//! tied DN1/DN2 forms and the play (backlash) form; gains round trip; zone guard; typed errors.

use hammerstein::Error;
use hammerstein::regressors::{
    Effect, EffectSet, HysteresisForm, StaticNonlinearity, Udn, directions, from_spec,
};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Uniform input in [-3, 3] with ~20 % held samples (exercises the direction rule).
fn input(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut u: Vec<f64> = Vec::with_capacity(n);
    for k in 0..n {
        if k > 0 && rng.random_range(0.0..1.0) < 0.2 {
            u.push(u[k - 1]);
        } else {
            u.push(rng.random_range(-3.0..3.0));
        }
    }
    u
}

/// Full parameter vector [p, a, b, z1, z2, e1, e2] drawn at random (admissible).
fn random_theta(rng: &mut StdRng) -> [f64; 7] {
    [
        rng.random_range(0.5..3.0),
        rng.random_range(0.05..0.8),
        rng.random_range(0.05..0.8),
        rng.random_range(0.3..1.5),
        rng.random_range(-1.5..-0.3),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    ]
}

/// All configurations under test: 16 subsets × {shift, play}, plus tied DN1/DN2 in both forms.
fn configs() -> Vec<Udn<f64>> {
    let mut v = Vec::new();
    for set in EffectSet::all_subsets() {
        v.push(Udn::new(set));
        if set.contains(Effect::Hysteresis) {
            v.push(Udn::new(set).with_form(HysteresisForm::Play));
        }
    }
    for k in [1, 2] {
        v.push(Udn::dn(k).unwrap());
        v.push(Udn::dn(k).unwrap().with_form(HysteresisForm::Play));
    }
    v
}

/// The active subset of a full θ for a configuration.
fn active(m: &Udn<f64>, full: &[f64; 7]) -> Vec<f64> {
    let names = ["p", "a", "b", "z1", "z2", "e1", "e2"];
    StaticNonlinearity::<f64>::param_names(m)
        .iter()
        .map(|n| full[names.iter().position(|x| x == n).unwrap()])
        .collect()
}

/// Independent reference: branch variable x(k) and the piecewise v(k) of NOTES.md.
fn reference(m: &Udn<f64>, full: &[f64; 7], u: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let set = m.effect_set();
    let [p, a, b, z1, z2, e1, e2] = *full;
    let a = if set.contains(Effect::Hysteresis) {
        a
    } else {
        0.0
    };
    let b = if !set.contains(Effect::DeadZone) {
        0.0
    } else if m.is_tied() {
        a
    } else {
        b
    };
    let (z1, z2) = if set.contains(Effect::Saturation) {
        (z1, z2)
    } else {
        (f64::INFINITY, f64::NEG_INFINITY)
    };
    let (e1, e2) = if set.contains(Effect::Preload) {
        (e1, e2)
    } else {
        (0.0, 0.0)
    };
    let play = m.form() == HysteresisForm::Play && set.contains(Effect::Hysteresis);
    let mut xs = Vec::new();
    let mut vs = Vec::new();
    let mut s = 1.0;
    let mut xp = u[0] - a;
    for k in 0..u.len() {
        if k > 0 && u[k] > u[k - 1] {
            s = 1.0;
        } else if k > 0 && u[k] < u[k - 1] {
            s = -1.0;
        }
        let x = if play {
            (u[k] - a).max((u[k] + a).min(xp))
        } else {
            u[k] - a * s
        };
        xp = x;
        let sg = if x > 0.0 {
            1.0
        } else if x < 0.0 {
            -1.0
        } else {
            0.0
        };
        let w = sg * (x.abs() - b).max(0.0);
        let v = (p * w).max(p * z2).min(p * z1)
            + if x > b { e1 } else { 0.0 }
            + if x < -b { e2 } else { 0.0 };
        xs.push(x);
        vs.push(v);
    }
    (xs, vs)
}

fn phi_g(m: &dyn StaticNonlinearity<f64>, u: &[f64]) -> Vec<f64> {
    let phi = m.regressors(u);
    let g = m.gains();
    assert_eq!(phi.ncols(), g.len());
    assert_eq!(phi.ncols(), m.n_regressors());
    (0..u.len())
        .map(|k| (0..g.len()).map(|j| phi[(k, j)] * g[j]).sum())
        .collect()
}

#[test]
fn phi_times_g_equals_piecewise_definition_for_every_configuration() {
    let u = input(3000, 11);
    let mut rng = StdRng::seed_from_u64(12);
    for m0 in configs() {
        for _ in 0..5 {
            let full = random_theta(&mut rng);
            let mut m = m0.clone();
            m.set_params(&active(&m, &full)).unwrap();
            let (_, v_ref) = reference(&m, &full, &u);
            let v = phi_g(&m, &u);
            let ev = m.eval(&u);
            for k in 0..u.len() {
                assert!(
                    (v[k] - v_ref[k]).abs() <= 1e-12 * (1.0 + v_ref[k].abs()),
                    "{}: k={k} φ·g={} ref={}",
                    StaticNonlinearity::<f64>::name(&m),
                    v[k],
                    v_ref[k]
                );
                assert!((ev[k] - v_ref[k]).abs() <= 1e-12 * (1.0 + v_ref[k].abs()));
            }
        }
    }
}

#[test]
fn every_zone_is_visited_so_the_test_above_checks_all_rows() {
    // Full UDN with preload: every column must be non-zero somewhere on this input.
    let u = input(3000, 11);
    let m = Udn::with_params(EffectSet::all(), &[2.0, 0.5, 0.3, 1.5, -1.0, 0.4, -0.2]).unwrap();
    let phi = m.regressors(&u);
    for j in 0..phi.ncols() {
        let nz = (0..u.len()).filter(|&k| phi[(k, j)] != 0.0).count();
        assert!(nz > 30, "column {j} nearly empty ({nz})");
    }
    // dead band (zero output) also occurs
    let v = m.eval(&u);
    assert!(v.iter().filter(|&&x| x == 0.0).count() > 30);
}

#[test]
fn direction_rule_on_held_inputs() {
    let u = [0.0, 0.0, -1.0, -1.0, -1.0, 2.0, 2.0, 1.0];
    assert_eq!(
        directions(&u),
        vec![1.0, 1.0, -1.0, -1.0, -1.0, 1.0, 1.0, -1.0]
    );
    // A held input keeps the falling branch of SH: v stays on u + a.
    let m = Udn::with_params(EffectSet::of(&[Effect::Hysteresis]), &[1.0, 0.5]).unwrap();
    let v = m.eval(&[1.0, 0.0, 0.0, 0.0]);
    assert_eq!(v, vec![0.5, 0.5, 0.5, 0.5]);
}

#[test]
fn update_from_gains_round_trips_theta() {
    let u = input(3000, 21);
    let mut rng = StdRng::seed_from_u64(22);
    for m0 in configs() {
        for _ in 0..3 {
            let full = random_theta(&mut rng);
            let mut truth = m0.clone();
            let theta = active(&truth, &full);
            truth.set_params(&theta).unwrap();
            let g = truth.gains();
            let mut m = m0.clone();
            m.initialize(&u);
            // searched parameters are not in g: give them their true values
            let mut start = m.params();
            for i in m.searched_params() {
                start[i] = theta[i];
            }
            m.set_params(&start).unwrap();
            m.update_from_gains(&g, &u).unwrap();
            let got = m.params();
            for (x, y) in got.iter().zip(&theta) {
                assert!(
                    (x - y).abs() < 1e-12 * (1.0 + y.abs()),
                    "{}: {got:?} vs {theta:?}",
                    StaticNonlinearity::<f64>::name(&m)
                );
            }
        }
    }
}

#[test]
fn searched_params_where_b_or_play_a_is_not_in_g() {
    let names = |m: &Udn<f64>| {
        let n = StaticNonlinearity::<f64>::param_names(m);
        m.searched_params()
            .iter()
            .map(|&i| n[i].clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&Udn::full()), vec!["b"]);
    assert_eq!(names(&Udn::dn(5).unwrap()), vec!["b"]);
    assert!(names(&Udn::dn(1).unwrap()).is_empty());
    assert!(names(&Udn::sh()).is_empty());
    assert!(names(&Udn::dn(7).unwrap()).is_empty());
    assert_eq!(names(&Udn::backlash()), vec!["a"]);
    assert_eq!(
        names(&Udn::full().with_form(HysteresisForm::Play)),
        vec!["a", "b"]
    );
    // The dropped column: full UDN has 6 regressors, not 7.
    assert_eq!(StaticNonlinearity::<f64>::n_regressors(&Udn::full()), 6);
    // Preload without dead-zone spans the constant.
    assert!(StaticNonlinearity::<f64>::spans_constant(
        &Udn::dn(6).unwrap()
    ));
    assert!(!StaticNonlinearity::<f64>::spans_constant(&Udn::full()));
    let u = input(500, 3);
    let m = Udn::full();
    let (lo, hi) = m.search_range(2, &u);
    assert!(lo == 0.0 && hi > 0.5 && hi <= 0.25 * 6.0);
}

#[test]
fn zone_guard_keeps_thresholds_inside_the_data() {
    let u = input(4000, 31);
    let n = u.len() as f64;
    for m0 in [
        Udn::sh(),
        Udn::dn(3).unwrap(),
        Udn::dn(7).unwrap(),
        Udn::dn(1).unwrap(),
    ] {
        let mut m = m0.clone();
        m.initialize(&u);
        let layout = StaticNonlinearity::<f64>::regressor_names(&m);
        // thresholds thrown far past the data: a = 40, b = 40, z1 = 100, z2 = -100 (p = 2)
        let g: Vec<f64> = layout
            .iter()
            .map(|c| match c.as_str() {
                "u_sloped" => 2.0,
                "-s_sloped" | "-(s+sign)_sloped" | "-sign_sloped" => 80.0,
                "sat_high" => 200.0,
                "sat_low" => -200.0,
                _ => 0.0,
            })
            .collect();
        m.update_from_gains(&g, &u).unwrap();
        let phi = m.regressors(&u);
        for (j, name) in layout.iter().enumerate() {
            let frac = (0..u.len()).filter(|&k| phi[(k, j)] != 0.0).count() as f64 / n;
            assert!(frac >= 0.025, "{name}: only {frac} of the samples");
        }
        let th = m.params();
        assert!(th[1] <= 0.25 * 6.0 + 1e-12, "a = {}", th[1]);
    }
    // inverted saturation limits from g are repaired, not accepted
    let mut m = Udn::sh();
    m.initialize(&u);
    m.update_from_gains(&[1.0, 0.3, -1.0, 1.0], &u).unwrap();
    let th = m.params();
    assert!(th[2] > th[3]);
}

#[test]
fn bad_input_gives_typed_errors() {
    let u = input(200, 41);
    let mut m = Udn::sh();
    m.initialize(&u);
    assert!(matches!(
        m.update_from_gains(&[1.0, f64::NAN, 1.0, -1.0], &u),
        Err(Error::NonFinite { index: 1, .. })
    ));
    assert!(matches!(
        m.update_from_gains(&[0.0, 0.1, 1.0, -1.0], &u),
        Err(Error::InvalidParameter(_))
    ));
    assert!(matches!(
        m.update_from_gains(&[-1.0, 0.1, 1.0, -1.0], &u),
        Err(Error::InvalidParameter(_))
    ));
    assert!(matches!(
        m.update_from_gains(&[1.0, 0.1], &u),
        Err(Error::LengthMismatch { .. })
    ));
    assert!(matches!(
        m.set_params(&[1.0, 0.5, 1.0]),
        Err(Error::LengthMismatch { .. })
    ));
    assert!(matches!(
        m.set_params(&[1.0, 0.5, -1.0, 1.0]),
        Err(Error::InvalidParameter(_))
    ));
    assert!(matches!(
        m.set_params(&[1.0, -0.5, 1.0, -1.0]),
        Err(Error::InvalidParameter(_))
    ));
    assert!(matches!(
        m.set_params(&[f64::NAN, 0.5, 1.0, -1.0]),
        Err(Error::InvalidParameter(_))
    ));
    assert!(Udn::<f64>::dn(9).is_err());
    assert!(Udn::<f64>::sh().with_tied(true).is_err());
    let mut spec = StaticNonlinearity::<f64>::spec(&Udn::sh());
    spec.kind = "nope".into();
    assert!(matches!(
        from_spec::<f64>(&spec),
        Err(Error::ModelFormat(_))
    ));
}

#[test]
fn names_and_spec_round_trip() {
    let name = |m: &Udn<f64>| StaticNonlinearity::<f64>::name(m);
    assert_eq!(name(&Udn::full()), "udn");
    assert_eq!(name(&Udn::sh()), "sh");
    assert_eq!(name(&Udn::dn(4).unwrap()), "sh");
    assert_eq!(name(&Udn::dn(3).unwrap()), "dn3");
    assert_eq!(name(&Udn::dn(1).unwrap()), "dn1");
    assert_eq!(name(&Udn::dn(2).unwrap()), "dn2");
    assert_eq!(name(&Udn::dn(8).unwrap()), "dn8");
    assert_eq!(name(&Udn::linear()), "linear");
    assert_eq!(name(&Udn::backlash()), "backlash");
    for n in [
        "udn", "sh", "dn1", "dn2", "dn3", "dn5", "dn6", "dn7", "dn8", "linear", "backlash",
        "sh-play",
    ] {
        assert_eq!(name(&Udn::by_name(n).unwrap()), n);
    }
    assert_eq!(name(&Udn::by_name("saturation,hysteresis").unwrap()), "sh");
    assert!(Udn::<f64>::by_name("dn9").is_err());
    assert!(Udn::<f64>::by_name("hysteresys").is_err());
    assert_eq!(
        StaticNonlinearity::<f64>::effects(&Udn::sh()),
        vec!["hysteresis", "saturation"]
    );
    let u = input(300, 51);
    for mut m in configs() {
        m.initialize(&u);
        let spec = StaticNonlinearity::<f64>::spec(&m);
        let json = serde_json::to_string(&spec).unwrap();
        let back: hammerstein::regressors::NonlinearitySpec = serde_json::from_str(&json).unwrap();
        let r = from_spec::<f64>(&back).unwrap();
        assert_eq!(r.name(), name(&m));
        // serde_json's default float parsing may differ from the written value in the last ulp
        for (x, y) in r.params().iter().zip(m.params()) {
            assert!((x - y).abs() <= 1e-15 * y.abs().max(1.0));
        }
        assert_eq!(r.spec().config, spec.config);
    }
}

#[test]
fn analytic_jacobian_matches_central_differences_away_from_thresholds() {
    let u = input(2000, 61);
    let mut rng = StdRng::seed_from_u64(62);
    let h = 1e-7;
    let margin = 1e-4;
    for m0 in configs() {
        let full = random_theta(&mut rng);
        let mut m = m0.clone();
        let theta = active(&m, &full);
        m.set_params(&theta).unwrap();
        let jac = m.param_jacobian(&u);
        // samples away from every threshold (reference branch variable)
        let (x, _) = reference(&m, &full, &u);
        let set = m.effect_set();
        let b = if !set.contains(Effect::DeadZone) {
            0.0
        } else if m.is_tied() {
            full[1]
        } else {
            full[2]
        };
        let a = if set.contains(Effect::Hysteresis) {
            full[1]
        } else {
            0.0
        };
        let play = m.form() == HysteresisForm::Play && set.contains(Effect::Hysteresis);
        let mut ok = vec![true; u.len()];
        let mut far_hist = true;
        for k in 0..u.len() {
            let w = x[k].signum() * (x[k].abs() - b).max(0.0);
            let mut near = (x[k].abs() - b).abs() < margin;
            if set.contains(Effect::Saturation) {
                near |= (w - full[3]).abs() < margin || (w - full[4]).abs() < margin;
            }
            if play && k > 0 && u[k] != u[k - 1] {
                // the play's dx/da is carried while the operator is inside its band, and reset
                // when it clearly hits a side: a near-switch taints it until the next reset
                let (lo, hi) = (u[k] - a, u[k] + a);
                if (x[k - 1] - lo).abs() < margin || (x[k - 1] - hi).abs() < margin {
                    far_hist = false;
                } else if x[k - 1] < lo || x[k - 1] > hi {
                    far_hist = true;
                }
            }
            ok[k] = !near && far_hist;
        }
        let n_ok = ok.iter().filter(|&&o| o).count();
        assert!(
            n_ok > u.len() * 9 / 10,
            "{}: too few samples away from thresholds ({n_ok})",
            StaticNonlinearity::<f64>::name(&m)
        );
        for j in 0..theta.len() {
            let mut tp = theta.clone();
            let mut tm = theta.clone();
            tp[j] += h;
            tm[j] -= h;
            let (mut mp, mut mm) = (m.clone(), m.clone());
            mp.set_params(&tp).unwrap();
            mm.set_params(&tm).unwrap();
            let (vp, vm) = (mp.eval(&u), mm.eval(&u));
            let mut mean_fd = 0.0;
            let mut mean_an = 0.0;
            for k in (0..u.len()).filter(|&k| ok[k]) {
                let fd = (vp[k] - vm[k]) / (2.0 * h);
                assert!(
                    (fd - jac[(k, j)]).abs() < 1e-5 * (1.0 + fd.abs()),
                    "{} param {j} k={k}: fd {fd} analytic {}",
                    StaticNonlinearity::<f64>::name(&m),
                    jac[(k, j)]
                );
                mean_fd += fd;
                mean_an += jac[(k, j)];
            }
            assert!((mean_fd - mean_an).abs() / n_ok as f64 <= 1e-6);
        }
    }
}

#[test]
fn play_form_holds_output_inside_the_band() {
    let m = Udn::with_params(EffectSet::of(&[Effect::Hysteresis]), &[1.0, 0.5])
        .unwrap()
        .with_form(HysteresisForm::Play);
    // rise to 2, reverse by 0.6 (< 2a = 1): output held at 1.5; reverse further: follows u + a
    let v = m.eval(&[0.0, 1.0, 2.0, 1.7, 1.4, 0.5, 0.9]);
    let want: [f64; 7] = [-0.5, 0.5, 1.5, 1.5, 1.5, 1.0, 1.0];
    for (x, y) in v.iter().zip(want) {
        assert!((x - y).abs() < 1e-15, "{v:?}");
    }
}

#[test]
fn f32_matches_f64() {
    let u = input(1000, 71);
    let u32v: Vec<f32> = u.iter().map(|&x| x as f32).collect();
    let theta = [2.0, 0.5, 0.3, 1.5, -1.0, 0.4, -0.2];
    let m64 = Udn::<f64>::with_params(EffectSet::all(), &theta).unwrap();
    let th32: Vec<f32> = theta.iter().map(|&x| x as f32).collect();
    let m32 = Udn::<f32>::with_params(EffectSet::all(), &th32).unwrap();
    let (v64, v32) = (m64.eval(&u), m32.eval(&u32v));
    let x = reference(&m64, &theta, &u).0;
    let mut compared = 0;
    for k in 0..u.len() {
        // f32 rounding can flip a zone only within ~1e-5 of a threshold
        let w = x[k].signum() * (x[k].abs() - 0.3).max(0.0);
        if (x[k].abs() - 0.3).abs() > 1e-4 && (w - 1.5).abs() > 1e-4 && (w + 1.0).abs() > 1e-4 {
            assert!((v32[k] as f64 - v64[k]).abs() < 1e-5, "k={k}");
            compared += 1;
        }
    }
    assert!(compared > 900);
    let mut m = Udn::<f32>::sh();
    m.initialize(&u32v);
    let g = m.gains();
    m.update_from_gains(&g, &u32v).unwrap();
    assert!(m.params().iter().all(|x| x.is_finite()));
}

/// eval equals φ·g summed in the columns' order from +0, bit for bit, for every configuration:
/// random parameters, zero gains, and inputs placed exactly on the thresholds (|x| = b, w = z1,
/// w = z2, x = 0), where a kernel that skips zero products could differ in a sign or a rounding.
#[test]
fn eval_is_phi_times_g_bit_for_bit_including_thresholds() {
    let mut rng = StdRng::seed_from_u64(21);
    for m0 in configs() {
        for trial in 0..6 {
            let mut full = random_theta(&mut rng);
            if trial == 1 {
                // zero preloads: products ±0 in every zone
                full[5] = 0.0;
                full[6] = -0.0;
            }
            let mut m = m0.clone();
            m.set_params(&active(&m, &full)).unwrap();
            let [_, a, b, z1, z2, _, _] = full;
            let mut u = input(2000, 30 + trial);
            // samples on the zone edges, reached from both sides (both directions of s)
            for (i, x) in [0.0, b, -b, b + z1, -b + z2, a, -a, a + b, b - a, z1, z2]
                .into_iter()
                .enumerate()
            {
                u[100 + 4 * i] = x;
                u[101 + 4 * i] = x;
                u[102 + 4 * i] = x - 1.0;
                u[103 + 4 * i] = x;
            }
            let phi = m.regressors(&u);
            let g = m.gains();
            let ev = m.eval(&u);
            for k in 0..u.len() {
                let mut acc = 0.0f64;
                for j in 0..g.len() {
                    acc += phi[(k, j)] * g[j];
                }
                assert_eq!(
                    ev[k].to_bits(),
                    acc.to_bits(),
                    "{}: k={k} u={} eval={} φ·g={}",
                    StaticNonlinearity::<f64>::name(&m),
                    u[k],
                    ev[k],
                    acc
                );
            }
        }
    }
}

/// `input_shifted(m)` gives N' and κ with N'(u) + κ = N(u + m) on every sample when the UDN has
/// no dead-zone and no preload (hysteresis in both forms, saturation), and `None` otherwise;
/// shifting back by −m restores the parameters and the constant's sign.
#[test]
fn input_shifted_moves_the_thresholds_and_returns_the_constant() {
    let u = input(1500, 41);
    let mut rng = StdRng::seed_from_u64(42);
    for m0 in configs() {
        let full = random_theta(&mut rng);
        let mut m = m0.clone();
        m.set_params(&active(&m, &full)).unwrap();
        let name = StaticNonlinearity::<f64>::name(&m);
        let set = m.effect_set();
        let anchored = set.contains(Effect::DeadZone) || set.contains(Effect::Preload);
        for shift in [0.0, 7.5, -1234.0] {
            let got = m.input_shifted(shift);
            if anchored {
                assert!(got.is_none(), "{name}: shifted although anchored at 0");
                continue;
            }
            let (n2, kappa) = got.unwrap();
            let us: Vec<f64> = u.iter().map(|x| x + shift).collect();
            let (v_shifted, v2) = (m.eval(&us), n2.eval(&u));
            for k in 0..u.len() {
                assert!(
                    (v_shifted[k] - (v2[k] + kappa)).abs() <= 1e-9 * (1.0 + v_shifted[k].abs()),
                    "{name} shift {shift}: k={k} N(u+m)={} N'(u)+κ={}",
                    v_shifted[k],
                    v2[k] + kappa
                );
            }
            let (back, k_back) = n2.input_shifted(-shift).unwrap();
            for (p, q) in back.params().iter().zip(m.params()) {
                assert!(
                    (p - q).abs() <= 1e-9 * (1.0 + q.abs()),
                    "{name}: {p} against {q}"
                );
            }
            assert!((kappa + k_back).abs() <= 1e-9 * (1.0 + kappa.abs()));
        }
    }
}

/// A UDN that says it is memoryless gives the same v behind any input history (the simulation
/// then evaluates one start); every configuration with hysteresis says it has a memory, and
/// its rising and falling starts do differ on some records.
#[test]
fn memoryless_configurations_forget_the_inputs_history() {
    let mut rng = StdRng::seed_from_u64(41);
    let mut with_memory_differing = 0;
    for mut m in configs() {
        let full = random_theta(&mut rng);
        m.set_params(&active(&m, &full)).unwrap();
        let u = input(400, rng.random_range(0..1000));
        let v = m.eval(&u);
        let behind = |h: &[f64]| {
            let mut ext = h.to_vec();
            ext.extend_from_slice(&u);
            m.eval(&ext)[h.len()..].to_vec()
        };
        let histories = [
            vec![u[0] + 5.0],
            vec![u[0] - 5.0],
            vec![u[0] - 4.0, u[0] + 4.0],
        ];
        if StaticNonlinearity::<f64>::memoryless(&m) {
            assert!(
                !m.effects().contains(&"hysteresis".to_string()),
                "{}",
                m.name()
            );
            for h in &histories {
                assert_eq!(behind(h), v, "{} behind {h:?}", m.name());
            }
        } else {
            assert!(
                StaticNonlinearity::<f64>::param_names(&m).contains(&"a".to_string())
                    || m.name().contains("dn"),
                "{} has a memory only with hysteresis",
                m.name()
            );
            if histories.iter().any(|h| behind(h) != v) {
                with_memory_differing += 1;
            }
        }
    }
    assert!(with_memory_differing > 0);
}
