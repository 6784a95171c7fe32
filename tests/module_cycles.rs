//! DESIGN.md's rule "no import cycles between modules of the library or of the tool crate",
//! checked on the sources themselves so that a clone standing alone checks it too.
//!
//! A module is a file (`a/b.rs` or `a/b/mod.rs` is `a::b`; `lib.rs` and `main.rs` at the root).
//! Its imports are the paths in its non-test code that start with `crate::` or `super::`
//! (`use` trees expanded, and paths written out in expressions and types), each resolved to the
//! longest module it names. A parent naming its own descendants is structure, not an import,
//! and is left out; a child importing its parent is kept. Text only: a path built by a macro is
//! not seen. A cycle is a strongly connected set of two or more modules.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

type Module = Vec<String>;

/// Every `.rs` file under `root` as its module path, with its non-test text; the files of
/// modules declared under `#[cfg(test)]` (`mod tests;`) are left out.
fn modules(root: &Path) -> BTreeMap<Module, String> {
    let mut mods = all_files(root);
    let test_only: Vec<Module> = mods
        .keys()
        .flat_map(|m| {
            let file = file_of(root, m);
            let text = fs::read_to_string(&file).unwrap();
            // `#[path]` names a file beside this one: a child of its directory's module
            let mut dir = m.clone();
            if !matches!(
                file.file_stem().and_then(|s| s.to_str()),
                Some("mod" | "lib" | "main")
            ) {
                dir.pop();
            }
            test_children(&text)
                .into_iter()
                .map(|(c, by_path)| {
                    let parent = if by_path { &dir } else { m };
                    parent.iter().cloned().chain([c]).collect::<Module>()
                })
                .collect::<Vec<_>>()
        })
        .collect();
    for m in test_only {
        mods.remove(&m);
    }
    mods
}

/// The file of module `m` (as [`all_files`] named it).
fn file_of(root: &Path, m: &Module) -> PathBuf {
    let dir = m.iter().fold(root.to_path_buf(), |p, s| p.join(s));
    if m.is_empty() {
        let lib = root.join("lib.rs");
        return if lib.exists() {
            lib
        } else {
            root.join("main.rs")
        };
    }
    if dir.join("mod.rs").exists() {
        dir.join("mod.rs")
    } else {
        dir.with_extension("rs")
    }
}

/// The children a file declares under `#[cfg(test)]` as `mod NAME;` (with any visibility):
/// NAME, or the stem of the file a `#[path = "FILE"]` names (then `true`).
fn test_children(text: &str) -> Vec<(String, bool)> {
    let flat: String = text.split_whitespace().collect::<Vec<_>>().join(" ");
    flat.split("#[cfg(test)] ")
        .skip(1)
        .filter_map(|rest| {
            if let Some(p) = rest.strip_prefix("#[path = \"") {
                let file = p.split('"').next()?;
                let stem = Path::new(file).file_stem()?.to_str()?.to_owned();
                return Some((stem, true));
            }
            let decl = rest.split(';').next()?;
            let name = decl.strip_prefix("mod ").or_else(|| {
                decl.strip_prefix("pub")
                    .and_then(|d| d.split_once("mod ").map(|(_, n)| n))
            })?;
            name.chars().all(is_ident).then(|| (name.to_owned(), false))
        })
        .collect()
}

/// Every `.rs` file under `root` as its module path, with its non-test text.
fn all_files(root: &Path) -> BTreeMap<Module, String> {
    let mut out = BTreeMap::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        for entry in fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let rel: PathBuf = path.strip_prefix(root).unwrap().with_extension("");
            let mut m: Module = rel.iter().map(|s| s.to_str().unwrap().to_owned()).collect();
            if matches!(m.last().map(String::as_str), Some("mod" | "lib")) {
                m.pop();
            }
            out.insert(m, non_test_code(&fs::read_to_string(&path).unwrap()));
        }
    }
    out
}

/// The text before the first `#[cfg(test)] mod NAME {`, without `//` comments.
fn non_test_code(text: &str) -> String {
    let mut code = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") && test_mod_follows(text, line) {
            break;
        }
        code.push_str(line.split("//").next().unwrap());
        code.push('\n');
    }
    code
}

