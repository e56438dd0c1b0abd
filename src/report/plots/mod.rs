//! One file per plot of the report: the output against the measurement, the residual in time and
//! by the input's direction, the correlation tests, the estimated nonlinearity and output map, the
//! order candidates, the guided loop's steps, and the best linear approximation per level.

pub mod bla_plot;
pub(crate) mod correlation_plot;
pub(crate) mod feedback_plot;
pub(crate) mod nonlinearity_plot;
pub(crate) mod order_plot;
pub(crate) mod output_map_plot;
pub(crate) mod output_plot;
pub(crate) mod residual_direction_plot;
pub(crate) mod residual_time_plot;
pub(crate) mod steps_plot;
