//! The `[peridynamics]` table of a scene, validated: horizon, ratio `m = delta / h`,
//! kernel, quadrature rule (which is also the node layout), surface correction,
//! linear solver and bond force law.

use super::kernel::Kernel;
use crate::scene::choice::choice;
use crate::domain::Point;
use serde::Serialize;

choice! {
    /// How each cell of the lattice is integrated; the nodes are the rule's points.
    pub enum Quadrature("peridynamics.quadrature", default Some(Quadrature::Compatible), serde "kebab-case") {
        /// One node at each cell centre with the full cell area (FA; the seed's midpoint rule, Q1).
        FullArea = "full-area" => "cell-centre nodes with the full cell area (the seed's midpoint rule)",
        /// Cell-centre nodes weighted by the exact area of the cell inside the horizon disc.
        PartialArea = "partial-area" => "cell-centre nodes weighted by the cell area inside the horizon",
        /// Four nodes per cell at the 2x2 Gauss points, a quarter of the area each (Q3).
        Gauss2x2 = "gauss2x2" => "four nodes per cell at the 2x2 Gauss points",
        /// Triangles, one node at each centroid with the triangle's area (P1; the seed's "type 5").
        TriangleP1 = "triangle-p1" => "triangles, one node at each centroid (type 5, P1)",
        /// Triangles, three interior nodes `(2/3, 1/6, 1/6)` (barycentric) per triangle with a
        /// third of its area each (P2; the seed's "type 4").
        TriangleP2 = "triangle-p2" => "triangles, three interior nodes each (type 4, P2)",
        /// Triangles, the seven-point rule per triangle (vertices 3, edge midpoints 8,
        /// centroid 27, times `|T|/60`; P3, the seed's "type 3"); vertices and edge midpoints
        /// are shared with the neighbouring triangles.
        TriangleP3 = "triangle-p3" => "triangles, seven-point rule with shared vertices and edge midpoints (type 3, P3)",
        /// Triangles, a third of each triangle's area at each vertex (P1; the seed's "type 1"):
        /// the nodes are the vertices, shared.
        TriangleVertex = "triangle-vertex" => "triangles, a third of the area at each vertex (type 1, P1)",
        /// Triangles, a third of each triangle's area at each edge midpoint (P2; the seed's
        /// "type 2"): the nodes are the edge midpoints, shared.
        TriangleEdge = "triangle-edge" => "triangles, a third of the area at each edge midpoint (type 2, P2)",
        /// Triangles, Hillion's four-point rule (P3; the seed's "type 6", eq. 1.1.7 and app. B.2).
        TriangleHillion = "triangle-hillion" => "triangles, Hillion's four interior points (type 6, P3)",
        /// Cell-centre nodes; at nodes with a complete family the bond weights are
        /// corrected to reproduce the continuum moments exactly ([`super::compatible`]).
        Compatible = "ac" => "cell-centre nodes, bond weights matched to the continuum moments (asymptotically compatible)",
    }
}

impl Quadrature {
    /// The rule on the reference triangle `(0,0), (1,0), (0,1)` as `(point, share of |T|)`,
    /// for the triangle rules (seed 000, sec. 1.1.3; types 1-6 of table 6.1.1); `None` for
    /// the rules of square cells.
    pub fn triangle_rule(self) -> Option<Vec<(Point, f64)>> {
        let third = 1.0 / 3.0;
        Some(match self {
            Quadrature::TriangleVertex => vec![([0.0, 0.0], third), ([1.0, 0.0], third), ([0.0, 1.0], third)],
            Quadrature::TriangleEdge => vec![([0.5, 0.0], third), ([0.5, 0.5], third), ([0.0, 0.5], third)],
            Quadrature::TriangleP3 => {
                let (v, e, c) = (3.0 / 60.0, 8.0 / 60.0, 27.0 / 60.0);
                vec![
                    ([0.0, 0.0], v),
                    ([1.0, 0.0], v),
                    ([0.0, 1.0], v),
                    ([0.5, 0.0], e),
                    ([0.5, 0.5], e),
                    ([0.0, 0.5], e),
                    ([third, third], c),
                ]
            }
            Quadrature::TriangleP2 => {
                let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
                vec![([a, a], third), ([b, a], third), ([a, b], third)]
            }
            Quadrature::TriangleP1 => vec![([third, third], 1.0)],
            Quadrature::TriangleHillion => {
                // Seed 000, app. B.2: nu_1..nu_4 in closed form; weights 1/4 -+ sqrt(6)/36.
                let (r2, r3, r6) = (2f64.sqrt(), 3f64.sqrt(), 6f64.sqrt());
                let n1 = 0.3 - r6 / 20.0 - r3 / 10.0 + r2 / 20.0;
                let n2 = 0.3 - r6 / 20.0 + r3 / 10.0 - r2 / 20.0;
                let n3 = 0.3 + r6 / 20.0 + r3 / 10.0 + r2 / 20.0;
                let n4 = 0.3 + r6 / 20.0 - r3 / 10.0 - r2 / 20.0;
                let (low, high) = (0.25 - r6 / 36.0, 0.25 + r6 / 36.0);
                vec![([n1, n2], low), ([n2, n1], low), ([n3, n4], high), ([n4, n3], high)]
            }
            Quadrature::FullArea | Quadrature::PartialArea | Quadrature::Gauss2x2 | Quadrature::Compatible => return None,
        })
    }

