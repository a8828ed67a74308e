//! `GET /`: a page to try the service from a browser. One self-contained HTML file
//! (styles and script inline, nothing fetched from elsewhere) that posts the photo to
//! `POST /segment` and draws the numbered centrelines over it.

use axum::extract::State;
use axum::http::header;
use axum::response::IntoResponse;

use super::state::AppState;

const PAGE: &str = include_str!("page.html");

/// The page, with this deployment's presets in its preset list (`default` first).
pub async fn index(State(state): State<AppState>) -> impl IntoResponse {
    (
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8"),
            (
                header::CONTENT_SECURITY_POLICY,
                "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; \
                 img-src blob: data:; connect-src 'self'; form-action 'none'; \
                 frame-ancestors 'none'",
            ),
        ],
        render(&state.presets.names()),
    )
}

fn render(presets: &[&str]) -> String {
    let mut names: Vec<&str> = presets.to_vec();
    names.sort_by_key(|name| *name != "default");
    let options: String = names
        .iter()
        .map(|name| {
            let name = escape(name);
            format!("<option value=\"{name}\">{name}</option>")
        })
        .collect();
    PAGE.replace("{{presets}}", &options)
}

/// `text` safe inside HTML text and quoted attributes.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_listed_default_first_and_escaped() {
        let page = render(&["clutter", "default", "<b>\"x\""]);
        let first = page.find("<option value=\"default\">").unwrap();
        let second = page.find("<option value=\"clutter\">").unwrap();
        assert!(first < second);
        assert!(page.contains("<option value=\"&lt;b&gt;&quot;x&quot;\">"));
        assert!(!page.contains("{{presets}}"));
        assert!(!page.contains("<b>\"x\""));
    }
}
