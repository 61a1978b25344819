//! A frame as an ordered list of passes ([`FramePasses`]): the techniques' preparation and
//! the GPU culler's phases, the surfaces in one or more phases, the passes over the finished
//! picture ([`OVERLAY_PASSES`]), the pick readback and the depth handed to the host. Each pass
//! says what it reads and writes ([`Resources`]) and who records it. What a frame draws is decided once, in
//! [`FramePasses::plan`] from the frame's [`FrameShape`]; the recording, the clears, the
//! barriers, the pixel-key planes, the display bits and the replay key all follow from the
//! list.
//!
//! The uploads go ahead of the list, in a prologue command buffer of their own, so that a
//! replayed frame gets them too (`record.rs`).

use crate::commands_key::mix;
use crate::render::pixel_keys::KeyUse;
use crate::render::{
    OverlaySets, OverlayShader, DISPLAY_CAP_KEYS, DISPLAY_HIGHLIGHT_OUTLINE,
    DISPLAY_NEAREST_SURFACES,
};
use crate::shaders;
use crate::vk::Blend;

/// Which image a pass draws into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassTarget {
    /// The colour target (shaded image).
    Color,
    /// The R32_UINT pick target (instance id + 1, 0 for nothing).
    Pick,
}

/// What passes read and write: the targets, the GPU culler's draws, the transparency
/// method's storage and the pixel keys' planes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct Resources(u32);

impl Resources {
    /// Nothing.
    pub const NONE: Self = Self(0);
    /// The colour target (the picture).
    pub const COLOR: Self = Self(1);
    /// The depth target (read through the depth set by passes over the picture).
    pub const DEPTH: Self = Self(1 << 1);
    /// The pick target (instance ids).
    pub const PICK_IDS: Self = Self(1 << 2);
    /// The draws the submission records from (the GPU culler's, or the techniques' own).
    pub const DRAWS: Self = Self(1 << 3);
    /// The transparency method's storage and targets.
    pub const TRANSPARENCY: Self = Self(1 << 4);
    /// The pixel keys' outline plane (the outline highlight style).
    pub const OUTLINE_KEYS: Self = Self(1 << 5);
    /// The pixel keys' nearest-surfaces plane (the silhouettes').
    pub const NEAREST_SURFACES: Self = Self(1 << 6);
    /// The pixel keys' two cap planes (the cap ties').
    pub const CAP_KEYS: Self = Self(1 << 7);
    /// What the surfaces write through storage, which passes over the picture read: they wait
    /// for the writes with a barrier.
    const STORAGE: Self = Self(
        Self::TRANSPARENCY.0 | Self::OUTLINE_KEYS.0 | Self::NEAREST_SURFACES.0 | Self::CAP_KEYS.0,
    );

    /// Both.
    pub const fn with(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// Whether it holds any of `other`.
    pub fn has(self, other: Self) -> bool {
        self.0 & other.0 != 0
    }

    /// The pixel keys' planes among these.
    pub fn key_use(self) -> KeyUse {
        KeyUse {
            outline: self.has(Self::OUTLINE_KEYS),
            nearest_surfaces: self.has(Self::NEAREST_SURFACES),
            cap_keys: self.has(Self::CAP_KEYS),
        }
    }
}

/// The depth a frame's silhouettes are found in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SilhouetteSource {
    /// The depth buffer: the surfaces fill it (edges, hidden-line). The silhouettes go under
    /// the translucent surfaces merged over the picture, as the edge lines do.
    DepthBuffer,
    /// The nearest surfaces every surface records in the pixel keys (X-ray, whose translucent
    /// surfaces write no depth). They outline the nearest surfaces, so they go over the merge.
    NearestSurfaces,
}

/// What decides a frame's passes: the display mode, the settings, the section and the
/// device, as the renderer reads them for one frame (`Renderer::frame_shape`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct FrameShape {
    /// The image the surfaces draw into.
    pub target: PassTarget,
    /// Phases of the surfaces (at least 1): a GPU culler's phase runs before each one after
    /// the first, reading the depth so far.
    pub phases: u32,
    /// Translucent surfaces are drawn with the transparency method and merged.
    pub translucent: bool,
    /// Ambient occlusion darkens the opaque picture.
    pub ssao: bool,
    /// Silhouette edges are drawn, found in this depth.
    pub silhouettes: Option<SilhouetteSource>,
    /// The silhouettes read the nearest surfaces (X-ray's, or those of highlighted parts).
    pub nearest_surfaces: bool,
    /// Caps that tie with another part's surface are painted from the cap keys.
    pub cap_ties: bool,
    /// A band goes around highlighted parts (the outline highlight style).
    pub outline: bool,
    /// The depth is handed to the host after the frame.
    pub depth_to_host: bool,
}

