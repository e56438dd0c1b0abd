//! The guided loop on the user's own data (`hammerstein diagnose --follow`, the demo): fit,
//! diagnose, take the top suggestion's settings change, refit — until the residuals are
//! consistent with noise, nothing helps, the suggestion cannot be applied, or a step limit.

use super::diagnose::Diagnoser;
use super::outcome::{Diagnosis, Suggestion};
use crate::data::IoData;
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
}

/// A followed sequence of steps.
#[derive(Debug, Clone)]
pub struct Followed<T: Real> {
    /// Every step, the starting model first.
    pub steps: Vec<FollowStep<T>>,
    /// Why it stopped.
    pub stop: FollowStop,
}

impl<T: Real> Followed<T> {
    /// The last step (the final model and its diagnosis).
    pub fn last(&self) -> Option<&FollowStep<T>> {
        self.steps.last()
    }

    /// The steps whose validation MSE is higher than the previous step's: there the training
    /// criterion and the held-out data disagree (a system outside the model class, or a
    /// validation record unlike the training one).
    pub fn validation_rose(&self) -> Vec<usize> {
        self.steps
            .windows(2)
            .enumerate()
            .filter(|(_, w)| {
                w[1].diagnosis.validation.metrics.mse > w[0].diagnosis.validation.metrics.mse
            })
            .map(|(i, _)| i + 1)
            .collect()
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
    /// (not fitted again).
    pub fn follow(
        &self,
        start: &Hammerstein<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        max_steps: usize,
    ) -> Result<Followed<T>> {
        self.follow_with(start, train, validation, max_steps, None)
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
        self.follow_with(start, train, validation, max_steps, Some(observer))
    }

    fn follow_with(
        &self,
        start: &Hammerstein<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        max_steps: usize,
        observer: Option<&dyn Observer>,
    ) -> Result<Followed<T>> {
        let mut model = match observer {
            Some(o) => start.fit_observed(train, o)?,
            None => start.fit(train)?,
        };
        let mut change = "start".to_string();
        let mut steps = Vec::new();
        loop {
            let diagnosis = self.run(&model, train, validation, observer)?;
            let stop = if diagnosis.adequate {
                Some(FollowStop::Adequate)
            } else if diagnosis.suggestions.is_empty() {
                Some(FollowStop::NothingHelps)
            } else if steps.len() >= max_steps {
                Some(FollowStop::MaxSteps)
            } else {
                None
            };
            // the best suggestion this model class can act on: one that cannot be applied (a
            // change outside the class) passes the turn to the next in rank
            let next = match stop {
                Some(_) => None,
                None => {
                    let mut first_error = None;
                    let mut chosen = None;
                    for s in &diagnosis.suggestions {
                        let applied = diagnosis.apply(s).and_then(|_| {
                            diagnosis
                                .refitted(s)
                                .cloned()
                                .ok_or_else(|| Error::InvalidParameter("no refitted model".into()))
                        });
                        match applied {
                            Ok(m) => {
                                chosen = Some(Ok((m, s.action.label())));
                                break;
                            }
                            Err(e) => {
                                first_error.get_or_insert(e);
                            }
                        }
                    }
                    chosen.or_else(|| first_error.map(Err))
                }
            };
            steps.push(FollowStep {
                change: change.clone(),
                model,
                diagnosis,
            });
            match (stop, next) {
                (Some(stop), _) => return Ok(Followed { steps, stop }),
                (None, Some(Ok((m, label)))) => {
                    model = m;
                    change = label;
                }
                (None, Some(Err(e))) => {
                    return Ok(Followed {
                        steps,
                        stop: FollowStop::CannotApply(e.to_string()),
                    });
                }
                (None, None) => unreachable!("a step without a stop has a next model"),
            }
        }
    }
}
