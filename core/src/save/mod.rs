//! Saving scenes: glTF 2.0 (`.gltf` with a `.bin` beside it, or `.glb`) and CSF (`.csf`,
//! `.csf.gz`). Each save reports what the target format cannot hold.

mod gltf;

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::csf::{
    csf_outline_from_scene, save_csf_from, CsfFileError, CsfGeometriesOf, SaveCsfError,
};
use crate::load::SceneFormat;
use crate::scene::{flatten, GeometryStore, Scene, SceneError};

pub use self::gltf::{gltf_document, gltf_document_from, Binary, GltfDocument, GltfError};

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
/// format could not keep (empty when nothing was lost). See [`save_outline`].
pub fn save_scene(scene: &Scene, path: &Path) -> Result<Vec<String>, SaveError> {
    scene.validate()?;
    let paths = flatten(scene)?.instances.len();
    let meshes = scene.nodes.iter().filter(|n| n.mesh.is_some()).count();
    let notes = save_outline(scene, scene, path)?;
    log::debug!(
        "saved {} ({meshes} mesh nodes, {paths} instances)",
        path.display()
    );
    Ok(notes)
}

/// Writes the scene outlined by `outline` to `path` in the format its extension names, its
/// geometries read one at a time from `geometries` (the outline's may be stand-ins, as a load
/// through a [`crate::scene::GeometrySink`] leaves them) and written as they are read: no
/// more than one geometry and a few megabytes of the file are held, so that a scene larger than
/// memory can be converted. A GLB's buffer is written to a temporary file in the page
/// directory first (its length comes before it in the file), then copied after the JSON (where
/// no temporary file can be made there, with a warning, it is made in memory). Returns notes on
/// what the format could not keep.
pub fn save_outline(
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
    match SceneFormat::from_path(path) {
        Some(format @ (SceneFormat::Gltf | SceneFormat::Glb)) => {
            save_gltf_outline(outline, geometries, path, format == SceneFormat::Glb)
        }
        Some(SceneFormat::Csf | SceneFormat::CsfGz) => save_csf_outline(outline, geometries, path),
        None => Err(SaveError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}

/// [`save_outline`] to glTF: a `.glb` where `binary_container`, else a `.gltf` with its buffer
/// in a `.bin` file beside it.
fn save_gltf_outline(
    outline: &Scene,
    geometries: &dyn GeometryStore,
    path: &Path,
    binary_container: bool,
) -> Result<Vec<String>, SaveError> {
    let io_at = |path: &Path| {
        let path = path.to_owned();
        move |source| SaveError::Io { path, source }
    };
    let made = |error| match error {
        GltfError::Scene(error) => SaveError::Scene(error),
        GltfError::Geometry(why) => SaveError::Geometry {
            path: path.to_owned(),
            why,
        },
    };
    let unfolded_nodes = if binary_container {
        let directory = crate::graph::page_directory();
        // The buffer in a temporary file, or where the page directory has no room, in memory.
        let (binary, _guard) =
            match crate::graph::temporary_file(&directory, "for the GLB's buffer") {
                Ok((buffer, guard)) => (Binary::to_file(buffer), Some(guard)),
                Err(error) => {
                    log::warn!("{}: {error}; the buffer is made in memory", path.display());
                    (Binary::Memory(Vec::new()), None)
                }
            };
        let document = gltf_document_from(outline, geometries, binary).map_err(made)?;
        let unfolded_nodes = document.unfolded_nodes;
        let mut output = std::io::BufWriter::new(std::fs::File::create(path).map_err(io_at(path))?);
        document
            .write_glb(&mut output)
            .and_then(|()| output.flush())
            .map_err(io_at(path))?;
        unfolded_nodes
    } else {
        let bin_name = format!(
            "{}.bin",
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into())
        );
        let bin_path = path.with_file_name(&bin_name);
        let buffer = std::fs::File::create(&bin_path).map_err(io_at(&bin_path))?;
        let document =
            gltf_document_from(outline, geometries, Binary::to_file(buffer)).map_err(made)?;
        let json = document.json_with_uri(&bin_name);
        let unfolded_nodes = document.unfolded_nodes;
        if let Some(written) = document.binary.finish() {
            written.map_err(io_at(&bin_path))?;
        }
        std::fs::write(path, json).map_err(io_at(path))?;
        unfolded_nodes
    };
    let mut notes = Vec::new();
    if unfolded_nodes > outline.nodes.len() {
        notes.push(format!(
            "glTF nodes have one parent: shared subgraphs were unfolded ({} nodes became {unfolded_nodes}); meshes stay shared",
            outline.nodes.len(),
        ));
    }
    let wire: usize = (outline.geometries.iter())
        .flat_map(|g| &g.parts)
        .map(|part| part.wire_index_count as usize / 2)
        .sum();
    if wire > 0 {
        notes.push(format!(
            "{wire} edges (wire indices) are not written: glTF has no place for them"
        ));
    }
    Ok(notes)
}

/// [`save_outline`] to CSF (`.csf`, or `.csf.gz` compressed, first written whole to a temporary
/// file in the page directory).
fn save_csf_outline(
    outline: &Scene,
    geometries: &dyn GeometryStore,
    path: &Path,
) -> Result<Vec<String>, SaveError> {
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
