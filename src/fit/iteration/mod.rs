//! The paper's iterative subspace loop: one fit's fixed data and iterate (`problem.rs`), one
//! pass of its steps with the bounded 1-D search (`search.rs`), the start (`init.rs`), the
//! nonlinearity's initial direction (`initial_direction.rs`) and the loop as state + step +
//! termination (`loop_state.rs`).

pub(crate) mod init;
pub(crate) mod initial_direction;
pub(crate) mod loop_state;
pub(crate) mod problem;
pub(crate) mod search;
