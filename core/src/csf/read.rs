//! Schema-driven CSF parsing: every offset, count and alignment is checked against the file
//! before anything is read, so a malformed file gives a [`CsfError`] and never a panic.

use std::borrow::Cow;
use std::io::{Read as _, Seek as _, SeekFrom};

use crate::scene::graph::first_cycle;

use super::{
    error, part_channel_size, CsfError, CsfFile, CsfGeometry, CsfGeometryPart, CsfMaterial,
    CsfMeta, CsfNode, CsfNodePart, FLAG_PER_PART_VERTICES, FLAG_UNIQUE_NODES, MAGIC, VERSION,
    VERSION_COMPAT,
};

const HEADER_SIZE_V4: usize = 64;
const HEADER_SIZE_V5: usize = 88;
const GEOMETRY_SIZE: usize = 128;
const MATERIAL_SIZE: usize = 160;
const META_SIZE: usize = 152;
const NODE_SIZE: usize = 160;
const PART_SIZE: usize = 12;

/// Little-endian access to a slice whose length the caller has checked.
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn u32(&self, at: usize) -> u32 {
        u32::from_le_bytes([self.0[at], self.0[at + 1], self.0[at + 2], self.0[at + 3]])
    }
    fn i32(&self, at: usize) -> i32 {
        self.u32(at) as i32
    }
    fn u64(&self, at: usize) -> u64 {
        u64::from(self.u32(at)) | (u64::from(self.u32(at + 4)) << 32)
    }
    fn f32(&self, at: usize) -> f32 {
        f32::from_bits(self.u32(at))
    }
    fn matrix(&self, at: usize) -> [f32; 16] {
        std::array::from_fn(|i| self.f32(at + 4 * i))
    }
    fn name(&self, at: usize) -> String {
        let bytes = &self.0[at..at + 128];
        let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
        String::from_utf8_lossy(&bytes[..end]).into_owned()
    }
}

fn floats(bytes: impl AsRef<[u8]>) -> Vec<f32> {
    (bytes.as_ref())
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn u32s(bytes: impl AsRef<[u8]>) -> Vec<u32> {
    (bytes.as_ref())
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn i32s(bytes: impl AsRef<[u8]>) -> Vec<i32> {
    u32s(bytes).into_iter().map(|v| v as i32).collect()
}

/// Where a file's bytes are read from: memory, or the file itself (read where each array
/// lies, so that the file is never held whole).
pub enum CsfBytes<'a> {
    /// The file's bytes, in memory.
    Memory(&'a [u8]),
    /// An open file of `len` bytes.
    File {
        /// The file.
        file: std::cell::RefCell<std::fs::File>,
        /// Its length.
        len: u64,
    },
}

impl<'a> CsfBytes<'a> {
    /// The file's length.
    fn len(&self) -> u64 {
        match self {
            Self::Memory(data) => data.len() as u64,
            Self::File { len, .. } => *len,
        }
    }

    /// `size` bytes at `offset`, which lie within the file.
    fn read(&self, offset: u64, size: u64) -> std::io::Result<Cow<'a, [u8]>> {
        match self {
            Self::Memory(data) => Ok(Cow::Borrowed(
                &data[offset as usize..(offset + size) as usize],
            )),
            Self::File { file, .. } => {
                let mut file = file.borrow_mut();
                let mut bytes = vec![0; size as usize];
                file.seek(SeekFrom::Start(offset))?;
                file.read_exact(&mut bytes)?;
                Ok(Cow::Owned(bytes))
            }
        }
    }
}

struct Reader<'a> {
    bytes: CsfBytes<'a>,
    header_size: usize,
}

