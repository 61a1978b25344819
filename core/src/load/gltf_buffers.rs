//! The bytes of a glTF document and of the buffers it names, as the loader reads them, and the
//! files its URIs name.
//!
//! No file is read whole. Of a GLB, the header and the JSON chunk are read ([`open_document`];
//! a `.gltf` is its JSON, read whole); its binary chunk, and each `.bin` file the document
//! names, is a [`FileWindow`]: memory reserved for all of its bytes, which costs nothing until
//! written, into which the loader reads, before each mesh, the bytes of the accessors the mesh
//! reads ([`GltfBuffers::read`]), and before the textures those of the images. Every
//! [`BYTES_BETWEEN_RELEASES`] of geometry converted it gives the memory read into back,
//! reserving it anew ([`GltfBuffers::release`]), so that loading holds the memory budget's
//! geometry plus about that much of the file, and a model larger than memory loads.
//!
//! The file is read, not mapped: a file changed or cut short while it loads makes a read fail
//! (an error that names the buffer), where a mapping's lost pages would stop the process.
//! Bytes the caller already holds ([`super::load_bytes`]) are borrowed; a data URI is decoded
//! into memory.

use std::borrow::Cow;
use std::fs::File;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use memmap2::{MmapMut, MmapOptions};

use super::LoadError;

/// Bytes of geometry the glTF loader converts between two releases of the memory it read its
/// buffers into (the geometry standing for the accessors it reads): about what a load holds of
/// a file's buffers, beyond the mesh being converted.
pub const BYTES_BETWEEN_RELEASES: u64 = 8 << 20;

/// A buffer's bytes (or an image's).
pub(super) enum SourceBytes<'a> {
    /// Bytes in memory: borrowed from the caller, or decoded or read by the loader.
    Memory(Cow<'a, [u8]>),
    /// A stretch of a file, read into memory where the loader asks.
    File(FileWindow),
}

impl<'a> SourceBytes<'a> {
    /// The bytes (of a [`FileWindow`], those read so far; the others are zero).
    pub(super) fn bytes(&self) -> &[u8] {
        match self {
            Self::Memory(bytes) => bytes,
            Self::File(window) => &window.memory,
        }
    }

    /// The same bytes again (a second buffer naming a GLB's binary chunk): a window of the
    /// same stretch, none of it read; `None` where no memory can be reserved for it.
    pub(super) fn duplicate(&self) -> Option<SourceBytes<'a>> {
        match self {
            Self::Memory(bytes) => Some(Self::Memory(bytes.clone())),
            Self::File(window) => FileWindow::new(
                Arc::clone(&window.file),
                &window.path,
                window.start,
                window.memory.len(),
            )
            .map(Self::File),
        }
    }
}

/// A stretch of a file, with memory reserved for all of it (anonymous, without swap reserved:
/// a page costs nothing until written) and read into it range by range.
pub(super) struct FileWindow {
    /// The file.
    file: Arc<File>,
    /// The file's path, for errors.
    path: PathBuf,
    /// Where the stretch begins in the file.
    start: u64,
    /// The stretch's bytes, where read.
    memory: MmapMut,
}

impl FileWindow {
    /// The `length` bytes of `file` (at `path`) from `start`, none read yet; `None` where no
    /// memory can be reserved for them.
    fn new(file: Arc<File>, path: &Path, start: u64, length: usize) -> Option<Self> {
        let memory = reserved(length)
            .map_err(|e| {
                log::debug!(
                    "{}: no memory reserved for {length} bytes ({e}); read whole",
                    path.display()
                )
            })
            .ok()?;
        Some(Self {
            file,
            path: path.to_owned(),
            start,
            memory,
        })
    }

    /// Reads `range` of the stretch from the file (the caller keeps it within the stretch).
    fn read(&mut self, range: Range<usize>) -> std::io::Result<()> {
        let at = self.start + range.start as u64;
        read_at(&self.file, at, &mut self.memory[range])
    }

    /// Gives back the memory of what was read, for memory reserved anew: the stretch reads as
    /// zeros again until read.
    fn release(&mut self) {
        match reserved(self.memory.len()) {
            Ok(fresh) => self.memory = fresh,
            Err(e) => log::debug!(
                "{}: the memory read of it is kept, none could be reserved anew: {e}",
                self.path.display()
            ),
        }
    }
}

