//! The import graph of `src/`: no cycle between files, and no import against the layering
//! that ARCHITECTURE.md states. The graph is read from the source: every `use` of
//! `crate::`, `super::`, `self::` or a child module, and every `crate::…` path in the code,
//! resolved to the file that defines the item (following `pub use` re-exports, which are
//! a module's face, not a dependency). Test modules (`#[cfg(test)]` onwards) are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A crate's files by module path (`["scene", "load"]`), and each file's text.
struct Crate {
    files: BTreeMap<Vec<String>, (PathBuf, String)>,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `.rs` files under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module path of `file` (relative to `src/`): `scene/mod.rs` and `scene.rs` are
/// `["scene"]`; the crate roots are `[]`.
fn module_path(file: &Path) -> Vec<String> {
    let mut parts: Vec<String> = file
        .with_extension("")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The library crate (everything but the binary's `main.rs` and `cli/`) or the binary's.
fn read_crate(binary: bool) -> Crate {
    let src = root().join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    let mut files = BTreeMap::new();
    for path in paths {
        let rel = path.strip_prefix(&src).unwrap().to_path_buf();
        let in_binary = rel == Path::new("main.rs") || rel.starts_with("cli");
        if in_binary == binary {
            let text = std::fs::read_to_string(&path).unwrap();
            files.insert(module_path(&rel), (rel, text));
        }
    }
    Crate { files }
}

/// `text` without comments and without its test module.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths of a `use` tree: `a::{b::C, d}` is `a::b::C` and `a::d`.
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let t = tree.split(" as ").next().unwrap_or(tree).trim();
        return vec![t.to_string()];
    };
    let prefix = &tree[..open];
    let close = tree.rfind('}').filter(|&c| c > open).unwrap_or(tree.len());
    let inner = &tree[open + 1..close];
    let mut out = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                out.extend(
                    expand(&inner[start..i])
                        .into_iter()
                        .map(|p| format!("{prefix}{p}")),
                );
                start = i + 1;
            }
            _ => {}
        }
    }
    if !inner[start..].trim().is_empty() {
        out.extend(
            expand(&inner[start..])
                .into_iter()
                .map(|p| format!("{prefix}{p}")),
        );
    }
    out
}

/// The `use` statements of `code`: (whether it is a `pub use`, its paths). A statement
/// starts a line (`use`, `pub use`, `pub(crate) use`) and runs to its `;`.
fn uses(code: &str) -> Vec<(bool, Vec<String>)> {
    let mut out = Vec::new();
    let mut offset = 0;
    for line in code.split_inclusive('\n') {
        let trimmed = line.trim_start();
        let (public, rest) = if let Some(r) = trimmed.strip_prefix("use ") {
            (false, Some(r))
        } else if let Some(r) = trimmed.strip_prefix("pub") {
            let r = r.trim_start();
            let r = match r.strip_prefix('(') {
                Some(v) => v.split_once(')').map_or(r, |(_, after)| after.trim_start()),
                None => r,
            };
            (true, r.strip_prefix("use "))
        } else {
            (false, None)
        };
        if let Some(rest) = rest {
            let start = offset + (line.len() - rest.len());
            if let Some(end) = code[start..].find(';') {
                out.push((public, expand(&code[start..start + end])));
            }
        }
        offset += line.len();
    }
    out
}

/// The `crate::…` paths written in the code outside `use` statements.
fn inline_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = code[from..].find("crate::") {
        let at = from + i;
        let ident_before = code[..at]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':');
        let len = code[at..]
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(code.len() - at);
        if !ident_before {
            out.push(code[at..at + len].trim_end_matches(':').to_string());
        }
        from = at + len.max(1);
    }
    out
}

impl Crate {
    /// The file that defines what `path` (as written in module `me`) names, following
    /// re-exports; `None` for another crate's item.
    fn resolve(&self, me: &[String], path: &str, depth: usize) -> Option<Vec<String>> {
        let mut segs: Vec<&str> = path.split("::").map(str::trim).collect();
        segs.retain(|s| !s.is_empty());
        let mut base: Vec<String> = match segs.first().copied()? {
            "crate" => {
                segs.remove(0);
                Vec::new()
            }
            "self" => {
                segs.remove(0);
                me.to_vec()
            }
            "super" => {
                let mut b = me.to_vec();
                while segs.first() == Some(&"super") {
                    segs.remove(0);
                    b.pop();
                }
                b
            }
            first => {
                let mut child = me.to_vec();
                child.push(first.to_string());
                if !self.files.contains_key(&child) {
                    return None;
                }
                me.to_vec()
            }
        };
        // The longest prefix that is a module.
        let mut rest = segs.as_slice();
        while let Some((first, tail)) = rest.split_first() {
            let mut next = base.clone();
            next.push(first.to_string());
            if !self.files.contains_key(&next) {
                break;
            }
            base = next;
            rest = tail;
        }
        // An item the module re-exports lives where the re-export points.
        if let (Some(item), true) = (rest.first(), depth < 8)
            && let Some((_, text)) = self.files.get(&base)
        {
            for (public, paths) in uses(&code(text)) {
                if !public {
                    continue;
                }
                for p in paths {
                    let last = p.rsplit("::").next().unwrap_or("").trim();
                    if (last == *item || last == "*")
                        && let Some(found) = self.resolve(&base, &p, depth + 1)
                    {
                        return Some(found);
                    }
                }
            }
        }
        Some(base)
    }