/// How a pass over the picture draws.
#[derive(Clone, Copy, Debug)]
pub(crate) enum OverlayDraw {
    /// A full-screen triangle of the renderer's own (`render::Pipelines::overlay`).
    Fullscreen(OverlayShader),
    /// The transparency method's merge (its pipeline comes with the techniques).
    TransparencyMerge,
}

/// A pass over the finished picture, recorded by the renderer.
#[derive(Debug)]
pub(crate) struct OverlayPass {
    /// Its name.
    pub name: &'static str,
    /// What a frame of this shape reads in it, or `None` when the frame does not draw it.
    pub reads: fn(&FrameShape) -> Option<Resources>,
    /// How it draws.
    pub draw: OverlayDraw,
}

/// The passes over the picture, in the order they are drawn: the caps first (they are part of
/// the opaque picture), occlusion darkening the opaque surfaces before lines go over them and
/// translucent surfaces are merged over both, X-ray's silhouettes over the merge, the
/// highlight band, and the background under whatever the picture leaves uncovered. A new pass
/// over the picture is one more entry here (and its shader in `shaders.rs`).
pub(crate) static OVERLAY_PASSES: [OverlayPass; 7] = [
    OverlayPass {
        name: "cap ties",
        reads: |shape| shape.cap_ties.then_some(Resources::CAP_KEYS),
        draw: OverlayDraw::Fullscreen(OverlayShader {
            fragment: &shaders::CAP_TIES_FRAG,
            blend: Blend::PREMULTIPLIED_OVER,
            sets: OverlaySets::Frame,
        }),
    },
    OverlayPass {
        name: "ambient occlusion",
        reads: |shape| shape.ssao.then_some(Resources::DEPTH),
        draw: OverlayDraw::Fullscreen(OverlayShader {
            fragment: &shaders::SSAO_FRAG,
            blend: Blend::DARKEN,
            sets: OverlaySets::FrameAndDepth,
        }),
    },
    OverlayPass {
        name: "silhouettes",
        reads: |shape| {
            (shape.silhouettes == Some(SilhouetteSource::DepthBuffer))
                .then(|| silhouette_reads(shape))
        },
        draw: SILHOUETTES,
    },
    OverlayPass {
        name: "transparency merge",
        reads: |shape| shape.translucent.then_some(Resources::TRANSPARENCY),
        draw: OverlayDraw::TransparencyMerge,
    },
    OverlayPass {
        name: "nearest surfaces' silhouettes",
        reads: |shape| {
            (shape.silhouettes == Some(SilhouetteSource::NearestSurfaces))
                .then(|| silhouette_reads(shape))
        },
        draw: SILHOUETTES,
    },
    OverlayPass {
        name: "highlight outline",
        reads: |shape| shape.outline.then_some(Resources::OUTLINE_KEYS),
        draw: OverlayDraw::Fullscreen(OverlayShader {
            fragment: &shaders::OUTLINE_FRAG,
            blend: Blend::PREMULTIPLIED_OVER,
            sets: OverlaySets::Frame,
        }),
    },
    OverlayPass {
        name: "background",
        reads: |shape| (shape.target == PassTarget::Color).then_some(Resources::COLOR),
        draw: OverlayDraw::Fullscreen(OverlayShader {
            fragment: &shaders::BACKGROUND_FRAG,
            blend: Blend::UNDER,
            sets: OverlaySets::Frame,
        }),
    },
];

/// The silhouettes' pipeline: lines where the depth (or the nearest surfaces) breaks.
const SILHOUETTES: OverlayDraw = OverlayDraw::Fullscreen(OverlayShader {
    fragment: &shaders::SILHOUETTES_FRAG,
    blend: Blend::PREMULTIPLIED_OVER,
    sets: OverlaySets::FrameAndDepth,
});

/// What the silhouettes read: the depth, and the nearest surfaces where they use them.
fn silhouette_reads(shape: &FrameShape) -> Resources {
    if shape.nearest_surfaces {
        Resources::DEPTH.with(Resources::NEAREST_SURFACES)
    } else {
        Resources::DEPTH
    }
}

