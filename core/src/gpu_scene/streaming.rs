//! Geometry streaming under a memory budget: when the full detail of a scene's geometries
//! needs more device memory than the budget (`CADR_MEMORY_BUDGET`, see `memory_budget.rs`),
//! each geometry goes on the GPU in a coarse form (for each part the finest cut of its
//! level-of-detail DAG within a share of its triangles, or of its stand-ins where the DAG
//! cannot cut that far, with its own compact vertices and the part's own edges: an eighth,
//! less where the scene is so large against the budget that the coarse forms would take more
//! than half of it, down to each part's coarsest cut or stand-in; see [`coarse_share`] and
//! [`CoarseForm::of`]), and only the geometries the frames ask for are held at full detail, as
//! many as the budget allows.
//!
//! With a CPU culler the host asks for every geometry of the instances it draws (such a culler
//! has no level-of-detail threshold: full detail is what it draws). Otherwise the asking is
//! done on the GPU: the part boxes of a streamed geometry's instances carry its coarse form's
//! error ([`abi::CadrBox::coarse_error`]) and the geometry's request bit
//! ([`abi::CadrBox::request_bit`]), and a GPU culler that draws such an instance where that
//! error projects over its threshold sets the bit in the request buffer
//! ([`abi::CadrSceneStreaming`]). Before each frame the scene reads the bits, asks a preparing
//! thread ([`Preparer`]) for the full detail of the geometries asked for (at most
//! [`UPLOAD_BYTES_PER_FRAME`] a frame) and writes what it has prepared; where the budget is
//! spent, it puts back in their coarse form those asked for least recently (never one asked for
//! in the last [`KEEP_FRAMES`] frames, so that a view that needs more than the budget does not
//! swap geometries back and forth). A geometry is never missing: until its full detail arrives
//! it is drawn coarse.
//!
//! The bits are read while a later frame may be setting them: a request read too early is
//! simply asked for again by the next frame.

use std::panic::AssertUnwindSafe;
use std::sync::{mpsc, Arc, Mutex};

use super::clusters::GeometryClusters;
use crate::error::RenderResult;
use crate::graph::{GeometryHandle, GeometrySource};
use crate::scene::{Geometry, Part, Vertex, VertexAttributes};
use crate::vk::raw as vk;
use crate::vk::{Buffer, Device};
use cadr_plugin_abi as abi;

/// Bytes of full-detail geometry asked for, and written, in one frame at most (a geometry larger
/// than this still comes, alone in its frame).
pub const UPLOAD_BYTES_PER_FRAME: u64 = 32 << 20;

/// Frames a geometry stays at full detail after it was last asked for, whatever the budget.
pub const KEEP_FRAMES: u64 = 8;

/// A coarse form of a geometry: what the GPU holds of it while its full detail is not there.
pub(super) struct CoarseForm {
    /// A coarse cut of every part ([`coarse_share`]), parts in the same order, vertices
    /// compacted. Once placed on the GPU (where it stays), streaming keeps the form without
    /// its arrays ([`CoarseForm::placed`]) and makes them again from the full detail where it
    /// must place it anew (the arenas laid out again).
    pub(super) geometry: Geometry,
    /// Whether `geometry` holds the form's arrays.
    has_arrays: bool,
    /// Per part: the object-space error of its coarse form against its full detail.
    pub(super) errors: Vec<f32>,
    /// Per part: its full detail's bounds and shape, which the coarse form's instances keep
    /// (so that they are culled as the full detail would be).
    pub(super) full_parts: Vec<PartBounds>,
}

/// A part's bounding sphere, box and shape flags, as its part entry in the GPU scene holds them.
#[derive(Clone, Copy, Debug)]
pub(super) struct PartBounds {
    /// Bounding sphere (centre, radius) in object space.
    pub(super) sphere: [f32; 4],
    /// The smallest box along the object's axes around its triangles' vertices.
    pub(super) bounds: abi::CadrBox,
    /// Its shape as instance flags (`CADR_INSTANCE_CLOSED`, `CADR_INSTANCE_INSIDE_OUT`,
    /// `CADR_INSTANCE_CURVED`).
    pub(super) shape: u32,
}

/// Whether a coarse form is worth streaming: at most this fraction of the full form's
/// triangles (else the geometry stays at full detail, counted against the budget).
const COARSE_AT_MOST: f64 = 0.5;

/// The largest share of a part's triangles its coarse form aims at: the finest cut of its DAG
/// within it. Coarser would hold less memory but show more while the full detail is on its
/// way.
const COARSE_SHARE: f64 = 0.125;

/// The most of the budget the coarse forms aim to take, as a fraction of it (see
/// [`coarse_share`]).
const COARSE_BUDGET_FRACTION: f64 = 0.5;

