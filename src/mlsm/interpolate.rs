//! Moving least-squares interpolation of a nodal field at arbitrary points:
//! value shape functions (`mlsm::wls`) of a degree-`p` monomial basis over the
//! `2 binom(p + 2, 2)` nearest source nodes (12 for the default `p = 2`), unweighted
//! (the Gaussian weight of the solver is scaled by the distance to the nearest node,
//! which degenerates when a target sits on a node). Reproduces polynomials of degree
//! `p` exactly; error `O(h^(p+1))` for smooth fields.

use super::{fit::shape_functions, Basis, Op, ShapeError, Weight};
use crate::domain::Point;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Support size of the default (degree-2) interpolation: twice the 6 functions of
/// the basis.
pub const SUPPORT: usize = 12;

/// `values` (at `source`, `K` components each) interpolated at every target point:
/// `v(x) = sum_j phi_j(x) v_j` over the nearest [`SUPPORT`] source nodes (degree 2).
pub fn mls_values<const K: usize>(source: &[Point], values: &[[f64; K]], targets: &[Point]) -> Result<Vec<[f64; K]>, ShapeError> {
    mls_values_of_degree(source, values, targets, 2)
}

/// [`mls_values`] with a degree-`degree` basis over twice as many nearest source
/// nodes as it has functions (an interpolation as accurate as a degree-`degree`
/// solution it carries).
pub fn mls_values_of_degree<const K: usize>(
    source: &[Point],
    values: &[[f64; K]],
    targets: &[Point],
    degree: u32,
) -> Result<Vec<[f64; K]>, ShapeError> {
    let basis = Basis::Monomials { degree };
    let n = (2 * basis.size()).min(source.len());
    let tree = ImmutableKdTree::<f64, 2>::new_from_slice(source).expect("finite source nodes");
    targets
        .par_iter()
        .enumerate()
        .map(|(t, p)| {
            let found = tree.query(p).nearest_n::<SquaredEuclidean<f64>>(NonZeroUsize::new(n).expect("source nodes")).execute();
            let points: Vec<Point> = found.iter().map(|f| source[f.item as usize]).collect();
            let mut phi = vec![0.0; n];
            shape_functions(&basis, &Weight::None, *p, &points, &[Op::Value], &mut phi).map_err(|e| ShapeError {
                node: t,
                x: p[0],
                y: p[1],
                basis_size: e.basis_size,
                support: n,
                ratio: e.ratio,
            })?;
            let mut v = [0.0; K];
            for (w, f) in phi.iter().zip(&found) {
                for (v, u) in v.iter_mut().zip(&values[f.item as usize]) {
                    *v += w * u;
                }
            }
            Ok(v)
        })
        .collect()
}

/// Fields to interpolate together by [`mls_fields_of_degree`]: up to this many
/// two-component fields share one pass (the 8 states of a run's history).
const FIELDS_PER_PASS: usize = 8;

/// Several two-component fields on the same `source` nodes (the states of a run's
/// history) interpolated at every target by [`mls_values_of_degree`], up to
/// [`FIELDS_PER_PASS`] of them in one pass, so that each target's shape functions are
/// computed once per pass and not once per field.
pub fn mls_fields_of_degree(
    source: &[Point],
    fields: &[&[[f64; 2]]],
    targets: &[Point],
    degree: u32,
) -> Result<Vec<Vec<[f64; 2]>>, ShapeError> {
    let mut out = Vec::with_capacity(fields.len());
    for chunk in fields.chunks(FIELDS_PER_PASS) {
        let packed: Vec<[f64; 2 * FIELDS_PER_PASS]> = (0..source.len())
            .map(|i| {
                let mut v = [0.0; 2 * FIELDS_PER_PASS];
                for (f, field) in chunk.iter().enumerate() {
                    v[2 * f..2 * f + 2].copy_from_slice(&field[i]);
                }
                v
            })
            .collect();
        let at = mls_values_of_degree(source, &packed, targets, degree)?;
        out.extend((0..chunk.len()).map(|f| at.iter().map(|v| [v[2 * f], v[2 * f + 1]]).collect()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten fields (two passes) on a scattered cloud come out as each one interpolated
    /// on its own, to round-off (1e-12 of the largest value: the same shape functions,
    /// summed in the same order).
    #[test]
    fn fields_together_equal_fields_one_by_one() {
        // A scattered cloud: a jittered 15 x 15 lattice on the unit square.
        let jitter = |k: usize| ((k as f64 * 12.9898).sin() * 43758.5453).fract() * 0.03;
        let source: Vec<Point> = (0..225).map(|k| [(k % 15) as f64 / 14.0 + jitter(k), (k / 15) as f64 / 14.0 + jitter(k + 500)]).collect();
        let targets: Vec<Point> = (0..50).map(|k| [0.013 + 0.019 * k as f64, 0.5 + 0.4 * ((k as f64) * 0.7).sin()]).collect();
        let fields: Vec<Vec<[f64; 2]>> =
            (0..10).map(|f| source.iter().map(|p| [(p[0] * (f + 1) as f64).sin(), p[1].powi(f as i32 % 3) + p[0]]).collect()).collect();
        let refs: Vec<&[[f64; 2]]> = fields.iter().map(Vec::as_slice).collect();
        let together = mls_fields_of_degree(&source, &refs, &targets, 3).unwrap();
        assert_eq!(together.len(), 10);
        for (field, got) in fields.iter().zip(&together) {
            let alone = mls_values_of_degree(&source, field, &targets, 3).unwrap();
            for (a, b) in alone.iter().zip(got) {
                assert!((a[0] - b[0]).abs() <= 1e-12 && (a[1] - b[1]).abs() <= 1e-12, "{a:?} against {b:?}");
            }
        }
    }
}
