//! The `defect` error estimate of a static Navier run: its truncation error measured
//! on local polynomial fits of its own solution, mapped to an error by its own
//! operator (defect correction without a second discretisation).
//!
//! The run solves `A x = b`; at the exact nodal values `u*` (extended smoothly to the
//! ghosts) its rows leave the truncation error `tau = A u* - b`, and `x - u* =
//! -A^-1 tau` exactly. `tau` is estimated row by row from fits `P` of degree
//! `q = p + 2` (`p` the run's polynomial degree) of `x` at coarse centres
//! ([`crate::mlsm::taylor`]): every row of node `i` is exact on polynomials of degree
//! `<= p`, so `tau_r ~ sum_j a_rj H_p(x_j)` with `H_p` the part of `P` above degree
//! `p` about `x_i`. Then `e = -A^-1 tau` (one solve with the run's operator, to a
//! relative residual of [`CORRECTION_TOLERANCE`]) and the reference is `x - e`. The
//! stress reference is `G (x - e) - tau_G`, `G` the run's gradient stencils and
//! `tau_G = sum_j g_ij H_p(x_j)` their own truncation error.
//!
//! Near singular corners the fits cannot see the solution; there `tau` comes from
//! the higher-degree operator instead ([`super::corner_defect`]).
//!
//! Measured against the true errors and the `higher-degree` reference:
//! docs/notebook/2026-11-28-cheap-estimate.md.

use super::discrete::Discretisation;
use crate::domain::Point;
use crate::linalg::Csr;
use crate::mlsm::taylor::{fit, fit_points, HighPart, LocalPolynomial};
use crate::mlsm::Op;
use crate::physics::elasticity::stress::Gradient;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Relative residual the correction `A e = -tau` is solved to: an estimate needs one
/// digit of `e`, and a looser solve loses it. Tensor cantilever at 1e6 nodes
/// (`--spacing 0.01225`), effectivity in u: 0.85 at 1e-3 (8 GMRES iterations), 0.75 at
/// 1e-2 (6), 0.47 at 3e-2 (5) (docs/notebook/2026-11-28-cheap-estimate.md).
pub const CORRECTION_TOLERANCE: f64 = 1e-2;

/// Support members (nearest first) whose farthest sets a fit centre's reach.
const REACH_MEMBERS: usize = 20;

/// Radius, in units of its reach (the farthest of its [`REACH_MEMBERS`] nearest support
/// members), within which a fit centre stands for every node not yet taken by
/// another: one centre per 7 to 17 nodes on the shipped scenes. The fits are wide
/// ([`fit_points`], about 3.4 support radii), so a node 1.5 support radii from its
/// centre is measured as well as by its own fit: against 1.0
/// (the support itself, twice the centres) the effectivities moved by at most 0.12
/// (kirsch 0.82 -> 0.87, flamant sigma 0.82 -> 0.90, tensor cantilever at 1.2e5 nodes
/// 1.00 -> 1.12 in u) and the estimate stage took 0.67x; at 2.0 flamant's rose to
/// 1.38 (docs/notebook/2026-11-28-cheap-estimate.md).
const CLAIM_RADIUS: f64 = 1.5;

/// The fits of a run's solution at coarse centres, and which centre measures each node.
pub struct Fits {
    /// The run's polynomial degree `p`: the rows are exact on degree `<= p`.
    pub exact_degree: u32,
    /// One fit per centre, of the unknowns of a node (displacement, and pressure in
    /// the displacement-pressure form: 0 otherwise).
    fits: Vec<LocalPolynomial<3>>,
    /// Index into `fits` of every node.
    centre_of: Vec<u32>,
}

