//! Writing CSF in the reference layout: header, then each array followed depth-first by the
//! data its elements point to, with the reference alignments, and the pointer table (the file
//! locations of every non-null offset field, in writing order) at the end.
//!
//! The geometries are written one at a time, each as its source gives it, into memory or a
//! file: written to a file, no more than one geometry's blocks and the last few megabytes are
//! held ([`write_csf_file`]), so that a scene larger than memory can be saved.

use std::borrow::Cow;
use std::convert::Infallible;
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};

use super::{CsfFile, CsfGeometry, CsfMeta, FLAG_UNIQUE_NODES, MAGIC};

/// Bytes a file-backed writer holds before it writes them out: larger blocks go straight to
/// the file.
const FLUSH_BYTES: usize = 1 << 20;

/// Where the bytes go, as they are laid out.
struct Out<'f> {
    /// The bytes from `base` on, not yet written out.
    bytes: Vec<u8>,
    /// Where `bytes` starts in the file.
    base: usize,
    /// The file the bytes before `base` were written to (none: all are in `bytes`).
    file: Option<&'f mut File>,
    /// The first write that failed: nothing is written after it.
    failed: Option<std::io::Error>,
    /// File locations of the offset fields written so far (the pointer table).
    locations: Vec<u64>,
}

impl Out<'_> {
    /// The file size so far.
    fn len(&self) -> usize {
        self.base + self.bytes.len()
    }

    /// Pads with zeros to a multiple of `max(align, 4)`.
    fn align(&mut self, align: usize) {
        let align = align.max(4);
        let padded = self.len().div_ceil(align) * align;
        self.bytes.resize(padded - self.base, 0);
    }

    /// Appends `size` zero bytes at `align` and returns where they start.
    fn reserve(&mut self, size: usize, align: usize) -> usize {
        self.make_room(size + align);
        self.align(align);
        let at = self.len();
        self.bytes.resize(at + size - self.base, 0);
        at
    }

    /// Writes the held bytes out where a file takes them and `more` bytes would take them past
    /// [`FLUSH_BYTES`].
    fn make_room(&mut self, more: usize) {
        if self.bytes.len() + more > FLUSH_BYTES {
            self.flush();
        }
    }

    /// Appends `data` at `align` and returns where it starts: into the held bytes, or, where a
    /// file takes them and it would not fit [`FLUSH_BYTES`], straight to the file.
    fn append(&mut self, data: &[u8], align: usize) -> usize {
        self.make_room(data.len() + align);
        self.align(align);
        let at = self.len();
        if self.file.is_none() || self.bytes.len() + data.len() <= FLUSH_BYTES {
            self.bytes.extend_from_slice(data);
            return at;
        }
        self.flush();
        if let (Some(file), None) = (self.file.as_deref_mut(), &self.failed) {
            self.failed = file.write_all(data).err();
        }
        self.base += data.len();
        at
    }

    /// Writes the held bytes out to the file, if there is one.
    fn flush(&mut self) {
        let Some(file) = self.file.as_deref_mut() else {
            return;
        };
        if self.failed.is_none() {
            self.failed = file.write_all(&self.bytes).err();
        }
        self.base += self.bytes.len();
        self.bytes.clear();
    }

    fn put(&mut self, at: usize, value: &[u8]) {
        if at >= self.base {
            let at = at - self.base;
            self.bytes[at..at + value.len()].copy_from_slice(value);
            return;
        }
        // Into what the file already holds: a field of an array written before its data.
        let Some(file) = self.file.as_deref_mut() else {
            return;
        };
        if self.failed.is_none() {
            let written = file
                .seek(SeekFrom::Start(at as u64))
                .and_then(|_| file.write_all(value))
                .and_then(|()| file.seek(SeekFrom::End(0)).map(|_| ()));
            self.failed = written.err();
        }
    }

    fn put_i32(&mut self, at: usize, value: i32) {
        self.put(at, &value.to_le_bytes());
    }

    fn put_f32s(&mut self, at: usize, values: &[f32]) {
        for (i, v) in values.iter().enumerate() {
            self.put(at + 4 * i, &v.to_le_bytes());
        }
    }

    fn put_name(&mut self, at: usize, name: &str) {
        let mut end = name.len().min(127);
        while !name.is_char_boundary(end) {
            end -= 1;
        }
        self.put(at, &name.as_bytes()[..end]);
    }

    /// Points the offset field at `location` to `offset` and records it in the pointer table.
    fn link(&mut self, location: usize, offset: usize) {
        self.put(location, &(offset as u64).to_le_bytes());
        self.locations.push(location as u64);
    }

    /// Writes `data` at `align` and links the field at `location` to it (nothing when empty).
    fn block(&mut self, location: usize, data: &[u8], align: usize) {
        if data.is_empty() {
            return;
        }
        let at = self.append(data, align);
        self.link(location, at);
    }
}

