//! Dependencies between the library's modules point one way: no two sibling modules (nor
//! two top-level modules) use each other, directly or through others.
//!
//! The graph is read from the sources: every `crate::…` and `super::…` path outside
//! comments and test modules (`#[cfg(test)]` to the end of the file, or a `tests.rs`), `use` groups
//! expanded, each resolved to the deepest module file it names. A use of an ancestor (a
//! child using its parent's types, a parent re-exporting its children) is not a
//! dependency between units; every other edge A → B is recorded between the two siblings
//! under their lowest common ancestor, and each level must be acyclic.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

type Module = Vec<String>;

/// Every module file under `src/` (lib.rs is the crate root `[]`; main.rs is the binary,
/// not a module).
fn modules(root: &Path) -> BTreeMap<Module, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel = path.strip_prefix(root).unwrap();
            let mut parts: Vec<String> = rel
                .iter()
                .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
                .collect();
            // `main.rs` is the binary; a `tests.rs` is a module's `#[cfg(test)] mod tests;`,
            // left out like a test module written inline.
            if parts == ["main"] || parts.last().is_some_and(|p| p == "tests") {
                continue;
            }
            if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
                parts.pop();
            }
            out.insert(parts, std::fs::read_to_string(&path).unwrap());
        }
    }
    out
}

/// The code of a file without comments, string contents and its test module.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                i += 1;
            }
            i += 2;
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else {
            out.push(b[i] as char);
            i += 1;
        }
    }
    out
}

fn ident_at(s: &[u8], mut i: usize) -> (String, usize) {
    let start = i;
    while i < s.len() && (s[i].is_ascii_alphanumeric() || s[i] == b'_') {
        i += 1;
    }
    (String::from_utf8_lossy(&s[start..i]).into_owned(), i)
}

fn skip_ws(s: &[u8], mut i: usize) -> usize {
    while i < s.len() && s[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// The paths starting at `i` (after a `crate::`/`super::` prefix), `{…}` groups expanded.
fn paths_at(s: &[u8], i: usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let mut path = prefix;
    let mut i = skip_ws(s, i);
    loop {
        if s.get(i) == Some(&b'{') {
            i += 1;
            loop {
                i = skip_ws(s, i);
                match s.get(i) {
                    Some(b'}') => return i + 1,
                    Some(b',') => i += 1,
                    None => return i,
                    _ => {
                        let before = i;
                        i = paths_at(s, i, path.clone(), out);
                        if i == before {
                            i += 1;
                        }
                    }
                }
            }
        }
        let (name, next) = ident_at(s, i);
        if name.is_empty() {
            out.push(path);
            return i;
        }
        path.push(name);
        i = next;
        if s.get(i) == Some(&b':') && s.get(i + 1) == Some(&b':') {
            i += 2;
        } else {
            out.push(path);
            return i;
        }
    }
}

/// The modules `module`'s code refers to by path.
fn references(module: &Module, text: &str) -> Vec<Vec<String>> {
    let code = code(text);
    let s = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let boundary = i == 0 || !(s[i - 1].is_ascii_alphanumeric() || s[i - 1] == b'_');
        if boundary && s[i..].starts_with(b"crate::") {
            i = paths_at(s, i + 7, Vec::new(), &mut out);
        } else if boundary && s[i..].starts_with(b"super::") {
            // `super` of a file module is its parent; of a mod.rs module, the grandparent.
            let mut base = module.clone();
            base.pop();
            let mut j = i + 7;
            while s[j..].starts_with(b"super::") {
                base.pop();
                j += 7;
            }
            i = paths_at(s, j, base, &mut out);
        } else {
            i += 1;
        }
    }
    out
}

/// The deepest known module a path names.
fn resolve(path: &[String], known: &BTreeMap<Module, String>) -> Module {
    (0..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| known.contains_key(p))
        .unwrap_or_default()
}

fn is_prefix(a: &Module, b: &Module) -> bool {
    a.len() <= b.len() && b[..a.len()] == a[..]
}

/// A cycle in `edges`, if any (depth-first search).
fn find_cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in edges.get(n).into_iter().flatten() {
            match state.get(m.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|x| x == m).unwrap();
                    let mut cycle = stack[at..].to_vec();
                    cycle.push(m.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(m, edges, state, stack) {
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
    for n in edges.keys() {
        if state.get(n.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, edges, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn no_module_cycles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let known = modules(&root);
    assert!(known.contains_key(&vec!["sim".to_string(), "cpu".to_string()]));
    // Per parent module: edges between its children, with the file-level edge behind each.
    let mut levels: BTreeMap<Module, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    let mut why: BTreeMap<(Module, String, String), String> = BTreeMap::new();
    for (module, text) in &known {
        for path in references(module, text) {
            let target = resolve(&path, &known);
            if is_prefix(&target, module) || is_prefix(module, &target) {
                continue;
            }
            let common = module
                .iter()
                .zip(&target)
                .take_while(|(a, b)| a == b)
                .count();
            let parent = module[..common].to_vec();
            let (a, b) = (module[common].clone(), target[common].clone());
            levels
                .entry(parent.clone())
                .or_default()
                .entry(a.clone())
                .or_default()
                .insert(b.clone());
            why.entry((parent, a, b))
                .or_insert_with(|| format!("{} uses {}", module.join("::"), path.join("::")));
        }
    }
    let mut cycles = Vec::new();
    for (parent, edges) in &levels {
        if let Some(cycle) = find_cycle(edges) {
            let steps: Vec<String> = cycle
                .windows(2)
                .map(|w| why[&(parent.clone(), w[0].clone(), w[1].clone())].clone())
                .collect();
            cycles.push(format!(
                "in crate::{}: {} ({})",
                parent.join("::"),
                cycle.join(" → "),
                steps.join("; ")
            ));
        }
    }
    assert!(cycles.is_empty(), "module cycles:\n{}", cycles.join("\n"));
}

#[test]
fn the_reader_sees_a_known_edge() {
    // The parser must see `use` groups and `super` paths, or the test above proves nothing.
    let known: BTreeMap<Module, String> = [
        (vec![], String::new()),
        (vec!["a".into()], String::new()),
        (vec!["a".into(), "x".into()], String::new()),
        (vec!["b".into()], String::new()),
    ]
    .into_iter()
    .collect();
    let text = "// use crate::b;\nuse crate::{b::Thing, a};\nfn f() { super::x::g(); }";
    let refs: Vec<Module> = references(&vec!["a".into(), "y".into()], text)
        .iter()
        .map(|p| resolve(p, &known))
        .collect();
    assert!(refs.contains(&vec!["b".to_string()]), "{refs:?}");
    assert!(
        refs.contains(&vec!["a".to_string(), "x".to_string()]),
        "{refs:?}"
    );
    assert_eq!(refs.len(), 3, "the comment is not a reference: {refs:?}");
}
