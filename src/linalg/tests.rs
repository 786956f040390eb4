//! Cross-solver tests on a collocation-like system.
