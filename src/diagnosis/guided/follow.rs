//! The guided loop on the user's own data (`hammerstein diagnose --follow`, the demo): fit,
//! diagnose, take the top suggestion's settings change, refit — until the residuals are
//! consistent with noise, nothing helps, the suggestion cannot be applied, or a step limit.

use super::confirm::{Confirmation, Confirmer};
use super::follow_options::FollowOptions;
use crate::data::IoData;
use crate::diagnosis::diagnoser::diagnose::Diagnoser;
use crate::diagnosis::diagnoser::outcome::{Diagnosis, Suggestion};
use crate::error::{Error, Result};
use crate::fit::{Hammerstein, HammersteinModel, Observer};
use crate::real::Real;
use serde::Serialize;

/// Why a followed sequence stopped.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "reason", content = "detail")]
pub enum FollowStop {
    /// The last model's residuals are consistent with noise.
    Adequate,
    /// Residual tests still fail but no candidate passes the training criterion.
    NothingHelps,
    /// No suggestion names a change this model class can make (the first one's reason).
    CannotApply(String),
    /// The step limit was reached.
    MaxSteps,
    /// The next step was not confirmed on the held-back part of the training record
    /// ([`super::confirm`]): not taken (the check, as text).
    NotConfirmed(String),
    /// The time budget was spent: stopped after the step in progress.
    TimeBudget,
}

impl std::fmt::Display for FollowStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FollowStop::Adequate => write!(f, "the residuals are consistent with noise"),
            FollowStop::NothingHelps => write!(
                f,
                "residual tests still fail but no candidate passes the training criterion"
            ),
            FollowStop::CannotApply(m) => {
                write!(
                    f,
                    "no suggestion is a change this model class can make: {m}"
                )
            }
            FollowStop::MaxSteps => write!(f, "the step limit was reached"),
            FollowStop::NotConfirmed(m) => write!(
                f,
                "the next step is not confirmed on the held-back part of the training record: {m}"
            ),
            FollowStop::TimeBudget => write!(
                f,
                "the time budget was spent (stopped after the step in progress; its model is kept)"
            ),
        }
    }
}

/// One step of a followed sequence: the model, its diagnosis, and what changed to get there.
#[derive(Debug, Clone)]
pub struct FollowStep<T: Real> {
    /// What changed from the previous step ("start", "+ hysteresis", "order 3", "delay 2").
    pub change: String,
    /// The model fitted at this step.
    pub model: HammersteinModel<T>,
    /// Its diagnosis.
    pub diagnosis: Diagnosis<T>,
    /// The step's check on the held-back part of the training record (`None`: the start, or
    /// the loop run without checks).
    pub confirmation: Option<Confirmation>,
}

/// A followed sequence of steps.
#[derive(Debug, Clone)]
pub struct Followed<T: Real> {
    /// Every step, the starting model first.
    pub steps: Vec<FollowStep<T>>,
    /// Why it stopped.
    pub stop: FollowStop,
    /// What the final check found on the model the loop ended with (an effect the input cannot
    /// identify, a parameter at its null value, an order the record does not support), one
    /// sentence each; a part it dropped is a step of its own (`super::final_check`).
    pub final_check: Vec<String>,
    /// The step the loop proposed but did not take because the held-back data did not confirm
    /// it: its label and check.
    pub refused: Option<(String, Confirmation)>,
}

impl<T: Real> Followed<T> {
    /// The last step (the final model and its diagnosis).
    pub fn last(&self) -> Option<&FollowStep<T>> {
        self.steps.last()
    }

    /// The model the guided loop ends with (the last step's, after the final check): the one
    /// `diagnose --follow --save` writes.
    pub fn model(&self) -> Option<&HammersteinModel<T>> {
        self.steps.last().map(|s| &s.model)
    }

    /// The steps whose validation MSE is higher than the previous step's: there the training
    /// criterion and the held-out data disagree (a system outside the model class, or a
    /// validation record unlike the training one).
    pub fn validation_rose(&self) -> Vec<usize> {
        rises(
            self.steps
                .iter()
                .map(|s| s.diagnosis.validation.metrics.mse),
        )
    }
}