    /// Whether the rule puts nodes on triangle vertices or edges, shared with the
    /// neighbouring triangles (types 1-3).
    pub fn shares_points(self) -> bool {
        matches!(self, Quadrature::TriangleVertex | Quadrature::TriangleEdge | Quadrature::TriangleP3)
    }

    /// What one unit cell `[0, 1]^2` adds to its points: `(point, share of the cell area)`.
    /// A triangle rule is applied to the cell's two triangles `(0,0), (1,0), (1,1)` and
    /// `(0,0), (1,1), (0,1)` (the point `A + xi (B - A) + eta (C - A)` of each); points on
    /// the cell's edges and corners are shared with the neighbouring cells.
    pub fn cell_contributions(self) -> Vec<(Point, f64)> {
        match self.triangle_rule() {
            None => self.square_rule(),
            Some(rule) => {
                let triangles = [[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]];
                let mut out: Vec<(Point, f64)> = Vec::new();
                for [a, b, c] in triangles {
                    for &(q, w) in &rule {
                        let p = on_triangle(q, [a, b, c]);
                        match out.iter_mut().find(|(o, _)| (o[0] - p[0]).abs() + (o[1] - p[1]).abs() < 1e-12) {
                            Some(o) => o.1 += 0.5 * w,
                            None => out.push((p, 0.5 * w)),
                        }
                    }
                }
                out
            }
        }
    }

    /// The rules of square cells: `(point in [0, 1]^2, share of the cell area)`.
    fn square_rule(self) -> Vec<(Point, f64)> {
        match self {
            Quadrature::Gauss2x2 => {
                let g = 3f64.sqrt() / 6.0;
                let (a, b) = (0.5 - g, 0.5 + g);
                vec![([a, a], 0.25), ([b, a], 0.25), ([a, b], 0.25), ([b, b], 0.25)]
            }
            _ => vec![([0.5, 0.5], 1.0)],
        }
    }

    /// Points of the periodic unit of the lattice with their share of the cell area: the
    /// cell's contributions with shared points folded into `[0, 1)^2` and summed.
    pub fn unit_cell(self) -> Vec<(Point, f64)> {
        let mut out: Vec<(Point, f64)> = Vec::new();
        for (p, w) in self.cell_contributions() {
            match unit_index(&out, p) {
                Some(k) => out[k].1 += w,
                None => out.push(([p[0] - p[0].floor(), p[1] - p[1].floor()], w)),
            }
        }
        out
    }
}

/// Where the point `p` of a cell, folded into the periodic unit `[0, 1)^2`, stands in
/// `unit` (points of [`Quadrature::unit_cell`]).
pub fn unit_index(unit: &[(Point, f64)], p: Point) -> Option<usize> {
    let folded = [p[0] - p[0].floor(), p[1] - p[1].floor()];
    unit.iter().position(|(o, _)| (o[0] - folded[0]).abs() + (o[1] - folded[1]).abs() < 1e-12)
}

/// The point `A + xi (B - A) + eta (C - A)` of the triangle `[A, B, C]` for the point
/// `q = (xi, eta)` of the reference triangle.
pub fn on_triangle(q: Point, [a, b, c]: [Point; 3]) -> Point {
    [a[0] + q[0] * (b[0] - a[0]) + q[1] * (c[0] - a[0]), a[1] + q[0] * (b[1] - a[1]) + q[1] * (c[1] - a[1])]
}

choice! {
    /// Surface correction of bonds near free edges.
    pub enum SurfaceCorrection("peridynamics.correction", default Some(SurfaceCorrection::None), serde "lowercase") {
        /// Bonds as they are: nodes near a free edge are softer (the PD surface effect).
        None = "none" => "bonds as they are (nodes near a free edge are softer)",
        /// Volume method: bond `ij` scaled by `2 V_delta / (V_i + V_j)`, `V_i` the family
        /// volume of node `i` and `V_delta = pi delta^2` (Le & Bobaru 2018, volume method).
        Volume = "volume" => "bond ij scaled by 2 V_delta / (V_i + V_j) (volume method)",
    }
}

