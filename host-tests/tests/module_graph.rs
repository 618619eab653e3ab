//! The firmware library's modules import in one direction: between the modules of one parent
//! (src/*.rs, src/app/*.rs, src/control/*.rs, ...) the graph of `crate::` and `super::` paths
//! has no cycle. Read from the sources as text: a path names the sibling module it starts
//! with (a re-exported item of the parent names none). The chip binary's modules (src/main.rs
//! and what it declares) are not the library's and are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// `src/a/b.rs` -> [a, b]; `src/a/mod.rs` -> [a]; `src/lib.rs` -> [].
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut m: Vec<String> = rel.iter().map(|c| c.to_string_lossy().into_owned()).collect();
    if matches!(m.last().map(String::as_str), Some("lib" | "mod")) {
        m.pop();
    }
    m
}

/// The code of a line without its `//` comment (a `//` inside a string literal is rare in
/// these sources and only shortens what is read).
fn code(line: &str) -> &str {
    let mut in_str = false;
    let b = line.as_bytes();
    for i in 0..b.len() {
        match b[i] {
            b'"' if i == 0 || b[i - 1] != b'\\' => in_str = !in_str,
            b'/' if !in_str && b.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
    }
    line
}

fn ident_at(s: &str) -> Option<&str> {
    let end = s.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(s.len());
    (end > 0).then(|| &s[..end])
}

/// Every path `crate::x::..` or `super::x::..` in `text` (a `{a, b}` group gives one path for
/// each of its first names), as names from the crate root.
fn paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut found = Vec::new();
    for line in text.lines() {
        let line = code(line);
        for (start, base) in [("crate::", 0u8), ("super::", 1u8)] {
            let mut rest = line;
            while let Some(i) = rest.find(start) {
                let boundary = rest[..i].chars().last().is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '_' || c == '$'));
                let after = &rest[i + start.len()..];
                rest = after;
                if !boundary {
                    continue;
                }
                let parent: Vec<String> = if base == 0 { Vec::new() } else { module[..module.len().saturating_sub(1)].to_vec() };
                // `super::super::x`
                let (parent, after) = if base == 1 && after.starts_with("super::") {
                    (parent[..parent.len().saturating_sub(1)].to_vec(), &after["super::".len()..])
                } else {
                    (parent, after)
                };
                // the path's names up to its end or a `{a, b}` group (each of whose first names)
                let mut names = parent;
                let mut s = after;
                loop {
                    if let Some(group) = s.strip_prefix('{') {
                        let group = &group[..group.find('}').unwrap_or(group.len())];
                        for g in group.split(',').filter_map(|g| ident_at(g.trim())) {
                            let mut p = names.clone();
                            p.push(g.to_string());
                            found.push(p);
                        }
                        break;
                    }
                    let Some(id) = ident_at(s) else {
                        found.push(names);
                        break;
                    };
                    names.push(id.to_string());
                    s = &s[id.len()..];
                    match s.strip_prefix("::") {
                        Some(r) => s = r,
                        None => {
                            found.push(names);
                            break;
                        }
                    }
                }
            }
        }
    }
    found
}

/// The library's modules and, per parent, the edges between its child modules.
fn graph() -> (BTreeSet<Vec<String>>, BTreeMap<Vec<String>, BTreeSet<(String, String)>>) {
    graph_of("../src", false)
}

/// `graph` of the crate whose sources are at `dir` (relative to host-tests).
/// `skip_tests`: leave out each file's `#[cfg(test)] mod tests` (a test imports what it checks).
fn graph_of(dir: &str, skip_tests: bool) -> (BTreeSet<Vec<String>>, BTreeMap<Vec<String>, BTreeSet<(String, String)>>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    // the binary's modules: src/main.rs and the `mod x;` it declares (none in a library crate)
    let main = std::fs::read_to_string(src.join("main.rs")).unwrap_or_default();
    let bin: BTreeSet<String> = main.lines().filter_map(|l| l.trim().strip_prefix("mod ")?.strip_suffix(';').map(str::to_string)).collect();
    let files: Vec<(Vec<String>, String)> = files
        .iter()
        .map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            let text = if skip_tests { text.split("\n#[cfg(test)]\nmod tests").next().unwrap_or_default().to_string() } else { text };
            (module_of(&src, f), text)
        })
        .filter(|(m, _)| !(m.first().is_some_and(|x| x == "main" || bin.contains(x))))
        .collect();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<(String, String)>> = BTreeMap::new();
    for (m, text) in &files {
        for p in paths(text, m) {
            let common = m.iter().zip(&p).take_while(|(a, b)| a == b).count();
            if common < m.len() && common < p.len() && modules.contains(&p[..=common]) {
                edges.entry(m[..common].to_vec()).or_default().insert((m[common].clone(), p[common].clone()));
            }
        }
    }
    (modules, edges)
}

