//! The one frame loop: a [`View`] owns a renderer (its target and frames) and the active
//! techniques, draws a GPU scene (its own, or one shared with the other views of the same
//! tree through [`SharedScenes`]), and takes a scene graph with its tree each frame.
//! The command line, the C API and the tests draw and pick through it, so a scene reaches the
//! GPU by one road: graph → tree → [`GpuScene`] → techniques → Vulkan.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use glam::{DVec3, DVec4};

use crate::error::{RenderError, RenderResult};
use crate::frame::Renderer;
use crate::gpu_scene::{GpuScene, Transforms, ViewState, ViewedScene};
use crate::graph::{NodeHandle, SceneGraph};
use crate::render::pick::{PickSample, PixelRect};
use crate::render::{Camera, FrameStats, Section};
use crate::technique::{Combination, PluginRegistry, Techniques};
use crate::timings::{self, Phase};
use crate::tree::SceneTree;
use crate::vk::{Device, Shared};

/// What a view's picture covers ([`View::coverage`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Coverage {
    /// Pixels that show a pickable part.
    pub pixels: u64,
    /// Parts (scene tree instances) that show in at least one pixel.
    pub parts: u64,
}

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

/// A GPU scene that views may share.
type SceneCell = Arc<Mutex<GpuScene>>;

/// The scene in `cell`, locked (a frame that panicked left it as far as it got: the next
/// sync brings it up to date).
fn lock(cell: &Mutex<GpuScene>) -> MutexGuard<'_, GpuScene> {
    cell.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The GPU scenes of one scene tree that its views share: one per device and place of world
/// matrices ([`Transforms`]). Keep one beside the tree and hand it to [`View::sync_shared`]
/// with that tree. It holds the scenes weakly: a scene goes with the last view drawing it.
#[derive(Default)]
pub struct SharedScenes(Shared<Mutex<GpuScene>>);

impl SharedScenes {
    /// The live scene on `device` with world matrices kept where `transforms` says.
    fn find(&self, device: &Arc<Device>, transforms: Transforms) -> Option<SceneCell> {
        self.0.find(|cell| {
            let scene = lock(cell);
            Arc::ptr_eq(scene.device(), device) && scene.transforms() == transforms
        })
    }

    /// GPU scenes alive.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether no GPU scene is alive.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A renderer with its techniques and the GPU scene it draws.
pub struct View {
    // Dropped in this order: the scene and the techniques before the renderer whose layouts
    // they use.
    scene: Option<SceneCell>,
    /// What this view keeps of its own of the scene: culling, drawn set, changed slots.
    own: ViewState,
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
            own: ViewState::new(),
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

    /// The GPU scene last drawn, if any (locked while the guard lives: other views of it wait).
    pub fn scene(&self) -> Option<MutexGuard<'_, GpuScene>> {
        self.scene.as_deref().map(lock)
    }

    /// Instances this view drew in its last frame.
    pub fn drawn_count(&self) -> usize {
        self.own.drawn_count()
    }

    /// Triangles of the instances this view drew in its last frame (before a GPU culler's
    /// decisions).
    pub fn drawn_triangles(&self) -> u64 {
        self.own.drawn_triangles()
    }

    /// Brings this view's own GPU scene up to date with `tree` (which must be up to date with
    /// `graph`): created on first use, then synced with the changes since its last sync (a
    /// tree it has not read before is uploaded afresh). World matrices of moved subtrees are
    /// computed where the active techniques need them ([`Techniques::transforms`]).
    pub fn sync(&mut self, graph: &SceneGraph, tree: &mut SceneTree) -> RenderResult<()> {
        self.sync_with(graph, tree, None)
    }

    /// [`View::sync`] with the GPU scene shared by the views of `tree` that keep their scenes
    /// in `scenes` (the one on this view's device whose world matrices are kept where its
    /// techniques need them; made when there is none). Each view keeps only its target, its
    /// culling and its uniforms; the geometry, instances, matrices and materials are on the
    /// GPU once.
    pub fn sync_shared(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        scenes: &mut SharedScenes,
    ) -> RenderResult<()> {
        self.sync_with(graph, tree, Some(scenes))
    }

    fn sync_with(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        scenes: Option<&mut SharedScenes>,
    ) -> RenderResult<()> {
        let transforms = self.techniques.transforms();
        timings::time(Phase::Upload, || {
            let cell = self.choose_scene(graph, tree, transforms, scenes)?;
            // Other views' frames may read a shared scene too: a change waits for them all.
            let shared = Arc::strong_count(&cell) > 1;
            let renderer = &self.renderer;
            let mut settle = || {
                renderer.finish()?;
                if shared {
                    renderer.device().wait_idle()?;
                }
                Ok(())
            };
            let synced = lock(&cell).sync_after(graph, tree, transforms, &mut settle);
            synced
        })
    }

