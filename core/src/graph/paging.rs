//! Which geometries the graph keeps in memory and which in its page file: geometries go to
//! memory until their bytes reach the graph's share of the memory budget (half of it), and to
//! the page file after that, so that a model larger than memory loads. What every user of a
//! geometry needs without its arrays (name, parts, whether it has attributes) stays in memory.

use std::borrow::Cow;
use std::path::PathBuf;

use super::page_file::{Page, PageFile};
use super::GraphError;
use crate::scene::{Aabb, Geometry, Part};

/// Where one geometry is kept.
#[derive(Clone, Debug)]
pub(super) enum StoredGeometry {
    /// In memory.
    Resident(Geometry),
    /// In the page file, with what is known of it without reading it.
    Paged {
        /// Its record.
        page: Page,
        /// Its name.
        name: String,
        /// Its parts.
        parts: Vec<Part>,
        /// Whether its vertices have attributes.
        has_attributes: bool,
        /// The bounds of its vertices.
        bounds: Aabb,
    },
}

/// What a geometry is, without its arrays (see [`super::SceneGraph::geometry_info_at`]).
#[derive(Clone, Copy, Debug)]
pub struct GeometryInfo<'g> {
    /// Its name.
    pub name: &'g str,
    /// Its parts.
    pub parts: &'g [Part],
    /// Whether its vertices have texture coordinates and colours.
    pub has_attributes: bool,
    /// Whether it is kept in the page file (reading it costs a file read).
    pub paged: bool,
}

/// A geometry as another thread can read it (see
/// [`super::SceneGraph::geometry_source_at`]).
#[derive(Debug)]
pub enum GeometrySource {
    /// A copy of a geometry kept in memory.
    Copy(Geometry),
    /// The record of a geometry kept in the page file, and the geometry's name.
    Page(Page, String),
}

impl GeometrySource {
    /// The geometry; fails, naming the geometry and the file, where its page cannot be read.
    pub fn load(self) -> Result<Geometry, String> {
        match self {
            Self::Copy(geometry) => Ok(geometry),
            Self::Page(page, name) => page.read().map_err(|e| format!("geometry '{name}': {e}")),
        }
    }
}

/// Where the graph's geometries are kept (see [`super::SceneGraph::geometry_memory`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GeometryMemory {
    /// Bytes of geometry in memory.
    pub resident_bytes: u64,
    /// Bytes of geometry in the page file.
    pub paged_bytes: u64,
    /// Geometries in the page file.
    pub paged_geometries: u64,
    /// The page file new records go to, once one is made (a graph that adopted loaded
    /// geometries also keeps the loads' files).
    pub page_file: Option<PathBuf>,
}

impl StoredGeometry {
    /// The geometry, read back where it is paged.
    pub(super) fn load(&self) -> Result<Cow<'_, Geometry>, GraphError> {
        match self {
            Self::Resident(geometry) => Ok(Cow::Borrowed(geometry)),
            Self::Paged { page, name, .. } => (page.read())
                .map(Cow::Owned)
                .map_err(|e| GraphError::PageRead(format!("geometry '{name}': {e}"))),
        }
    }

    /// What it is, without reading it.
    pub(super) fn info(&self) -> GeometryInfo<'_> {
        match self {
            Self::Resident(geometry) => GeometryInfo {
                name: &geometry.name,
                parts: &geometry.parts,
                has_attributes: !geometry.attributes.is_empty(),
                paged: false,
            },
            Self::Paged {
                name,
                parts,
                has_attributes,
                ..
            } => GeometryInfo {
                name,
                parts,
                has_attributes: *has_attributes,
                paged: true,
            },
        }
    }

    /// The bounds of its vertices.
    pub(super) fn bounds(&self) -> Aabb {
        match self {
            Self::Resident(geometry) => geometry.bounds(),
            Self::Paged { bounds, .. } => *bounds,
        }
    }

    /// What another thread can read it from.
    pub(super) fn source(&self) -> GeometrySource {
        match self {
            Self::Resident(geometry) => GeometrySource::Copy(geometry.clone()),
            Self::Paged { page, name, .. } => GeometrySource::Page(page.clone(), name.clone()),
        }
    }
}

/// The graph's paging state: its limit, what is in memory, and the page file.
pub(super) struct Paging {
    /// The most geometry bytes kept in memory.
    limit: u64,
    resident_bytes: u64,
    paged_geometries: u64,
    /// Its page files: the one it writes to last; more after it adopted loaded geometries
    /// ([`Paging::absorb`]). A file whose records are all freed goes, but for the last.
    files: Vec<PageFile>,
    /// Whether a failure to write the page file was reported (once: the geometries then stay
    /// in memory).
    failure_reported: bool,
}

impl Paging {
    /// Paging at half the memory budget.
    pub(super) fn new() -> Self {
        Self {
            limit: crate::memory_budget::budget().unwrap_or(u64::MAX) / 2,
            resident_bytes: 0,
            paged_geometries: 0,
            files: Vec::new(),
            failure_reported: false,
        }
    }

    pub(super) fn set_limit(&mut self, bytes: u64) {
        self.limit = bytes;
    }

