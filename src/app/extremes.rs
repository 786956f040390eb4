//! The largest displacement and von Mises stress of a run and where they are: the key
//! `extremes` of `summary.json` and one line of `mlsm run`'s terminal summary.

use super::number::{plain, point};
use serde::Serialize;

/// The largest `|u|` (m) and von Mises stress (Pa) at the nodes, with their nodes'
/// positions; the stress only when the run computed one (not in a dynamic run).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(super) struct Extremes {
    /// Largest displacement magnitude `|u| = sqrt(ux^2 + uy^2)` (m).
    pub max_displacement_m: f64,
    /// The node where it is (m).
    pub max_displacement_at: [f64; 2],
    /// Largest von Mises stress (Pa; with `sigma_zz` in plane strain).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_von_mises_pa: Option<f64>,
    /// The node where it is (m).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_von_mises_at: Option<[f64; 2]>,
    /// The time of the state (s): a dynamic run's final state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f64>,
}

/// The index and value of the largest of `values` (the first of equal ones; NaN
/// never wins), `None` when there is none.
fn largest(values: impl Iterator<Item = f64>) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (i, v) in values.enumerate() {
        if !v.is_nan() && best.is_none_or(|(_, b)| v > b) {
            best = Some((i, v));
        }
    }
    best
}

impl Extremes {
    /// The extremes of `displacement` (and `von_mises`) at the nodes `positions`;
    /// `None` without nodes.
    pub(super) fn of(positions: &[[f64; 2]], displacement: &[[f64; 2]], von_mises: Option<&[f64]>) -> Option<Self> {
        let (i, u) = largest(displacement.iter().take(positions.len()).map(|u| u[0].hypot(u[1])))?;
        let stress = von_mises.and_then(|s| largest(s.iter().take(positions.len()).copied()));
        Some(Extremes {
            max_displacement_m: u,
            max_displacement_at: positions[i],
            max_von_mises_pa: stress.map(|(_, s)| s),
            max_von_mises_at: stress.map(|(j, _)| positions[j]),
            time_s: None,
        })
    }

    /// The same extremes, of the state at time `t` (s).
    pub(super) fn at_time(self, t: f64) -> Self {
        Extremes { time_s: Some(t), ..self }
    }

    /// One terminal line: `largest |u| 1.234e-4 m at (0.3, 0.05); largest von Mises
    /// stress 1.200e8 Pa at (0, 0.5)` (with the time of a dynamic run's state).
    pub(super) fn line(&self) -> String {
        let mut line = String::from("largest");
        if let Some(t) = self.time_s {
            line.push_str(&format!(" at t = {} s", plain(t)));
        }
        line.push_str(&format!(": |u| {:.3e} m at {}", self.max_displacement_m, point(self.max_displacement_at)));
        match (self.max_von_mises_pa, self.max_von_mises_at) {
            (Some(s), Some(at)) => line.push_str(&format!("; von Mises stress {s:.3e} Pa at {}", point(at))),
            _ if self.time_s.is_some() => line.push_str("; (no stress in a dynamic run)"),
            _ => line.push_str("; (no stress computed: output.fields asks for none)"),
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extremes_name_the_largest_values_and_their_nodes() {
        let x = [[0.0, 0.0], [0.3, 0.05], [1.0, 0.5]];
        let u = [[0.0, 0.0], [3e-4, -4e-4], [1e-4, 0.0]];
        let vm = [2e8, f64::NAN, 1.5e8];
        let e = Extremes::of(&x, &u, Some(&vm)).unwrap();
        assert_eq!((e.max_displacement_m, e.max_displacement_at), (5e-4, [0.3, 0.05]));
        assert_eq!((e.max_von_mises_pa, e.max_von_mises_at), (Some(2e8), Some([0.0, 0.0])));
        assert_eq!(e.line(), "largest: |u| 5.000e-4 m at (0.3, 0.05); von Mises stress 2.000e8 Pa at (0, 0)");
        let json = serde_json::to_value(e).unwrap();
        assert_eq!(json["max_displacement_m"], 5e-4);
        assert_eq!(json["max_von_mises_at"], serde_json::json!([0.0, 0.0]));
        assert!(json.get("time_s").is_none());
        // A dynamic run's final state has no stress.
        let d = Extremes::of(&x, &u, None).unwrap().at_time(1e-3);
        assert_eq!(d.line(), "largest at t = 0.001 s: |u| 5.000e-4 m at (0.3, 0.05); (no stress in a dynamic run)");
        let json = serde_json::to_value(d).unwrap();
        assert!(json.get("max_von_mises_pa").is_none() && json["time_s"] == 1e-3);
        assert_eq!(Extremes::of(&[], &[], None), None);
    }
}
