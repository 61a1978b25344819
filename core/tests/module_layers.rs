//! The layers of `cadr-core`, checked: a module uses only the modules of the layers below its
//! own, and within a module's folder the files use each other without cycles. ARCHITECTURE.md
//! draws the same layers; a new module gets a place in [`LAYERS`] (the test names any module
//! it does not know).
//!
//! References are read from the code (comment lines are skipped): `crate::module…` paths,
//! braced groups included, and in a folder `super::name` and `crate::folder::name`, where a
//! name re-exported by the folder's `mod.rs` stands for the file that defines it.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Core's top-level modules, bottom layer first. A module may use those of lower layers only.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "foundations",
        &[
            "timings",
            "commands_key",
            "memory_budget",
            "disk_cache",
            "panic_boundary",
            "freed_memory",
            "host_heap",
        ],
    ),
    ("threads", &["parallel"]),
    ("vulkan", &["vk"]),
    ("errors", &["error"]),
    ("shader compiler", &["shaders"]),
    ("scene model", &["scene"]),
    ("scene graph", &["graph"]),
    ("scene tree", &["tree"]),
    ("file formats and generators", &["csf", "generate"]),
    ("loading", &["load"]),
    ("saving", &["save"]),
    ("rendering pieces", &["render"]),
    ("GPU scene", &["gpu_scene"]),
    ("techniques, host side", &["technique"]),
    ("frame", &["frame"]),
    ("view", &["view"]),
];

fn source_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files.sort();
    files
}

/// `source` without its comment lines (doc links name modules above without using them).
fn code_of(source: &str) -> String {
    source
        .lines()
        .filter(|line| !line.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The leading identifier of `text`.
fn identifier(text: &str) -> Option<&str> {
    let end = text
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(text.len());
    (end > 0).then(|| &text[..end])
}

/// The first path segment after each `prefix` in `code`: the identifier itself, or for a
/// braced group each of its top-level items' first identifiers.
fn names_after(code: &str, prefix: &str) -> Vec<String> {
    let mut names = Vec::new();
    for (at, _) in code.match_indices(prefix) {
        // `super::` inside a longer path (`a::super::`) does not occur; `crate::` may follow
        // `$`, which macros use, and is read the same.
        let rest = &code[at + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1;
            let mut item = String::new();
            for c in group.chars() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    _ => {}
                }
                if depth == 0 {
                    break;
                }
                if depth == 1 && c == ',' {
                    names.extend(identifier(item.trim()).map(str::to_owned));
                    item.clear();
                } else if depth == 1 && c != '}' {
                    item.push(c);
                } else {
                    item.push(' ');
                }
            }
            names.extend(identifier(item.trim()).map(str::to_owned));
        } else if let Some(name) = identifier(rest) {
            names.push(name.to_owned());
        }
    }
    names
}

/// The top-level module a file of `src/` belongs to.
fn module_of(root: &Path, file: &Path) -> String {
    let relative = file.strip_prefix(root).unwrap();
    let first = relative.components().next().unwrap();
    first
        .as_os_str()
        .to_string_lossy()
        .trim_end_matches(".rs")
        .to_owned()
}

fn layer_of(module: &str) -> Option<usize> {
    LAYERS
        .iter()
        .position(|(_, modules)| modules.contains(&module))
}

#[test]
fn every_module_uses_only_the_layers_below_its_own() {
    let root = source_root();
    let mut unknown = BTreeSet::new();
    let mut back_arrows = Vec::new();
    for file in rust_files(&root) {
        let module = module_of(&root, &file);
        if module == "lib" {
            continue;
        }
        let Some(own) = layer_of(&module) else {
            unknown.insert(module);
            continue;
        };
        let code = code_of(&fs::read_to_string(&file).unwrap());
        let used: BTreeSet<String> = names_after(&code, "crate::").into_iter().collect();
        for target in used.iter().filter(|t| **t != module) {
            match layer_of(target) {
                Some(layer) if layer < own => {}
                Some(layer) => back_arrows.push(format!(
                    "{} ({}) uses crate::{target} ({}, {})",
                    file.strip_prefix(&root).unwrap().display(),
                    LAYERS[own].0,
                    LAYERS[layer].0,
                    if layer == own {
                        "the same layer"
                    } else {
                        "a layer above"
                    },
                )),
                None => {
                    unknown.insert(target.clone());
                }
            }
        }
    }
    assert!(
        unknown.is_empty(),
        "modules missing from LAYERS (give each a layer here and in ARCHITECTURE.md): {unknown:?}"
    );
    assert!(
        back_arrows.is_empty(),
        "references against the layers:\n{}",
        back_arrows.join("\n")
    );
}