/// Device bytes of a geometry's full detail (vertices, its levels' indices, clusters and
/// groups) per byte of the geometry in host memory, about: 1.55 for gen:fine. The coarse forms'
/// share is set from the scene's host bytes, known before any geometry is read (see
/// [`coarse_share`]).
const FULL_BYTES_PER_HOST_BYTE: f64 = 1.5;

/// The share of each part's triangles the coarse forms of a scene with `scene_bytes` of
/// geometry in host memory aim at under a `budget` of full-detail device bytes:
/// [`COARSE_SHARE`], or less where the forms would then take more than
/// [`COARSE_BUDGET_FRACTION`] of the budget (their bytes follow their triangles, roughly), so
/// that what the GPU holds past the budget stays a fraction of it rather than growing with the
/// scene. A share too small for a part gives its coarsest cut or stand-in (a part never
/// vanishes), so a scene very large against its budget still holds those whole.
pub(super) fn coarse_share(budget: u64, scene_bytes: u64) -> f64 {
    let full_bytes = FULL_BYTES_PER_HOST_BYTE * scene_bytes.max(1) as f64;
    (COARSE_BUDGET_FRACTION * budget as f64 / full_bytes).min(COARSE_SHARE)
}

/// The share of a coarse form's error its edges may stray: the culler draws a part's edges at
/// the coarsest level within half its threshold (a line a pixel off has left its pixels, where a
/// surface a pixel off has only moved its outline), so a coarse form takes its part's edges
/// within half its own error.
const EDGE_ERROR_SHARE: f32 = 0.5;

/// The full detail a coarse form is made from: the geometry, its edges (a line list: its own, or
/// those found by crease angle) with its parts' ranges in them, and its clusters.
pub(super) struct FullDetail<'a> {
    pub(super) geometry: &'a Geometry,
    pub(super) wire: &'a [u32],
    pub(super) parts: &'a [Part],
    pub(super) clusters: &'a GeometryClusters,
}

/// A coarse form's arrays as they are made: the full detail's vertices it uses, renumbered in
/// the order first used.
#[derive(Default)]
struct FormArrays {
    remap: Vec<u32>,
    vertices: Vec<Vertex>,
    attributes: Vec<VertexAttributes>,
    indices: Vec<u32>,
    wire: Vec<u32>,
}

impl FormArrays {
    /// The form's number for the full detail's vertex `vertex`, taking it in where new; `None`
    /// for a vertex the full detail does not have.
    fn vertex(&mut self, full: &Geometry, vertex: u32) -> Option<u32> {
        let slot = self.remap.get_mut(vertex as usize)?;
        if *slot == u32::MAX {
            *slot = self.vertices.len() as u32;
            self.vertices.push(*full.vertices.get(vertex as usize)?);
            if let Some(a) = full.attributes.get(vertex as usize) {
                self.attributes.push(*a);
            }
        }
        Some(*slot)
    }
}

impl CoarseForm {
    /// The coarse form of `full`, whose parts' entries are `full_parts`, each part cut within
    /// `share` of its triangles ([`coarse_share`]) and drawn with its own edges at about the
    /// cut's error; `None` where it would not save enough ([`COARSE_AT_MOST`]).
    pub(super) fn of(
        full: &FullDetail<'_>,
        full_parts: Vec<PartBounds>,
        share: f64,
    ) -> Option<Self> {
        let (geometry, clusters) = (full.geometry, full.clusters);
        let mut form = FormArrays {
            remap: vec![u32::MAX; geometry.vertices.len()],
            ..FormArrays::default()
        };
        let mut parts = Vec::with_capacity(geometry.parts.len());
        let mut errors = Vec::with_capacity(geometry.parts.len());
        for part in 0..clusters.part_ranges.len() {
            let (own, levels) = clusters.part_records(part)?;
            let (chosen, error) = coarse_triangles(clusters, own, share);
            let first_index = form.indices.len() as u32;
            for cluster in chosen {
                let start = cluster.first_index as usize;
                for i in start..start + cluster.index_count as usize {
                    let vertex = form.vertex(geometry, *clusters.index(i)?)?;
                    form.indices.push(vertex);
                }
            }
            let first_wire_index = form.wire.len() as u32;
            for i in coarse_edges(full, part, levels, error)? {
                let vertex = form.vertex(geometry, *clusters.wire_index(full.wire, i)?)?;
                form.wire.push(vertex);
            }
            parts.push(Part {
                first_index,
                index_count: form.indices.len() as u32 - first_index,
                first_wire_index,
                wire_index_count: form.wire.len() as u32 - first_wire_index,
            });
            errors.push(error);
        }
        let whole = geometry.indices.len().max(1) as f64;
        if parts.len() != full_parts.len() || form.indices.len() as f64 > COARSE_AT_MOST * whole {
            return None;
        }
        Some(Self {
            geometry: Geometry {
                name: geometry.name.clone(),
                vertices: form.vertices,
                indices: form.indices,
                wire_indices: form.wire,
                parts,
                attributes: form.attributes,
            },
            has_arrays: true,
            errors,
            full_parts,
        })
    }