/// One pass of a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FramePass {
    /// Outside rendering, first: the vertex and parameter paths' and the submission's
    /// preparation, then the GPU culler's phase 0 (when one is active). Writes the draws.
    Prepare,
    /// Outside rendering, before the surfaces' `phase` (≥ 1): the GPU culler's phase, which
    /// reads the depth so far and writes the draws.
    Cull {
        /// The culler's phase.
        phase: u32,
    },
    /// Inside rendering: the submission records the technique pipelines' passes (opaque,
    /// translucent, caps, edges… as `TechniquePipelines::passes` lists them) from the draws.
    Surfaces {
        /// The phase (the rendering is suspended between phases).
        phase: u32,
        /// Whether it is the last phase (the rendering ends after it).
        last: bool,
        /// The target it draws into.
        target: PassTarget,
        /// What it writes: its target, the depth, and the storage the passes over the
        /// picture read.
        writes: Resources,
    },
    /// Over the finished picture, recorded by the renderer.
    Overlay {
        /// Its index in [`OVERLAY_PASSES`].
        index: usize,
        /// What it reads in this frame.
        reads: Resources,
    },
    /// After the pick pass: the renderer copies the picked rectangle's ids and depths back.
    PickReadback,
    /// Last: the depth left for the host to copy (`Renderer::depth_for_host`).
    DepthToHost,
}

impl FramePass {
    /// Its name, as the GPU time of each pass is reported (`Renderer::gpu_pass_times`).
    pub fn name(&self) -> &'static str {
        match *self {
            FramePass::Prepare => "prepare and cull",
            FramePass::Cull { phase } => match phase {
                1 => "cull phase 1",
                2 => "cull phase 2",
                _ => "cull",
            },
            FramePass::Surfaces {
                target: PassTarget::Pick,
                ..
            } => "pick surfaces",
            FramePass::Surfaces { phase, .. } => match phase {
                0 => "surfaces phase 0",
                1 => "surfaces phase 1",
                2 => "surfaces phase 2",
                _ => "surfaces",
            },
            FramePass::Overlay { index, .. } => OVERLAY_PASSES[index].name,
            FramePass::PickReadback => "pick readback",
            FramePass::DepthToHost => "depth to host",
        }
    }

    /// What it reads.
    pub fn reads(&self) -> Resources {
        match *self {
            FramePass::Prepare => Resources::NONE,
            FramePass::Cull { .. } => Resources::DEPTH,
            FramePass::Surfaces { .. } => Resources::DRAWS,
            FramePass::Overlay { reads, .. } => reads,
            FramePass::PickReadback => Resources::PICK_IDS.with(Resources::DEPTH),
            FramePass::DepthToHost => Resources::DEPTH,
        }
    }

    /// What it writes.
    pub fn writes(&self) -> Resources {
        match *self {
            FramePass::Prepare | FramePass::Cull { .. } => Resources::DRAWS,
            FramePass::Surfaces { writes, .. } => writes,
            FramePass::Overlay { .. } => Resources::COLOR,
            FramePass::PickReadback | FramePass::DepthToHost => Resources::NONE,
        }
    }

    /// A word that tells it from every other pass, for the replay key.
    fn key_word(&self) -> u64 {
        match *self {
            FramePass::Prepare => 1,
            FramePass::Cull { phase } => 2 | u64::from(phase) << 8,
            FramePass::Surfaces {
                phase,
                last,
                writes,
                ..
            } => 3 | u64::from(phase) << 8 | u64::from(last) << 40 | u64::from(writes.0) << 48,
            FramePass::Overlay { index, reads } => {
                4 | (index as u64) << 8 | u64::from(reads.0) << 48
            }
            FramePass::PickReadback => 5,
            FramePass::DepthToHost => 6,
        }
    }
}

/// A frame's passes, in the order they are recorded.
#[derive(Clone, Debug)]
pub(crate) struct FramePasses {
    passes: Vec<FramePass>,
}

