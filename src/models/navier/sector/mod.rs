//! Equilibrium of a sector around each re-entrant corner, and of a ring around each
//! free hole, imposed on the collocation system.
//!
//! At a re-entrant corner whose two edges are traction-free, the fields of a point
//! force and of a point couple at the corner satisfy the Navier equation everywhere
//! but at the corner and leave both edges free. The collocation rows see them only
//! through the few stencils at the corner, where no polynomial fits the singular
//! field, so the discrete system nearly admits them: on scattered nodes the solution
//! of the L bracket carried a spurious corner load of 1-10 times the applied one (the
//! column's section forces, `benches/section_forces.py`), and its tip deflection had
//! the wrong sign. Here the equilibrium of the sector `V` of radius `rho` around the
//! corner (its straight sides on the free edges) is imposed,
//!
//! ```text
//! integral over the arc of sigma(u) n ds = -F,   integral over the arc of r x sigma(u) n ds = -M,
//! ```
//!
//! `F` and `M` the force and moment of the loads inside the sector: the tractions
//! prescribed on its straight sides and the body force over it ([`loads`]; zero for a
//! corner between free edges without body force), `n` the arc's outward normal, `r`
//! from the corner, `sigma(u)` from a degree-2 least
//! squares fit over the 12 nearest nodes at each point of a midpoint rule on the arc.
//! Its three multipliers are a force and a couple injected into the Navier rows of
//! the interior nodes within [`INJECTION_SPACINGS`] of the corner (each row's share
//! scaled by its norm), and the system is bordered by them ([`border`],
//! `linalg::border`): `A x + G lambda = b`, `C x = d`. Sparse LU factors the bordered
//! matrix as it stands; the Krylov solvers take it with a block preconditioner around
//! one of `A`. (Until 2026-11-27 the multipliers were eliminated on three pivot rows,
//! which put the balance rows, without a diagonal entry, in their place: ILU met a
//! zero pivot there, and BiCGSTAB + ILUT failed on the bracket. The bordered matrix
//! also has 7 % fewer entries: the elimination filled the injected rows.)
//!
//! The boundary nodes near a balanced corner keep their ghosts (`domain::ghost`,
//! `navier::discrete`). Without them RBF-FD's one-sided 30-node traction stencils
//! made a spurious load of their own outside the sector (the L's tip -9.0e-4 m at
//! 1 mm against -4.84e-4 m with them; finite elements -4.894e-4), and least squares
//! one at some spacings and node sets (the scattered bracket's tip 182 % off at
//! 1.5 mm, 46 % at 3 mm; with the ghosts 1.9 % and 3.8 %), where the multigrid's
//! block Gauss-Seidel also diverged next to the ghost-free edges.
//!
//! In the displacement-pressure form `sigma = -p I + mu (grad u + grad u^T)`, with `p`
//! fitted like `u`, and the multipliers go into the momentum rows.
//!
//! Applied when both edges at the corner carry tractions (until 2026-11-27 only free
//! edges without body force, in the displacement form: the other corners stayed
//! ghost-free, and there the multigrid diverged); the radius is [`SECTOR_SPACINGS`] local
//! spacings of the nodes within it (on nodes graded towards the corner, the largest
//! of their spacings, not the corner node's: an arc of 10 corner spacings crossed
//! nodes 2 to 4 times coarser, and the graded bracket's tip at 0.5 mm was -1.8e-3 m
//! instead of -5.4e-4), halved (down to [`MIN_SECTOR_SPACINGS`]) while the arc leaves
//! the solid more than once or meets a boundary part other than the corner's two.
//!
//! **Holes.** A hole with traction edges (an inner loop of the boundary,
//! `domain::corner::holes`) carries the resultant of its loads and no more, yet the
//! discrete solution could put a spurious one on it where the hole spans few spacings: on the scattered
//! bracket the holes (radius 6 and 5 spacings at 2 mm) carried 0.45 F (least
//! squares) and 0.24 F (PHS, p = 4), which made PHS's tip deflection 14 % too large
//! and with it the error estimate of the default run 0.17. The same three conditions
//! are imposed (with the loads on the hole and the body force between it and the
//! circle) on a whole circle around the hole (centred at its nodes' length-weighted mean, at
//! [`RING_SPACINGS`] from its farthest node, inside the solid with no other boundary
//! node within), the multipliers injected into the Navier rows of the interior nodes
//! within [`INJECTION_SPACINGS`] of the hole's nodes.
//!
//! A corner or hole with traction edges that gets no balance (the cases above, or no
//! arc or ring fits, or its fit or injection fails) is listed as [`Unbalanced`] with
//! the reason, which the checks turn into a note.