impl<T: Real> Diagnoser<T> {
    /// The settings that act on `suggestion` for `model` (the candidate's own settings change:
    /// an effect added at the model's order, an order, a delay, …), and a short label of the
    /// change.
    pub fn next_settings(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        suggestion: &Suggestion,
    ) -> Result<(Hammerstein<T>, String)> {
        let candidate =
            self.candidates()
                .get(&suggestion.effect)
                .ok_or_else(|| Error::UnknownCandidate {
                    name: suggestion.effect.to_string(),
                })?;
        let analysis = self.analysis(model, train)?;
        let next = candidate.apply(model, &analysis)?;
        let label = suggestion.action.label();
        Ok((next, label))
    }

    /// From `start`, fits, diagnoses and follows the top suggestion it can act on up to
    /// `max_steps` times; each step's model is the one the diagnosis refitted for the suggestion
    /// (not fitted again), taken when the held-back part of the training record confirms it
    /// ([`FollowOptions::default`]: [`super::confirm`]).
    pub fn follow(
        &self,
        start: &Hammerstein<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        max_steps: usize,
    ) -> Result<Followed<T>> {
        let options = FollowOptions::steps(max_steps);
        self.follow_with(start, train, validation, &options, None)
    }

    /// [`follow`](Self::follow) with `observer` notified by the first fit and by every
    /// diagnosis ([`Diagnoser::diagnose_observed`]).
    pub fn follow_observed(
        &self,
        start: &Hammerstein<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        max_steps: usize,
        observer: &dyn Observer,
    ) -> Result<Followed<T>> {
        let options = FollowOptions::steps(max_steps);
        self.follow_with(start, train, validation, &options, Some(observer))
    }

    /// [`follow`](Self::follow) with its options (step limit, confirmation rule, time budget)
    /// and an optional observer.
    pub fn follow_with(
        &self,
        start: &Hammerstein<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        options: &FollowOptions,
        observer: Option<&dyn Observer>,
    ) -> Result<Followed<T>> {
        let clock = std::time::Instant::now();
        let model = match observer {
            Some(o) => start.fit_observed(train, o)?,
            None => start.fit(train)?,
        };
        let mut confirmer = options
            .confirm
            .map(|rule| Confirmer::new(rule, &model, train));
        let mut checks: Vec<Confirmation> = Vec::new();
        // order raises refused because the record does not support them (`final_check.rs`)
        let mut unsupported: Vec<String> = Vec::new();
        let mut override_stop: Option<(FollowStop, Option<(String, Confirmation)>)> = None;
        let (steps, stop) = drive(
            model,
            options.max_steps,
            |m| self.run(m, train, validation, observer),
            |d| (d.adequate, !d.suggestions.is_empty()),
            |d, current| {
                if options.time_budget.is_some_and(|b| clock.elapsed() >= b) {
                    override_stop = Some((FollowStop::TimeBudget, None));
                    return Err(Error::InvalidParameter("time budget spent".into()));
                }
                let (m, label) = first_applicable(d, current, train, &mut unsupported)?;
                if let Some(c) = confirmer.as_mut() {
                    let effect = d
                        .suggestions
                        .iter()
                        .find(|s| s.action.label() == label && d.refitted(s).is_some())
                        .map(|s| s.effect.clone());
                    let check = match effect {
                        Some(effect) => c.check(self, &effect, &m),
                        None => Confirmation::unchecked("its suggestion was not found".into()),
                    };
                    if !check.confirmed {
                        override_stop = Some((
                            FollowStop::NotConfirmed(format!("{label}: {}", check.text())),
                            Some((label.clone(), check)),
                        ));
                        return Err(Error::InvalidParameter("not confirmed".into()));
                    }
                    checks.push(check);
                }
                Ok((m, label))
            },
        )?;
        let (stop, refused) = match (stop, override_stop) {
            (FollowStop::CannotApply(_), Some((stop, refused))) => (stop, refused),
            (stop, _) => (stop, None),
        };
        let mut checks = checks.into_iter();
        let mut steps: Vec<FollowStep<T>> = steps
            .into_iter()
            .enumerate()
            .map(|(i, (change, model, diagnosis))| FollowStep {
                change,
                model,
                diagnosis,
                confirmation: if i == 0 { None } else { checks.next() },
            })
            .collect();
        // the final check on the model the loop ended with (`final_check.rs`)
        let (extra, mut final_check) = match (steps.first(), steps.last()) {
            (Some(f), Some(l)) => {
                self.check_final(&f.model, &l.model, train, validation, observer)?
            }
            _ => (Vec::new(), Vec::new()),
        };
        unsupported.dedup();
        final_check.splice(0..0, unsupported);
        steps.extend(
            extra
                .into_iter()
                .map(|(change, model, diagnosis)| FollowStep {
                    change,
                    model,
                    diagnosis,
                    confirmation: None,
                }),
        );
        Ok(Followed {
            steps,
            stop,
            final_check,
            refused,
        })
    }
}

