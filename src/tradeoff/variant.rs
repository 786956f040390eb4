//! A configuration of the sweep as a scene file: the scene's own text with the
//! approximation, solver and node spacing replaced, so that every configuration run is
//! a complete scene a user can run again, and its changes a snippet they can paste.

use crate::scene::problem::preset::significant;
use crate::scene::problem::{Problem, ProblemError};
use std::path::Path;
use toml::{Table, Value};

/// The approximation and solver of a family of configurations; `None` keeps the
/// scene's own.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// `approximation.basis` (`"monomials"`, `"phs"`).
    pub basis: &'static str,
    /// `approximation.degree`.
    pub degree: u32,
    /// `approximation.support`; `None` for the basis's default.
    pub support: Option<usize>,
    /// `solver.kind`; `None` for the scene's.
    pub solver: Option<&'static str>,
}

/// Dotted-key changes to a scene (`("nodes.spacing", 0.04)`), in order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Edits(pub Vec<(String, Value)>);

impl Edits {
    /// The changes that make the scene `p` use `setting` (the approximation table is
    /// replaced, its `formulation`, `ghost_nodes` and `pressure_stabilisation` kept) and the spacing function
    /// scaled to the far-field spacing `h` (a graded refinement scaled with it).
    pub fn of(p: &Problem, setting: Option<&Setting>, h: f64) -> Result<Edits, ProblemError> {
        let mut edits = Vec::new();
        let fill = p.with_spacing(h)?.navier.fill;
        edits.push(("nodes.spacing".to_string(), Value::Float(fill.spacing)));
        if let Some(r) = &fill.refine {
            edits.push(("nodes.refine.spacing".to_string(), Value::Float(significant(r.spacing, 4))));
            edits.push(("nodes.refine.growth".to_string(), Value::Float(significant(r.growth, 4))));
        }
        if let Some(s) = setting {
            edits.push(("approximation.basis".into(), Value::String(s.basis.into())));
            edits.push(("approximation.degree".into(), Value::Integer(s.degree.into())));
            if let Some(n) = s.support {
                edits.push(("approximation.support".into(), Value::Integer(n as i64)));
            }
            if let Some(kind) = s.solver {
                edits.push(("solver.kind".into(), Value::String(kind.into())));
            }
        }
        Ok(Edits(edits))
    }

    /// `text` (a scene) with these changes; a changed basis drops the approximation
    /// keys of the old one (weight, shape, exponent, support).
    pub fn apply(&self, text: &str, path: &Path) -> Result<String, ProblemError> {
        let bad = |reason: String| ProblemError { file: path.to_path_buf(), field: "(file)".into(), reason, kind: crate::scene::problem::ProblemErrorKind::Invalid };
        let mut scene: Table = text.parse().map_err(|e: toml::de::Error| bad(e.message().to_string()))?;
        // The configuration is explicit: a preset of the scene would override it.
        scene.remove("preset");
        if self.0.iter().any(|(k, _)| k == "approximation.basis") {
            if let Some(Value::Table(a)) = scene.get_mut("approximation") {
                a.retain(|k, _| ["formulation", "ghost_nodes", "pressure_stabilisation"].contains(&k));
            }
        }
        for (key, value) in &self.0 {
            set(&mut scene, key, value.clone());
        }
        toml::to_string(&scene).map_err(|e| bad(e.to_string()))
    }

    /// The changes as a scene snippet (TOML tables).
    pub fn snippet(&self) -> String {
        let mut t = Table::new();
        for (key, value) in &self.0 {
            set(&mut t, key, value.clone());
        }
        toml::to_string(&t).unwrap_or_default()
    }
}

/// Set the dotted `key` of `t`, creating tables on the way.
fn set(t: &mut Table, key: &str, value: Value) {
    match key.split_once('.') {
        None => {
            t.insert(key.into(), value);
        }
        Some((head, rest)) => {
            let entry = t.entry(head.to_string()).or_insert_with(|| Value::Table(Table::new()));
            if !entry.is_table() {
                *entry = Value::Table(Table::new());
            }
            if let Value::Table(inner) = entry {
                set(inner, rest, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_replace_the_approximation_and_keep_the_rest() {
        let text = "name = \"x\"\n[approximation]\nbasis = \"monomials\"\nweight = \"gaussian\"\nsigma = 1.0\nformulation = \"auto\"\n[nodes]\nspacing = 0.1\n";
        let edits = Edits(vec![
            ("nodes.spacing".into(), Value::Float(0.05)),
            ("approximation.basis".into(), Value::String("phs".into())),
            ("approximation.degree".into(), Value::Integer(4)),
            ("solver.kind".into(), Value::String("gmres".into())),
        ]);
        let out: Table = edits.apply(text, Path::new("s.toml")).unwrap().parse().unwrap();
        let a = out["approximation"].as_table().unwrap();
        assert_eq!(a.keys().collect::<Vec<_>>(), ["basis", "degree", "formulation"]);
        assert_eq!(out["nodes"]["spacing"].as_float(), Some(0.05));
        assert_eq!(out["solver"]["kind"].as_str(), Some("gmres"));
        assert_eq!(out["name"].as_str(), Some("x"));
        let snippet = edits.snippet();
        assert!(
            snippet.contains("[nodes]\nspacing = 0.05") && snippet.contains("[approximation]\nbasis = \"phs\"\ndegree = 4"),
            "{snippet}"
        );
    }
}
