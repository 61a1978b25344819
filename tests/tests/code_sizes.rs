//! Sizes a reader can hold: no function of the product's code (every crate's `src/`, tests and
//! test fixtures aside) is longer than [`MAX_FUNCTION_LINES`], and no struct has more than
//! [`MAX_STRUCT_FIELDS`] fields unless its doc comment says why ("Its many fields …"). A
//! function or struct is counted from its first line to the closing brace at the same
//! indentation, as `rustfmt` lays it out.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::fs;
use std::path::{Path, PathBuf};

/// The longest a function may be, in lines.
const MAX_FUNCTION_LINES: usize = 120;

/// The most fields a struct may have without a reason written in its doc comment.
const MAX_STRUCT_FIELDS: usize = 15;

/// What a struct's doc comment says when it has more fields, with the reason.
const MANY_FIELDS_REASON: &str = "many fields";

/// The folders whose `.rs` files are the product's code, from the workspace root (under
/// `plugins`, every crate's `src/`).
const SOURCE_FOLDERS: &[&str] = &["core/src", "capi/src", "cli/src", "vk-ext/src", "plugins"];

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn rust_files(folder: &Path, files: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(folder).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, files);
        } else if path.extension().is_some_and(|e| e == "rs")
            && path.components().any(|c| c.as_os_str() == "src")
        {
            files.push(path);
        }
    }
}

/// The name of the function whose signature starts on `line`, if one does.
fn function_name(line: &str) -> Option<&str> {
    let mut words = line.split_whitespace().peekable();
    while let Some(word) = words.next() {
        match word {
            "pub" | "const" | "async" | "unsafe" | "extern" | "\"C\"" => continue,
            w if w.starts_with("pub(") => continue,
            "fn" => {
                let name = words.next()?;
                let end = name.find(['(', '<']).unwrap_or(name.len());
                return Some(&name[..end]);
            }
            _ => return None,
        }
    }
    None
}

/// `(name, first line, lines)` of every function with a body in `text`, test modules
/// included (the caller filters them out).
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (start, line) in lines.iter().enumerate() {
        let Some(name) = function_name(line) else {
            continue;
        };
        let indent = &line[..line.len() - line.trim_start().len()];
        // The signature ends at the first line ending with `{` (a body) or `;` (none).
        let Some(open) = (start..lines.len())
            .find(|&i| lines[i].trim_end().ends_with('{') || lines[i].trim_end().ends_with(';'))
        else {
            continue;
        };
        if lines[open].trim_end().ends_with(';') {
            continue;
        }
        let closing = format!("{indent}}}");
        if let Some(end) = (open + 1..lines.len()).find(|&i| lines[i].trim_end() == closing) {
            found.push((name.to_owned(), start + 1, end - start + 1));
        }
    }
    found
}

/// The line where a file's `#[cfg(test)] mod …` starts (its functions are test code); a
/// `#[cfg(test)]` on any other item exempts nothing.
fn test_module_start(text: &str) -> usize {
    let lines: Vec<&str> = text.lines().collect();
    lines
        .windows(2)
        .position(|pair| {
            pair[0].trim() == "#[cfg(test)]" && pair[1].trim_start().starts_with("mod ")
        })
        .map_or(usize::MAX, |i| i + 1)
}

/// The name of the struct with named fields whose definition starts on `line`, if one does.
fn struct_name(line: &str) -> Option<&str> {
    let rest = line.trim_start();
    let rest = rest
        .strip_prefix("pub ")
        .or_else(|| rest.strip_prefix("pub(crate) "))
        .or_else(|| rest.strip_prefix("pub(super) "))
        .unwrap_or(rest);
    let rest = rest.strip_prefix("struct ")?;
    if !rest.trim_end().ends_with('{') {
        return None;
    }
    let end = rest.find(['<', ' ', '{']).unwrap_or(rest.len());
    Some(&rest[..end])
}

