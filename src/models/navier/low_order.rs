//! The low-order operator the multigrid preconditioner is built on when the scene's
//! stencils are large (`solver.multigrid`).
//!
//! Block Gauss–Seidel smoothing and aggregation both lean on small stencils. On the
//! 56-node stencils of PHS + degree 6 the smoother diverges at the ghost nodes near
//! the corners, and with every coupling strong the aggregates hold about 50 nodes:
//! GMRES with the multigrid on the system stalls. Built instead on a PHS `r^3` +
//! degree-2 discretisation of the same equations on the same nodes and ghosts
//! (12-node stencils; the same unknowns and row layout, other coefficients), the
//! multigrid approximates the inverse of the high-order system well enough for GMRES,
//! which still solves the scene's system: the solution is the high-order one. Degree 6
//! then converges in iterations nearly flat in the node count, and degree 4 (30-node
//! stencils) gains too, for some more memory. On stencils of 9-13 nodes the system's
//! own multigrid is better, and at 20 nodes (degree 3) both cost the same
//! (docs/notebook/2026-11-26-low-order-multigrid-operator.md).
//! This is the "smaller stencil" preconditioning of the RBF-FD literature.

use super::discrete::Discretisation;
use super::system::System;
use crate::physics::case::Case;
use crate::scene::choice::choice;
use crate::domain::FillKind;
use crate::physics::exact::ExactSolution;
use crate::linalg::Csr;
use crate::mlsm::stencil::default_rbf_fd_support;
use crate::mlsm::{Approximation, Basis, Radial, Weight};

choice! {
    /// Which operator the multigrid preconditioner is built on (`solver.multigrid`).
    pub enum MultigridOperator("solver.multigrid", default Some(MultigridOperator::Auto)) {
        Auto = "auto" => "the system's own matrix on stencils of at most 20 nodes, the low-order operator on larger ones (PHS degree >= 4)",
        System = "system" => "the system's own matrix",
        LowOrder = "low-order" => "a PHS r^3 + degree-2 RBF-FD discretisation of the same equations on the same nodes and ghosts (12-node stencils); GMRES still solves the scene's system",
    }
}

/// The largest stencil on which `auto` builds the multigrid on the system itself
/// (module docs: 9-13 nodes favour the system, 20 is a tie, 30 and 56 favour the
/// low-order operator).
pub const AUTO_SYSTEM_SUPPORT: usize = 20;

impl MultigridOperator {
    /// Whether the multigrid of a run whose supports take `support` nodes is built on
    /// the low-order operator.
    pub fn low_order(self, support: usize) -> bool {
        match self {
            MultigridOperator::Auto => support > AUTO_SYSTEM_SUPPORT,
            MultigridOperator::System => false,
            MultigridOperator::LowOrder => true,
        }
    }
}

/// The low-order approximation on a `fill`: PHS `r^3` + monomials of degree 2 on its
/// default stencil (12 nodes scattered, 13 on grids), ghost nodes as the scene's.
pub fn approximation(scene: &Approximation, fill: FillKind) -> Approximation {
    let basis = Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree: 2 };
    Approximation { basis, weight: Weight::None, support: default_rbf_fd_support(basis.size(), fill), ghost_nodes: scene.ghost_nodes }
}

/// The rows of the low-order operator on the nodes and ghosts of `disc`, unscaled as
/// assembled; the reason when its shapes or rows cannot be made (the multigrid then
/// takes the system and the solver's report says why).
pub fn rows(case: &Case, disc: &mut Discretisation, exact: Option<&dyn ExactSolution>, low_order: &Approximation) -> Result<Csr, String> {
    disc.with_approximation(low_order, |d| System { case, disc: d, exact }.assemble().map(|(m, _)| m))
        .and_then(|assembled| assembled)
        .map_err(|e| e.to_string())
}
