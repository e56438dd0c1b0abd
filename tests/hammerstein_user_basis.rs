//! The loop with a user-defined basis (written against the public trait only): paper Example 1.

mod hammerstein_common;
use hammerstein::fit::{HammersteinModel, Termination};
use hammerstein::{Hammerstein, IoData};
use hammerstein_common::*;

fn example1() -> IoData<f64> {
    let truth = UserSh::<f64>::new(2.0, 0.5, 1.5, -1.0);
    record(&truth, &example1_input(2000, 7), 0.0)
}

fn check_example1(model: &HammersteinModel<f64>, tol: f64) {
    let p = model.parameters();
    let want = [2.0, 0.5, 1.5, -1.0];
    for (i, (name, v)) in p.iter().enumerate() {
        close(name, *v, want[i], tol);
    }
    let tf = model.transfer_function().unwrap();
    assert_eq!(model.linear().order(), 2, "{tf:?}");
    close("a1", tf.denominator[1], -0.2, tol);
    close("a2", tf.denominator[2], 0.35, tol);
    close("b0", tf.numerator[0], 0.0, tol);
    close("b1", tf.numerator[1], 1.0, tol);
    close("b2", tf.numerator[2], 0.5, tol);
}

#[test]
fn user_basis_recovers_example1() {
    let data = example1();
    let model = Hammerstein::new(Box::new(UserSh::<f64>::new(1.0, 0.0, 1.0, -1.0)))
        .fit(&data)
        .unwrap();
    let rep = model.report();
    eprintln!("{:?}", rep.iterations);
    eprintln!("{:?} best {}", rep.termination, rep.best_iteration);
    check_example1(&model, 1e-6);
    assert!(rep.converged, "{:?}", rep.termination);
    assert_eq!(rep.termination, Termination::Converged);
    close("offset", model.output_offset(), 0.0, 1e-8);
}