    /// The form as streaming keeps it once it is on the GPU: its errors and the full detail's
    /// bounds, without its arrays (host memory: about an eighth of the scene's geometry).
    fn placed(&self) -> Self {
        Self {
            geometry: Geometry {
                name: self.geometry.name.clone(),
                parts: self.geometry.parts.clone(),
                ..Geometry::default()
            },
            has_arrays: false,
            errors: self.errors.clone(),
            full_parts: self.full_parts.clone(),
        }
    }
}

/// The error of a cluster's own triangles against the part's (0 for an original cluster).
fn own_error(clusters: &GeometryClusters, cluster: &abi::CadrCluster) -> f32 {
    if cluster.refined == abi::CADR_CLUSTER_ORIGINAL {
        return 0.0;
    }
    (clusters.groups.get(cluster.refined as usize)).map_or(f32::MAX, |g| g.error)
}

/// Whether `cluster` belongs to the part's cut at object-space error `error`: the rule the
/// cullers apply to projected errors (its group too coarse, its own triangles fine enough),
/// which tiles the part without cracks as errors only grow toward the coarse levels. Stand-ins
/// are left out: they stand for the whole part, not a piece of it.
fn in_cut(clusters: &GeometryClusters, cluster: &abi::CadrCluster, error: f32) -> bool {
    let Some(group) = clusters.groups.get(cluster.group as usize) else {
        return false;
    };
    group.depth != abi::CADR_CLUSTER_PROXY_DEPTH
        && group.error > error
        && own_error(clusters, cluster) <= error
}

/// Whether `cluster` is one of its part's stand-ins (whole-part replacements, see
/// `stand_ins.rs`).
fn is_stand_in(clusters: &GeometryClusters, cluster: &abi::CadrCluster) -> bool {
    (clusters.groups.get(cluster.group as usize))
        .is_some_and(|g| g.depth == abi::CADR_CLUSTER_PROXY_DEPTH)
}

/// The triangles of a part's coarse form, from its clusters `part` (stand-ins last), and their
/// error against the part: the finest cut of its DAG whose triangles are at most `share` of the
/// part's; where the DAG cannot simplify that far (a faceted part, whose creases it keeps), the
/// finest of its stand-ins within the share, or its coarsest stand-in where that still has
/// fewer triangles than the DAG's coarsest cut; else that cut.
fn coarse_triangles<'c>(
    clusters: &GeometryClusters,
    part: &'c [abi::CadrCluster],
    share: f64,
) -> (Vec<&'c abi::CadrCluster>, f32) {
    let triangles = |c: &abi::CadrCluster| u64::from(c.index_count / 3);
    let full: u64 = (part.iter())
        .filter(|c| in_cut(clusters, c, 0.0))
        .map(triangles)
        .sum();
    let wanted = (full as f64 * share).ceil() as u64;
    let (threshold, error) = coarse_cut(clusters, part, wanted);
    let cut: Vec<_> = part
        .iter()
        .filter(|c| in_cut(clusters, c, threshold))
        .collect();
    let cut_triangles: u64 = cut.iter().map(|c| triangles(c)).sum();
    if cut_triangles <= wanted {
        return (cut, error);
    }
    let stand_ins = || part.iter().filter(|c| is_stand_in(clusters, c));
    let stand_in = (stand_ins().find(|c| triangles(c) <= wanted))
        .or_else(|| stand_ins().next_back())
        .filter(|c| triangles(c) < cut_triangles);
    match stand_in.and_then(|s| Some((s, clusters.groups.get(s.group as usize)?.error))) {
        Some((stand_in, stand_in_error)) => (vec![stand_in], stand_in_error.max(error)),
        None => (cut, error),
    }
}

