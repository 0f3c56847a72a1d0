//! Text from recipes and profiles that reaches the G-code: names, written
//! into `;` comment lines. A line break there would end the comment and make
//! the rest of the name a command, so such text is refused at load
//! ([`check`]), and the G-code writer escapes what might still slip through
//! ([`one_line`]).

use std::borrow::Cow;

use crate::base::error::{Error, Result};

/// Whether `c` may not appear in text written into the G-code: a control
/// character (line feed, carriage return, tab, NUL, escape, DEL, C1 codes)
/// or a Unicode line or paragraph separator.
pub(crate) fn is_unsafe(c: char) -> bool {
    c.is_control() || c == '\u{2028}' || c == '\u{2029}'
}

/// A name for character `c` in an error message: `a line break (U+000A)`.
fn describe(c: char) -> String {
    let what = match c {
        '\n' | '\r' | '\u{0b}' | '\u{0c}' | '\u{85}' | '\u{2028}' | '\u{2029}' => "a line break",
        '\t' => "a tab",
        '\0' => "a NUL character",
        '\u{1b}' => "an escape character",
        _ => "a control character",
    };
    format!("{what} (U+{:04X})", c as u32)
}

/// Refuses text with a character of [`is_unsafe`], naming `place`, the
/// character and where it is.
pub(crate) fn check(place: &str, s: &str) -> Result<()> {
    match s.chars().enumerate().find(|(_, c)| is_unsafe(*c)) {
        None => Ok(()),
        Some((k, c)) => Err(Error::input(
            place,
            format!(
                "contains {} at character {}; expected one line of text without control characters (it is written into a G-code comment)",
                describe(c),
                k + 1
            ),
        )),
    }
}

/// Refuses a line of G-code (a profile's start or end G-code, one line of
/// it) with a character of [`is_unsafe`] other than a tab (which G-code
/// allows between words), naming `place`, the character and where it is.
pub(crate) fn check_gcode_line(place: &str, line: &str) -> Result<()> {
    match line
        .chars()
        .enumerate()
        .find(|&(_, c)| c != '\t' && is_unsafe(c))
    {
        None => Ok(()),
        Some((k, c)) => Err(Error::input(
            place,
            format!(
                "contains {} at character {}; expected G-code lines broken only by line feeds (U+000A)",
                describe(c),
                k + 1
            ),
        )),
    }
}

/// `s` made safe for one comment line: each character of [`is_unsafe`]
/// written as `\u{…}`. Text that passed [`check`] comes back unchanged.
pub(crate) fn one_line(s: &str) -> Cow<'_, str> {
    if !s.chars().any(is_unsafe) {
        return Cow::Borrowed(s);
    }
    Cow::Owned(
        s.chars()
            .map(|c| {
                if is_unsafe(c) {
                    c.escape_unicode().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_line_breaks_with_the_place() {
        let e = check("parts[0].name", "x\nM109 S450").unwrap_err();
        assert_eq!(e.place.as_deref(), Some("parts[0].name"));
        assert!(
            e.message.contains("line break (U+000A) at character 2"),
            "{e}"
        );
        assert!(check("name", "vase ; ok — ünïcode").is_ok());
        assert!(check("name", "a\u{2028}b").is_err());
        assert!(check("name", "a\u{85}b").is_err());
    }

    #[test]
    fn one_line_escapes_and_keeps_clean_text() {
        assert!(matches!(one_line("plain"), Cow::Borrowed("plain")));
        let s = one_line("x\r\nM109 S450");
        assert!(!s.contains('\n') && !s.contains('\r'), "{s}");
        assert_eq!(s, "x\\u{d}\\u{a}M109 S450");
    }
}
