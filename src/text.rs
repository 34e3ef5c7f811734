//! Text shown to the user: user data (column names, file names, TOML values) echoed in a message passes through
//! [`escape_control`] first, so a terminal escape sequence in a CSV header cannot reach the terminal.

use std::borrow::Cow;

/// `s` with every control character (C0, DEL, C1, e.g. ESC) written as a Rust-style escape (`\u{1b}`, `\n`, `\t`);
/// printable text, including non-ASCII letters, is unchanged. Borrowed when there is nothing to escape.
pub fn escape_control(s: &str) -> Cow<'_, str> {
    if !s.chars().any(char::is_control) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// [`escape_control`] for a whole message flightid composed: its own line breaks and tabs (a list of stretches, a
/// TOML parser's pointer to the bad line) are kept as they are, every other control character is escaped.
pub fn escape_control_in_message(s: &str) -> Cow<'_, str> {
    let escaped = |c: char| c.is_control() && c != '\n' && c != '\t';
    if !s.chars().any(escaped) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if escaped(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_sequences_are_made_visible_and_letters_kept() {
        assert_eq!(escape_control("alpha_rad"), "alpha_rad");
        assert_eq!(escape_control("Höhe_m"), "Höhe_m");
        assert_eq!(escape_control("\u{1b}[31mred"), "\\u{1b}[31mred");
        assert_eq!(
            escape_control("a\nb\tc\u{7f}\u{9b}"),
            "a\\nb\\tc\\u{7f}\\u{9b}"
        );
    }

    #[test]
    fn a_message_keeps_its_line_breaks_and_escapes_the_rest() {
        assert_eq!(
            escape_control_in_message("stretches:\n  1: 0 s\tto 30 s\n  2: \u{1b}[31m\r"),
            "stretches:\n  1: 0 s\tto 30 s\n  2: \\u{1b}[31m\\r"
        );
    }
}