use crate::physics::case::Case;
use crate::domain::{NodeSet, Point};
use crate::physics::elasticity::dofs::DofMap;
use crate::physics::elasticity::conditions::ComponentCondition;
use crate::physics::exact::ExactSolution;
use crate::linalg::Csr;
use kiddo::ImmutableKdTree;

mod arc;
mod impose;
mod loads;
use arc::{arc, arc_lame, arc_rows, row_scale, Arc};
pub use impose::border;
use impose::has_rank_three;

/// Radius of the sector, in local spacings of the corner node (the tip deflection of
/// the L bracket was the same at 10 and 20 spacings to 0.3 %; at 5 it scattered).
pub const SECTOR_SPACINGS: f64 = 10.0;

/// Smallest radius tried, in local spacings, where the arc would meet another part.
pub const MIN_SECTOR_SPACINGS: f64 = 4.0;

/// Radius around the corner, in local spacings, of the interior nodes whose Navier
/// rows carry the multipliers.
pub const INJECTION_SPACINGS: f64 = 2.0;

/// What a balance's contour goes around.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Around {
    /// A re-entrant corner between two free edges: an arc from edge to edge.
    Corner,
    /// A traction-free hole: a whole circle around it.
    Hole,
}

/// The balance of one corner's sector or one hole's ring: three rows over the
/// unknowns and the injected rows' shares of the three multipliers.
#[derive(Debug, Clone)]
pub struct SectorBalance {
    /// Corner or hole.
    pub around: Around,
    /// The corner, or the centre of the hole's circle.
    pub centre: Point,
    /// Radius of the arc (m).
    pub radius: f64,
    /// Force x, force y and moment of the arc's tractions, `(unknown, coefficient)`.
    rows: [Vec<(usize, f64)>; 3],
    /// Their right-hand sides: minus the enclosed loads, in the rows' scale.
    loads: [f64; 3],
    /// `(row, g)`: the row's share of the force x, force y and couple multipliers.
    injected: Vec<(usize, [f64; 3])>,
}

/// What `summary.json` says of one imposed balance.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SectorSummary {
    /// Corner or hole.
    pub around: Around,
    /// The corner, or the centre of the hole's circle.
    pub centre: Point,
    /// Radius of the arc (m).
    pub radius: f64,
}

impl SectorBalance {
    /// What it goes around, its centre and radius.
    pub fn summary(&self) -> SectorSummary {
        SectorSummary { around: self.around, centre: self.centre, radius: self.radius }
    }
}

/// A contour that qualifies for a balance: what it goes around, its centre, its arc,
/// the local spacing there, the points whose neighbourhood carries the
/// multipliers (the corner, or the hole's boundary nodes), and the boundary parts it
/// encloses.
#[derive(Debug, Clone)]
struct Contour {
    around: Around,
    centre: Point,
    arc: Arc,
    h: f64,
    seeds: Vec<Point>,
    parts: Vec<usize>,
}

/// A re-entrant corner between traction edges or a hole with traction edges that gets
/// no balance, and why: reported as a note, since its discrete solution may carry the
/// spurious load the balance removes.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Unbalanced {
    /// Corner or hole.
    pub around: Around,
    /// The corner, or the mean position of the hole's nodes.
    pub at: Point,
    /// Why it is not balanced.
    pub reason: String,
}

/// The re-entrant corners and holes with traction edges of a node set: the contours of
/// those that qualify for a balance (module docs), and those that do not, with the
/// reason. Made once per discretisation ([`survey`]; `Discretisation::survey`): the
/// ghost placement reads its corners, the assembly its contours.
#[derive(Debug, Clone, Default)]
pub struct Survey {
    contours: Vec<Contour>,
    /// The corners and holes that get no balance, and why.
    pub unbalanced: Vec<Unbalanced>,
}

impl Survey {
    /// The re-entrant corners that [`balances`] will balance (in-process static solves).
    pub fn balanced_corners(&self) -> Vec<Point> {
        self.contours.iter().filter(|c| c.around == Around::Corner).map(|c| c.centre).collect()
    }

