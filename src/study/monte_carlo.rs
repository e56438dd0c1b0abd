//! The Monte Carlo study of Example 1: M seeded runs of each of the paper's seven settings
//! (Table 2: UDN structure assumed, noise-free / 10 / 8 dB; Table 3: exact SH structure,
//! noise-free / 10 / 8 / 5 dB), with the mean and standard deviation of every parameter
//! (the paper's eq. 23, divisor M).
//!
//! Run k of every setting uses seed `base + k`, so the settings share inputs and noise shapes
//! (common random numbers) and Tables 2 and 3 are computed on the same records. Runs are
//! parallel over rayon; the linear algebra inside each fit stays sequential (faer `Par::Seq`).

use super::example1::{Example1, PARAM_NAMES, true_value};
use crate::error::{Error, Result};
use crate::fit::{Criterion, Hammerstein, HammersteinModel, select_structure};
use crate::real::Real;
use crate::regressors::{Effect, EffectSet};
use crate::subspace::{MethodKind, Order};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which of the paper's tables a setting belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Table {
    /// Table 2: the structure is unknown, the full UDN is assumed.
    Table2,
    /// Table 3: the exact SH structure is fitted.
    Table3,
}

impl Table {
    /// The table's number (2 or 3).
    pub fn number(self) -> u8 {
        match self {
            Table::Table2 => 2,
            Table::Table3 => 3,
        }
    }
    /// Parameters the table reports.
    pub fn params(self) -> &'static [&'static str] {
        match self {
            Table::Table2 => &super::paper_tables::TABLE2_PARAMS,
            Table::Table3 => &super::paper_tables::TABLE3_PARAMS,
        }
    }
}

/// One setting of the study: a table and an SNR.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    /// The table.
    pub table: Table,
    /// SNR in dB (`None`: noise-free).
    pub snr_db: Option<f64>,
}

/// The paper's seven settings, Table 2 first.
pub fn paper_settings() -> Vec<Setting> {
    let t2 = [None, Some(10.0), Some(8.0)].map(|snr_db| Setting {
        table: Table::Table2,
        snr_db,
    });
    let t3 = [None, Some(10.0), Some(8.0), Some(5.0)].map(|snr_db| Setting {
        table: Table::Table3,
        snr_db,
    });
    t2.into_iter().chain(t3).collect()
}

/// How each run is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// The best configuration: Table 2 decides the structure by BIC over the 16 UDN effect subsets
    /// (absent effects' parameters are then 0) and refits the chosen one; both tables refine the
    /// loop's result on the simulation error.
    #[default]
    Best,
    /// The paper's loop alone: full UDN for Table 2, SH for Table 3, no refinement, no structure
    /// decision.
    PaperLoop,
}

/// Settings of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyConfig {
    /// Monte Carlo runs M per setting.
    pub runs: usize,
    /// Base seed: run k uses `seed + k`.
    pub seed: u64,
    /// Subspace method of the loop.
    pub method: MethodKind,
    /// How each run is estimated.
    pub strategy: Strategy,
    /// The settings to run.
    pub settings: Vec<Setting>,
    /// Samples per record (paper: 2000).
    pub n: usize,
}

impl Default for StudyConfig {
    fn default() -> Self {
        Self {
            runs: 50,
            seed: 1,
            method: MethodKind::Moesp,
            strategy: Strategy::Best,
            settings: paper_settings(),
            n: 2000,
        }
    }
}

/// Monte Carlo statistics of one parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamStats {
    /// Parameter name.
    pub name: String,
    /// True value.
    pub truth: f64,
    /// Mean over the successful runs.
    pub mean: f64,
    /// Standard deviation, divisor M (eq. 23).
    pub std: f64,
    /// Root mean square error about the true value.
    pub rmse: f64,
    /// Largest absolute error of a run.
    pub max_abs_error: f64,
}

/// The outcome of one setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettingResult {
    /// The setting.
    pub setting: Setting,
    /// Per-parameter statistics, in the table's order.
    pub params: Vec<ParamStats>,
    /// Runs whose estimate entered the statistics.
    pub successes: usize,
    /// Errors of the failed runs (seed, message).
    pub failures: Vec<(u64, String)>,
    /// Table 2 with the structure decided: how often each effect set was chosen (label, count).
    pub structures: Vec<(String, usize)>,
    /// The estimates of every successful run (seed, values in the table's order).
    pub estimates: Vec<(u64, Vec<f64>)>,
}

impl SettingResult {
    /// Statistics of one parameter by name.
    pub fn param(&self, name: &str) -> Option<&ParamStats> {
        self.params.iter().find(|p| p.name == name)
    }
}

/// One run's estimate: the table's parameters (in order) and the chosen structure (Table 2, best).
#[derive(Debug, Clone, PartialEq)]
pub struct RunEstimate {
    /// Values in the table's parameter order.
    pub values: Vec<f64>,
    /// The effect set fitted.
    pub structure: EffectSet,
}

fn sh_set() -> EffectSet {
    EffectSet::of(&[Effect::Hysteresis, Effect::Saturation])
}

/// The loop settings for a table and strategy (order 2 and no feed-through as in the paper's
/// G(z), no offset: the records have none).
pub fn estimator<T: Real>(table: Table, strategy: Strategy, method: MethodKind) -> Hammerstein<T> {
    let base = match table {
        Table::Table2 => Hammerstein::udn(EffectSet::all()),
        Table::Table3 => Hammerstein::udn(sh_set()),
    };
    base.method(method)
        .order(Order::Fixed(2))
        .with_d(false)
        .offset(false)
        .refine(strategy == Strategy::Best)
}

