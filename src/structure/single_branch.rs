//! Within `single-branch`: Hammerstein, Wiener and Wiener–Hammerstein ranked by validation error.
//!
//! Algorithm:
//! 1. Data: the record's highest level, where the nonlinearity is strongest against the noise
//!    (at low levels all three classes are nearly linear and fit alike). The models are fitted
//!    on the level's first realization, its whole block (the transient period included; the fit
//!    estimates the initial state), and validated on the level's other realizations — the same
//!    amplitude, other phases, so the validation input is new but not an extrapolation. With one
//!    realization at that level, the next lower level validates (an amplitude the models did not
//!    see), and a note says so.
//! 2. Models, each with the library's fit ([`crate::Hammerstein`]) at the BLAs' order:
//!    `hammerstein` — a polynomial input map (u, u², u³) before the linear block;
//!    `wiener` — a linear input and a polynomial output map x + c₂x² + c₃x³ (`poly3`);
//!    `wiener-hammerstein` — both maps. The fit has one linear block, so this last model is the
//!    Hammerstein–Wiener structure N–G–g, the fit's stand-in for a Wiener–Hammerstein system
//!    G₁–f–G₂ (both have a nonlinearity that neither a pure input nor a pure output map
//!    expresses).
//! 3. Validation: each model simulated on each validation block with its initial state
//!    estimated by least squares ([`crate::HammersteinModel::simulate_on`]); the errors on the
//!    steady periods (the transient period dropped) pooled; the validation MSE their mean square.
//! 4. Ranking, the one-standard-error rule of cross-validation (Breiman, Friedman, Olshen &
//!    Stone, *Classification and Regression Trees*, 1984, §3.4.3; Hastie, Tibshirani & Friedman,
//!    *The Elements of Statistical Learning*, §7.10): a model is *within noise* of the lowest MSE
//!    when its loss differential to the best model, d_k = e_m(k)² − e_best(k)², has a
//!    Diebold–Mariano statistic below 1 (mean under one Newey–West standard error; Diebold &
//!    Mariano, J. Business & Economic Statistics 13(3), 1995). First comes the simplest model
//!    within noise (one map before two; between equals the lower MSE), then the others by MSE.
//!    The ranking is **decisive** when no other model as simple as the first is within noise —
//!    a model with both maps within noise of a simpler one is not needed, which the rule decides.

use super::record::Record;
use crate::diebold_mariano::diebold_mariano;
use crate::error::{Error, Result};
use crate::regressors::{OutputMap, Polynomial, PolynomialMap};
use crate::{Hammerstein, HammersteinModel, IoData, Order};

/// One candidate's fit and validation.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CandidateFit {
    /// The model class ("hammerstein", "wiener", "wiener-hammerstein").
    pub name: String,
    /// What was fitted.
    pub model: String,
    /// Number of static maps (1 or 2): the complexity the rule prefers fewer of.
    pub maps: usize,
    /// MSE on the fitting block.
    pub train_mse: f64,
    /// MSE on the validation blocks' steady periods.
    pub validation_mse: f64,
    /// Diebold–Mariano statistic of its loss differential to the lowest-MSE model (0 for that one).
    pub dm_vs_best: f64,
    /// Whether its validation MSE is within one standard error of the lowest.
    pub within_noise: bool,
    /// Why the fit failed (then the MSEs are infinite).
    pub error: Option<String>,
}

/// The single-branch ranking.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SingleBranchRanking {
    /// The candidates, first the preferred one (see the module's rule).
    pub candidates: Vec<CandidateFit>,
    /// Whether the first is preferred beyond noise.
    pub decisive: bool,
    /// The level the models were fitted on.
    pub fit_level: usize,
    /// What validated: "held-out realizations" or "the next lower level".
    pub validation: String,
    /// Validation samples pooled.
    pub validation_samples: usize,
}

fn block_data(record: &Record, level: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
    record
        .blocks()
        .iter()
        .filter(|b| b.level == level)
        .filter_map(|b| Some((b.u.clone(), b.y.clone()?)))
        .collect()
}

fn settings(name: &str, order: usize) -> Result<Hammerstein<f64>> {
    let poly_in = || -> Result<Hammerstein<f64>> {
        Ok(Hammerstein::new(Box::new(Polynomial::<f64>::new(3)?)))
    };
    let map = || -> Result<Option<Box<dyn OutputMap<f64>>>> {
        Ok(Some(Box::new(PolynomialMap::<f64>::new(3)?)))
    };
    let s = match name {
        "hammerstein" => poly_in()?,
        "wiener" => Hammerstein::linear().output_nonlinearity(map()?),
        _ => poly_in()?.output_nonlinearity(map()?),
    };
    Ok(s.order(Order::Fixed(order)))
}

