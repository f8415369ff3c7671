//! The house: stage folders in one direction of flow, checked on the source itself.
//!
//! Every `crate::<module>` reference in `src/` must point at the same or a lower layer:
//!
//! ```text
//! 0 numeric    small numeric helpers (trig in degrees, cbrt, exp, fixed decimals); no stage
//! 1 error, kinematics (and the re-exported Axis, AxisVec, Plane)
//! 2 input      plain configuration; imports no stage
//! 3 program    NC programs → canonical moves
//! 4 motion     moves → setpoints
//! 5 drive      setpoints → actual axis positions
//! 6 pipeline   the stages connected; the Sink trait
//! 7 measure    sink: the ball bar
//! 8 check      sinks: limits and collisions (uses measure's θ frame)
//! 9 report     files
//! 10 study     runs and studies beside the pipeline
//! 11 cli       the command line
//! ```
//!
//! A reference upwards is a module reaching back up the pipeline, or a cycle in the making.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const LAYERS: &[(&str, u32)] = &[
    ("numeric", 0),
    ("error", 1),
    ("kinematics", 1),
    ("Axis", 1),
    ("AxisVec", 1),
    ("Plane", 1),
    ("Error", 1),
    ("Result", 1),
    ("input", 2),
    ("program", 3),
    ("motion", 4),
    ("drive", 5),
    ("pipeline", 6),
    ("measure", 7),
    ("check", 8),
    ("report", 9),
    ("study", 10),
    ("cli", 11),
];

fn layer(name: &str) -> Option<u32> {
    LAYERS.iter().find(|(n, _)| *n == name).map(|(_, l)| *l)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file of `src/` belongs to (`src/check/scene/monitor.rs` → check).
fn owner(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// Every `crate::name` in `text`, with `crate::{a, b::c}` groups expanded to their heads.
fn crate_references(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let inner = &group[..group.find('}').unwrap_or(group.len())];
            names.extend(
                inner
                    .split(',')
                    .map(|s| s.trim().split("::").next().unwrap_or("").trim().to_string())
                    .filter(|s| !s.is_empty()),
            );
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            names.push(name);
        }
    }
    names
}

#[test]
fn every_module_refers_only_to_its_own_layer_or_below() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut upward = Vec::new();
    let mut edges: BTreeMap<(String, String), usize> = BTreeMap::new();
    for file in &files {
        let module = owner(&src, file);
        if module == "lib" || module == "main" {
            continue;
        }
        let from = layer(&module).unwrap_or_else(|| {
            panic!(
                "{}: module `{module}` has no layer in this test",
                file.display()
            )
        });
        // Code only: a comment that points the reader elsewhere is not a dependency.
        let text: String = std::fs::read_to_string(file)
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .map(|l| format!("{l}\n"))
            .collect();
        for name in crate_references(&text) {
            let to = layer(&name).unwrap_or_else(|| {
                panic!("{}: `crate::{name}` is not a known module", file.display())
            });
            *edges.entry((module.clone(), name.clone())).or_default() += 1;
            if to > from {
                upward.push(format!("{} ({module}) -> crate::{name}", file.display()));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "references that reach up:\n{}",
        upward.join("\n")
    );
    // The graph is real: the pipeline's stages do refer to the ones below them.
    for (from, to) in [
        ("motion", "program"),
        ("drive", "input"),
        ("pipeline", "drive"),
        ("measure", "pipeline"),
        ("check", "pipeline"),
        ("report", "measure"),
        ("study", "pipeline"),
        ("cli", "study"),
        ("kinematics", "numeric"),
        ("report", "numeric"),
    ] {
        assert!(
            edges.contains_key(&(from.to_string(), to.to_string())),
            "expected {from} to use {to}"
        );
    }
}

#[test]
fn the_reader_crate_depends_on_nothing_of_mtsim() {
    let manifest = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ngc/Cargo.toml"),
    )
    .unwrap();
    let deps = manifest
        .split("[dependencies]")
        .nth(1)
        .unwrap_or("")
        .split("\n[")
        .next()
        .unwrap_or("");
    let names: Vec<&str> = deps
        .lines()
        .filter_map(|l| l.split('=').next())
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect();
    assert_eq!(names, ["serde"], "ngc's dependencies: {names:?}");
    let mut files = Vec::new();
    rust_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ngc/src"),
        &mut files,
    );
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(!text.contains("mtsim::"), "{} names mtsim", file.display());
    }
}

// ---------------------------------------------------------------------------------------------
// Loops between files.
//
// The graph's nodes are the crate's source files, found from the crate root by following its
// `mod name;` declarations (with `#[path]`). A file A has an edge to a file B ≠ A when A's code
// (comments and string literals removed) names a path that resolves into B:
//
// - `crate::a::b::Item`, `super::Item`, `self::a::Item`, and `child::Item` for a module `child`
//   the file declares; `use` groups (`crate::{a, b::{c, d}}`) are expanded;
// - the path is followed down the module tree as far as it names modules, then an item that the
//   module only brings in with a `use` (`pub use other::Item;`, or a private `use` its children
//   reach as `super::Item`) is followed to where it comes from, so a `mod.rs` that gathers
//   items for its users or its children is not the file they depend on.
//
// A parent's `mod child;` declaration and its re-exports (`pub use child::Item;`) are
// containment, not edges: they offer the child's items to the parent's users, and the parent's
// own code does not depend on them. A parent may use its children's items (`child::f()`), and a
// child may use its parent's items (`super::Item`), but not both: a child that names an item
// defined in its parent file while the parent's code names one of the child's items is a loop,
// as is any longer cycle. Paths inside inline modules resolve from that module, and test code
// (a `#[cfg(test)]` module or `use`) makes no edge: tests are clients of the whole crate.

