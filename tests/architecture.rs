//! The layers of ARCHITECTURE.md, enforced: every `crate::` path (and `super::`, `self::`, a child
//! module) in `src/` is resolved to the file it names; an import must not run against the
//! documented layer order, and no files may import each other around a cycle.
//!
//! `cargo test --test architecture -- --nocapture print_graph` prints the file graph.
#![cfg(not(target_arch = "wasm32"))] // native: reads the source tree

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Source files by path relative to `src/` ("geometry/sphere.rs").
type Files = BTreeMap<String, String>;

fn read_tree(dir: &Path, prefix: &str, out: &mut Files) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if p.is_dir() {
            read_tree(&p, &format!("{prefix}{name}/"), out);
        } else if name.ends_with(".rs") {
            out.insert(format!("{prefix}{name}"), std::fs::read_to_string(&p).unwrap());
        }
    }
}

fn source_files() -> Files {
    let mut files = Files::new();
    read_tree(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), "", &mut files);
    files
}

/// The layer table of ARCHITECTURE.md: module → row (lowest 0).
fn layers(markdown: &str) -> BTreeMap<String, usize> {
    let start = markdown.find("<!-- layers").expect("ARCHITECTURE.md has the layer table");
    let end = markdown.find("<!-- /layers -->").expect("the layer table ends");
    let mut out = BTreeMap::new();
    let rows = markdown[start..end].lines().filter(|l| l.starts_with('|') && !l.starts_with("|---") && !l.starts_with("| layer"));
    for (row, line) in rows.enumerate() {
        let modules = line.split('|').nth(2).expect("a modules column");
        for m in modules.split(',') {
            let m = m.trim().trim_matches('`');
            assert!(!m.is_empty(), "empty module name in: {line}");
            out.insert(m.to_string(), row);
        }
    }
    out
}

/// The code of a file without comments, string literals (raw ones too) and its `#[cfg(test)]`
/// modules, wherever they sit in the file.
fn code(text: &str) -> String {
    strip_test_modules(&without_comments_and_strings(text))
}

fn without_comments_and_strings(text: &str) -> String {
    let (mut out, mut chars) = (String::new(), text.chars().peekable());
    let mut prev = ' ';
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                let mut prev = ' ';
                for c in chars.by_ref() {
                    if prev == '*' && c == '/' {
                        break;
                    }
                    prev = c;
                }
            }
            // A raw string r"…", r#"…"#, br"…": no escapes inside.
            'r' if !is_ident(prev) || (prev == 'b' && !out[..out.len() - 1].ends_with(is_ident)) => {
                let rest: String = chars.clone().take_while(|&c| c == '#' || c == '"').collect();
                let hashes = rest.chars().take_while(|&c| c == '#').count();
                if rest.len() > hashes && rest.as_bytes()[hashes] == b'"' {
                    for _ in 0..=hashes {
                        chars.next();
                    }
                    let close: String = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
                    let mut body = String::new();
                    for c in chars.by_ref() {
                        body.push(c);
                        if body.ends_with(&close) {
                            break;
                        }
                    }
                    out.push_str("\"\"");
                    prev = '"';
                    continue;
                }
                out.push(c);
            }
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if !escaped && c == '"' {
                        break;
                    }
                    escaped = !escaped && c == '\\';
                }
                out.push_str("\"\"");
            }
            // A char literal ('x', '\n', '"'), not a lifetime.
            '\'' => {
                let rest: String = chars.clone().take(3).collect();
                let len = if rest.starts_with('\\') {
                    rest.find('\'').map_or(0, |i| i + 1)
                } else if rest.chars().nth(1) == Some('\'') {
                    2
                } else {
                    0
                };
                for _ in 0..len {
                    chars.next();
                }
                out.push('\'');
            }
            c => out.push(c),
        }
        prev = out.chars().last().unwrap_or(' ');
    }
    out
}