/// The part's coarse cut: the finest whose triangles are at most `wanted` (or its coarsest);
/// returns the cut's error threshold and the largest error of its clusters.
fn coarse_cut(clusters: &GeometryClusters, part: &[abi::CadrCluster], wanted: u64) -> (f32, f32) {
    let triangles_at = |error: f32| -> u64 {
        (part.iter())
            .filter(|c| in_cut(clusters, c, error))
            .map(|c| u64::from(c.index_count / 3))
            .sum()
    };
    let mut errors: Vec<f32> = (part.iter())
        .map(|c| own_error(clusters, c))
        .filter(|e| *e < f32::MAX)
        .collect();
    errors.sort_by(f32::total_cmp);
    errors.dedup();
    // Triangles only fall as the threshold grows: the first threshold within the share.
    let at = errors.partition_point(|&e| triangles_at(e) > wanted);
    let threshold = errors.get(at).or(errors.last()).copied().unwrap_or(0.0);
    let error = (part.iter())
        .filter(|c| in_cut(clusters, c, threshold))
        .map(|c| own_error(clusters, c))
        .fold(0.0, f32::max);
    (threshold, error)
}

/// The wire indices (as `full` lays them out: its edges, then their levels) of part `part`'s
/// edges, whose levels are `levels`, for its coarse form of error `error`: the coarsest level
/// within [`EDGE_ERROR_SHARE`] of it, else the edges whole. The full detail's own edges, not
/// edges found again on the coarse triangles, which would show the creases a simplification
/// makes across smooth faces. `None` where the part is not there.
fn coarse_edges(
    full: &FullDetail<'_>,
    part: usize,
    levels: &[abi::CadrCluster],
    error: f32,
) -> Option<std::ops::Range<usize>> {
    let within = levels.iter().rev().find(|level| {
        (full.clusters.groups.get(level.group as usize))
            .is_some_and(|g| g.error <= EDGE_ERROR_SHARE * error)
    });
    let (start, count) = match within {
        Some(level) => (level.first_index, level.index_count),
        None => {
            let whole = full.parts.get(part)?;
            (whole.first_wire_index, whole.wire_index_count)
        }
    };
    Some(start as usize..start as usize + count as usize)
}

/// What streaming knows of one geometry slot.
struct Residency {
    /// The geometry this is about: a slot given to another geometry starts over.
    handle: GeometryHandle,
    /// Its coarse form; `None` where the geometry is always at full detail.
    coarse: Option<Arc<CoarseForm>>,
    /// Device bytes of its full detail.
    full_bytes: u64,
    /// Whether its full detail is on the GPU.
    full: bool,
    /// Whether its full detail is being prepared (its bytes already counted against the
    /// budget).
    loading: bool,
    /// The preparation it waits for (see [`Streaming::start_loading`]).
    ticket: u64,
    /// The last frame that asked for it.
    last_wanted: u64,
    /// The first frame that may bring its full detail again after it found no room or could
    /// not be read.
    retry_after: u64,
    /// Reads of its page that failed in a row.
    failed_reads: u32,
}

/// When a geometry whose full detail did not come is tried again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LoadRetry {
    /// After [`KEEP_FRAMES`] frames (it found no room, or its page could not be read).
    Later,
    /// Never (preparing it panicked): it stays coarse.
    Never,
}

/// Why a preparation gave no full detail.
#[derive(Debug)]
pub(super) enum PrepareFailure {
    /// The preparation panicked (a bug).
    Panicked,
    /// The geometry could not be read from the scene graph's page file (the message says why).
    Unreadable(String),
}

/// Reads of a geometry's page that may fail in a row before it stays coarse.
pub(super) const READ_ATTEMPTS: u32 = 3;

/// The streaming state of a GPU scene: the budget, each slot's residency and the requests.
pub(super) struct Streaming {
    budget: u64,
    /// The share of each part's triangles its coarse form aims at ([`coarse_share`]), decided
    /// when the scene starts streaming.
    coarse_share: f64,
    slots: Vec<Option<Residency>>,
    /// One bit per geometry slot, set by the GPU cullers, read and cleared by the host.
    requests: Buffer,
    request_words: u32,
    /// The geometry slots asked for on the host: those a CPU culler left visible.
    host_wanted: Vec<u32>,
    /// Frames seen (each [`Streaming::take_requests`] is one).
    frame: u64,
    /// Preparations asked for, counted: each one's ticket.
    tickets: u64,
    /// Full-detail bytes on the GPU, of streamed geometries and of those always at full detail.
    full_bytes: u64,
    /// Full-detail bytes of every geometry, on the GPU or not.
    total_bytes: u64,
    /// Bytes brought to the GPU by streaming since the scene was made.
    streamed_bytes: u64,
    /// Reads of geometries from the scene graph's page file that failed.
    failed_reads: u64,
}

