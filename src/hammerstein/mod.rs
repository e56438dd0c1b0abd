//! The iterative Hammerstein loop: settings, the fitted model, refinement and structure selection.
//! Joins `regressors` and `subspace`.