choice! {
    /// The constitutive model of the peridynamic solid (`peridynamics.solid`).
    pub enum Solid("peridynamics.solid", default Some(Solid::Auto), serde "kebab-case") {
        /// Bond-based where it represents the material, the linear peridynamic solid otherwise
        /// (resolved by validation: a validated [`PdParams`] never holds it).
        Auto = "auto" => "bond-based where it represents the material (nu = 1/4 plane strain, 1/3 plane stress), else the linear peridynamic solid",
        /// Pairwise bonds only: in-plane `lambda = mu` ([`super::kernel`]).
        BondBased = "bond-based" => "pairwise bonds only (in-plane lambda = mu: nu = 1/4 plane strain, 1/3 plane stress)",
        /// Bonds plus the dilatation term of [`super::dilatation`]: any `nu`.
        Linear = "lps" => "the linear peridynamic solid: bonds plus a dilatation term, any nu",
    }
}

choice! {
    /// How traction and free edges are treated (`peridynamics.boundary`).
    pub enum EdgeTreatment("peridynamics.boundary", default Some(EdgeTreatment::Fictitious), serde "kebab-case") {
        /// Fictitious nodes beyond traction and free edges, their displacements extended
        /// from the solid by a cubic fit that meets the local traction condition
        /// ([`super::extension`]): every family is complete, and the run converges to the
        /// Navier solution at second order in delta.
        Fictitious = "fictitious" => "fictitious nodes beyond traction and free edges, extended from the solid under the local traction condition (static runs)",
        /// The nonlocal model's own free surface: truncated families, tractions as a body
        /// force in the first cell layer ([`super::loads`]); the surface effect converges at
        /// first order in delta.
        Surface = "surface" => "truncated families at free edges, tractions as a layer body force (the nonlocal surface)",
    }
}

/// The `[peridynamics]` table of a scene, validated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PdParams {
    /// Horizon delta (m).
    pub horizon: f64,
    /// Ratio `m = delta / h`; `h` is the cell size.
    pub ratio: f64,
    /// Micromodulus shape.
    pub kernel: Kernel,
    /// Quadrature rule (and node layout).
    pub quadrature: Quadrature,
    /// Surface correction.
    pub correction: SurfaceCorrection,
    /// Linear solver of the static system (`[peridynamics.solver]`).
    pub solver: crate::linalg::SolverParams,
    /// Bond force law.
    pub force: BondForce,
    /// Constitutive model (bond-based or the linear peridynamic solid, never `Auto`).
    pub solid: Solid,
    /// Treatment of traction and free edges.
    pub boundary: EdgeTreatment,
    /// Bonds that break and pre-cracks (`[peridynamics.fracture]`, [`super::fracture`]).
    pub fracture: Option<super::fracture::Fracture>,
    /// A perturbed lattice: every point moved by a uniform offset of up to
    /// `perturbation h / 2` per coordinate, weights kept (0: the rule's lattice).
    pub perturbation: f64,
    /// The cells the rule integrates: a lattice of squares or a Delaunay triangulation.
    pub points: PointSet,
    /// Cut-cell weights on the lattice: a cell cut by the boundary gives its points inside
    /// the solid its area inside, and its points outside (collar) the area outside
    /// ([`super::triangulated::cut_cell`]); `false`: full weights.
    pub cut_cells: bool,
}

choice! {
    /// The cells a quadrature rule integrates (`peridynamics.points`).
    pub enum PointSet("peridynamics.points", default Some(PointSet::Lattice), serde "lowercase") {
        /// Square cells of side `h = delta / m` aligned with the solid's bounding box
        /// (split in two triangles for the triangle rules).
        Lattice = "lattice" => "square cells of side h = delta / m (each split in two triangles for the triangle rules)",
        /// A Delaunay triangulation of the solid's boundary-conforming scattered nodes at
        /// spacing `h` ([`super::triangulated`]); triangle rules only.
        Delaunay = "delaunay" => "a Delaunay triangulation of boundary-conforming scattered nodes at spacing h (triangle rules)",
    }
}

choice! {
    /// Bond force law.
    pub enum BondForce("peridynamics.force", default Some(BondForce::Linear), serde "kebab-case") {
        /// `f = c_ij (xi ⊗ xi) eta` (seed 000, eq. 4.1.3).
        Linear = "linear" => "f = c (xi ⊗ xi) eta (the linear model; static and dynamic runs)",
        /// `f = c_ij |xi|^3 s (xi + eta)/|xi + eta|`, `s = (|xi + eta| - |xi|)/|xi|` (seed 000,
        /// definition 4.1.1); its linearisation is the linear law. Dynamics only.
        BondStretch = "bond-stretch" => "f = c |xi|^3 s (xi + eta)/|xi + eta| (nonlinear; dynamics only)",
    }
}

