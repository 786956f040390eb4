//! A multigrid level's operator as the V-cycle applies it ([`super::amg`]): its
//! values in single precision, on the finest level of a displacement system in 2 x 2
//! node blocks.
//!
//! Single precision: the cycle need only be a fixed linear map, and the smoother and
//! residual passes are memory-bound (an entry in 8 bytes instead of 12); a low-order
//! operator that only preconditions is held once, in single precision
//! (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "Single-precision cycle").
//!
//! Node blocks ([`BlockRows::square`]): the two rows of a node reach the same support
//! nodes, so one column index serves four entries (5 bytes an entry instead of 8) and
//! the sweep reads `x` in pairs (docs/notebook/2026-11-27-node-blocks-in-the-cycle.md).

use super::aggregation::Blocks;
use super::blocks::BlockRows;
use super::csr::{product, Csr, RowsRef};
use super::smoother::{gauss_seidel, Sweep};
use rayon::prelude::*;

/// What a hierarchy keeps of its finest operator once it is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Finest {
    /// The system the Krylov method solves: its rows stay in double precision for the
    /// method's products ([`super::amg::Amg::fine_operator`]).
    System,
    /// An operator that only preconditions (a low-order operator, a saddle point's
    /// displacement block, rows the Krylov method holds elsewhere): single precision.
    PreconditionerOnly,
}

/// How a level's operator is held.
#[derive(Debug)]
pub(super) enum LevelOperator {
    /// Rounded to single precision, in compressed rows.
    Single(Csr<f32>),
    /// The system's rows ([`Finest::System`]) and their values rounded to single
    /// precision, which share the rows' structure.
    System { rows: Csr, single: Vec<f32> },
    /// In square node blocks in single precision (an operator that only
    /// preconditions).
    Blocks(BlockRows),
}

impl LevelOperator {
    /// The operator `a` of a level with nodes of `blocks`, kept as `keep` says. An
    /// operator that only preconditions is held in node blocks when a node has two
    /// unknowns and the blocks hold few stored zeros ([`super::blocks::MAX_FILL`]);
    /// the system's own rows are not: next to their double-precision copy the blocks
    /// took more memory than the single-precision values, for no gain in time
    /// (docs/notebook/2026-11-27-node-blocks-in-the-cycle.md).
    pub(super) fn new(a: Csr, keep: Finest, blocks: Blocks) -> Self {
        if blocks.block == 2 && keep == Finest::PreconditionerOnly {
            if let Some(b) = BlockRows::square(&a, 2) {
                return LevelOperator::Blocks(b);
            }
        }
        match keep {
            Finest::System => {
                let single = a.values().par_iter().with_min_len(4096).map(|&v| v as f32).collect();
                LevelOperator::System { rows: a, single }
            }
            Finest::PreconditionerOnly => LevelOperator::Single(a.into_single()),
        }
    }

    /// `y = A x` as the cycle applies it.
    pub(super) fn product(&self, x: &[f64], y: &mut [f64]) {
        match self {
            LevelOperator::Single(a) => product(a, x, y),
            LevelOperator::System { rows, single } => product(rows.with_values(single), x, y),
            LevelOperator::Blocks(b) => b.product(x, y),
        }
    }

    /// One block Gauss–Seidel sweep ([`gauss_seidel`]) over the nodes of `level`
    /// (their blocks and the pseudo-inverses of the diagonal blocks).
    pub(super) fn gauss_seidel(&self, level: (Blocks, &[f64]), f: &[f64], z: &mut [f64], direction: Sweep, copies: &mut Vec<Vec<f64>>) {
        let (blocks, inv) = level;
        match self {
            LevelOperator::Single(a) => gauss_seidel(RowsRef::from(a), blocks, inv, f, z, direction, copies),
            LevelOperator::System { rows, single } => gauss_seidel(rows.with_values(single), blocks, inv, f, z, direction, copies),
            LevelOperator::Blocks(b) => gauss_seidel(b, blocks, inv, f, z, direction, copies),
        }
    }

    /// Stored entries (a block's zeros included).
    pub(super) fn nnz(&self) -> usize {
        match self {
            LevelOperator::Single(a) => a.nnz(),
            LevelOperator::System { rows, .. } => rows.nnz(),
            LevelOperator::Blocks(b) => b.nnz(),
        }
    }

    /// The system's rows in double precision, when kept.
    pub(super) fn system_rows(&self) -> Option<&Csr> {
        match self {
            LevelOperator::System { rows, .. } => Some(rows),
            _ => None,
        }
    }

    /// [`LevelOperator::system_rows`], the rest dropped.
    pub(super) fn into_system_rows(self) -> Option<Csr> {
        match self {
            LevelOperator::System { rows, .. } => Some(rows),
            _ => None,
        }
    }
}
