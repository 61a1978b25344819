//! Fuzzing the CSF reader with a proptest mutator over the CSF files of the fuzz corpus in `fuzz/corpus/csf/`:
//! whatever the bytes, reading, converting, validating and flattening return errors and never
//! panic or read out of bounds. Failures proptest finds are kept in `proptest-regressions/`.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use std::path::PathBuf;

use cadr_core::csf::{csf_from_scene, read_csf, scene_from_csf, write_csf};
use cadr_core::load::load_file;
use cadr_core::scene::flatten;
use cadr_tests::fixtures::{rich_csf_file, scratch_dir, CubeGltf};
use proptest::prelude::*;

fn corpus_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/csf")
}

/// The seeds: the cube scene in every version, and a file with every optional structure.
fn seeds() -> Vec<(String, Vec<u8>)> {
    let dir = scratch_dir("csf_seeds");
    let scene = load_file(&CubeGltf::new().write_glb(&dir, "cube")).unwrap();
    let file = csf_from_scene(&scene).unwrap();
    let mut seeds: Vec<(String, Vec<u8>)> = (2..=6)
        .map(|version| (format!("cube-v{version}.csf"), write_csf(&file, version)))
        .collect();
    seeds.push(("rich-v6.csf".into(), write_csf(&rich_csf_file(), 6)));
    seeds
}

#[test]
fn corpus_seeds_are_current() {
    for (name, bytes) in seeds() {
        let path = corpus_dir().join(&name);
        let stored = std::fs::read(&path).unwrap_or_default();
        if stored != bytes {
            if std::env::var("CADR_UPDATE_CORPUS").is_ok_and(|v| v == "1") {
                std::fs::create_dir_all(corpus_dir()).unwrap();
                std::fs::write(&path, &bytes).unwrap();
                continue;
            }
            panic!(
                "{} differs from what cadr writes; run with CADR_UPDATE_CORPUS=1",
                path.display()
            );
        }
        read_csf(&stored).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

fn corpus() -> Vec<Vec<u8>> {
    let mut files: Vec<Vec<u8>> = std::fs::read_dir(corpus_dir())
        .map(|entries| {
            entries
                .filter_map(|e| std::fs::read(e.ok()?.path()).ok())
                // Plain CSF only: the gzip inputs of the coverage-guided corpus are not mutated here.
                .filter(|bytes| bytes.starts_with(&cadr_core::csf::MAGIC.to_le_bytes()))
                .collect()
        })
        .unwrap_or_default();
    if files.is_empty() {
        files = seeds().into_iter().map(|(_, bytes)| bytes).collect();
    }
    files
}

/// Values that break naive readers: boundaries, sign flips, sizes near the file's.
const INTERESTING: [u32; 10] = [
    0,
    1,
    2,
    3,
    7,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    0xffff_fffe,
    4096,
];

#[derive(Clone, Debug)]
enum Mutation {
    Byte { at: usize, value: u8 },
    Word { at: usize, value: u32 },
    Truncate { keep: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, value)| Mutation::Byte { at, value }),
        (any::<usize>(), prop::sample::select(INTERESTING.to_vec()))
            .prop_map(|(at, value)| Mutation::Word { at, value }),
        any::<usize>().prop_map(|keep| Mutation::Truncate { keep }),
    ]
}

fn apply(bytes: &mut Vec<u8>, mutation: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    match *mutation {
        Mutation::Byte { at, value } => {
            let len = bytes.len();
            bytes[at % len] = value;
        }
        Mutation::Word { at, value } => {
            // Aligned, where the format's fields are.
            let slots = bytes.len() / 4;
            if slots > 0 {
                let at = (at % slots) * 4;
                bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
            }
        }
        Mutation::Truncate { keep } => bytes.truncate(keep % (bytes.len() + 1)),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_never_panic(seed in any::<prop::sample::Index>(), mutations in prop::collection::vec(mutation(), 1..12)) {
        let files = corpus();
        let mut bytes = files[seed.index(files.len())].clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        if let Ok(file) = read_csf(&bytes) {
            if let Ok(scene) = scene_from_csf(&file, "fuzz") {
                if scene.validate().is_ok() {
                    let _ = flatten(&scene);
                }
            }
            // What was read can always be written, and reads back to the same bytes
            // (compared as bytes: a mutation may have written a NaN, which is not equal to itself).
            let written = write_csf(&file, file.version);
            let again = read_csf(&written).unwrap();
            prop_assert!(write_csf(&again, again.version) == written);
        }
    }
}
