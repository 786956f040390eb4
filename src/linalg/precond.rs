//! Preconditioners `M ≈ A` for the Krylov solvers: Jacobi, ILU(0) (adapter over
//! `faer-precond`), the native dual-threshold ILUT of [`super::ilut`] and the
//! smoothed-aggregation multigrid of [`super::amg`].
//!
//! All are exposed to `faer::matrix_free` through [`BuiltPreconditioner`],
//! whose `LinOp::apply` / `Precond::apply_in_place` compute `M⁻¹ v`.

use super::amg::{Amg, AmgParams};
use super::layout::NodeLayout;
pub use super::ilut::{Ilut, ILUT_PIVOT_RTOL};
use super::inverse::Inverse;
use super::{Preconditioner, SolveError, SparseMatrix};
use faer::dyn_stack::{MemStack, StackReq};
use faer::matrix_free::{LinOp, Precond};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, MatRef, Par};
use faer_precond::{Ilu0, Ilu0Error};

/// Jacobi (diagonal) preconditioner `M = diag(a_11, …, a_nn)`, applied as
/// `M⁻¹ v = (v_i / a_ii)_i` (Saad, *Iterative Methods*, 2nd ed., §4.1 / §10.2).
/// Stores the inverse diagonal because `faer`'s `Diag` preconditioner
/// *multiplies* by the stored diagonal.
#[derive(Clone, Debug)]
pub struct Jacobi {
    inv_diag: Vec<f64>,
}

impl Jacobi {
    /// Errors: [`SolveError::Singular`] if some `a_ii` is zero or not stored.
    pub fn try_new(a: &SparseMatrix) -> Result<Self, SolveError> {
        let n = a.nrows();
        let mut diag = vec![0.0f64; n];
        for (j, d) in diag.iter_mut().enumerate() {
            let rows = a.symbolic().row_idx_of_col_raw(j);
            if let Ok(p) = rows.binary_search(&j) {
                *d = a.val_of_col(j)[p];
            }
        }
        if let Some(i) = diag.iter().position(|&d| d == 0.0) {
            return Err(SolveError::Singular {
                detail: format!(
                    "Jacobi preconditioning needs a nonzero diagonal but a_({i},{i}) = 0; \
                     use ilut or lu"
                ),
            });
        }
        Ok(Jacobi { inv_diag: diag.iter().map(|d| 1.0 / d).collect() })
    }

    /// `x ← M⁻¹ x`.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        for (xi, di) in x.iter_mut().zip(&self.inv_diag) {
            *xi *= di;
        }
    }
}

/// A constructed preconditioner, usable as the right preconditioner of
/// `faer::matrix_free::bicgstab`.
#[derive(Debug)]
pub enum BuiltPreconditioner {
    /// See [`Jacobi`].
    Jacobi(Jacobi),
    /// `faer_precond::Ilu0`: `L U = A` on the pattern of `A`
    /// (Saad, Alg. 10.4); requires every diagonal entry to be stored.
    Ilu0(Box<Ilu0<usize, f64>>),
    /// See [`Ilut`].
    Ilut(Ilut),
    /// See [`Amg`].
    Amg(Box<Amg>),
    /// The block-triangular preconditioner of the displacement-pressure form.
    SaddlePoint(Box<super::saddle::SaddlePoint>),
    /// The block-triangular preconditioner of a bordered system (constraints with
    /// multipliers), around one of the others built on its leading block.
    Bordered(Box<super::border::Bordered>),
}

/// `a` with an explicit zero stored at every missing diagonal entry, or `None` when
/// every diagonal entry is already stored.
fn with_stored_diagonal(a: &SparseMatrix) -> Result<Option<SparseMatrix>, SolveError> {
    let n = a.ncols();
    let missing: Vec<usize> = (0..n).filter(|&j| a.symbolic().row_idx_of_col_raw(j).binary_search(&j).is_err()).collect();
    if missing.is_empty() {
        return Ok(None);
    }
    let mut t = super::Triplets::new(n);
    for j in 0..n {
        for (&i, &v) in a.symbolic().row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            t.push(i, j, v);
        }
    }
    for j in missing {
        t.push(j, j, 0.0);
    }
    super::assemble(&t).map(Some)
}

