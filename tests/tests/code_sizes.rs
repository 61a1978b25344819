//! Sizes a reader can hold: no function of the product's code (every crate's `src/`, tests and
//! test fixtures aside) is longer than [`MAX_FUNCTION_LINES`]. A function is counted from its
//! `fn` line to the closing brace at the same indentation, as `rustfmt` lays it out.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::fs;
use std::path::{Path, PathBuf};

/// The longest a function may be, in lines.
const MAX_FUNCTION_LINES: usize = 120;

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

#[test]
fn the_counter_measures_a_function_from_its_signature_to_its_closing_brace() {
    let text = "fn short() {\n    1\n}\n\npub(crate) unsafe fn longer<T>(\n    a: T,\n) -> T {\n    let b = a;\n    b\n}\nfn declared();\n";
    assert_eq!(
        functions(text),
        [("short".to_owned(), 1, 3), ("longer".to_owned(), 5, 6)]
    );
}

#[test]
fn no_function_of_the_product_is_longer_than_120_lines() {
    let root = workspace_root();
    let mut files = Vec::new();
    for folder in SOURCE_FOLDERS {
        rust_files(&root.join(folder), &mut files);
    }
    assert!(files.len() > 50, "only {} source files found", files.len());
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
