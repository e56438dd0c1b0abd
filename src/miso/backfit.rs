//! The several-input fit by backfitting: each branch fitted by the single-input method to its
//! partial residual, in sweeps, until the total training MSE settles (see the module docs).
//!
//! Sweep 0 fits every branch to its partial residual (the other inputs' contributions from the
//! linear start or from the branches fitted before it): the last branch completely (order
//! selection, feed-through decision, refinement), the others — when their order or feed-through
//! is automatic — provisionally, at the singular-value gap's order without feed-through (one
//! loop, the order selection's own first candidate), since their residual still holds the
//! linear start's approximation of the later inputs. From sweep 1 on (from sweep 0 with
//! `refit_from`) every branch is refitted warm (`Hammerstein::fit_from` at its order and
//! feed-through, from its poles and parameters); a branch whose structure is provisional, or
//! whose structure was selected while another branch had a different order or feed-through
//! than it has now, is also refitted completely, and the lower information criterion on its
//! partial residual wins. Once a sweep changes no branch's order or feed-through: warm refits
//! only. A refit replaces the branch only when the total training MSE does not rise (at another
//! order or feed-through: when the information criterion does not rise). Stops when the
//! structures are settled and a sweep lowers the total MSE by less than the tolerance
//! (relative), the fit is exact to round-off, or at the sweep limit. Then all branches are
//! refined jointly (`fit::refine_jointly`: Levenberg–Marquardt over every branch's parameters on
//! the total output error), kept when the total training MSE falls.

use super::horizon::{BaseClaim, base_claim, raised_from};
use super::linear_start::linear_start;
use super::model::{MisoModel, mse_of_sum};
use super::partial::partial_record;
use super::report::{MisoReport, SweepRecord};
use super::settings::MisoHammerstein;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::order_selection::{criterion, exact_floor_of, training_mse_of};
use crate::fit::{Hammerstein, HammersteinModel, RefineReport, refine_jointly};
use crate::real::Real;
use crate::subspace::Order;

impl<T: Real> MisoHammerstein<T> {
    /// Fits one branch per input of `data` (its inputs in the settings' branch order, one
    /// output) by backfitting.
    pub fn fit(&self, data: &IoData<T>) -> Result<MisoModel<T>> {
        self.check_record(data)?;
        Backfit::new(self, data, None, true)?.run()
    }

    /// Fits from a fitted model: every branch starts from `base`'s and keeps its order and
    /// feed-through (warm refits only).
    pub fn fit_from(&self, data: &IoData<T>, base: &MisoModel<T>) -> Result<MisoModel<T>> {
        self.fit_from_with(data, base, false)
    }

    /// Fits from a fitted model with every branch's order and feed-through selected again: the
    /// first sweep refits every branch warm and completely and keeps the lower BIC, the later
    /// ones the branches beside which another branch's structure changed, until no structure
    /// changes — e.g. after one branch was replaced by a diagnosis' refit, since the other
    /// branches' orders were chosen while that branch lacked its effect.
    pub fn refit_from(&self, data: &IoData<T>, base: &MisoModel<T>) -> Result<MisoModel<T>> {
        self.fit_from_with(data, base, true)
    }

    fn fit_from_with(
        &self,
        data: &IoData<T>,
        base: &MisoModel<T>,
        reselect: bool,
    ) -> Result<MisoModel<T>> {
        self.check_record(data)?;
        if base.branches().len() != self.branches.len() {
            return Err(Error::Dimension(format!(
                "the base model has {} branches, the settings {}",
                base.branches().len(),
                self.branches.len()
            )));
        }
        Backfit::new(self, data, Some(base), reselect)?.run()
    }

    fn check_record(&self, data: &IoData<T>) -> Result<()> {
        self.validate()?;
        if data.n_inputs() != self.branches.len() {
            return Err(Error::Dimension(format!(
                "the record has {} inputs ({}), the settings {} branches",
                data.n_inputs(),
                data.input_names().join(", "),
                self.branches.len()
            )));
        }
        if data.n_outputs() != 1 {
            return Err(Error::Dimension(format!(
                "a several-input Hammerstein model has one output; the record has {}",
                data.n_outputs()
            )));
        }
        Ok(())
    }
}

