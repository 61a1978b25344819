//! Saving scenes: glTF 2.0 (`.gltf` with a `.bin` beside it, or `.glb`) and CSF (`.csf`,
//! `.csf.gz`). Each save reports what the target format cannot hold.

mod gltf;

use std::path::{Path, PathBuf};

use crate::csf::{
    csf_outline_from_scene, save_csf_from, CsfFileError, CsfGeometriesOf, SaveCsfError,
};
use crate::load::SceneFormat;
use crate::scene::{flatten, GeometryStore, Scene, SceneError};

pub use self::gltf::{gltf_document, GltfDocument};

/// Why a scene could not be saved.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Writing failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// Writing the CSF file failed.
    #[error(transparent)]
    Csf(#[from] CsfFileError),
    /// A geometry could not be read back to be written (a page file that fails).
    #[error("{}: {why}", path.display())]
    Geometry {
        /// The file being written.
        path: PathBuf,
        /// Why, naming the geometry.
        why: String,
    },
    /// The extension names no format cadr writes.
    #[error("{}: unknown output format (expected .gltf, .glb, .csf or .csf.gz)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Writes `scene` to `path` in the format its extension names; returns notes on what the
/// format could not keep (empty when nothing was lost). glTF is made whole in memory first;
/// CSF is written one geometry at a time (see [`save_csf_outline`]).
pub fn save_scene(scene: &Scene, path: &Path) -> Result<Vec<String>, SaveError> {
    let io = |source| SaveError::Io {
        path: path.to_owned(),
        source,
    };
    let mut notes = Vec::new();
    let paths = flatten(scene)?.instances.len();
    let meshes = scene.nodes.iter().filter(|n| n.mesh.is_some()).count();
    match SceneFormat::from_path(path) {
        Some(format @ (SceneFormat::Gltf | SceneFormat::Glb)) => {
            let document = gltf_document(scene)?;
            if document.unfolded_nodes > scene.nodes.len() {
                notes.push(format!(
                    "glTF nodes have one parent: shared subgraphs were unfolded ({} nodes became {}); meshes stay shared",
                    scene.nodes.len(),
                    document.unfolded_nodes
                ));
            }
            let wire: usize = scene
                .geometries
                .iter()
                .map(|g| g.wire_indices.len() / 2)
                .sum();
            if wire > 0 {
                notes.push(format!(
                    "{wire} edges (wire indices) are not written: glTF has no place for them"
                ));
            }
            if format == SceneFormat::Glb {
                std::fs::write(path, document.to_glb()).map_err(io)?;
            } else {
                let bin_name = format!(
                    "{}.bin",
                    path.file_stem()
                        .map(|s| s.to_string_lossy().into_owned())
                        .unwrap_or_else(|| "scene".into())
                );
                let bin_path = path.with_file_name(&bin_name);
                std::fs::write(&bin_path, &document.binary).map_err(|source| SaveError::Io {
                    path: bin_path.clone(),
                    source,
                })?;
                std::fs::write(path, document.json_with_uri(&bin_name)).map_err(io)?;
            }
        }
        Some(SceneFormat::Csf | SceneFormat::CsfGz) => {
            scene.validate()?;
            notes = save_csf_outline(scene, scene, path)?;
        }
        None => {
            return Err(SaveError::UnknownFormat {
                path: path.to_owned(),
            })
        }
    }
    log::debug!(
        "saved {} ({meshes} mesh nodes, {paths} instances)",
        path.display()
    );
    Ok(notes)
}

/// Writes the scene outlined by `outline` to the CSF file `path` (`.csf`, or `.csf.gz`
/// compressed), its geometries read one at a time from `geometries` (the outline's may be
/// stand-ins, as a load through a [`crate::scene::GeometrySink`] leaves them): no more than one
/// geometry and a few megabytes of the file are held, so that a scene larger than memory can be
/// converted. Returns notes on what CSF could not keep.
pub fn save_csf_outline(
    outline: &Scene,
    geometries: &dyn GeometryStore,
    path: &Path,
) -> Result<Vec<String>, SaveError> {
    outline.validate_outline_references()?;
    if geometries.geometry_count() != outline.geometries.len() {
        return Err(SaveError::Scene(SceneError(format!(
            "{} geometries to write for the {} of the scene",
            geometries.geometry_count(),
            outline.geometries.len()
        ))));
    }
    let mut notes = Vec::new();
    let file = csf_outline_from_scene(outline);
    if file.nodes.len() > outline.nodes.len() + 1 {
        notes.push(format!(
            "CSF nodes are a tree: shared subgraphs were unfolded ({} nodes became {}); geometries stay shared",
            outline.nodes.len(),
            file.nodes.len()
        ));
    }
    let textured = outline
        .materials
        .iter()
        .filter(|m| m.base_color_texture.is_some())
        .count();
    if textured > 0 {
        notes.push(format!(
            "{} textures used by {textured} materials are not written: CSF has no textures",
            outline.textures.len()
        ));
    }
    let mut source = CsfGeometriesOf::new(geometries);
    save_csf_from(&file, &mut source, path).map_err(|error| match error {
        SaveCsfError::File(error) => SaveError::Csf(error),
        SaveCsfError::Geometry(why) => SaveError::Geometry {
            path: path.to_owned(),
            why,
        },
    })?;
    if source.attributed > 0 {
        notes.push(format!(
            "the texture coordinates and vertex colours of {} geometries are not written: cadr's CSF writer keeps positions and normals",
            source.attributed
        ));
    }
    Ok(notes)
}
