//! The repository's shape, checked so it stays readable: no import cycle between the
//! modules of `sndt-core`, `sndt-host`, the Python module or the C API, no host import that
//! points up the host's declared layers (the table in `host/src/lib.rs`, which
//! `docs/ARCHITECTURE.md` repeats), no function longer than [`MAX_FN_LINES`] in those
//! crates or the firmware, no pointer to a document the repository does not ship, and a
//! README short enough to read.
//!
//! The checks read the source text (a small scanner, not a Rust parser): module paths from
//! file paths, imports from `crate::...`, `super::...` and a `mod.rs`'s own `use child::...`
//! re-exports, outside `#[cfg(test)] mod tests` blocks.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest function allowed, in lines from `fn` to its closing brace.
const MAX_FN_LINES: usize = 80;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().path()) {
            if e.is_dir() {
                stack.push(e);
            } else if e.extension().is_some_and(|x| x == "rs") {
                out.push(e);
            }
        }
    }
    out.sort();
    out
}

/// Module path of a source file relative to its crate's `src/` (`""` for the crate root).
fn module_path(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into()).collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts.join("::")
}

/// The source without `#[cfg(test)] mod ... { ... }` blocks and without comments.
fn code_without_tests(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..i]);
        let after = &rest[i..];
        match after.find('{') {
            Some(open) if after[..open].contains("mod ") && !after[..open].contains(';') => {
                let close = matching_brace(after, open).unwrap_or(after.len() - 1);
                rest = &after[close + 1..];
            }
            _ => {
                out.push_str("#[cfg(test)]");
                rest = &after["#[cfg(test)]".len()..];
            }
        }
    }
    out.push_str(rest);
    out.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Index of the brace closing the one at `open` (braces in strings and chars are rare
/// enough in this code base to be ignored, comments are not: callers strip them).
fn matching_brace(text: &str, open: usize) -> Option<usize> {
    let mut depth = 0i32;
    for (i, c) in text[open..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(open + i);
                }
            }
            _ => {}
        }
    }
    None
}

/// Identifier paths following `prefix` in `code`, e.g. `a::b::C` after `crate::`.
fn paths_after<'a>(code: &'a str, prefix: &str) -> Vec<&'a str> {
    code.match_indices(prefix)
        .filter(|(i, _)| {
            let before = code[..*i].chars().next_back();
            !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
        })
        .map(|(i, _)| {
            let s = &code[i + prefix.len()..];
            let end = s
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(s.len());
            s[..end].trim_end_matches(':')
        })
        .collect()
}

/// The longest known module that `path` (relative to the crate root) names.
fn resolve(path: &str, modules: &BTreeSet<String>) -> Option<String> {
    let segs: Vec<&str> = path.split("::").collect();
    (1..=segs.len())
        .rev()
        .map(|n| segs[..n].join("::"))
        .find(|m| modules.contains(m))
}

/// Import edges between the modules of one crate.
fn import_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let files = rust_files(src);
    let modules: BTreeSet<String> = files.iter().map(|f| module_path(src, f)).collect();
    let mut graph = BTreeMap::new();
    for f in &files {
        let me = module_path(src, f);
        let code = code_without_tests(&std::fs::read_to_string(f).unwrap());
        let parent = me.rsplit_once("::").map_or("", |(p, _)| p).to_string();
        let join = |base: &str, rest: &str| {
            if base.is_empty() {
                rest.to_string()
            } else {
                format!("{base}::{rest}")
            }
        };
        let mut targets: Vec<String> = paths_after(&code, "crate::")
            .into_iter()
            .map(str::to_string)
            .collect();
        targets.extend(
            paths_after(&code, "super::")
                .into_iter()
                .map(|p| join(&parent, p)),
        );
        targets.extend(paths_after(&code, "use ").into_iter().map(|p| join(&me, p)));
        let deps: BTreeSet<String> = targets
            .iter()
            .filter_map(|t| resolve(t, &modules))
            .filter(|d| *d != me && !d.is_empty())
            .collect();
        graph.insert(me, deps);
    }
    graph
}

/// One cycle of `graph`, if there is any (depth-first search).
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        done: &mut BTreeSet<String>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == m) {
            return Some(path[i..].to_vec());
        }
        if done.contains(m) {
            return None;
        }
        path.push(m.to_string());
        for d in graph.get(m).into_iter().flatten() {
            if let Some(c) = visit(d, graph, done, path) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(m.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|m| visit(m, graph, &mut done, &mut Vec::new()))
}