impl PdParams {
    /// Cell size `h = delta / m`.
    pub fn spacing(&self) -> f64 {
        self.horizon / self.ratio
    }

    /// Whether the dilatation term of the linear peridynamic solid is on.
    pub fn has_dilatation(&self) -> bool {
        self.solid == Solid::Linear
    }

    /// Whether traction and free edges get fictitious nodes ([`super::extension`]).
    pub fn has_fictitious_nodes(&self) -> bool {
        self.boundary == EdgeTreatment::Fictitious
    }

    /// Width of the Dirichlet collar outside displacement parts (and of the band of
    /// fictitious nodes outside traction parts): `delta + 0.75 h`
    /// (the extra `0.75 h` covers the cells the partial-area rule counts beyond
    /// `delta`), and one more `delta` for the linear peridynamic solid, whose
    /// dilatation at a collar node next to the solid reads the collar's own family.
    pub fn collar_width(&self) -> f64 {
        let reach = if self.has_dilatation() { 2.0 } else { 1.0 };
        reach * self.horizon + 0.75 * self.spacing()
    }

    /// Nodes per cell of the rule.
    pub fn nodes_per_cell(&self) -> usize {
        self.quadrature.unit_cell().len()
    }
}

#[cfg(test)]
mod tests {
    use super::Quadrature;
    use crate::scene::choice::Choice;

    /// Every triangle rule integrates the monomials `x^a y^b` on the reference triangle
    /// exactly up to its degree (`a! b! / (a + b + 2)!`) and not one degree further
    /// (seed 000, sec. 1.1.3: types 1 and 5 are P1, 2 and 4 P2, 3 and 6 P3). Round-off of
    /// a handful of products: 1e-15.
    #[test]
    fn triangle_rules_have_their_degree() {
        let factorial = |n: i32| (1..=n).map(f64::from).product::<f64>();
        let degree = [
            (Quadrature::TriangleVertex, 1),
            (Quadrature::TriangleEdge, 2),
            (Quadrature::TriangleP3, 3),
            (Quadrature::TriangleP2, 2),
            (Quadrature::TriangleP1, 1),
            (Quadrature::TriangleHillion, 3),
        ];
        for (q, d) in degree {
            let rule = q.triangle_rule().unwrap();
            let error = |a: i32, b: i32| {
                let exact = factorial(a) * factorial(b) / factorial(a + b + 2);
                let sum: f64 = rule.iter().map(|(p, w)| 0.5 * w * p[0].powi(a) * p[1].powi(b)).sum();
                (sum - exact).abs()
            };
            for a in 0..=d {
                for b in 0..=d - a {
                    assert!(error(a, b) < 1e-15, "{} on x^{a} y^{b}", q.name());
                }
            }
            let next = (0..=d + 1).map(|a| error(a, d + 1 - a)).fold(0.0, f64::max);
            assert!(next > 1e-6, "{} is exact beyond degree {d}", q.name());
        }
    }

    /// A cell's contributions and its periodic unit both carry the whole cell area; the
    /// seven-point rule's unit is the vertex 6 x 3/120, three edge midpoints 2 x 8/120 and
    /// the two centroids 27/120.
    #[test]
    fn cells_carry_their_area() {
        for &(q, _, _) in Quadrature::VALUES {
            let total: f64 = q.cell_contributions().iter().map(|c| c.1).sum();
            let unit: f64 = q.unit_cell().iter().map(|c| c.1).sum();
            assert!((total - 1.0).abs() < 1e-14 && (unit - 1.0).abs() < 1e-14, "{}: {total} {unit}", q.name());
        }
        let mut p3: Vec<f64> = Quadrature::TriangleP3.unit_cell().iter().map(|c| c.1).collect();
        p3.sort_by(f64::total_cmp);
        let expected = [16.0 / 120.0, 16.0 / 120.0, 16.0 / 120.0, 18.0 / 120.0, 27.0 / 120.0, 27.0 / 120.0];
        assert!(p3.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-15), "{p3:?}");
        assert_eq!(Quadrature::TriangleVertex.unit_cell().len(), 1);
        assert_eq!(Quadrature::TriangleEdge.unit_cell().len(), 3);
        assert_eq!(Quadrature::TriangleHillion.unit_cell().len(), 8);
    }
}
