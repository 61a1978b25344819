//! Loading scenes from files and generators.
//!
//! A scene is named by a [`SceneSource`]: a path to a `.gltf`/`.glb` file, or `gen:NAME[:k=v,...]`
//! for a built-in generator (see [`crate::generate`]).

mod gltf;

pub use self::gltf::{load_gltf, load_gltf_bytes};

use std::path::{Path, PathBuf};

use crate::generate::{self, GeneratorSpec};
use crate::scene::Scene;

/// Why a scene could not be loaded. Every variant names the file (or generator) and, for bad
/// content, the item and field at fault.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The glTF parser rejected the file (bad JSON, bad GLB header or chunk, failed validation).
    #[error("{}: not a valid glTF file: {message}", path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// The file parsed, but its content is inconsistent.
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the item.
        message: String,
    },
    /// The file's extension is not one cadr reads.
    #[error("{}: unknown scene format (expected .gltf or .glb, or gen:NAME for a generator)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A `gen:` source that names no generator or has bad parameters.
    #[error("{0}")]
    Generator(String),
}

/// Where a scene comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A file.
    File(PathBuf),
    /// A built-in generator.
    Generator(GeneratorSpec),
}

impl SceneSource {
    /// Parses a command-line scene argument: `gen:...` is a generator, anything else a path.
    pub fn parse(text: &str) -> Result<Self, LoadError> {
        match text.strip_prefix("gen:") {
            Some(spec) => GeneratorSpec::parse(spec)
                .map(Self::Generator)
                .map_err(LoadError::Generator),
            None => Ok(Self::File(PathBuf::from(text))),
        }
    }

    /// Loads or generates the scene.
    pub fn load(&self) -> Result<Scene, LoadError> {
        match self {
            Self::File(path) => load_file(path),
            Self::Generator(spec) => Ok(generate::generate(spec)),
        }
    }
}

/// Loads a scene file, choosing the format by extension.
pub fn load_file(path: &Path) -> Result<Scene, LoadError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    match extension.as_str() {
        "gltf" | "glb" => load_gltf(path),
        _ => Err(LoadError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}

/// Parses and loads a command-line scene argument.
pub fn load_scene(text: &str) -> Result<Scene, LoadError> {
    SceneSource::parse(text)?.load()
}