/// `code` without every `#[cfg(test)] mod name { … }` (matched by braces, so code after a test
/// module is still read).
fn strip_test_modules(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(i) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..i]);
        let after = &rest[i + "#[cfg(test)]".len()..];
        let trimmed = after.trim_start();
        let is_mod = trimmed.trim_start_matches("pub ").trim_start_matches("pub(crate) ").starts_with("mod ");
        match trimmed.find(['{', ';']) {
            Some(open) if is_mod && trimmed.as_bytes()[open] == b'{' => {
                let mut depth = 0;
                let mut end = trimmed.len();
                for (k, c) in trimmed[open..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = open + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                rest = &trimmed[end..];
            }
            _ => {
                out.push_str("#[cfg(test)]");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The module path of a file: "a/b.rs" → [a, b], "a/mod.rs" → [a], "lib.rs" → [].
fn module_path(file: &str) -> Vec<String> {
    let mut parts: Vec<String> = file.trim_end_matches(".rs").split('/').map(String::from).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

/// The file defining the longest prefix of `path` that is a module.
fn resolve(files: &Files, path: &[String]) -> Option<String> {
    (1..=path.len()).rev().find_map(|n| {
        let p = path[..n].join("/");
        [format!("{p}.rs"), format!("{p}/mod.rs")].into_iter().find(|f| files.contains_key(f))
    })
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of the use-tree starting at `s` (after a `::`): `a::b`, `a::{b, c::d}`, `*`.
fn use_tree(s: &str) -> Vec<Vec<String>> {
    let s = s.trim_start();
    if let Some(rest) = s.strip_prefix('{') {
        let (mut depth, mut item, mut out) = (0, String::new(), Vec::new());
        for c in rest.chars() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => break,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    out.extend(use_tree(&item));
                    item.clear();
                    continue;
                }
                _ => {}
            }
            item.push(c);
        }
        out.extend(use_tree(&item));
        return out.into_iter().filter(|p| !p.is_empty()).collect();
    }
    let ident: String = s.chars().take_while(|&c| is_ident(c)).collect();
    if ident.is_empty() || ident == "self" {
        return vec![vec![]];
    }
    let rest = &s[ident.len()..];
    match rest.trim_start().strip_prefix("::") {
        Some(more) => use_tree(more).into_iter().map(|p| [vec![ident.clone()], p].concat()).collect(),
        None => vec![vec![ident]],
    }
}

/// How a path was written: from the crate root (`crate::`, or the library's name in the binary)
/// or relative to the file (`super::`, `self::`, a child module).
#[derive(Clone, Copy, PartialEq)]
enum Root {
    Crate,
    Relative,
}

/// Every module path a file refers to, absolute from the crate root.
fn references(file: &str, text: &str) -> Vec<(Vec<String>, Root)> {
    let code = code(text);
    let here = module_path(file);
    // `mod name;` declarations: a `use name::…` refers to the child.
    let children: BTreeSet<String> = code
        .lines()
        .filter_map(|l| l.trim().trim_start_matches("pub ").strip_prefix("mod ").and_then(|r| r.strip_suffix(';')).map(String::from))
        .collect();
    // `super` is the module above this one; `self` and child modules are this one's.
    let above: Vec<String> = here[..here.len().saturating_sub(1)].to_vec();
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        let at_word = i == 0 || !is_ident(bytes[i - 1] as char) && bytes[i - 1] != b':';
        let rest = &code[i..];
        let base: Option<(usize, Vec<String>, Root)> = if !at_word {
            None
        } else if rest.starts_with("crate::") {
            Some((7, vec![], Root::Crate))
        } else if rest.starts_with("spherical_faces::") && (file.starts_with("cli/") || file == "main.rs") {
            Some((17, vec![], Root::Crate))
        } else if rest.starts_with("super::") {
            let mut base = above.clone();
            let mut skip = 7;
            while code[i + skip..].starts_with("super::") {
                base.pop();
                skip += 7;
            }
            Some((skip, base, Root::Relative))
        } else if rest.starts_with("self::") {
            Some((6, here.clone(), Root::Relative))
        } else {
            let ident: String = rest.chars().take_while(|&c| is_ident(c)).collect();
            (children.contains(&ident) && rest[ident.len()..].starts_with("::")).then(|| (0, here.clone(), Root::Relative))
        };
        match base {
            Some((skip, base, root)) => {
                for p in use_tree(&code[i + skip..]) {
                    out.push(([base.clone(), p].concat(), root));
                }
                i += skip.max(1);
            }
            None => i += rest.chars().next().map_or(1, char::len_utf8),
        }
    }
    out
}

/// The file graph: file → files it imports; and every reference the graph cannot follow.
fn graph(files: &Files) -> (BTreeMap<String, BTreeSet<String>>, Vec<String>) {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut unfollowed = Vec::new();
    for (file, text) in files {
        let entry = g.entry(file.clone()).or_default();
        for alias in aliases_of_crate(&code(text)) {
            unfollowed.push(format!("{file}: `{alias}` hides the paths it names from this check"));
        }
        for (path, root) in references(file, text) {
            match resolve(files, &path) {
                Some(target) if &target != file => {
                    entry.insert(target);
                }
                Some(_) => {}
                None if root == Root::Relative => {}
                None if path.is_empty() => unfollowed.push(format!("{file}: a glob or `self` of `crate` hides the paths it names from this check")),
                None => unfollowed.push(format!("{file}: `crate::{}` names no module file (an item or re-export of lib.rs?)", path.join("::"))),
            }
        }
    }
    (g, unfollowed)
}

/// `use crate as x;` and `extern crate self as x;`: names of the crate root this check cannot follow.
fn aliases_of_crate(code: &str) -> Vec<String> {
    let words: Vec<&str> = code.split(|c: char| !is_ident(c)).filter(|w| !w.is_empty()).collect();
    words.windows(3).filter(|w| matches!(w, ["crate", "as", _] | ["crate", "self", "as"])).map(|w| w.join(" ")).collect()
}

/// The top-level module of a file ("geometry/mesh/mod.rs" → "geometry", "cli/args.rs" → "cli").
fn top(file: &str) -> String {
    file.split('/').next().unwrap().trim_end_matches(".rs").to_string()
}

/// Everything wrong with the imports of `files` against `layers`.
fn violations(files: &Files, layers: &BTreeMap<String, usize>) -> Vec<String> {
    let (g, mut out) = graph(files);
    for (from, targets) in &g {
        let Some(&lf) = layers.get(&top(from)) else {
            out.push(format!("{from}: module `{}` is not in the layer table", top(from)));
            continue;
        };
        for to in targets {
            if top(to) == top(from) {
                continue;
            }
            match layers.get(&top(to)) {
                Some(&lt) if lt < lf => {}
                Some(_) => out.push(format!("{from} -> {to}: `{}` may not import `{}` (not on a lower layer)", top(from), top(to))),
                None => out.push(format!("{from} -> {to}: module `{}` is not in the layer table", top(to))),
            }
        }
    }
    // Cycles: a depth-first search that reports every back edge.
    let mut state: BTreeMap<&str, u8> = BTreeMap::new();
    fn visit<'a>(
        n: &'a str,
        g: &'a BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<&'a str, u8>,
        stack: &mut Vec<&'a str>,
        out: &mut Vec<String>,
    ) {
        state.insert(n, 1);
        stack.push(n);
        for m in g.get(n).into_iter().flatten() {
            match state.get(m.as_str()) {
                Some(1) => {
                    let start = stack.iter().position(|s| s == m).unwrap();
                    out.push(format!("import cycle: {} -> {m}", stack[start..].join(" -> ")));
                }
                Some(_) => {}
                None => visit(m, g, state, stack, out),
            }
        }
        stack.pop();
        state.insert(n, 2);
    }
    for n in g.keys() {
        if !state.contains_key(n.as_str()) {
            visit(n, &g, &mut state, &mut Vec::new(), &mut out);
        }
    }
    out
}