/// Ranks Hammerstein, Wiener and Wiener–Hammerstein on a measured record by validation MSE
/// (the module's algorithm); `order` is the linear block's order (the verdict's).
pub fn rank_single_branch(record: &Record, order: usize) -> Result<SingleBranchRanking> {
    let period = record.period();
    let top = record.levels() - 1;
    let blocks = block_data(record, top);
    let ((fu, fy), valid, validation) = match blocks.len() {
        0 => {
            return Err(Error::InvalidParameter(
                "the record has no measured output at its highest level".into(),
            ));
        }
        1 if top == 0 => {
            return Err(Error::InvalidParameter(
                "one realization at one level: nothing to validate the single-branch models on"
                    .into(),
            ));
        }
        1 => (
            blocks[0].clone(),
            block_data(record, top - 1),
            "the next lower level".to_string(),
        ),
        _ => (
            blocks[0].clone(),
            blocks[1..].to_vec(),
            "held-out realizations".to_string(),
        ),
    };
    let train = IoData::siso(&fu, &fy)?;
    let names = [
        (
            "hammerstein",
            "polynomial input map (degree 3) -> linear block",
            1,
        ),
        ("wiener", "linear block -> poly3 output map", 1),
        (
            "wiener-hammerstein",
            "polynomial input map (degree 3) -> linear block -> poly3 output map (Hammerstein-Wiener stand-in)",
            2,
        ),
    ];
    let mut fits = Vec::new();
    let mut errors: Vec<Option<Vec<f64>>> = Vec::new();
    for (name, model, maps) in names {
        let fitted: Result<(HammersteinModel<f64>, Vec<f64>)> = (|| {
            let m = settings(name, order)?.fit(&train)?;
            let mut e = Vec::new();
            for (u, y) in &valid {
                let sim = m.simulate_on(&IoData::siso(u, y)?)?;
                e.extend((period..y.len()).map(|k| y[k] - sim.y_hat[k]));
            }
            Ok((m, e))
        })();
        let (train_mse, validation_mse, e, error) = match fitted {
            Ok((m, e)) => {
                let v = e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64;
                if v.is_finite() {
                    (m.report().train_mse, v, Some(e), None)
                } else {
                    (
                        f64::INFINITY,
                        f64::INFINITY,
                        None,
                        Some("the simulation diverged".to_string()),
                    )
                }
            }
            Err(err) => (f64::INFINITY, f64::INFINITY, None, Some(err.to_string())),
        };
        fits.push(CandidateFit {
            name: name.into(),
            model: model.into(),
            maps,
            train_mse,
            validation_mse,
            dm_vs_best: f64::INFINITY,
            within_noise: false,
            error,
        });
        errors.push(e);
    }
    let best = (0..fits.len())
        .min_by(|&a, &b| fits[a].validation_mse.total_cmp(&fits[b].validation_mse))
        .unwrap_or(0);
    let Some(eb) = errors[best].clone() else {
        return Err(Error::Identification(format!(
            "none of the single-branch models could be fitted: {}",
            fits.iter()
                .filter_map(|f| f.error.clone())
                .collect::<Vec<_>>()
                .join("; ")
        )));
    };
    for (f, e) in fits.iter_mut().zip(&errors) {
        if let Some(e) = e {
            let (_, dm) = diebold_mariano(&eb, e);
            f.dm_vs_best = if dm.is_nan() { 0.0 } else { dm };
            f.within_noise = f.dm_vs_best < 1.0;
        }
    }
    fits[best].dm_vs_best = 0.0;
    fits[best].within_noise = true;
    // the simplest within noise first (lower MSE between equals), then the rest by MSE
    let first = (0..fits.len())
        .filter(|&i| fits[i].within_noise)
        .min_by(|&a, &b| {
            fits[a]
                .maps
                .cmp(&fits[b].maps)
                .then(fits[a].validation_mse.total_cmp(&fits[b].validation_mse))
        })
        .unwrap_or(best);
    let decisive = !fits
        .iter()
        .enumerate()
        .any(|(i, f)| i != first && f.within_noise && f.maps <= fits[first].maps);
    let lead = fits.remove(first);
    fits.sort_by(|a, b| a.validation_mse.total_cmp(&b.validation_mse));
    fits.insert(0, lead);
    Ok(SingleBranchRanking {
        candidates: fits,
        decisive,
        fit_level: top,
        validation,
        validation_samples: eb.len(),
    })
}
