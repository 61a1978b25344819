//! CSF, the nvpro "cadscene file" of the seed samples (`.csf`, `.csf.gz`), versions 2 to 6.
//!
//! [`CsfFile`] mirrors the file's structures faithfully (so a file read and written again keeps
//! what cadr does not use: texture coordinates, aux channels, per-part channels, material and
//! meta payloads). [`read_csf`] parses it by schema, checking every offset, count and alignment
//! against the file and naming the structure, index and field of any problem; the file's
//! pointer table is not needed for that and is ignored. [`write_csf`] writes the reference
//! layout of version 6 (depth-first, the same alignments, the pointer table at the end), or an
//! older version's layout for compatibility tests; [`write_csf_file`] the same to a file, a
//! geometry at a time, for a scene larger than memory. [`scene_from_csf`] and [`csf_from_scene`]
//! convert to and from cadr's [`Scene`](crate::scene::Scene).

mod convert;
mod read;
mod write;

pub use convert::{
    csf_from_scene, csf_outline_from_scene, scene_from_csf, scene_from_csf_source, CsfGeometriesOf,
};
pub use read::{read_csf, read_csf_from, read_csf_through, CsfBytes, TakeCsfGeometry};
pub use write::{write_csf, write_csf_bytes, write_csf_file, CsfGeometries, CsfWriteError};

use std::borrow::Cow;
use std::io::Read as _;
use std::path::Path;

use crate::graph::{temporary_file, RemovedOnDrop};

/// `CADSCENEFILE_MAGIC`.
pub const MAGIC: i32 = 1_567_262_451;
/// The newest version, the one [`write_csf`] writes by default.
pub const VERSION: i32 = 6;
/// The oldest version a reader accepts (version 1 is a binary break).
pub const VERSION_COMPAT: i32 = 2;
/// File flag: every node is referenced once (a tree).
pub const FLAG_UNIQUE_NODES: u32 = 1;
/// File flag: triangle strips (never set by the reference writers; not supported).
pub const FLAG_STRIPS: u32 = 2;
/// File flag: parts own vertex sub-ranges (given by the VERTEXRANGE part channel).
pub const FLAG_PER_PART_VERTICES: u32 = 32;
/// GUID of the glTF 2 material packet in material payloads.
pub const GUID_MATERIAL_GLTF2: [u32; 4] = [0, 0, 0, 2];
/// Part channel enum: per-part bounding box (24 bytes).
pub const PART_CHANNEL_BBOX: i32 = 0;
/// Part channel enum: per-part vertex range (8 bytes).
pub const PART_CHANNEL_VERTEXRANGE: i32 = 1;

/// A whole CSF file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CsfFile {
    /// Format version (2..=6) the file was read as; writing uses the version asked for.
    pub version: i32,
    /// `fileFlags` (after the v<3 fix-up, a bit field).
    pub file_flags: u32,
    /// Root node, or negative for a flat list of instances.
    pub root: i32,
    /// Geometries.
    pub geometries: Vec<CsfGeometry>,
    /// Materials.
    pub materials: Vec<CsfMaterial>,
    /// Nodes.
    pub nodes: Vec<CsfNode>,
    /// Per-node metadata (v ≥ 5), empty or one per node.
    pub node_metas: Vec<CsfMeta>,
    /// Per-geometry metadata (v ≥ 5), empty or one per geometry.
    pub geometry_metas: Vec<CsfMeta>,
    /// File metadata (v ≥ 5).
    pub file_meta: Option<CsfMeta>,
}

