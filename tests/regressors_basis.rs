//! Polynomial and user-defined bases: φ·g equals the defining formula, gains round trip, specs
//! rebuild, augmenting a UDN with user columns keeps the UDN's part intact.

use hammerstein::Error;
use hammerstein::regressors::{
    Augmented, NonlinearitySpec, Polynomial, StaticNonlinearity, Udn, UserBasis, UserColumn,
    directions, from_spec, from_spec_with,
};
use rand::{RngExt, SeedableRng, rngs::StdRng};

fn input(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(-3.0..3.0)).collect()
}

fn phi_g(m: &dyn StaticNonlinearity<f64>, u: &[f64]) -> Vec<f64> {
    let phi = m.regressors(u);
    let g = m.gains();
    assert_eq!(phi.ncols(), g.len());
    (0..u.len())
        .map(|k| (0..g.len()).map(|j| phi[(k, j)] * g[j]).sum())
        .collect()
}

#[test]
fn polynomial_matches_its_formula_and_round_trips() {
    let u = input(500, 1);
    let mut rng = StdRng::seed_from_u64(2);
    for (poly, powers) in [
        (Polynomial::<f64>::new(3).unwrap(), vec![1, 2, 3]),
        (Polynomial::<f64>::odd(5).unwrap(), vec![1, 3, 5]),
    ] {
        let mut m = poly.clone();
        let c: Vec<f64> = powers.iter().map(|_| rng.random_range(-3.0..3.0)).collect();
        m.set_params(&c).unwrap();
        let v = phi_g(&m, &u);
        for k in 0..u.len() {
            let want: f64 = powers
                .iter()
                .zip(&c)
                .map(|(&j, &cj)| cj * u[k].powi(j))
                .sum();
            assert!((v[k] - want).abs() < 1e-12 * (1.0 + want.abs()));
        }
        let mut m2 = poly.clone();
        m2.initialize(&u);
        m2.update_from_gains(&m.gains(), &u).unwrap();
        assert_eq!(m2.params(), c);
        let back = from_spec::<f64>(&m.spec()).unwrap();
        assert_eq!(back.name(), m.name());
        assert_eq!(back.params(), c);
        assert!(m2.update_from_gains(&[f64::NAN; 3], &u).is_err());
    }
    assert_eq!(
        StaticNonlinearity::<f64>::name(&Polynomial::<f64>::new(3).unwrap()),
        "poly3"
    );
    assert!(Polynomial::<f64>::new(0).is_err());
    let mut p = Polynomial::<f64>::new(2).unwrap();
    assert!(matches!(
        p.set_params(&[1.0]),
        Err(Error::LengthMismatch { .. })
    ));
}

fn friction_columns() -> Vec<UserColumn<f64>> {
    vec![
        UserColumn::new("u", |u, _s| u),
        UserColumn::new("u_pos", |u: f64, _s| if u > 0.0 { u } else { 0.0 }),
        UserColumn::new("coulomb", |_u, s| s),
    ]
}

#[test]
fn user_basis_evaluates_columns_of_u_and_direction() {
    let u = input(400, 3);
    let mut b = UserBasis::new("friction", &["asymmetry", "coulomb"], friction_columns()).unwrap();
    b.set_params(&[1.5, 0.5, -0.3]).unwrap();
    let s = directions(&u);
    let v = phi_g(&b, &u);
    for k in 0..u.len() {
        let want = 1.5 * u[k] + 0.5 * u[k].max(0.0) - 0.3 * s[k];
        assert!((v[k] - want).abs() < 1e-13);
    }
    assert_eq!(b.regressor_names(), vec!["u", "u_pos", "coulomb"]);
    // rebuild: through the user's closure, and an error for the same spec without it
    let spec = b.spec();
    let rebuilt = from_spec_with::<f64>(&spec, |sp| {
        (sp.kind == "friction").then(|| {
            UserBasis::from_spec(sp, friction_columns())
                .map(|x| Box::new(x) as Box<dyn StaticNonlinearity<f64>>)
        })
    })
    .unwrap();
    assert_eq!(rebuilt.eval(&u), b.eval(&u));
    assert!(matches!(
        from_spec::<f64>(&spec),
        Err(Error::ModelFormat(_))
    ));
    // bad definitions
    assert!(UserBasis::<f64>::new("empty", &[], vec![]).is_err());
    let dup = vec![
        UserColumn::new("u", |u, _| u),
        UserColumn::new("u", |u, _| u),
    ];
    assert!(UserBasis::<f64>::new("dup", &[], dup).is_err());
}

#[test]
fn augmented_udn_keeps_the_udn_part_and_adds_user_terms() {
    let u = input(1000, 4);
    let sh = Udn::with_params(Udn::<f64>::sh().effect_set(), &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let extra = vec![
        UserColumn::new("u_pos", |u: f64, _s| if u > 0.0 { u } else { 0.0 }),
        UserColumn::new("coulomb", |_u, s| s),
    ];
    let mut aug = Augmented::new(sh.clone(), extra.clone()).unwrap();
    let n0 = StaticNonlinearity::<f64>::n_regressors(&sh);
    assert_eq!(aug.n_regressors(), n0 + 2);
    assert_eq!(
        aug.param_names(),
        vec!["p", "a", "z1", "z2", "u_pos", "coulomb"]
    );
    aug.set_params(&[2.0, 0.5, 1.5, -1.0, 0.7, 0.2]).unwrap();
    let v_sh = sh.eval(&u);
    let s = directions(&u);
    let v = phi_g(&aug, &u);
    for k in 0..u.len() {
        let want = v_sh[k] + 0.7 * u[k].max(0.0) + 0.2 * s[k];
        assert!((v[k] - want).abs() < 1e-12);
    }
    // gains round trip through the base's update (zone guard included) and the extra gains
    let g = aug.gains();
    let mut a2 = Augmented::new(Udn::sh(), extra.clone()).unwrap();
    a2.initialize(&u);
    a2.update_from_gains(&g, &u).unwrap();
    for (x, y) in a2.params().iter().zip(aug.params()) {
        assert!(
            (x - y).abs() < 1e-12,
            "{:?} vs {:?}",
            a2.params(),
            aug.params()
        );
    }
    // Jacobian: base part analytic, extra part = the columns
    let jac = aug.param_jacobian(&u);
    assert_eq!(jac.ncols(), 6);
    for k in 0..u.len() {
        assert_eq!(jac[(k, 5)], s[k]);
    }
    // spec round trip (base rebuilt from its own spec)
    let spec: NonlinearitySpec =
        serde_json::from_str(&serde_json::to_string(&aug.spec()).unwrap()).unwrap();
    let back = Augmented::<f64>::from_spec(&spec, extra.clone()).unwrap();
    assert_eq!(back.name(), aug.name());
    for (x, y) in back.params().iter().zip(aug.params()) {
        assert!((x - y).abs() < 1e-14);
    }
    assert!(Augmented::<f64>::from_spec(&spec, extra[..1].to_vec()).is_err());
    // a user column may not reuse a base name
    assert!(Augmented::new(Udn::<f64>::sh(), vec![UserColumn::new("p", |u, _| u)]).is_err());
    assert!(matches!(
        aug.update_from_gains(&[1.0; 5], &u),
        Err(Error::LengthMismatch { .. })
    ));
}
