//! The viewer page: its template (`viewer.html`) with the title, the live
//! state and the data filled in, each as text safe in its place.

use std::io::Write;

use super::Data;

/// The viewer page; `__P3DP_TITLE__`, `__P3DP_LIVE__` and `__P3DP_DATA__` are filled in.
const TEMPLATE: &str = include_str!("viewer.html");

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Writes the viewer page of `data` under `title` to `w`, the path data
/// streamed as it is encoded (the same bytes as [`page`]).
pub(crate) fn write_page(title: &str, data: &Data, w: &mut dyn Write) -> std::io::Result<()> {
    let mut rest = TEMPLATE;
    let keys = ["__P3DP_TITLE__", "__P3DP_LIVE__", "__P3DP_DATA__"];
    loop {
        let next = keys
            .iter()
            .filter_map(|k| rest.find(k).map(|at| (at, *k)))
            .min_by_key(|(at, _)| *at);
        let Some((at, k)) = next else {
            return w.write_all(rest.as_bytes());
        };
        w.write_all(&rest.as_bytes()[..at])?;
        match k {
            "__P3DP_TITLE__" => w.write_all(escape_html(title).as_bytes())?,
            "__P3DP_LIVE__" => w.write_all(script_json(&serde_json::Value::Null).as_bytes())?,
            _ => data.write_json(w)?,
        }
        rest = &rest[at + k.len()..];
    }
}

/// A viewer page showing `data` (as [`super::Data::to_value`] makes it; `null`: no model
/// yet) under `title`. `live` is `null` for a file; `p3dp watch` gives the
/// state the page starts from and follows its server-sent events.
pub(crate) fn page_with(title: &str, data: &serde_json::Value, live: &serde_json::Value) -> String {
    fill(
        TEMPLATE,
        &[
            ("__P3DP_TITLE__", escape_html(title)),
            ("__P3DP_LIVE__", script_json(live)),
            ("__P3DP_DATA__", script_json(data)),
        ],
    )
}

/// JSON to put inside a `<script>` element: every `<` written `\u003c` (the
/// same string to a JSON reader), so no `</script>` or `<!--` in a name or
/// a message can end or change the element.
pub(super) fn script_json(v: &serde_json::Value) -> String {
    v.to_string().replace('<', "\\u003c")
}

/// `template` with each placeholder replaced by its value, in one pass (a
/// value that contains a placeholder's name is left as it is).
fn fill(template: &str, values: &[(&str, String)]) -> String {
    let mut out =
        String::with_capacity(template.len() + values.iter().map(|v| v.1.len()).sum::<usize>());
    let mut rest = template;
    loop {
        let next = values
            .iter()
            .filter_map(|(k, v)| rest.find(k).map(|at| (at, *k, v)))
            .min_by_key(|(at, _, _)| *at);
        let Some((at, k, v)) = next else {
            out.push_str(rest);
            return out;
        };
        out.push_str(&rest[..at]);
        out.push_str(v);
        rest = &rest[at + k.len()..];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn template_has_its_placeholders_and_no_network() {
        for p in ["__P3DP_DATA__", "__P3DP_TITLE__", "__P3DP_LIVE__"] {
            assert!(TEMPLATE.contains(p), "{p}");
        }
        assert!(!TEMPLATE.contains("http://") && !TEMPLATE.contains("https://"));
        assert_eq!(escape_html("a<b>&\""), "a&lt;b&gt;&amp;&quot;");
    }

    #[test]
    fn placeholders_are_filled_once_and_script_json_cannot_close_its_element() {
        let v = serde_json::json!({"name": "</script><!-- __P3DP_DATA__"});
        let page = page_with("__P3DP_DATA__ <b>", &v, &serde_json::Value::Null);
        assert_eq!(
            page.matches("</script>").count(),
            TEMPLATE.matches("</script>").count()
        );
        assert!(
            page.contains("<title>__P3DP_DATA__ &lt;b&gt;"),
            "the title is filled as text"
        );
        assert!(!page.contains("__P3DP_LIVE__"));
        let json = script_json(&v);
        assert_eq!(serde_json::from_str::<serde_json::Value>(&json).unwrap(), v);
    }
}
