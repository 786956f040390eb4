//! The Pareto front of (cost, error) points.
//!
//! A point is on the front when no other point is at most as costly and at most as
//! wrong while strictly better in one of the two: the configurations worth choosing.

/// Indices of the points of `points` = `(cost, error)` on the Pareto front (both to be
/// minimised), sorted by cost. Points with a coordinate that is not a positive finite
/// number are never on it; of two identical points only the first is.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let mut order: Vec<usize> = (0..points.len()).filter(|&i| ok(points[i].0) && ok(points[i].1)).collect();
    // By cost, then error, then index: a sweep keeps each point that beats every
    // cheaper (or equally cheap and earlier) one.
    order.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1)).then(a.cmp(&b)));
    let mut best = f64::INFINITY;
    let mut front = Vec::new();
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// Whether `a` dominates `b`: at most as costly and as wrong, strictly better in one.
pub fn dominates(a: (f64, f64), b: (f64, f64)) -> bool {
    a.0 <= b.0 && a.1 <= b.1 && (a.0 < b.0 || a.1 < b.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point off the front is dominated by a front point; no front point is
    /// dominated by any point (checked by brute force on a table).
    fn check(points: &[(f64, f64)]) {
        let front = pareto_front(points);
        let valid = |p: (f64, f64)| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite();
        for (i, &p) in points.iter().enumerate() {
            let on = front.contains(&i);
            let dominated = points.iter().any(|&q| valid(q) && dominates(q, p));
            if valid(p) {
                let duplicate_of_earlier = points[..i].contains(&p);
                assert_eq!(on, !dominated && !duplicate_of_earlier, "point {i} {p:?}");
            } else {
                assert!(!on);
            }
        }
        assert!(front.windows(2).all(|w| points[w[0]].0 <= points[w[1]].0 && points[w[0]].1 > points[w[1]].1));
    }

    #[test]
    fn synthetic_table() {
        // seconds, error: three families crossing over, a tie, a duplicate, bad values.
        let points = [
            (0.05, 2e-2), // cheapest: on
            (0.10, 5e-3), // on
            (0.10, 8e-3), // same cost, worse: off
            (0.30, 6e-3), // dominated by (0.10, 5e-3)
            (0.40, 1e-4), // on
            (0.40, 1e-4), // duplicate: only the first
            (1.20, 2e-4), // dominated
            (2.00, 3e-6), // on
            (5.00, 3e-6), // same error, costlier: off
            (f64::NAN, 1e-9),
            (3.0, 0.0),
            (-1.0, 1e-9),
        ];
        assert_eq!(pareto_front(&points), vec![0, 1, 4, 7]);
        check(&points);
    }

    #[test]
    fn random_tables_match_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200 {
            let n = rng.random_range(0..30);
            // Coarse values so that ties occur.
            let points: Vec<(f64, f64)> =
                (0..n).map(|_| (rng.random_range(1..10) as f64 * 0.1, 10f64.powi(-rng.random_range(0..6)))).collect();
            check(&points);
        }
    }
}
