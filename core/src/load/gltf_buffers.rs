//! The bytes of a glTF document and of its buffers, as the loader reads them, and the files
//! its URIs name.
//!
//! A file (the `.gltf` or `.glb` itself, a `.bin` beside it) is mapped into memory, not read:
//! the operating system reads its pages as the loader touches them, so a model larger than
//! memory loads. Touched pages count in the process's resident memory until they are given
//! back; the loader gives them back ([`GltfBuffers::release_mapped_pages`]) every
//! [`MAPPED_BYTES_BETWEEN_RELEASES`] of geometry converted, so that loading holds the memory
//! budget's geometry plus about that much of the file.
//!
//! A data URI is decoded into memory, and bytes the caller already holds
//! ([`super::load_bytes`]) are borrowed. A file that cannot be mapped (a file system without
//! mappings, a pipe) is read into memory instead.
//!
//! A mapped file must not shrink while it is loaded: reading a page past its new end stops the
//! process (`SIGBUS`), as with every program that maps its input.

use std::borrow::Cow;
use std::fs::File;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use memmap2::{Mmap, MmapOptions, UncheckedAdvice};

/// Bytes of geometry the loader converts between two [`GltfBuffers::release_mapped_pages`]
/// (standing for the accessors it reads): about what a load holds of a mapped file, beyond the
/// mesh being converted.
pub const MAPPED_BYTES_BETWEEN_RELEASES: u64 = 8 << 20;

/// The bytes of a file or a buffer.
#[derive(Clone)]
pub(super) enum SourceBytes<'a> {
    /// Bytes in memory: borrowed from the caller, or read or decoded by the loader.
    Memory(Cow<'a, [u8]>),
    /// A range of a file mapped into memory.
    Mapped {
        /// The mapping (shared by a GLB's document and its binary chunk).
        map: Arc<Mmap>,
        /// The bytes of the mapping that are these.
        range: Range<usize>,
    },
}

impl<'a> SourceBytes<'a> {
    /// The bytes.
    pub(super) fn bytes(&self) -> &[u8] {
        match self {
            Self::Memory(bytes) => bytes,
            Self::Mapped { map, range } => &map[range.clone()],
        }
    }

    /// The bytes of `range` within these, keeping a mapping (not copying it).
    pub(super) fn narrowed(self, range: Range<usize>) -> SourceBytes<'a> {
        match self {
            Self::Memory(Cow::Borrowed(bytes)) => Self::Memory(Cow::Borrowed(&bytes[range])),
            Self::Memory(Cow::Owned(mut bytes)) => {
                bytes.truncate(range.end);
                bytes.drain(..range.start);
                Self::Memory(Cow::Owned(bytes))
            }
            Self::Mapped { map, range: whole } => Self::Mapped {
                map,
                range: whole.start + range.start..whole.start + range.end,
            },
        }
    }

    /// Gives back the pages of a mapping that the process has touched: the next read of them
    /// reads the file again. Bytes in memory stay.
    fn release_pages(&mut self) {
        if let Self::Mapped { map, range } = self {
            if range.start == range.end {
                return;
            }
            // SAFETY: the mapping is a shared, read-only mapping of a file (`Mmap`); dropping
            // its pages only unmaps them from this process, and the next read faults them in
            // from the file again with the same bytes. `&mut self` means no slice of it is
            // borrowed meanwhile.
            let released = unsafe {
                map.unchecked_advise_range(UncheckedAdvice::DontNeed, range.start, range.len())
            };
            if let Err(e) = released {
                log::debug!("giving back the pages of a mapped glTF buffer failed: {e}");
            }
        }
    }
}

/// Opens a scene file for reading: a regular file is mapped (read whole where it cannot be),
/// anything else (a pipe) read whole.
pub(super) fn open_document(path: &Path) -> std::io::Result<SourceBytes<'static>> {
    let opened = File::open(path)?;
    let metadata = opened.metadata()?;
    if !metadata.is_file() {
        return std::fs::read(path).map(|bytes| SourceBytes::Memory(Cow::Owned(bytes)));
    }
    map_or_read(
        &opened,
        path,
        usize::try_from(metadata.len()).unwrap_or(usize::MAX),
    )
}

/// Opens the first `length` bytes of a buffer's (or an image's) file. Only a regular file is opened, and no
/// more than the buffer declares is mapped: a URI naming a device or a pipe (`/dev/zero`) must
/// not hang cadr or take all of its memory.
pub(super) fn open_buffer_file(
    file: &Path,
    length: usize,
) -> std::io::Result<SourceBytes<'static>> {
    let opened = File::open(file)?;
    let metadata = opened.metadata()?;
    if !metadata.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "it is not a regular file",
        ));
    }
    let wanted = (length as u64).min(metadata.len());
    map_or_read(&opened, file, usize::try_from(wanted).unwrap_or(usize::MAX))
}

/// The first `length` bytes of the regular file `opened` (at `path`), mapped, or read where
/// the file cannot be mapped.
fn map_or_read(opened: &File, path: &Path, length: usize) -> std::io::Result<SourceBytes<'static>> {
    if length == 0 {
        return Ok(SourceBytes::Memory(Cow::Owned(Vec::new())));
    }
    // SAFETY: the mapping is read-only and cadr never writes the file. Another process shrinking the file while it is loaded would make a read of the lost
    // pages stop the process (`SIGBUS`), as the module's documentation says.
    let mapped = unsafe { MmapOptions::new().len(length).map(opened) };
    match mapped {
        Ok(map) => Ok(SourceBytes::Mapped {
            map: Arc::new(map),
            range: 0..length,
        }),
        Err(e) => {
            log::debug!(
                "{}: cannot be mapped ({e}); reading it whole",
                path.display()
            );
            let mut data = Vec::new();
            std::io::Read::read_to_end(&mut std::io::Read::take(opened, length as u64), &mut data)?;
            Ok(SourceBytes::Memory(Cow::Owned(data)))
        }
    }
}

/// A glTF document's buffers, in the document's order.
pub(super) struct GltfBuffers<'a>(pub(super) Vec<SourceBytes<'a>>);

impl GltfBuffers<'_> {
    /// Buffer `index`'s bytes.
    pub(super) fn get(&self, index: usize) -> Option<&[u8]> {
        self.0.get(index).map(SourceBytes::bytes)
    }

    /// Gives back the pages of the mapped buffers that loading has touched so far.
    pub(super) fn release_mapped_pages(&mut self) {
        self.0.iter_mut().for_each(SourceBytes::release_pages);
    }
}

/// The path a URI names, its `%XX` escapes decoded.
pub(super) fn percent_decode(uri: &str) -> PathBuf {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}
