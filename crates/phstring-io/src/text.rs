//! Text for messages: user text and numbers as they appear in errors and on the terminal.
//!
//! * [`clip`] shortens echoed user text (a 10 MB expression is not repeated in full).
//! * [`num`] prints a float short but exact (`5e-324`, not 300 decimals).
//! * [`sanitize_text`] drops control characters from text written into files and figures.
//! * [`printable`] escapes control characters, so that a title or a value cannot move the
//!   cursor, clear the screen or ring the bell.

use std::borrow::Cow;

/// Longest user text echoed in a message, in bytes (about; cut at a character boundary).
pub const CLIP: usize = 200;

/// The 1-based line of byte `offset` of `bytes` (the newlines before it, plus one).
pub fn line_of_byte(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// `text`, or its first [`CLIP`] bytes followed by `… (N bytes)` when it is longer.
pub fn clip(text: &str) -> Cow<'_, str> {
    if text.len() <= CLIP {
        Cow::Borrowed(text)
    } else {
        let head = &text[..text.floor_char_boundary(CLIP)];
        Cow::Owned(format!("{head}… ({} bytes)", text.len()))
    }
}

/// A float for a message: the core's [`phstring::Num`] (the shortest exact form for
/// ordinary magnitudes, scientific notation otherwise: `0.01`, `5e-324`, `1e300`), so that
/// the library and the front end print numbers alike.
pub fn num(x: f64) -> Num {
    Num(x)
}

pub use phstring::Num;

/// A list of floats for a message: `[0.5, 1e300]`, at most 8 shown.
pub fn nums(xs: &[f64]) -> String {
    let mut parts: Vec<String> = xs.iter().take(8).map(|x| num(*x).to_string()).collect();
    if xs.len() > 8 {
        parts.push(format!("… ({} values)", xs.len()));
    }
    format!("[{}]", parts.join(", "))
}

/// `text` with control characters escaped (`\u{1b}`, `\0`, `\r`, …); line breaks are kept
/// when `keep_newlines`.
pub fn printable(text: &str, keep_newlines: bool) -> Cow<'_, str> {
    let bad = |c: char| c.is_control() && !(keep_newlines && c == '\n');
    if !text.chars().any(bad) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if bad(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// `text` without control characters (they would reach a terminal, make an SVG file invalid
/// or break a CSV row), cut to at most `max_chars` characters with a trailing `…`
/// (`usize::MAX`: not cut).
pub fn sanitize_text(text: &str, max_chars: usize) -> String {
    let mut out = String::new();
    for (n, c) in text.chars().filter(|c| !c.is_control()).enumerate() {
        if n + 1 > max_chars {
            out.push('…');
            break;
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_keeps_short_text_and_cuts_long_text_at_a_char_boundary() {
        assert_eq!(clip("sin(t)"), "sin(t)");
        let long = "é".repeat(1000);
        let c = clip(&long);
        assert!(c.len() < CLIP + 30, "{c}");
        assert!(c.ends_with("… (2000 bytes)"), "{c}");
    }

    #[test]
    fn numbers_are_short_and_exact() {
        assert_eq!(num(0.01).to_string(), "0.01");
        assert_eq!(num(5e-324).to_string(), "5e-324");
        assert_eq!(num(1e300).to_string(), "1e300");
        assert_eq!(num(-3.0).to_string(), "-3");
        assert_eq!(num(0.1 + 0.2).to_string(), "0.30000000000000004");
        assert_eq!(num(1.5e-30).to_string(), "1.5e-30");
        assert_eq!(num(f64::NAN).to_string(), "NaN");
        assert_eq!(num(f64::INFINITY).to_string(), "inf");
        assert_eq!(nums(&[1.0, 2.5]), "[1, 2.5]");
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("a\u{1b}[2Jb\0", false), "a\\u{1b}[2Jb\\u{0}");
        assert_eq!(printable("a\nb\r", true), "a\nb\\r");
        assert_eq!(printable("a\nb", false), "a\\nb");
        assert!(matches!(printable("plain", false), Cow::Borrowed(_)));
    }
}
