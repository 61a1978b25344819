//! Writing CSF in the reference layout: header, then each array followed depth-first by the
//! data its elements point to, with the reference alignments, and the pointer table (the file
//! locations of every non-null offset field, in writing order) at the end.

use super::{CsfFile, CsfGeometry, CsfMeta, FLAG_UNIQUE_NODES, MAGIC};

struct Out {
    bytes: Vec<u8>,
    /// File locations of the offset fields written so far (the pointer table).
    locations: Vec<u64>,
}

impl Out {
    /// Pads with zeros to a multiple of `max(align, 4)`.
    fn align(&mut self, align: usize) {
        let align = align.max(4);
        let padded = self.bytes.len().div_ceil(align) * align;
        self.bytes.resize(padded, 0);
    }

    /// Appends `size` zero bytes at `align` and returns where they start.
    fn reserve(&mut self, size: usize, align: usize) -> usize {
        self.align(align);
        let at = self.bytes.len();
        self.bytes.resize(at + size, 0);
        at
    }

    fn put(&mut self, at: usize, value: &[u8]) {
        self.bytes[at..at + value.len()].copy_from_slice(value);
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
        let at = self.reserve(data.len(), align);
        self.put(at, data);
        self.link(location, at);
    }
}

fn le<T: Copy>(values: &[T], to_bytes: impl Fn(T) -> [u8; 4]) -> Vec<u8> {
    values.iter().flat_map(|&v| to_bytes(v)).collect()
}

/// Serialises `file` as CSF `version` (6 is current; 2 to 5 write the older layouts, whose
/// geometries cannot hold channels beyond one normal and one texture channel).
pub fn write_csf(file: &CsfFile, version: i32) -> Vec<u8> {
    let version = version.clamp(2, 6);
    let header_size = if version >= 5 { 88 } else { 64 };
    let mut out = Out {
        bytes: vec![0; header_size],
        locations: Vec::new(),
    };
    out.put_i32(0, MAGIC);
    out.put_i32(4, version);
    let flags = if version < 3 {
        u32::from(file.file_flags & FLAG_UNIQUE_NODES != 0)
    } else {
        file.file_flags
    };
    out.put(8, &flags.to_le_bytes());
    out.put_i32(16, file.geometries.len() as i32);
    out.put_i32(20, file.materials.len() as i32);
    out.put_i32(24, file.nodes.len() as i32);
    out.put_i32(28, file.root);

    if !file.geometries.is_empty() {
        let array = out.reserve(file.geometries.len() * 128, 8);
        out.link(40, array);
        for (i, geometry) in file.geometries.iter().enumerate() {
            write_geometry(&mut out, array + 128 * i, geometry, version);
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
        write_metas(&mut out, 64, &file.node_metas);
        write_metas(&mut out, 72, &file.geometry_metas);
        write_metas(&mut out, 80, file.file_meta.as_slice());
    }

    let table = out.reserve(out.locations.len() * 8, 8);
    let locations = std::mem::take(&mut out.locations);
    for (i, location) in locations.iter().enumerate() {
        out.put(table + 8 * i, &location.to_le_bytes());
    }
    out.put_i32(12, locations.len() as i32);
    out.put(32, &(table as u64).to_le_bytes());
    out.bytes
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