/// The refitted model of the best suggestion this model class can act on, with its label: one
/// that cannot be applied (a change outside the class) passes the turn to the next in rank; the
/// first error when none can. A refit that trains worse than `model`, the model it extends, is
/// not taken (`final_check::no_worse_on_training`), nor an order raise the record does not
/// support (`final_check::unsupported_order`: its block is unstable), which is said in
/// `unsupported`.
fn first_applicable<T: Real>(
    d: &Diagnosis<T>,
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    unsupported: &mut Vec<String>,
) -> Result<(HammersteinModel<T>, String)> {
    // a nonlinearity in feedback named first lies outside the class: the loop stops there
    // (the command line adds the feedback model as its last step) rather than patching the
    // Hammerstein model with the next suggestion
    if let Some(s) = d
        .suggestions
        .first()
        .filter(|s| s.effect == crate::diagnosis::ids::CandidateId::FeedbackNonlinearity)
    {
        return Err(Error::NotApplicable {
            effect: s.effect.to_string(),
            change: s.change.clone(),
        });
    }
    let mut first_error = None;
    for s in &d.suggestions {
        let applied = d.apply(s).and_then(|_| {
            d.refitted(s)
                .cloned()
                .ok_or_else(|| Error::InvalidParameter("no refitted model".into()))
                .and_then(|m| super::final_check::no_worse_on_training(model, m, train))
        });
        let applied =
            applied.and_then(
                |m| match super::final_check::unsupported_order(model, &m, train) {
                    Some(note) => {
                        unsupported.push(note.clone());
                        Err(Error::Identification(note))
                    }
                    None => Ok(m),
                },
            );
        match applied {
            Ok(m) => return Ok((m, s.action.label())),
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    Err(first_error.unwrap_or_else(|| Error::InvalidParameter("no suggestion".into())))
}

/// The guided loop, for one input and for several: diagnose the model; stop when it is
/// adequate (`verdict`'s first flag), when no suggestion is left (its second) or after
/// `max_steps` changes; otherwise `act` on the diagnosis (the next model and the change's label;
/// an error stops the loop as [`FollowStop::CannotApply`]) and repeat. Every step as
/// (change, model, diagnosis), the first labelled "start".
pub(crate) fn drive<M, D>(
    mut model: M,
    max_steps: usize,
    mut diagnose: impl FnMut(&M) -> Result<D>,
    verdict: impl Fn(&D) -> (bool, bool),
    mut act: impl FnMut(&D, &M) -> Result<(M, String)>,
) -> Result<(Vec<(String, M, D)>, FollowStop)> {
    let mut change = "start".to_string();
    let mut steps = Vec::new();
    loop {
        let diagnosis = diagnose(&model)?;
        let (adequate, has_suggestions) = verdict(&diagnosis);
        let stop = if adequate {
            Some(FollowStop::Adequate)
        } else if !has_suggestions {
            Some(FollowStop::NothingHelps)
        } else if steps.len() >= max_steps {
            Some(FollowStop::MaxSteps)
        } else {
            None
        };
        let next = match stop {
            Some(_) => None,
            None => Some(act(&diagnosis, &model)),
        };
        steps.push((change, model, diagnosis));
        match (stop, next) {
            (Some(stop), _) => return Ok((steps, stop)),
            (None, Some(Ok((m, label)))) => {
                model = m;
                change = label;
            }
            (None, Some(Err(e))) => return Ok((steps, FollowStop::CannotApply(e.to_string()))),
            (None, None) => unreachable!("a step without a stop has a next model"),
        }
    }
}

/// The steps (1-based, counting from the start) whose validation MSE rose over the previous
/// step's, given every step's validation MSE in order.
pub(crate) fn rises(mses: impl IntoIterator<Item = f64>) -> Vec<usize> {
    let m: Vec<f64> = mses.into_iter().collect();
    m.windows(2)
        .enumerate()
        .filter(|(_, w)| w[1] > w[0])
        .map(|(i, _)| i + 1)
        .collect()
}
