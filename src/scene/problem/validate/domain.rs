//! `[[domain.region]]`: rectangles, discs and polygons combined by CSG, and the
//! names of their edges (the boundary parts conditions refer to).

use super::Ctx;
use crate::domain::{CsgOp, Domain, Primitive, PrimitiveKind, Region};
use crate::scene::problem::spec::{DomainSpec, RectangleNames, RegionSpec};
use crate::scene::problem::ProblemError;

/// `[[domain.region]]`: primitives combined left to right, with named boundary parts.
pub(super) fn domain(c: &Ctx, spec: &DomainSpec) -> Result<Domain, ProblemError> {
    if spec.region.is_empty() {
        return c.err("domain.region", "at least one region is needed");
    }
    let mut parts: Vec<String> = Vec::new();
    let mut regions = Vec::new();
    for (k, r) in spec.region.iter().enumerate() {
        let at = RegionAt { c, k, r };
        let op: CsgOp = c.choose(&at.field("op"), r.op.as_deref())?;
        if k == 0 && op != CsgOp::Union {
            return c.err(at.field("op"), "the first region must add material (op = \"union\" or no op)");
        }
        let (primitive, names) = match c.choose(&at.field("shape"), Some(&r.shape))? {
            PrimitiveKind::Rectangle => at.rectangle()?,
            PrimitiveKind::Disc => at.disc(op)?,
            PrimitiveKind::Polygon => at.polygon()?,
        };
        let edge_parts = names.iter().map(|name| part_id(&mut parts, name)).collect();
        regions.push(Region { primitive, op, edge_parts });
    }
    let domain = Domain { regions, parts };
    let (lo, hi) = domain.bounding_box();
    if !(hi[0] > lo[0] && hi[1] > lo[1]) || domain.area_estimate(400) <= 0.0 {
        return c.err("domain.region", "the regions leave no material (empty intersection or everything subtracted)");
    }
    Ok(domain)
}

/// Index of the boundary part `name`, added if new.
fn part_id(parts: &mut Vec<String>, name: &str) -> usize {
    match parts.iter().position(|p| p == name) {
        Some(i) => i,
        None => {
            parts.push(name.to_string());
            parts.len() - 1
        }
    }
}

/// Region `k` of the scene, being validated.
struct RegionAt<'a> {
    c: &'a Ctx<'a>,
    k: usize,
    r: &'a RegionSpec,
}

