//! What a Krylov method asks of a preconditioner `M ≈ A`: its action `z = M⁻¹ v`,
//! its size and what it stores. Every preconditioner of [`super::precond`] answers
//! it, so that the bordered preconditioner ([`super::border`]) wraps any of them.

use super::amg::Amg;

/// A preconditioner as the Krylov methods use it: `z = M⁻¹ v` with `M ≈ A`.
pub trait Inverse: std::fmt::Debug + Send + Sync {
    /// Unknowns of `v` and `z`.
    fn dim(&self) -> usize;

    /// Stored entries (for reports).
    fn nonzeros(&self) -> usize;

    /// `z = M⁻¹ v` for one vector.
    fn solve_into(&self, v: &[f64], z: &mut [f64]);

    /// The multigrid inside, if any (its cycle growth names the cause of a failure).
    fn multigrid(&self) -> Option<&Amg> {
        None
    }

    /// What a solve report adds to the method's name (empty for none).
    fn describe(&self) -> String {
        String::new()
    }
}
