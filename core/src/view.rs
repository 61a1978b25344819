//! The one frame loop: a [`View`] owns a renderer (its target and frames), the active
//! techniques and the GPU scene they draw, and takes a scene graph with its tree each frame.
//! The command line, the C API and the tests draw and pick through it, so a scene reaches the
//! GPU by one road: graph → tree → [`GpuScene`] → techniques → Vulkan.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DVec3, DVec4};

use crate::error::{RenderError, RenderResult};
use crate::frame::Renderer;
use crate::gpu_scene::GpuScene;
use crate::gpu_scene::Transforms;
use crate::graph::{NodeHandle, SceneGraph};
use crate::render::pick::{PickSample, PixelRect};
use crate::render::{Camera, FrameStats, Section};
use crate::technique::{Combination, PluginRegistry, Techniques};
use crate::timings::{self, Phase};
use crate::tree::SceneTree;
use crate::vk::Device;

/// What a pick found under one pixel (or, for a rectangle, the nearest pixel of one part).
#[derive(Clone, Debug, PartialEq)]
pub struct PickHit {
    /// The scene tree instance (the occurrence of a part on one path).
    pub instance: u32,
    /// The geo node drawn.
    pub node: NodeHandle,
    /// The part of its geometry.
    pub part: u32,
    /// The occurrence: graph nodes from the root to `node` (a shared subgraph appears on
    /// several paths; this says which).
    pub path: Vec<NodeHandle>,
    /// The pixel (column, row).
    pub pixel: (u32, u32),
    /// Depth at the pixel (0 near plane, 1 far plane).
    pub depth: f32,
    /// The surface point under the pixel's centre, in world space; on a section cap, the
    /// point where the plane cuts the part (`depth` is then that point's too).
    pub position: DVec3,
}

/// The world position of a pixel's centre at `depth`, seen by `camera` on a `width` × `height`
/// target (the inverse of what the frame does, in f64).
pub fn unproject(
    camera: &Camera,
    (width, height): (u32, u32),
    (x, y): (u32, u32),
    depth: f32,
) -> DVec3 {
    let ndc = DVec4::new(
        (f64::from(x) + 0.5) / f64::from(width) * 2.0 - 1.0,
        (f64::from(y) + 0.5) / f64::from(height) * 2.0 - 1.0,
        f64::from(depth),
        1.0,
    );
    let view = camera.projection.inverse() * ndc;
    let view = view / view.w;
    camera.view.inverse().transform_point3(view.truncate())
}

/// The depth of the world point `point` seen by `camera` (0 near plane, 1 far plane).
fn depth_of(camera: &Camera, point: DVec3) -> f32 {
    let clip = camera.projection * camera.view * point.extend(1.0);
    (clip.z / clip.w) as f32
}

/// `sample` as a pick reports it, with the world point under its pixel's centre. A cap's
/// pixel shows the plane where it cuts the part, so its point and depth move from the far face
/// the cap is painted on to the plane (where a user who clicks a cut face measures from).
fn surface_point(
    sample: PickSample,
    section: &Section,
    camera: &Camera,
    size: (u32, u32),
) -> (PickSample, DVec3) {
    let pixel = (sample.x, sample.y);
    let surface = unproject(camera, size, pixel, sample.depth);
    if !sample.cap {
        return (sample, surface);
    }
    let near = unproject(camera, size, pixel, 0.0);
    match section.cap_entry(near, surface) {
        Some(cut) => (
            PickSample {
                depth: depth_of(camera, cut),
                ..sample
            },
            cut,
        ),
        None => (sample, surface),
    }
}

/// A renderer with its techniques and GPU scene.
pub struct View {
    // Dropped in this order: the scene and the techniques before the renderer whose layouts
    // they use.
    scene: Option<GpuScene>,
    techniques: Techniques,
    renderer: Renderer,
    /// Whether a frame was drawn (the first counts as [`Phase::FirstFrame`]).
    drawn: bool,
}

impl Drop for View {
    fn drop(&mut self) {
        // A frame in flight may still read the GPU scene, which is dropped first.
        let _ = self.renderer.finish();
    }
}

impl View {
    /// A view of `width` × `height` pixels drawing with techniques from `registry`, starting
    /// with the built-in combination ([`Combination::built_in`]; choose another with
    /// [`View::techniques_mut`]).
    pub fn new(
        device: &Arc<Device>,
        registry: Arc<PluginRegistry>,
        width: u32,
        height: u32,
    ) -> RenderResult<Self> {
        let renderer = Renderer::new(device, width, height)?;
        let mut techniques = Techniques::new(
            device,
            registry,
            renderer.pipelines().technique_set_layouts(),
        );
        techniques.select(&Combination::built_in())?;
        Ok(Self {
            scene: None,
            techniques,
            renderer,
            drawn: false,
        })
    }

