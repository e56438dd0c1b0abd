//! Model diagnosis: compare a model with measurements, residual tests, and ranked suggestions of
//! the physical effect the model is missing.