fn documented_layers() -> BTreeMap<String, usize> {
    layers(&std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md")).unwrap())
}

#[test]
fn imports_follow_the_documented_layers_without_cycles() {
    let files = source_files();
    let layers = documented_layers();
    // Every top-level module of src/ has its row.
    for file in files.keys() {
        assert!(layers.contains_key(&top(file)), "{file}: module `{}` is missing from ARCHITECTURE.md's layer table", top(file));
    }
    let edges: usize = graph(&files).0.values().map(BTreeSet::len).sum();
    assert!(edges > 200, "only {edges} imports found: the scanner is broken");
    let v = violations(&files, &layers);
    assert!(v.is_empty(), "{} violations:\n{}", v.len(), v.join("\n"));
}

/// The toolkit never imports a method, the writers, the pipeline or a front end.
#[test]
fn the_toolkit_imports_no_method() {
    let layers = documented_layers();
    let row = layers["st_adapted"];
    for m in ["geometry", "reference", "congruence", "solver", "remeshing", "panels"] {
        assert!(layers[m] < row, "{m} is not below the methods");
    }
    for m in methods(&layers) {
        assert!(layers[&m] < layers["export"] && layers[&m] < layers["pipeline"] && layers[&m] < layers["web"]);
    }
}

/// The methods: the modules on the methods row of the layer table (as many as there are).
fn methods(layers: &BTreeMap<String, usize>) -> Vec<String> {
    let row = layers["st_adapted"];
    layers.iter().filter(|(_, &l)| l == row).map(|(m, _)| m.clone()).collect()
}

/// The places of the recipe where a method is named outside its folder, its stage file and its
/// view: the protocol's line, the view registry, the CLI's subcommand, the module lines of
/// `lib.rs` and `stages/mod.rs`, and the benchmark workloads, which measure named methods.
const SEAMS: [&str; 6] = ["pipeline/protocol.rs", "web/app/views/mod.rs", "cli/methods.rs", "lib.rs", "pipeline/stages/mod.rs", "bench_workloads.rs"];

/// The stage type a method's line in `methods!` names (`Sq => stages::sq::SqStage`).
fn stage_type(protocol: &str, method: &str) -> Option<String> {
    let needle = format!("stages::{method}::");
    let line = protocol.lines().find(|l| l.contains("=>") && l.contains(&needle))?;
    let after = &line[line.find(&needle)? + needle.len()..];
    Some(after.chars().take_while(|&c| is_ident(c)).collect())
}

/// The recipe of ARCHITECTURE.md for every method on the methods row: its folder with a driver,
/// `params.rs` (with its link fields), `guarantees.rs` and `report.rs`, its stage file
/// implementing `Method`, its view module and its line in `views::views`, its line in the
/// protocol's `methods!` and its CLI subcommand. No count: a fourth method passes the same way.
#[test]
fn every_method_follows_the_recipe() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md")).unwrap();
    assert!(doc.contains("<!-- recipe") && doc.contains("<!-- /recipe -->"), "ARCHITECTURE.md shows the recipe");
    let files = source_files();
    let methods = methods(&documented_layers());
    assert!(!methods.is_empty(), "the methods row of the layer table is empty");
    let (views, protocol, cli) = (&files["web/app/views/mod.rs"], &files["pipeline/protocol.rs"], &files["cli/methods.rs"]);
    for m in &methods {
        for part in [
            format!("{m}/mod.rs"),
            format!("{m}/params.rs"),
            format!("{m}/guarantees.rs"),
            format!("{m}/report.rs"),
            format!("pipeline/stages/{m}.rs"),
            format!("web/app/views/{m}.rs"),
        ] {
            assert!(files.contains_key(&part), "{m}: src/{part} is missing (ARCHITECTURE.md, How to add a method)");
        }
        assert!(files[&format!("{m}/params.rs")].contains("impl LinkFields for"), "{m}: its params.rs writes no link fields");
        let stage = stage_type(protocol, m).unwrap_or_else(|| panic!("{m}: no line in the protocol's methods!"));
        assert!(files[&format!("pipeline/stages/{m}.rs")].contains(&format!("impl Method for {stage}")), "{m}: its stage file implements no Method");
        assert!(views.contains(&format!("{m}::")), "{m}: no line in views::views");
        assert!(cli.contains("MethodArgs<") && code(cli).contains(&stage), "{m}: no subcommand in cli/methods.rs");
    }
}

