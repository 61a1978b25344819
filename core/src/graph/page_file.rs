//! The page file: where the scene graph keeps the geometries that do not fit its share of the
//! memory budget, so that a model larger than memory can be loaded and edited. Each geometry is
//! one record (its vertices, indices, wire indices, parts and attributes), written when the
//! geometry is created or replaced and read back, whole, when something needs it: the GPU
//! scene when it lays the geometry out or streams its full detail in (on its preparing thread),
//! a host that asks for the data. A record carries a CRC-32 of its bytes, so a file that was
//! changed or cut short under cadr gives a clear error, never wrong geometry.
//!
//! The file is made when the first geometry goes there, named `cadr-pages-PID-N.bin`, in
//! `CADR_PAGE_DIR`, else `TMPDIR`, else `/var/tmp` (see [`page_directory`]), and removed when
//! the graph is dropped (the first file a process makes removes those of ended processes: a
//! crash leaves its file behind). The room of a destroyed or replaced geometry is used again.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use crate::scene::{Geometry, Part, Vertex, VertexAttributes};

/// What starts every record.
const MAGIC: [u8; 8] = *b"CADRPG01";
/// Bytes of a record's header: the magic and six counts.
const HEADER_BYTES: usize = 8 + 6 * 4;

/// Page files made by this process, counted (for their names).
static FILES_MADE: AtomicU64 = AtomicU64::new(0);

/// The open file, shared by the graph (which writes) and the readers of its pages (any thread).
struct OpenFile {
    file: Mutex<File>,
    path: PathBuf,
}

impl Drop for OpenFile {
    fn drop(&mut self) {
        // Nothing else uses the file: its pages are gone with the graph.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// One geometry's record in a page file: where it is and what its bytes sum to. Readable from
/// any thread, also after the graph replaced the geometry (the read then fails its check or
/// gives the old data, which the asker knows to ignore).
#[derive(Clone)]
pub struct Page {
    file: Arc<OpenFile>,
    offset: u64,
    len: u64,
    crc: u32,
}

impl std::fmt::Debug for Page {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Page({} at {}, {} bytes)",
            self.file.path.display(),
            self.offset,
            self.len
        )
    }
}

impl Page {
    /// Bytes the record takes in the file.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the record is empty (never: a record has at least its header).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Reads the geometry back. Fails with a message naming the file where it cannot be read
    /// or its bytes are not what was written.
    pub fn read(&self) -> Result<Geometry, String> {
        let failed = |why: String| {
            format!(
                "page file {} could not be read at byte {} ({} bytes): {why}",
                self.file.path.display(),
                self.offset,
                self.len
            )
        };
        // Read straight into the geometry's arrays: no copy of the record is held besides.
        let mut crc = flate2::Crc::new();
        let decoded = {
            let mut file = (self.file.file.lock()).unwrap_or_else(|p| p.into_inner());
            file.seek(SeekFrom::Start(self.offset))
                .and_then(|_| decode(&mut *file, self.len, &mut crc))
                .map_err(|e| failed(e.to_string()))?
        };
        let geometry = decoded.ok_or_else(|| {
            failed("the record is malformed (its counts do not add up to its length)".into())
        })?;
        if crc.sum() != self.crc {
            return Err(failed(
                "its bytes are not those written (CRC mismatch)".into(),
            ));
        }
        Ok(geometry)
    }
}

/// A page file and its free room. Only the graph that owns it writes to it.
pub struct PageFile {
    file: Arc<OpenFile>,
    /// Rooms of records no longer used, as (offset, length), in offset order, never adjacent.
    free: Vec<(u64, u64)>,
    /// Where the file ends.
    end: u64,
}