/// One token of Rust code: an identifier (or keyword), or a piece of punctuation.
#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    PathSep,
    Punct(char),
}

/// The index just past the (nested) block comment that starts at `c[i]`; `inside` sees
/// each character within it.
fn past_block_comment(c: &[char], mut i: usize, inside: &mut dyn FnMut(char)) -> usize {
    let mut depth = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
        } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                break;
            }
        } else {
            inside(c[i]);
            i += 1;
        }
    }
    i
}

/// The tokens of `text`, with comments, string, byte-string and char literals left out
/// (a path named in a message or a doc comment is no dependency).
fn tokens(text: &str) -> Vec<Token> {
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i = past_block_comment(&c, i, &mut |_| {});
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if (ch == 'r' || (ch == 'b' && c.get(i + 1) == Some(&'r'))) && {
            let start = if ch == 'b' { i + 2 } else { i + 1 };
            let mut j = start;
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            c.get(j) == Some(&'"')
        } {
            // A raw string: r"..." or r#"..."# (any number of #).
            let mut j = if ch == 'b' { i + 2 } else { i + 1 };
            let mut hashes = 0;
            while c[j] == '#' {
                hashes += 1;
                j += 1;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
        } else if ch == '\'' {
            // A char literal ('x', '\n', '\'') or a lifetime ('a).
            if c.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            if word == "b" && c.get(i) == Some(&'"') {
                continue; // b"...": the string follows
            }
            out.push(Token::Ident(word));
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push(Token::PathSep);
            i += 2;
        } else if ch.is_numeric() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_' || c[i] == '.') {
                i += 1;
            }
        } else {
            if !ch.is_whitespace() {
                out.push(Token::Punct(ch));
            }
            i += 1;
        }
    }
    out
}

/// A path named in a file: the module it is named from, and its segments (`*` for a glob).
struct Reference {
    from: Vec<String>,
    segments: Vec<String>,
}

/// One source file, read: the modules it holds (itself and its inline modules), the child
/// module files it declares, and the paths it names.
struct SourceFile {
    modules: Vec<Vec<String>>,
    children: Vec<(Vec<String>, PathBuf)>,
    references: Vec<Reference>,
    /// `use` items: (module, name it brings in) → the path it names. A `pub use` is a
    /// re-export; a private `use` is also seen by the module's children (`super::name`).
    imports: Vec<(Vec<String>, String, Reference)>,
}

