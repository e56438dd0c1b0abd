//! LAPACK backend (feature `lapack`): the same models as faer, and noise-free recovery.
#![cfg(feature = "lapack")]

mod subspace_common;

use hammerstein::solvers::Lapack;
use hammerstein::subspace::{Compression, MethodKind, Order, SubspaceOptions, identify};
use hammerstein::{Faer, LinAlg};
use subspace_common::*;

#[test]
fn lapack_recovers_known_systems() {
    for (sys, i, n) in [(paper_siso(), 10, 2000), (mimo4(), 6, 3000)] {
        let d64 = simulate::<f64>(&sys, n, 0.0, 21);
        let d32 = simulate::<f32>(&sys, n, 0.0, 21);
        for kind in [MethodKind::Moesp, MethodKind::N4sid] {
            let id = identify(
                kind.build::<f64>(i).unwrap().as_ref(),
                &Lapack,
                &[d64.view()],
                &SubspaceOptions::default(),
            )
            .unwrap();
            assert_eq!(id.model.order(), sys.order());
            assert!(pole_error(&id.model.poles().unwrap(), &sys.poles().unwrap()) < 1e-9);
            assert!(markov_rel_error(&id.model, &sys, 10) < 1e-9);
            let id = identify(
                kind.build::<f32>(i).unwrap().as_ref(),
                &Lapack,
                &[d32.view()],
                &SubspaceOptions {
                    order: Order::Fixed(sys.order()),
                    ..Default::default()
                },
            )
            .unwrap();
            assert!(pole_error(&id.model.poles().unwrap(), &sys.poles().unwrap()) < 1e-3);
            assert!(markov_rel_error(&id.model, &sys, 10) < 1e-3);
        }
    }
}

#[test]
fn faer_and_lapack_agree() {
    for (sys, i, n) in [(paper_siso(), 10, 2000), (mimo4(), 6, 3000)] {
        let d = simulate::<f64>(&sys, n, 0.3, 22);
        for kind in [MethodKind::Moesp, MethodKind::N4sid] {
            for c in [Compression::Cholesky, Compression::Qr] {
                let m = kind.build_with::<f64>(i, c).unwrap();
                let opts = SubspaceOptions {
                    order: Order::Fixed(sys.order()),
                    ..Default::default()
                };
                let backends: [&dyn LinAlg<f64>; 2] = [&Faer::default(), &Lapack];
                let a = identify(m.as_ref(), backends[0], &[d.view()], &opts).unwrap();
                let b = identify(m.as_ref(), backends[1], &[d.view()], &opts).unwrap();
                for (x, y) in a.singular_values.iter().zip(&b.singular_values) {
                    assert!((x - y).abs() <= 1e-10 * a.singular_values[0], "{x} vs {y}");
                }
                let me = markov_rel_error(&a.model, &b.model, 10);
                assert!(me < 1e-10, "{kind:?} {c:?}: Markov {me:e}");
            }
        }
    }
}
