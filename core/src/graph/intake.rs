//! Loading for the graph: the geometries a loader makes are taken one by one, kept in memory up
//! to a limit and written to a page file beyond it at once, so that a model larger than memory
//! loads with no more of its geometry in memory than the limit; the loader's scene is only an
//! outline (stand-ins for the geometries). A graph then adopts them, page file and all
//! ([`super::SceneGraph::import_loaded`]). The load needs no graph, so a host's graph stays
//! free for other threads while a file is read.

use std::borrow::Cow;

use super::paging::{Paging, StoredGeometry};
use crate::scene::{Geometry, GeometrySink, GeometryStore, GeometrySummary};

/// The geometries of a scene being loaded for a graph (a [`GeometrySink`]): in memory up to
/// the limit they were made with, in a page file of their own beyond it. Dropped without being
/// imported, they take their page file with them.
pub struct LoadedGeometries {
    pub(super) paging: Paging,
    /// The geometries taken, in the scene's order.
    pub(super) taken: Vec<StoredGeometry>,
    /// Their bounds and vertex counts, for statistics before the import.
    summaries: Vec<GeometrySummary>,
}

impl LoadedGeometries {
    /// None yet; up to `memory_limit` bytes of them will be kept in memory (see
    /// [`super::SceneGraph::geometry_memory_left`]).
    pub fn new(memory_limit: u64) -> Self {
        let mut paging = Paging::new();
        paging.set_limit(memory_limit);
        Self {
            paging,
            taken: Vec::new(),
            summaries: Vec::new(),
        }
    }

    /// How many have been taken.
    pub fn len(&self) -> usize {
        self.taken.len()
    }

    /// Whether none has been taken.
    pub fn is_empty(&self) -> bool {
        self.taken.is_empty()
    }

    /// The bounds and vertex count of each, in the scene's order (for
    /// `crate::scene::flatten_outline` and `crate::scene::SceneStats::of_outline`).
    pub fn summaries(&self) -> &[GeometrySummary] {
        &self.summaries
    }

    /// Bytes in memory, in the page file, and the file.
    pub fn memory(&self) -> super::GeometryMemory {
        self.paging.memory()
    }
}

impl GeometrySink for LoadedGeometries {
    fn take(&mut self, index: u32, geometry: Geometry) -> Geometry {
        debug_assert_eq!(index as usize, self.taken.len(), "geometries come in order");
        let stand_in = geometry.stand_in();
        self.summaries.push(geometry.summary());
        self.taken.push(self.paging.store(geometry));
        stand_in
    }
}

/// The geometries taken, read back one at a time (from memory, or the page file).
impl GeometryStore for LoadedGeometries {
    fn geometry_count(&self) -> usize {
        self.taken.len()
    }

    fn geometry(&self, index: usize) -> Result<Cow<'_, Geometry>, String> {
        let stored =
            (self.taken.get(index)).ok_or_else(|| format!("the load took no geometry {index}"))?;
        stored.load().map_err(|e| e.to_string())
    }
}

impl std::fmt::Debug for LoadedGeometries {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "LoadedGeometries({} taken, {:?})",
            self.len(),
            self.memory()
        )
    }
}
