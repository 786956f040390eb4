//! Imposing the balances on the assembled system: each balance's three rows and the
//! injected rows' shares of its three multipliers become the border of the system,
//! `[A G; C 0]` (`linalg::border`), which every solver takes as it stands (module
//! docs of [`super`]).

use super::SectorBalance;
use crate::linalg::border::Border;

/// The border of `balances`: per balance, the columns of `G` (force x, force y and
/// couple multipliers in the injected rows), the rows of `C` (force x, force y and
/// moment of the arc's tractions) and their right-hand sides `d` (minus the loads
/// inside the contour).
pub fn border(balances: &[SectorBalance]) -> Border {
    let mut border = Border::default();
    for b in balances {
        for m in 0..3 {
            border.columns.push(b.injected.iter().map(|&(row, g)| (row, g[m])).collect());
            border.rows.push(b.rows[m].clone());
            border.values.push(b.loads[m]);
        }
    }
    border
}

/// Whether the injection `g` (one column per multiplier) has rank three, by Gaussian
/// elimination with partial pivoting (a pivot below `1e-8` of its largest entry counts
/// as zero). Below three the bordered system would be singular, and the balance is
/// refused and named as unbalanced.
pub(super) fn has_rank_three(injected: &[(usize, [f64; 3])]) -> bool {
    let mut g: Vec<[f64; 3]> = injected.iter().map(|(_, g)| *g).collect();
    let largest = g.iter().flat_map(|r| r.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let mut pivots = [usize::MAX; 3];
    for k in 0..3 {
        let (p, v) =
            (0..g.len())
                .filter(|a| !pivots.contains(a))
                .map(|a| (a, g[a][k].abs()))
                .fold((usize::MAX, 0.0), |m, x| if x.1 > m.1 { x } else { m });
        if p == usize::MAX || v <= 1e-8 * largest {
            return false;
        }
        pivots[k] = p;
        let pivot = g[p];
        for (a, row) in g.iter_mut().enumerate() {
            if !pivots.contains(&a) {
                let f = row[k] / pivot[k];
                for j in k..3 {
                    row[j] -= f * pivot[j];
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::navier::sector::Around;

    /// The border holds each balance's rows and the injected rows' shares in the
    /// order force x, force y, moment.
    #[test]
    fn the_border_holds_three_multipliers_per_balance() {
        let rows: [Vec<(usize, f64)>; 3] = std::array::from_fn(|k| vec![(k, 1.0 + k as f64), (7, -1.0)]);
        let injected = vec![(3, [1.0, 2.0, 3.0]), (5, [4.0, 5.0, 6.0])];
        let loads = [0.5, -0.25, 2.0];
        let balance = SectorBalance { around: Around::Corner, centre: [0.0, 0.0], radius: 1.0, rows: rows.clone(), loads, injected };
        let border = border(&[balance.clone(), balance]);
        assert_eq!(border.len(), 6);
        assert_eq!(border.columns[1], vec![(3, 2.0), (5, 5.0)]);
        assert_eq!(border.columns[5], vec![(3, 3.0), (5, 6.0)]);
        assert_eq!(border.rows[2], rows[2]);
        assert_eq!(border.rows[3], rows[0]);
        assert_eq!(border.values, vec![0.5, -0.25, 2.0, 0.5, -0.25, 2.0]);
    }

    /// Injections that cannot carry three independent multipliers are refused.
    #[test]
    fn a_rank_deficient_injection_is_refused() {
        assert!(!has_rank_three(&[(0, [1.0, 0.0, 0.0]), (1, [2.0, 0.0, 0.0]), (2, [0.0, 1.0, 0.0])]));
        assert!(has_rank_three(&[(0, [1.0, 0.0, 0.5]), (1, [0.0, 1.0, 0.0]), (2, [0.0, 1.0, 1.0])]));
    }
}