/// A method is named outside its folder, its stage file and its view only in the recipe's
/// places ([`SEAMS`]): the session, the design link, the stage ids, the worker and the rest of the
/// app go through the seam.
#[test]
fn no_file_outside_the_recipe_names_a_method() {
    let files = source_files();
    let methods = methods(&documented_layers());
    let protocol = &files["pipeline/protocol.rs"];
    let mut found = Vec::new();
    for m in &methods {
        let stage = stage_type(protocol, m).unwrap_or_default();
        let own = |f: &str| f.starts_with(&format!("{m}/")) || f == format!("pipeline/stages/{m}.rs") || f == format!("web/app/views/{m}.rs");
        for (file, text) in files.iter().filter(|(f, _)| !own(f) && !SEAMS.contains(&f.as_str())) {
            let code = code(text);
            let words: Vec<&str> = code.split(|c: char| !is_ident(c)).collect();
            let path = code.contains(&format!("{m}::"))
                && code.match_indices(&format!("{m}::")).any(|(i, _)| i == 0 || !is_ident(code.as_bytes()[i - 1] as char));
            if path || (!stage.is_empty() && words.contains(&stage.as_str())) {
                found.push(format!("{file} names `{m}`"));
            }
        }
    }
    assert!(found.is_empty(), "outside the recipe's places:\n{}", found.join("\n"));
}

