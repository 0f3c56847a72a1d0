//! The one XML writer of every XML file p3dp writes (the mesh's 3MF model,
//! the `.gcode.3mf` package's metadata): elements and attributes in order,
//! each value escaped, and text XML cannot hold **refused**, not passed on.
//!
//! XML 1.0 (§2.2, production `Char`) allows tab, line feed, carriage return
//! and U+0020–U+D7FF, U+E000–U+FFFD, U+10000–U+10FFFF: any other character
//! (a C0 control such as U+0001, U+FFFE, U+FFFF) makes the document
//! malformed, and a reader stops at it. The C1 controls and DEL are
//! allowed by XML 1.0 but "discouraged" (§2.2) and must be references in
//! XML 1.1; they are refused too. Refusing (an error naming the value and
//! the character) rather than replacing keeps a name what its author wrote,
//! everywhere it appears; the three allowed controls are written as
//! character references (`&#9;`, `&#10;`, `&#13;`), which attribute-value
//! normalisation (§3.3.3) and line-end handling (§2.11) leave intact.

use std::borrow::Cow;
use std::fmt::Write as _;

use crate::base::error::{Error, Result};

/// Whether `c` may be written in p3dp's XML: XML 1.0's `Char` production
/// without the discouraged controls (DEL, C1).
pub(crate) fn allowed(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r') || (!c.is_control() && !matches!(c, '\u{fffe}' | '\u{ffff}'))
}

/// `s` escaped for an attribute value (in `"`) or element text: `& < > " '`
/// as entities, tab, line feed and carriage return as character
/// references; an error naming `what` and the first character XML does not
/// allow.
pub(crate) fn escape<'a>(what: &str, s: &'a str) -> Result<Cow<'a, str>> {
    if let Some((k, c)) = s.chars().enumerate().find(|&(_, c)| !allowed(c)) {
        let shown: String = s
            .chars()
            .map(|c| {
                if allowed(c) && !c.is_control() {
                    c.to_string()
                } else {
                    c.escape_unicode().to_string()
                }
            })
            .collect();
        return Err(Error::input(
            "",
            format!(
                "the {what} `{shown}` holds U+{:04X} at character {}, which XML 1.0 does not allow; expected text without control characters, U+FFFE or U+FFFF",
                c as u32,
                k + 1
            ),
        ));
    }
    if !s.contains(['&', '<', '>', '"', '\'', '\t', '\n', '\r']) {
        return Ok(Cow::Borrowed(s));
    }
    let mut out = String::with_capacity(s.len() + 16);
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            c => out.push(c),
        }
    }
    Ok(Cow::Owned(out))
}

/// Whether `name` is a plain XML name p3dp writes (`config`, `xml:lang`,
/// `BambuStudio:3mfVersion`): ASCII letters, digits, `_ : . -`, not starting
/// with a digit, `.` or `-`. Names come from p3dp's code, never its input.
fn plain_name(name: &str) -> bool {
    let mut b = name.bytes();
    b.next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == b'_' || c == b':')
        && b.all(|c| c.is_ascii_alphanumeric() || b"_:.-".contains(&c))
}

/// An XML document (or a piece of one) written line by line, one element or
/// end tag a line, indented by depth.
pub(crate) struct Writer {
    out: String,
    indent: &'static str,
}

impl Writer {
    /// A document: the declaration (`version="1.0" encoding="UTF-8"`), then
    /// elements indented by `indent` a level.
    pub(crate) fn new(indent: &'static str) -> Writer {
        let mut w = Writer::piece(indent);
        w.out
            .push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        w
    }

    /// A piece of a document, no declaration (the rest of a document
    /// written in parts).
    pub(crate) fn piece(indent: &'static str) -> Writer {
        Writer {
            out: String::new(),
            indent,
        }
    }