/// `length` bytes of anonymous memory, reserved without swap: a page costs nothing until it
/// is written.
fn reserved(length: usize) -> std::io::Result<MmapMut> {
    MmapOptions::new().len(length).no_reserve_swap().map_anon()
}

/// Fills `into` with the bytes of `file` from `at`.
fn read_at(file: &File, at: u64, into: &mut [u8]) -> std::io::Result<()> {
    use std::io::{Read as _, Seek as _};
    let mut file = file;
    file.seek(std::io::SeekFrom::Start(at))?;
    file.read_exact(into)
}

/// The `length` bytes of the regular file `file` (at `path`) from `start`: a window read as
/// asked, or the bytes read whole where no memory can be reserved for a window.
fn stretch_of(
    file: File,
    path: &Path,
    start: u64,
    length: usize,
) -> std::io::Result<SourceBytes<'static>> {
    if length == 0 {
        return Ok(SourceBytes::Memory(Cow::Owned(Vec::new())));
    }
    let file = Arc::new(file);
    if let Some(window) = FileWindow::new(Arc::clone(&file), path, start, length) {
        return Ok(SourceBytes::File(window));
    }
    read_stretch(&file, start, length).map(|bytes| SourceBytes::Memory(Cow::Owned(bytes)))
}

/// The `length` bytes of `file` from `start`, read into memory of their own (an error, not an
/// abort, where there is not that much memory).
fn read_stretch(file: &File, start: u64, length: usize) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(length)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::OutOfMemory, e))?;
    bytes.resize(length, 0);
    read_at(file, start, &mut bytes)?;
    Ok(bytes)
}

/// Opens `file`, refusing anything but a regular file (a URI naming a device or a pipe, such
/// as `/dev/zero`, must not hang cadr or take all of its memory); returns it and its length.
fn open_regular(file: &Path) -> std::io::Result<(File, u64)> {
    let opened = File::open(file)?;
    let metadata = opened.metadata()?;
    if !metadata.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "it is not a regular file",
        ));
    }
    Ok((opened, metadata.len()))
}

/// A buffer's file: its first `length` bytes (no more than the file has), read as the loader
/// asks.
pub(super) fn open_buffer_file(
    file: &Path,
    length: usize,
) -> std::io::Result<SourceBytes<'static>> {
    let (opened, file_length) = open_regular(file)?;
    let length = usize::try_from(file_length).map_or(length, |have| have.min(length));
    stretch_of(opened, file, 0, length)
}

/// The whole of an image's file.
pub(super) fn read_image_file(file: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    let (opened, length) = open_regular(file)?;
    let mut data = Vec::new();
    opened.take(length).read_to_end(&mut data)?;
    Ok(data)
}

/// A glTF file or GLB as the loader parses it: the JSON, and a GLB's binary chunk.
pub(super) struct Document<'a> {
    /// The JSON text.
    pub(super) json: Cow<'a, [u8]>,
    /// A GLB's binary chunk, where it has one.
    pub(super) bin: Option<SourceBytes<'a>>,
}

/// The glTF file at `path`: a GLB's header and JSON chunk read, its binary chunk a window
/// read as the loader asks; a `.gltf` (or anything but a regular file) read whole.
pub(super) fn open_document(path: &Path) -> Result<Document<'static>, LoadError> {
    let io = |source| LoadError::Io {
        path: path.to_owned(),
        source,
    };
    let opened = File::open(path).map_err(io)?;
    let metadata = opened.metadata().map_err(io)?;
    let mut magic = [0_u8; 4];
    let is_glb = metadata.is_file() && read_at(&opened, 0, &mut magic).is_ok() && magic == *b"glTF";
    if !is_glb {
        let json = std::fs::read(path).map_err(io)?;
        return Ok(Document {
            json: Cow::Owned(json),
            bin: None,
        });
    }
    let chunks = glb_chunks(metadata.len(), &mut |at, into| read_at(&opened, at, into)).map_err(
        |message| LoadError::Gltf {
            path: path.to_owned(),
            message,
        },
    )?;
    let json_length = (chunks.json.end - chunks.json.start) as usize;
    let json = read_stretch(&opened, chunks.json.start, json_length).map_err(io)?;
    let bin = match chunks.bin {
        Some(bin) => {
            Some(stretch_of(opened, path, bin.start, (bin.end - bin.start) as usize).map_err(io)?)
        }
        None => None,
    };
    Ok(Document {
        json: Cow::Owned(json),
        bin,
    })
}

