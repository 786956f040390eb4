//! Numbers as a reader writes them on the terminal: `1`, `0.025`, `8000`, `2.5e-4`
//! (four significant digits, no trailing zeros, no `e0`), and points as `(x, y)`.

/// Significant digits of [`plain`].
const DIGITS: usize = 4;

/// `x` with [`DIGITS`] significant digits, in decimal between 1e-3 and 1e6, else in
/// scientific notation, without trailing zeros: `1`, `0.025`, `8000`, `2.5e-4`, `-3.142`.
pub(super) fn plain(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let magnitude = x.abs();
    if (1e-3..1e6).contains(&magnitude) {
        // Digits after the point that keep DIGITS significant ones.
        let whole = magnitude.log10().floor() as i32 + 1;
        let decimals = (DIGITS as i32 - whole).max(0) as usize;
        let text = format!("{x:.decimals$}");
        // Rounding may carry into a new digit (9.9996 -> 10.000): still no trailing zeros.
        return trim_zeros(&text).to_string();
    }
    let text = format!("{x:.*e}", DIGITS - 1);
    match text.split_once('e') {
        Some((mantissa, exponent)) => format!("{}e{exponent}", trim_zeros(mantissa)),
        None => text,
    }
}

/// `text` without the trailing zeros of its fraction (and without a bare point).
fn trim_zeros(text: &str) -> &str {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        text
    }
}

/// A point as `(x, y)` in [`plain`] numbers.
pub(super) fn point(p: [f64; 2]) -> String {
    format!("({}, {})", plain(p[0]), plain(p[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_numbers_read_as_written() {
        let cases = [
            (1.0, "1"),
            (0.025, "0.025"),
            (2.5e-4, "2.5e-4"),
            (8000.0, "8000"),
            (0.1 / 6.0, "0.01667"),
            (1.0 / 3.0, "0.3333"),
            (-4.56789, "-4.568"),
            (100.0, "100"),
            (2.1e11, "2.1e11"),
            (1e-4, "1e-4"),
            (9.99996, "10"),
            (0.0, "0"),
            (123456.0, "123456"),
        ];
        for (x, want) in cases {
            assert_eq!(plain(x), want, "{x}");
        }
        assert_eq!(point([0.3, -0.05]), "(0.3, -0.05)");
    }
}