#[test]
fn the_scanner_finds_a_planted_cycle_and_ignores_test_modules() {
    let mut g = BTreeMap::new();
    g.insert("a".to_string(), BTreeSet::from(["b".to_string()]));
    g.insert("b".to_string(), BTreeSet::from(["c".to_string()]));
    g.insert("c".to_string(), BTreeSet::from(["a".to_string()]));
    assert_eq!(find_cycle(&g).map(|c| c.len()), Some(3));
    g.get_mut("c").unwrap().clear();
    assert_eq!(find_cycle(&g), None);
    let code =
        "use crate::a;\n#[cfg(test)]\nmod tests {\n    use crate::b;\n}\nfn f() {} // crate::c\n";
    let stripped = code_without_tests(code);
    assert_eq!(paths_after(&stripped, "crate::"), ["a"]);
}

/// The crates whose modules must not import each other in a circle, with the fewest
/// modules each has: fewer found means the scanner missed files, and the check passed on
/// nothing.
const ACYCLIC_CRATES: [(&str, usize); 4] = [
    ("core/src", 10),
    ("host/src", 10),
    ("python/src", 5),
    ("targets/c/src", 2),
];

#[test]
fn no_import_cycle_between_modules() {
    for (krate, fewest) in ACYCLIC_CRATES {
        let graph = import_graph(&repo().join(krate));
        assert!(
            graph.len() >= fewest,
            "{krate}: only {} modules found",
            graph.len()
        );
        if let Some(cycle) = find_cycle(&graph) {
            panic!("{krate}: import cycle {}", cycle.join(" -> "));
        }
    }
}

/// The host's layers as its crate doc declares them: the top-level module names of each
/// table row `| N | [`a`], [`b`] | role |`, by layer number.
fn declared_layers(doc: &str, row_prefix: &str) -> BTreeMap<String, u32> {
    let mut layers = BTreeMap::new();
    for line in doc.lines() {
        let Some(row) = line.trim().strip_prefix(row_prefix) else {
            continue;
        };
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let Some(layer) = cells.first().and_then(|c| c.parse::<u32>().ok()) else {
            continue;
        };
        for name in cells[1].split('`').skip(1).step_by(2) {
            let name = name.trim_start_matches("host/src/");
            let name = name.trim_end_matches('/').trim_end_matches(".rs");
            layers.insert(name.to_string(), layer);
        }
    }
    layers
}

/// The text from the line `heading` to the next heading line (one starting with `#`
/// after any `//!`), or to the end.
fn section<'a>(text: &'a str, heading: &str) -> &'a str {
    let Some(start) = text.find(heading) else {
        return "";
    };
    let body = &text[start + heading.len()..];
    let mut end = body.len();
    let mut at = 0;
    for line in body.split_inclusive('\n') {
        if at > 0 && line.trim_start_matches("//!").trim_start().starts_with('#') {
            end = at;
            break;
        }
        at += line.len();
    }
    &body[..end]
}

/// Imports from a module of a lower layer to one of a higher layer, as
/// `from -> to (layer a -> b)` lines. Submodules take their top-level module's layer.
fn upward_imports(
    graph: &BTreeMap<String, BTreeSet<String>>,
    layers: &BTreeMap<String, u32>,
) -> Vec<String> {
    let layer_of = |m: &str| layers.get(m.split("::").next().unwrap_or(m)).copied();
    let mut out = Vec::new();
    for (from, deps) in graph {
        let Some(a) = layer_of(from) else { continue };
        for to in deps {
            match layer_of(to) {
                Some(b) if b > a => out.push(format!("{from} -> {to} (layer {a} -> {b})")),
                _ => {}
            }
        }
    }
    out
}

#[test]
fn the_layer_check_finds_a_planted_upward_import() {
    let doc = "//! | layer | modules | role |\n//! | 1 | [`data`] | r |\n//! | 2 | [`eval`], [`out`] | w |\n";
    let layers = declared_layers(doc, "//! | ");
    assert_eq!(layers.len(), 3);
    assert_eq!(layers["out"], 2);
    let mut g = BTreeMap::new();
    g.insert(
        "eval::run".to_string(),
        BTreeSet::from(["data::read".to_string()]),
    );
    g.insert("out".to_string(), BTreeSet::from(["eval".to_string()]));
    assert!(
        upward_imports(&g, &layers).is_empty(),
        "same layer and downward are allowed"
    );
    g.insert(
        "data::read".to_string(),
        BTreeSet::from(["out".to_string()]),
    );
    assert_eq!(
        upward_imports(&g, &layers),
        ["data::read -> out (layer 1 -> 2)"]
    );
}