impl<'a> Reader<'a> {
    /// `size` bytes at `offset`, which lie within the file; a file that cannot be read there
    /// (changed under the reader) names the structure and field read.
    fn read(
        &self,
        structure: &str,
        field: &'static str,
        offset: u64,
        size: u64,
    ) -> Result<Cow<'a, [u8]>, CsfError> {
        self.bytes.read(offset, size).map_err(|e| {
            error(
                structure,
                field,
                format!("bytes {offset}..{} could not be read: {e}", offset + size),
            )
        })
    }

    /// The bytes of an array of `count` elements of `element_size` at `offset`.
    fn array(
        &self,
        structure: &str,
        field: &'static str,
        offset: u64,
        count: u64,
        element_size: u64,
        align: u64,
    ) -> Result<Cow<'a, [u8]>, CsfError> {
        if count == 0 {
            return Ok(Cow::Borrowed(&[])); // zero-length arrays are accepted whatever their offset
        }
        let size = count.checked_mul(element_size).ok_or_else(|| {
            error(
                structure,
                field,
                format!("{count} elements of {element_size} bytes overflow"),
            )
        })?;
        if offset == 0 {
            return Err(error(
                structure,
                field,
                format!("is null, but {count} elements are declared"),
            ));
        }
        if offset < self.header_size as u64 {
            return Err(error(
                structure,
                field,
                format!("offset {offset} lies inside the header"),
            ));
        }
        if offset % align != 0 {
            return Err(error(
                structure,
                field,
                format!("offset {offset} is not aligned to {align} bytes"),
            ));
        }
        let end = offset.checked_add(size).ok_or_else(|| {
            error(
                structure,
                field,
                format!("offset {offset} + {size} bytes overflows"),
            )
        })?;
        if end > self.bytes.len() {
            return Err(error(
                structure,
                field,
                format!(
                    "bytes {offset}..{end} lie beyond the end of the file ({} bytes)",
                    self.bytes.len()
                ),
            ));
        }
        self.read(structure, field, offset, size)
    }
}

/// Checks the pointer table as the reference loader does before it relocates through it: the
/// table 8-aligned and inside the file, each entry the 8-aligned offset of a pointer field
/// after the header's first 40 bytes and inside the file. cadr reads by the schema and never
/// relocates, but a file it accepts must be one the reference loader can read.
fn check_pointer_table(reader: &Reader<'_>, num_pointers: i32, table: u64) -> Result<(), CsfError> {
    let entries = count("header", "numPointers", num_pointers)?;
    if entries == 0 {
        return Ok(());
    }
    let size = reader.bytes.len();
    if table % 8 != 0 {
        return Err(error(
            "header",
            "pointersOFFSET",
            format!("offset {table} is not aligned to 8 bytes"),
        ));
    }
    let end = entries
        .checked_mul(8)
        .and_then(|bytes| table.checked_add(bytes))
        .filter(|&end| end <= size)
        .ok_or_else(|| {
            error(
                "header",
                "pointersOFFSET",
                format!(
                    "the table of {entries} pointers at offset {table} lies beyond the end of the file ({size} bytes)"
                ),
            )
        })?;
    let table_bytes = reader.read("header", "pointersOFFSET", table, end - table)?;
    let fields = Fields(&table_bytes);
    for (index, at) in (0..end - table).step_by(8).enumerate() {
        let location = fields.u64(at as usize);
        if location % 8 != 0 || location < 40 || location > size.saturating_sub(8) {
            return Err(error(
                "pointer table",
                "entry",
                format!(
                    "entry {index} points at offset {location}, not an 8-aligned pointer field between 40 and {}",
                    size.saturating_sub(8)
                ),
            ));
        }
    }
    Ok(())
}

fn count(structure: &str, field: &'static str, value: i32) -> Result<u64, CsfError> {
    u64::try_from(value).map_err(|_| error(structure, field, format!("count {value} is negative")))
}

fn product(structure: &str, field: &'static str, factors: &[u64]) -> Result<u64, CsfError> {
    factors
        .iter()
        .try_fold(1_u64, |acc, &f| acc.checked_mul(f))
        .ok_or_else(|| error(structure, field, "count overflows"))
}

/// Parses a CSF file of version 2 to 6 (already decompressed).
pub fn read_csf(data: &[u8]) -> Result<CsfFile, CsfError> {
    let mut geometries = Vec::new();
    let mut file = read_csf_through(data, &mut |_, _, geometry| {
        geometries.push(geometry);
        Ok(())
    })?;
    file.geometries = geometries;
    Ok(file)
}

