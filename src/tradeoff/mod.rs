//! The speed-accuracy trade-off of a scene (`mlsm tradeoff`): which configurations to
//! run and in which order ([`design`]), each as a scene file ([`variant`]), and the
//! Pareto front of their cost and error ([`front`]). The command in `app` runs them
//! one by one as separate processes (so each has its own peak memory and can be
//! stopped at the budget) and writes the tables and the plot.

pub mod design;
pub mod front;
pub mod hp;
pub mod request;
pub mod target;
pub mod variant;
