//! The contour of a balance: the arc around a re-entrant corner (a hole's circle is
//! one with the angles of a whole turn), found in the solid, and the rows of the
//! force and moment of the tractions on it, `sigma(u) n` from a degree-2 least-squares
//! fit at each point of a midpoint rule (module docs of [`super`]).

use super::{dist, MIN_SECTOR_SPACINGS, SECTOR_SPACINGS};
use crate::physics::case::Case;
use crate::domain::{NodeSet, Point};
use crate::physics::elasticity::dofs::{DofMap, Unknowns, PRESSURE};
use crate::physics::elasticity::material::Lame;
use crate::mlsm::{wls, Basis, Op, Weight};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::collections::BTreeMap;
use std::num::NonZeroUsize;

/// Nodes of the least-squares fit of the stress at an arc point.
const FIT_NODES: usize = 12;

/// The part of the circle of radius `radius` around a corner inside the solid.
#[derive(Debug, Clone, Copy)]
pub(super) struct Arc {
    /// Radius (m).
    pub radius: f64,
    /// Start and end angle, `end > start`.
    pub angles: (f64, f64),
}

/// The arc of the largest radius from [`SECTOR_SPACINGS`] down that leaves the solid
/// once and meets no boundary node of a part other than the corner's `parts`.
pub(super) fn arc(case: &Case, nodes: &NodeSet, corner: Point, parts: [usize; 2], h: f64) -> Option<Arc> {
    let mut spacings = SECTOR_SPACINGS;
    while spacings >= MIN_SECTOR_SPACINGS {
        let radius = spacings * h;
        let foreign =
            nodes.boundary.iter().any(|b| dist(b.position, corner) <= radius * 1.05 && b.touches.iter().any(|(p, _)| !parts.contains(p)));
        if !foreign {
            if let Some(angles) = inside_interval(case, corner, radius) {
                return Some(Arc { radius, angles });
            }
        }
        spacings /= 2.0;
    }
    None
}

/// The one interval of angles whose circle points lie in the solid, its ends found
/// by bisection; `None` when the circle enters the solid more than once.
pub(super) fn inside_interval(case: &Case, c: Point, radius: f64) -> Option<(f64, f64)> {
    const SAMPLES: usize = 720;
    let at = |t: f64| case.domain.contains([c[0] + radius * t.cos(), c[1] + radius * t.sin()]);
    let step = std::f64::consts::TAU / SAMPLES as f64;
    let inside: Vec<bool> = (0..SAMPLES).map(|k| at(k as f64 * step)).collect();
    // Entries: an outside sample followed by an inside one.
    let entries: Vec<usize> = (0..SAMPLES).filter(|&k| !inside[k] && inside[(k + 1) % SAMPLES]).collect();
    let [entry] = entries[..] else { return None };
    let exit = (1..SAMPLES).map(|d| (entry + 1 + d) % SAMPLES).find(|&k| !inside[k])?;
    let refine = |mut out: f64, mut inn: f64| {
        for _ in 0..50 {
            let mid = 0.5 * (out + inn);
            if at(mid) {
                inn = mid;
            } else {
                out = mid;
            }
        }
        0.5 * (out + inn)
    };
    let start = refine(entry as f64 * step, (entry + 1) as f64 * step);
    let mut end_out = exit as f64 * step;
    if end_out <= start {
        end_out += std::f64::consts::TAU;
    }
    let end = refine(end_out, end_out - step);
    Some((start, end))
}

/// The force and moment rows of the arc's tractions (midpoint rule, about two points
/// per local spacing, at least 48).
pub(super) fn arc_rows(
    case: &Case,
    (nodes, dofs): (&NodeSet, &DofMap),
    tree: &ImmutableKdTree<f64, 2>,
    c: Point,
    arc: &Arc,
    h: f64,
) -> Option<[Vec<(usize, f64)>; 3]> {
    let lame = arc_lame(case, dofs);
    let pressure = dofs.unknowns() == Unknowns::DisplacementPressure;
    let ops: &[Op] = if pressure { &[Op::Dx, Op::Dy, Op::Value] } else { &[Op::Dx, Op::Dy] };
    let (t0, t1) = arc.angles;
    let count = ((arc.radius * (t1 - t0) / (0.5 * h)).ceil() as usize).max(48);
    let dt = (t1 - t0) / count as f64;
    let fit = NonZeroUsize::new(FIT_NODES.min(nodes.len()))?;
    let mut sums: [BTreeMap<usize, f64>; 3] = Default::default();
    let (mut points, mut weights) = (Vec::with_capacity(FIT_NODES), vec![0.0; ops.len() * FIT_NODES]);
    let scale = row_scale(lame, arc.radius);
    for k in 0..count {
        let t = t0 + (k as f64 + 0.5) * dt;
        let n = [t.cos(), t.sin()];
        let q = [c[0] + arc.radius * n[0], c[1] + arc.radius * n[1]];
        let r = [q[0] - c[0], q[1] - c[1]];
        let ds = arc.radius * dt * scale;
        let found = tree.query(&q).nearest_n::<SquaredEuclidean<f64>>(fit).execute();
        points.clear();
        points.extend(found.iter().map(|f| nodes.positions[f.item as usize]));
        let m = points.len();
        wls::shape_functions(&Basis::Monomials { degree: 2 }, &Weight::None, (q, &points), ops, &mut weights[..ops.len() * m]).ok()?;
        let mut add = |col: usize, (tx, ty): (f64, f64)| {
            *sums[0].entry(col).or_default() += ds * tx;
            *sums[1].entry(col).or_default() += ds * ty;
            *sums[2].entry(col).or_default() += ds * (r[0] * ty - r[1] * tx) / arc.radius;
        };
        for (j, f) in found.iter().enumerate() {
            let node = f.item as usize;
            if pressure {
                // -p n, the unknown being p / mu.
                let v = -lame.mu * weights[2 * m + j];
                add(dofs.dof(node, PRESSURE), (v * n[0], v * n[1]));
            }
            for comp in 0..2 {
                // Traction t = sigma n of the gradient that component `comp` of node j
                // contributes: its weights in row `comp` of grad u.
                let mut g = [[0.0; 2]; 2];
                g[comp] = [weights[j], weights[m + j]];
                let [sxx, syy, sxy] = lame.stress(g);
                add(dofs.dof(node, comp), (sxx * n[0] + sxy * n[1], sxy * n[0] + syy * n[1]));
            }
        }
    }
    Some(sums.map(|s| s.into_iter().collect()))
}

/// The Lame parameters of the arc's stress from the displacement gradient: the
/// material's, or with `lambda = 0` in the displacement-pressure form, whose pressure
/// carries the rest.
pub(super) fn arc_lame(case: &Case, dofs: &DofMap) -> Lame {
    let lame = case.material.lame();
    match dofs.unknowns() {
        Unknowns::Displacement => lame,
        Unknowns::DisplacementPressure => Lame { lambda: 0.0, mu: lame.mu },
    }
}

/// The factor of the balance rows, which makes their coefficients O(1): one over the
/// stress of a unit gradient (`lame` as in [`arc_lame`]) times the arc's radius (the
/// moment row is divided by the radius once more).
pub(super) fn row_scale(lame: Lame, radius: f64) -> f64 {
    1.0 / ((lame.lambda + 2.0 * lame.mu) * radius)
}
