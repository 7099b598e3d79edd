//! The architecture as a test (DESIGN: dependencies point downwards): no
//! file in `src/` imports, directly or through others, a file that imports
//! it; each top-level module imports only the modules below it; no file in
//! `src/` grows past 600 lines. Imports are read from the source as the
//! compiler resolves `crate::`, `super::` and `self::` paths (a module's
//! `mod.rs` re-exporting its own children is not an edge).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// What each top-level module may import (besides itself): the layers,
/// lowest first. `main`/`cli` is the binary.
const ALLOWED: &[(&str, &[&str])] = &[
    ("error", &[]),
    ("gpu", &["error"]),
    ("limits", &["error"]),
    ("frame", &["error", "limits"]),
    ("spatial", &["gpu"]),
    ("tf", &["error", "gpu", "limits"]),
    ("volume", &["error", "frame", "gpu", "limits", "tf"]),
    ("desc", &["error", "gpu", "limits", "tf", "volume"]),
    ("prims", &["error", "gpu", "volume"]),
    ("scene", &["error", "frame"]),
    ("octree", &["error", "frame", "gpu", "scene", "spatial"]),
    (
        "accel",
        &[
            "desc", "error", "gpu", "limits", "octree", "prims", "spatial", "tf", "volume",
        ],
    ),
    ("parallel", &["desc", "error", "volume"]),
    (
        "render",
        &["accel", "desc", "error", "frame", "gpu", "limits", "tf", "volume"],
    ),
    (
        "bench",
        &[
            "accel", "desc", "error", "frame", "gpu", "limits", "render", "tf", "volume",
        ],
    ),
];

type Module = Vec<String>;

struct Crate {
    /// Module path -> file.
    files: BTreeMap<Module, PathBuf>,
}

