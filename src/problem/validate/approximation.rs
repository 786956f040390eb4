//! `[nodes]` and `[approximation]`: node generation and the local approximation of
//! the Navier model (basis, weight, support size, ghost nodes).

use super::{packing, Ctx, MAX_NODES};
use crate::choice::Choice;
use crate::domain::{Domain, FillKind, FillParams, Primitive};
use crate::mlsm::{Approximation, Basis, BasisKind, Weight, WeightKind};
use crate::problem::spec::{ApproximationSpec, NodesSpec};
use crate::problem::ProblemError;

/// Default support size for a basis of `m` functions.
///
/// Scattered fills: `2 m` (12 for degree-2 monomials), a least-squares fit
/// over-determined by a factor 2. Grid fills: the smallest complete ring of lattice
/// neighbours (9, 13, 21, 25, 29, 37, 45, 49, ...) with at least `1.4 m` nodes, because
/// the `n` nearest of a lattice node are ambiguous when the n-th distance is shared
/// by several nodes; an arbitrary pick makes stencils asymmetric (measured on
/// manufactured_traction.toml: order 1.3-1.6 with 12 nodes, 1.9-2.0 with 9).
pub fn default_support(m: usize, fill: FillKind) -> usize {
    match fill {
        FillKind::Scattered => 2 * m,
        FillKind::Grid => {
            // Count lattice points within radius^2 = r2 for increasing r2.
            let mut r2 = 1;
            loop {
                let k = (r2 as f64).sqrt() as i64;
                let count = (-k..=k).flat_map(|i| (-k..=k).map(move |j| i * i + j * j)).filter(|&d| d <= r2).count();
                if count as f64 >= 1.4 * m as f64 {
                    return count;
                }
                r2 += 1;
            }
        }
    }
}

/// Ghost nodes outside traction boundaries unless the scene says otherwise (static
/// scenes; time-dependent ones default to none).
pub const DEFAULT_GHOST_NODES: bool = true;

/// Support size of an RBF basis without `support` (the RBF interpolates its support).
const DEFAULT_RBF_SUPPORT: usize = 9;

/// `[nodes]`: fill, spacing (or count), seed, relaxation sweeps.
pub(super) fn nodes(c: &Ctx, s: &NodesSpec, domain: &Domain, area: f64) -> Result<FillParams, ProblemError> {
    let single_rectangle = domain.regions.len() == 1 && matches!(domain.regions[0].primitive, Primitive::Rectangle { .. });
    let kind = match &s.fill {
        None if single_rectangle => FillKind::Grid,
        None => FillKind::Scattered,
        Some(w) => c.choose("nodes.fill", Some(w))?,
    };
    let spacing = match (s.spacing, s.count) {
        (Some(_), Some(_)) => return c.err("nodes", "give either spacing or count, not both"),
        (None, None) => return c.err("nodes", "missing: give spacing = <m> or count = <nodes>"),
        (Some(h), None) => c.positive("nodes.spacing", h)?,
        (None, Some(n)) => {
            if n < 4 {
                return c.err("nodes.count", format!("must be at least 4, got {n}"));
            }
            (area * packing(kind) / n as f64).sqrt()
        }
    };
    let size = domain.scale();
    if spacing > size / 2.0 {
        return c.err("nodes.spacing", format!("spacing {spacing} is more than half the domain size {size:.3e}"));
    }
    let relax = s.relax.unwrap_or(0);
    if relax > 1000 {
        return c.err("nodes.relax", format!("{relax} sweeps; the fill settles within tens (seed 002 uses about 10); at most 1000"));
    }
    Ok(FillParams { spacing, kind, seed: s.seed.unwrap_or(0), relax_iterations: relax })
}

/// The basis of `[approximation]`: its kind with its degree or shape parameter.
fn basis(c: &Ctx, s: &ApproximationSpec) -> Result<Basis, ProblemError> {
    let kind: BasisKind = c.choose("approximation.basis", s.basis.as_deref())?;
    let basis = match kind.rbf() {
        None => {
            let degree = s.degree.unwrap_or(2);
            if !(2..=6).contains(&degree) {
                return c.err("approximation.degree", format!("must be 2..6 (the Navier equations need second derivatives), got {degree}"));
            }
            if kind == BasisKind::Tensor {
                Basis::Tensor { degree }
            } else {
                Basis::Monomials { degree }
            }
        }
        Some(rbf) => {
            if s.degree.is_some() {
                return c.err("approximation.degree", "RBF bases have no degree; remove it");
            }
            let shape = c.need("approximation.shape", s.shape, "an RBF basis needs shape (in units of the node spacing)")?;
            Basis::Rbf { rbf, shape: c.positive("approximation.shape", shape)? }
        }
    };
    if s.shape.is_some() && kind.rbf().is_none() {
        return c.err("approximation.shape", "only RBF bases take a shape parameter");
    }
    Ok(basis)
}

/// `[approximation]`: basis, weight, support size, ghost nodes.
pub(super) fn approximation(c: &Ctx, s: &ApproximationSpec, fill: FillKind, dynamic: bool) -> Result<Approximation, ProblemError> {
    let basis = basis(c, s)?;
    let weight = match c.choose("approximation.weight", s.weight.as_deref())? {
        WeightKind::None => {
            if s.sigma.is_some() {
                return c.err("approximation.sigma", format!("weight = \"{}\" takes no sigma", WeightKind::None.name()));
            }
            Weight::None
        }
        WeightKind::Gaussian => Weight::Gaussian { sigma: c.positive("approximation.sigma", s.sigma.unwrap_or(1.0))? },
    };
    // Polynomial bases have a fixed size m; an RBF basis has one function per support node.
    let m = basis.polynomial_degree().map(|_| basis.size(0));
    let support = match (s.support, m) {
        (Some(n), _) => n,
        (None, None) => DEFAULT_RBF_SUPPORT,
        (None, Some(m)) => default_support(m, fill),
    };
    if support < 2 {
        return c.err("approximation.support", format!("must be at least 2, got {support}"));
    }
    if let Some(m) = m.filter(|&m| support < m) {
        return c.err(
            "approximation.support",
            format!(
                "{support} nodes cannot determine the {m} coefficients of the basis ({}); use support >= {m} (about {} recommended)",
                basis.describe(),
                2 * m
            ),
        );
    }
    // Ghost nodes gave growing modes in explicit MLSM dynamics (README, known limits):
    // off by default for time-dependent scenes.
    let ghost_nodes = s.ghost_nodes.unwrap_or(DEFAULT_GHOST_NODES && !dynamic);
    Ok(Approximation { basis, weight, support, ghost_nodes })
}

/// The fill must give at least two supports' worth of nodes and at most [`MAX_NODES`].
pub(super) fn check_node_count(c: &Ctx, fill: &FillParams, approximation: &Approximation, area: f64) -> Result<(), ProblemError> {
    let expected_nodes = area / fill.spacing.powi(2) * packing(fill.kind);
    if expected_nodes < 2.0 * approximation.support as f64 {
        return c.err(
            "nodes.spacing",
            format!(
                "spacing {} gives about {expected_nodes:.0} nodes, too few for supports of {} nodes; use a smaller spacing",
                fill.spacing, approximation.support
            ),
        );
    }
    if expected_nodes > MAX_NODES {
        return c.err(
            "nodes.spacing",
            format!("spacing {} gives about {expected_nodes:.1e} nodes (over 5e7); this machine cannot hold the system", fill.spacing),
        );
    }
    Ok(())
}