/// What a streaming scene holds and has done (see [`super::GpuScene::streaming`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamingReport {
    /// The most full-detail geometry bytes the GPU may hold (`CADR_MEMORY_BUDGET`).
    pub budget: u64,
    /// Full-detail geometry bytes on the GPU now (coarse forms not counted).
    pub full_bytes: u64,
    /// Full-detail bytes of every geometry of the scene.
    pub total_full_bytes: u64,
    /// Bytes brought to the GPU by streaming since the scene was made.
    pub streamed_bytes: u64,
    /// Frames whose requests were read.
    pub frames: u64,
    /// Reads of full detail from the scene graph's page file that failed (each logged; the
    /// geometry stays coarse and is read again later, up to 3 times in a row).
    pub failed_reads: u64,
}

/// What a frame's requests decided: the slots to bring to full detail and those to put back
/// in their coarse form.
#[derive(Debug, Default)]
pub(super) struct StreamingPlan {
    pub(super) load: Vec<u32>,
    pub(super) unload: Vec<u32>,
}

impl Streaming {
    /// Streaming under `budget` bytes of full-detail geometry, the coarse forms cut within
    /// `coarse_share` of their parts' triangles ([`coarse_share`]).
    pub(super) fn new(device: &Arc<Device>, budget: u64, coarse_share: f64) -> RenderResult<Self> {
        Ok(Self {
            budget,
            coarse_share,
            slots: Vec::new(),
            requests: request_buffer(device, 1)?,
            request_words: 1,
            host_wanted: Vec::new(),
            frame: 0,
            tickets: 0,
            full_bytes: 0,
            total_bytes: 0,
            streamed_bytes: 0,
            failed_reads: 0,
        })
    }

    /// The coarse form slot `slot` (holding `handle`) goes on the GPU in, where it is not at full
    /// detail; `None` to place it whole. A geometry new to the slot starts coarse, unless it
    /// has no coarse form worth the name; `coarse_of` gives its full-detail bytes and its
    /// coarse form.
    pub(super) fn form_to_place(
        &mut self,
        slot: u32,
        handle: GeometryHandle,
        coarse_of: impl FnOnce() -> (u64, Option<CoarseForm>),
    ) -> Option<Arc<CoarseForm>> {
        let index = slot as usize;
        if self.slots.len() <= index {
            self.slots.resize_with(index + 1, || None);
        }
        let known = self.slots[index]
            .as_ref()
            .is_some_and(|r| r.handle == handle);
        if known {
            self.refill(index, coarse_of);
        } else {
            self.forget(slot);
            let (full_bytes, coarse) = coarse_of();
            let coarse = coarse.map(Arc::new);
            let full = coarse.is_none();
            self.total_bytes += full_bytes;
            if full {
                self.full_bytes += full_bytes;
            }
            self.slots[index] = Some(Residency {
                handle,
                coarse,
                full_bytes,
                full,
                loading: false,
                ticket: 0,
                last_wanted: 0,
                retry_after: 0,
                failed_reads: 0,
            });
        }
        let residency = self.slots[index].as_ref()?;
        (!residency.full)
            .then(|| residency.coarse.clone())
            .flatten()
    }

    /// Gives slot `index`'s coarse form its arrays again (made by `coarse_of`) where it goes
    /// on the GPU in it and streaming kept it without them.
    fn refill(&mut self, index: usize, coarse_of: impl FnOnce() -> (u64, Option<CoarseForm>)) {
        let Some(residency) = self.slots[index].as_mut() else {
            return;
        };
        let without_arrays = residency.coarse.as_ref().is_some_and(|c| !c.has_arrays);
        if !residency.full && without_arrays {
            if let (_, Some(form)) = coarse_of() {
                residency.coarse = Some(Arc::new(form));
            }
        }
    }

    /// Slot `slot`'s coarse form is on the GPU: streaming keeps it without its arrays.
    pub(super) fn placed(&mut self, slot: u32) {
        let Some(residency) = self.slots.get_mut(slot as usize).and_then(Option::as_mut) else {
            return;
        };
        if let Some(form) = residency.coarse.as_mut().filter(|c| c.has_arrays) {
            *form = Arc::new(form.placed());
        }
    }

    /// Where slot `slot` is known to hold `handle`: the coarse form it goes on the GPU in, as
    /// [`Streaming::form_to_place`] would say; `None` where it is not known, or where that
    /// form must be made again (kept without its arrays).
    pub(super) fn known_form(
        &self,
        slot: u32,
        handle: GeometryHandle,
    ) -> Option<Option<Arc<CoarseForm>>> {
        let residency = self.slots.get(slot as usize)?.as_ref()?;
        let form = (!residency.full)
            .then(|| residency.coarse.clone())
            .flatten();
        if form.as_ref().is_some_and(|f| !f.has_arrays) {
            return None;
        }
        (residency.handle == handle).then_some(form)
    }

