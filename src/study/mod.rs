//! Reproducible studies: the paper's Example 1 Monte Carlo runs with the Cramér–Rao bound.