/// `CSFGeometry`: vertex channels, solid (triangle) and wire (line) indices, parts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CsfGeometry {
    /// Positions, 3 floats per vertex.
    pub vertices: Vec<f32>,
    /// Normal channels, channel-major, 3 floats per vertex each.
    pub normals: Vec<f32>,
    /// Number of normal channels in `normals`.
    pub normal_channels: i32,
    /// Texture coordinate channels, channel-major, 2 floats per vertex each.
    pub tex: Vec<f32>,
    /// Number of texture coordinate channels.
    pub tex_channels: i32,
    /// Aux channels (vec4 per vertex each), in `aux_storage_order`.
    pub aux: Vec<f32>,
    /// Which aux channel (RADIANCE 0, TANGENT 1) each stored aux array is.
    pub aux_storage_order: Vec<i32>,
    /// Per-part channel bytes, channel after channel in `perpart_storage_order`.
    pub perpart: Vec<u8>,
    /// Which per-part channel (BBOX 0, VERTEXRANGE 1) each stored array is.
    pub perpart_storage_order: Vec<i32>,
    /// Triangle-list indices.
    pub index_solid: Vec<u32>,
    /// Line-list indices (edges).
    pub index_wire: Vec<u32>,
    /// Parts: consecutive ranges of the solid and wire indices.
    pub parts: Vec<CsfGeometryPart>,
}

impl CsfGeometry {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len() / 3
    }

    /// The per-part vertex ranges `(begin, count)`, when the VERTEXRANGE channel is stored.
    pub fn part_vertex_ranges(&self) -> Option<Vec<(u32, u32)>> {
        let parts = self.parts.len();
        let mut offset = 0;
        for &channel in &self.perpart_storage_order {
            let size = part_channel_size(channel)?;
            if channel == PART_CHANNEL_VERTEXRANGE {
                let bytes = self.perpart.get(offset..offset + size * parts)?;
                return Some(
                    bytes
                        .chunks_exact(8)
                        .map(|c| (le_u32(&c[0..4]), le_u32(&c[4..8])))
                        .collect(),
                );
            }
            offset += size * parts;
        }
        None
    }
}

/// Bytes per part of a part channel, `None` for an unknown channel.
pub fn part_channel_size(channel: i32) -> Option<usize> {
    match channel {
        PART_CHANNEL_BBOX => Some(24),
        PART_CHANNEL_VERTEXRANGE => Some(8),
        _ => None,
    }
}

fn le_u32(bytes: &[u8]) -> u32 {
    u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
}

/// `CSFGeometryPart`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CsfGeometryPart {
    /// Deprecated per-part vertex count, kept for round trips.
    pub deprecated: i32,
    /// Solid indices of the part.
    pub num_index_solid: i32,
    /// Wire indices of the part.
    pub num_index_wire: i32,
}

/// `CSFMaterial`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CsfMaterial {
    /// Name (at most 127 bytes are stored).
    pub name: String,
    /// RGBA colour (the samples use it as diffuse).
    pub color: [f32; 4],
    /// User data.
    pub kind: i32,
    /// Payload: a sequence of byte packets (see [`GUID_MATERIAL_GLTF2`]).
    pub bytes: Vec<u8>,
}

/// `CSFMeta`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CsfMeta {
    /// Name (at most 127 bytes are stored).
    pub name: String,
    /// User flags.
    pub flags: i32,
    /// Payload: a sequence of byte packets.
    pub bytes: Vec<u8>,
}

/// `CSFNode`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CsfNode {
    /// Local transform, column-major.
    pub object_tm: [f32; 16],
    /// World transform as stored (recomputable from the tree).
    pub world_tm: [f32; 16],
    /// Geometry index or -1.
    pub geometry: i32,
    /// One per geometry part.
    pub parts: Vec<CsfNodePart>,
    /// Child node indices.
    pub children: Vec<i32>,
}

/// `CSFNodePart`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CsfNodePart {
    /// 1 when drawn ("should always be 1").
    pub active: i32,
    /// Material index.
    pub material: i32,
    /// -1, or a child node whose matrix the part uses instead of the owning node's.
    pub node: i32,
}

/// A malformed CSF file: names the structure (with its index), the field and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{structure} {field}: {problem}")]
pub struct CsfError {
    /// The structure, e.g. "header" or "geometry 3".
    pub structure: String,
    /// The field, e.g. "indexSolidOFFSET".
    pub field: &'static str,
    /// What is wrong.
    pub problem: String,
}