/// The geometries a CSF file is written with, handed over one at a time in order.
pub trait CsfGeometries {
    /// Why a geometry could not be had.
    type Error;
    /// How many there are.
    fn count(&self) -> usize;
    /// Geometry number `index` (each asked for once, in order).
    fn geometry(&mut self, index: usize) -> Result<Cow<'_, CsfGeometry>, Self::Error>;
}

/// A file's own geometries, in memory.
impl CsfGeometries for &[CsfGeometry] {
    type Error = Infallible;
    fn count(&self) -> usize {
        self.len()
    }
    fn geometry(&mut self, index: usize) -> Result<Cow<'_, CsfGeometry>, Infallible> {
        Ok(Cow::Borrowed(&self[index]))
    }
}

/// Why [`write_csf_file`] failed.
#[derive(Debug)]
pub enum CsfWriteError<E> {
    /// A geometry could not be had from its source.
    Geometry(E),
    /// Writing the file failed.
    Io(std::io::Error),
}

fn le<T: Copy>(values: &[T], to_bytes: impl Fn(T) -> [u8; 4]) -> Vec<u8> {
    values.iter().flat_map(|&v| to_bytes(v)).collect()
}

/// Serialises `file` as CSF `version` (6 is current; 2 to 5 write the older layouts, whose
/// geometries cannot hold channels beyond one normal and one texture channel).
pub fn write_csf(file: &CsfFile, version: i32) -> Vec<u8> {
    let Ok(bytes) = write_csf_bytes(file, &mut file.geometries.as_slice(), version);
    bytes
}

/// Serialises `file` as CSF `version` in memory, its geometries taken from `geometries` one at
/// a time instead of `file.geometries` (which is not read).
pub fn write_csf_bytes<G: CsfGeometries>(
    file: &CsfFile,
    geometries: &mut G,
    version: i32,
) -> Result<Vec<u8>, G::Error> {
    let mut out = Out {
        bytes: Vec::new(),
        base: 0,
        file: None,
        failed: None,
        locations: Vec::new(),
    };
    write_into(&mut out, file, geometries, version)?;
    Ok(out.bytes)
}

/// Writes `file` as CSF `version` to `output` (from its start), its geometries taken from
/// `geometries` one at a time instead of `file.geometries` (which is not read): a file-backed
/// write holds one geometry and a few megabytes of the file, however large it grows.
pub fn write_csf_file<G: CsfGeometries>(
    file: &CsfFile,
    geometries: &mut G,
    version: i32,
    output: &mut File,
) -> Result<(), CsfWriteError<G::Error>> {
    let mut out = Out {
        bytes: Vec::with_capacity(FLUSH_BYTES),
        base: 0,
        file: Some(output),
        failed: None,
        locations: Vec::new(),
    };
    write_into(&mut out, file, geometries, version).map_err(CsfWriteError::Geometry)?;
    out.flush();
    match out.failed {
        Some(error) => Err(CsfWriteError::Io(error)),
        None => Ok(()),
    }
}