impl BuiltPreconditioner {
    /// Build the preconditioner `kind` for `a`; `layout` gives AMG its near-null space,
    /// and with `layout.multipliers > 0` the preconditioner of the bordered system
    /// around `kind` built on its leading block ([`super::border`]).
    /// Errors: [`SolveError::Singular`] for zero pivots / missing diagonals.
    pub fn build(a: &SparseMatrix, kind: Preconditioner, layout: Option<NodeLayout>) -> Result<Self, SolveError> {
        if let Some(l) = layout.filter(|l| l.multipliers > 0) {
            let rows = super::csr::to_csr(a);
            let lead = super::csr::columns_of(super::border::leading_block(&rows, l.multipliers));
            let inner = Self::build(&lead, kind, Some(l.nodes_only()))?;
            drop(lead);
            return Ok(BuiltPreconditioner::Bordered(Box::new(super::border::Bordered::build(&rows, l.multipliers, Box::new(inner))?)));
        }
        Ok(match kind {
            Preconditioner::Jacobi => BuiltPreconditioner::Jacobi(Jacobi::try_new(a)?),
            Preconditioner::Ilu0 => {
                // Ghost-node rows carry no diagonal entry (their unknown is coupled only
                // through the stencils of other nodes); ILU(0) on the pattern of A + 0 I
                // updates those pivots during elimination like any other (on Kirsch
                // BiCGSTAB then converges where the bare pattern is refused:
                // docs/notebook/round2-direct-against-iterative.md).
                let padded = with_stored_diagonal(a)?;
                let a = padded.as_ref().unwrap_or(a);
                let p = Ilu0::try_new(a.as_ref()).map_err(|e| match e {
                    Ilu0Error::MissingDiagonal { col } => SolveError::Singular {
                        detail: format!(
                            "ILU(0) needs every diagonal entry stored, but a_({col},{col}) is \
                             structurally zero; use ilut or lu"
                        ),
                    },
                    Ilu0Error::ZeroPivot { col } => {
                        SolveError::Singular { detail: format!("ILU(0) hit a zero pivot at row/column {col}; use ilut or lu") }
                    }
                    other => SolveError::Dimension { detail: format!("ILU(0) could not be built: {other}") },
                })?;
                BuiltPreconditioner::Ilu0(Box::new(p))
            }
            Preconditioner::Ilut { drop, fill } => BuiltPreconditioner::Ilut(Ilut::try_new(a, drop, fill)?),
            Preconditioner::Amg => BuiltPreconditioner::Amg(Box::new(Amg::build(a, layout, AmgParams::default())?)),
        })
    }

    /// The operator in compressed rows, when the preconditioner keeps one (AMG's
    /// finest level).
    pub fn fine_operator(&self) -> Option<&super::csr::Csr> {
        match self {
            BuiltPreconditioner::Amg(p) => p.fine_operator(),
            _ => None,
        }
    }

    /// `x ← M⁻¹ x` for one vector.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        match self {
            BuiltPreconditioner::Jacobi(j) => j.solve_in_place(x),
            BuiltPreconditioner::Ilut(p) => p.solve_in_place(x),
            BuiltPreconditioner::Amg(p) => p.solve_in_place(x),
            BuiltPreconditioner::SaddlePoint(p) => p.solve_in_place(x),
            BuiltPreconditioner::Bordered(p) => {
                let v = x.to_vec();
                p.solve_into(&v, x);
            }
            BuiltPreconditioner::Ilu0(p) => {
                let n = x.len();
                let m = faer::MatMut::from_column_major_slice_mut(x, n, 1);
                Precond::apply_in_place(&**p, m, Par::Seq, MemStack::new(&mut []));
            }
        }
    }
}

impl Inverse for BuiltPreconditioner {
    fn dim(&self) -> usize {
        match self {
            BuiltPreconditioner::Jacobi(j) => j.inv_diag.len(),
            BuiltPreconditioner::Ilu0(p) => p.dim(),
            BuiltPreconditioner::Ilut(p) => p.dim(),
            BuiltPreconditioner::Amg(p) => p.dim(),
            BuiltPreconditioner::SaddlePoint(p) => p.dim(),
            BuiltPreconditioner::Bordered(p) => p.dim(),
        }
    }

