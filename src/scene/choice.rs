//! Options a scene file chooses by name. Every option enum owns, in one table, the
//! scene name and a one-line help of each of its values, and its default; the
//! parser, the error messages ("expected one of ...") and the scene reference
//! (`mlsm options`, problems/README.md) all read that table.
//!
//! An option whose value carries numbers (a basis with its degree, a kernel with its
//! exponent, ...) has a fieldless companion enum (`BasisKind`, `KernelKind`, ...)
//! that implements [`Choice`]; the numbers come from their own scene fields.

/// Define an option enum and its [`Choice`] table together: the scene field, the
/// default (and how it is chosen when it depends on the scene, `note`), the serde
/// renaming when the enum is written to summaries (`serde`), then every variant with
/// its scene name and one-line help (which is also the variant's doc).
///
/// ```text
/// choice! {
///     /// How a region combines with the regions before it.
///     pub enum CsgOp("domain.region[k].op", default Some(CsgOp::Union)) {
///         Union = "union" => "add the region",
///         Subtract = "subtract" => "cut the region out",
///     }
/// }
/// ```
macro_rules! choice {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident ($field:literal, default $default:expr $(, note $note:literal)? $(, serde $serde:literal)?) {
            $( $(#[$vmeta:meta])* $variant:ident = $value:literal => $help:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        $( #[derive(serde::Serialize)] #[serde(rename_all = $serde)] )?
        $vis enum $name {
            $( $(#[$vmeta])* #[doc = $help] $variant ),+
        }

        impl $crate::scene::choice::Choice for $name {
            const FIELD: &'static str = $field;
            const VALUES: &'static [(Self, &'static str, &'static str)] = &[$(($name::$variant, $value, $help)),+];
            const DEFAULT: Option<Self> = $default;
            $( const DEFAULT_NOTE: &'static str = $note; )?
        }
    };
}
pub(crate) use choice;

/// An option enum: its values, their scene names and help, its default.
pub trait Choice: Copy + PartialEq + Sized + 'static {
    /// The scene field that chooses it, as written in the reference (`approximation.basis`).
    const FIELD: &'static str;
    /// Every value with its scene name and a one-line help, in reference order.
    const VALUES: &'static [(Self, &'static str, &'static str)];
    /// The value when the field is absent; `None` when the field is required or the
    /// default depends on the rest of the scene ([`Choice::DEFAULT_NOTE`] says how).
    const DEFAULT: Option<Self>;
    /// How the default is chosen, when it depends on the scene (empty otherwise).
    const DEFAULT_NOTE: &'static str = "";

    /// Scene name of the value.
    fn name(self) -> &'static str {
        Self::VALUES.iter().find(|v| v.0 == self).map(|v| v.1).expect("every value is listed in VALUES")
    }

    /// One-line help of the value.
    fn help(self) -> &'static str {
        Self::VALUES.iter().find(|v| v.0 == self).map(|v| v.2).expect("every value is listed in VALUES")
    }

    /// The value named `word`, or the reason it is none (names the known values).
    fn parse(word: &str) -> Result<Self, String> {
        Self::VALUES
            .iter()
            .find(|v| v.1 == word)
            .map(|v| v.0)
            .ok_or_else(|| format!("unknown value \"{word}\" (expected one of {})", Self::expected()))
    }

    /// The known names, quoted: `"a", "b", "c"`.
    fn expected() -> String {
        Self::VALUES.iter().map(|v| format!("\"{}\"", v.1)).collect::<Vec<_>>().join(", ")
    }

    /// The default as the reference states it.
    fn default_text() -> String {
        match (Self::DEFAULT, Self::DEFAULT_NOTE) {
            (_, note) if !note.is_empty() => note.to_string(),
            (Some(d), _) => format!("\"{}\"", d.name()),
            (None, _) => "required".to_string(),
        }
    }
}

/// One option of the scene reference: field, default, values with their help.
#[derive(Debug, Clone, PartialEq)]
pub struct OptionDoc {
    /// Scene field.
    pub field: &'static str,
    /// Default, in words.
    pub default: String,
    /// `(name, help)` of every value.
    pub values: Vec<(&'static str, &'static str)>,
}

impl OptionDoc {
    /// The reference entry of `C`.
    pub fn of<C: Choice>() -> Self {
        OptionDoc { field: C::FIELD, default: C::default_text(), values: C::VALUES.iter().map(|v| (v.1, v.2)).collect() }
    }
}

/// `text` with the pipes escaped, for a Markdown table cell.
pub fn escape_cell(text: &str) -> String {
    text.replace('|', "\\|")
}

/// The options as a Markdown table: field, value, default, meaning.
pub fn reference_markdown(options: &[OptionDoc]) -> String {
    let mut s = String::from("| field | value | meaning |\n|---|---|---|\n");
    for o in options {
        for (k, (name, help)) in o.values.iter().enumerate() {
            let field = if k == 0 { format!("`{}` (default: {})", o.field, o.default) } else { String::new() };
            s.push_str(&format!("| {field} | `\"{name}\"` | {} |\n", escape_cell(help)));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    choice! {
        /// A test option.
        enum Colour("paint.colour", default Some(Colour::Blue)) {
            Red = "red" => "warm",
            Blue = "blue" => "cold",
        }
    }

    #[test]
    fn names_parse_and_errors_list_the_values() {
        assert_eq!(Colour::parse("red"), Ok(Colour::Red));
        assert_eq!(Colour::Blue.name(), "blue");
        assert_eq!(Colour::Red.help(), "warm");
        let e = Colour::parse("green").unwrap_err();
        assert_eq!(e, "unknown value \"green\" (expected one of \"red\", \"blue\")");
        assert_eq!(Colour::default_text(), "\"blue\"");
        let md = reference_markdown(&[OptionDoc::of::<Colour>()]);
        assert!(md.contains("| `paint.colour` (default: \"blue\") | `\"red\"` | warm |"), "{md}");
        assert!(md.contains("|  | `\"blue\"` | cold |"), "{md}");
    }
}