/// Lays `file` out into `out`, its geometries from `geometries`.
fn write_into<G: CsfGeometries>(
    out: &mut Out<'_>,
    file: &CsfFile,
    geometries: &mut G,
    version: i32,
) -> Result<(), G::Error> {
    let version = version.clamp(2, 6);
    let header_size = if version >= 5 { 88 } else { 64 };
    out.reserve(header_size, 8);
    out.put_i32(0, MAGIC);
    out.put_i32(4, version);
    let flags = if version < 3 {
        u32::from(file.file_flags & FLAG_UNIQUE_NODES != 0)
    } else {
        file.file_flags
    };
    out.put(8, &flags.to_le_bytes());
    let geometry_count = geometries.count();
    out.put_i32(16, geometry_count as i32);
    out.put_i32(20, file.materials.len() as i32);
    out.put_i32(24, file.nodes.len() as i32);
    out.put_i32(28, file.root);

    if geometry_count > 0 {
        let array = out.reserve(geometry_count * 128, 8);
        out.link(40, array);
        for i in 0..geometry_count {
            let geometry = geometries.geometry(i)?;
            write_geometry(out, array + 128 * i, &geometry, version);
        }
    }

    if !file.materials.is_empty() {
        let array = out.reserve(file.materials.len() * 160, 8);
        out.link(48, array);
        for (i, m) in file.materials.iter().enumerate() {
            let at = array + 160 * i;
            out.put_name(at, &m.name);
            out.put_f32s(at + 128, &m.color);
            out.put_i32(at + 144, m.kind);
            out.put_i32(at + 148, m.bytes.len() as i32);
            out.block(at + 152, &m.bytes, 4);
        }
    }

    if !file.nodes.is_empty() {
        let array = out.reserve(file.nodes.len() * 160, 8);
        out.link(56, array);
        for (i, n) in file.nodes.iter().enumerate() {
            let at = array + 160 * i;
            out.put_f32s(at, &n.object_tm);
            out.put_f32s(at + 64, &n.world_tm);
            out.put_i32(at + 128, n.geometry);
            out.put_i32(at + 132, n.parts.len() as i32);
            out.put_i32(at + 136, n.children.len() as i32);
            let parts: Vec<u8> = n
                .parts
                .iter()
                .flat_map(|p| [p.active, p.material, if version >= 4 { p.node } else { 0 }])
                .flat_map(i32::to_le_bytes)
                .collect();
            out.block(at + 144, &parts, 4);
            out.block(at + 152, &le(&n.children, i32::to_le_bytes), 4);
        }
    }

    if version >= 5 {
        write_metas(out, 64, &file.node_metas);
        write_metas(out, 72, &file.geometry_metas);
        write_metas(out, 80, file.file_meta.as_slice());
    }

    let table = out.reserve(out.locations.len() * 8, 8);
    let locations = std::mem::take(&mut out.locations);
    for (i, location) in locations.iter().enumerate() {
        out.put(table + 8 * i, &location.to_le_bytes());
    }
    out.put_i32(12, locations.len() as i32);
    out.put(32, &(table as u64).to_le_bytes());
    Ok(())
}

/// Writes geometry `g`'s 128-byte record at `at` (its arrays as blocks appended to `out`), as
/// `version` lays it out: before version 6 an identity matrix where the channel counts go, one
/// normal and texture coordinate channel at most, and no auxiliary or per-part channels.
fn write_geometry(out: &mut Out, at: usize, g: &CsfGeometry, version: i32) {
    if version >= 6 {
        out.put_i32(at + 16, g.normal_channels);
        out.put_i32(at + 20, g.tex_channels);
        out.put_i32(at + 24, g.aux_storage_order.len() as i32);
        out.put_i32(at + 28, g.perpart_storage_order.len() as i32);
    } else {
        // The deprecated geometry matrix of older versions: identity.
        out.put_f32s(
            at,
            &[
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ],
        );
    }
    out.put_i32(at + 64, g.parts.len() as i32);
    out.put_i32(at + 68, g.vertex_count() as i32);
    out.put_i32(at + 72, g.index_solid.len() as i32);
    out.put_i32(at + 76, g.index_wire.len() as i32);
    out.block(at + 80, &le(&g.vertices, f32::to_le_bytes), 4);
    let normals = if version >= 6 {
        &g.normals[..]
    } else {
        &g.normals[..g.normals.len().min(g.vertices.len())]
    };
    out.block(at + 88, &le(normals, f32::to_le_bytes), 4);
    let tex = if version >= 6 {
        &g.tex[..]
    } else {
        &g.tex[..g.tex.len().min(g.vertex_count() * 2)]
    };
    out.block(at + 96, &le(tex, f32::to_le_bytes), 4);
    out.block(at + 104, &le(&g.index_solid, u32::to_le_bytes), 4);
    out.block(at + 112, &le(&g.index_wire, u32::to_le_bytes), 4);
    let parts: Vec<u8> = g
        .parts
        .iter()
        .flat_map(|p| [p.deprecated, p.num_index_solid, p.num_index_wire])
        .flat_map(i32::to_le_bytes)
        .collect();
    out.block(at + 120, &parts, 4);
    if version >= 6 {
        out.block(at + 40, &le(&g.aux, f32::to_le_bytes), 4);
        out.block(at + 32, &le(&g.aux_storage_order, i32::to_le_bytes), 4);
        out.block(at + 48, &le(&g.perpart_storage_order, i32::to_le_bytes), 4);
        out.block(at + 56, &g.perpart, 16);
    }
}

fn write_metas(out: &mut Out, location: usize, metas: &[CsfMeta]) {
    if metas.is_empty() {
        return;
    }
    let array = out.reserve(metas.len() * 152, 8);
    out.link(location, array);
    for (i, meta) in metas.iter().enumerate() {
        let at = array + 152 * i;
        out.put_name(at, &meta.name);
        out.put_i32(at + 128, meta.flags);
        out.put(at + 136, &(meta.bytes.len() as u64).to_le_bytes());
        out.block(at + 144, &meta.bytes, 16);
    }
}