impl FramePasses {
    /// The passes of a frame of `shape`: the preparation, the surfaces' phases with a culler's
    /// phase before each but the first, the passes over the picture the shape draws, and after
    /// a pick pass its readback.
    pub fn plan(shape: &FrameShape) -> Self {
        // The passes over the picture this frame draws, with what each reads (the table's
        // predicates are plain functions: asking twice costs nothing, unlike a second list).
        let overlays = || {
            OVERLAY_PASSES
                .iter()
                .enumerate()
                .filter_map(|(index, pass)| {
                    (pass.reads)(shape).map(|reads| FramePass::Overlay { index, reads })
                })
        };
        // The surfaces write what the passes over the picture read of them.
        let drawn = match shape.target {
            PassTarget::Color => Resources::COLOR,
            PassTarget::Pick => Resources::PICK_IDS,
        };
        let writes = overlays().fold(drawn.with(Resources::DEPTH), |writes, pass| {
            writes.with(Resources(pass.reads().0 & Resources::STORAGE.0))
        });
        let phases = shape.phases.max(1);
        let mut passes = Vec::with_capacity(2 * phases as usize + OVERLAY_PASSES.len() + 1);
        passes.push(FramePass::Prepare);
        for phase in 0..phases {
            if phase > 0 {
                passes.push(FramePass::Cull { phase });
            }
            passes.push(FramePass::Surfaces {
                phase,
                last: phase + 1 == phases,
                target: shape.target,
                writes,
            });
        }
        passes.extend(overlays());
        if shape.target == PassTarget::Pick {
            passes.push(FramePass::PickReadback);
        }
        if shape.depth_to_host {
            passes.push(FramePass::DepthToHost);
        }
        Self { passes }
    }

    /// The passes in order.
    pub fn iter(&self) -> impl Iterator<Item = &FramePass> {
        self.passes.iter()
    }

    /// What the surfaces write.
    pub fn surface_writes(&self) -> Resources {
        self.passes
            .iter()
            .filter(|pass| matches!(pass, FramePass::Surfaces { .. }))
            .fold(Resources::NONE, |all, pass| all.with(pass.writes()))
    }

    /// What the passes over the picture read.
    pub fn overlay_reads(&self) -> Resources {
        self.passes
            .iter()
            .filter(|pass| matches!(pass, FramePass::Overlay { .. }))
            .fold(Resources::NONE, |all, pass| all.with(pass.reads()))
    }

    /// Whether the passes over the picture read what the surfaces wrote through storage, so
    /// that they wait for those writes.
    pub fn overlays_read_storage(&self) -> bool {
        self.overlay_reads().has(Resources::STORAGE)
    }

    /// How many phases the surfaces are drawn in.
    pub fn surface_phases(&self) -> u32 {
        self.passes
            .iter()
            .filter(|pass| matches!(pass, FramePass::Surfaces { .. }))
            .count() as u32
    }

    /// The display bits the surfaces' shaders need for what they write: the outline keys,
    /// the nearest surfaces and the cap keys.
    pub fn display_bits(&self) -> u32 {
        let writes = self.surface_writes();
        let mut bits = 0;
        if writes.has(Resources::OUTLINE_KEYS) {
            bits |= DISPLAY_HIGHLIGHT_OUTLINE;
        }
        if writes.has(Resources::NEAREST_SURFACES) {
            bits |= DISPLAY_NEAREST_SURFACES;
        }
        if writes.has(Resources::CAP_KEYS) {
            bits |= DISPLAY_CAP_KEYS;
        }
        bits
    }