    /// Every corner and hole with traction edges, for an assembly that imposes no
    /// balance (rows split over MPI ranks, time steps), those that qualified with
    /// `reason`.
    pub fn none_balanced(&self, reason: &str) -> Vec<Unbalanced> {
        let mut unbalanced = self.unbalanced.clone();
        unbalanced.extend(self.contours.iter().map(|c| Unbalanced { around: c.around, at: c.centre, reason: reason.into() }));
        unbalanced
    }
}

/// The [`Survey`] of `nodes`.
pub fn survey(case: &Case, nodes: &NodeSet) -> Survey {
    let traction = |part: usize| case.conditions.get(part).is_some_and(|c| c.is_all(ComponentCondition::Traction));
    let corners =
        crate::domain::corner::corners(&case.domain, nodes).into_iter().filter(|c| c.reentrant && c.parts.iter().all(|&p| traction(p)));
    let holes = crate::domain::corner::holes(nodes)
        .into_iter()
        .filter(|hole| hole.iter().all(|&i| nodes.boundary[i].touches.iter().all(|&(p, _)| traction(p))));
    let (mut contours, mut unbalanced) = (Vec::new(), Vec::new());
    let mut refuse = |around: Around, at: Point, reason: &str| unbalanced.push(Unbalanced { around, at, reason: reason.into() });
    for c in corners {
        let h = spacing_at_arc(nodes, c.position, nodes.local_spacing[c.node]);
        match arc(case, nodes, c.position, c.parts, h) {
            Some(arc) => {
                let parts = c.parts.to_vec();
                contours.push(Contour { around: Around::Corner, centre: c.position, arc, h, seeds: vec![c.position], parts })
            }
            None => refuse(
                Around::Corner,
                c.position,
                &format!("no arc of {MIN_SECTOR_SPACINGS} to {SECTOR_SPACINGS} spacings stays between its two edges"),
            ),
        }
    }
    for hole in holes {
        let mean = crate::domain::corner::mean_position(nodes, &hole);
        match ring(case, nodes, &hole) {
            Some(ring) => contours.push(ring),
            None => refuse(Around::Hole, mean, "no ring 3 to 10 spacings out fits in the solid without meeting another boundary"),
        }
    }
    Survey { contours, unbalanced }
}

/// The spacing `h` at which the arc of radius `SECTOR_SPACINGS h` is `SECTOR_SPACINGS`
/// spacings of the nodes it crosses: the fixed point of `h <- max local spacing within
/// SECTOR_SPACINGS h`, from the corner node's spacing, after at most 20 steps (a
/// grading of 0.1 per unit distance has none: the radius then grows by ten corner
/// spacings a step, and [`arc`] halves it where it meets another part).
fn spacing_at_arc(nodes: &NodeSet, corner: Point, mut h: f64) -> f64 {
    for _ in 0..20 {
        let r = SECTOR_SPACINGS * h;
        let within =
            nodes.positions.iter().zip(&nodes.local_spacing).filter(|(p, _)| dist(**p, corner) <= r).map(|(_, &s)| s).fold(h, f64::max);
        if within <= h * 1.001 {
            break;
        }
        h = within;
    }
    h
}

/// The balances of the case's re-entrant corners and holes that qualify (module docs),
/// and those that get none, with the reason; `exact` gives the loads a scene takes
/// from its exact solution.
pub fn balances(
    case: &Case,
    survey: &Survey,
    (nodes, dofs): (&NodeSet, &DofMap),
    matrix: &Csr,
    exact: Option<&dyn ExactSolution>,
) -> (Vec<SectorBalance>, Vec<Unbalanced>) {
    let Survey { contours, mut unbalanced } = survey.clone();
    if contours.is_empty() {
        return (Vec::new(), unbalanced);
    }
    let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&nodes.positions).expect("finite node positions");
    let mut balances = Vec::with_capacity(contours.len());
    for c in contours {
        let rows = arc_rows(case, (nodes, dofs), &tree, c.centre, &c.arc, c.h);
        let injected = injection((nodes, dofs), matrix, c.centre, &c.seeds, c.h);
        match (rows, injected) {
            (Some(rows), Some(injected)) if has_rank_three(&injected) => {
                let [fx, fy, m] = loads::enclosed(case, exact, c.centre, &c.arc, &c.parts);
                let scale = row_scale(arc_lame(case, dofs), c.arc.radius);
                let loads = [-scale * fx, -scale * fy, -scale * m / c.arc.radius];
                balances.push(SectorBalance { around: c.around, centre: c.centre, radius: c.arc.radius, rows, loads, injected })
            }
            (None, _) => unbalanced.push(Unbalanced { around: c.around, at: c.centre, reason: "the stress fit on its arc failed".into() }),
            _ => unbalanced.push(Unbalanced {
                around: c.around,
                at: c.centre,
                reason: "too few interior nodes near it carry the force and couple".into(),
            }),
        }
    }
    (balances, unbalanced)
}