    /// Every dependency between two files of the crate, with a re-export not counted.
    fn edges(&self) -> BTreeSet<(Vec<String>, Vec<String>)> {
        let mut edges = BTreeSet::new();
        for (me, (_, text)) in &self.files {
            let code = code(text);
            let mut paths: Vec<String> = uses(&code)
                .into_iter()
                .filter(|(public, _)| !public)
                .flat_map(|(_, p)| p)
                .collect();
            paths.extend(inline_paths(&code));
            for p in paths {
                if let Some(to) = self.resolve(me, &p, 0)
                    && &to != me
                    && !to.is_empty()
                {
                    edges.insert((me.clone(), to));
                }
            }
        }
        edges
    }
}

/// A cycle among `edges`, as the files around it, if there is one.
fn find_cycle(edges: &BTreeSet<(Vec<String>, Vec<String>)>) -> Option<Vec<String>> {
    let mut next: BTreeMap<&Vec<String>, Vec<&Vec<String>>> = BTreeMap::new();
    for (a, b) in edges {
        next.entry(a).or_default().push(b);
    }
    // Depth-first search with the path on a stack: 0 unseen, 1 on the path, 2 done.
    fn visit<'a>(
        v: &'a Vec<String>,
        next: &BTreeMap<&'a Vec<String>, Vec<&'a Vec<String>>>,
        state: &mut BTreeMap<&'a Vec<String>, u8>,
        path: &mut Vec<&'a Vec<String>>,
    ) -> Option<Vec<String>> {
        state.insert(v, 1);
        path.push(v);
        for &w in next.get(v).into_iter().flatten() {
            match state.get(w).copied().unwrap_or(0) {
                1 => {
                    let start = path.iter().position(|p| *p == w).unwrap_or(0);
                    let mut cycle: Vec<String> =
                        path[start..].iter().map(|p| p.join("::")).collect();
                    cycle.push(w.join("::"));
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(w, next, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(v, 2);
        None
    }
    let mut state = BTreeMap::new();
    let starts: Vec<&Vec<String>> = next.keys().copied().collect();
    for v in starts {
        if state.get(v).copied().unwrap_or(0) == 0
            && let Some(c) = visit(v, &next, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

/// The layers ARCHITECTURE.md states: each top-level module of the library and its layer
/// (the numbered lines between `<!-- layers -->` and `<!-- /layers -->`).
fn layers() -> BTreeMap<String, usize> {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let start = text
        .find("<!-- layers -->")
        .expect("ARCHITECTURE.md states the layers");
    let end = text.find("<!-- /layers -->").expect("the layers end");
    let mut out = BTreeMap::new();
    for line in text[start..end].lines().skip(1) {
        let Some((number, modules)) = line.split_once(". ") else {
            continue;
        };
        let Ok(layer) = number.trim().parse::<usize>() else {
            continue;
        };
        for m in modules.split(',') {
            out.insert(m.trim().trim_matches('`').to_string(), layer);
        }
    }
    out
}

/// The imports that break the layering: from a module to one on its own layer or below
/// it in ARCHITECTURE.md's list (a later line), or from a module the list lacks.
fn layer_problems(
    edges: &BTreeSet<(Vec<String>, Vec<String>)>,
    layers: &BTreeMap<String, usize>,
) -> Vec<String> {
    let mut problems = Vec::new();
    for (a, b) in edges {
        let (ta, tb) = (&a[0], &b[0]);
        if ta == tb {
            continue;
        }
        match (layers.get(ta), layers.get(tb)) {
            (Some(la), Some(lb)) if la > lb => {}
            (Some(_), Some(_)) => problems.push(format!(
                "{} imports {}, which is not on a layer above it",
                a.join("::"),
                b.join("::")
            )),
            _ => problems.push(format!(
                "{} or {} is missing from ARCHITECTURE.md's layers",
                ta, tb
            )),
        }
    }
    problems
}

#[test]
fn no_import_cycle_between_files() {
    for binary in [false, true] {
        let krate = read_crate(binary);
        let edges = krate.edges();
        assert!(
            edges.len() > 100 || binary,
            "only {} imports read",
            edges.len()
        );
        if let Some(cycle) = find_cycle(&edges) {
            panic!("an import cycle: {}", cycle.join(" -> "));
        }
    }
}

#[test]
fn imports_follow_the_layers_architecture_states() {
    let krate = read_crate(false);
    let edges = krate.edges();
    let layers = layers();
    let problems = layer_problems(&edges, &layers);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // Every module is placed.
    for module in krate.files.keys().filter_map(|m| m.first()) {
        assert!(
            layers.contains_key(module),
            "{module} is missing from ARCHITECTURE.md's layers"
        );
    }
}

/// The checks can fail: a loop or an upward import added to the real graph is caught.
#[test]
fn the_checks_catch_a_loop_and_an_upward_import() {
    let krate = read_crate(false);
    let mut edges = krate.edges();
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    // The graph resolves re-exports to the defining file.
    assert!(edges.contains(&(m("scene::texture"), m("scene::source"))));
    assert!(edges.contains(&(m("render::cpu"), m("render::job"))));
    let mut looped = edges.clone();
    looped.insert((m("scene::source"), m("scene::texture")));
    assert!(find_cycle(&looped).is_some());
    edges.insert((m("scene::load"), m("render::cpu")));
    assert!(!layer_problems(&edges, &layers()).is_empty());
}