/// A [`CsfError`] for `field` of `structure`.
pub(crate) fn error(
    structure: impl Into<String>,
    field: &'static str,
    problem: impl Into<String>,
) -> CsfError {
    CsfError {
        structure: structure.into(),
        field,
        problem: problem.into(),
    }
}

/// Why a CSF file could not be loaded or saved.
#[derive(Debug, thiserror::Error)]
pub enum CsfFileError {
    /// Reading, decompressing or writing failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// The content is malformed.
    #[error("{}: {source}", path.display())]
    Malformed {
        /// The file.
        path: std::path::PathBuf,
        /// The problem.
        #[source]
        source: CsfError,
    },
}

/// Whether `path` names a gzip-compressed CSF (`.csf.gz`, or any `.gz`).
pub fn is_gzip_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// The most bytes a `.csf.gz` may decompress to unless `CADR_MAX_DECOMPRESSED_BYTES` says
/// otherwise: a small file must not make cadr take all of the host's memory.
pub const DEFAULT_MAX_DECOMPRESSED_BYTES: u64 = 8 << 30;

/// The variable that sets the decompression limit, in bytes.
pub const MAX_DECOMPRESSED_VARIABLE: &str = "CADR_MAX_DECOMPRESSED_BYTES";

fn decompression_limit() -> u64 {
    std::env::var(MAX_DECOMPRESSED_VARIABLE)
        .ok()
        .and_then(|text| text.trim().parse().ok())
        .unwrap_or(DEFAULT_MAX_DECOMPRESSED_BYTES)
}

/// Decompresses gzip `raw`, refusing (before holding more) data that grows past `limit` bytes.
pub fn gunzip_within(raw: &[u8], limit: u64) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(raw)
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)?;
    if out.len() as u64 > limit {
        return Err(past_the_limit(raw.len() as u64, limit));
    }
    Ok(out)
}

/// The error of a gzip file of `compressed` bytes that decompresses past `limit` bytes.
fn past_the_limit(compressed: u64, limit: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!(
            "its {compressed} compressed bytes decompress to more than {limit} bytes, the limit ({MAX_DECOMPRESSED_VARIABLE} raises it)"
        ),
    )
}

/// The gzip file `compressed` decompressed, as it streams, into a temporary file in `directory`
/// (see [`crate::graph::temporary_file`]), within `limit` bytes (the decompression limit): so
/// that neither the compressed nor the decompressed bytes are ever held whole.
fn unpacked(
    compressed: std::fs::File,
    directory: &Path,
    limit: u64,
) -> std::io::Result<(std::fs::File, RemovedOnDrop)> {
    use std::io::{Seek as _, Write as _};
    let compressed_bytes = compressed.metadata()?.len();
    let (mut file, guard) = temporary_file(directory, "to unpack it into")?;
    let mut decoder = flate2::read::GzDecoder::new(std::io::BufReader::new(compressed))
        .take(limit.saturating_add(1));
    let mut writer = std::io::BufWriter::new(&mut file);
    let written = std::io::copy(&mut decoder, &mut writer)?;
    writer.flush()?;
    drop(writer);
    if written > limit {
        return Err(past_the_limit(compressed_bytes, limit));
    }
    file.rewind()?;
    Ok((file, guard))
}

/// Reads a `.csf` or `.csf.gz` file.
pub fn load_csf(path: &Path) -> Result<CsfFile, CsfFileError> {
    let raw = std::fs::read(path).map_err(|source| CsfFileError::Io {
        path: path.to_owned(),
        source,
    })?;
    csf_from_bytes(&raw, is_gzip_path(path), path)
}

/// A CSF file's bytes, decompressed (within the decompression limit) when `gzip` is true; the
/// compressed bytes, where owned, go once decompressed.
fn plain_bytes<'r>(
    raw: Cow<'r, [u8]>,
    gzip: bool,
    path: &Path,
) -> Result<Cow<'r, [u8]>, CsfFileError> {
    if !gzip {
        return Ok(raw);
    }
    gunzip_within(&raw, decompression_limit())
        .map(Cow::Owned)
        .map_err(|source| CsfFileError::Io {
            path: path.to_owned(),
            source,
        })
}