/// The backfitting's state: the branches fitted so far and their training contributions.
struct Backfit<'a, T: Real> {
    settings: &'a MisoHammerstein<T>,
    data: &'a IoData<T>,
    models: Vec<Option<HammersteinModel<T>>>,
    contributions: Vec<Vec<T>>,
    warm_start: bool,
    floor: f64,
    /// Whether the branches' structures (order, feed-through) may still change: the sweeps
    /// after the first also try a complete fit of each branch until a sweep changes none.
    structure_open: bool,
    /// Whether a branch's structure changed in the current sweep.
    structure_changed: bool,
    /// For each branch, the other branches' structures when its own was last selected (`None`
    /// before its first complete fit): its structure is selected again only when they differ.
    seen: Vec<Option<Structures>>,
    /// What each branch of the base model said about its horizon (all `None` for a fresh
    /// fit): a refit at the horizon the base stood raised at still stands raised.
    base_claims: Vec<BaseClaim>,
}

/// Every branch's structure (order, feed-through); `None` for a branch not fitted yet (the
/// linear start's contribution).
type Structures = Vec<Option<(usize, bool)>>;

/// A model's structure: its order and whether it has a feed-through.
fn structure_of<T: Real>(m: &HammersteinModel<T>) -> (usize, bool) {
    (m.linear().order(), m.has_feedthrough())
}

impl<'a, T: Real> Backfit<'a, T> {
    fn new(
        settings: &'a MisoHammerstein<T>,
        data: &'a IoData<T>,
        base: Option<&MisoModel<T>>,
        reselect: bool,
    ) -> Result<Self> {
        let m = settings.branches.len();
        let floor = exact_floor_of(data);
        let base_claims = match base {
            Some(b) => b.branches().iter().map(base_claim).collect(),
            None => vec![None; m],
        };
        let (models, contributions) = match base {
            None => (
                vec![None; m],
                linear_start(data).unwrap_or_else(|| vec![Vec::new(); m]),
            ),
            Some(b) => {
                let sim = b.simulate_on(data)?;
                (
                    b.branches().iter().cloned().map(Some).collect(),
                    sim.contributions,
                )
            }
        };
        Ok(Self {
            settings,
            data,
            models,
            contributions,
            warm_start: base.is_some(),
            floor,
            structure_open: base.is_none() || reselect,
            structure_changed: false,
            seen: vec![None; m],
            base_claims,
        })
    }

    /// The other branches' structures as branch `i` sees them (its own entry blank).
    fn others(&self, i: usize) -> Structures {
        let mut s: Structures = self
            .models
            .iter()
            .map(|m| m.as_ref().map(structure_of))
            .collect();
        if let Some(own) = s.get_mut(i) {
            *own = None;
        }
        s
    }