/// Whether `line` declares a field at `indent` plus one level.
fn is_field(line: &str, indent: &str) -> bool {
    let Some(rest) = line
        .strip_prefix(indent)
        .and_then(|l| l.strip_prefix("    "))
    else {
        return false;
    };
    let rest = rest
        .strip_prefix("pub ")
        .or_else(|| rest.strip_prefix("pub(crate) "))
        .or_else(|| rest.strip_prefix("pub(super) "))
        .unwrap_or(rest);
    let name_end = rest
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(0);
    name_end > 0
        && (rest.as_bytes()[0].is_ascii_lowercase() || rest.as_bytes()[0] == b'_')
        && rest[name_end..].starts_with(": ")
}

/// `(name, first line, fields, reason given)` of every struct with named fields in `text`:
/// the reason is given when the doc comment above it says [`MANY_FIELDS_REASON`].
fn structs(text: &str) -> Vec<(String, usize, usize, bool)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (start, line) in lines.iter().enumerate() {
        let Some(name) = struct_name(line) else {
            continue;
        };
        let indent = &line[..line.len() - line.trim_start().len()];
        let closing = format!("{indent}}}");
        let Some(end) = (start + 1..lines.len()).find(|&i| lines[i].trim_end() == closing) else {
            continue;
        };
        let fields = lines[start + 1..end]
            .iter()
            .filter(|l| is_field(l, indent))
            .count();
        let reason = lines[..start]
            .iter()
            .rev()
            .take_while(|l| {
                let l = l.trim_start();
                l.starts_with("///") || l.starts_with("#[")
            })
            .any(|l| l.contains(MANY_FIELDS_REASON));
        found.push((name.to_owned(), start + 1, fields, reason));
    }
    found
}

#[test]
fn the_struct_counter_counts_named_fields_and_finds_the_reason() {
    let text = "/// A pair.\npub(crate) struct Pair<T> {\n    /// First.\n    pub first: T,\n    second: Vec<T>,\n}\n/// Its many fields: none.\n#[derive(Debug)]\nstruct Empty {\n}\nstruct Tuple(u32);\n";
    assert_eq!(
        structs(text),
        [
            ("Pair".to_owned(), 2, 2, false),
            ("Empty".to_owned(), 9, 0, true)
        ]
    );
}

#[test]
fn the_counter_measures_a_function_from_its_signature_to_its_closing_brace() {
    let text = "fn short() {\n    1\n}\n\npub(crate) unsafe fn longer<T>(\n    a: T,\n) -> T {\n    let b = a;\n    b\n}\nfn declared();\n";
    assert_eq!(
        functions(text),
        [("short".to_owned(), 1, 3), ("longer".to_owned(), 5, 6)]
    );
}

/// Every `.rs` file of the product's code.
fn product_files(root: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for folder in SOURCE_FOLDERS {
        rust_files(&root.join(folder), &mut files);
    }
    assert!(files.len() > 50, "only {} source files found", files.len());
    files
}

#[test]
fn no_struct_of_the_product_has_more_than_15_fields_without_a_reason() {
    let root = workspace_root();
    let mut too_wide = Vec::new();
    for file in &product_files(&root) {
        let text = fs::read_to_string(file).unwrap();
        let tests_from = test_module_start(&text);
        for (name, line, fields, reason) in structs(&text) {
            if fields > MAX_STRUCT_FIELDS && !reason && line < tests_from {
                let path = file.strip_prefix(&root).unwrap_or(file);
                too_wide.push(format!("{}:{line} {name}: {fields} fields", path.display()));
            }
        }
    }
    assert!(
        too_wide.is_empty(),
        "structs over {MAX_STRUCT_FIELDS} fields (group them, or say why in the doc comment: \
         \"Its {MANY_FIELDS_REASON} …\"):\n{}",
        too_wide.join("\n")
    );
}

#[test]
fn no_function_of_the_product_is_longer_than_120_lines() {
    let root = workspace_root();
    let files = product_files(&root);
    let mut too_long = Vec::new();
    for file in &files {
        let text = fs::read_to_string(file).unwrap();
        let tests_from = test_module_start(&text);
        for (name, line, length) in functions(&text) {
            if length > MAX_FUNCTION_LINES && line < tests_from {
                let path = file.strip_prefix(&root).unwrap_or(file);
                too_long.push(format!("{}:{line} {name}: {length} lines", path.display()));
            }
        }
    }
    assert!(
        too_long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines (split them into named steps):\n{}",
        too_long.join("\n")
    );
}