    /// Keeps `geometry`: in memory while that stays within the limit, else in the page file
    /// (in memory after all where the file cannot be written: no data is lost).
    pub(super) fn store(&mut self, geometry: Geometry) -> StoredGeometry {
        let bytes = geometry.host_bytes();
        if self.resident_bytes.saturating_add(bytes) > self.limit {
            match self.page_out(&geometry) {
                Ok(page) => {
                    self.paged_geometries += 1;
                    return StoredGeometry::Paged {
                        page,
                        has_attributes: !geometry.attributes.is_empty(),
                        bounds: geometry.bounds(),
                        name: geometry.name,
                        parts: geometry.parts,
                    };
                }
                Err(message) if !self.failure_reported => {
                    self.failure_reported = true;
                    log::warn!("{message}; geometries stay in memory");
                }
                Err(_) => {}
            }
        }
        self.resident_bytes += bytes;
        StoredGeometry::Resident(geometry)
    }

    fn page_out(&mut self, geometry: &Geometry) -> Result<Page, String> {
        if self.files.is_empty() {
            self.files.push(PageFile::create()?);
        }
        let last = self.files.len() - 1;
        self.files[last].write(geometry)
    }

    /// Takes over what `other` keeps (the geometries it stored now belong to this paging):
    /// its bytes in memory, its paged geometries and its page files.
    pub(super) fn absorb(&mut self, other: Paging) {
        self.resident_bytes += other.resident_bytes;
        self.paged_geometries += other.paged_geometries;
        // Ours stays last: new records keep going to it.
        let ours = std::mem::replace(&mut self.files, other.files);
        self.files.extend(ours);
    }

    /// Bytes the limit leaves for geometries kept in memory.
    pub(super) fn memory_left(&self) -> u64 {
        self.limit.saturating_sub(self.resident_bytes)
    }

    /// Forgets a geometry kept by [`Paging::store`] (destroyed or replaced).
    pub(super) fn release(&mut self, stored: &StoredGeometry) {
        match stored {
            StoredGeometry::Resident(geometry) => self.resident_bytes -= geometry.host_bytes(),
            StoredGeometry::Paged { page, .. } => {
                self.paged_geometries -= 1;
                let Some(at) = self.files.iter().position(|f| f.holds(page)) else {
                    return;
                };
                self.files[at].free(page);
                if self.files[at].bytes_in_use() == 0 && at + 1 < self.files.len() {
                    self.files.remove(at);
                }
            }
        }
    }

    pub(super) fn memory(&self) -> GeometryMemory {
        GeometryMemory {
            resident_bytes: self.resident_bytes,
            paged_bytes: self.files.iter().map(PageFile::bytes_in_use).sum(),
            paged_geometries: self.paged_geometries,
            page_file: self.files.last().map(|f| f.path().to_path_buf()),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::super::SceneGraph;
    use crate::scene::{Geometry, Part, Vertex};

    fn quad(name: &str, size: f32) -> Geometry {
        let vertex = |x: f32, y: f32| Vertex {
            position: [x * size, y * size, 0.0],
            normal: [0.0, 0.0, 1.0],
        };
        Geometry {
            name: name.into(),
            vertices: vec![
                vertex(0.0, 0.0),
                vertex(1.0, 0.0),
                vertex(1.0, 1.0),
                vertex(0.0, 1.0),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
            parts: vec![Part {
                first_index: 0,
                index_count: 6,
                ..Part::default()
            }],
            ..Geometry::default()
        }
    }

    #[test]
    fn geometries_past_the_memory_limit_go_to_the_page_file_and_read_back_unchanged() {
        let mut graph = SceneGraph::new();
        graph.set_geometry_memory_limit(quad("a", 1.0).host_bytes());
        let a = graph.create_geometry(quad("a", 1.0)).unwrap();
        let b = graph.create_geometry(quad("b", 2.0)).unwrap();
        let c = graph.create_geometry(quad("c", 3.0)).unwrap();
        let paged = |graph: &SceneGraph, h: super::super::GeometryHandle| {
            graph.geometry_info_at(h.index()).unwrap().paged
        };
        assert!(!paged(&graph, a) && paged(&graph, b) && paged(&graph, c));
        assert_eq!(*graph.geometry(b).unwrap(), quad("b", 2.0));
        assert_eq!(graph.geometry_bounds(c).unwrap(), quad("c", 3.0).bounds());
        let memory = graph.geometry_memory();
        assert_eq!(memory.resident_bytes, quad("a", 1.0).host_bytes());
        assert_eq!(memory.paged_geometries, 2);
        let page_file = memory.page_file.clone().unwrap();
        assert_eq!(
            std::fs::metadata(&page_file).unwrap().len(),
            memory.paged_bytes
        );

        // Replaced and destroyed geometries give their room back.
        graph.replace_geometry(b, quad("b2", 5.0)).unwrap();
        assert_eq!(*graph.geometry(b).unwrap(), quad("b2", 5.0));
        assert_eq!(graph.geometry_memory().paged_bytes, memory.paged_bytes);
        graph.destroy_geometry(c).unwrap();
        assert_eq!(graph.geometry_memory().paged_geometries, 1);
        assert!(graph.geometry_memory().paged_bytes < memory.paged_bytes);
        let scene = graph.to_scene().unwrap();
        assert_eq!(scene.geometries, vec![quad("a", 1.0), quad("b2", 5.0)]);
        drop(graph);
        assert!(!page_file.exists(), "the page file goes with the graph");
    }
}
