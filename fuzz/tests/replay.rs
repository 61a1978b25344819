//! Every input of the fuzz corpora (`fuzz/corpus/TARGET/`) and every finding kept as a
//! regression (`fuzz/findings/TARGET/`) runs through its target in the ordinary test run: none
//! may panic, and each target has a corpus.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::{Path, PathBuf};

use cadr_fuzz::Target;

fn inputs(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| Some(e.ok()?.path()))
                .filter(|p| p.is_file())
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

fn replay(target: Target, kind: &str) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(kind)
        .join(target.name());
    let files = inputs(&dir);
    let failures: Vec<String> = files
        .iter()
        .filter_map(|file| {
            let data = std::fs::read(file).unwrap();
            std::panic::catch_unwind(|| target.run(&data))
                .err()
                .map(|_| file.display().to_string())
        })
        .collect();
    assert!(failures.is_empty(), "these inputs fail: {failures:#?}");
    files.len()
}

#[test]
fn gltf_corpus_and_findings_replay() {
    assert!(
        replay(Target::Gltf, "corpus") > 0,
        "the glTF corpus is empty"
    );
    replay(Target::Gltf, "findings");
}

#[test]
fn csf_corpus_and_findings_replay() {
    assert!(replay(Target::Csf, "corpus") > 0, "the CSF corpus is empty");
    replay(Target::Csf, "findings");
}

#[test]
fn scene_load_corpus_and_findings_replay() {
    assert!(
        replay(Target::SceneLoad, "corpus") > 0,
        "the scene_load corpus is empty"
    );
    replay(Target::SceneLoad, "findings");
}