/// Whether the `#[cfg(test)]` on `line` is followed by an inline `mod NAME {`.
fn test_mod_follows(text: &str, line: &str) -> bool {
    let at = text.find(line).unwrap() + line.len();
    let rest = line.trim_start()["#[cfg(test)]".len()..].to_owned() + &text[at..];
    let rest = rest.trim_start();
    let Some(rest) = rest.strip_prefix("mod") else {
        return false;
    };
    let name_end = rest
        .trim_start()
        .find(|c: char| !c.is_alphanumeric() && c != '_');
    name_end.is_some_and(|i| rest.trim_start()[i..].trim_start().starts_with('{'))
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths a `use` tree names: `a::{b, c::{d, e}}` → a::b, a::c::d, a::c::e.
fn expand(tree: &str, prefix: &str, out: &mut Vec<String>) {
    let tree = tree.trim();
    if let Some(open) = tree.find('{') {
        let head = tree[..open].trim_end_matches("::");
        let body = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
        let (mut depth, mut start) = (0, 0);
        for (i, c) in body.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand(&body[start..i], &join(prefix, head), out);
                    start = i + 1;
                }
                _ => {}
            }
        }
        expand(&body[start..], &join(prefix, head), out);
    } else if !tree.is_empty() {
        let path = tree.split(" as ").next().unwrap().trim();
        out.push(join(prefix, path));
    }
}

fn join(a: &str, b: &str) -> String {
    match (a.is_empty(), b.is_empty()) {
        (true, _) => b.to_owned(),
        (_, true) => a.to_owned(),
        _ => format!("{a}::{b}"),
    }
}

/// Every path of `code` that starts with `crate` or `super`: in `use` trees and written out.
fn paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let flat: String = code.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut rest = flat.as_str();
    while let Some(i) = rest.find("use ") {
        let word_start = i == 0 || !is_ident(rest[..i].chars().next_back().unwrap());
        rest = &rest[i + 4..];
        if word_start {
            let end = rest.find(';').unwrap_or(rest.len());
            expand(&rest[..end].replace(' ', ""), "", &mut out);
        }
    }
    for root in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(i) = flat[from..].find(root) {
            let at = from + i;
            from = at + root.len();
            // inside a longer path (`super::super::x`, `a_crate::`): not a path's start
            if at > 0
                && flat[..at]
                    .chars()
                    .next_back()
                    .is_some_and(|c| is_ident(c) || c == ':')
            {
                continue;
            }
            let end = flat[at..]
                .find(|c: char| !is_ident(c) && c != ':')
                .map_or(flat.len(), |e| at + e);
            out.push(flat[at..end].trim_end_matches(':').to_owned());
        }
    }
    out
}

/// The import graph: module → the modules its paths resolve to (descendants left out).
fn graph(mods: &BTreeMap<Module, String>) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut g = BTreeMap::new();
    for (m, code) in mods {
        let mut to = BTreeSet::new();
        for p in paths(code) {
            let mut seg: Vec<&str> = p.split("::").filter(|s| !s.is_empty()).collect();
            let mut target: Module = match seg.first() {
                Some(&"crate") => {
                    seg.remove(0);
                    Vec::new()
                }
                Some(&"super") => {
                    let mut base = m.clone();
                    while seg.first() == Some(&"super") {
                        seg.remove(0);
                        base.pop();
                    }
                    base
                }
                _ => continue,
            };
            target.extend(seg.iter().map(|s| s.to_string()));
            while !target.is_empty() && !mods.contains_key(&target) {
                target.pop();
            }
            let descendant = target.len() > m.len() && target[..m.len()] == m[..];
            if !target.is_empty() && target != *m && !descendant {
                to.insert(target);
            }
        }
        g.insert(m.clone(), to);
    }
    g
}