    fn run(mut self) -> Result<MisoModel<T>> {
        let y = self.data.output_slice(0);
        let mut sweeps = Vec::new();
        let mut converged = false;
        let mut last = if self.warm_start {
            mse_of_sum(y, &self.contributions)
        } else {
            f64::INFINITY
        };
        for sweep in 0..self.settings.max_sweeps {
            self.structure_changed = false;
            let kept = (0..self.settings.branches.len())
                .map(|i| self.update(sweep, i))
                .collect::<Result<Vec<bool>>>()?;
            let e = mse_of_sum(y, &self.contributions);
            sweeps.push(SweepRecord { train_mse: e, kept });
            if (sweep >= 1 || self.warm_start) && !self.structure_changed {
                self.structure_open = false;
            }
            // while a structure may still change the sweeps go on
            let settled = !self.structure_open
                && (e.is_nan() || (last.is_finite() && last - e <= self.settings.tolerance * last));
            if settled || e <= self.floor {
                converged = true;
                break;
            }
            last = e;
        }
        let mut train_mse = mse_of_sum(y, &self.contributions);
        let mut branches = self
            .models
            .into_iter()
            .map(|m| m.ok_or_else(|| Error::Identification("a branch was never fitted".into())))
            .collect::<Result<Vec<_>>>()?;
        let runs = self.settings.joint
            && branches.len() >= 2
            && branches.iter().all(|b| b.settings().options().refine)
            && train_mse > self.floor;
        let mut joint_refinement = None;
        if runs {
            let (report, refined) = joint(
                self.data,
                &branches,
                &self.contributions,
                train_mse,
                self.settings.tolerance,
            );
            if let Some((b, mse)) = refined {
                (branches, train_mse) = (b, mse);
            }
            joint_refinement = report;
        }
        // each branch's report states whether the horizon it finished with stands raised (a
        // warm refit copied its base's claim, which may describe another horizon)
        for (i, b) in branches.iter_mut().enumerate() {
            let (Some(requested), Some(&base)) =
                (self.settings.branches.get(i), self.base_claims.get(i))
            else {
                continue;
            };
            b.report.horizon_raised_from = raised_from(requested, base, b);
        }
        let settings = MisoHammerstein {
            branches: branches.iter().map(|b| b.settings().clone()).collect(),
            max_sweeps: self.settings.max_sweeps,
            tolerance: self.settings.tolerance,
            joint: self.settings.joint,
        };
        Ok(MisoModel {
            branches,
            input_names: self.data.input_names().to_vec(),
            output_name: self.data.output_names()[0].clone(),
            settings,
            report: MisoReport {
                sweeps,
                converged,
                train_mse,
                joint_refinement,
            },
        })
    }

    /// The settings of branch `i`'s provisional first fit, `None` when its first fit selects its
    /// structure: every branch but the last of a fresh fit whose order or feed-through is
    /// automatic is first fitted at the order of the singular-value gap without feed-through
    /// (the order selection's own first candidate). Its structure is selected in the next sweep,
    /// beside the other branches' nonlinear fits rather than the linear start's approximation.
    fn provisional_settings(&self, i: usize, settings: &Hammerstein<T>) -> Option<Hammerstein<T>> {
        let o = settings.options();
        let automatic = matches!(o.order, Order::Auto) || o.d_auto;
        if self.warm_start || i + 1 >= self.settings.branches.len() || !automatic {
            return None;
        }
        let order = match &o.order {
            Order::Auto => Order::Gap,
            other => other.clone(),
        };
        let d = o.with_d && !o.d_auto;
        Some(settings.clone().order(order).with_d(d))
    }

    /// The first fit of branch `i` (settings `settings`) to its partial residual `rec`: complete,
    /// or provisional (`provisional_settings`); an error here is the user's to see.
    fn first_fit(&mut self, i: usize, settings: &Hammerstein<T>, rec: &IoData<T>) -> Result<bool> {
        let provisional = self.provisional_settings(i, settings);
        let model = provisional.as_ref().unwrap_or(settings).fit(rec)?;
        // a provisional structure is selected in the next sweep (nothing seen yet)
        if provisional.is_none() {
            self.seen[i] = Some(self.others(i));
        }
        let sim = model.simulate_on(rec)?;
        self.contributions[i] = sim.y_hat;
        self.models[i] = Some(model);
        Ok(true)
    }