    /// `<name a="v"…` at `depth`, the values escaped.
    fn tag(&mut self, depth: usize, name: &str, attrs: &[(&str, &str)]) -> Result<()> {
        debug_assert!(plain_name(name), "element name `{name}`");
        for _ in 0..depth {
            self.out.push_str(self.indent);
        }
        let _ = write!(self.out, "<{name}");
        for (k, v) in attrs {
            debug_assert!(plain_name(k), "attribute name `{k}`");
            let what = format!("{name} {k}");
            let _ = write!(self.out, " {k}=\"{}\"", escape(&what, v)?);
        }
        Ok(())
    }

    /// A start tag on its own line.
    pub(crate) fn open(&mut self, depth: usize, name: &str, attrs: &[(&str, &str)]) -> Result<()> {
        self.tag(depth, name, attrs)?;
        self.out.push_str(">\n");
        Ok(())
    }

    /// An empty element (`<name a="v"/>`).
    pub(crate) fn empty(&mut self, depth: usize, name: &str, attrs: &[(&str, &str)]) -> Result<()> {
        self.tag(depth, name, attrs)?;
        self.out.push_str("/>\n");
        Ok(())
    }

    /// An element holding only text (`<name a="v">text</name>`).
    pub(crate) fn leaf(
        &mut self,
        depth: usize,
        name: &str,
        attrs: &[(&str, &str)],
        text: &str,
    ) -> Result<()> {
        self.tag(depth, name, attrs)?;
        let text = escape(name, text)?;
        let _ = writeln!(self.out, ">{text}</{name}>");
        Ok(())
    }

    /// An end tag on its own line.
    pub(crate) fn close(&mut self, depth: usize, name: &str) {
        for _ in 0..depth {
            self.out.push_str(self.indent);
        }
        let _ = writeln!(self.out, "</{name}>");
    }

    /// The text written.
    pub(crate) fn finish(self) -> String {
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_keeps_controls_as_references() {
        assert!(matches!(
            escape("n", "plain ü"),
            Ok(Cow::Borrowed("plain ü"))
        ));
        assert_eq!(
            escape("n", "a<b & \"c\" 'd'>").unwrap(),
            "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;"
        );
        assert_eq!(escape("n", "a\tb\r\nc").unwrap(), "a&#9;b&#13;&#10;c");
    }

    #[test]
    fn refuses_what_xml_forbids_naming_it() {
        for (bad, code, at) in [
            ("a\u{fffe}b", "U+FFFE", 2),
            ("\u{ffff}", "U+FFFF", 1),
            ("ab\u{1}", "U+0001", 3),
            ("x\u{0}", "U+0000", 2),
            ("x\u{1b}[2J", "U+001B", 2),
            ("\u{85}", "U+0085", 1),
            ("\u{7f}", "U+007F", 1),
        ] {
            let e = escape("object name", bad).unwrap_err();
            assert!(
                e.message.contains(&format!("{code} at character {at}"))
                    && e.message.starts_with("the object name `"),
                "{e}"
            );
            assert!(!e.message.contains(['\u{fffe}', '\u{ffff}', '\u{1b}', '\0']));
        }
        // the rest of Unicode, astral planes included, passes
        escape("n", "\u{fffd}\u{e000}\u{10ffff}\u{d7ff} 🐢").unwrap();
    }

    #[test]
    fn a_written_document_reads_back_with_its_values() {
        let hostile = "<&\"'>\t\n\r x";
        let mut w = Writer::new(" ");
        w.open(0, "config", &[]).unwrap();
        w.empty(1, "object", &[("name", hostile), ("id", "1")])
            .unwrap();
        w.leaf(1, "metadata", &[("name", "Application")], hostile)
            .unwrap();
        w.close(0, "config");
        let text = w.finish();
        assert!(text.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<config>\n <object "));
        let doc = roxmltree::Document::parse(&text).unwrap();
        let object = doc
            .descendants()
            .find(|n| n.has_tag_name("object"))
            .unwrap();
        assert_eq!(object.attribute("name"), Some(hostile));
        let meta = doc
            .descendants()
            .find(|n| n.has_tag_name("metadata"))
            .unwrap();
        assert_eq!(meta.text(), Some(hostile));
        let mut w = Writer::new(" ");
        assert!(w.empty(0, "object", &[("name", "a\u{ffff}")]).is_err());
    }
}
