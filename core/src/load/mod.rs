//! Loading scenes from files and generators.
//!
//! A scene is named by a [`SceneSource`]: a path to a `.gltf`/`.glb` file, or `gen:NAME[:k=v,...]`
//! for a built-in generator (see [`crate::generate`]).

mod gltf;
mod gltf_buffers;
mod gltf_textures;

pub use self::gltf::load_gltf_bytes;
pub use self::gltf_buffers::BYTES_BETWEEN_RELEASES as GLTF_BYTES_BETWEEN_RELEASES;

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use crate::generate::{self, GeneratorSpec};
use crate::graph::LoadedGeometries;
#[cfg(doc)]
use crate::graph::SceneGraph;
use crate::scene::{GeometrySink, KeepInScene, Scene};

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
    /// A CSF file could not be read or is malformed.
    #[error(transparent)]
    Csf(#[from] crate::csf::CsfFileError),
    /// The file's extension is not one cadr reads.
    #[error("{}: unknown scene format (expected .gltf, .glb, .csf or .csf.gz, or gen:NAME for a generator)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A `gen:` source that names no generator or has bad parameters.
    #[error("{0}")]
    Generator(String),
    /// Reading the file panicked, in cadr or in a dependency, and the load's panic boundary
    /// caught it ([`crate::panic_boundary`]): the file is refused, and the panic (a bug to
    /// report, with the file) is logged with its location.
    #[error("{}: the file could not be read: {READER_PANIC} ({})", path.display(), panic.message)]
    ReaderPanicked {
        /// The file.
        path: PathBuf,
        /// What panicked, and where.
        panic: crate::panic_boundary::CaughtPanic,
    },
}

/// What a [`LoadError::ReaderPanicked`] says of itself, so that a caller that sees only the
/// text (a C host, a fuzz target through the C API) can tell a caught panic from a refusal.
pub const READER_PANIC: &str = "its reader hit an internal error (a bug in cadr or a library it uses; please report it with the file)";

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
        self.load_through(&mut KeepInScene)
    }

    /// [`SceneSource::load`], handing each geometry to `sink` as it is made (see
    /// [`GeometrySink`]).
    pub fn load_through(&self, sink: &mut dyn GeometrySink) -> Result<Scene, LoadError> {
        crate::timings::time(crate::timings::Phase::Load, || match self {
            Self::File(path) => read_file(path, sink),
            Self::Generator(spec) => Ok(generate::generate_through(spec, sink)),
        })
    }

    /// Loads the scene for a graph ([`SceneGraph::import_loaded`]): each geometry is taken as
    /// soon as it is made, kept in memory up to `memory_limit` bytes (the graph's
    /// [`SceneGraph::geometry_memory_left`]) and written to a page file beyond it, so that a
    /// model larger than memory loads. Returns the scene's outline (stand-ins for the
    /// geometries) and the geometries.
    pub fn load_for_graph(
        &self,
        memory_limit: u64,
    ) -> Result<(Scene, LoadedGeometries), LoadError> {
        let mut geometries = LoadedGeometries::new(memory_limit);
        let outline = self.load_through(&mut geometries)?;
        Ok((outline, geometries))
    }
}

/// Scene file formats cadr reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// glTF 2.0 JSON with external or embedded buffers.
    Gltf,
    /// glTF 2.0 binary.
    Glb,
    /// CSF, uncompressed.
    Csf,
    /// CSF, gzip-compressed.
    CsfGz,
}

impl SceneFormat {
    /// The format a file name's extension says (`.gltf`, `.glb`, `.csf`, `.csf.gz`).
    pub fn from_path(path: &Path) -> Option<Self> {
        let name = path.file_name()?.to_string_lossy().to_lowercase();
        [
            (".csf.gz", Self::CsfGz),
            (".csf", Self::Csf),
            (".gltf", Self::Gltf),
            (".glb", Self::Glb),
        ]
        .into_iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map(|(_, format)| format)
    }
}

/// Loads a scene file, choosing the format by extension.
pub fn load_file(path: &Path) -> Result<Scene, LoadError> {
    read_file(path, &mut KeepInScene)
}

