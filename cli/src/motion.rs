//! What moves during a benchmark: the camera (`--camera static|orbit`) and assembly nodes
//! (`--animate N`, an exploded view as the `animate` sample shows). Both are deterministic,
//! so runs compare.

use cadr_core::graph::{NodeHandle, NodeKind, SceneGraph};
use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::Aabb;
use glam::{DMat4, DVec3};

/// Frames per full orbit.
const ORBIT_FRAMES: f64 = 120.0;
/// Distance of the orbiting eye from the centre, in scene radii: close enough that the
/// frustum cuts.
const ORBIT_DISTANCE: f64 = 1.1;
/// Frames per explode-and-return cycle of animated nodes.
const ANIMATE_FRAMES: f64 = 60.0;

/// How the camera moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CameraPath {
    /// Fitted to the scene, still.
    Static,
    /// Around the scene, a 120th of a turn per frame.
    Orbit,
}

impl CameraPath {
    /// The option's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Static => "static",
            Self::Orbit => "orbit",
        }
    }
}

/// The motion of a benchmark.
#[derive(Clone, Debug)]
pub struct Motion {
    /// The camera's path.
    pub camera: CameraPath,
    /// Assembly nodes moved every frame: the node, its matrix at rest and its direction.
    moved: Vec<(NodeHandle, DMat4, DVec3)>,
    /// How far they move at most.
    amplitude: f64,
    /// Nodes asked for.
    pub requested: usize,
}

impl Motion {
    /// The camera's path and how many assembly nodes to move (chosen by
    /// [`Motion::choose_nodes`]).
    pub fn new(camera: CameraPath, requested: usize) -> Self {
        Self {
            camera,
            moved: Vec::new(),
            amplitude: 0.0,
            requested,
        }
    }

    /// Picks the nodes to move: Transform nodes with children, nearest the root first (the
    /// assemblies an exploded view moves), at most `requested` of them.
    pub fn choose_nodes(&mut self, graph: &SceneGraph, bounds: &Aabb) {
        self.moved.clear();
        self.amplitude = if bounds.is_empty() {
            1.0
        } else {
            bounds.radius() * 0.05
        };
        let mut queue = std::collections::VecDeque::from([graph.root()]);
        let mut seen = std::collections::HashSet::new();
        while let Some(handle) = queue.pop_front() {
            if self.moved.len() >= self.requested {
                break;
            }
            let Ok(node) = graph.node(handle) else {
                continue;
            };
            if !seen.insert(handle) {
                continue;
            }
            if handle != graph.root()
                && !node.children().is_empty()
                && matches!(node.kind, NodeKind::Transform { .. })
            {
                // A direction of its own, the same every run.
                let i = self.moved.len() as f64;
                let direction =
                    DVec3::new((i * 2.4).cos(), ((i * 1.7).sin()) * 0.5, (i * 2.4).sin());
                self.moved.push((
                    handle,
                    node.local_matrix(),
                    direction.normalize_or(DVec3::X),
                ));
            }
            queue.extend(node.children().iter().map(|link| link.node));
        }
    }

    /// Nodes moved every frame.
    pub fn moved_nodes(&self) -> usize {
        self.moved.len()
    }

    /// The camera of frame `frame`.
    pub fn camera(&self, bounds: &Aabb, aspect: f64, frame: usize) -> Camera {
        match self.camera {
            CameraPath::Static => Camera::fit(bounds, aspect, DEFAULT_DIRECTION),
            CameraPath::Orbit => {
                Camera::orbit(bounds, aspect, frame as f64 / ORBIT_FRAMES, ORBIT_DISTANCE)
            }
        }
    }

    /// Moves the chosen nodes to where they are in frame `frame`.
    pub fn animate(&self, graph: &mut SceneGraph, frame: usize) -> Result<(), String> {
        let phase = (frame as f64 / ANIMATE_FRAMES * std::f64::consts::TAU)
            .sin()
            .abs();
        for &(node, rest, direction) in &self.moved {
            let offset = DMat4::from_translation(direction * self.amplitude * phase);
            graph
                .set_matrix(node, offset * rest)
                .map_err(|e| format!("cannot move an animated node: {e}"))?;
        }
        Ok(())
    }
}