    /// What the recording of these passes depends on: equal lists record equal commands.
    pub fn key(&self) -> u64 {
        self.passes
            .iter()
            .fold(self.passes.len() as u64, |key, pass| {
                mix(key, pass.key_word())
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shaded() -> FrameShape {
        FrameShape {
            target: PassTarget::Color,
            phases: 1,
            translucent: false,
            ssao: false,
            silhouettes: None,
            nearest_surfaces: false,
            cap_ties: false,
            outline: false,
            depth_to_host: false,
        }
    }

    fn overlay_names(passes: &FramePasses) -> Vec<&'static str> {
        passes
            .iter()
            .filter_map(|pass| match pass {
                FramePass::Overlay { index, .. } => Some(OVERLAY_PASSES[*index].name),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_plain_frame_prepares_draws_the_surfaces_and_the_background() {
        let passes = FramePasses::plan(&shaded());
        assert_eq!(overlay_names(&passes), ["background"]);
        assert_eq!(passes.surface_phases(), 1);
        assert_eq!(
            passes.surface_writes(),
            Resources::COLOR.with(Resources::DEPTH)
        );
        assert!(!passes.overlays_read_storage());
        assert_eq!(passes.display_bits(), 0);
    }

    #[test]
    fn every_setting_adds_its_pass_in_the_drawing_order() {
        let shape = FrameShape {
            translucent: true,
            ssao: true,
            silhouettes: Some(SilhouetteSource::DepthBuffer),
            nearest_surfaces: true,
            cap_ties: true,
            outline: true,
            ..shaded()
        };
        let passes = FramePasses::plan(&shape);
        assert_eq!(
            overlay_names(&passes),
            [
                "cap ties",
                "ambient occlusion",
                "silhouettes",
                "transparency merge",
                "highlight outline",
                "background"
            ]
        );
        let writes = passes.surface_writes();
        for written in [
            Resources::TRANSPARENCY,
            Resources::OUTLINE_KEYS,
            Resources::NEAREST_SURFACES,
            Resources::CAP_KEYS,
        ] {
            assert!(writes.has(written), "{written:?}");
        }
        assert!(passes.overlays_read_storage());
        assert_eq!(
            passes.display_bits(),
            DISPLAY_HIGHLIGHT_OUTLINE | DISPLAY_NEAREST_SURFACES | DISPLAY_CAP_KEYS
        );
        let keys = writes.key_use();
        assert!(keys.outline && keys.nearest_surfaces && keys.cap_keys);
    }

    #[test]
    fn xray_silhouettes_go_over_the_merge() {
        let shape = FrameShape {
            translucent: true,
            silhouettes: Some(SilhouetteSource::NearestSurfaces),
            nearest_surfaces: true,
            ..shaded()
        };
        let passes = FramePasses::plan(&shape);
        assert_eq!(
            overlay_names(&passes),
            [
                "transparency merge",
                "nearest surfaces' silhouettes",
                "background"
            ]
        );
    }

    #[test]
    fn culler_phases_go_between_the_surfaces_phases() {
        let passes = FramePasses::plan(&FrameShape {
            phases: 2,
            ..shaded()
        });
        let order: Vec<String> = passes
            .iter()
            .map(|pass| match pass {
                FramePass::Prepare => "prepare".to_string(),
                FramePass::Cull { phase } => format!("cull {phase}"),
                FramePass::Surfaces { phase, last, .. } => format!("surfaces {phase} {last}"),
                FramePass::Overlay { .. } => "overlay".to_string(),
                FramePass::PickReadback => "readback".to_string(),
                FramePass::DepthToHost => "depth to host".to_string(),
            })
            .collect();
        assert_eq!(
            order,
            [
                "prepare",
                "surfaces 0 false",
                "cull 1",
                "surfaces 1 true",
                "overlay"
            ]
        );
        assert!(passes.iter().any(|pass| pass.reads().has(Resources::DEPTH)));
    }

    #[test]
    fn a_pick_pass_draws_ids_and_reads_them_back_with_nothing_over_them() {
        let passes = FramePasses::plan(&FrameShape {
            target: PassTarget::Pick,
            ..shaded()
        });
        assert!(overlay_names(&passes).is_empty());
        assert!(matches!(
            passes.iter().last(),
            Some(FramePass::PickReadback)
        ));
        assert!(passes.surface_writes().has(Resources::PICK_IDS));
        assert!(!passes.surface_writes().has(Resources::COLOR));
    }

    #[test]
    fn a_frame_that_hands_its_depth_over_does_so_last() {
        let passes = FramePasses::plan(&FrameShape {
            depth_to_host: true,
            ssao: true,
            ..shaded()
        });
        assert_eq!(passes.iter().last(), Some(&FramePass::DepthToHost));
        assert!(passes.surface_writes().has(Resources::DEPTH));
        assert_ne!(
            passes.key(),
            FramePasses::plan(&FrameShape {
                ssao: true,
                ..shaded()
            })
            .key()
        );
    }

    #[test]
    fn the_key_changes_with_every_pass_added() {
        let plain = FramePasses::plan(&shaded()).key();
        let variants = [
            FrameShape {
                ssao: true,
                ..shaded()
            },
            FrameShape {
                outline: true,
                ..shaded()
            },
            FrameShape {
                cap_ties: true,
                ..shaded()
            },
            FrameShape {
                translucent: true,
                ..shaded()
            },
            FrameShape {
                phases: 2,
                ..shaded()
            },
            FrameShape {
                silhouettes: Some(SilhouetteSource::DepthBuffer),
                ..shaded()
            },
            FrameShape {
                silhouettes: Some(SilhouetteSource::DepthBuffer),
                nearest_surfaces: true,
                ..shaded()
            },
        ];
        let mut keys = vec![plain];
        for shape in variants {
            let key = FramePasses::plan(&shape).key();
            assert!(!keys.contains(&key), "{shape:?}");
            keys.push(key);
        }
        assert_eq!(FramePasses::plan(&shaded()).key(), plain);
    }
}
