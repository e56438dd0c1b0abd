//! Example 1 (noise-free, SH) with every subspace method, both scalars and both backends.

mod hammerstein_common;
use hammerstein::fit::HammersteinModel;
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein::{BackendKind, Hammerstein, IoData, MethodKind, Real};
use hammerstein_common::*;

fn example1<T: Real>() -> IoData<T> {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth =
        Udn::<T>::with_params(set, &[T::lit(2.0), T::lit(0.5), T::lit(1.5), T::lit(-1.0)]).unwrap();
    record(&truth, &example1_input::<T>(2000, 7), 0.0)
}

fn check<T: Real>(model: &HammersteinModel<T>, tol: f64) {
    let want = [("p", 2.0), ("a", 0.5), ("z1", 1.5), ("z2", -1.0)];
    let got = model.parameters();
    for (name, w) in want {
        let v = got.iter().find(|(n, _)| n == name).unwrap().1;
        close(name, v, w, tol);
    }
    let tf = model.transfer_function().unwrap();
    assert_eq!(model.linear().order(), 2, "{tf:?}");
    close("a1", tf.denominator[1], -0.2, tol);
    close("a2", tf.denominator[2], 0.35, tol);
    close("b1", tf.numerator[1], 1.0, tol);
    close("b2", tf.numerator[2], 0.5, tol);
}

fn fit<T: Real>(method: MethodKind, backend: BackendKind) -> HammersteinModel<T> {
    Hammerstein::<T>::sh()
        .method(method)
        .backend(backend)
        .fit(&example1::<T>())
        .unwrap()
}

#[test]
fn moesp_f64() {
    check(&fit::<f64>(MethodKind::Moesp, BackendKind::Faer), 1e-6);
}

#[test]
fn n4sid_f64() {
    check(&fit::<f64>(MethodKind::N4sid, BackendKind::Faer), 1e-6);
    check(
        &fit::<f64>(MethodKind::N4sidUnweighted, BackendKind::Faer),
        1e-6,
    );
}

// f32: single precision carries ~7 digits; the parameters come back to 1e-3
#[test]
fn moesp_f32() {
    check(&fit::<f32>(MethodKind::Moesp, BackendKind::Faer), 1e-3);
}

#[test]
fn n4sid_f32() {
    check(&fit::<f32>(MethodKind::N4sid, BackendKind::Faer), 1e-3);
}

#[cfg(feature = "lapack")]
#[test]
fn lapack_moesp_f64() {
    check(&fit::<f64>(MethodKind::Moesp, BackendKind::Lapack), 1e-6);
}

#[cfg(feature = "lapack")]
#[test]
fn lapack_n4sid_f32() {
    check(&fit::<f32>(MethodKind::N4sid, BackendKind::Lapack), 1e-3);
}

#[cfg(not(feature = "lapack"))]
#[test]
fn lapack_without_feature_is_a_typed_error() {
    let err = Hammerstein::<f64>::sh()
        .backend(BackendKind::Lapack)
        .fit(&example1::<f64>())
        .unwrap_err();
    assert!(
        matches!(err, hammerstein::Error::BackendUnavailable { .. }),
        "{err}"
    );
}
