//! `[[probe]]`: named point values. A name is a word (it becomes a column of
//! `convergence.csv`) and unique; the point lies on or inside the solid (a point
//! outside would be an extrapolation, not a reading); a stress probe makes the run
//! compute the stress (both models have one: MLSM derivatives, the nonlocal gradient).

use super::Ctx;
use crate::physics::case::Outputs;
use crate::domain::Domain;
use crate::quality::post::probe::Probe;
use crate::scene::problem::spec::ProbeSpec;

/// The probes of the scene; requests the stress a stress probe reads.
pub(super) fn probes(c: &Ctx, specs: &[ProbeSpec], domain: &Domain, outputs: &mut Outputs) -> Result<Vec<Probe>, super::ProblemError> {
    let (lo, hi) = domain.bounding_box();
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mut out: Vec<Probe> = Vec::with_capacity(specs.len());
    for (k, s) in specs.iter().enumerate() {
        let field = |f: &str| format!("probe[{k}].{f}");
        let name = c.need(&field("name"), s.name.clone(), "a name for the probe (letters, digits, _ or -)")?;
        if name.is_empty() || !name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '-') {
            return c.err(field("name"), format!("\"{name}\": use letters, digits, _ or - (the name heads a CSV column)"));
        }
        if out.iter().any(|p| p.name == name) {
            return c.err(field("name"), format!("\"{name}\" names two probes"));
        }
        let at = c.need(&field("at"), s.at, "the point [x, y]")?.0;
        c.finite(&field("at"), &at)?;
        // On the boundary counts as inside: the signed distance of a boundary point is
        // zero up to the round-off of the geometry, relative to its size.
        let d = domain.signed_distance(at);
        if d > 1e-9 * size {
            return c.err(field("at"), format!("[{}, {}] lies outside the solid (at distance {d:.3e})", at[0], at[1]));
        }
        let quantity = c.choose(&field("quantity"), s.quantity.as_deref())?;
        let probe = Probe { name, at, quantity };
        outputs.stress_at_probes |= probe.quantity.is_stress();
        out.push(probe);
    }
    Ok(out)
}