impl PageFile {
    /// A new, empty page file in the page directory. The first one of a process removes
    /// those that processes which ended without removing theirs (a crash) left there.
    pub fn create() -> Result<Self, String> {
        let n = FILES_MADE.fetch_add(1, Ordering::Relaxed);
        if n == 0 {
            remove_orphans(&page_directory());
        }
        let path = page_directory().join(format!("cadr-pages-{}-{n}.bin", std::process::id()));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|e| format!("page file {} could not be made: {e}", path.display()))?;
        Ok(Self {
            file: Arc::new(OpenFile {
                file: Mutex::new(file),
                path,
            }),
            free: Vec::new(),
            end: 0,
        })
    }

    /// Whether `page` is a record of this file.
    pub fn holds(&self, page: &Page) -> bool {
        Arc::ptr_eq(&self.file, &page.file)
    }

    /// Where the file is.
    pub fn path(&self) -> &Path {
        &self.file.path
    }

    /// Bytes of the file in use by records.
    pub fn bytes_in_use(&self) -> u64 {
        self.end - self.free.iter().map(|&(_, len)| len).sum::<u64>()
    }

    /// Writes `geometry` as a new record (in the smallest free room it fits, else at the end).
    /// On failure (a full disk) nothing is taken.
    pub fn write(&mut self, geometry: &Geometry) -> Result<Page, String> {
        let record = Record::of(geometry);
        let len = record.len();
        let room = (self.free.iter().enumerate())
            .filter(|(_, &(_, room))| room >= len)
            .min_by_key(|(_, &(_, room))| room)
            .map(|(i, _)| i);
        let offset = room.map_or(self.end, |i| self.free[i].0);
        {
            let mut file = (self.file.file.lock()).unwrap_or_else(|p| p.into_inner());
            file.seek(SeekFrom::Start(offset))
                .and_then(|_| (record.pieces().iter()).try_for_each(|piece| file.write_all(piece)))
                .map_err(|e| {
                    format!(
                        "geometry '{}' could not be written to page file {}: {e}",
                        geometry.name,
                        self.file.path.display()
                    )
                })?;
        }
        match room {
            Some(i) if self.free[i].1 > len => {
                self.free[i] = (offset + len, self.free[i].1 - len);
            }
            Some(i) => {
                self.free.remove(i);
            }
            None => self.end += len,
        }
        Ok(Page {
            file: self.file.clone(),
            offset,
            len,
            crc: record.crc(),
        })
    }

    /// Gives the room of `page` (a record of this file) back.
    pub fn free(&mut self, page: &Page) {
        let at = self
            .free
            .partition_point(|&(offset, _)| offset < page.offset);
        self.free.insert(at, (page.offset, page.len));
        // Merged with the following room, then with the preceding one, where they touch.
        if at + 1 < self.free.len() && self.free[at].0 + self.free[at].1 == self.free[at + 1].0 {
            self.free[at].1 += self.free[at + 1].1;
            self.free.remove(at + 1);
        }
        if at > 0 && self.free[at - 1].0 + self.free[at - 1].1 == self.free[at].0 {
            self.free[at - 1].1 += self.free[at].1;
            self.free.remove(at);
        }
        // Room at the end is no room: the file may end there.
        if let Some(&(offset, len)) = self.free.last() {
            if offset + len == self.end {
                self.end = offset;
                self.free.pop();
                let file = (self.file.file.lock()).unwrap_or_else(|p| p.into_inner());
                let _ = file.set_len(self.end);
            }
        }
    }
}

/// The variable that names the directory page files go to.
pub const DIRECTORY_VARIABLE: &str = "CADR_PAGE_DIR";

/// Where page files go: `CADR_PAGE_DIR`, else `TMPDIR`, else `/var/tmp` where it exists (on
/// disk by convention, where `/tmp` is often memory: paging there would save none), else the
/// system's temporary directory. Readers that unpack a compressed file to read it in pieces put
/// their temporary file there too.
pub(crate) fn page_directory() -> PathBuf {
    let named = |variable: &str| std::env::var_os(variable).filter(|v| !v.is_empty());
    if let Some(directory) = named(DIRECTORY_VARIABLE).or_else(|| named("TMPDIR")) {
        return PathBuf::from(directory);
    }
    let var_tmp = Path::new("/var/tmp");
    if var_tmp.is_dir() {
        return var_tmp.to_path_buf();
    }
    std::env::temp_dir()
}

/// Temporary files made by this process (a `.csf.gz` unpacked to be read or written to be
/// packed, a GLB's buffer), counted (for their names).
static TEMPORARY_FILES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Removes a temporary file when dropped, where it could not be removed while open.
#[derive(Debug)]
pub(crate) struct RemovedOnDrop(Option<std::path::PathBuf>);

impl RemovedOnDrop {
    /// A guard with nothing to remove.
    pub(crate) fn nothing() -> Self {
        Self(None)
    }
}

impl Drop for RemovedOnDrop {
    fn drop(&mut self) {
        if let Some(path) = self.0.take() {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// A new temporary file in `directory` (the page directory, [`page_directory`]), open to read
/// and write, for `purpose` (which its error names). It is removed from its directory as soon
/// as it is open (where the system allows; otherwise when the returned guard is dropped), so
/// that nothing is left behind, even by a crash.
pub(crate) fn temporary_file(
    directory: &Path,
    purpose: &str,
) -> std::io::Result<(std::fs::File, RemovedOnDrop)> {
    let number = TEMPORARY_FILES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = directory.join(format!("cadr-temporary-{}-{number}", std::process::id()));
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(&path)
        .map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!("a temporary file {purpose}, {}: {e}", path.display()),
            )
        })?;
    let guard = RemovedOnDrop(std::fs::remove_file(&path).is_err().then_some(path));
    Ok((file, guard))
}

