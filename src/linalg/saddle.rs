//! The preconditioner of the displacement-pressure form: its rows are a saddle point
//!
//! ```text
//! [ A  B ] [u]   [f]      A: the displacement rows' displacement columns (Navier, traction)
//! [ C  D ] [p] = [g]      B: their pressure columns (-grad p); C, D: the continuity rows
//! ```
//!
//! with `D -> 0` as nu -> 1/2, on which the multigrid of the whole matrix fails (its
//! 3x3 node blocks have a vanishing pressure pivot: stagnation at nu = 0.3, a NaN at
//! 0.4999). Preconditioned instead by the block upper triangle (Elman, Silvester &
//! Wathen, *Finite Elements and Fast Iterative Solvers*, ch. 9)
//!
//! ```text
//! P = [ A  B ]      P⁻¹ [r_u; r_p]:  z_p = S̃⁻¹ r_p,  z_u = Ã⁻¹ (r_u − B z_p)
//!     [ 0  S̃ ]
//! ```
//!
//! with `Ã⁻¹` one V-cycle of the multigrid on `A` (two unknowns per node, the
//! rigid-body modes) and `S̃ = diag(D) − diag(C diag(A)⁻¹ B)`, the diagonal of the
//! SIMPLE approximation of the Schur complement `D − C A⁻¹ B`. Chosen on exported
//! systems (`benches/pyamg_saddle_point.py`): on the Lame ring its iterations are
//! nearly flat in the node count, and the exact Schur complement's own diagonal was no
//! better (against its diagonal the complement has two eigenvalues with a negative
//! real part: the equal-order pressure's weak modes;
//! docs/notebook/2026-11-26-up-form-iterative-solvers.md).

use super::amg::{Amg, AmgParams, Finest};
use super::layout::NodeLayout;
use super::csr::Csr;
use std::sync::Mutex;

/// Unknowns per node of the displacement-pressure form (`u, v, p`, interleaved).
const PER_NODE: usize = 3;

/// The block-triangular preconditioner of a displacement-pressure system.
#[derive(Debug)]
pub struct SaddlePoint {
    /// The multigrid of the displacement block `A` (unknowns `2 node + c`).
    displacement: Amg,
    /// `B`: the displacement rows' pressure columns (rows `2 node + c`, columns `node`).
    gradient: Csr,
    /// `1 / S̃_i` for each node's pressure.
    inverse_schur: Vec<f64>,
    /// The displacement and the pressure parts of a vector, reused between applications.
    work: Mutex<(Vec<f64>, Vec<f64>)>,
}

/// The entries of `a` whose row and column components (index mod 3) are those of
/// `rows_of` and `cols_of`, renumbered within them: a displacement unknown
/// `3 node + c` becomes `2 node + c`, a pressure `3 node + 2` becomes `node`.
fn block(a: &Csr, rows_of: Component, cols_of: Component) -> Csr {
    let nodes = a.nrows() / PER_NODE;
    let (ptr, idx, val) = (a.row_offsets(), a.col_indices(), a.values());
    let (mut offsets, mut cols, mut vals) = (vec![0usize], Vec::new(), Vec::new());
    for row in (0..a.nrows()).filter(|r| rows_of.holds(r % PER_NODE)) {
        for k in ptr[row]..ptr[row + 1] {
            let c = idx[k] as usize;
            if cols_of.holds(c % PER_NODE) {
                cols.push(cols_of.renumber(c) as u32);
                vals.push(val[k]);
            }
        }
        offsets.push(cols.len());
    }
    Csr::from_parts(offsets.len() - 1, cols_of.count(nodes), offsets, cols, vals)
}

/// Which unknowns of a node a block takes.
#[derive(Clone, Copy)]
enum Component {
    Displacement,
    Pressure,
}