/// The checker itself: it finds an upward import, a cycle between files, an import through a
/// `use` group and through `super::`, and it does not flag what is allowed.
#[test]
fn the_checker_catches_forbidden_imports() {
    let layers: BTreeMap<String, usize> = [("geometry", 0), ("panels", 1), ("st_adapted", 2)].map(|(m, l)| (m.to_string(), l)).into_iter().collect();
    let file = |p: &str, s: &str| (p.to_string(), s.to_string());
    let clean: Files = [
        file("geometry/mod.rs", "pub mod sphere;\n"),
        file("geometry/sphere.rs", "pub struct Sphere;\n"),
        file("panels/mod.rs", "pub mod arc;\nuse crate::geometry::sphere::Sphere;\n// use crate::st_adapted::X; (a comment)\n"),
        file("panels/arc.rs", "use super::mod_item;\nfn f() -> &'static str { \"crate::st_adapted::x\" }\n"),
        file(
            "st_adapted/mod.rs",
            "use crate::{geometry::sphere::Sphere, panels::arc};\n#[cfg(test)]\nmod tests {\n    use crate::st_adapted::x;\n}\n",
        ),
    ]
    .into_iter()
    .collect();
    assert!(violations(&clean, &layers).is_empty(), "{:?}", violations(&clean, &layers));
    // A method import from the toolkit, inside a use group.
    let mut upward = clean.clone();
    upward.insert("panels/arc.rs".into(), "use crate::{geometry::sphere::Sphere, st_adapted::Result};\n".into());
    let v = violations(&upward, &layers);
    assert!(v.iter().any(|s| s.contains("panels/arc.rs -> st_adapted/mod.rs") && s.contains("may not import")), "{v:?}");
    // Two files importing each other.
    let mut cycle = clean.clone();
    cycle.insert("geometry/sphere.rs".into(), "use super::circle::Circle;\n".into());
    cycle.insert("geometry/circle.rs".into(), "use crate::geometry::sphere::Sphere;\n".into());
    let v = violations(&cycle, &layers);
    assert!(v.iter().any(|s| s.contains("import cycle") && s.contains("geometry/sphere.rs") && s.contains("geometry/circle.rs")), "{v:?}");
    // A module missing from the table.
    let mut unknown = clean;
    unknown.insert("web.rs".into(), "use crate::panels::arc::Arc;\n".into());
    let v = violations(&unknown, &layers);
    assert!(v.iter().any(|s| s.contains("`web` is not in the layer table")), "{v:?}");
}