/// A cycle of `edges`, if there is one.
fn cycle(edges: &BTreeSet<(String, String)>) -> Option<Vec<String>> {
    fn visit(n: &str, edges: &BTreeSet<(String, String)>, state: &mut BTreeMap<String, u8>, stack: &mut Vec<String>) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for (_, to) in edges.iter().filter(|(from, _)| from == n) {
            match state.get(to).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|s| s == to).unwrap();
                    let mut c = stack[at..].to_vec();
                    c.push(to.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(to, edges, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for (from, _) in edges {
        if state.get(from).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(from, edges, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn sibling_modules_import_without_a_cycle() {
    let (modules, edges) = graph();
    // the reading sees the tree: the application's modules and their known imports
    assert!(modules.contains(&vec!["app".to_string(), "commands".to_string()]), "{modules:?}");
    let app = &edges[&vec!["app".to_string()]];
    assert!(app.contains(&("pose".into(), "commands".into())), "{app:?}");
    assert!(app.contains(&("commands".into(), "errors".into())), "{app:?}");
    assert!(edges[&vec![]].contains(&("app".into(), "control".into())));
    for (parent, e) in &edges {
        if let Some(c) = cycle(e) {
            panic!("an import cycle between the modules of crate::{}: {}", parent.join("::"), c.join(" -> "));
        }
    }
}

/// The model's modules (model/src) import in one direction too, between the modules of each
/// parent (the crate's: params, material, de, finger, inverse, ...; finger's and inverse's
/// own), their unit tests left out.
#[test]
fn model_modules_import_without_a_cycle() {
    let (modules, edges) = graph_of("../model/src", true);
    // the reading sees the model: its modules and a known import
    assert!(modules.contains(&vec!["finger".to_string(), "stiffness".to_string()]), "{modules:?}");
    assert!(edges[&vec![]].contains(&("finger".into(), "de".into())), "{:?}", edges[&vec![]]);
    for (parent, e) in &edges {
        if let Some(c) = cycle(e) {
            panic!("an import cycle between the modules of finger_model::{}: {}", parent.join("::"), c.join(" -> "));
        }
    }
}

#[test]
fn app_modules_import_only_those_declared_before_them() {
    // src/app.rs' header says so: its `mod` lines are in import order
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../src/app.rs")).unwrap();
    let order: Vec<String> =
        text.lines().filter_map(|l| l.trim().trim_start_matches("pub ").strip_prefix("mod ")?.strip_suffix(';').map(str::to_string)).collect();
    assert!(order.len() >= 10, "{order:?}");
    let (_, edges) = graph();
    for (from, to) in &edges[&vec!["app".to_string()]] {
        let at = |m: &str| order.iter().position(|o| o == m).unwrap_or_else(|| panic!("app::{m} not declared in src/app.rs"));
        assert!(at(to) < at(from), "app::{from} imports app::{to}, declared after it in src/app.rs");
    }
}

#[test]
fn a_cycle_is_seen() {
    // the check itself: two modules that name each other
    let m = vec!["app".to_string(), "a".to_string()];
    let p = paths("use super::b::X;\nlet y = crate::app::{b, c}; // crate::app::d\n", &m);
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert_eq!(p, vec![s(&["app", "b", "X"]), s(&["app", "b"]), s(&["app", "c"])]);
    let e: BTreeSet<(String, String)> = [("a", "b"), ("b", "c"), ("c", "a")].iter().map(|(x, y)| (x.to_string(), y.to_string())).collect();
    assert_eq!(cycle(&e), Some(vec!["a".into(), "b".into(), "c".into(), "a".into()]));
    let e: BTreeSet<(String, String)> = [("a", "b"), ("b", "c"), ("a", "c")].iter().map(|(x, y)| (x.to_string(), y.to_string())).collect();
    assert_eq!(cycle(&e), None);
}

#[test]
fn each_fault_has_its_console_text() {
    use finger_fw::control::Fault;
    // the console's words (docs/console.md `status` fault=), one per fault, in the enum's order
    let words: Vec<&str> = Fault::ALL.iter().map(|f| f.text()).collect();
    assert_eq!(
        words,
        ["hv-refused", "pwm", "enable", "hv-model", "board card", "qemu image on a real chip", "breakdown", "hv-mismatch", "stack-open", "sensor", "leakage"]
    );
}