    /// Whether slot `slot` is drawn in its coarse form (its full detail not on the GPU).
    pub(super) fn is_coarse(&self, slot: u32) -> bool {
        (self.slots.get(slot as usize).and_then(Option::as_ref))
            .is_some_and(|r| !r.full && r.coarse.is_some())
    }

    /// The coarse form of slot `slot`'s geometry, whichever form the GPU holds.
    pub(super) fn coarse_form_of(&self, slot: u32) -> Option<Arc<CoarseForm>> {
        self.slots.get(slot as usize)?.as_ref()?.coarse.clone()
    }

    /// Forgets slot `slot` (its geometry is gone or replaced).
    pub(super) fn forget(&mut self, slot: u32) {
        if let Some(residency) = self.slots.get_mut(slot as usize).and_then(Option::take) {
            self.total_bytes -= residency.full_bytes;
            if residency.full || residency.loading {
                self.full_bytes -= residency.full_bytes;
            }
        }
    }

    /// Puts slot `slot` back in its coarse form (its full detail's bytes freed).
    pub(super) fn set_coarse(&mut self, slot: u32) {
        let Some(residency) = self.slots.get_mut(slot as usize).and_then(Option::as_mut) else {
            return;
        };
        if residency.full && residency.coarse.is_some() {
            residency.full = false;
            self.full_bytes -= residency.full_bytes;
        }
    }

    /// Slot `slot`'s full detail is being prepared: its bytes count against the budget. Returns
    /// the preparation's ticket, which its result must show (a geometry replaced meanwhile
    /// keeps its handle, so the handle cannot tell an old preparation from a new one); `None`
    /// where the slot does not wait for one.
    pub(super) fn start_loading(&mut self, slot: u32) -> Option<u64> {
        let residency = self.slots.get_mut(slot as usize)?.as_mut()?;
        if residency.full || residency.loading || residency.coarse.is_none() {
            return None;
        }
        self.tickets += 1;
        residency.loading = true;
        residency.ticket = self.tickets;
        self.full_bytes += residency.full_bytes;
        Some(self.tickets)
    }

    /// Device bytes of slot `slot`'s full detail (0 for a slot it does not know).
    pub(super) fn full_bytes_of(&self, slot: u32) -> u64 {
        (self.slots.get(slot as usize))
            .and_then(Option::as_ref)
            .map_or(0, |r| r.full_bytes)
    }

    /// Whether slot `slot` still waits for the preparation of `ticket`.
    pub(super) fn is_loading(&self, slot: u32, ticket: u64) -> bool {
        (self.slots.get(slot as usize))
            .and_then(Option::as_ref)
            .is_some_and(|r| r.loading && r.ticket == ticket)
    }

    /// Slot `slot`'s full detail is on the GPU.
    pub(super) fn loaded(&mut self, slot: u32) {
        if let Some(residency) = self.slots.get_mut(slot as usize).and_then(Option::as_mut) {
            if residency.loading {
                residency.loading = false;
                residency.full = true;
                residency.failed_reads = 0;
            }
        }
    }

    /// Asks, until asked otherwise, for the full detail of the geometry slots `slots`: what a
    /// CPU culler (which draws full detail) leaves visible.
    pub(super) fn ask_for(&mut self, slots: Vec<u32>) {
        self.host_wanted = slots;
    }

    /// Forgets every preparation asked for (the preparing thread goes with the arenas it
    /// served): those geometries stay coarse until asked for again.
    pub(super) fn cancel_loading(&mut self) {
        for residency in self.slots.iter_mut().flatten() {
            if residency.loading {
                residency.loading = false;
                self.full_bytes -= residency.full_bytes;
            }
        }
    }

    /// Counts `bytes` brought to the GPU by streaming.
    pub(super) fn count_streamed(&mut self, bytes: u64) {
        self.streamed_bytes += bytes;
    }

    /// Slot `slot`'s full detail did not come: its bytes are freed, and it is tried again
    /// as `retry` says.
    pub(super) fn load_failed(&mut self, slot: u32, retry: LoadRetry) {
        let frame = self.frame;
        if let Some(residency) = self.slots.get_mut(slot as usize).and_then(Option::as_mut) {
            if residency.loading {
                residency.loading = false;
                self.full_bytes -= residency.full_bytes;
            }
            residency.retry_after = match retry {
                LoadRetry::Later => frame + KEEP_FRAMES,
                LoadRetry::Never => u64::MAX,
            };
        }
    }