/// Reads the table's parameters from a fitted model: nonlinearity parameters by name (absent
/// effects: b, e1, e2 = 0; a = 0 without hysteresis; z1, z2 = ±∞ without saturation) and a1, a2,
/// b1, b2 from the transfer function z⁻¹(b1 + b2 z⁻¹)/(1 + a1 z⁻¹ + a2 z⁻²).
pub fn table_values<T: Real>(model: &HammersteinModel<T>, table: Table) -> Result<Vec<f64>> {
    let nl = model.parameters();
    let tf = model.transfer_function()?;
    let coef = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
    table
        .params()
        .iter()
        .map(|&name| {
            Ok(match name {
                "a1" => coef(&tf.denominator, 1),
                "a2" => coef(&tf.denominator, 2),
                "b1" => coef(&tf.numerator, 1),
                "b2" => coef(&tf.numerator, 2),
                _ => match nl.iter().find(|(n, _)| n == name) {
                    Some((_, v)) => *v,
                    None => match name {
                        "z1" => f64::INFINITY,
                        "z2" => f64::NEG_INFINITY,
                        "p" => {
                            return Err(Error::Identification(
                                "the fitted nonlinearity has no gain p".into(),
                            ));
                        }
                        _ => 0.0,
                    },
                },
            })
        })
        .collect()
}

/// Estimates one record for a setting.
pub fn estimate_run<T: Real>(
    data: &crate::data::IoData<T>,
    table: Table,
    strategy: Strategy,
    method: MethodKind,
) -> Result<RunEstimate> {
    let settings = estimator::<T>(table, strategy, method);
    let structure = match (table, strategy) {
        (Table::Table2, Strategy::Best) => {
            // BIC over the 16 subsets with the paper's loop, then the chosen one refined.
            select_structure(&settings.clone().refine(false), data, Criterion::Bic)?.chosen
        }
        (Table::Table2, Strategy::PaperLoop) => EffectSet::all(),
        (Table::Table3, _) => sh_set(),
    };
    let model = settings.with_effects(structure)?.fit(data)?;
    Ok(RunEstimate {
        values: table_values(&model, table)?,
        structure,
    })
}

/// Mean, std (divisor M), RMSE and largest error of one parameter's estimates.
pub fn param_stats(name: &str, values: &[f64]) -> ParamStats {
    let truth = true_value(name).unwrap_or(f64::NAN);
    let m = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / m;
    let std = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / m).sqrt();
    let rmse = (values.iter().map(|v| (v - truth).powi(2)).sum::<f64>() / m).sqrt();
    let max_abs_error = values.iter().fold(0.0f64, |a, v| a.max((v - truth).abs()));
    ParamStats {
        name: name.to_string(),
        truth,
        mean,
        std,
        rmse,
        max_abs_error,
    }
}

/// Runs the study; `progress` is called once per finished run (from worker threads).
pub fn run_study<T: Real>(
    config: &StudyConfig,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<SettingResult>> {
    if config.runs == 0 {
        return Err(Error::InvalidParameter(
            "the study needs at least one run".into(),
        ));
    }
    debug_assert!(PARAM_NAMES.len() == 11);
    let jobs: Vec<(usize, u64)> = (0..config.settings.len())
        .flat_map(|s| (0..config.runs).map(move |k| (s, config.seed.wrapping_add(k as u64))))
        .collect();
    let outcomes: Vec<(usize, u64, Result<RunEstimate>)> = jobs
        .into_par_iter()
        .map(|(s, seed)| {
            let setting = config.settings[s];
            let design = Example1 {
                n: config.n,
                ..Example1::new(setting.snr_db)
            };
            let res = design
                .generate::<T>(seed)
                .and_then(|d| estimate_run(&d.data, setting.table, config.strategy, config.method));
            progress();
            (s, seed, res)
        })
        .collect();
    let mut results = Vec::with_capacity(config.settings.len());
    for (s, &setting) in config.settings.iter().enumerate() {
        let mut estimates = Vec::new();
        let mut failures = Vec::new();
        let mut structures: Vec<(String, usize)> = Vec::new();
        for (_, seed, res) in outcomes.iter().filter(|o| o.0 == s) {
            match res {
                Ok(est) if est.values.iter().all(|v| v.is_finite()) => {
                    estimates.push((*seed, est.values.clone()));
                    let label = est.structure.label();
                    match structures.iter_mut().find(|(l, _)| *l == label) {
                        Some(e) => e.1 += 1,
                        None => structures.push((label, 1)),
                    }
                }
                Ok(est) => {
                    let label = est.structure.label();
                    failures.push((*seed, format!("non-finite estimate (structure {label})")));
                    match structures.iter_mut().find(|(l, _)| *l == label) {
                        Some(e) => e.1 += 1,
                        None => structures.push((label, 1)),
                    }
                }
                Err(e) => failures.push((*seed, e.to_string())),
            }
        }
        structures.sort_by_key(|b| std::cmp::Reverse(b.1));
        let params = setting
            .table
            .params()
            .iter()
            .enumerate()
            .map(|(i, &name)| {
                let vals: Vec<f64> = estimates.iter().map(|(_, v)| v[i]).collect();
                param_stats(name, &vals)
            })
            .collect();
        results.push(SettingResult {
            setting,
            params,
            successes: estimates.len(),
            failures,
            structures,
            estimates,
        });
    }
    Ok(results)
}