    fn nonzeros(&self) -> usize {
        match self {
            BuiltPreconditioner::Jacobi(j) => j.inv_diag.len(),
            // faer-precond's L includes its unit diagonal; count it once (as U's).
            BuiltPreconditioner::Ilu0(p) => p.symbolic().l_nnz() + p.symbolic().u_nnz() - p.dim(),
            BuiltPreconditioner::Ilut(p) => p.nonzeros(),
            BuiltPreconditioner::Amg(p) => p.nonzeros(),
            BuiltPreconditioner::SaddlePoint(p) => p.nonzeros(),
            BuiltPreconditioner::Bordered(p) => p.nonzeros(),
        }
    }

    fn solve_into(&self, v: &[f64], z: &mut [f64]) {
        match self {
            BuiltPreconditioner::Amg(p) => p.solve_into(v, z),
            BuiltPreconditioner::Bordered(p) => p.solve_into(v, z),
            _ => {
                z.copy_from_slice(v);
                self.solve_in_place(z);
            }
        }
    }

    fn multigrid(&self) -> Option<&Amg> {
        match self {
            BuiltPreconditioner::Amg(p) => Some(p),
            BuiltPreconditioner::SaddlePoint(_) => None,
            BuiltPreconditioner::Bordered(p) => p.inner().multigrid(),
            BuiltPreconditioner::Jacobi(_) | BuiltPreconditioner::Ilu0(_) | BuiltPreconditioner::Ilut(_) => None,
        }
    }

    /// AMG's levels and operator complexity.
    fn describe(&self) -> String {
        match self {
            BuiltPreconditioner::Amg(p) => levels(p),
            BuiltPreconditioner::SaddlePoint(p) => {
                format!(" on the displacement block{}, the Schur complement by its SIMPLE diagonal", levels(p.multigrid()))
            }
            BuiltPreconditioner::Bordered(p) => format!("{}, bordered by the constraints' Schur complement", p.inner().describe()),
            BuiltPreconditioner::Jacobi(_) | BuiltPreconditioner::Ilu0(_) | BuiltPreconditioner::Ilut(_) => String::new(),
        }
    }
}

impl LinOp<f64> for BuiltPreconditioner {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.dim()
    }
    fn ncols(&self) -> usize {
        self.dim()
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        out.copy_from(rhs);
        self.apply_in_place(out, par, stack);
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack);
    }
}

impl Precond<f64> for BuiltPreconditioner {
    fn apply_in_place_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn apply_in_place(&self, mut rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        if let BuiltPreconditioner::Ilu0(p) = self {
            return Precond::apply_in_place(&**p, rhs, par, stack);
        }
        // Called from faer's BiCGSTAB, between its vector kernels.
        super::vector_state::clear_upper_halves();
        let mut buf = Vec::new();
        for c in 0..rhs.ncols() {
            if let Some(col) = rhs.rb_mut().col_mut(c).try_as_col_major_mut() {
                self.solve_in_place(col.as_slice_mut());
                continue;
            }
            buf.clear();
            buf.extend((0..rhs.nrows()).map(|i| *rhs.rb().get(i, c)));
            self.solve_in_place(&mut buf);
            for (i, v) in buf.iter().enumerate() {
                *rhs.rb_mut().get_mut(i, c) = *v;
            }
        }
    }
    fn conj_apply_in_place(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply_in_place(rhs, par, stack);
    }
}

/// ` [levels 2013888/199833/..., operator complexity 1.27]` of a multigrid.
fn levels(p: &Amg) -> String {
    let sizes: Vec<String> = p.sizes().iter().map(|s| s.to_string()).collect();
    format!(" [multigrid levels of {} unknowns, all levels storing {:.2}x the finest's entries]", sizes.join("/"), p.operator_complexity())
}

#[cfg(test)]
mod tests {
    use super::super::{assemble, Triplets};
    use super::*;

    #[test]
    fn zero_pivots_are_singular_errors() {
        // [[0, 1], [1, 0]] is nonsingular but has no pivot without pivoting.
        let a = assemble(&Triplets::from_entries(2, &[(0, 1, 1.0), (1, 0, 1.0)])).unwrap();
        for kind in [Preconditioner::Jacobi, Preconditioner::Ilu0, Preconditioner::Ilut { drop: 0.0, fill: 2 }] {
            match BuiltPreconditioner::build(&a, kind, None) {
                Err(SolveError::Singular { .. }) => {}
                other => panic!("{kind:?}: expected Singular, got {other:?}"),
            }
        }
    }
}