/// The strongly connected sets of two or more modules (Tarjan's algorithm, iterative).
fn cycles(g: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<Module>> {
    let nodes: Vec<&Module> = g.keys().collect();
    let index_of: BTreeMap<&Module, usize> =
        nodes.iter().enumerate().map(|(i, m)| (*m, i)).collect();
    let succ: Vec<Vec<usize>> = nodes
        .iter()
        .map(|m| {
            g[*m]
                .iter()
                .filter_map(|t| index_of.get(t).copied())
                .collect()
        })
        .collect();
    let n = nodes.len();
    let (mut index, mut low) = (vec![usize::MAX; n], vec![0; n]);
    let (mut on_stack, mut stack, mut out, mut next) = (vec![false; n], Vec::new(), Vec::new(), 0);
    for start in 0..n {
        if index[start] != usize::MAX {
            continue;
        }
        let mut call = vec![(start, 0usize)];
        index[start] = next;
        low[start] = next;
        next += 1;
        stack.push(start);
        on_stack[start] = true;
        while let Some(&mut (v, ref mut k)) = call.last_mut() {
            if *k < succ[v].len() {
                let w = succ[v][*k];
                *k += 1;
                if index[w] == usize::MAX {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    call.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            call.pop();
            if let Some(&(parent, _)) = call.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut comp = Vec::new();
                loop {
                    let w = stack.pop().unwrap();
                    on_stack[w] = false;
                    comp.push(nodes[w].clone());
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    comp.sort();
                    out.push(comp);
                }
            }
        }
    }
    out
}

fn check(root: &Path, at_least: usize) {
    let mods = modules(root);
    assert!(
        mods.len() >= at_least,
        "{}: {} modules found",
        root.display(),
        mods.len()
    );
    let g = graph(&mods);
    let edges: usize = g.values().map(BTreeSet::len).sum();
    assert!(
        edges >= mods.len() / 2,
        "{}: only {edges} imports read",
        root.display()
    );
    let found = cycles(&g);
    let shown: Vec<String> = found
        .iter()
        .map(|c| {
            c.iter()
                .map(|m| m.join("::"))
                .collect::<Vec<_>>()
                .join(" <-> ")
        })
        .collect();
    assert!(
        found.is_empty(),
        "{}: import cycles: {shown:#?}",
        root.display()
    );
}

#[test]
fn the_library_modules_import_each_other_in_no_circle() {
    check(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), 100);
}

#[test]
fn the_tool_crate_modules_import_each_other_in_no_circle() {
    check(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/brdftab"),
        20,
    );
}

/// The check can fail: a cycle through a `use` tree, one through a written-out path and one
/// through `super::`, each found; a parent naming its child and a child its parent are not.
#[test]
fn the_check_finds_cycles_it_is_shown() {
    let dir = std::env::temp_dir().join(format!("brdftab-modcycles-{}", std::process::id()));
    let write = |rel: &str, text: &str| {
        let p = dir.join(rel);
        fs::create_dir_all(p.parent().unwrap()).unwrap();
        fs::write(p, text).unwrap();
    };
    write(
        "lib.rs",
        "pub mod a;\npub mod b;\npub mod p;\npub mod x;\npub mod y;\n",
    );
    write("a.rs", "use crate::{b::{self, Thing as T}, p};\n");
    write(
        "b.rs",
        "pub fn f() { crate::a::g(); }\n#[cfg(test)]\n#[path = \"b_tests.rs\"]\nmod tests;\n",
    );
    write("p/mod.rs", "mod c;\npub use c::C;\nfn h() { c::f() }\n");
    write(
        "p/c.rs",
        "use super::h;\n// use crate::a; (a comment is no import)\n",
    );
    write(
        "x.rs",
        "pub struct X;\n#[cfg(test)]\nmod tests {\n    use crate::y;\n}\n",
    );
    write("y/mod.rs", "mod z;\n#[cfg(test)]\npub(crate) mod util;\n");
    write("y/util.rs", "use crate::a;\n");
    write("y/z.rs", "fn f() -> super::super::x::X { todo!() }\n");
    let g = graph(&modules(&dir));
    // close a second cycle through super:: paths and a written-out crate:: path
    write("x.rs", "pub struct X;\nfn f() { crate::y::z::f() }\n");
    let found = cycles(&graph(&modules(&dir)));
    fs::remove_dir_all(&dir).unwrap();
    let m = |s: &str| -> Module { s.split("::").map(str::to_owned).collect() };
    assert_eq!(g[&m("a")], [m("b"), m("p")].into_iter().collect());
    assert_eq!(
        g[&m("p")],
        BTreeSet::new(),
        "a parent's own children are structure"
    );
    assert_eq!(g[&m("p::c")], [m("p")].into_iter().collect());
    assert_eq!(g[&m("x")], BTreeSet::new(), "test code is left out");
    assert_eq!(g[&m("y::z")], [m("x")].into_iter().collect());
    assert!(
        !g.contains_key(&m("y::util")),
        "a module for tests only is left out"
    );
    assert_eq!(cycles(&g), vec![vec![m("a"), m("b")]]);
    assert_eq!(found, vec![vec![m("a"), m("b")], vec![m("x"), m("y::z")]]);
}
