//! docs/gcode.md has a row for every G and M code the fanuc and haas dialects accept: each
//! code is read on its own in the dialect (a code the dialect does not have is refused as
//! unsupported, whatever words it would need), and the accepted ones are looked up in the
//! code tables of the section "Fanuc and Haas codes, one by one".

use std::collections::BTreeSet;
use std::path::Path;

use ngc::{read_str_with, Dialect, Error, Options};

/// Whether `word` on a line of its own is a code of `dialect`: it reads, or it stops for a
/// reason other than the code being unknown (a missing word, a missing P ...).
fn accepted(dialect: Dialect, word: &str) -> bool {
    let options = Options {
        dialect,
        ..Options::default()
    };
    let text = format!("{word}\n");
    match read_str_with(Path::new("t.nc"), &text, &options).find_map(|m| m.err()) {
        None => true,
        Some(Error::Syntax(s)) => {
            !(s.message.starts_with("unsupported code") || s.message.contains("is not supported"))
        }
        Some(other) => panic!("{word}: {other:?}"),
    }
}

/// The G codes (×10) and M codes `dialect` accepts, as written in a program: `G0`, `G43.4`.
fn accepted_codes(dialect: Dialect) -> Vec<(char, u32)> {
    let g = (0..=3000u32)
        .filter(|c| accepted(dialect, &g_word(*c)))
        .map(|c| ('G', c));
    let m = (0..=300u32)
        .filter(|c| accepted(dialect, &format!("M{c}")))
        .map(|c| ('M', c * 10));
    g.chain(m).collect()
}

fn g_word(tenths: u32) -> String {
    if tenths % 10 == 0 {
        format!("G{}", tenths / 10)
    } else {
        format!("G{}.{}", tenths / 10, tenths % 10)
    }
}

/// The codes (letter, value ×10) in the first column of the G and M code tables of
/// docs/gcode.md's section "Fanuc and Haas codes, one by one": `G02`, `G03`; ranges
/// `G54`-`G59` (whole codes) and `M21`-`M28`.
fn documented_codes(doc: &str) -> BTreeSet<(char, u32)> {
    let start = doc
        .find("## Fanuc and Haas codes, one by one")
        .expect("docs/gcode.md has the section \"Fanuc and Haas codes, one by one\"");
    let section = &doc[start..];
    let end = section[3..].find("\n## ").map_or(section.len(), |e| e + 3);
    let mut codes = BTreeSet::new();
    for line in section[..end].lines().filter(|l| l.starts_with("| `")) {
        let first = line[1..].split('|').next().unwrap_or("");
        for item in first.split(',') {
            let words: Vec<(char, u32)> = item
                .split('`')
                .skip(1)
                .step_by(2)
                .filter_map(parse_code)
                .collect();
            match words[..] {
                [(l, a), (m, b)] if item.contains("`-`") && l == m => {
                    codes.extend((a..=b).step_by(10).map(|c| (l, c)));
                }
                _ => codes.extend(words),
            }
        }
    }
    codes
}

/// `G43.4` → ('G', 434); None for other words (`X Y Z`, `#`).
fn parse_code(word: &str) -> Option<(char, u32)> {
    let letter = word.chars().next().filter(|c| matches!(c, 'G' | 'M'))?;
    let value: f64 = word[1..].parse().ok()?;
    Some((letter, (value * 10.0).round() as u32))
}

fn name((letter, tenths): (char, u32)) -> String {
    if letter == 'G' {
        g_word(tenths)
    } else {
        format!("M{}", tenths / 10)
    }
}

#[test]
fn every_code_the_fanuc_and_haas_dialects_accept_has_a_row_in_docs_gcode_md() {
    let doc_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/gcode.md");
    let doc = std::fs::read_to_string(&doc_path).expect("docs/gcode.md");
    let documented = documented_codes(&doc);
    assert!(documented.len() > 100, "{documented:?}");
    let mut accepted_somewhere = BTreeSet::new();
    for dialect in [Dialect::Fanuc, Dialect::Haas] {
        let accepted = accepted_codes(dialect);
        let missing: Vec<String> = accepted
            .iter()
            .filter(|c| !documented.contains(c))
            .map(|c| name(*c))
            .collect();
        assert!(
            missing.is_empty(),
            "the {dialect:?} dialect accepts codes docs/gcode.md (\"Fanuc and Haas codes, one by one\") has no row for: {}",
            missing.join(" ")
        );
        accepted_somewhere.extend(accepted);
    }
    // And no row for a code neither dialect reads.
    let stale: Vec<String> = documented
        .iter()
        .filter(|c| !accepted_somewhere.contains(c))
        .map(|c| name(*c))
        .collect();
    assert!(
        stale.is_empty(),
        "docs/gcode.md has rows for codes neither the fanuc nor the haas dialect accepts: {}",
        stale.join(" ")
    );
}

#[test]
fn the_doc_table_parser_reads_single_codes_lists_and_ranges() {
    let doc = "## Fanuc and Haas codes, one by one\n| Code | x |\n|---|---|\n\
               | `G02`, `G03` | a |\n| `G54`-`G59` | b |\n| `G43.4` | c |\n| `M21`-`M23` | d |\n\
               | `X Y Z` | e |\n## Next\n| `G99` | f |\n";
    let got: Vec<String> = documented_codes(doc).into_iter().map(name).collect();
    assert_eq!(
        got,
        ["G2", "G3", "G43.4", "G54", "G55", "G56", "G57", "G58", "G59", "M21", "M22", "M23"]
    );
}