/// The glTF document or GLB in `bytes`, borrowed.
pub(super) fn document_in(bytes: &[u8]) -> Result<Document<'_>, String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(Document {
            json: Cow::Borrowed(bytes),
            bin: None,
        });
    }
    let chunks = glb_chunks(bytes.len() as u64, &mut |at, into| {
        // `glb_chunks` reads only within the length it is given.
        into.copy_from_slice(&bytes[at as usize..at as usize + into.len()]);
        Ok(())
    })?;
    let range = |r: Range<u64>| r.start as usize..r.end as usize;
    Ok(Document {
        json: Cow::Borrowed(&bytes[range(chunks.json)]),
        bin: chunks
            .bin
            .map(|bin| SourceBytes::Memory(Cow::Borrowed(&bytes[range(bin)]))),
    })
}

/// Size of the GLB header (magic, version, length) and of a chunk's header (length, type).
const GLB_HEADER_SIZE: u64 = 12;
const CHUNK_HEADER_SIZE: u64 = 8;

/// Where a GLB's chunks lie in its file.
struct GlbChunks {
    /// The JSON chunk's data.
    json: Range<u64>,
    /// The binary chunk's data, where there is one.
    bin: Option<Range<u64>>,
}

/// Finds a GLB's chunks in a file of `file_length` bytes, reading its headers with `read_at`
/// (offset, bytes to fill), never past `file_length`. Every length is checked against the
/// header's and the file's before anything is read by it.
fn glb_chunks(
    file_length: u64,
    read_at: &mut dyn FnMut(u64, &mut [u8]) -> std::io::Result<()>,
) -> Result<GlbChunks, String> {
    let mut read_words = |at: u64, words: &mut [u32]| -> Result<(), String> {
        let mut bytes = vec![0_u8; 4 * words.len()];
        read_at(at, &mut bytes).map_err(|e| format!("the GLB cannot be read: {e}"))?;
        for (word, bytes) in words.iter_mut().zip(bytes.chunks_exact(4)) {
            *word = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        }
        Ok(())
    };
    if file_length < GLB_HEADER_SIZE {
        return Err(format!(
            "the file has {file_length} bytes, less than the {GLB_HEADER_SIZE}-byte GLB header"
        ));
    }
    let mut header = [0_u32; 3];
    read_words(0, &mut header)?;
    let [_, version, length] = header;
    let length = u64::from(length);
    if length < GLB_HEADER_SIZE {
        return Err(format!(
            "the GLB header's length is {length} bytes, less than the {GLB_HEADER_SIZE}-byte header itself"
        ));
    }
    if version != 2 {
        return Err(format!(
            "GLB version {version} is not supported (only 2 is)"
        ));
    }
    if length > file_length {
        return Err(format!(
            "the GLB header's length is {length} bytes, but the file has {file_length} (truncated?)"
        ));
    }
    let mut chunk = |at: u64, expected: &[u8; 4], name: &str| -> Result<Range<u64>, String> {
        if at + CHUNK_HEADER_SIZE > length {
            return Err(format!(
                "the GLB's {name} chunk header at byte {at} lies past its length ({length} bytes)"
            ));
        }
        let mut words = [0_u32; 2];
        read_words(at, &mut words)?;
        let [chunk_length, kind] = words;
        if kind.to_le_bytes() != *expected {
            return Err(format!(
                "the GLB's chunk at byte {at} is of type {:?}, not {name}",
                String::from_utf8_lossy(&kind.to_le_bytes())
            ));
        }
        let data = at + CHUNK_HEADER_SIZE;
        let end = data + u64::from(chunk_length);
        if end > length {
            return Err(format!(
                "the GLB's {name} chunk declares {chunk_length} bytes, but only {} follow its header",
                length - data
            ));
        }
        Ok(data..end)
    };
    let json = chunk(GLB_HEADER_SIZE, b"JSON", "JSON")?;
    let bin = (json.end < length)
        .then(|| chunk(json.end, b"BIN\0", "BIN"))
        .transpose()?;
    Ok(GlbChunks { json, bin })
}

/// A glTF document's buffers, in the document's order.
pub(super) struct GltfBuffers<'a>(pub(super) Vec<SourceBytes<'a>>);

