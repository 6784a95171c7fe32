//! Least-squares fitting of model parameters to any source.
