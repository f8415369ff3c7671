//! Macros (Job planning, "Macro technique (DEFINE ... AS)"): `DEFINE LIFT AS G0 Z50`
//! names a piece of block text; a later block that holds the name as a word has it
//! replaced by the text before the block is read. A macro's text is not expanded again
//! (no macro inside a macro), text in quotes and after `;` is left as written, and the
//! macros of a program hold for the subprograms it calls.

use super::expr::Scan;
use super::Reader;
use crate::lex::LineResult;

/// Most macros one program run defines.
const MAX_MACROS: usize = 1000;

impl Reader {
    /// `DEFINE name AS text` (the cursor after `DEFINE`).
    pub(super) fn define(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        let Some((name, n_at)) = sc.ident() else {
            return Err(sc.err(at, "expected `DEFINE name AS text`", "DEFINE"));
        };
        let name = name.to_string();
        if !sc.keyword("AS") {
            return Err(sc.err(
                n_at,
                format!("expected `AS` after `DEFINE {name}`"),
                "DEFINE",
            ));
        }
        let rest = &sc.s[sc.at..];
        let end = comment_start(rest);
        let text = String::from_utf8_lossy(&rest[..end]).trim().to_string();
        sc.at = sc.s.len();
        if text.is_empty() {
            return Err(sc.err(at, format!("`DEFINE {name} AS` without text"), "DEFINE"));
        }
        if let Some(m) = self.macros.iter_mut().find(|(n, _)| *n == name) {
            m.1 = text;
        } else if self.macros.len() >= MAX_MACROS {
            return Err(sc.err(at, format!("more than {MAX_MACROS} macros"), "DEFINE"));
        } else {
            self.macros.push((name, text));
        }
        Ok(())
    }

    /// The upper-cased block `up` with its macro names replaced, when it holds any.
    pub(super) fn expand(&self, up: &str) -> Option<String> {
        if self.macros.is_empty() || is_definition(up) {
            return None;
        }
        let s = up.as_bytes();
        let mut out = String::with_capacity(up.len());
        let (mut k, mut from, mut changed) = (0, 0, false);
        while k < s.len() {
            match s[k] {
                b';' => break,
                b'"' => {
                    k += 1;
                    while k < s.len() && s[k] != b'"' {
                        k += 1;
                    }
                    k += 1;
                }
                c if c.is_ascii_uppercase() || c == b'_' || c == b'$' => {
                    let start = k;
                    while k < s.len() && (s[k].is_ascii_alphanumeric() || s[k] == b'_') {
                        k += 1;
                    }
                    let word = &up[start..k];
                    if let Some((_, text)) = self.macros.iter().find(|(n, _)| n == word) {
                        out.push_str(&up[from..start]);
                        out.push_str(text);
                        from = k;
                        changed = true;
                    }
                }
                _ => k += 1,
            }
        }
        if !changed {
            return None;
        }
        out.push_str(&up[from.min(up.len())..]);
        Some(out)
    }
}

/// The byte where a `;` comment starts outside quotes (or the end).
fn comment_start(s: &[u8]) -> usize {
    let mut quoted = false;
    for (k, &c) in s.iter().enumerate() {
        match c {
            b'"' => quoted = !quoted,
            b';' if !quoted => return k,
            _ => {}
        }
    }
    s.len()
}

/// The block is a `DEFINE` (its name is not replaced in it).
fn is_definition(up: &str) -> bool {
    let mut sc = Scan::new(up);
    super::flow::skip_number_and_label(&mut sc);
    sc.keyword("DEFINE")
}