impl Component {
    fn holds(self, c: usize) -> bool {
        match self {
            Component::Displacement => c < 2,
            Component::Pressure => c == 2,
        }
    }
    fn renumber(self, unknown: usize) -> usize {
        match self {
            Component::Displacement => unknown / PER_NODE * 2 + unknown % PER_NODE,
            Component::Pressure => unknown / PER_NODE,
        }
    }
    fn count(self, nodes: usize) -> usize {
        match self {
            Component::Displacement => 2 * nodes,
            Component::Pressure => nodes,
        }
    }
}

impl SaddlePoint {
    /// The preconditioner of `a` (the solved, row-equilibrated system, three unknowns
    /// per node of `layout`), its multigrid built on the displacement block of
    /// `multigrid_source` (the system itself or a low-order operator on the same
    /// unknowns). `None` when `layout` does not have three unknowns per node.
    pub fn build(a: &Csr, multigrid_source: Option<&Csr>, layout: NodeLayout) -> Option<Self> {
        let nodes = layout.positions.len();
        if !layout.has_pressure() || a.nrows() != PER_NODE * nodes {
            return None;
        }
        let displacement = block(multigrid_source.unwrap_or(a), Component::Displacement, Component::Displacement);
        let gradient = block(a, Component::Displacement, Component::Pressure);
        let continuity = block(a, Component::Pressure, Component::Displacement);
        let inverse_schur = simple_inverse_schur(a, &gradient, &continuity);
        drop(continuity);
        let layout = NodeLayout { per_node: 2, positions: layout.positions, multipliers: 0 };
        let displacement = Amg::build_from_rows(displacement, Some(layout), AmgParams::default(), Finest::PreconditionerOnly);
        Some(SaddlePoint { displacement, gradient, inverse_schur, work: Mutex::new((Vec::new(), Vec::new())) })
    }

    /// `z = P⁻¹ z` (module docs).
    pub fn solve_in_place(&self, z: &mut [f64]) {
        let nodes = self.inverse_schur.len();
        let mut guard = self.work.lock().unwrap_or_else(|e| e.into_inner());
        let (work, pressure) = &mut *guard;
        work.resize(2 * nodes, 0.0);
        pressure.clear();
        for (node, s) in self.inverse_schur.iter().enumerate() {
            z[PER_NODE * node + 2] *= s;
            pressure.push(z[PER_NODE * node + 2]);
        }
        let (ptr, idx, val) = (self.gradient.row_offsets(), self.gradient.col_indices(), self.gradient.values());
        for (row, w) in work.iter_mut().enumerate() {
            let entries = ptr[row]..ptr[row + 1];
            *w = z[row / 2 * PER_NODE + row % 2] - super::csr::row_dot(&idx[entries.clone()], &val[entries], pressure);
        }
        self.displacement.solve_in_place(work);
        for (row, w) in work.iter().enumerate() {
            z[row / 2 * PER_NODE + row % 2] = *w;
        }
    }

    /// Stored entries of the multigrid and of `B`.
    pub fn nonzeros(&self) -> usize {
        self.displacement.nonzeros() + self.gradient.nnz()
    }

    /// Unknowns.
    pub fn dim(&self) -> usize {
        PER_NODE * self.inverse_schur.len()
    }

    /// The multigrid's levels, for the report.
    pub fn multigrid(&self) -> &Amg {
        &self.displacement
    }
}

