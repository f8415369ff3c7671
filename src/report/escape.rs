//! Text escaped for HTML: the one escape of every page (a leaf, so that the page's sections
//! in their own files and the page itself can all use it).

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
