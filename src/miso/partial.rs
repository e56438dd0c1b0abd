//! The partial residual record of one input: its input column and the output less the other
//! branches' simulated contributions.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;
use faer::Mat;

/// The record (uᵢ, y − Σ_{j≠i} ŷⱼ) of input `i`, where `contributions[j]` is branch j's
/// simulated output on `data` (empty vectors count as zero: branches not fitted yet).
pub fn partial_record<T: Real>(
    data: &IoData<T>,
    i: usize,
    contributions: &[Vec<T>],
) -> Result<IoData<T>> {
    let nn = data.len();
    if i >= data.n_inputs() {
        return Err(Error::Dimension(format!(
            "input {} of a record with {} inputs",
            i + 1,
            data.n_inputs()
        )));
    }
    if let Some(c) = contributions
        .iter()
        .find(|c| !c.is_empty() && c.len() != nn)
    {
        return Err(Error::LengthMismatch {
            what: format!(
                "a branch contribution has {} samples, the record {nn}",
                c.len()
            ),
        });
    }
    let u = data.input_slice(i);
    let y = data.output_slice(0);
    let mut r = y.to_vec();
    for (j, c) in contributions.iter().enumerate() {
        if j != i && !c.is_empty() {
            for (rk, ck) in r.iter_mut().zip(c) {
                *rk -= *ck;
            }
        }
    }
    let rec = IoData::with_names(
        Mat::from_fn(nn, 1, |k, _| u[k]),
        Mat::from_fn(nn, 1, |k, _| r[k]),
        vec![data.input_names()[i].clone()],
        vec![data.output_names()[0].clone()],
    )?;
    rec.with_sample_time(data.sample_time())
}
