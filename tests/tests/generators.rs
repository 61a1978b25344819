//! Generators: the seeds' statistics, exact grid sizes, determinism, parameter errors.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::generate::{generate, GeneratorSpec};
use cadr_core::load::{load_scene, SceneSource};
use cadr_core::scene::{flatten, SceneStats};

fn stats(spec: &GeneratorSpec) -> SceneStats {
    let scene = generate(spec);
    let flat = flatten(&scene).expect("generated scenes are valid");
    SceneStats::new(&scene, &flat)
}

fn within(value: f64, target: f64, tolerance: f64) -> bool {
    (value - target).abs() <= target * tolerance
}

#[test]
fn graphicscard_has_the_seed_statistics() {
    let s = stats(&GeneratorSpec::GraphicsCard);
    assert!(
        within(s.instances as f64, 68_000.0, 0.1),
        "parts drawn: {}",
        s.instances
    );
    assert!(
        within(s.mesh_instances as f64, 2_500.0, 0.05),
        "objects: {}",
        s.mesh_instances
    );
    assert_eq!(s.geometries, 110);
    assert_eq!(s.materials, 66);
    let per_part = s.triangles as f64 / s.instances as f64;
    assert!(
        within(per_part, 10.0, 0.05),
        "triangles per part: {per_part}"
    );
    // The seed file has 5 004 nodes: a placement node above each object's shape.
    assert!(within(s.nodes as f64, 5_004.0, 0.15), "nodes: {}", s.nodes);
}

#[test]
fn racecar_has_the_seed_statistics() {
    let s = stats(&GeneratorSpec::RaceCar);
    assert!(
        within(s.instances as f64, 98_000.0, 0.1),
        "parts drawn: {}",
        s.instances
    );
    let per_part = s.triangles as f64 / s.instances as f64;
    assert!(
        within(per_part, 37.0, 0.05),
        "triangles per part: {per_part}"
    );
}

#[test]
fn grid_has_exactly_the_requested_parts() {
    for parts in [1, 9, 10, 11, 12_345] {
        let s = stats(&GeneratorSpec::Grid {
            parts,
            triangles_per_part: 12.0,
        });
        assert_eq!(s.instances as u64, parts);
    }
    let big = stats(&GeneratorSpec::Grid {
        parts: 1_000_000,
        triangles_per_part: 12.0,
    });
    assert_eq!(big.instances, 1_000_000);
    assert!(
        big.geometries <= 17,
        "a million parts share a few geometries"
    );
}

#[test]
fn generators_are_deterministic_and_share_geometry() {
    for spec in [GeneratorSpec::Demo, GeneratorSpec::GraphicsCard] {
        assert_eq!(generate(&spec), generate(&spec));
        let s = stats(&spec);
        assert!(
            s.mesh_instances > 5 * s.geometries,
            "{spec:?}: geometries are shared by many objects"
        );
        assert!(s.materials > 10);
    }
}

#[test]
fn generator_sources_parse_and_bad_ones_say_why() {
    assert_eq!(
        SceneSource::parse("gen:fine:units=3,detail=4").unwrap(),
        SceneSource::Generator(GeneratorSpec::Fine {
            units: 3,
            detail: 4,
            unique: false,
        })
    );
    assert_eq!(
        SceneSource::parse("gen:fine:units=3,unique=1").unwrap(),
        SceneSource::Generator(GeneratorSpec::Fine {
            units: 3,
            detail: 2,
            unique: true,
        })
    );
    let refused = SceneSource::parse("gen:fine:units=1000000,detail=32,unique=1")
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("unique=1") && refused.contains("memory"),
        "{refused}"
    );
    assert!(SceneSource::parse("gen:fine:unique=2").is_err());
    let fine = load_scene("gen:grid:parts=20,tris=5000").unwrap();
    let triangles: usize = fine.geometries.iter().map(|g| g.indices.len() / 3).sum();
    let parts: usize = fine.geometries.iter().map(|g| g.parts.len()).sum();
    assert!(
        (3000..8000).contains(&(triangles / parts)),
        "about 5000 triangles per part: {}",
        triangles / parts
    );
    assert_eq!(
        SceneSource::parse("gen:grid:parts=1_000,tris=20").unwrap(),
        SceneSource::Generator(GeneratorSpec::Grid {
            parts: 1000,
            triangles_per_part: 20.0
        })
    );
    for (text, expected) in [
        ("gen:nothing", "unknown generator 'gen:nothing'"),
        ("gen:grid", "gen:grid needs parts=N"),
        ("gen:grid:parts=abc", "parts=abc is not a whole number"),
        ("gen:grid:parts=0", "out of range"),
        ("gen:grid:parts=10,color=red", "unknown parameter 'color'"),
        ("gen:demo:parts=3", "gen:demo takes no parameters"),
        (
            "gen:grid:parts=10,tris=200000",
            "tris=200000 is out of range (8 to 100000)",
        ),
        (
            "gen:fine:units=0",
            "units=0 is not a number from 1 to 1000000",
        ),
        (
            "gen:fine:detail=33",
            "detail=33 is not a number from 1 to 32",
        ),
        (
            "gen:fine:teeth=3",
            "unknown parameter 'teeth' (known: units, detail, unique)",
        ),
    ] {
        let error = load_scene(text)
            .err()
            .unwrap_or_else(|| panic!("{text} was accepted"))
            .to_string();
        assert!(error.contains(expected), "{text}: {error}");
    }
}
