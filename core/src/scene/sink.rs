//! Where a loader puts each geometry as soon as it has made it: kept in the scene (the plain
//! road, for savers, converters and tests), or handed to a scene graph that may write it to its
//! page file at once (`crate::graph::GeometryIntake`), so that loading a model larger than
//! memory never holds all of its geometry. And where a saver reads them back, one at a time
//! ([`GeometryStore`]).

use std::borrow::Cow;

use super::{Aabb, Geometry, Scene, SceneError};

/// Where a saver reads a scene's geometries, one at a time: the scene itself, or the sink a
/// load handed them to (`crate::graph::LoadedGeometries`, whose scene is an outline).
pub trait GeometryStore {
    /// How many geometries there are.
    fn geometry_count(&self) -> usize;
    /// Geometry number `index` (below [`GeometryStore::geometry_count`]), or why it cannot be
    /// read (a page file that fails, naming the geometry).
    fn geometry(&self, index: usize) -> Result<Cow<'_, Geometry>, String>;
}

/// A scene's own geometries, in memory.
impl GeometryStore for Scene {
    fn geometry_count(&self) -> usize {
        self.geometries.len()
    }

    fn geometry(&self, index: usize) -> Result<Cow<'_, Geometry>, String> {
        self.geometries
            .get(index)
            .map(Cow::Borrowed)
            .ok_or_else(|| format!("the scene has no geometry {index}"))
    }
}

/// Takes the geometries of a scene being loaded, one by one.
pub trait GeometrySink {
    /// Takes geometry number `index` of the scene being loaded (already validated) and returns
    /// what the scene keeps at that index: the geometry itself, or, where the sink keeps its
    /// arrays, a stand-in with its name and parts and no arrays. A scene holding stand-ins is
    /// an outline: only the sink that made them can complete it.
    fn take(&mut self, index: u32, geometry: Geometry) -> Geometry;
}

/// The sink that keeps every geometry in the scene.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeepInScene;

impl GeometrySink for KeepInScene {
    fn take(&mut self, _index: u32, geometry: Geometry) -> Geometry {
        geometry
    }
}

/// What flattening and statistics need of a geometry a sink keeps (see
/// [`super::flatten_outline`], [`super::SceneStats::of_outline`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometrySummary {
    /// The bounds of its vertices.
    pub bounds: Aabb,
    /// Its vertex count.
    pub vertices: u64,
}

impl Geometry {
    /// Its bounds and vertex count.
    pub fn summary(&self) -> GeometrySummary {
        GeometrySummary {
            bounds: self.bounds(),
            vertices: self.vertices.len() as u64,
        }
    }

    /// The stand-in a sink leaves in an outline scene for a geometry it keeps (see
    /// [`GeometrySink::take`]): the name and parts, no arrays.
    pub fn stand_in(&self) -> Geometry {
        Geometry {
            name: self.name.clone(),
            parts: self.parts.clone(),
            ..Geometry::default()
        }
    }
}

impl Scene {
    /// Validates `geometry` as the scene's next one and hands it to `sink`; returns its index.
    /// The error names the geometry by that index.
    pub fn add_geometry(
        &mut self,
        sink: &mut dyn GeometrySink,
        geometry: Geometry,
    ) -> Result<u32, SceneError> {
        let index = self.geometries.len() as u32;
        geometry.validate(index as usize)?;
        let kept = sink.take(index, geometry);
        self.geometries.push(kept);
        Ok(index)
    }

    /// Hands every geometry of a scene made whole in memory (by a generator: valid as made) to
    /// `sink`, so that the scene becomes what handing each as it was made would have made.
    pub fn hand_geometries_to(&mut self, sink: &mut dyn GeometrySink) {
        for (index, geometry) in std::mem::take(&mut self.geometries).into_iter().enumerate() {
            let kept = sink.take(index as u32, geometry);
            self.geometries.push(kept);
        }
    }
}