/// The five ways around the checker are caught: an unresolved `crate::` path (an item or a
/// re-export of lib.rs), a glob of `crate`, an alias of `crate`, an import after a test module,
/// and an import after a raw string ending in a backslash.
#[test]
fn the_checker_cannot_be_fooled() {
    let layers: BTreeMap<String, usize> = [("geometry", 0), ("panels", 1), ("st_adapted", 2)].map(|(m, l)| (m.to_string(), l)).into_iter().collect();
    let base: Files = [
        ("geometry/mod.rs", "pub struct Sphere;\n"),
        ("panels/mod.rs", "use crate::geometry::Sphere;\n"),
        ("st_adapted/mod.rs", "pub struct Result;\n"),
        ("lib.rs", "pub use st_adapted::Result;\n"),
    ]
    .map(|(p, s)| (p.to_string(), s.to_string()))
    .into_iter()
    .collect();
    let mut layers_with_root = layers.clone();
    layers_with_root.insert("lib".into(), 3);
    assert!(violations(&base, &layers_with_root).is_empty(), "{:?}", violations(&base, &layers_with_root));
    let with = |text: &str| {
        let mut files = base.clone();
        files.insert("panels/mod.rs".into(), text.into());
        violations(&files, &layers_with_root)
    };
    let upward = |v: &[String]| v.iter().any(|s| s.contains("panels/mod.rs -> st_adapted/mod.rs"));
    // 1. A path through a re-export of lib.rs names no module file.
    let v = with("use crate::Result;\n");
    assert!(v.iter().any(|s| s.contains("`crate::Result` names no module file")), "{v:?}");
    // 2. A glob of the crate root.
    let v = with("use crate::*;\nfn f() -> Result { todo!() }\n");
    assert!(v.iter().any(|s| s.contains("a glob or `self` of `crate`")), "{v:?}");
    // 3. An alias of the crate root.
    let v = with("use crate as root;\nuse root::st_adapted::Result;\n");
    assert!(v.iter().any(|s| s.contains("`crate as root`")), "{v:?}");
    let v = with("extern crate self as root;\n");
    assert!(v.iter().any(|s| s.contains("`crate self as`")), "{v:?}");
    // 4. An import after the test module is still read; the test module's own imports are not.
    let v = with("#[cfg(test)]\nmod tests {\n    use crate::st_adapted::Result;\n}\nuse crate::st_adapted::Result;\n");
    assert!(upward(&v), "{v:?}");
    assert!(with("#[cfg(test)]\nmod tests {\n    use crate::st_adapted::Result;\n}\nfn f() {}\n").is_empty());
    // 5. A raw string ending in a backslash does not swallow the code after it.
    let v = with("const P: &str = r\"C:\\\";\nuse crate::st_adapted::Result;\n");
    assert!(upward(&v), "{v:?}");
    let v = with("const P: &str = r#\"a \"quoted\" \\\"#;\nuse crate::st_adapted::Result;\n");
    assert!(upward(&v), "{v:?}");
    assert!(with("const P: &str = r\"use crate::st_adapted::Result;\";\n").is_empty());
}

#[test]
fn print_graph() {
    let files = source_files();
    for (from, targets) in graph(&files).0 {
        for to in targets {
            println!("{from} -> {to}");
        }
    }
}
