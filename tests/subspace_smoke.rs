#[path = "common/paper.rs"]
mod paper;

use hammerstein::subspace::{Moesp, Order, SubspaceOptions, identify};
use hammerstein::{Faer, IoData};
use rand::{RngExt, SeedableRng, rngs::StdRng};

#[test]
fn moesp_recovers_paper_linear_block() {
    // G(z) = z^-1 (1 + 0.5 z^-1) / (1 - 0.2 z^-1 + 0.35 z^-2), observable canonical form
    let sys = paper::paper_block();
    let mut rng = StdRng::seed_from_u64(1);
    let u: Vec<f64> = (0..2000).map(|_| rng.random_range(-3.0..3.0)).collect();
    let y = sys.simulate_siso(&u, Some(&[0.3, -0.2])).unwrap();
    let data = IoData::siso(&u, &y).unwrap();
    let id = identify(
        &Moesp::new(10),
        &Faer::default(),
        &[data.view()],
        &SubspaceOptions {
            order: Order::Auto,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(id.model.order(), 2);
    let tf = id.model.transfer_function(0, 0).unwrap();
    let want_den = [1.0, -0.2, 0.35];
    let want_num = [0.0, 1.0, 0.5];
    for k in 0..3 {
        assert!((tf.denominator[k] - want_den[k]).abs() < 1e-9, "{tf:?}");
        assert!((tf.numerator[k] - want_num[k]).abs() < 1e-9, "{tf:?}");
    }
}
