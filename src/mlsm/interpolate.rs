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
