//! Which nodes of a run this process works on: all of them, or, when the solve is
//! distributed over MPI ranks (`solver.kind = "petsc"`), the Morton block of nodes it
//! owns ([`super::partition::morton_owners`]). A model holds a [`Share`], builds the
//! supports, shapes and rows of the nodes it [`owns`](Share::owns), and lets the share
//! sum what each rank counted ([`Share::sum`]) and solve the rows ([`Share::solve`]).

use super::distributed::{self, Distribution};
use super::partition::morton_owners;
use super::petsc::{self, World};
use crate::linalg::triplets::Entry;
use crate::linalg::{SolveError, SolveReport, SolverKind, SolverParams};

/// A position `[x, y]`.
type Point = [f64; 2];

/// The nodes of a run as this process shares them: whole, or split among MPI ranks
/// (node `i` belongs to rank `owner[i]`, this process is rank `world.rank`).
#[derive(Debug, Clone)]
pub struct Share {
    owner: Option<Vec<u32>>,
    world: World,
}

impl Share {
    /// Every node on this one process.
    pub fn whole() -> Self {
        Share { owner: None, world: World::SERIAL }
    }

    /// Whether `solver` splits the nodes among MPI ranks (PETSc does).
    pub fn splits(solver: &SolverParams) -> bool {
        matches!(solver.kind, SolverKind::Petsc { .. })
    }

    /// The share of `points` for `solver`: Morton blocks over the ranks running when
    /// the solver [`splits`](Share::splits) them, else whole.
    pub fn of(points: &[Point], solver: &SolverParams) -> Self {
        if Self::splits(solver) {
            Self::as_rank(points, petsc::world())
        } else {
            Self::whole()
        }
    }

    /// The share rank `world.rank` of `world.size` holds (Morton blocks of `points`),
    /// as [`Share::of`] makes it under `mpirun`; tests build any rank's share in one
    /// process.
    pub fn as_rank(points: &[Point], world: World) -> Self {
        Share { owner: Some(morton_owners(points, world.size)), world }
    }

    /// The same share with more points appended, each owned by the owner of the node
    /// it follows (`leaders[k]`: the node of appended point `k`, e.g. a ghost's parent).
    pub fn with_followers(self, leaders: &[usize]) -> Self {
        let owner = self.owner.map(|o| {
            let more: Vec<u32> = leaders.iter().map(|&i| o[i]).collect();
            [o, more].concat()
        });
        Share { owner, ..self }
    }

    /// Whether the nodes are split among ranks.
    pub fn is_split(&self) -> bool {
        self.owner.is_some()
    }

    /// Whether this process works on node `i` (always, unless split).
    pub fn owns(&self, i: usize) -> bool {
        self.owner.as_ref().is_none_or(|o| o[i] as usize == self.world.rank)
    }

    /// `values[k] <- sum over the ranks of values[k]`; nothing to do when whole.
    /// `what` names the values in the message of a failed collective, which MPI's
    /// default error handler turns into an abort of the whole job before it returns,
    /// so partial sums never pass as a result.
    pub fn sum(&self, values: &mut [f64], what: &str) {
        if self.is_split() {
            petsc::sum_over_ranks(values).unwrap_or_else(|e| panic!("MPI_Allreduce of {what}: {e}"));
        }
    }

    /// Solve the system whose rows this rank owns (`entries`, in the nodes' numbering,
    /// `per_node` unknowns per node, `positions` of the nodes for the multigrid's
    /// rigid-body modes) with PETSc over the ranks ([`distributed::solve`]). The share
    /// must be split.
    pub fn solve(
        &self,
        per_node: usize,
        entries: impl Iterator<Item = Entry> + Clone,
        rhs: &[f64],
        positions: &[Point],
        solver: &SolverParams,
    ) -> Result<(Vec<f64>, SolveReport), SolveError> {
        let owner = self.owner.clone().ok_or_else(|| SolveError::Petsc { detail: "a distributed solve of a whole node set".into() })?;
        distributed::solve(&Distribution::new(owner, per_node, self.world), entries, rhs, positions, solver)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_whole_share_owns_every_node_and_sums_nothing() {
        let s = Share::whole();
        assert!(!s.is_split() && (0..5).all(|i| s.owns(i)));
        let mut v = [1.0, 2.0];
        s.sum(&mut v, "test values");
        assert_eq!(v, [1.0, 2.0]);
    }

    #[test]
    fn followers_belong_to_the_rank_of_their_leader() {
        let points: Vec<Point> = (0..8).map(|i| [i as f64, 0.0]).collect();
        for rank in 0..2 {
            let s = Share::as_rank(&points, World { rank, size: 2 }).with_followers(&[0, 7]);
            let own: Vec<bool> = (0..10).map(|i| s.owns(i)).collect();
            assert_eq!(own[..8].iter().filter(|&&o| o).count(), 4, "rank {rank} owns half of the nodes");
            assert_eq!(own[8], own[0], "the ghost of node 0 follows it");
            assert_eq!(own[9], own[7], "the ghost of node 7 follows it");
        }
    }
}