    /// Slot `slot`'s geometry could not be read (`message` says why): it stays coarse, and is
    /// tried again later, up to [`READ_ATTEMPTS`] times in a row. Each failure is logged.
    pub(super) fn read_failed(&mut self, slot: u32, message: &str) {
        self.failed_reads += 1;
        let Some(residency) = self.slots.get_mut(slot as usize).and_then(Option::as_mut) else {
            return;
        };
        residency.failed_reads += 1;
        let attempts = residency.failed_reads;
        if attempts < READ_ATTEMPTS {
            log::warn!("{message}; it stays coarse and is read again in {KEEP_FRAMES} frames");
            self.load_failed(slot, LoadRetry::Later);
        } else {
            log::error!("{message}; it failed {attempts} times and stays coarse");
            self.load_failed(slot, LoadRetry::Never);
        }
    }

    /// Makes the request buffer hold a bit for each of `slots` geometry slots (a new buffer
    /// clears every request); returns whether it was replaced.
    pub(super) fn reserve_requests(
        &mut self,
        device: &Arc<Device>,
        slots: usize,
    ) -> RenderResult<bool> {
        let words = slots.div_ceil(32).max(1) as u32;
        if words <= self.request_words {
            return Ok(false);
        }
        self.requests = request_buffer(device, words)?;
        self.request_words = words;
        Ok(true)
    }

    /// Reads and clears the requests, a frame passing, and decides which geometries come to full
    /// detail and which go back to their coarse form.
    pub(super) fn take_requests(&mut self) -> RenderResult<StreamingPlan> {
        self.frame += 1;
        let frame = self.frame;
        // The GPU's requests (an allocation only where some bit is set), then the host's.
        let mut wanted = Vec::new();
        for (word_index, word) in self.requests.mapped()?.chunks_exact(4).enumerate() {
            let mut word = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
            while word != 0 {
                wanted.push(word_index as u32 * 32 + word.trailing_zeros());
                word &= word - 1;
            }
        }
        if !wanted.is_empty() {
            let zeros = vec![0; self.request_words as usize * 4];
            self.requests.write(0, &zeros)?;
        }
        let mut loads_wanted = false;
        for &slot in wanted.iter().chain(&self.host_wanted) {
            if let Some(r) = self.slots.get_mut(slot as usize).and_then(Option::as_mut) {
                r.last_wanted = frame;
                loads_wanted |=
                    !r.full && !r.loading && r.coarse.is_some() && r.retry_after <= frame;
            }
        }
        if !loads_wanted {
            return Ok(StreamingPlan::default());
        }
        wanted.extend_from_slice(&self.host_wanted);
        wanted.sort_unstable();
        wanted.dedup();
        Ok(self.plan(&wanted))
    }

    /// The loads the wanted slots need and the unloads that make room for them.
    fn plan(&self, wanted: &[u32]) -> StreamingPlan {
        let mut plan = StreamingPlan::default();
        let mut full_bytes = self.full_bytes;
        let mut uploading = 0u64;
        // Coarse candidates for room, least recently wanted first.
        let mut evictable: Vec<(u64, u32, u64)> = (self.slots.iter().enumerate())
            .filter_map(|(slot, r)| {
                let r = r.as_ref()?;
                let old = r.last_wanted + KEEP_FRAMES < self.frame;
                (r.full && !r.loading && r.coarse.is_some() && old).then_some((
                    r.last_wanted,
                    slot as u32,
                    r.full_bytes,
                ))
            })
            .collect();
        evictable.sort_unstable();
        let mut evictable = evictable.into_iter();
        for &slot in wanted {
            let Some(r) = self.slots.get(slot as usize).and_then(Option::as_ref) else {
                continue;
            };
            if r.full || r.loading || r.coarse.is_none() || r.retry_after > self.frame {
                continue;
            }
            // One larger than the budget never comes; one past this frame's uploads, or past
            // the room old geometries leave, may let a smaller one through.
            let too_much_now = uploading > 0 && uploading + r.full_bytes > UPLOAD_BYTES_PER_FRAME;
            if r.full_bytes > self.budget || too_much_now {
                continue;
            }
            while full_bytes + r.full_bytes > self.budget {
                let Some((_, unload, bytes)) = evictable.next() else {
                    break;
                };
                plan.unload.push(unload);
                full_bytes -= bytes;
            }
            if full_bytes + r.full_bytes > self.budget {
                continue;
            }
            full_bytes += r.full_bytes;
            uploading += r.full_bytes;
            plan.load.push(slot);
        }
        plan
    }

    /// The request buffer and its words, for the scene view's extension.
    pub(super) fn requests(&self) -> (&Buffer, u32) {
        (&self.requests, self.request_words)
    }

    /// What streaming holds and has done.
    pub(super) fn report(&self) -> StreamingReport {
        StreamingReport {
            budget: self.budget,
            full_bytes: self.full_bytes,
            total_full_bytes: self.total_bytes,
            streamed_bytes: self.streamed_bytes,
            frames: self.frame,
            failed_reads: self.failed_reads,
        }
    }

