//! Tests of the smoothed-aggregation multigrid ([`super`]).

use super::*;
use crate::linalg::csr::{columns_of, to_csr};
use crate::linalg::{assemble, gmres, scaling, Triplets};

/// Rows and back to columns gives the matrix bit for bit (pattern and values), and
/// scaled rows are each multiplied by their own scale.
#[test]
fn rows_and_columns_convert_exactly() {
    let (a, _) = vector_laplacian(9);
    let back = columns_of(to_csr(&a));
    assert_eq!(back.symbolic().col_ptr(), a.symbolic().col_ptr());
    assert_eq!(back.symbolic().row_idx(), a.symbolic().row_idx());
    assert_eq!(back.val(), a.val());
    let scales: Vec<f64> = (0..a.nrows()).map(|i| 1.0 + i as f64).collect();
    let mut rows = to_csr(&a);
    rows.scale_rows(&scales);
    let scaled = columns_of(rows);
    for j in 0..a.ncols() {
        for ((&i, &v), &w) in a.symbolic().row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)).zip(scaled.val_of_col(j)) {
            assert_eq!(w, v * scales[i]);
        }
    }
}

fn vector_laplacian(m: usize) -> (SparseMatrix, Vec<[f64; 2]>) {
    shifted_vector_laplacian(m, 0.0)
}

/// The vector Laplacian of `m²` grid nodes on the unit square with `shift` added to the
/// diagonal of its interior rows (its boundary rows are `u = 0`).
fn shifted_vector_laplacian(m: usize, shift: f64) -> (SparseMatrix, Vec<[f64; 2]>) {
    let h = 1.0 / (m - 1) as f64;
    let mut t = Triplets::new(2 * m * m);
    let mut positions = Vec::new();
    for j in 0..m {
        for i in 0..m {
            let node = i + m * j;
            positions.push([i as f64 * h, j as f64 * h]);
            for c in 0..2 {
                let row = 2 * node + c;
                if i == 0 || j == 0 || i == m - 1 || j == m - 1 {
                    t.push(row, row, 1.0);
                    continue;
                }
                t.push(row, row, -4.0 / (h * h) + shift);
                for other in [node - 1, node + 1, node - m, node + m] {
                    t.push(row, 2 * other + c, 1.0 / (h * h));
                }
            }
        }
    }
    (assemble(&t).unwrap(), positions)
}

/// One V-cycle as the preconditioner of GMRES: on the vector Laplacian the count
/// stays bounded as the grid is refined 4x (measured 8, 9, 10 at 33², 65², 129²
/// nodes); without a coarse space ILU- or Jacobi-type methods grow like 1/h.
#[test]
fn multigrid_iterations_do_not_grow_with_the_grid() {
    let mut counts = Vec::new();
    for m in [33, 65, 129] {
        let (a, positions) = vector_laplacian(m);
        let (a, d) = scaling::equilibrate_rows(&to_csr(&a)).unwrap();
        let b: Vec<f64> = (0..a.nrows()).map(|i| if (i / 2) % m == 0 { 0.0 } else { 1.0 }).collect();
        let b = scaling::scale_rhs(&b, &d);
        let amg = Amg::build_from_rows(
            a,
            Some(NodeLayout { per_node: 2, positions: &positions, multipliers: 0 }),
            AmgParams::default(),
            Finest::System,
        );
        assert!(amg.sizes().len() >= 2, "{:?}", amg.sizes());
        // Five-node aggregates of a 5-point stencil carry 3 coarse unknowns for 10
        // fine ones, and the coarse stencils widen: measured 3.3.
        assert!(amg.operator_complexity() < 4.0, "{}", amg.operator_complexity());
        let out = gmres::solve_gmres(amg.fine_operator().expect("kept"), &b, |v, z| amg.solve_into(v, z), 1e-10, 200, 30);
        assert_eq!(out.status, gmres::Status::Converged, "{m}: {:?}", out.history);
        counts.push(out.iterations);
    }
    eprintln!("GMRES+AMG iterations on 33², 65², 129² nodes: {counts:?}");
    assert!(counts.iter().all(|&c| c <= 20), "{counts:?}");
}

/// A hierarchy that only preconditions keeps no double-precision copy of its
/// finest operator, and its cycle is the same linear map as one that keeps the
/// system: both apply the finest rows rounded to single precision, so the
/// preconditioned vectors agree bit for bit and GMRES takes the same iterations.
#[test]
fn a_preconditioner_only_hierarchy_applies_the_same_cycle() {
    let (a, positions) = vector_laplacian(65);
    let (a, d) = scaling::equilibrate_rows(&to_csr(&a)).unwrap();
    let b = scaling::scale_rhs(&(0..a.nrows()).map(|i| 1.0 + (i % 7) as f64).collect::<Vec<_>>(), &d);
    let layout = Some(NodeLayout { per_node: 2, positions: &positions, multipliers: 0 });
    let kept = Amg::build_from_rows(a.clone(), layout, AmgParams::default(), Finest::System);
    let only = Amg::build_from_rows(a.clone(), layout, AmgParams::default(), Finest::PreconditionerOnly);
    assert!(kept.fine_operator().is_some() && only.fine_operator().is_none());
    let (mut z1, mut z2) = (vec![0.0; b.len()], vec![1.0; b.len()]);
    kept.solve_into(&b, &mut z1);
    only.solve_into(&b, &mut z2);
    assert_eq!(z1, z2);
    let run = |amg: &Amg| gmres::solve_gmres(&a, &b, |v, z| amg.solve_into(v, z), 1e-10, 200, 30);
    let (o1, o2) = (run(&kept), run(&only));
    assert_eq!(o1.status, gmres::Status::Converged);
    assert_eq!(o1.iterations, o2.iterations);
}

/// [`Amg::cycle_growth`] tells a converging cycle from a diverging one. On the vector
/// Laplacian (65² nodes) one V-cycle shrinks an error (measured 0.146). Shifted by
/// `+1/(2h²)` on the interior rows the operator is indefinite (the shift exceeds its
/// smallest eigenvalues' magnitude, `2π²`, by far), its smooth modes are no longer
/// damped by the smoother nor fixed by the coarse levels, and the cycle amplifies an
/// error instead (measured 3.3e22 in the third cycle).
#[test]
fn cycle_growth_tells_a_converging_cycle_from_a_diverging_one() {
    let h = 1.0 / 64.0;
    let growth = |shift: f64| {
        let (a, positions) = shifted_vector_laplacian(65, shift);
        let layout = Some(NodeLayout { per_node: 2, positions: &positions, multipliers: 0 });
        let (rows, _) = scaling::equilibrate_rows(&to_csr(&a)).unwrap();
        Amg::build_from_rows(rows, layout, AmgParams::default(), Finest::System).cycle_growth().expect("several levels")
    };
    let (converging, diverging) = (growth(0.0), growth(0.5 / (h * h)));
    eprintln!("cycle growth: Laplacian {converging:.3}, shifted {diverging:.3}");
    assert!(converging < 0.5, "{converging}");
    assert!(diverging > 2.0, "{diverging}");
}