/// `1 / S̃_i` with `S̃_i = D_ii − Σ_j C_ij B_ji / A_jj` (module docs); a node whose
/// `S̃_i` vanishes or is not finite gets 1 (the rows are equilibrated to entries of
/// at most 1, so its pressure is left about unscaled).
fn simple_inverse_schur(a: &Csr, gradient: &Csr, continuity: &Csr) -> Vec<f64> {
    let nodes = continuity.nrows();
    (0..nodes)
        .map(|node| {
            let row = continuity.row(node);
            let coupling: f64 = row
                .col_indices()
                .iter()
                .zip(row.values())
                .map(|(&j, &c)| {
                    let j = j as usize;
                    let b = gradient.row(j);
                    let b_ji = b.col_indices().binary_search(&(node as u32)).map_or(0.0, |k| b.values()[k]);
                    let a_jj = a.diagonal(j / 2 * PER_NODE + j % 2);
                    if a_jj == 0.0 {
                        0.0
                    } else {
                        c * b_ji / a_jj
                    }
                })
                .sum();
            let s = a.diagonal(PER_NODE * node + 2) - coupling;
            if s != 0.0 && s.is_finite() {
                1.0 / s
            } else {
                1.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A 3-unknowns-per-node system on a ring of `nodes` nodes: a diagonally dominant
    /// displacement block, a gradient-like `B`, a divergence-like `C` and a small `D`.
    fn ring(nodes: usize) -> Csr {
        let mut e = Vec::new();
        for i in 0..nodes {
            let (prev, next) = ((i + nodes - 1) % nodes, (i + 1) % nodes);
            for c in 0..2 {
                let row = 3 * i + c;
                e.extend([(row, row, 4.0 + c as f64), (row, 3 * prev + c, -1.5), (row, 3 * next + c, -1.0 - 0.2 * c as f64)]);
                e.extend([(row, 3 * next + 2, 0.5), (row, 3 * prev + 2, -0.5 + 0.1 * c as f64)]);
            }
            let row = 3 * i + 2;
            e.extend([(row, 3 * next, 0.5), (row, 3 * prev + 1, -0.5), (row, row, 1e-3 * (1 + i % 3) as f64)]);
        }
        Csr::from_triplets(3 * nodes, 3 * nodes, &e)
    }

    /// On a system small enough for the multigrid to be one exact LU, one application is
    /// the block-triangular solve itself: `z_p = r_p / S̃`, `z_u = A⁻¹ (r_u − B z_p)`,
    /// with `S̃ = D − diag(C diag(A)⁻¹ B)` computed densely here (to round-off, 1e-12).
    #[test]
    fn one_application_is_the_block_triangular_solve() {
        let nodes = 40;
        let a = ring(nodes);
        let positions: Vec<[f64; 2]> = (0..nodes).map(|i| [(i as f64).cos(), (i as f64).sin()]).collect();
        let pc = SaddlePoint::build(&a, None, NodeLayout { per_node: 3, positions: &positions, multipliers: 0 })
            .expect("three unknowns per node");
        let dense = DMatrix::from_fn(3 * nodes, 3 * nodes, |r, c| {
            let row = a.row(r);
            row.col_indices().binary_search(&(c as u32)).map_or(0.0, |k| row.values()[k])
        });
        let (u, p): (Vec<usize>, Vec<usize>) = (0..3 * nodes).partition(|k| k % 3 < 2);
        let sub = |rows: &[usize], cols: &[usize]| DMatrix::from_fn(rows.len(), cols.len(), |i, j| dense[(rows[i], cols[j])]);
        let (a_uu, b, c, d) = (sub(&u, &u), sub(&u, &p), sub(&p, &u), sub(&p, &p));
        let inv_diag_a = DMatrix::from_diagonal(&a_uu.diagonal().map(|x| 1.0 / x));
        let schur = d.diagonal() - (&c * inv_diag_a * &b).diagonal();
        let r: Vec<f64> = (0..3 * nodes).map(|k| ((k * 37 % 11) as f64 - 5.0) / 5.0).collect();
        let mut z = r.clone();
        pc.solve_in_place(&mut z);
        let z_p = DVector::from_fn(nodes, |i, _| r[p[i]] / schur[i]);
        let r_u = DVector::from_fn(2 * nodes, |i, _| r[u[i]]);
        let z_u = a_uu.lu().solve(&(r_u - &b * &z_p)).unwrap();
        let worst =
            (0..nodes).map(|i| (z[p[i]] - z_p[i]).abs()).chain((0..2 * nodes).map(|i| (z[u[i]] - z_u[i]).abs())).fold(0.0, f64::max);
        let size = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(worst <= 1e-12 * size, "worst difference {worst:e} of {size:e}");
        assert_eq!(pc.dim(), 3 * nodes);
    }
}