fn module_of(src: &Path, file: &Path) -> Module {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The source without comments, string literals (raw ones too) and char
/// literals: paths in docs or messages are not imports.
fn code_of(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < c.len() {
        let at = |i: usize, k: usize| c.get(i + k).copied().unwrap_or('\0');
        match c[i] {
            '/' if at(i, 1) == '/' => {
                while i < c.len() && c[i] != '\n' {
                    i += 1;
                }
            }
            '/' if at(i, 1) == '*' => {
                let mut depth = 0;
                while i < c.len() {
                    if c[i] == '/' && at(i, 1) == '*' {
                        depth += 1;
                        i += 2;
                    } else if c[i] == '*' && at(i, 1) == '/' {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
                out.push(' ');
            }
            'r' if (at(i, 1) == '"' || at(i, 1) == '#')
                && (i == 0 || !c[i - 1].is_alphanumeric() && c[i - 1] != '_') =>
            {
                // r"..." or r#"..."#
                let mut j = i + 1;
                let mut hashes = 0;
                while c.get(j) == Some(&'#') {
                    hashes += 1;
                    j += 1;
                }
                if c.get(j) != Some(&'"') {
                    out.push('r');
                    i += 1;
                    continue;
                }
                j += 1;
                loop {
                    if j >= c.len() {
                        break;
                    }
                    if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                out.push_str("\"\"");
                i = j;
            }
            '"' => {
                i += 1;
                while i < c.len() && c[i] != '"' {
                    i += if c[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            // A char literal ('x', '\n', '"'); a lifetime ('a) has no closing quote.
            '\'' if at(i, 1) == '\\' => {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push_str("' '");
            }
            '\'' if at(i, 2) == '\'' => {
                i += 3;
                out.push_str("' '");
            }
            ch => {
                out.push(ch);
                i += 1;
            }
        }
    }
    out
}

/// `a::{b, c::{d, e}}` -> `a::b`, `a::c::d`, `a::c::e`.
fn expand(tree: &str) -> Vec<String> {
    let Some(open) = tree.find('{') else {
        return vec![tree.to_string()];
    };
    let close = tree.rfind('}').unwrap();
    let (head, inner) = (&tree[..open], &tree[open + 1..close]);
    let mut items = Vec::new();
    let (mut depth, mut cur) = (0, String::new());
    for c in inner.chars() {
        match c {
            ',' if depth == 0 => items.push(std::mem::take(&mut cur)),
            '{' => {
                depth += 1;
                cur.push(c)
            }
            '}' => {
                depth -= 1;
                cur.push(c)
            }
            _ => cur.push(c),
        }
    }
    items.push(cur);
    items
        .into_iter()
        .filter(|i| !i.is_empty())
        .flat_map(|i| {
            let i = i.split(" as ").next().unwrap_or("").to_string();
            if i == "self" {
                vec![head.trim_end_matches("::").to_string()]
            } else {
                expand(&format!("{head}{i}"))
            }
        })
        .collect()
}

/// Every `crate::`/`super::`/`self::` path a file names.
fn paths_in(code: &str) -> Vec<String> {
    let mut paths = Vec::new();
    for stmt in code.split(';') {
        if let Some(i) = stmt.find("use ") {
            let body: String = stmt[i + 4..].chars().filter(|c| !c.is_whitespace()).collect();
            paths.extend(expand(&body));
        }
    }
    let bytes = code.as_bytes();
    for start in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(i) = code[from..].find(start) {
            let at = from + i;
            let boundary = at == 0 || !(bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_');
            let end = code[at..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .map_or(code.len(), |e| at + e);
            if boundary {
                paths.push(code[at..end].trim_end_matches(':').to_string());
            }
            from = end.max(at + 1);
        }
    }
    paths
}

impl Crate {
    fn read() -> (Crate, Vec<(Module, String)>) {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        walk(&src, &mut files);
        let mut map = BTreeMap::new();
        let mut sources = Vec::new();
        for f in files {
            if f.ends_with("main.rs") {
                // The binary's root: its one module, `cli`, is read as its own.
                continue;
            }
            let m = module_of(&src, &f);
            sources.push((m.clone(), std::fs::read_to_string(&f).unwrap()));
            map.insert(m, f);
        }
        (Crate { files: map }, sources)
    }

    /// The file a path names: its longest prefix that is a module.
    fn resolve(&self, mut path: Vec<String>) -> Option<Module> {
        while !path.is_empty() {
            if self.files.contains_key(&path) {
                return Some(path);
            }
            path.pop();
        }
        None
    }

    /// File-level import edges.
    fn edges(&self, sources: &[(Module, String)]) -> BTreeMap<Module, BTreeSet<Module>> {
        let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
        for (m, text) in sources {
            let is_dir = self.files[m]
                .file_name()
                .is_some_and(|n| n == "mod.rs" || n == "lib.rs");
            for p in paths_in(&code_of(text)) {
                let mut parts = p.split("::").map(String::from);
                let first = parts.next().unwrap_or_default();
                let mut base: Vec<String> = match first.as_str() {
                    "crate" => Vec::new(),
                    "self" => m.clone(),
                    "super" => m[..m.len().saturating_sub(1)].to_vec(),
                    _ => continue,
                };
                for part in parts {
                    match part.as_str() {
                        "super" => {
                            base.pop();
                        }
                        "self" => {}
                        _ => base.push(part),
                    }
                }
                if let Some(target) = self.resolve(base) {
                    let inside = is_dir && target.starts_with(m);
                    if target != *m && !inside {
                        edges.entry(m.clone()).or_default().insert(target);
                    }
                }
            }
        }
        edges
    }
}

/// Strongly connected components of more than one file (Tarjan).
fn cycles(edges: &BTreeMap<Module, BTreeSet<Module>>, nodes: &[Module]) -> Vec<Vec<Module>> {
    struct State<'a> {
        edges: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<Module, usize>,
        low: BTreeMap<Module, usize>,
        stack: Vec<Module>,
        on: BTreeSet<Module>,
        out: Vec<Vec<Module>>,
    }
    fn visit(s: &mut State, v: &Module) {
        let i = s.index.len();
        s.index.insert(v.clone(), i);
        s.low.insert(v.clone(), i);
        s.stack.push(v.clone());
        s.on.insert(v.clone());
        for w in s.edges.get(v).cloned().unwrap_or_default() {
            if !s.index.contains_key(&w) {
                visit(s, &w);
                let l = s.low[&w].min(s.low[v]);
                s.low.insert(v.clone(), l);
            } else if s.on.contains(&w) {
                let l = s.index[&w].min(s.low[v]);
                s.low.insert(v.clone(), l);
            }
        }
        if s.low[v] == s.index[v] {
            let mut scc = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on.remove(&w);
                let done = w == *v;
                scc.push(w);
                if done {
                    break;
                }
            }
            if scc.len() > 1 {
                s.out.push(scc);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for n in nodes {
        if !s.index.contains_key(n) {
            visit(&mut s, n);
        }
    }
    s.out
}

fn name(m: &Module) -> String {
    if m.is_empty() {
        "lib".into()
    } else {
        m.join("/")
    }
}

#[test]
fn the_source_reader_skips_comments_strings_and_chars() {
    let code = code_of(
        "let a = '\"'; use crate::x; /* crate::y */ let s = r#\"crate::z\"#; // crate::w\nlet b = \"crate::v\"; fn f<'a>() {}",
    );
    assert_eq!(paths_in(&code), ["crate::x", "crate::x"], "{code}");
    assert!(code.contains("fn f<'a>()"), "{code}");
}

#[test]
fn no_file_in_src_imports_one_that_imports_it() {
    let (krate, sources) = Crate::read();
    let edges = krate.edges(&sources);
    // The reader finds real imports (it would pass vacuously otherwise).
    let method = vec!["accel".to_string(), "method".to_string()];
    assert!(edges[&method].contains(&vec!["accel".to_string(), "builder".to_string()]));
    let nodes: Vec<Module> = krate.files.keys().cloned().collect();
    let found = cycles(&edges, &nodes);
    let listed: Vec<String> = found
        .iter()
        .map(|c| c.iter().map(name).collect::<Vec<_>>().join(" "))
        .collect();
    assert!(found.is_empty(), "import cycles between files:\n{}", listed.join("\n"));
}

#[test]
fn each_module_imports_only_the_modules_below_it() {
    let (krate, sources) = Crate::read();
    let edges = krate.edges(&sources);
    let mut wrong = Vec::new();
    for (from, targets) in &edges {
        let (Some(a), false) = (from.first(), from.is_empty()) else {
            continue;
        };
        if a == "cli" {
            continue;
        }
        let allowed = ALLOWED
            .iter()
            .find(|(m, _)| m == a)
            .unwrap_or_else(|| panic!("module {a} is in no layer of ALLOWED"))
            .1;
        for t in targets {
            if let Some(b) = t.first() {
                if b != a && !allowed.contains(&b.as_str()) {
                    wrong.push(format!("{} imports {}", name(from), name(t)));
                }
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the layers:\n{}", wrong.join("\n"));
}

#[test]
fn no_file_in_src_is_over_600_lines() {
    let (krate, sources) = Crate::read();
    let long: Vec<String> = sources
        .iter()
        .map(|(m, text)| (m, text.lines().count()))
        .filter(|(_, n)| *n > 600)
        .map(|(m, n)| format!("{}: {n} lines", krate.files[m].display()))
        .collect();
    assert!(long.is_empty(), "{}", long.join("\n"));
}
