//! The paper's Example 1 linear block, defined once for every shared test module
//! (`common`, `hammerstein_common` and `subspace_common` include this file).
#![allow(dead_code)]

use hammerstein::StateSpace;

/// The paper's linear block G(z) = z⁻¹(1 + 0.5 z⁻¹)/(1 − 0.2 z⁻¹ + 0.35 z⁻²), observable
/// canonical form.
pub fn paper_block() -> StateSpace<f64> {
    StateSpace::from_rows(
        &[&[0.2, 1.0], &[-0.35, 0.0]],
        &[&[1.0], &[0.5]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .expect("the paper's block has consistent shapes")
}