#[test]
fn host_imports_point_down_its_declared_layers() {
    let src = repo().join("host/src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let layers = declared_layers(section(&lib, "//! ## Layers"), "//! | ");
    let graph = import_graph(&src);
    // Every top-level module has a layer, and nothing else does.
    let top: BTreeSet<String> = graph
        .keys()
        .filter(|m| !m.is_empty() && !m.contains("::"))
        .cloned()
        .collect();
    let declared: BTreeSet<String> = layers.keys().cloned().collect();
    assert_eq!(
        declared, top,
        "host/src/lib.rs: the layer table and the modules differ"
    );
    let architecture = std::fs::read_to_string(repo().join("docs/ARCHITECTURE.md")).unwrap();
    assert_eq!(
        declared_layers(section(&architecture, "### Host layers"), "| "),
        layers,
        "docs/ARCHITECTURE.md states other host layers than host/src/lib.rs"
    );
    let up = upward_imports(&graph, &layers);
    assert!(
        up.is_empty(),
        "host imports that point up its layers:\n{}",
        up.join("\n")
    );
}

/// The core's modules by row of the "Modules, in dependency order" table of its crate
/// doc: `| `a`, `b::{c, d}` | what |` gives `a`, `b::c` and `b::d` the row's number.
fn core_rows(doc: &str) -> BTreeMap<String, u32> {
    let mut rows = BTreeMap::new();
    let table = section(doc, "//! ## Modules, in dependency order");
    let body = table
        .lines()
        .filter_map(|l| l.trim().strip_prefix("//! | `"));
    for (row, line) in (0u32..).zip(body) {
        let first = line.split(" | ").next().unwrap_or("");
        for name in format!("`{first}").split('`').skip(1).step_by(2) {
            match name.split_once("::{") {
                Some((parent, children)) => {
                    for child in children.trim_end_matches('}').split(',') {
                        rows.insert(format!("{parent}::{}", child.trim()), row);
                    }
                }
                None => {
                    rows.insert(name.to_string(), row);
                }
            }
        }
    }
    rows
}

#[test]
fn core_imports_point_up_its_module_table() {
    let src = repo().join("core/src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let rows = core_rows(&lib);
    let graph = import_graph(&src);
    // Every module is in the table, but the crate root, test helpers and folders whose
    // mod.rs only declares the files in it.
    let missing: Vec<&String> = graph
        .keys()
        .filter(|m| !m.is_empty() && *m != "testutil" && !rows.contains_key(*m))
        .filter(|m| !rows.keys().any(|r| r.starts_with(&format!("{m}::"))))
        .collect();
    assert!(
        missing.is_empty(),
        "core modules missing from lib.rs's table: {missing:?}"
    );
    // A module may use modules of its own row or rows above it ("in dependency order").
    let mut down = Vec::new();
    for (from, deps) in &graph {
        let Some(a) = rows.get(from) else { continue };
        for to in deps {
            if let Some(b) = rows.get(to).filter(|b| *b > a) {
                down.push(format!("{from} (row {a}) -> {to} (row {b})"));
            }
        }
    }
    assert!(
        down.is_empty(),
        "core imports that point down its module table:\n{}",
        down.join("\n")
    );
}

#[test]
fn the_core_table_reader_expands_braces() {
    let doc = "//! ## Modules, in dependency order\n//!\n//! | module | what |\n//! |---|---|\n//! | `error`, `labels` | e |\n//! | `geometry::{sqrt, dda}` | g |\n//! | `integrate` | i |\n//!\n//! ## Features\n//! | `x` | y |\n";
    let rows = core_rows(doc);
    let expected = [
        ("error", 0),
        ("labels", 0),
        ("geometry::sqrt", 1),
        ("geometry::dda", 1),
        ("integrate", 2),
    ];
    assert_eq!(
        rows,
        expected.iter().map(|(m, r)| (m.to_string(), *r)).collect()
    );
}

/// `(file, line, name, lines)` of every function longer than [`MAX_FN_LINES`].
fn long_functions(dir: &Path) -> Vec<(String, usize, String, usize)> {
    let mut out = Vec::new();
    for f in rust_files(dir) {
        let text = std::fs::read_to_string(&f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let Some(name) = fn_name(line) else { continue };
            if let Some(n) = fn_length(&lines[i..]) {
                if n > MAX_FN_LINES {
                    out.push((f.display().to_string(), i + 1, name, n));
                }
            }
        }
    }
    out
}

/// The name of the function a line starts, if it starts one.
fn fn_name(line: &str) -> Option<String> {
    let t = line.trim_start();
    if t.starts_with("//") {
        return None;
    }
    let mut words = t.split_whitespace().peekable();
    while let Some(w) = words.next() {
        if w == "fn" {
            let name = words.next()?;
            return Some(name.split(['(', '<']).next()?.to_string());
        }
        let qualifier = w.starts_with("pub") || matches!(w, "const" | "unsafe" | "async");
        if !qualifier {
            return None;
        }
    }
    None
}

/// Lines from the `fn` line to its closing brace, or `None` for a declaration without body.
fn fn_length(lines: &[&str]) -> Option<usize> {
    let mut depth = 0i32;
    let mut opened = false;
    for (i, line) in lines.iter().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        for c in code.chars() {
            match c {
                '{' => {
                    depth += 1;
                    opened = true;
                }
                '}' => depth -= 1,
                _ => {}
            }
        }
        if opened && depth == 0 {
            return Some(i + 1);
        }
        if !opened && code.trim_end().ends_with(';') {
            return None;
        }
    }
    None
}

#[test]
fn no_function_is_longer_than_the_limit() {
    let mut long = Vec::new();
    for dir in [
        "core/src",
        "host/src",
        "host/benches",
        "python/src",
        "targets/c/src",
        "targets/cortex-m4f/src",
    ] {
        long.extend(long_functions(&repo().join(dir)));
    }
    let report: Vec<String> = long
        .iter()
        .map(|(f, l, name, n)| format!("{f}:{l} {name}: {n} lines"))
        .collect();
    assert!(
        report.is_empty(),
        "functions over {MAX_FN_LINES} lines:\n{}",
        report.join("\n")
    );
}

#[test]
fn the_length_scanner_counts_a_known_function() {
    let src = [
        "pub(crate) fn f(x: u32) -> u32 {",
        "    if x > 0 {",
        "        1",
        "    } else { 0 }",
        "}",
    ];
    assert_eq!(fn_name(src[0]).as_deref(), Some("f"));
    assert_eq!(fn_length(&src), Some(5));
    assert_eq!(fn_name("    fn g<T>();"), Some("g".into()));
    assert_eq!(fn_length(&["fn g<T>();"]), None);
    assert_eq!(fn_name("let fn_x = 3;"), None);
}

/// Phrases that point at documents a reader of this repository does not have. Built from
/// parts so that this file does not match itself.
fn outside_references() -> Vec<String> {
    vec![
        ["DES", "IGN"].concat(),
        ["Require", "ment "].concat(),
        ["issue", " "].concat(),
        ["the issue", "'s"].concat(),
        ["../", "shared"].concat(),
    ]
}

/// Files a reader sees: sources, docs and scripts, outside build output.
fn shipped_text_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![repo()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().path()) {
            let name = e.file_name().unwrap().to_string_lossy().to_string();
            if e.is_dir() {
                if !(name.starts_with('.') || name == "target" || name == "out") {
                    stack.push(e);
                }
            } else if [".rs", ".md", ".sh", ".toml"]
                .iter()
                .any(|x| name.ends_with(x))
            {
                out.push(e);
            }
        }
    }
    out
}