/// [`load_file`], handing each geometry to `sink` as it is made. The file is never read whole:
/// a CSF file is read where each of its arrays lies (a `.csf.gz` from a temporary file it is
/// unpacked into as it streams), a glTF file's buffers a mesh's accessors at a time (see
/// `gltf_buffers.rs`).
fn read_file(path: &Path, sink: &mut dyn GeometrySink) -> Result<Scene, LoadError> {
    let format = SceneFormat::from_path(path).ok_or_else(|| LoadError::UnknownFormat {
        path: path.to_owned(),
    })?;
    read_behind_boundary(Input::File, format, path, sink)
}

/// Loads a scene from a file's bytes held in memory. `path` names the file in errors and, for
/// glTF, is where external buffers are looked up (beside it).
///
/// Runs behind a panic boundary: a panic while the file is read, validated or converted is
/// logged (as an error, with its location) and returned as [`LoadError::ReaderPanicked`].
pub fn load_bytes(bytes: &[u8], format: SceneFormat, path: &Path) -> Result<Scene, LoadError> {
    read_behind_boundary(
        Input::Bytes(Cow::Borrowed(bytes)),
        format,
        path,
        &mut KeepInScene,
    )
}

/// What a reader reads.
enum Input<'b> {
    /// The file's bytes; where owned, they go as soon as the reader no longer needs them.
    Bytes(Cow<'b, [u8]>),
    /// The file at the path, read as its format reads a file (see [`read_file`]).
    File,
}

/// [`read_input`] behind the load's panic boundary (see [`load_bytes`]).
fn read_behind_boundary(
    input: Input<'_>,
    format: SceneFormat,
    path: &Path,
    sink: &mut dyn GeometrySink,
) -> Result<Scene, LoadError> {
    crate::panic_boundary::catch(|| read_input(input, format, path, sink)).unwrap_or_else(|panic| {
        log::error!("{}: reading it {panic}", path.display());
        Err(LoadError::ReaderPanicked {
            path: path.to_owned(),
            panic,
        })
    })
}

/// With the `fault-injection` feature, the variable that makes every file read panic on a
/// worker thread, as a panic inside a dependency's decoder would: the tests of the load's panic
/// boundary set it.
#[cfg(feature = "fault-injection")]
pub const INJECTED_PANIC_VARIABLE: &str = "CADR_FAULT_READER_PANIC";

/// Reads a scene of `format` from `input`, handing each geometry to `sink`.
fn read_input(
    input: Input<'_>,
    format: SceneFormat,
    path: &Path,
    sink: &mut dyn GeometrySink,
) -> Result<Scene, LoadError> {
    #[cfg(feature = "fault-injection")]
    if std::env::var_os(INJECTED_PANIC_VARIABLE).is_some() {
        crate::parallel::map(&[false, true], |&injected| {
            assert!(!injected, "a panic injected by {INJECTED_PANIC_VARIABLE}");
        });
    }
    let scene = match (input, format) {
        (Input::Bytes(bytes), SceneFormat::Gltf | SceneFormat::Glb) => {
            return gltf::load_gltf_bytes_through(&bytes, path, sink);
        }
        (Input::File, SceneFormat::Gltf | SceneFormat::Glb) => {
            return gltf::load_gltf_file_through(path, sink);
        }
        (Input::Bytes(bytes), SceneFormat::Csf | SceneFormat::CsfGz) => {
            let gzip = format == SceneFormat::CsfGz;
            crate::csf::csf_scene_from_bytes(bytes, gzip, path, sink)?
        }
        (Input::File, SceneFormat::Csf | SceneFormat::CsfGz) => {
            let gzip = format == SceneFormat::CsfGz;
            crate::csf::csf_scene_from_file(path, gzip, sink)?
        }
    };
    scene.validate_outline().map_err(|e| LoadError::Invalid {
        path: path.to_owned(),
        message: e.0,
    })?;
    Ok(scene)
}

/// Parses and loads a command-line scene argument.
pub fn load_scene(text: &str) -> Result<Scene, LoadError> {
    SceneSource::parse(text)?.load()
}