/// Reads a CSF file's bytes held in memory, gzip-compressed when `gzip` is true; `path` names
/// the file in errors.
pub fn csf_from_bytes(raw: &[u8], gzip: bool, path: &Path) -> Result<CsfFile, CsfFileError> {
    let bytes = plain_bytes(Cow::Borrowed(raw), gzip, path)?;
    read_csf(&bytes).map_err(|source| CsfFileError::Malformed {
        path: path.to_owned(),
        source,
    })
}

/// The scene of a CSF file's bytes held in memory (gzip-compressed when `gzip` is true), read
/// and converted one geometry at a time, each handed to `sink` (see [`scene_from_csf_source`]);
/// `path` names the file in errors, and the scene is named after it.
pub fn csf_scene_from_bytes(
    raw: Cow<'_, [u8]>,
    gzip: bool,
    path: &Path,
    sink: &mut dyn crate::scene::GeometrySink,
) -> Result<crate::scene::Scene, CsfFileError> {
    let plain = plain_bytes(raw, gzip, path)?;
    scene_named_after(path, CsfBytes::Memory(&plain), sink)
}

/// The scene of a CSF file, read from the file where each array lies and converted one
/// geometry at a time, each handed to `sink` (see [`scene_from_csf_source`]): the file is never
/// held whole. A gzip-compressed one (`gzip`, a `.csf.gz`) is first decompressed as it streams
/// into a temporary file (see `unpacked`) and read from there. The scene is named after the file.
pub fn csf_scene_from_file(
    path: &Path,
    gzip: bool,
    sink: &mut dyn crate::scene::GeometrySink,
) -> Result<crate::scene::Scene, CsfFileError> {
    let io = |source| CsfFileError::Io {
        path: path.to_owned(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    // The guard, where there is one, lives until the file is read.
    let (file, _unpacked) = if gzip {
        let directory = crate::graph::page_directory();
        unpacked(file, &directory, decompression_limit()).map_err(io)?
    } else {
        (file, RemovedOnDrop::nothing())
    };
    let len = file.metadata().map_err(io)?.len();
    let bytes = CsfBytes::File {
        file: std::cell::RefCell::new(file),
        len,
    };
    scene_named_after(path, bytes, sink)
}

/// The scene of the CSF file at `path`, read from `bytes`, named after the file.
fn scene_named_after(
    path: &Path,
    bytes: CsfBytes<'_>,
    sink: &mut dyn crate::scene::GeometrySink,
) -> Result<crate::scene::Scene, CsfFileError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    scene_from_csf_source(bytes, &name, sink).map_err(|source| CsfFileError::Malformed {
        path: path.to_owned(),
        source,
    })
}

/// Writes `file` as version 6 to `path`, gzip-compressed when the name ends in `.gz`.
pub fn save_csf(file: &CsfFile, path: &Path) -> Result<(), CsfFileError> {
    save_csf_from(file, &mut file.geometries.as_slice(), path).map_err(|error| match error {
        SaveCsfError::File(error) => error,
        SaveCsfError::Geometry(never) => match never {},
    })
}

/// Why [`save_csf_from`] failed.
#[derive(Debug)]
pub enum SaveCsfError<E> {
    /// Writing the file failed.
    File(CsfFileError),
    /// A geometry could not be had from its source.
    Geometry(E),
}

/// Writes `file` as version 6 to `path`, gzip-compressed when the name ends in `.gz`, its
/// geometries taken one at a time from `geometries` (`file.geometries` is not read): no more
/// than one geometry and a few megabytes of the file are held, however large it is. A `.gz`
/// file is written whole to a temporary file in the page directory first (see
/// `graph::page_file`), then compressed as it streams from there (where no temporary file can be
/// made there, with a warning, it is made whole in memory).
pub fn save_csf_from<G: CsfGeometries>(
    file: &CsfFile,
    geometries: &mut G,
    path: &Path,
) -> Result<(), SaveCsfError<G::Error>> {
    let io = |source| {
        SaveCsfError::File(CsfFileError::Io {
            path: path.to_owned(),
            source,
        })
    };
    let written = |error| match error {
        CsfWriteError::Geometry(error) => SaveCsfError::Geometry(error),
        CsfWriteError::Io(source) => io(source),
    };
    if !is_gzip_path(path) {
        let mut output = std::fs::File::create(path).map_err(io)?;
        return write_csf_file(file, geometries, VERSION, &mut output).map_err(written);
    }
    use std::io::{Seek as _, Write as _};
    let directory = crate::graph::page_directory();
    let output = std::fs::File::create(path).map_err(io)?;
    let mut encoder = flate2::write::GzEncoder::new(
        std::io::BufWriter::new(output),
        flate2::Compression::default(),
    );
    match temporary_file(&directory, "to write it into") {
        Ok((mut unpacked, _guard)) => {
            write_csf_file(file, geometries, VERSION, &mut unpacked).map_err(written)?;
            unpacked.rewind().map_err(io)?;
            std::io::copy(&mut std::io::BufReader::new(unpacked), &mut encoder).map_err(io)?;
        }
        // No room in the page directory: the file is made whole in memory instead.
        Err(error) => {
            log::warn!("{}: {error}; the file is made in memory", path.display());
            let bytes =
                write_csf_bytes(file, geometries, VERSION).map_err(SaveCsfError::Geometry)?;
            encoder.write_all(&bytes).map_err(io)?;
        }
    }
    encoder
        .finish()
        .and_then(|mut writer| writer.flush())
        .map_err(io)
}

#[cfg(test)]
mod decompression_tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
    use super::*;
    use std::io::Write;

    fn gzip(bytes: &[u8]) -> Vec<u8> {
        let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        encoder.write_all(bytes).expect("compress");
        encoder.finish().expect("compress")
    }

    #[test]
    fn a_small_file_that_decompresses_past_the_limit_is_refused() {
        // 4 MiB of zeros compress to a few KiB: a bomb in miniature.
        let bomb = gzip(&vec![0u8; 4 << 20]);
        assert!(bomb.len() < 64 << 10);
        let refused = gunzip_within(&bomb, 1 << 20).expect_err("past the limit");
        assert!(
            refused.to_string().contains("more than 1048576 bytes"),
            "{refused}"
        );
        assert_eq!(
            gunzip_within(&bomb, 4 << 20).map(|v| v.len()).ok(),
            Some(4 << 20)
        );
    }

    #[test]
    fn a_file_unpacks_into_a_temporary_file_that_leaves_nothing_behind() {
        use std::io::Read as _;
        let directory =
            std::env::temp_dir().join(format!("cadr-unpack-test-{}", std::process::id()));
        std::fs::create_dir_all(&directory).unwrap();
        let plain: Vec<u8> = (0..3_000_000_u32).map(|i| (i % 251) as u8).collect();
        let compressed_path = directory.join("plain.gz");
        std::fs::write(&compressed_path, gzip(&plain)).unwrap();
        let open = || std::fs::File::open(&compressed_path).unwrap();
        let entries = || std::fs::read_dir(&directory).unwrap().count();

        let (mut file, guard) = unpacked(open(), &directory, 4 << 20).unwrap();
        // Removed from the directory while open (Linux allows it): only the gzip file is there.
        assert_eq!(entries(), 1);
        let mut unpacked_bytes = Vec::new();
        file.read_to_end(&mut unpacked_bytes).unwrap();
        assert!(unpacked_bytes == plain, "the unpacked bytes differ");
        drop((file, guard));

        let refused = unpacked(open(), &directory, 1 << 20).expect_err("past the limit");
        assert!(
            refused.to_string().contains(MAX_DECOMPRESSED_VARIABLE),
            "{refused}"
        );
        assert_eq!(entries(), 1, "a refused unpack leaves nothing behind");
        std::fs::remove_dir_all(&directory).unwrap();
    }
}