impl RegionAt<'_> {
    fn field(&self, s: &str) -> String {
        format!("domain.region[{}].{s}", self.k)
    }

    /// Refuse `field` when it is given: it belongs to another shape.
    fn unused(&self, field: &str, present: bool, shape: &str) -> Result<(), ProblemError> {
        if present {
            self.c.err(self.field(field), format!("not used by a {shape}; remove it"))
        } else {
            Ok(())
        }
    }

    /// `min`, `max`, and the names of the bottom, right, top and left edges.
    fn rectangle(&self) -> Result<(Primitive, Vec<String>), ProblemError> {
        let (c, r) = (self.c, self.r);
        self.unused("center", r.center.is_some(), "rectangle")?;
        self.unused("radius", r.radius.is_some(), "rectangle")?;
        self.unused("vertices", r.vertices.is_some(), "rectangle")?;
        self.unused("name", r.name.is_some(), "rectangle (use names = { left = \"...\" })")?;
        self.unused("edge_names", r.edge_names.is_some(), "rectangle (use names)")?;
        let min = c.need(&self.field("min"), r.min, "a rectangle needs min = [x, y]")?.0;
        let max = c.need(&self.field("max"), r.max, "a rectangle needs max = [x, y]")?.0;
        c.finite(&self.field("min"), &min)?;
        c.finite(&self.field("max"), &max)?;
        if !(max[0] > min[0] && max[1] > min[1]) {
            return c.err(self.field("max"), format!("must exceed min in both coordinates (min = {min:?}, max = {max:?})"));
        }
        let d = RectangleNames::default();
        let n = r.names.as_ref().unwrap_or(&d);
        let names = [("bottom", &n.bottom), ("right", &n.right), ("top", &n.top), ("left", &n.left)]
            .iter()
            .map(|(def, given)| given.as_deref().unwrap_or(def).to_string())
            .collect();
        Ok((Primitive::Rectangle { min, max }, names))
    }

    /// `center`, `radius`, and the name of its edge.
    fn disc(&self, op: CsgOp) -> Result<(Primitive, Vec<String>), ProblemError> {
        let (c, r) = (self.c, self.r);
        self.unused("min", r.min.is_some(), "disc")?;
        self.unused("max", r.max.is_some(), "disc")?;
        self.unused("vertices", r.vertices.is_some(), "disc")?;
        self.unused("names", r.names.is_some(), "disc (use name)")?;
        self.unused("edge_names", r.edge_names.is_some(), "disc (use name)")?;
        let center = c.need(&self.field("center"), r.center, "a disc needs center = [x, y]")?.0;
        c.finite(&self.field("center"), &center)?;
        let radius = c.positive(&self.field("radius"), c.need(&self.field("radius"), r.radius, "a disc needs radius")?)?;
        let name = r.name.clone().unwrap_or_else(|| if op == CsgOp::Subtract { "hole".into() } else { "rim".into() });
        Ok((Primitive::Disc { center, radius }, vec![name]))
    }

    /// `vertices` (oriented counter-clockwise here) and the names of its edges.
    fn polygon(&self) -> Result<(Primitive, Vec<String>), ProblemError> {
        let (c, r) = (self.c, self.r);
        self.unused("min", r.min.is_some(), "polygon")?;
        self.unused("max", r.max.is_some(), "polygon")?;
        self.unused("center", r.center.is_some(), "polygon")?;
        self.unused("radius", r.radius.is_some(), "polygon")?;
        self.unused("names", r.names.is_some(), "polygon (use edge_names)")?;
        self.unused("name", r.name.is_some(), "polygon (use edge_names)")?;
        let mut v: Vec<[f64; 2]> = r.vertices.iter().flatten().map(|p| p.0).collect();
        if v.len() < 3 {
            return c.err(self.field("vertices"), format!("a polygon needs at least 3 vertices, got {}", v.len()));
        }
        for p in &v {
            c.finite(&self.field("vertices"), p)?;
        }
        let mut names: Vec<String> = match &r.edge_names {
            Some(n) if n.len() != v.len() => {
                return c.err(self.field("edge_names"), format!("{} names for {} edges (edge k joins vertex k to k+1)", n.len(), v.len()))
            }
            Some(n) => n.clone(),
            None => (0..v.len()).map(|i| format!("edge{i}")).collect(),
        };
        let area2: f64 = (0..v.len())
            .map(|i| {
                let (a, b) = (v[i], v[(i + 1) % v.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        if area2.abs() <= 1e-14 * polygon_scale(&v).powi(2) {
            return c.err(self.field("vertices"), "the polygon has zero area");
        }
        if let Some((i, j)) = self_intersection(&v) {
            return c.err(self.field("vertices"), format!("edges {i} and {j} cross: the polygon must be simple"));
        }
        if area2 < 0.0 {
            // Clockwise: reverse, keeping each edge's name with the same geometric edge.
            v.reverse();
            let n = names.len();
            names = (0..n).map(|k| names[(2 * n - 2 - k) % n].clone()).collect();
        }
        Ok((Primitive::Polygon { vertices: v }, names))
    }
}

fn polygon_scale(v: &[[f64; 2]]) -> f64 {
    v.iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0, f64::max).max(1e-300)
}

/// First pair of non-adjacent polygon edges that intersect.
fn self_intersection(v: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = v.len();
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    for i in 0..n {
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (a, b, p, q) = (v[i], v[(i + 1) % n], v[j], v[(j + 1) % n]);
            let (d1, d2) = (cross(a, b, p), cross(a, b, q));
            let (d3, d4) = (cross(p, q, a), cross(p, q, b));
            // Collinear edges (an edge split in parts, e.g. to name a support) cross
            // only where they overlap.
            let collinear = d1 == 0.0 && d2 == 0.0;
            let overlap = |k: usize| a[k].min(b[k]) <= p[k].max(q[k]) && p[k].min(q[k]) <= a[k].max(b[k]);
            if (collinear && overlap(0) && overlap(1)) || (!collinear && d1 * d2 <= 0.0 && d3 * d4 <= 0.0) {
                return Some((i, j));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::self_intersection;

    /// An edge split into collinear parts (a support named on a beam's bottom edge) is
    /// simple; a bow tie and an edge that doubles back over another are not.
    #[test]
    fn split_edges_are_simple_and_crossings_are_not() {
        let split = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [5.0, 0.0], [5.0, 1.0], [0.0, 1.0]];
        assert_eq!(self_intersection(&split), None);
        let bow_tie = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(self_intersection(&bow_tie).is_some());
        let doubled = [[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [2.0, 1.0], [2.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]];
        assert!(self_intersection(&doubled).is_some());
    }
}
