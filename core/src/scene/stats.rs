//! Scene statistics, as `cadr info` prints them.

use std::fmt;

use super::{Aabb, FlatScene, GeometrySummary, Scene};

/// Counts of what a scene stores and what it draws.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneStats {
    /// Nodes in the graph.
    pub nodes: usize,
    /// Distinct geometries.
    pub geometries: usize,
    /// Parts over all distinct geometries.
    pub parts: usize,
    /// Materials.
    pub materials: usize,
    /// Paths from a root to a node with a mesh.
    pub mesh_instances: usize,
    /// Paths to drawable parts: one per mesh instance and part (what one-draw-per-part issues).
    pub instances: usize,
    /// Triangles stored in the geometries.
    pub stored_triangles: u64,
    /// Vertices stored in the geometries.
    pub stored_vertices: u64,
    /// Triangles drawn per frame (over all instances).
    pub triangles: u64,
    /// Vertices referenced per frame (over all mesh instances).
    pub vertices: u64,
    /// World-space bounds of what is drawn.
    pub bounds: Aabb,
}

impl SceneStats {
    /// Statistics of `scene` and its flattened form.
    pub fn new(scene: &Scene, flat: &FlatScene) -> Self {
        let vertices: Vec<u64> = (scene.geometries.iter())
            .map(|g| g.vertices.len() as u64)
            .collect();
        Self::with_vertex_counts(scene, flat, &vertices)
    }

    /// Statistics of an outline (a scene whose geometries are stand-ins, see
    /// [`super::GeometrySink`]) and its flattened form ([`super::flatten_outline`]), with what
    /// is known of each geometry: `summaries`, in the scene's order.
    pub fn of_outline(outline: &Scene, flat: &FlatScene, summaries: &[GeometrySummary]) -> Self {
        let vertices: Vec<u64> = summaries.iter().map(|s| s.vertices).collect();
        Self::with_vertex_counts(outline, flat, &vertices)
    }

    /// Statistics of `scene`, whose geometries have `vertices` vertices each.
    fn with_vertex_counts(scene: &Scene, flat: &FlatScene, vertices: &[u64]) -> Self {
        Self {
            nodes: scene.nodes.len(),
            geometries: scene.geometries.len(),
            parts: scene.geometries.iter().map(|g| g.parts.len()).sum(),
            materials: scene.materials.len(),
            mesh_instances: flat.instances.len(),
            instances: flat.draws.len(),
            stored_triangles: scene.geometries.iter().map(|g| g.triangle_count()).sum(),
            stored_vertices: vertices.iter().sum(),
            triangles: flat
                .draws
                .iter()
                .map(|d| u64::from(d.index_count / 3))
                .sum(),
            vertices: flat
                .instances
                .iter()
                .map(|i| vertices[i.geometry as usize])
                .sum(),
            bounds: flat.bounds,
        }
    }
}

impl fmt::Display for SceneStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "nodes:            {}", self.nodes)?;
        writeln!(f, "geometries:       {}", self.geometries)?;
        writeln!(f, "parts:            {} (in the geometries)", self.parts)?;
        writeln!(f, "materials:        {}", self.materials)?;
        writeln!(
            f,
            "mesh instances:   {} (paths to nodes with a geometry)",
            self.mesh_instances
        )?;
        writeln!(
            f,
            "instances:        {} (paths to drawable parts)",
            self.instances
        )?;
        writeln!(
            f,
            "triangles:        {} drawn, {} stored",
            self.triangles, self.stored_triangles
        )?;
        writeln!(
            f,
            "vertices:         {} drawn, {} stored",
            self.vertices, self.stored_vertices
        )?;
        if self.bounds.is_empty() {
            writeln!(f, "bounds:           empty")
        } else {
            let (min, max) = (self.bounds.min, self.bounds.max);
            let size = max - min;
            writeln!(
                f,
                "bounds:           min ({:.4}, {:.4}, {:.4}) max ({:.4}, {:.4}, {:.4}) size ({:.4}, {:.4}, {:.4})",
                min.x, min.y, min.z, max.x, max.y, max.z, size.x, size.y, size.z
            )
        }
    }
}