    /// The renderer (target size, pixels, PNG).
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The renderer, to resize it.
    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// The active techniques.
    pub fn techniques(&self) -> &Techniques {
        &self.techniques
    }

    /// The active techniques, to choose or swap them.
    pub fn techniques_mut(&mut self) -> &mut Techniques {
        &mut self.techniques
    }

    /// The section planes and caps of this view.
    pub fn section(&self) -> &Section {
        self.renderer.section()
    }

    /// Cuts the view with `section`'s planes (every pass, picking included, ignores what they
    /// cut away) and caps cuts through closed parts when its caps are on.
    pub fn set_section(&mut self, section: Section) {
        self.renderer.set_section(section);
    }

    /// The GPU scene last drawn, if any.
    pub fn scene(&self) -> Option<&GpuScene> {
        self.scene.as_ref()
    }

    /// Brings the GPU scene up to date with `tree` (which must be up to date with `graph`):
    /// created on first use, then synced with the changes since this view's last frame (a
    /// tree this view has not read before is uploaded afresh). World matrices of moved
    /// subtrees are computed where the active techniques need them
    /// ([`Techniques::transforms`]).
    pub fn sync(&mut self, graph: &SceneGraph, tree: &mut SceneTree) -> RenderResult<()> {
        let transforms = self.techniques.transforms();
        let renderer = &self.renderer;
        timings::time(Phase::Upload, || match &mut self.scene {
            Some(scene) => scene.sync_after(graph, tree, transforms, &mut || renderer.finish()),
            None => {
                let device = renderer.device();
                self.scene = Some(GpuScene::new(device, graph, tree, transforms)?);
                Ok(())
            }
        })
    }

    /// Draws one frame of `tree` seen by `camera` with the active techniques (syncing the GPU
    /// scene first).
    pub fn render(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        camera: &Camera,
    ) -> RenderResult<FrameStats> {
        self.sync(graph, tree)?;
        self.draw(camera)
    }

    /// Draws one frame of the GPU scene as last synced (see [`View::sync`]).
    pub fn draw(&mut self, camera: &Camera) -> RenderResult<FrameStats> {
        let first = !self.drawn;
        let (scene, techniques, renderer) = self.parts()?;
        let stats = if first {
            timings::time(Phase::FirstFrame, || {
                renderer.render_techniques(scene, techniques, camera)
            })?
        } else {
            renderer.render_techniques(scene, techniques, camera)?
        };
        self.drawn = true;
        Ok(stats)
    }

    /// The GPU scene, the techniques and the renderer, borrowed together for a frame.
    fn parts(&mut self) -> RenderResult<(&mut GpuScene, &mut Techniques, &mut Renderer)> {
        let scene = self
            .scene
            .as_mut()
            .ok_or_else(|| RenderError::InvalidUse("no GPU scene: sync first".into()))?;
        if scene.transforms() == Transforms::Gpu && self.techniques.transforms() == Transforms::Host
        {
            // The host's copies of moved matrices lag behind: only a sync brings them back.
            return Err(RenderError::InvalidUse(
                "the techniques now read world matrices on the host: sync before drawing".into(),
            ));
        }
        Ok((scene, &mut self.techniques, &mut self.renderer))
    }

    /// Picks the pickable parts with visible pixels in `rect`, seen by `camera`: one hit per
    /// occurrence and part (its nearest pixel), nearest first. For one pixel, at most one hit.
    pub fn pick(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        camera: &Camera,
        rect: PixelRect,
    ) -> RenderResult<Vec<PickHit>> {
        self.sync(graph, tree)?;
        let (scene, techniques, renderer) = self.parts()?;
        let samples = renderer.pick_techniques(scene, techniques, camera, rect)?;
        let size = renderer.size();
        let section = renderer.section();
        let mut nearest: HashMap<u32, (PickSample, DVec3)> = HashMap::new();
        for sample in samples {
            let (sample, position) = surface_point(sample, section, camera, size);
            let best = nearest.entry(sample.instance).or_insert((sample, position));
            if sample.depth < best.0.depth {
                *best = (sample, position);
            }
        }
        let mut hits: Vec<PickHit> = nearest
            .into_values()
            .filter_map(|(sample, position)| {
                let instance = tree.instance(sample.instance)?;
                let path = tree.path(instance.tree_node);
                Some(PickHit {
                    instance: sample.instance,
                    node: *path.last()?,
                    part: instance.part,
                    path,
                    pixel: (sample.x, sample.y),
                    depth: sample.depth,
                    position,
                })
            })
            .collect();
        hits.sort_by(|a, b| {
            a.depth
                .total_cmp(&b.depth)
                .then(a.instance.cmp(&b.instance))
        });
        Ok(hits)
    }
}
