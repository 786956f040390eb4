//! How good a result is: error norms against exact fields, probes and Richardson
//! extrapolation ([`post`]), the checks that turn a doubtful result into a warning
//! ([`warnings`]), and the nonlocal-to-local comparison with the peridynamic run's
//! estimate ([`compare`]).

pub mod compare;
pub mod post;
pub mod warnings;