impl GltfBuffers<'_> {
    /// Buffer `index`'s bytes (of a file's, those read so far).
    pub(super) fn get(&self, index: usize) -> Option<&[u8]> {
        self.0.get(index).map(SourceBytes::bytes)
    }

    /// Reads `range` of buffer `index` from its file, where it has one (bytes in memory are
    /// there already). The range is clamped to the buffer.
    pub(super) fn read(&mut self, index: usize, range: Range<u64>) -> Result<(), String> {
        let Some(SourceBytes::File(window)) = self.0.get_mut(index) else {
            return Ok(());
        };
        let length = window.memory.len() as u64;
        let (start, end) = (range.start.min(length), range.end.min(length));
        if start == end {
            return Ok(());
        }
        window.read(start as usize..end as usize).map_err(|e| {
            format!(
                "buffer {index}: bytes {start}..{end} of '{}' cannot be read ({e}); was the file changed while it loaded?",
                window.path.display()
            )
        })
    }

    /// Gives back the memory of every file's bytes read so far.
    pub(super) fn release(&mut self) {
        for buffer in &mut self.0 {
            if let SourceBytes::File(window) = buffer {
                window.release();
            }
        }
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

    use super::*;

    /// A buffer file cut short after it was opened (another program rewriting it while it
    /// loads) makes the read of the lost bytes an error naming the buffer and the file, not a
    /// signal that stops the process, and the bytes read before stay as they were read.
    #[test]
    fn a_buffer_file_cut_short_while_it_loads_fails_its_read_with_an_error() {
        let path = std::env::temp_dir().join(format!("cadr-cut-buffer-{}.bin", std::process::id()));
        let content: Vec<u8> = (0..1_u32 << 20).map(|i| (i % 251) as u8).collect();
        std::fs::write(&path, &content).unwrap();
        let mut buffers = GltfBuffers(vec![open_buffer_file(&path, content.len()).unwrap()]);
        assert!(matches!(buffers.0[0], SourceBytes::File(_)));
        buffers.read(0, 100..200).unwrap();
        assert_eq!(&buffers.get(0).unwrap()[100..200], &content[100..200]);
        assert!(buffers.get(0).unwrap()[300..400].iter().all(|&b| b == 0));

        std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap()
            .set_len(4096)
            .unwrap();
        let error = buffers.read(0, 8192..16384).unwrap_err();
        assert!(
            error.contains("buffer 0") && error.contains(&path.display().to_string()),
            "{error}"
        );
        assert_eq!(&buffers.get(0).unwrap()[100..200], &content[100..200]);

        // Given back, the bytes read are gone until read again.
        buffers.release();
        assert!(buffers.get(0).unwrap()[100..200].iter().all(|&b| b == 0));
        buffers.read(0, 100..200).unwrap();
        assert_eq!(&buffers.get(0).unwrap()[100..200], &content[100..200]);
        std::fs::remove_file(&path).unwrap();
    }

    /// A GLB's chunks are found by their headers, every length checked against the file's.
    #[test]
    fn a_glbs_chunks_are_found_and_bad_lengths_refused() {
        let glb = |length: u32, json_length: u32, bin: Option<&[u8]>| {
            let mut bytes = b"glTF".to_vec();
            bytes.extend(2_u32.to_le_bytes());
            bytes.extend(length.to_le_bytes());
            bytes.extend(json_length.to_le_bytes());
            bytes.extend(b"JSON");
            bytes.extend(b"{}  ");
            if let Some(bin) = bin {
                bytes.extend((bin.len() as u32).to_le_bytes());
                bytes.extend(b"BIN\0");
                bytes.extend(bin);
            }
            bytes
        };
        let whole = glb(36, 4, Some(b"abcd"));
        let document = document_in(&whole).unwrap();
        assert_eq!(&*document.json, b"{}  ");
        assert_eq!(document.bin.unwrap().bytes(), b"abcd");
        assert!(document_in(&glb(24, 4, None)).unwrap().bin.is_none());
        for (bytes, expected) in [
            (glb(8, 4, None), "less than the 12-byte header"),
            (glb(400, 4, None), "but the file has 24"),
            (
                glb(24, 40, None),
                "JSON chunk declares 40 bytes, but only 4",
            ),
            (
                glb(34, 4, Some(b"abcd")),
                "BIN chunk declares 4 bytes, but only 2",
            ),
            (
                glb(30, 4, Some(b"abcd")),
                "BIN chunk header at byte 24 lies past",
            ),
        ] {
            let error = document_in(&bytes).err().unwrap();
            assert!(error.contains(expected), "{error}");
        }
    }
}