impl Fits {
    /// Fits of degree `p + 2` of the unknowns `x` of `disc` at coarse centres chosen
    /// greedily in node order ([`CLAIM_RADIUS`]), or why there are none (too few
    /// nodes). `done(k, n)` is told after each of about twenty batches that `k` of the
    /// `n` fits are made.
    pub fn of(disc: &Discretisation, x: &[f64], p: u32, done: &dyn Fn(usize, usize)) -> Result<Fits, String> {
        let n = disc.nodes.len();
        let q = p + 2;
        let points = fit_points(q);
        if points > n {
            return Err(format!("{n} nodes are too few for the fits of degree {q} it needs ({points} nodes each)"));
        }
        let positions = &disc.nodes.positions;
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).map_err(|e| format!("node positions: {e}"))?;
        let mut centre_of = vec![u32::MAX; n];
        let mut centres = Vec::new();
        for i in 0..n {
            if centre_of[i] == u32::MAX {
                let k = centres.len() as u32;
                centres.push(i);
                let at = positions[i];
                let reach2 = disc
                    .supports
                    .of(i)
                    .iter()
                    .take(REACH_MEMBERS)
                    .filter(|&&j| (j as usize) < n)
                    .map(|&j| squared_distance(positions[j as usize], at))
                    .fold(0.0, f64::max);
                tree.query(&at).within::<SquaredEuclidean<f64>>(reach2 * CLAIM_RADIUS * CLAIM_RADIUS).unsorted().visit(|f| {
                    if centre_of[f.item as usize] == u32::MAX {
                        centre_of[f.item as usize] = k;
                    }
                });
                centre_of[i] = k;
            }
        }
        let per_node = disc.dofs.unknowns().per_node();
        let value = |j: usize| {
            let mut v = [0.0; 3];
            for (c, slot) in v.iter_mut().enumerate().take(per_node) {
                *slot = x[disc.dofs.dof(j, c)];
            }
            v
        };
        let fit_at = |&c: &usize| {
            let near = nearest(&tree, positions, c, points, disc.supports.of(c));
            let values: Vec<[f64; 3]> = near.iter().map(|&j| value(j)).collect();
            let near: Vec<Point> = near.iter().map(|&j| positions[j]).collect();
            fit(positions[c], &near, &values, q).map_err(|_| {
                format!(
                    "the {points} nodes nearest to ({:.4e}, {:.4e}) do not determine a fit of degree {q}",
                    positions[c][0], positions[c][1]
                )
            })
        };
        let mut fits = Vec::with_capacity(centres.len());
        for batch in centres.chunks(centres.len().div_ceil(20)) {
            fits.extend(batch.par_iter().map(fit_at).collect::<Result<Vec<_>, String>>()?);
            done(fits.len(), centres.len());
        }
        Ok(Fits { exact_degree: p, fits, centre_of })
    }

    /// `H_p` about node `i` of the fit that measures it.
    fn high_part(&self, i: usize, at: Point) -> HighPart<3> {
        self.fits[self.centre_of[i] as usize].high_part_about(at, self.exact_degree)
    }

    /// Number of fit centres.
    pub fn centres(&self) -> usize {
        self.fits.len()
    }
}

/// `|a - b|^2`.
fn squared_distance(a: Point, b: Point) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// The `count` nodes nearest to node `c` (`count <= ` the node count), in no order: all
/// nodes within a radius guessed from the support `support` of `c` (the area of
/// `count` nodes at its density, 1.5x), widened until it holds `count`, and the
/// `count` nearest of them selected. A radius search that keeps everything costs a
/// fraction of a sorted k-nearest search of 150 (insertion into a sorted list).
fn nearest(tree: &ImmutableKdTree<f64, 2>, positions: &[Point], c: usize, count: usize, support: &[u32]) -> Vec<usize> {
    let at = positions[c];
    let members: Vec<f64> = support.iter().filter(|&&j| (j as usize) < positions.len()).map(|&j| squared_distance(positions[j as usize], at)).collect();
    let reach2 = members.iter().copied().fold(0.0, f64::max);
    let mut radius2 = if reach2 > 0.0 { reach2 * 1.5 * count as f64 / members.len() as f64 } else { f64::INFINITY };
    let mut found: Vec<(f64, usize)> = Vec::with_capacity(2 * count);
    loop {
        found.clear();
        tree.query(&at).within::<SquaredEuclidean<f64>>(radius2).unsorted().visit(|n| found.push((n.distance, n.item as usize)));
        if found.len() >= count || radius2 == f64::INFINITY {
            break;
        }
        radius2 *= 2.0;
    }
    if found.len() > count {
        found.select_nth_unstable_by(count - 1, |a, b| a.0.total_cmp(&b.0));
        found.truncate(count);
    }
    found.into_iter().map(|(_, j)| j).collect()
}