/// Distances of a hole's ring from the hole, in local spacings, tried from the
/// largest down: the field around a hole is smooth, so the ring may come closer than
/// a corner's arc, but it must stay outside the injected nodes
/// ([`INJECTION_SPACINGS`]).
const RING_SPACINGS: [f64; 6] = [10.0, 8.0, 6.0, 5.0, 4.0, 3.0];

/// The circle around a hole (its boundary nodes `hole`): centred at their mean
/// (weighted by the boundary length each stands for), at
/// the largest distance of [`RING_SPACINGS`] from the farthest of them that lies in
/// the solid all round and has no other boundary node inside.
fn ring(case: &Case, nodes: &NodeSet, hole: &[usize]) -> Option<Contour> {
    // Means weighted by the arc length each node stands for (graded nodes crowd one side).
    let centre = crate::domain::corner::mean_position(nodes, hole);
    let length = |i: usize| nodes.boundary[i].lengths.iter().sum::<f64>();
    let h = hole.iter().map(|&i| length(i) * nodes.local_spacing[i]).sum::<f64>() / hole.iter().map(|&i| length(i)).sum::<f64>();
    let reach = hole.iter().map(|&i| dist(nodes.positions[i], centre)).fold(0.0, f64::max);
    let own: std::collections::BTreeSet<usize> = hole.iter().copied().collect();
    let mut parts: Vec<usize> = hole.iter().flat_map(|&i| nodes.boundary[i].touches.iter().map(|&(p, _)| p)).collect();
    parts.sort_unstable();
    parts.dedup();
    RING_SPACINGS.iter().find_map(|&s| {
        let radius = reach + s * h;
        let foreign = (0..nodes.boundary.len()).any(|b| !own.contains(&b) && dist(nodes.positions[b], centre) <= radius + 0.5 * h);
        let inside = (0..720).all(|j| {
            let t = j as f64 * std::f64::consts::TAU / 720.0;
            case.domain.contains([centre[0] + radius * t.cos(), centre[1] + radius * t.sin()])
        });
        (!foreign && inside).then(|| Contour {
            around: Around::Hole,
            centre,
            arc: Arc { radius, angles: (0.0, std::f64::consts::TAU) },
            h,
            seeds: hole.iter().map(|&i| nodes.positions[i]).collect(),
            parts: parts.clone(),
        })
    })
}

/// The injected rows: the Navier rows of the interior nodes within
/// [`INJECTION_SPACINGS`] of a seed (the corner, or the hole's boundary nodes; the
/// radius grows by half until there are two nodes, up to twice), each scaled by the
/// row's norm; the couple's share is the direction perpendicular to the node's offset
/// from the centre.
fn injection((nodes, dofs): (&NodeSet, &DofMap), matrix: &Csr, c: Point, seeds: &[Point], h: f64) -> Option<Vec<(usize, [f64; 3])>> {
    let interior = nodes.boundary.len()..nodes.len();
    let reach = seeds.iter().map(|&s| dist(s, c)).fold(0.0, f64::max);
    let mut radius = INJECTION_SPACINGS * h;
    for _ in 0..3 {
        let near: Vec<usize> = interior
            .clone()
            .filter(|&i| {
                let p = nodes.positions[i];
                dist(p, c) < reach + radius && seeds.iter().any(|&s| dist(p, s) < radius)
            })
            .collect();
        if near.len() >= 2 {
            let mut out = Vec::with_capacity(2 * near.len());
            for i in near {
                let p = nodes.positions[i];
                let d = dist(p, c);
                let perp = [-(p[1] - c[1]) / d, (p[0] - c[0]) / d];
                for comp in 0..2 {
                    let row = dofs.dof(i, comp);
                    let norm = crate::linalg::scaled_norm(matrix.row(row).values());
                    let mut g = [0.0; 3];
                    g[comp] = norm;
                    g[2] = norm * perp[comp];
                    out.push((row, g));
                }
            }
            return Some(out);
        }
        radius *= 1.5;
    }
    None
}

fn dist(a: Point, b: Point) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}
