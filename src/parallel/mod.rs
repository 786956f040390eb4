//! Runs over MPI ranks, and the only place that knows about them: the PETSc and MPI
//! binding ([`petsc`], behind the feature `petsc`), how the nodes are split among the
//! ranks ([`partition`], [`share`]), the distributed solve ([`distributed`]) and the solver each rank runs
//! ([`launch`]).
//! A model holds a [`share::Share`] and asks it which nodes are its own and to sum
//! over the ranks; in one process the share is the whole node set.

pub mod distributed;
pub mod launch;
pub mod partition;
pub mod petsc;
pub mod share;