/// Removes the page files in `directory` whose process has ended (Linux: no `/proc/PID`; on
/// other systems none is removed).
fn remove_orphans(directory: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(directory) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let pid = (name.to_str())
            .and_then(|name| name.strip_prefix("cadr-pages-"))
            .and_then(|rest| rest.split('-').next())
            .and_then(|pid| pid.parse::<u32>().ok());
        if let Some(pid) = pid {
            if !Path::new(&format!("/proc/{pid}")).exists() {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// A geometry's record, in the pieces it is written from (so that no copy of its arrays is
/// made): the magic, the six counts and the padded name, then the vertices, indices, wire
/// indices, parts and attributes.
struct Record<'g> {
    head: Vec<u8>,
    parts: Vec<[u32; 4]>,
    geometry: &'g Geometry,
}

impl<'g> Record<'g> {
    fn of(geometry: &'g Geometry) -> Self {
        let name = geometry.name.as_bytes();
        let parts: Vec<[u32; 4]> = (geometry.parts.iter())
            .map(|p| {
                [
                    p.first_index,
                    p.index_count,
                    p.first_wire_index,
                    p.wire_index_count,
                ]
            })
            .collect();
        let counts = [
            name.len(),
            geometry.vertices.len(),
            geometry.indices.len(),
            geometry.wire_indices.len(),
            parts.len(),
            geometry.attributes.len(),
        ];
        let mut head = Vec::with_capacity(HEADER_BYTES + name.len().next_multiple_of(4));
        head.extend_from_slice(&MAGIC);
        for count in counts {
            head.extend_from_slice(&(count as u32).to_le_bytes());
        }
        head.extend_from_slice(name);
        head.resize(head.len().next_multiple_of(4), 0);
        Self {
            head,
            parts,
            geometry,
        }
    }

    /// The record's bytes, piece by piece.
    fn pieces(&self) -> [&[u8]; 6] {
        [
            &self.head,
            bytemuck::cast_slice(&self.geometry.vertices),
            bytemuck::cast_slice(&self.geometry.indices),
            bytemuck::cast_slice(&self.geometry.wire_indices),
            bytemuck::cast_slice(&self.parts),
            bytemuck::cast_slice(&self.geometry.attributes),
        ]
    }

    fn len(&self) -> u64 {
        self.pieces().iter().map(|piece| piece.len() as u64).sum()
    }

    fn crc(&self) -> u32 {
        let mut crc = flate2::Crc::new();
        for piece in self.pieces() {
            crc.update(piece);
        }
        crc.sum()
    }
}

/// Reads `buffer` whole from `source`, adding its bytes to `crc`.
fn read_into(
    source: &mut impl Read,
    buffer: &mut [u8],
    crc: &mut flate2::Crc,
) -> std::io::Result<()> {
    source.read_exact(buffer)?;
    crc.update(buffer);
    Ok(())
}

/// Reads a record of `len` bytes (a [`Record`]) from `source` into the geometry's arrays,
/// adding its bytes to `crc`; `Ok(None)` where its header is not one or its counts do not add
/// up to `len` (checked before anything of their size is allocated).
fn decode(
    source: &mut impl Read,
    len: u64,
    crc: &mut flate2::Crc,
) -> std::io::Result<Option<Geometry>> {
    let mut header = [0u8; HEADER_BYTES];
    if len < HEADER_BYTES as u64 {
        return Ok(None);
    }
    read_into(source, &mut header, crc)?;
    if header[..8] != MAGIC {
        return Ok(None);
    }
    let counts: [u64; 6] = std::array::from_fn(|i| {
        let at = 8 + 4 * i;
        u64::from(u32::from_le_bytes([
            header[at],
            header[at + 1],
            header[at + 2],
            header[at + 3],
        ]))
    });
    let [name_len, vertex_count, index_count, wire_count, part_count, attribute_count] = counts;
    // Each count is under 2^32, so this sum cannot overflow.
    let total = HEADER_BYTES as u64
        + name_len.next_multiple_of(4)
        + 24 * vertex_count
        + 4 * (index_count + wire_count)
        + 16 * part_count
        + 12 * attribute_count;
    if total != len {
        return Ok(None);
    }
    let mut name = vec![0u8; name_len.next_multiple_of(4) as usize];
    read_into(source, &mut name, crc)?;
    name.truncate(name_len as usize);
    let mut vertices = vec![Vertex::default(); vertex_count as usize];
    read_into(source, bytemuck::cast_slice_mut(&mut vertices), crc)?;
    let mut indices = vec![0u32; index_count as usize];
    read_into(source, bytemuck::cast_slice_mut(&mut indices), crc)?;
    let mut wire_indices = vec![0u32; wire_count as usize];
    read_into(source, bytemuck::cast_slice_mut(&mut wire_indices), crc)?;
    let mut parts = vec![[0u32; 4]; part_count as usize];
    read_into(source, bytemuck::cast_slice_mut(&mut parts), crc)?;
    let mut attributes = vec![VertexAttributes::default(); attribute_count as usize];
    read_into(source, bytemuck::cast_slice_mut(&mut attributes), crc)?;
    let Ok(name) = String::from_utf8(name) else {
        return Ok(None);
    };
    Ok(Some(Geometry {
        name,
        vertices,
        indices,
        wire_indices,
        parts: (parts.into_iter())
            .map(
                |[first_index, index_count, first_wire_index, wire_index_count]| Part {
                    first_index,
                    index_count,
                    first_wire_index,
                    wire_index_count,
                },
            )
            .collect(),
        attributes,
    }))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn triangle(name: &str, offset: f32) -> Geometry {
        let vertex = |x: f32, y: f32| Vertex {
            position: [x + offset, y, 0.0],
            normal: [0.0, 0.0, 1.0],
        };
        Geometry {
            name: name.into(),
            vertices: vec![vertex(0.0, 0.0), vertex(1.0, 0.0), vertex(0.0, 1.0)],
            indices: vec![0, 1, 2],
            wire_indices: vec![0, 1, 1, 2],
            parts: vec![Part {
                first_index: 0,
                index_count: 3,
                first_wire_index: 0,
                wire_index_count: 4,
            }],
            attributes: vec![VertexAttributes::default(); 3],
        }
    }

    #[test]
    fn records_read_back_as_written_and_freed_room_is_used_again() {
        let mut file = PageFile::create().unwrap();
        let path = file.path().to_path_buf();
        let a = file.write(&triangle("a", 0.0)).unwrap();
        let b = file.write(&triangle("b", 1.0)).unwrap();
        assert_eq!(a.read().unwrap(), triangle("a", 0.0));
        assert_eq!(b.read().unwrap(), triangle("b", 1.0));
        file.free(&a);
        assert_eq!(file.bytes_in_use(), b.len());
        let c = file.write(&triangle("c", 2.0)).unwrap();
        assert_eq!(c.offset, a.offset, "the freed room is used again");
        assert_eq!(c.read().unwrap(), triangle("c", 2.0));
        file.free(&b);
        file.free(&c);
        assert_eq!((file.bytes_in_use(), file.end), (0, 0), "{:?}", file.free);
        drop((a, b, c, file));
        assert!(
            !path.exists(),
            "the page file is removed with its last page"
        );
    }

    #[test]
    fn a_changed_or_short_file_is_a_clear_error() {
        let mut file = PageFile::create().unwrap();
        let page = file.write(&triangle("a", 0.0)).unwrap();
        let path = file.path().to_path_buf();
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[HEADER_BYTES + 8] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        let error = page.read().unwrap_err();
        assert!(
            error.contains("CRC mismatch") && error.contains("cadr-pages-"),
            "{error}"
        );
        std::fs::write(&path, &bytes[..10]).unwrap();
        let error = page.read().unwrap_err();
        assert!(error.contains("could not be read"), "{error}");
    }

    #[test]
    fn files_of_ended_processes_are_removed_and_others_kept() {
        let directory = std::env::temp_dir().join(format!("cadr-orphans-{}", std::process::id()));
        std::fs::create_dir_all(&directory).unwrap();
        // No process has a PID past the kernel's limit (at most 2^22).
        let orphan = directory.join("cadr-pages-99999999-0.bin");
        let live = directory.join(format!("cadr-pages-{}-7.bin", std::process::id()));
        let other = directory.join("notes.bin");
        for path in [&orphan, &live, &other] {
            std::fs::write(path, b"x").unwrap();
        }
        remove_orphans(&directory);
        assert!(!orphan.exists() && live.exists() && other.exists());
        std::fs::remove_dir_all(&directory).unwrap();
    }

    #[test]
    fn malformed_records_decode_to_none() {
        let decoded =
            |bytes: &[u8], len: usize| decode(&mut &bytes[..], len as u64, &mut flate2::Crc::new());
        let geometry = triangle("a", 0.0);
        let bytes = Record::of(&geometry).pieces().concat();
        assert_eq!(
            decoded(&bytes, bytes.len()).unwrap(),
            Some(triangle("a", 0.0))
        );
        assert!(decoded(&bytes, bytes.len() - 1).unwrap().is_none());
        assert!(decoded(&bytes, bytes.len() + 1).unwrap().is_none());
        assert!(decoded(&bytes, 3).unwrap().is_none());
        let mut huge = bytes.clone();
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decoded(&huge, huge.len()).unwrap().is_none());
        let mut not_a_record = bytes.clone();
        not_a_record[0] = b'X';
        assert!(decoded(&not_a_record, bytes.len()).unwrap().is_none());
        // A source shorter than the length it claims: an error of the read.
        assert!(decoded(&bytes[..bytes.len() - 4], bytes.len()).is_err());
    }
}
