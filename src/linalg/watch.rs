//! Who watches an iterative solve while it runs (the terminal's progress of the solve
//! stage, with its ETA): after each iteration it is told the relative residual reached
//! and the one the tolerance asks for. Krylov methods gain digits of the residual at a
//! roughly steady rate, so the digits gained are a measure of the work done.

/// Told the progress of an iterative solve.
pub trait Watch {
    /// After an iteration: the relative residual `reached` (GMRES: its estimate within
    /// a cycle) and the tolerance `target`.
    fn residual(&self, reached: f64, target: f64);
}

/// Nobody watching.
impl Watch for () {
    fn residual(&self, _: f64, _: f64) {}
}

/// The progress of a solve from 1 down to `target` in digits of the residual: `(done,
/// total)` with `done = floor(log10(1 / reached))`, clamped to `0..=total`, and
/// `total = ceil(log10(1 / target))`. `None` when the target is not below 1.
pub fn digits_gained(reached: f64, target: f64) -> Option<(u64, u64)> {
    if !(target > 0.0 && target < 1.0) {
        return None;
    }
    let total = (-target.log10()).ceil();
    let done = if reached.is_finite() && reached > 0.0 { (-reached.log10()).clamp(0.0, total) } else { 0.0 };
    Some((done.floor() as u64, total as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_count_from_one_to_the_target() {
        assert_eq!(digits_gained(1.0, 1e-10), Some((0, 10)));
        assert_eq!(digits_gained(3e-6, 1e-10), Some((5, 10)));
        assert_eq!(digits_gained(1e-12, 1e-10), Some((10, 10)), "past the target counts as done");
        assert_eq!(digits_gained(3.0, 1e-10), Some((0, 10)), "a residual above 1 has gained nothing");
        assert_eq!(digits_gained(f64::NAN, 1e-10), Some((0, 10)));
        assert_eq!(digits_gained(1e-3, 5e-9), Some((3, 9)));
        assert_eq!(digits_gained(0.5, 1.0), None);
    }
}
