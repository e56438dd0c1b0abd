//! `use hammerstein::*` followed by a path into the crate compiles: no module is named like the
//! crate (the loop's module was `hammerstein::hammerstein`, which made this E0659).

#[allow(unused_imports)]
use hammerstein::*;

#[test]
fn glob_import_then_crate_paths() {
    use hammerstein::fit::Termination as T;
    let s: hammerstein::fit::Hammerstein<f64> = Hammerstein::sh();
    assert_eq!(
        s.options().horizon,
        hammerstein::Hammerstein::<f64>::sh().options().horizon
    );
    let _ = std::mem::size_of::<T>();
}