/// The truncation error `tau` of every row of `matrix` (the run's assembled rows, the
/// multipliers of a bordered system last, where `tau` is 0) from `fits`: the rows of
/// node `i` and of its ghost are measured about `x_i` (module docs).
pub fn truncation_error(disc: &Discretisation, matrix: &Csr, fits: &Fits) -> Vec<f64> {
    let (dofs, n) = (disc.dofs, disc.nodes.len());
    let per_node = dofs.unknowns().per_node();
    let mut tau = vec![0.0; matrix.nrows()];
    // A node's own rows in place, its ghost's (few) collected and written after.
    let ghost_rows: Vec<(usize, [f64; 3])> = tau[..n * per_node]
        .par_chunks_mut(per_node)
        .enumerate()
        .map_init(Vec::new, |seen: &mut Vec<(usize, [f64; 3])>, (i, own)| {
            let high = fits.high_part(i, disc.nodes.positions[i]);
            // The rows of a node and of its ghost read the same few nodes, each with
            // every component: `H_p` once per node read.
            seen.clear();
            let mut row_tau = |r: usize| {
                let row = matrix.row(r);
                let mut sum = 0.0;
                for (&col, &a) in row.col_indices().iter().zip(row.values()) {
                    if (col as usize) < dofs.len() {
                        let (j, c) = dofs.location(col as usize);
                        let h = match seen.iter().find(|(k, _)| *k == j) {
                            Some((_, h)) => *h,
                            None => {
                                let h = high.value(disc.point(j));
                                seen.push((j, h));
                                h
                            }
                        };
                        sum += a * h[c];
                    }
                }
                sum
            };
            for (c, t) in own.iter_mut().enumerate() {
                *t = row_tau(dofs.dof(i, c));
            }
            disc.ghost[i].map(|k| {
                let mut t = [0.0; 3];
                for (c, tc) in t.iter_mut().enumerate().take(per_node) {
                    *tc = row_tau(dofs.dof(k, c));
                }
                (k, t)
            })
        })
        .flatten()
        .collect();
    for (k, t) in ghost_rows {
        for (c, tc) in t.iter().enumerate().take(per_node) {
            tau[dofs.dof(k, c)] = *tc;
        }
    }
    tau
}

/// The truncation error of the gradient stencils `(Dx, Dy)` of `disc` (in place at
/// every node) on `fits`: `tau_G[i][c][d] = sum_k g^d_ik H_p(x_jk)[c]`.
pub fn gradient_truncation_error(disc: &Discretisation, fits: &Fits) -> Vec<Gradient> {
    (0..disc.nodes.len())
        .into_par_iter()
        .map(|i| {
            let high = fits.high_part(i, disc.nodes.positions[i]);
            let (dx, dy) = (disc.shapes.get(i, Op::Dx), disc.shapes.get(i, Op::Dy));
            let mut g = [[0.0; 2]; 2];
            for (k, &j) in disc.supports.of(i).iter().enumerate() {
                let h = high.value(disc.point(j as usize));
                for c in 0..2 {
                    g[c][0] += dx[k] * h[c];
                    g[c][1] += dy[k] * h[c];
                }
            }
            g
        })
        .collect()
}
