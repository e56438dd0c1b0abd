//! Structure selection: fits the 16 effect subsets of the UDN and ranks them by an information
//! criterion (BIC by default) or by the simulation MSE on a held-out part of the record.
//!
//! NOTES.md: BIC over the 16 subsets picks the true structure (SH) in 20/20 noisy runs; validation
//! MSE alone tends to pick supersets. On noise-free data every superset of the true structure fits
//! exactly, and BIC's N·ln(MSE) would rank them by round-off; the MSE is therefore floored at the
//! loop's exact-fit level (see `problem::exact_floor`) so that the penalty decides among exact fits.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::fit_report::Termination;
use crate::fit::fitted::model::HammersteinModel;
use crate::fit::iteration::problem::{exact_floor, variance};
use crate::fit::settings::Hammerstein;
use crate::real::Real;
use crate::regressors::EffectSet;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How candidate structures are ranked.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// Bayesian information criterion N·ln(MSE) + k·ln(N) on the training record (default).
    #[default]
    Bic,
    /// Akaike information criterion N·ln(MSE) + 2k.
    Aic,
    /// Simulation MSE on the last `fraction` of the record, the model fitted on the rest.
    Validation(f64),
}

/// One fitted candidate structure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StructureCandidate {
    /// The effects modelled.
    pub effects: EffectSet,
    /// The paper's DN type (1..=8) when the set is one of Table 1's.
    pub dn_type: Option<u8>,
    /// Training MSE (validation MSE for [`Criterion::Validation`]).
    pub mse: f64,
    /// Criterion value (lower is better; infinite when the fit failed).
    pub score: f64,
    /// Number of estimated parameters k (nonlinearity, 2n linear, D, offset).
    pub n_params: usize,
    /// Model order of the fit.
    pub order: usize,
    /// Why its loop stopped (`None` when the fit failed).
    pub termination: Option<Termination>,
    /// The nonlinearity parameters by name.
    pub parameters: Vec<(String, f64)>,
    /// The error, when the fit failed.
    pub error: Option<String>,
}

/// The result of a structure selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StructureReport {
    /// The ranking criterion.
    pub criterion: Criterion,
    /// The chosen effect set.
    pub chosen: EffectSet,
    /// Its DN type, when it is one of Table 1's.
    pub dn_type: Option<u8>,
    /// All candidates, best first.
    pub candidates: Vec<StructureCandidate>,
}

/// Fits the 16 UDN effect subsets with the other settings of `base` and ranks them.
pub fn select_structure<T: Real>(
    base: &Hammerstein<T>,
    data: &IoData<T>,
    criterion: Criterion,
) -> Result<StructureReport> {
    if base.effects().is_none() {
        return Err(Error::NotUdn {
            what: "structure selection needs a UDN; it cannot use".into(),
            name: base.nonlinearity_name(),
        });
    }
    base.validate()?;
    let (train, valid) = match criterion {
        Criterion::Validation(f) => {
            let (a, b) = data.split_validation(f)?;
            (a, Some(b))
        }
        _ => (data.clone(), None),
    };
    let scoring = Scoring {
        criterion,
        nn: train.len() as f64,
        floor_train: exact_floor::<T>(variance(&train.output(0))),
        floor_valid: valid
            .as_ref()
            .map(|v| exact_floor::<T>(variance(&v.output(0)))),
        with_d: base.options().with_d,
        offset: base.options().offset,
    };
    let mut candidates: Vec<StructureCandidate> = EffectSet::all_subsets()
        .into_par_iter()
        .map(|set| {
            let settings = base.with_effects(set)?;
            Ok(match settings.fit(&train) {
                Ok(model) => scoring.candidate(set, &model, valid.as_ref()),
                Err(e) => StructureCandidate {
                    effects: set,
                    dn_type: set.dn_type(),
                    mse: f64::INFINITY,
                    score: f64::INFINITY,
                    n_params: 0,
                    order: 0,
                    termination: None,
                    parameters: vec![],
                    error: Some(e.to_string()),
                },
            })
        })
        .collect::<Result<Vec<_>>>()?;
    // lower score first; ties (equal floored fits under validation) go to fewer parameters
    candidates.sort_by(|a, b| {
        a.score
            .total_cmp(&b.score)
            .then(a.n_params.cmp(&b.n_params))
    });
    let first = candidates
        .first()
        .filter(|c| c.score.is_finite())
        .ok_or_else(|| {
            Error::Identification(format!(
                "no effect subset could be fitted: {}",
                candidates
                    .first()
                    .and_then(|c| c.error.clone())
                    .unwrap_or_default()
            ))
        })?;
    Ok(StructureReport {
        criterion,
        chosen: first.effects,
        dn_type: first.dn_type,
        candidates,
    })
}

/// How a fitted candidate is scored: the criterion, the training length, the exact-fit floors
/// of the training and validation records, the base settings' feed-through and offset (counted
/// as parameters).
struct Scoring {
    criterion: Criterion,
    nn: f64,
    floor_train: f64,
    floor_valid: Option<f64>,
    with_d: bool,
    offset: bool,
}

impl Scoring {
    /// The table row of the model fitted with the effects `set` (scored on `valid` under the
    /// validation criterion).
    fn candidate<T: Real>(
        &self,
        set: EffectSet,
        model: &HammersteinModel<T>,
        valid: Option<&IoData<T>>,
    ) -> StructureCandidate {
        let nn = self.nn;
        let order = model.linear().order();
        let k = model.nonlinearity().params().len()
            + 2 * order
            + usize::from(self.with_d)
            + usize::from(self.offset);
        let (mse, score) = match (valid, self.criterion) {
            (Some(v), _) => match model.simulate_on(v) {
                Ok(sim) => {
                    let y = v.output(0);
                    let m = crate::fit::numerics::linear_ls::mse(&y, &sim.y_hat);
                    (m, m.max(self.floor_valid.unwrap_or(0.0)))
                }
                Err(_) => (f64::INFINITY, f64::INFINITY),
            },
            (None, Criterion::Aic) => {
                let m = model.report().train_mse;
                (m, nn * m.max(self.floor_train).ln() + 2.0 * k as f64)
            }
            (None, _) => {
                let m = model.report().train_mse;
                (m, nn * m.max(self.floor_train).ln() + k as f64 * nn.ln())
            }
        };
        StructureCandidate {
            effects: set,
            dn_type: set.dn_type(),
            mse,
            score: if score.is_nan() { f64::INFINITY } else { score },
            n_params: k,
            order,
            termination: Some(model.report().termination),
            parameters: model.parameters(),
            error: None,
        }
    }
}