    /// The scene this view syncs: from `scenes` when given (made there when it has none for
    /// this device and `transforms`), else its own (made when it has none, or when the one it
    /// has is shared with other views).
    fn choose_scene(
        &mut self,
        graph: &SceneGraph,
        tree: &mut SceneTree,
        transforms: Transforms,
        mut scenes: Option<&mut SharedScenes>,
    ) -> RenderResult<SceneCell> {
        let device = Arc::clone(self.renderer.device());
        // This view's scene, when no other view draws it.
        let alone = self
            .scene
            .as_ref()
            .filter(|cell| Arc::strong_count(cell) == 1)
            .cloned();
        let found = match scenes.as_deref_mut() {
            Some(scenes) => match scenes.find(&device, transforms) {
                Some(cell) => Some(cell),
                // None keeps world matrices where these techniques need them: a scene of the
                // tree's that only this view draws changes where it keeps them (in the sync).
                None => alone.filter(|cell| scenes.0.holds(cell)),
            },
            None => alone,
        };
        if let (Some(current), Some(found)) = (&self.scene, &found) {
            if Arc::ptr_eq(current, found) {
                return Ok(Arc::clone(found));
            }
        }
        // Leaving a scene: frames in flight may still read it, and it may be the last view.
        self.renderer.finish()?;
        self.scene = None;
        let cell = match found {
            Some(cell) => cell,
            None => {
                let cell = Arc::new(Mutex::new(GpuScene::new(&device, graph, tree, transforms)?));
                if let Some(scenes) = scenes {
                    scenes.0.hold(&cell);
                }
                cell
            }
        };
        self.scene = Some(Arc::clone(&cell));
        Ok(cell)
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
        let cell = self.current_scene()?;
        let mut scene = lock(&cell);
        let mut viewed = caught_up(&self.techniques, &mut scene, &mut self.own)?;
        let (techniques, renderer) = (&mut self.techniques, &mut self.renderer);
        let stats = if first {
            timings::time(Phase::FirstFrame, || {
                renderer.render_techniques(&mut viewed, techniques, camera)
            })?
        } else {
            renderer.render_techniques(&mut viewed, techniques, camera)?
        };
        self.drawn = true;
        Ok(stats)
    }

    /// The GPU scene this view draws: none before its first sync.
    fn current_scene(&self) -> RenderResult<SceneCell> {
        self.scene
            .clone()
            .ok_or_else(|| RenderError::InvalidUse("no GPU scene: sync first".into()))
    }

    /// Picks the pickable parts with visible pixels in `rect`, seen by `camera`, in the GPU
    /// scene as last synced from `tree` (see [`View::sync`]): one hit per occurrence and part
    /// (its nearest pixel), nearest first. For one pixel, at most one hit.
    pub fn pick(
        &mut self,
        tree: &SceneTree,
        camera: &Camera,
        rect: PixelRect,
    ) -> RenderResult<Vec<PickHit>> {
        let samples = self.pick_samples(camera, rect)?;
        let size = self.renderer.size();
        let section = self.renderer.section();
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

    /// What the whole view shows of the GPU scene as last synced (see [`View::sync`]), seen by
    /// `camera` through the active techniques' pick pass: the pixels covered by pickable parts,
    /// and how many parts cover one. The figure triangles per covered pixel is measured
    /// against (`cadr bench`).
    pub fn coverage(&mut self, camera: &Camera) -> RenderResult<Coverage> {
        let (width, height) = self.renderer.size();
        let rect = PixelRect {
            x: 0,
            y: 0,
            width,
            height,
        };
        let samples = self.pick_samples(camera, rect)?;
        let mut parts: Vec<u32> = samples.iter().map(|sample| sample.instance).collect();
        parts.sort_unstable();
        parts.dedup();
        Ok(Coverage {
            pixels: samples.len() as u64,
            parts: parts.len() as u64,
        })
    }

    /// The pick pass's pixels in `rect`, seen by `camera`: one sample per pixel that shows a
    /// pickable part.
    fn pick_samples(&mut self, camera: &Camera, rect: PixelRect) -> RenderResult<Vec<PickSample>> {
        let cell = self.current_scene()?;
        let mut scene = lock(&cell);
        let mut viewed = caught_up(&self.techniques, &mut scene, &mut self.own)?;
        self.renderer
            .pick_techniques(&mut viewed, &mut self.techniques, camera, rect)
    }
}

/// `scene` with `own` (a view's state) caught up with it, ready for a frame of `techniques`.
fn caught_up<'a>(
    techniques: &Techniques,
    scene: &'a mut GpuScene,
    own: &'a mut ViewState,
) -> RenderResult<ViewedScene<'a>> {
    if scene.transforms() == Transforms::Gpu && techniques.transforms() == Transforms::Host {
        // The host's copies of moved matrices lag behind: only a sync brings them back.
        return Err(RenderError::InvalidUse(
            "the techniques now read world matrices on the host: sync before drawing".into(),
        ));
    }
    scene.catch_up(own);
    Ok(ViewedScene { scene, own })
}
