//! `p3dp explain CODE`: what a check measures, why a print fails from it,
//! how to fix it in the recipe and the `allow` that silences it. The text
//! is `docs/checks.md`, one section per code (its one source).

use crate::base::error::{Error, Result};
use crate::base::finding::CODES;

/// The page: an introduction, then one `` ## `CODE` `` section per code.
pub(crate) const PAGE: &str = include_str!("../../../docs/checks.md");

/// The section of `code` in [`PAGE`], from its heading to the next one.
pub(crate) fn section(code: &str) -> Option<&'static str> {
    let heading = format!("## `{code}`\n");
    let start = PAGE.find(&heading)?;
    let body = &PAGE[start..];
    let end = body[heading.len()..]
        .find("\n## ")
        .map_or(body.len(), |k| heading.len() + k + 1);
    Some(body[..end].trim_end())
}

/// `p3dp explain CODE`: the section of `code`, or an input error listing
/// every code; `p3dp explain`: every code and what it means, a line each.
pub(crate) fn run(code: Option<&str>) -> Result<String> {
    let Some(code) = code else {
        return Ok(list());
    };
    match CODES.iter().find(|(c, _)| *c == code) {
        Some(_) => section(code).map(|s| format!("{s}\n")).ok_or_else(|| {
            Error::input("", format!("no explanation of `{code}` in docs/checks.md"))
        }),
        None => {
            let known: Vec<&str> = CODES.iter().map(|(c, _)| *c).collect();
            Err(Error::input(
                "",
                format!(
                    "unknown check code `{code}`; expected one of {}",
                    known.join(", ")
                ),
            ))
        }
    }
}

/// Every code and its one-line meaning, then how to read more.
fn list() -> String {
    let width = CODES.iter().map(|(c, _)| c.len()).max().unwrap_or(0);
    let mut out: String = CODES
        .iter()
        .map(|(c, what)| format!("{c:<width$}  {what}\n"))
        .collect();
    out.push_str("`p3dp explain CODE` says what a check measures, why a print fails from it, how to fix the recipe and how to silence it.\n");
    out
}