#[test]
fn nothing_points_at_documents_outside_the_repository() {
    let phrases = outside_references();
    let mut found = Vec::new();
    for f in shipped_text_files() {
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            for p in &phrases {
                let hit = match line.find(p.as_str()) {
                    // "issue"/"Requirement" count only when a number follows.
                    Some(at) if p.ends_with(' ') => line[at + p.len()..]
                        .chars()
                        .next()
                        .is_some_and(|c| c.is_ascii_digit()),
                    Some(_) => true,
                    None => false,
                };
                if hit {
                    found.push(format!("{}:{}: {}", f.display(), i + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "references to outside documents:\n{}",
        found.join("\n")
    );
}

#[test]
fn readme_is_short_and_starts_with_the_two_commands() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let lines: Vec<&str> = readme.lines().collect();
    // Five minutes of reading: what it is, the commands, the core, robot recordings,
    // embedded and C use, the figures. Details belong in docs/ and in `--help`.
    assert!(lines.len() <= 200, "README.md has {} lines", lines.len());
    let block: Vec<&str> = lines
        .iter()
        .skip_while(|l| !l.starts_with("```"))
        .skip(1)
        .take_while(|l| !l.starts_with("```"))
        .copied()
        .collect();
    assert!(block[0].starts_with("cargo run --release -p sndt-host --bin sndt -- demo"));
    assert!(block[1].starts_with("bash scripts/test.sh"));
    let ci = std::fs::read_to_string(repo().join(".ci/run")).unwrap();
    assert!(ci.lines().any(|l| l.trim() == "exec bash scripts/test.sh"));
}
