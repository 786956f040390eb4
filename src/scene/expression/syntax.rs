//! The syntax checks exmex does not make, in the words of a scene author: token
//! scanning, refusal of ambiguous constructs, number literals with exponents, and
//! exmex's own syntax errors reworded.

use super::{FUNCTIONS, MAX_LENGTH, MAX_NESTING};
use exmex::MatchLiteral;

/// A token of an expression, for the checks exmex does not make.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Token<'a> {
    Number,
    Name(&'a str),
    Operator(u8),
    Open,
    Close,
}

/// Split `text` into tokens (numbers with exponents such as `1.5e-3`, names,
/// operators, parentheses); other characters are left to exmex's error.
fn tokens(text: &str) -> Vec<Token<'_>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_digit() || c == b'.' {
            let start = i;
            i += NumberLiteral::is_literal(&text[i..]).map_or(1, str::len).max(1);
            debug_assert!(i > start);
            out.push(Token::Number);
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push(Token::Name(&text[start..i]));
        } else {
            match c {
                b'(' => out.push(Token::Open),
                b')' => out.push(Token::Close),
                b'+' | b'-' | b'*' | b'/' | b'^' => out.push(Token::Operator(c)),
                _ => {}
            }
            i += 1;
        }
    }
    out
}

/// The index after the operand that starts at `i` (a number, a name, a function
/// call, a parenthesised group, or a signed operand).
fn operand_end(t: &[Token], i: usize) -> usize {
    let group_end = |open: usize| {
        let mut depth = 0;
        for (k, tok) in t.iter().enumerate().skip(open) {
            match tok {
                Token::Open => depth += 1,
                Token::Close if depth == 1 => return k + 1,
                Token::Close => depth -= 1,
                _ => {}
            }
        }
        t.len()
    };
    match t.get(i) {
        Some(Token::Name(_)) if t.get(i + 1) == Some(&Token::Open) => group_end(i + 1),
        Some(Token::Open) => group_end(i),
        Some(Token::Operator(b'-' | b'+')) => operand_end(t, i + 1),
        Some(_) => i + 1,
        None => i,
    }
}

/// What exmex would read differently from the usual rules, refused with the fix:
/// unknown functions, a function without parentheses, `E`/`e` (Euler's number or
/// Young's modulus?), a sign before a power (`-x^2` is `(-x)^2` to exmex), and
/// chained powers (`a^b^c` is `(a^b)^c` to exmex).
pub(super) fn check_tokens(text: &str) -> Result<(), String> {
    // exmex parses and differentiates recursively: bound the size and the nesting.
    if text.len() > MAX_LENGTH {
        return Err(format!("{} characters; at most {MAX_LENGTH}", text.len()));
    }
    let t = tokens(text);
    let mut depth = 0usize;
    for tok in &t {
        match tok {
            Token::Open => depth += 1,
            Token::Close => depth = depth.saturating_sub(1),
            _ => {}
        }
        if depth > MAX_NESTING {
            return Err(format!("parentheses nested deeper than {MAX_NESTING}"));
        }
    }
    for (i, tok) in t.iter().enumerate() {
        let operand_position = i == 0 || matches!(t[i - 1], Token::Operator(_) | Token::Open);
        match *tok {
            Token::Name(n) if t.get(i + 1) == Some(&Token::Open) && !FUNCTIONS.contains(&n) => {
                let hint = if n == "pow" { "; write a^b for a power" } else { "" };
                return Err(format!("unknown function \"{n}\" (known: {}){hint}", FUNCTIONS.join(", ")));
            }
            Token::Name(n) if FUNCTIONS.contains(&n) && t.get(i + 1) != Some(&Token::Open) => {
                return Err(format!("write the argument of {n} in parentheses: {n}(...)"));
            }
            Token::Name(n @ ("E" | "e")) => {
                return Err(format!(
                    "\"{n}\" is ambiguous (Euler's number or Young's modulus?); write exp(1), or define a constant with another name"
                ));
            }
            Token::Operator(s @ (b'-' | b'+')) if operand_position => {
                let end = operand_end(&t, i + 1);
                if t.get(end) == Some(&Token::Operator(b'^')) {
                    let s = s as char;
                    return Err(format!("a sign before a power is ambiguous here: write {s}(a^b) or ({s}a)^b"));
                }
            }
            Token::Operator(b'^') => {
                let end = operand_end(&t, i + 1);
                if t.get(end) == Some(&Token::Operator(b'^')) {
                    return Err("chained powers are ambiguous: write (a^b)^c or a^(b^c)".into());
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Numeric literals with decimal exponents (`1.5e-3`, `2E6`, `.5`, `3.`): exmex's
/// default literals have no exponent.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct NumberLiteral;

impl MatchLiteral for NumberLiteral {
    fn is_literal(text: &str) -> Option<&str> {
        let b = text.as_bytes();
        let digits = |mut i: usize| {
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            i
        };
        let int_end = digits(0);
        let mut end = int_end;
        if end < b.len() && b[end] == b'.' {
            end = digits(end + 1);
        }
        // A lone '.' is no number.
        if end == 0 || (int_end == 0 && end == 1) {
            return None;
        }
        if end < b.len() && (b[end] == b'e' || b[end] == b'E') {
            let mut j = end + 1;
            if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                j += 1;
            }
            let k = digits(j);
            if k > j {
                end = k;
            }
        }
        Some(&text[..end])
    }
}

/// exmex's syntax error in the words of a scene author.
pub(super) fn syntax_reason(message: &str) -> String {
    let reason = if message.contains("parentheses mismatch") || message.contains("paren") && message.contains("mismatch") {
        "unbalanced parentheses".to_string()
    } else if message.contains("binary operator cannot be") {
        "two operators in a row".to_string()
    } else if message.contains("ops and") && message.contains("node") {
        "a number or name without an operator before it (write 2*x, not 2x)".to_string()
    } else if message.contains("comma") {
        "functions take one argument; write a^b for powers".to_string()
    } else {
        let short: String = message.chars().take(160).collect();
        format!("cannot parse ({short})")
    };
    format!("syntax error: {reason}")
}