/// What takes each geometry of a file [`read_csf_through`] reads: the file read so far (all but
/// its geometries), the geometry's index, and the geometry.
pub type TakeCsfGeometry<'t> = dyn FnMut(&CsfFile, usize, CsfGeometry) -> Result<(), CsfError> + 't;

/// [`read_csf`] that hands each geometry to `take` as soon as it is read, in order, after
/// everything else of the file is read and checked, and returns the file without its
/// geometries: so that a reader converting them one by one never holds them all.
pub fn read_csf_through(data: &[u8], take: &mut TakeCsfGeometry<'_>) -> Result<CsfFile, CsfError> {
    read_csf_from(CsfBytes::Memory(data), take)
}

/// [`read_csf_through`] from `bytes`, in memory or in a file.
pub fn read_csf_from(
    bytes: CsfBytes<'_>,
    take: &mut TakeCsfGeometry<'_>,
) -> Result<CsfFile, CsfError> {
    let head = bytes
        .read(0, bytes.len().min(HEADER_SIZE_V5 as u64))
        .map_err(|e| error("header", "size", format!("could not be read: {e}")))?;
    let (version, header_size) = check_header(&head, bytes.len())?;
    let header = Fields(&head);
    let raw_flags = header.u32(8);
    let file_flags = if version < 3 {
        if raw_flags != 0 {
            FLAG_UNIQUE_NODES
        } else {
            0
        }
    } else {
        raw_flags
    };
    let num_geometries = count("header", "numGeometries", header.i32(16))?;
    let num_materials = count("header", "numMaterials", header.i32(20))?;
    let num_nodes = count("header", "numNodes", header.i32(24))?;
    let root = header.i32(28);
    if root >= 0 && root as u64 >= num_nodes {
        return Err(error(
            "header",
            "rootIDX",
            format!("{root}, but there are {num_nodes} nodes"),
        ));
    }
    let reader = Reader { bytes, header_size };
    check_pointer_table(&reader, header.i32(12), header.u64(32))?;

    let geometry_bytes = reader.array(
        "header",
        "geometriesOFFSET",
        header.u64(40),
        num_geometries,
        GEOMETRY_SIZE as u64,
        8,
    )?;
    // The nodes are checked against each geometry's part count, read ahead of its arrays.
    let geometry_parts = geometry_bytes
        .chunks_exact(GEOMETRY_SIZE)
        .enumerate()
        .map(|(index, bytes)| {
            count(
                &format!("geometry {index}"),
                "numParts",
                Fields(bytes).i32(64),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;

    let material_bytes = reader.array(
        "header",
        "materialsOFFSET",
        header.u64(48),
        num_materials,
        MATERIAL_SIZE as u64,
        8,
    )?;
    let materials = material_bytes
        .chunks_exact(MATERIAL_SIZE)
        .enumerate()
        .map(|(index, bytes)| read_material(&reader, index, Fields(bytes)))
        .collect::<Result<Vec<_>, CsfError>>()?;

    let node_bytes = reader.array(
        "header",
        "nodesOFFSET",
        header.u64(56),
        num_nodes,
        NODE_SIZE as u64,
        8,
    )?;
    let nodes = node_bytes
        .chunks_exact(NODE_SIZE)
        .enumerate()
        .map(|(index, bytes)| {
            read_node(
                &reader,
                version,
                root,
                index,
                Fields(bytes),
                &geometry_parts,
                num_materials,
                num_nodes,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    check_acyclic(&nodes)?;

    let (node_metas, geometry_metas, file_meta) = if version >= 5 {
        read_all_metas(&reader, &header, num_nodes, num_geometries)?
    } else {
        (Vec::new(), Vec::new(), None)
    };
    let file = CsfFile {
        version,
        file_flags,
        root,
        geometries: Vec::new(),
        materials,
        nodes,
        node_metas,
        geometry_metas,
        file_meta,
    };
    for (index, bytes) in geometry_bytes.chunks_exact(GEOMETRY_SIZE).enumerate() {
        let geometry = read_geometry(&reader, version, file_flags, index, Fields(bytes))?;
        take(&file, index, geometry)?;
    }
    Ok(file)
}

/// A file's node, geometry and file metas.
type Metas = (Vec<CsfMeta>, Vec<CsfMeta>, Option<CsfMeta>);

/// The node, geometry and file metas of a file of version 5 or later.
fn read_all_metas(
    reader: &Reader<'_>,
    header: &Fields<'_>,
    num_nodes: u64,
    num_geometries: u64,
) -> Result<Metas, CsfError> {
    let node_metas = read_metas(
        reader,
        "nodeMetasOFFSET",
        "node meta",
        header.u64(64),
        num_nodes,
    )?;
    let geometry_metas = read_metas(
        reader,
        "geometryMetasOFFSET",
        "geometry meta",
        header.u64(72),
        num_geometries,
    )?;
    let file_meta = read_metas(reader, "fileMetaOFFSET", "file meta", header.u64(80), 1)?
        .into_iter()
        .next();
    Ok((node_metas, geometry_metas, file_meta))
}

/// The file's version and header size, once its size, magic and version are checked.
/// `head` is the file's first bytes (up to a version 5 header's), `len` its length.
fn check_header(head: &[u8], len: u64) -> Result<(i32, usize), CsfError> {
    if len < HEADER_SIZE_V4 as u64 {
        return Err(error(
            "header",
            "size",
            format!("the file has {len} bytes; a header needs {HEADER_SIZE_V4}"),
        ));
    }
    let header = Fields(head);
    let magic = header.i32(0);
    if magic != MAGIC {
        return Err(error(
            "header",
            "magic",
            format!("{:#010x} is not the CSF magic {MAGIC:#010x}", magic as u32),
        ));
    }
    let version = header.i32(4);
    if !(VERSION_COMPAT..=VERSION).contains(&version) {
        return Err(error(
            "header",
            "version",
            format!("{version} is not supported (versions {VERSION_COMPAT} to {VERSION})"),
        ));
    }
    let header_size = if version >= 5 {
        HEADER_SIZE_V5
    } else {
        HEADER_SIZE_V4
    };
    if len < header_size as u64 {
        return Err(error(
            "header",
            "size",
            format!("the file has {len} bytes; a version {version} header needs {header_size}"),
        ));
    }
    Ok((version, header_size))
}

/// Material `index`, from its fields: name, colour, kind and payload bytes.
fn read_material(
    reader: &Reader<'_>,
    index: usize,
    fields: Fields<'_>,
) -> Result<CsfMaterial, CsfError> {
    let structure = format!("material {index}");
    let payload = reader.array(
        &structure,
        "bytesOFFSET",
        fields.u64(152),
        u64::from(fields.u32(148)),
        1,
        1,
    )?;
    Ok(CsfMaterial {
        name: fields.name(0),
        color: std::array::from_fn(|i| fields.f32(128 + 4 * i)),
        kind: fields.i32(144),
        bytes: payload.to_vec(),
    })
}

fn read_metas(
    reader: &Reader<'_>,
    field: &'static str,
    what: &str,
    offset: u64,
    count: u64,
) -> Result<Vec<CsfMeta>, CsfError> {
    if offset == 0 {
        return Ok(Vec::new());
    }
    let bytes = reader.array("header", field, offset, count, META_SIZE as u64, 8)?;
    bytes
        .chunks_exact(META_SIZE)
        .enumerate()
        .map(|(index, bytes)| {
            let fields = Fields(bytes);
            let structure = format!("{what} {index}");
            let payload = reader.array(
                &structure,
                "bytesOFFSET",
                fields.u64(144),
                fields.u64(136),
                1,
                1,
            )?;
            Ok(CsfMeta {
                name: fields.name(0),
                flags: fields.i32(128),
                bytes: payload.to_vec(),
            })
        })
        .collect()
}

fn read_geometry(
    reader: &Reader<'_>,
    version: i32,
    file_flags: u32,
    index: usize,
    fields: Fields<'_>,
) -> Result<CsfGeometry, CsfError> {
    let s = format!("geometry {index}");
    let s = s.as_str();
    let num_parts = count(s, "numParts", fields.i32(64))?;
    let num_vertices = count(s, "numVertices", fields.i32(68))?;
    let num_index_solid = count(s, "numIndexSolid", fields.i32(72))?;
    let num_index_wire = count(s, "numIndexWire", fields.i32(76))?;
    let (vertex_offset, normal_offset, tex_offset) =
        (fields.u64(80), fields.u64(88), fields.u64(96));
    let [normal_channels, tex_channels, aux_channels, part_channels] =
        channel_counts(s, version, &fields, num_vertices)?;
    if num_vertices > 0 && vertex_offset == 0 {
        return Err(error(
            s,
            "vertexOFFSET",
            format!("is null, but there are {num_vertices} vertices"),
        ));
    }
    let vertices = floats(reader.array(
        s,
        "vertexOFFSET",
        vertex_offset,
        product(s, "numVertices", &[num_vertices, 3])?,
        4,
        4,
    )?);
    let normals = floats(reader.array(
        s,
        "normalOFFSET",
        normal_offset,
        product(s, "numNormalChannels", &[num_vertices, 3, normal_channels])?,
        4,
        4,
    )?);
    let tex = floats(reader.array(
        s,
        "texOFFSET",
        tex_offset,
        product(s, "numTexChannels", &[num_vertices, 2, tex_channels])?,
        4,
        4,
    )?);
    // Version 6 added auxiliary vertex channels and per-part channels.
    let extra = if version >= 6 {
        read_extra_channels(
            reader,
            s,
            &fields,
            (num_vertices, num_parts),
            (aux_channels, part_channels),
        )?
    } else {
        ExtraChannels::default()
    };
    let index_solid = u32s(reader.array(
        s,
        "indexSolidOFFSET",
        fields.u64(104),
        num_index_solid,
        4,
        4,
    )?);
    let index_wire =
        u32s(reader.array(s, "indexWireOFFSET", fields.u64(112), num_index_wire, 4, 4)?);
    let parts: Vec<CsfGeometryPart> = reader
        .array(
            s,
            "partsOFFSET",
            fields.u64(120),
            num_parts,
            PART_SIZE as u64,
            4,
        )?
        .chunks_exact(PART_SIZE)
        .map(|p| {
            let f = Fields(p);
            CsfGeometryPart {
                deprecated: f.i32(0),
                num_index_solid: f.i32(4),
                num_index_wire: f.i32(8),
            }
        })
        .collect();
    let geometry = CsfGeometry {
        vertices,
        normals,
        normal_channels: normal_channels as i32,
        tex,
        tex_channels: tex_channels as i32,
        aux: extra.aux,
        aux_storage_order: extra.aux_storage_order,
        perpart: extra.perpart,
        perpart_storage_order: extra.perpart_storage_order,
        index_solid,
        index_wire,
        parts,
    };
    check_parts(s, &geometry, file_flags)?;
    Ok(geometry)
}

/// A geometry's channel counts: normals, texture coordinates, auxiliary and per-part
/// channels. Before version 6, bytes 16..63 held a deprecated matrix: the counts are derived
/// from the data offsets instead.
fn channel_counts(
    s: &str,
    version: i32,
    fields: &Fields<'_>,
    num_vertices: u64,
) -> Result<[u64; 4], CsfError> {
    let (normal_offset, tex_offset) = (fields.u64(88), fields.u64(96));
    let (normal_channels, tex_channels, aux_channels, part_channels) = if version >= 6 {
        (
            count(s, "numNormalChannels", fields.i32(16))?,
            count(s, "numTexChannels", fields.i32(20))?,
            count(s, "numAuxChannels", fields.i32(24))?,
            count(s, "numPartChannels", fields.i32(28))?,
        )
    } else {
        (
            u64::from(normal_offset != 0),
            u64::from(tex_offset != 0),
            0,
            0,
        )
    };
    // A null data offset means the channels are absent, whatever the count says; so do
    // channels of no vertices (or parts), which hold no data (and are written back as null).
    let normal_channels = if normal_offset == 0 || num_vertices == 0 {
        0
    } else {
        normal_channels
    };
    let tex_channels = if tex_offset == 0 || num_vertices == 0 {
        0
    } else {
        tex_channels
    };
    Ok([normal_channels, tex_channels, aux_channels, part_channels])
}

/// The auxiliary vertex channels and per-part channels a version 6 geometry adds: the aux
/// values and their storage order, the per-part values and theirs. A null offset means the
/// channels are absent whatever the count says, as do channels of no vertices (or parts).
fn read_extra_channels(
    reader: &Reader<'_>,
    s: &str,
    fields: &Fields<'_>,
    (num_vertices, num_parts): (u64, u64),
    (aux_channels, part_channels): (u64, u64),
) -> Result<ExtraChannels, CsfError> {
    let aux_channels = if fields.u64(40) == 0 || num_vertices == 0 {
        0
    } else {
        aux_channels
    };
    let aux = floats(reader.array(
        s,
        "auxOFFSET",
        fields.u64(40),
        product(s, "numAuxChannels", &[num_vertices, 4, aux_channels])?,
        4,
        4,
    )?);
    let aux_storage_order = i32s(reader.array(
        s,
        "auxStorageOrderOFFSET",
        fields.u64(32),
        aux_channels,
        4,
        4,
    )?);
    let part_channels = if fields.u64(56) == 0 || num_parts == 0 {
        0
    } else {
        part_channels
    };
    let perpart_storage_order = i32s(reader.array(
        s,
        "perpartStorageOrderOFFSET",
        fields.u64(48),
        part_channels,
        4,
        4,
    )?);
    let mut per_part_size = 0_u64;
    for (i, &channel) in perpart_storage_order.iter().enumerate() {
        let size = part_channel_size(channel).ok_or_else(|| {
            error(
                s,
                "perpartStorageOrderOFFSET",
                format!("entry {i} is the unknown part channel {channel}"),
            )
        })?;
        per_part_size += size as u64;
    }
    let perpart = reader
        .array(
            s,
            "perpartOFFSET",
            fields.u64(56),
            product(s, "numPartChannels", &[per_part_size, num_parts])?,
            1,
            4,
        )?
        .to_vec();
    Ok(ExtraChannels {
        aux,
        aux_storage_order,
        perpart,
        perpart_storage_order,
    })
}

/// What [`read_extra_channels`] reads, in [`CsfGeometry`]'s terms.
#[derive(Default)]
struct ExtraChannels {
    aux: Vec<f32>,
    aux_storage_order: Vec<i32>,
    perpart: Vec<u8>,
    perpart_storage_order: Vec<i32>,
}

/// Part ranges lie within the index buffers and indices within the vertices.
fn check_parts(s: &str, geometry: &CsfGeometry, file_flags: u32) -> Result<(), CsfError> {
    let (mut solid, mut wire) = (0_i64, 0_i64);
    for (p, part) in geometry.parts.iter().enumerate() {
        if part.num_index_solid < 0 || part.num_index_wire < 0 {
            return Err(error(
                format!("{s} part {p}"),
                "numIndexSolid",
                "index counts must not be negative",
            ));
        }
        solid += i64::from(part.num_index_solid);
        wire += i64::from(part.num_index_wire);
    }
    if solid > geometry.index_solid.len() as i64 {
        return Err(error(
            s,
            "parts",
            format!(
                "the parts use {solid} solid indices, but the geometry has {}",
                geometry.index_solid.len()
            ),
        ));
    }
    if wire > geometry.index_wire.len() as i64 {
        return Err(error(
            s,
            "parts",
            format!(
                "the parts use {wire} wire indices, but the geometry has {}",
                geometry.index_wire.len()
            ),
        ));
    }
    let vertex_count = geometry.vertex_count() as u64;
    let ranges = if file_flags & FLAG_PER_PART_VERTICES != 0 {
        Some(geometry.part_vertex_ranges().ok_or_else(|| {
            error(
                s,
                "perpartStorageOrderOFFSET",
                "the file has per-part vertices (flag 32) but no VERTEXRANGE part channel",
            )
        })?)
    } else {
        None
    };
    let (mut solid_start, mut wire_start) = (0_usize, 0_usize);
    for (p, part) in geometry.parts.iter().enumerate() {
        let (begin, count) = ranges.as_ref().map_or((0, vertex_count), |r| {
            (u64::from(r[p].0), u64::from(r[p].1))
        });
        if begin + count > vertex_count {
            return Err(error(
                format!("{s} part {p}"),
                "VERTEXRANGE",
                format!("vertices {begin}..{} beyond {vertex_count}", begin + count),
            ));
        }
        for (field, indices, start, len) in [
            (
                "indexSolidOFFSET",
                &geometry.index_solid,
                solid_start,
                part.num_index_solid as usize,
            ),
            (
                "indexWireOFFSET",
                &geometry.index_wire,
                wire_start,
                part.num_index_wire as usize,
            ),
        ] {
            if let Some((i, &value)) = indices[start..start + len]
                .iter()
                .enumerate()
                .find(|(_, &v)| u64::from(v) >= count)
            {
                return Err(error(
                    format!("{s} part {p}"),
                    field,
                    format!(
                        "index {} is {value}, but the part has {count} vertices",
                        start + i
                    ),
                ));
            }
        }
        solid_start += part.num_index_solid as usize;
        wire_start += part.num_index_wire as usize;
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn read_node(
    reader: &Reader<'_>,
    version: i32,
    root: i32,
    index: usize,
    fields: Fields<'_>,
    geometry_parts: &[u64],
    num_materials: u64,
    num_nodes: u64,
) -> Result<CsfNode, CsfError> {
    let s = format!("node {index}");
    let s = s.as_str();
    let geometry = fields.i32(128);
    if geometry < -1 || geometry >= 0 && geometry as usize >= geometry_parts.len() {
        return Err(error(
            s,
            "geometryIDX",
            format!(
                "{geometry}, but there are {} geometries",
                geometry_parts.len()
            ),
        ));
    }
    let num_parts = count(s, "numParts", fields.i32(132))?;
    let expected_parts = if geometry >= 0 {
        geometry_parts[geometry as usize]
    } else {
        0
    };
    if num_parts != expected_parts {
        return Err(error(
            s,
            "numParts",
            format!("{num_parts}, but its geometry {geometry} has {expected_parts} parts"),
        ));
    }
    let num_children = count(s, "numChildren", fields.i32(136))?;
    let parts = reader
        .array(
            s,
            "partsOFFSET",
            fields.u64(144),
            num_parts,
            PART_SIZE as u64,
            4,
        )?
        .chunks_exact(PART_SIZE)
        .enumerate()
        .map(|(p, bytes)| {
            let f = Fields(bytes);
            let part = CsfNodePart {
                active: f.i32(0),
                material: f.i32(4),
                node: if version < 4 { -1 } else { f.i32(8) },
            };
            if part.material < 0 || part.material as u64 >= num_materials {
                return Err(error(
                    format!("{s} part {p}"),
                    "materialIDX",
                    format!("{}, but there are {num_materials} materials", part.material),
                ));
            }
            if part.node < -1 || part.node >= 0 && part.node as u64 >= num_nodes {
                return Err(error(
                    format!("{s} part {p}"),
                    "nodeIDX",
                    format!("{}, but there are {num_nodes} nodes", part.node),
                ));
            }
            Ok(part)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let children = i32s(reader.array(s, "childrenOFFSET", fields.u64(152), num_children, 4, 4)?);
    if let Some((i, &child)) = children
        .iter()
        .enumerate()
        .find(|(_, &c)| c < 0 || c as u64 >= num_nodes)
    {
        return Err(error(
            s,
            "childrenOFFSET",
            format!("child {i} is {child}, but there are {num_nodes} nodes"),
        ));
    }
    if root < 0 && !children.is_empty() {
        return Err(error(
            s,
            "numChildren",
            format!("{num_children} children in a flat file (rootIDX {root})"),
        ));
    }
    Ok(CsfNode {
        object_tm: fields.matrix(0),
        world_tm: fields.matrix(64),
        geometry,
        parts,
        children,
    })
}

/// Fails when the children graph has a cycle.
fn check_acyclic(nodes: &[CsfNode]) -> Result<(), CsfError> {
    let child = |node: usize, i: usize| nodes[node].children.get(i).map(|&c| c as usize);
    match first_cycle(nodes.len(), child) {
        Some((node, child)) => Err(error(
            format!("node {node}"),
            "childrenOFFSET",
            format!("child {child} closes a cycle"),
        )),
        None => Ok(()),
    }
}