/// The items a folder's `mod.rs` re-exports from its files: item name → file stem.
fn re_exports(mod_code: &str, files: &BTreeSet<String>) -> BTreeMap<String, String> {
    let mut items = BTreeMap::new();
    for statement in mod_code.split(';') {
        let statement = statement.trim();
        let Some(at) = statement.find("use ") else {
            continue;
        };
        if !statement[..at].trim_start().starts_with("pub") {
            continue;
        }
        let path = &statement[at + 4..];
        let Some((file, rest)) = path.split_once("::") else {
            continue;
        };
        if !files.contains(file.trim()) {
            continue;
        }
        for word in rest.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
            if !word.is_empty() && word != "self" && word != "as" {
                items.insert(word.to_owned(), file.trim().to_owned());
            }
        }
    }
    items
}

/// A cycle in `edges`, if there is one, as the files along it.
fn find_cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, bool>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_owned(), true);
        path.push(node.to_owned());
        for next in edges.get(node).into_iter().flatten() {
            match state.get(next) {
                Some(true) => {
                    let start = path.iter().position(|n| n == next).unwrap();
                    let mut cycle = path[start..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                Some(false) => {}
                None => {
                    if let Some(cycle) = visit(next, edges, state, path) {
                        return Some(cycle);
                    }
                }
            }
        }
        path.pop();
        state.insert(node.to_owned(), false);
        None
    }
    let mut state = BTreeMap::new();
    for node in edges.keys() {
        if !state.contains_key(node) {
            if let Some(cycle) = visit(node, edges, &mut state, &mut Vec::new()) {
                return Some(cycle);
            }
        }
    }
    None
}

#[test]
fn the_files_of_a_module_use_each_other_without_cycles() {
    let root = source_root();
    let mut cycles = Vec::new();
    for entry in fs::read_dir(&root).unwrap() {
        let folder = entry.unwrap().path();
        if !folder.is_dir() {
            continue;
        }
        let module = folder.file_name().unwrap().to_string_lossy().into_owned();
        let files: BTreeSet<String> = fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "rs"))
            .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
            .filter(|stem| stem != "mod")
            .collect();
        let mod_code = code_of(&fs::read_to_string(folder.join("mod.rs")).unwrap());
        let exported = re_exports(&mod_code, &files);
        let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for file in &files {
            let code = code_of(&fs::read_to_string(folder.join(format!("{file}.rs"))).unwrap());
            let mut names = names_after(&code, "super::");
            names.extend(names_after(&code, &format!("crate::{module}::")));
            for name in names {
                let target = if files.contains(&name) {
                    Some(&name)
                } else {
                    exported.get(&name)
                };
                if let Some(target) = target.filter(|t| *t != file) {
                    edges
                        .entry(file.clone())
                        .or_default()
                        .insert(target.clone());
                }
            }
        }
        if let Some(cycle) = find_cycle(&edges) {
            cycles.push(format!("{module}/: {}", cycle.join(" → ")));
        }
    }
    assert!(
        cycles.is_empty(),
        "cycles between files:\n{}",
        cycles.join("\n")
    );
}

#[test]
fn the_reader_sees_paths_groups_and_nested_groups() {
    let code = "use crate::{a::B, c, d::{e, f}};\nlet x = crate::g::h();\n";
    assert_eq!(names_after(code, "crate::"), ["a", "c", "d", "g"]);
    let code = code_of("// crate::commented\nuse crate::kept;");
    assert_eq!(names_after(&code, "crate::"), ["kept"]);
    let files = ["one", "two"].map(String::from).into_iter().collect();
    let exported = re_exports("pub use one::{A, B as C};\nuse two::D;\n", &files);
    assert_eq!(exported.get("A").map(String::as_str), Some("one"));
    assert_eq!(exported.get("C").map(String::as_str), Some("one"));
    assert_eq!(exported.get("D"), None, "a private use is no re-export");
    let cyclic: BTreeMap<String, BTreeSet<String>> = [("a", "b"), ("b", "c"), ("c", "a")]
        .into_iter()
        .map(|(from, to)| (from.to_owned(), [to.to_owned()].into()))
        .collect();
    assert_eq!(find_cycle(&cyclic).unwrap(), ["a", "b", "c", "a"]);
    let acyclic: BTreeMap<String, BTreeSet<String>> =
        [("a".to_owned(), ["b".to_owned()].into())].into();
    assert_eq!(find_cycle(&acyclic), None);
}