    /// Refits branch `i` in sweep `sweep`; true when the refit was kept.
    fn update(&mut self, sweep: usize, i: usize) -> Result<bool> {
        let rec = match partial_record(self.data, i, &self.contributions) {
            Ok(rec) => rec,
            // the other branches explain the output exactly: nothing left for this one to fit
            Err(Error::ConstantOutput { .. }) if self.models[i].is_some() => return Ok(false),
            Err(e) => return Err(e),
        };
        let settings = self
            .settings
            .branch_settings(i)
            .ok_or_else(|| Error::Dimension(format!("no settings for input {}", i + 1)))?;
        let Some(current) = self.models[i].as_ref() else {
            return self.first_fit(i, &settings, &rec);
        };
        let theta: Vec<f64> = current
            .nonlinearity()
            .params()
            .iter()
            .map(|t| t.as_f64())
            .collect();
        // a complete refit (order and feed-through selected again) only when the structures
        // this branch's was selected beside have changed since
        let others = self.others(i);
        let try_full = self.structure_open
            && (sweep >= 1 || self.warm_start)
            && self.seen[i].as_ref() != Some(&others);
        if try_full {
            self.seen[i] = Some(others);
        }
        // the warm and the complete refit are independent: run side by side on the pool
        let (warm, full) = rayon::join(
            || {
                settings
                    .clone()
                    .at_structure_of(current)
                    .fit_from(&rec, current, &theta)
            },
            || try_full.then(|| settings.fit(&rec).ok()).flatten(),
        );
        // each fit simulated once: its criterion and, if kept, its contribution
        let r = rec.output_slice(0);
        let var = crate::fit::order_selection::variance_of(r);
        let score = |m: &HammersteinModel<T>, y: &[T]| {
            criterion(m, training_mse_of(m, &rec, y), rec.len(), var)
        };
        let simulated = [warm.ok(), full].into_iter().flatten().filter_map(|m| {
            let y = m.simulate_on(&rec).ok()?.y_hat;
            Some((m, y))
        });
        // the lower criterion wins; the warm refit on a tie
        let Some((candidate, y_hat)) =
            simulated.min_by(|(a, ya), (b, yb)| score(a, ya).total_cmp(&score(b, yb)))
        else {
            return Ok(false);
        };
        let before = crate::fit::order_selection::mse_between(r, &self.contributions[i]);
        let after = crate::fit::order_selection::mse_between(r, &y_hat);
        let changed = structure_of(&candidate) != structure_of(current);
        // the same structure: kept when the total MSE does not rise; another structure (a
        // complete refit chosen by the criterion, possibly of lower order): when the criterion
        // does not rise, so that an order chosen too high can come down
        let keep = if changed {
            criterion(&candidate, after, rec.len(), var)
                <= criterion(current, before, rec.len(), var)
        } else {
            after <= before
        };
        if after.is_nan() || !keep {
            return Ok(false);
        }
        if changed {
            self.structure_changed = true;
        }
        self.contributions[i] = y_hat;
        self.models[i] = Some(candidate);
        Ok(true)
    }
}

/// The joint refinement of the backfitted `branches` (training contributions `contributions`,
/// total MSE `mse_before`) on `data` (`fit::refine_jointly`, stopping at the sweeps'
/// `tolerance`): its report (`None` when it could
/// not start) and, when it lowered the total training MSE, the refined branches — their
/// standard errors recomputed on their new partial residuals — with that MSE.
#[allow(clippy::type_complexity)]
fn joint<T: Real>(
    data: &IoData<T>,
    branches: &[HammersteinModel<T>],
    contributions: &[Vec<T>],
    mse_before: f64,
    tolerance: f64,
) -> (
    Option<RefineReport>,
    Option<(Vec<HammersteinModel<T>>, f64)>,
) {
    let Ok(recs) = (0..branches.len())
        .map(|i| partial_record(data, i, contributions))
        .collect::<Result<Vec<_>>>()
    else {
        return (None, None);
    };
    let Ok((fit, iterations)) =
        refine_jointly(branches, &recs, data.output_slice(0), mse_before, tolerance)
    else {
        return (None, None);
    };
    let mut report = RefineReport {
        mse_before,
        mse_after: mse_before,
        iterations,
        accepted: false,
    };
    let Some(mut fit) = fit else {
        return (Some(report), None);
    };
    for (i, b) in fit.branches.iter_mut().enumerate() {
        if let Ok(rec) = partial_record(data, i, &fit.contributions) {
            crate::fit::uncertainty::attach(b, &rec);
        }
    }
    report.mse_after = fit.mse;
    report.accepted = true;
    (Some(report), Some((fit.branches, fit.mse)))
}