/// Reads `file`, the file of module `module`.
fn read_source(file: &Path, module: &[String]) -> SourceFile {
    let toks = tokens(&std::fs::read_to_string(file).unwrap());
    let is_mod_rs = matches!(
        file.file_name().and_then(|n| n.to_str()),
        Some("mod.rs" | "lib.rs" | "main.rs")
    );
    let dir = file.parent().unwrap();
    // The folder of the file's child modules (Rust's module-file rules).
    let child_dir = if is_mod_rs {
        dir.to_path_buf()
    } else {
        dir.join(file.file_stem().unwrap())
    };
    let mut src = SourceFile {
        modules: vec![module.to_vec()],
        children: Vec::new(),
        references: Vec::new(),
        imports: Vec::new(),
    };
    // The inline modules open at this point, with the brace depth they opened at.
    let mut scope: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut path_attr: Option<String> = None;
    let mut paths_seen = 0;
    // `#[cfg(test)]` seen, for the next item; the depth a test module opened at.
    let mut test_attr = false;
    let mut test_depth: Option<usize> = None;
    let current = |scope: &[(String, usize)]| -> Vec<String> {
        let mut m = module.to_vec();
        m.extend(scope.iter().map(|(n, _)| n.clone()));
        m
    };
    let text = std::fs::read_to_string(file).unwrap();
    let mut i = 0;
    while i < toks.len() {
        match &toks[i] {
            Token::Punct('{') => depth += 1,
            Token::Punct('}') => {
                depth -= 1;
                if scope.last().is_some_and(|(_, d)| *d == depth) {
                    scope.pop();
                }
                if test_depth == Some(depth) {
                    test_depth = None;
                }
            }
            Token::Punct('#')
                if toks[i + 1..].starts_with(&[
                    Token::Punct('['),
                    Token::Ident("cfg".into()),
                    Token::Punct('('),
                    Token::Ident("test".into()),
                    Token::Punct(')'),
                ]) =>
            {
                test_attr = true;
            }
            Token::Ident(w)
                if matches!(
                    w.as_str(),
                    "fn" | "struct" | "enum" | "impl" | "const" | "static" | "trait" | "type"
                ) =>
            {
                test_attr = false;
            }
            Token::Punct('#') if toks.get(i + 2) == Some(&Token::Ident("path".into())) => {
                // #[path = "..."]: the string was dropped by the tokenizer, so read it from
                // the text, in the order the attributes appear.
                path_attr = text
                    .match_indices("#[path")
                    .nth(paths_seen)
                    .and_then(|(k, _)| text[k..].split('"').nth(1))
                    .map(str::to_string);
                paths_seen += 1;
            }
            Token::Ident(w) if w == "mod" => {
                if let Some(Token::Ident(name)) = toks.get(i + 1) {
                    let mut path = current(&scope);
                    path.push(name.clone());
                    match toks.get(i + 2) {
                        Some(Token::Punct(';')) => {
                            let file = match path_attr.take() {
                                Some(p) => dir.join(p),
                                None => {
                                    let flat = child_dir.join(format!("{name}.rs"));
                                    if flat.exists() {
                                        flat
                                    } else {
                                        child_dir.join(name).join("mod.rs")
                                    }
                                }
                            };
                            src.children.push((path, file));
                        }
                        Some(Token::Punct('{')) => {
                            src.modules.push(path);
                            scope.push((name.clone(), depth));
                            if std::mem::take(&mut test_attr) && test_depth.is_none() {
                                test_depth = Some(depth);
                            }
                        }
                        _ => {}
                    }
                    i += 2;
                    continue;
                }
            }
            Token::Ident(w) if w == "use" => {
                let public = i > 0
                    && (toks[i - 1] == Token::Ident("pub".into())
                        || (toks[i - 1] == Token::Punct(')')
                            && toks.get(i.wrapping_sub(4)) == Some(&Token::Ident("pub".into()))));
                let from = current(&scope);
                let test = std::mem::take(&mut test_attr) || test_depth.is_some();
                let mut trees = Vec::new();
                i = use_tree(&toks, i + 1, Vec::new(), &mut trees);
                for (segments, alias) in trees {
                    let reference = Reference {
                        from: from.clone(),
                        segments,
                    };
                    let name = alias.unwrap_or_else(|| reference.segments.last().unwrap().clone());
                    if !public && !test {
                        src.references.push(Reference {
                            from: from.clone(),
                            segments: reference.segments.clone(),
                        });
                    }
                    if name != "*" {
                        src.imports.push((from.clone(), name, reference));
                    }
                }
                continue;
            }
            Token::Ident(first)
                if !matches!(toks.get(i.wrapping_sub(1)), Some(Token::PathSep))
                    && toks.get(i + 1) == Some(&Token::PathSep)
                    && test_depth.is_none() =>
            {
                let mut segments = vec![first.clone()];
                let mut j = i + 1;
                while toks.get(j) == Some(&Token::PathSep) {
                    match toks.get(j + 1) {
                        Some(Token::Ident(s)) => segments.push(s.clone()),
                        Some(Token::Punct('{')) => {
                            let mut trees = Vec::new();
                            j = use_tree(&toks, j + 1, segments.clone(), &mut trees);
                            for (s, _) in trees {
                                src.references.push(Reference {
                                    from: current(&scope),
                                    segments: s,
                                });
                            }
                            segments.clear();
                            break;
                        }
                        _ => break,
                    }
                    j += 2;
                }
                if !segments.is_empty() {
                    src.references.push(Reference {
                        from: current(&scope),
                        segments,
                    });
                }
                i = j;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    src
}

/// Parses the use tree that starts at `toks[i]` under `prefix`, pushing each full path (with
/// its `as` alias) to `out`; returns the index after the tree (past a final `;`).
fn use_tree(
    toks: &[Token],
    mut i: usize,
    prefix: Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>)>,
) -> usize {
    let mut path = prefix;
    loop {
        match toks.get(i) {
            Some(Token::Ident(s)) if s == "as" => {
                if let Some(Token::Ident(alias)) = toks.get(i + 1) {
                    out.push((std::mem::take(&mut path), Some(alias.clone())));
                }
                i += 2;
            }
            Some(Token::Ident(s)) => {
                path.push(s.clone());
                i += 1;
            }
            Some(Token::Punct('*')) => {
                path.push("*".into());
                i += 1;
            }
            Some(Token::PathSep) => i += 1,
            Some(Token::Punct('{')) => {
                i += 1;
                loop {
                    i = use_tree(toks, i, path.clone(), out);
                    match toks.get(i) {
                        Some(Token::Punct(',')) => i += 1,
                        Some(Token::Punct('}')) => {
                            i += 1;
                            break;
                        }
                        _ => return i,
                    }
                    if toks.get(i) == Some(&Token::Punct('}')) {
                        i += 1;
                        break;
                    }
                }
                path.clear();
            }
            _ => {
                if !path.is_empty() {
                    out.push((path, None));
                }
                if toks.get(i) == Some(&Token::Punct(';')) {
                    i += 1;
                }
                return i;
            }
        }
    }
}

/// The file graph of the crate whose root is `root`.
struct CrateGraph {
    /// Module path → the file it is in (inline modules included).
    modules: BTreeMap<Vec<String>, PathBuf>,
    /// (module, name) → the path a `use` in it brings in under that name.
    imports: BTreeMap<(Vec<String>, String), Reference>,
    /// file → file it names → one path that makes the edge (for the message).
    edges: BTreeMap<PathBuf, BTreeMap<PathBuf, String>>,
}

impl CrateGraph {
    fn read(root: &Path) -> CrateGraph {
        let mut graph = CrateGraph {
            modules: BTreeMap::new(),
            imports: BTreeMap::new(),
            edges: BTreeMap::new(),
        };
        let mut sources = Vec::new();
        let mut queue = vec![(Vec::new(), root.to_path_buf())];
        while let Some((module, file)) = queue.pop() {
            assert!(
                file.exists(),
                "{}: module {module:?} not found",
                file.display()
            );
            let src = read_source(&file, &module);
            for m in &src.modules {
                graph.modules.insert(m.clone(), file.clone());
            }
            queue.extend(src.children.iter().cloned());
            for (m, name, r) in &src.imports {
                let r = Reference {
                    from: r.from.clone(),
                    segments: r.segments.clone(),
                };
                graph.imports.insert((m.clone(), name.clone()), r);
            }
            sources.push((file, src));
        }
        for (file, src) in &sources {
            for r in &src.references {
                if let Some(to) = graph.resolve(r, 0) {
                    if &to != file {
                        graph
                            .edges
                            .entry(file.clone())
                            .or_default()
                            .entry(to)
                            .or_insert_with(|| r.segments.join("::"));
                    }
                }
            }
            graph.edges.entry(file.clone()).or_default();
        }
        graph
    }

    /// The file a path resolves into, or `None` for a path outside the crate (another crate,
    /// a type's associated item, a local name).
    fn resolve(&self, r: &Reference, hops: usize) -> Option<PathBuf> {
        if hops > 8 {
            return None;
        }
        let mut module = r.from.clone();
        let mut rest = r.segments.as_slice();
        match rest.first().map(String::as_str) {
            Some("crate") => {
                module.clear();
                rest = &rest[1..];
            }
            Some("self") => rest = &rest[1..],
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    module.pop()?;
                    rest = &rest[1..];
                }
            }
            Some(first) => {
                let mut child = module.clone();
                child.push(first.to_string());
                if !self.modules.contains_key(&child) {
                    return None;
                }
            }
            None => return None,
        }
        for (k, seg) in rest.iter().enumerate() {
            if seg == "self" {
                continue;
            }
            let mut child = module.clone();
            child.push(seg.clone());
            if self.modules.contains_key(&child) {
                module = child;
                continue;
            }
            if let Some(target) = self.imports.get(&(module.clone(), seg.clone())) {
                let mut segments = target.segments.clone();
                segments.extend(rest[k + 1..].iter().cloned());
                let followed = Reference {
                    from: target.from.clone(),
                    segments,
                };
                // An import of something outside the crate is no edge at all.
                return self.resolve(&followed, hops + 1);
            }
            break;
        }
        self.modules.get(&module).cloned()
    }

    /// Every loop of the graph: for each set of files that all reach each other (a strongly
    /// connected component of more than one file), the set and its shortest cycle through its
    /// first file, as the files in order (the first repeated at the end).
    fn loops(&self) -> Vec<(BTreeSet<PathBuf>, Vec<PathBuf>)> {
        let nodes: Vec<&PathBuf> = self.edges.keys().collect();
        let reach = |from: &PathBuf| -> BTreeSet<PathBuf> {
            let mut seen = BTreeSet::new();
            let mut stack = vec![from.clone()];
            while let Some(n) = stack.pop() {
                for to in self.edges.get(&n).into_iter().flat_map(|e| e.keys()) {
                    if seen.insert(to.clone()) {
                        stack.push(to.clone());
                    }
                }
            }
            seen
        };
        let reachable: BTreeMap<&PathBuf, BTreeSet<PathBuf>> =
            nodes.iter().map(|n| (*n, reach(n))).collect();
        let mut done: BTreeSet<PathBuf> = BTreeSet::new();
        let mut loops = Vec::new();
        for n in &nodes {
            if done.contains(*n) || !reachable[n].contains(*n) {
                continue;
            }
            // The files on a cycle through n: those n reaches and that reach n.
            let component: BTreeSet<PathBuf> = reachable[n]
                .iter()
                .filter(|m| reachable.get(m).is_some_and(|r| r.contains(*n)))
                .cloned()
                .collect();
            done.extend(component.iter().cloned());
            // The shortest cycle through n (breadth first inside the component).
            let mut previous: BTreeMap<PathBuf, PathBuf> = BTreeMap::new();
            let mut queue = std::collections::VecDeque::from([(*n).clone()]);
            'search: while let Some(m) = queue.pop_front() {
                for to in self.edges[&m].keys() {
                    if to == *n {
                        previous.insert((*n).clone(), m.clone());
                        break 'search;
                    }
                    if component.contains(to) && !previous.contains_key(to) {
                        previous.insert(to.clone(), m.clone());
                        queue.push_back(to.clone());
                    }
                }
            }
            let mut cycle = vec![(*n).clone()];
            let mut at = previous[*n].clone();
            while &at != *n {
                cycle.push(at.clone());
                at = previous[&at].clone();
            }
            cycle.push((*n).clone());
            cycle.reverse();
            loops.push((component, cycle));
        }
        loops
    }

    /// The loops written out, one per line: `a.rs -(super::b::X)-> b.rs -(...)-> a.rs`, and
    /// where more files are tied together than the cycle shows, all of them on the next line.
    fn describe_loops(&self, base: &Path) -> String {
        let name = |f: &PathBuf| f.strip_prefix(base).unwrap_or(f).display().to_string();
        self.loops()
            .iter()
            .map(|(component, cycle)| {
                let mut line = name(&cycle[0]);
                for pair in cycle.windows(2) {
                    line += &format!(
                        " -({})-> {}",
                        self.edges[&pair[0]][&pair[1]],
                        name(&pair[1])
                    );
                }
                if component.len() + 1 > cycle.len() {
                    let all: Vec<String> = component.iter().map(name).collect();
                    line += &format!("\n  (one of the loops among {})", all.join(", "));
                }
                line
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

fn assert_no_loops(root: &Path) {
    let graph = CrateGraph::read(root);
    let dir = root.parent().unwrap();
    // Every source file of the folder is part of the module tree the graph was read from.
    let mut files = Vec::new();
    rust_files(dir, &mut files);
    for file in files {
        let binary = file == dir.join("main.rs") || file.starts_with(dir.join("bin"));
        assert!(
            binary || graph.edges.contains_key(&file),
            "{} is not reached from {}",
            file.display(),
            root.display()
        );
    }
    let loops = graph.describe_loops(dir);
    assert!(loops.is_empty(), "files that import each other:\n{loops}");
}

#[test]
fn no_two_files_of_src_import_each_other() {
    assert_no_loops(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs"));
}

#[test]
fn no_two_files_of_the_reader_crate_import_each_other() {
    assert_no_loops(&Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ngc/src/lib.rs"));
}

/// The loop finder itself, on a small crate written for it: what it allows and what it finds.
#[test]
fn the_loop_finder_tells_structure_from_loops() {
    let dir = std::env::temp_dir().join(format!("mtsim-architecture-{}", std::process::id()));
    let write = |files: &[(&str, &str)]| {
        let _ = std::fs::remove_dir_all(&dir);
        for (name, text) in files {
            let path = dir.join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        CrateGraph::read(&dir.join("lib.rs")).describe_loops(&dir)
    };
    // A parent that uses its child's items, a child that uses a sibling through the parent's
    // re-export, its own test module using `super::*`, a path in a comment and a string, and
    // a test module that uses a file which uses its own.
    let allowed = write(&[
        ("lib.rs", "mod p;\nmod q;\npub use p::Z;\n"),
        ("p.rs", "mod c;\nmod d;\npub use c::Z;\npub use d::W;\nfn f() -> Z { c::make() }\n"),
        (
            "p/c.rs",
            "use super::W; // super::f\npub struct Z;\npub fn make() -> Z { let _ = \"super::f\"; Z }\n\
             #[cfg(test)]\nmod tests { use super::*; }\n",
        ),
        ("q.rs", "use crate::Z;\nuse crate::p::{self, W};\n"),
        (
            "p/d.rs",
            "pub struct W;\n#[cfg(test)]\nmod tests {\n    use crate::q;\n    fn t() { crate::p::c::make(); }\n}\n",
        ),
    ]);
    assert_eq!(allowed, "");
    // A child reaching back into its parent while the parent uses the child.
    let back = write(&[
        ("lib.rs", "mod p;\n"),
        ("p.rs", "mod c;\npub struct V;\nfn f() { c::g() }\n"),
        ("p/c.rs", "pub fn g() { let _ = super::V; }\n"),
    ]);
    assert_eq!(back, "p/c.rs -(super::V)-> p.rs -(c::g)-> p/c.rs");
    // Three siblings in a ring, through a use group.
    let ring = write(&[
        ("lib.rs", "mod a;\nmod b;\nmod c;\n"),
        ("a.rs", "use crate::{b::B, self as root};\npub struct A;\n"),
        ("b.rs", "use super::c::C;\npub struct B;\n"),
        ("c.rs", "pub struct C;\nfn f() { crate::a::A; }\n"),
    ]);
    assert_eq!(
        ring,
        "a.rs -(crate::b::B)-> b.rs -(super::c::C)-> c.rs -(crate::a::A)-> a.rs"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// Seams: one door per concept.
//
// A test program is a `TestProgram` (src/program/tests/), a measurement a `Measurement`
// (src/measure/). The scenario's `Program` enum is the configuration `input` reads; the rest of
// the house asks the trait, so the enum is named in at most three files (where it is defined,
// re-exported, and registered) and its variants are matched only there. Each implementation of
// either trait is in its folder and named in its one registry.

/// The code tokens of every source file of `src/`, by path relative to `src/`.
fn src_tokens() -> Vec<(String, Vec<Token>)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    files
        .iter()
        .map(|f| {
            let rel = f.strip_prefix(&src).unwrap().display().to_string();
            (rel, tokens(&std::fs::read_to_string(f).unwrap()))
        })
        .collect()
}

/// Whether `toks` names the identifier `name`.
fn names(toks: &[Token], name: &str) -> bool {
    toks.iter()
        .any(|t| matches!(t, Token::Ident(s) if s == name))
}

/// Whether `toks` name a variant of `name` (`name::Variant`).
fn names_variant(toks: &[Token], name: &str) -> bool {
    toks.windows(3).any(|w| {
        matches!(&w[0], Token::Ident(s) if s == name)
            && w[1] == Token::PathSep
            && matches!(&w[2], Token::Ident(v) if v.starts_with(|c: char| c.is_uppercase()))
    })
}

/// The types `impl Trait for Type` implements `trait_name` for, in `toks`.
fn implementors(toks: &[Token], trait_name: &str) -> Vec<String> {
    toks.windows(4)
        .filter_map(|w| match w {
            [Token::Ident(i), Token::Ident(t), Token::Ident(f), Token::Ident(ty)]
                if i == "impl" && t == trait_name && f == "for" =>
            {
                Some(ty.clone())
            }
            _ => None,
        })
        .collect()
}

/// The seams of enums read in one stage and asked of through a trait everywhere else: the
/// enum, the files that may name it (its definition, a re-export, the registry that turns it
/// into the trait), and the files among those that may match on its variants.
const ENUM_SEAMS: &[(&str, &[&str], &[&str])] = &[(
    "Program",
    &["input/scenario.rs", "input/mod.rs", "program/tests/mod.rs"],
    &["input/scenario.rs", "program/tests/mod.rs"],
)];

#[test]
fn the_test_program_enum_is_named_in_at_most_three_files_and_matched_only_where_read_and_registered(
) {
    let files = src_tokens();
    for (name, may_name, may_match) in ENUM_SEAMS {
        assert!(
            may_name.len() <= 3,
            "{name}: more than three files may name it"
        );
        let naming: Vec<&String> = files
            .iter()
            .filter(|(_, t)| names(t, name))
            .map(|(f, _)| f)
            .collect();
        let stray: Vec<&&String> = naming
            .iter()
            .filter(|f| !may_name.contains(&f.as_str()))
            .collect();
        assert!(
            stray.is_empty(),
            "`{name}` is named outside {may_name:?} (ask the trait instead): {stray:?}"
        );
        let matching: Vec<&String> = files
            .iter()
            .filter(|(f, t)| names_variant(t, name) && !may_match.contains(&f.as_str()))
            .map(|(f, _)| f)
            .collect();
        assert!(
            matching.is_empty(),
            "a stage matches on `{name}`'s variants outside {may_match:?}: {matching:?}"
        );
        // The rule sees what it is about: the definition does name and match the enum.
        assert!(naming.iter().any(|f| f.as_str() == may_match[0]));
    }
}

/// The named layouts' variants, as `Layout::Variant`.
const LAYOUTS: &[&str] = &[
    "Xyz",
    "TrtAc",
    "TrtBc",
    "TrtAb",
    "Xz",
    "Xyza",
    "Xyzabc",
    "Xyuv",
    "Xyzabcuvw",
    "Chain",
];

/// A machine build is a chain, with a named layout's closed forms as its fast path: the
/// layouts are named one by one (`Layout::TrtAc`) in one file only, and no stage matches
/// on them (it asks the kinematics: its chain, frames and inverse).
#[test]
fn named_layouts_appear_in_one_file_and_no_stage_matches_on_them() {
    let files = src_tokens();
    let naming: Vec<&String> = files
        .iter()
        .filter(|(_, toks)| {
            toks.windows(3).any(|w| {
                matches!(&w[0], Token::Ident(s) if s == "Layout")
                    && w[1] == Token::PathSep
                    && matches!(&w[2], Token::Ident(v) if LAYOUTS.contains(&v.as_str()))
            })
        })
        .map(|(f, _)| f)
        .collect();
    assert_eq!(
        naming,
        ["kinematics/layout.rs"],
        "the named layouts are written out in kinematics/layout.rs alone; elsewhere ask \
         `Kinematics` (its chain, `into_table_frames`, `turned_to_machine`, `inverse`)"
    );
}

/// One kinematics: the machine's own chain (`Kinematics::general`) is read inside
/// `src/kinematics*` alone. A stage asks the kinematics (frames, TCP, inverse, poses), which
/// picks the named layout's closed form or the chain; where a stage must know which (the
/// scene's bodies ride the chain's links), it asks `has_closed_form`, and a stage working on
/// a general chain's links takes `own_chain` without branching on whether it is there.
#[test]
fn the_general_chain_is_read_inside_the_kinematics_alone() {
    // Files outside src/kinematics* allowed to read `.general` (none).
    const ALLOWED: &[&str] = &[];
    let files = src_tokens();
    let reads = |toks: &[Token]| {
        toks.windows(2).any(|w| {
            w[0] == Token::Punct('.') && matches!(&w[1], Token::Ident(s) if s == "general")
        })
    };
    let branches = |toks: &[Token]| {
        toks.windows(5).any(|w| {
            matches!(&w[0], Token::Ident(s) if s == "own_chain")
                && w[1] == Token::Punct('(')
                && w[2] == Token::Punct(')')
                && w[3] == Token::Punct('.')
                && matches!(&w[4], Token::Ident(s) if s == "is_some" || s == "is_none")
        })
    };
    let inside = |f: &str| f == "kinematics.rs" || f.starts_with("kinematics/");
    let stray: Vec<&String> = files
        .iter()
        .filter(|(f, t)| !inside(f) && !ALLOWED.contains(&f.as_str()) && (reads(t) || branches(t)))
        .map(|(f, _)| f)
        .collect();
    assert!(
        stray.is_empty(),
        "a stage reads the general chain or branches on it; ask `Kinematics` (its frames, \
         `tcp_axes`, `inverse_first`, `has_closed_form`): {stray:?}"
    );
    // The rule sees what it is about: the kinematics does read it.
    assert!(files.iter().any(|(f, t)| f == "kinematics.rs" && reads(t)));
}

/// Each implementation of a seam's trait: in its folder, and its module named in the registry
/// file (`cone::Cone`, `cut::build`). `exempt` are implementations the registry need not list
/// (with the reason at the call).
fn assert_registered(trait_name: &str, folder: &str, registry: &str, exempt: &[&str]) {
    let files = src_tokens();
    let registry_tokens = &files
        .iter()
        .find(|(f, _)| f == registry)
        .unwrap_or_else(|| panic!("{registry} not found"))
        .1;
    let names_module = |module: &str| {
        registry_tokens
            .windows(2)
            .any(|w| matches!(&w[0], Token::Ident(s) if s == module) && w[1] == Token::PathSep)
    };
    let mut found = 0;
    for (file, toks) in &files {
        for ty in implementors(toks, trait_name) {
            found += 1;
            assert!(
                file.starts_with(folder),
                "{file}: `impl {trait_name} for {ty}` outside {folder}"
            );
            let module = Path::new(file).file_stem().unwrap().to_string_lossy();
            assert!(
                exempt.contains(&ty.as_str()) || file == registry || names_module(&module),
                "{file}: `{ty}` implements {trait_name} but {registry} does not register it \
                 (as `{module}::...`)"
            );
        }
    }
    assert!(found > 0, "no implementation of {trait_name} found");
}

#[test]
fn every_test_program_lives_in_program_tests_and_is_registered_there() {
    assert_registered("TestProgram", "program/tests/", "program/tests/mod.rs", &[]);
}

#[test]
fn every_measurement_lives_in_measure_and_is_registered_in_one_place() {
    // The ball bar is built by `simulate` itself (its bins feed the trace and the report).
    assert_registered(
        "Measurement",
        "measure/",
        "measure/measurement.rs",
        &["BallbarSink"],
    );
    // One registry: only measurement.rs names it, and the pipeline knows no measurement.
    for (file, toks) in src_tokens() {
        if file != "measure/measurement.rs" {
            assert!(
                !names(&toks, "REGISTRY"),
                "{file} names the measurement registry"
            );
        }
        if file == "pipeline.rs" {
            for name in ["Measurement", "BallbarSink", "measure"] {
                assert!(!names(&toks, name), "pipeline.rs names `{name}`");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Sizes.
//
// No function in `src/` or `crates/` is over [`MAX_FN_LINES`] lines and no file over
// [`MAX_CODE_LINES`] code lines, so that each reads as one concept:
//
// - a function's lines run from the line of its `fn` keyword to the line of its closing brace,
//   both included, with every line between (blank lines and comments too); its doc comment
//   and attributes do not count. A function inside another (or in an `impl` inside one)
//   counts on its own and in the one around it. Test functions count like any other;
// - a file's code lines are its lines that hold anything besides comments (`//`, `///`,
//   `//!`, `/* */`) and white space: a line inside a string literal is code, a blank line or
//   a comment line is not. A file's test module counts.
//
// What is over either limit today is in [`SIZE_ALLOWED`], each entry with why; an entry that
// is no longer over its limit is an error too, so that the list only shrinks.

/// The longest function allowed, lines.
const MAX_FN_LINES: usize = 150;

/// The most code lines a file may hold.
const MAX_CODE_LINES: usize = 1000;

/// Over a limit for now: the file (from the repository root), the function (None: the
/// file's code lines) and why. The lead shrinks this list as the splits land.
const SIZE_ALLOWED: &[(&str, Option<&str>, &str)] = &[];

/// `text` with comments removed and every character of a string or char literal (its
/// quotes included) replaced by `"`, line breaks kept: braces and `fn` in a comment or a
/// string are not code, and a line of a string literal still is.
fn code_only(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    // Copies `c[from..to]` as literal text: `"` for each character, line breaks kept.
    let literal = |out: &mut String, from: usize, to: usize| {
        for &ch in &c[from..to.min(c.len())] {
            out.push(if ch == '\n' { '\n' } else { '"' });
        }
    };
    while i < c.len() {
        let ch = c[i];
        let prev_ident = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
        if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i = past_block_comment(&c, i, &mut |ch| {
                if ch == '\n' {
                    out.push('\n');
                }
            });
        } else if ch == '"' {
            let start = i;
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            literal(&mut out, start, i);
        } else if !prev_ident && (ch == 'r' || (ch == 'b' && c.get(i + 1) == Some(&'r'))) && {
            let mut j = if ch == 'b' { i + 2 } else { i + 1 };
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            c.get(j) == Some(&'"')
        } {
            // A raw string: r"..." or r#"..."# (any number of #).
            let start = i;
            let mut j = if ch == 'b' { i + 2 } else { i + 1 };
            let mut hashes = 0;
            while c[j] == '#' {
                hashes += 1;
                j += 1;
            }
            j += 1;
            while j < c.len() {
                if c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
            literal(&mut out, start, i);
        } else if ch == '\'' && c.get(i + 1) == Some(&'\\') {
            // An escaped char literal: '\n', '\'', '\u{..}'.
            let start = i;
            i += 2;
            while i < c.len() && c[i] != '\'' {
                i += 1;
            }
            i += 1;
            literal(&mut out, start, i);
        } else if ch == '\'' && c.get(i + 2) == Some(&'\'') {
            // A char literal ('{'); a lifetime ('a) is code.
            literal(&mut out, i, i + 3);
            i += 3;
        } else {
            out.push(ch);
            i += 1;
        }
    }
    out
}

/// The code lines of `text` (see the rule above).
fn code_lines(text: &str) -> usize {
    code_only(text)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .count()
}

/// Every function of `text` with a body: its name and its length in lines.
fn function_lengths(text: &str) -> Vec<(String, usize)> {
    let code: Vec<char> = code_only(text).chars().collect();
    let line_at = |i: usize| code[..i].iter().filter(|&&ch| ch == '\n').count();
    let is_ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut out = Vec::new();
    for i in 0..code.len() {
        // The keyword `fn`, then a name (not a `fn(..)` pointer type).
        let starts = code[i..].starts_with(&['f', 'n'])
            && (i == 0 || !is_ident(code[i - 1]))
            && code.get(i + 2).is_some_and(|ch| ch.is_whitespace());
        if !starts {
            continue;
        }
        let mut j = i + 2;
        while j < code.len() && code[j].is_whitespace() {
            j += 1;
        }
        let name: String = code[j..].iter().take_while(|&&ch| is_ident(ch)).collect();
        if name.is_empty() {
            continue;
        }
        // The body: the first `{` before any `;` (a declaration without a body has none).
        while j < code.len() && code[j] != '{' && code[j] != ';' {
            j += 1;
        }
        if code.get(j) != Some(&'{') {
            continue;
        }
        let mut depth = 0;
        let mut end = j;
        for (k, &ch) in code.iter().enumerate().skip(j) {
            if ch == '{' {
                depth += 1;
            } else if ch == '}' {
                depth -= 1;
                if depth == 0 {
                    end = k;
                    break;
                }
            }
        }
        out.push((name, line_at(end) - line_at(i) + 1));
    }
    out
}

#[test]
fn no_function_is_over_150_lines_and_no_file_over_1000_code_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    rust_files(&root.join("crates"), &mut files);
    files.sort();
    let allowed = |file: &str, function: Option<&str>| {
        SIZE_ALLOWED
            .iter()
            .any(|(f, name, _)| *f == file && *name == function)
    };
    let mut over = Vec::new();
    let mut still_over = BTreeSet::new();
    for path in &files {
        let file = path
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(path).unwrap();
        let lines = code_lines(&text);
        if lines > MAX_CODE_LINES {
            still_over.insert((file.clone(), None));
            if !allowed(&file, None) {
                over.push(format!("{file}: {lines} code lines"));
            }
        }
        for (name, length) in function_lengths(&text) {
            if length > MAX_FN_LINES {
                still_over.insert((file.clone(), Some(name.clone())));
                if !allowed(&file, Some(&name)) {
                    over.push(format!("{file}: fn {name}, {length} lines"));
                }
            }
        }
    }
    let stale: Vec<String> = SIZE_ALLOWED
        .iter()
        .filter(|(f, name, _)| !still_over.contains(&(f.to_string(), name.map(String::from))))
        .map(|(f, name, _)| format!("{f} {}", name.unwrap_or("(file)")))
        .collect();
    assert!(
        over.is_empty(),
        "over {MAX_FN_LINES} lines a function or {MAX_CODE_LINES} code lines a file (split \
         by concept):\n  {}",
        over.join("\n  ")
    );
    assert!(
        stale.is_empty(),
        "within the limits now, so remove from SIZE_ALLOWED:\n  {}",
        stale.join("\n  ")
    );
}

/// The size rule's counting, on text written for it.
#[test]
fn the_size_rule_counts_code_lines_and_function_lines() {
    let text = "//! A module.\n\n/// Doc.\nfn one() {\n    // a comment\n    let s = \"{\n}\";\n\n    \
                let c = '{';\n}\n/* a\n block */\nfn two(f: fn(u8) -> u8) -> u8 where u8: Copy { f(1) }\n\
                trait T { fn three(&self); }\nfn r() { let _ = r#\"fn x() {\"#; }\n";
    // Code: fn one, let s (2 lines), let c, }, fn two, trait, fn r.
    assert_eq!(code_lines(text), 8);
    assert_eq!(
        function_lengths(text),
        vec![
            ("one".to_string(), 7),
            ("two".to_string(), 1),
            ("r".to_string(), 1)
        ]
    );
}

/// Front ends behind one trait (issue 37): outside its own folder of `crates/ngc/src`, a
/// control's front end is named only by its registration, once, in `reader/mod.rs`'s
/// `FRONT_ENDS` (a new control is its folder and that one line); the ISO family's reader is
/// the last entry, reading every program no other front end claims.
#[test]
fn each_front_end_is_named_only_by_its_registration() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/ngc/src");
    let registry = src.join("reader/mod.rs");
    let fronts = ["siemens", "heidenhain"];
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    for file in &files {
        let rel = file.strip_prefix(&src).unwrap();
        let text = std::fs::read_to_string(file).unwrap();
        for front in fronts {
            if rel.starts_with(front) {
                continue;
            }
            let path = format!("crate::{front}::");
            for (k, _) in text.match_indices(&path) {
                let named = &text[k + path.len()..];
                let name: String = named
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                assert!(
                    *file == registry && name == "FRONT_END",
                    "{} names `{path}{name}`: only reader/mod.rs names a front end, by its FRONT_END",
                    rel.display()
                );
            }
        }
    }
    let text = std::fs::read_to_string(&registry).unwrap();
    let list = &text[text
        .find("const FRONT_ENDS")
        .expect("FRONT_ENDS in reader/mod.rs")..];
    let list = &list[..list.find("];").unwrap()];
    for front in fronts {
        assert_eq!(
            list.matches(&format!("&crate::{front}::FRONT_END,"))
                .count(),
            1,
            "{front} registered once in FRONT_ENDS"
        );
        let folder = src.join(front);
        let mut own = Vec::new();
        rust_files(&folder, &mut own);
        assert!(
            own.iter().any(|f| std::fs::read_to_string(f)
                .unwrap()
                .contains("pub(crate) const FRONT_END: Registration")),
            "{front}/ defines its FRONT_END registration"
        );
    }
    let last = list
        .trim_end()
        .trim_end_matches(',')
        .rsplit(',')
        .next()
        .unwrap()
        .trim();
    assert_eq!(
        last, "&stream::FRONT_END",
        "the ISO family last in FRONT_ENDS"
    );
}