    /// The share of each part's triangles its coarse form aims at ([`coarse_share`]).
    pub(super) fn coarse_share(&self) -> f64 {
        self.coarse_share
    }

    /// The budget of full-detail bytes.
    pub(super) fn budget(&self) -> u64 {
        self.budget
    }
}

/// What the preparing thread is asked: a geometry slot, the preparation's ticket (see
/// [`Streaming::start_loading`]), and where to read the slot's geometry.
type PrepareJob = (u32, u64, GeometrySource);

/// What the preparing thread answers: the slot, the ticket, and the full detail prepared or
/// why there is none.
type Prepared<R> = (u32, u64, Result<R, PrepareFailure>);

/// How the preparing thread reads (from the scene graph's page file, where the geometry is
/// there) and prepares one geometry; fails where it cannot be read.
type Prepare<R> = fn(GeometrySource) -> Result<R, String>;

/// A thread that reads geometries (from the scene graph's page file) and prepares their full
/// detail (edges, clusters: the slow part, seconds for millions of triangles) off the frame's
/// thread, in the order asked; each frame takes what is ready. A preparation that panics or
/// cannot read its geometry says so (the geometry stays coarse).
pub(super) struct Preparer<R: Send + 'static> {
    jobs: Option<mpsc::Sender<PrepareJob>>,
    /// Behind a lock only so that the scene can be shared between threads (a receiver cannot).
    done: Mutex<mpsc::Receiver<Prepared<R>>>,
    thread: Option<std::thread::JoinHandle<()>>,
    /// The preparation, which the asking thread runs itself where no thread could be made.
    prepare: Prepare<R>,
    /// What the asking thread prepared itself, not yet taken.
    ready: Vec<Prepared<R>>,
}

/// Runs `prepare`, a panic turned into [`PrepareFailure::Panicked`].
fn prepared<R>(prepare: Prepare<R>, source: GeometrySource) -> Result<R, PrepareFailure> {
    match std::panic::catch_unwind(AssertUnwindSafe(|| prepare(source))) {
        Ok(Ok(prepared)) => Ok(prepared),
        Ok(Err(message)) => Err(PrepareFailure::Unreadable(message)),
        Err(_) => Err(PrepareFailure::Panicked),
    }
}

impl<R: Send + 'static> Preparer<R> {
    /// A preparing thread running `prepare`.
    pub(super) fn new(prepare: Prepare<R>) -> Self {
        let (jobs, asked) = mpsc::channel::<PrepareJob>();
        let (finished, done) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("cadr streaming".into())
            .spawn(move || {
                for (slot, ticket, source) in asked {
                    let result = prepared(prepare, source);
                    if finished.send((slot, ticket, result)).is_err() {
                        break;
                    }
                }
            })
            .ok();
        Self {
            jobs: Some(jobs),
            done: Mutex::new(done),
            thread,
            prepare,
            ready: Vec::new(),
        }
    }

    /// Asks for slot `slot`'s full detail (read from `source`), under `ticket`; false where
    /// the thread has gone (it never should: it catches panics), so that the slot does not
    /// wait for nothing.
    pub(super) fn ask(&mut self, slot: u32, ticket: u64, source: GeometrySource) -> bool {
        if self.thread.is_none() {
            self.ready
                .push((slot, ticket, prepared(self.prepare, source)));
            return true;
        }
        (self.jobs.as_ref()).is_some_and(|jobs| jobs.send((slot, ticket, source)).is_ok())
    }

    /// Gives back preparations taken but not written (they come first next time).
    pub(super) fn put_back(&mut self, mut later: Vec<Prepared<R>>) {
        later.append(&mut self.ready);
        self.ready = later;
    }

    /// The preparations finished since the last call.
    pub(super) fn finished(&mut self) -> Vec<Prepared<R>> {
        let mut ready = std::mem::take(&mut self.ready);
        let done = self
            .done
            .get_mut()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        ready.extend(done.try_iter());
        ready
    }
}

impl<R: Send + 'static> Drop for Preparer<R> {
    fn drop(&mut self) {
        // Closing the queue ends the thread after its current preparation.
        self.jobs = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// A host-visible, zeroed request buffer of `words` words.
fn request_buffer(device: &Arc<Device>, words: u32) -> RenderResult<Buffer> {
    let mut buffer = Buffer::new(
        device,
        "scene streaming requests",
        u64::from(words) * 4,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        crate::vk::MemoryLocation::GpuToCpu,
    )?;
    buffer.write(0, &vec![0; words as usize * 4])?;
    Ok(buffer)
}
