//! What the surfaces of a frame draw: the display modes a host chooses ([`ShadeMode`]) and the
//! set of surface passes a frame of them draws ([`PassSet`]), which keys the pipelines built
//! for it. (The frame's whole list of passes is `frame/passes.rs`.)

/// The display modes: how surfaces and edges are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ShadeMode {
    /// Shaded triangles.
    #[default]
    Solid,
    /// Shaded triangles (pushed back by a depth bias) with edge lines over them.
    Edges,
    /// Edge lines only, those hidden behind opaque surfaces removed: the opaque surfaces fill
    /// the depth buffer (pushed back by a depth bias) but not the picture; translucent ones
    /// hide no lines. Section caps are filled, over the lines behind them.
    HiddenLine,
    /// Every triangle's edges, hidden ones included (no surface is filled).
    Wireframe,
    /// Every part translucent with its edges, except highlighted parts, which stay opaque: what
    /// is inside an assembly shows through its housing.
    XRay,
}

impl ShadeMode {
    /// Every mode.
    pub const ALL: [ShadeMode; 5] = [
        ShadeMode::Solid,
        ShadeMode::Edges,
        ShadeMode::HiddenLine,
        ShadeMode::Wireframe,
        ShadeMode::XRay,
    ];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShadeMode::Solid => "solid",
            ShadeMode::Edges => "edges",
            ShadeMode::HiddenLine => "hidden-line",
            ShadeMode::Wireframe => "wireframe",
            ShadeMode::XRay => "xray",
        }
    }

    /// Whether translucent surfaces are drawn as such in this mode (in the line modes no
    /// surface is drawn: in hidden-line the opaque ones hide lines, the translucent ones do
    /// not). X-ray always draws some.
    pub fn shows_translucency(self) -> bool {
        matches!(self, ShadeMode::Solid | ShadeMode::Edges | ShadeMode::XRay)
    }

    /// Whether this mode draws feature edges, which silhouette edges join when they are on
    /// (`Renderer::set_silhouettes`): edges, hidden-line and X-ray. Wireframe draws every
    /// triangle's edges, which need none.
    pub fn draws_silhouettes(self) -> bool {
        matches!(
            self,
            ShadeMode::Edges | ShadeMode::HiddenLine | ShadeMode::XRay
        )
    }

    /// Parses a command-line name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The passes a set of pipelines draws: the shaded frame in a shade mode, or the pick pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PassSet {
    /// Shaded triangles (and edges in the edge modes) into the colour target; with
    /// `translucent`, opaque surfaces first, then the translucent ones with the transparency
    /// method (its targets join the rendering) and its merge after the rendering.
    Shaded {
        /// The display mode.
        mode: ShadeMode,
        /// Whether the frame draws translucent surfaces.
        translucent: bool,
        /// Samples per pixel (1, or the MSAA level the renderer draws with).
        samples: u32,
        /// In the hidden-line mode, whether hidden edges are drawn too, dashed and lighter
        /// (always false in the other modes).
        dashed_hidden: bool,
        /// In the hidden-line mode, whether the scene has translucent surfaces, which then
        /// hide no lines: what is behind glass shows through it (always false in the other
        /// modes, which draw translucency as such).
        lines_through_translucent: bool,
        /// In the edges and hidden-line modes, whether section caps can show (caps are on and
        /// the eye is on the cut side of a plane): the lines then write no depth, and after
        /// them a caps pass (`shaders/caps.frag`, depth EQUAL on the surfaces' depth) paints
        /// the visible caps again over the lines of the far faces they are painted on (always
        /// false in the other modes).
        caps_over_lines: bool,
        /// With `dashed_hidden`, whether the silhouettes of hidden curved surfaces are dashed
        /// too: a pass over the triangles whose geometry shader
        /// (`shaders/silhouette_lines.geom`) turns each into the segment where its surface
        /// turns away from the eye, drawn only behind the surfaces (silhouettes on, and the
        /// device has geometry shaders; always false otherwise).
        hidden_silhouettes: bool,
        /// Whether the opaque surfaces are drawn in two passes: the closed parts' with their
        /// back faces culled by the rasterizer, then the others' (the GPU culler routes each
        /// part, the plugin ABI's `CadrBackFacePasses`; only with a culler that announces
        /// `CADR_TRAIT_ROUTES_BACK_FACES`).
        back_faces_culled: bool,
        /// Whether, where `back_faces_culled`, the GPU picks one of the two surface pipelines
        /// per part from one stream of commands (a submission that announces
        /// `CADR_TRAIT_SWITCHES_PIPELINES`): both pipelines are made bindable by the GPU.
        face_pipelines_picked_by_gpu: bool,
        /// What the surface shader interpolates beyond what every frame needs.
        inputs: SurfaceInputs,
    },
    /// Triangles of pickable instances, their ids into the pick target.
    Pick {
        /// Whether translucent parts let the click through to what is behind them.
        through_translucent: bool,
        /// What the pick shader interpolates beyond what every frame needs.
        inputs: SurfaceInputs,
    },
}

/// What the surface, pick and translucent shaders (`shaded.frag`, `pick.frag`, and
/// `translucent.frag`, which reads only the attributes) interpolate beyond what every frame
/// needs. Each is left out where the frame cannot show it, so that the rasterizer interpolates
/// fewer values per triangle (on lavapipe, leaving them out saved 6-17 % of a large frame's GPU
/// time, `docs/BENCHMARKS.md`); each combination is its own shader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SurfaceInputs {
    /// The vertex colours and texture coordinates: the scene has vertex attributes, or shows
    /// textures (`CADR_SURFACE_ATTRIBUTES`, `shaders/texturing.glsl`).
    pub attributes: bool,
    /// The offset from the eye that finds a section cap: caps are on and some plane is active
    /// (`CADR_SURFACE_CAPS`, `shaders/section.glsl`).
    pub caps: bool,
}

impl SurfaceInputs {
    /// The `#define` lines that ask the shaders for these inputs.
    pub fn defines(self) -> String {
        let mut defines = String::new();
        if self.attributes {
            defines.push_str("#define CADR_SURFACE_ATTRIBUTES\n");
        }
        if self.caps {
            defines.push_str("#define CADR_SURFACE_CAPS\n");
        }
        defines
    }
}

impl PassSet {
    /// Samples per pixel of the pass's attachments (the pick pass is always exact: one).
    pub fn samples(self) -> u32 {
        match self {
            PassSet::Shaded { samples, .. } => samples,
            PassSet::Pick { .. } => 1,
        }
    }

    /// What the surface or pick shader interpolates.
    pub fn surface_inputs(self) -> SurfaceInputs {
        match self {
            PassSet::Shaded { inputs, .. } | PassSet::Pick { inputs, .. } => inputs,
        }
    }

    /// Whether the passes fill surfaces (solid, edges, X-ray), so that ambient occlusion, when
    /// on, applies.
    pub fn fills_surfaces(self) -> bool {
        matches!(
            self,
            PassSet::Shaded {
                mode: ShadeMode::Solid | ShadeMode::Edges | ShadeMode::XRay,
                ..
            }
        )
    }

    /// Whether the passes draw feature edges (edges, hidden-line, X-ray), so that silhouettes,
    /// when on, join them.
    pub fn draws_edges(self) -> bool {
        matches!(self, PassSet::Shaded { mode, .. } if mode.draws_silhouettes())
    }

    /// Whether the opaque surfaces may be split by back faces (`back_faces_culled`): the modes
    /// whose surfaces are opaque (solid, edges, hidden-line, whose surfaces write depth only),
    /// where the split's one more pass keeps the frame within the four passes a phase that
    /// cadr's GPU cullers handle. Not X-ray (its surfaces are translucent) or wireframe (no
    /// surfaces).
    pub fn may_split_back_faces(self) -> bool {
        match self {
            PassSet::Shaded {
                mode: ShadeMode::Solid | ShadeMode::Edges | ShadeMode::HiddenLine,
                ..
            } => self.culler_passes() < 4,
            _ => false,
        }
    }

    /// The draw passes a GPU culler sees in each phase, without a split by back faces (which
    /// adds one): the surfaces, the visible lines of the edge modes, the dashed hidden lines
    /// and hidden silhouettes, the caps painted over the lines and the translucent surfaces,
    /// as `TechniquePipelines` makes them (`tests/tests/back_faces.rs` draws every
    /// combination: a culler given more passes than it handles refuses the frame).
    pub fn culler_passes(self) -> usize {
        match self {
            PassSet::Shaded {
                mode,
                translucent,
                dashed_hidden,
                caps_over_lines,
                hidden_silhouettes,
                ..
            } => match mode {
                ShadeMode::Wireframe => 1 + usize::from(translucent),
                _ => {
                    let lines = usize::from(mode.draws_silhouettes());
                    let hidden = usize::from(dashed_hidden) * (1 + usize::from(hidden_silhouettes));
                    1 + lines + hidden + usize::from(caps_over_lines) + usize::from(translucent)
                }
            },
            PassSet::Pick { .. } => 1,
        }
    }
}

#[cfg(test)]
impl PassSet {
    /// The shaded pass set of `mode` with every option off and one sample (tests start from it
    /// and set what they vary).
    pub(crate) fn plain(mode: ShadeMode) -> Self {
        PassSet::Shaded {
            mode,
            translucent: false,
            samples: 1,
            dashed_hidden: false,
            lines_through_translucent: false,
            caps_over_lines: false,
            hidden_silhouettes: false,
            back_faces_culled: false,
            face_pipelines_picked_by_gpu: false,
            inputs: SurfaceInputs::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `passes` with the fields a closure sets.
    fn with(
        passes: PassSet,
        change: impl FnOnce(&mut bool, &mut bool, &mut bool, &mut bool),
    ) -> PassSet {
        let mut passes = passes;
        if let PassSet::Shaded {
            translucent,
            dashed_hidden,
            caps_over_lines,
            hidden_silhouettes,
            ..
        } = &mut passes
        {
            change(
                translucent,
                dashed_hidden,
                caps_over_lines,
                hidden_silhouettes,
            );
        }
        passes
    }

    #[test]
    fn the_surfaces_split_where_the_frame_keeps_within_four_culled_passes() {
        let solid = PassSet::plain(ShadeMode::Solid);
        assert_eq!(solid.culler_passes(), 1);
        assert!(solid.may_split_back_faces());
        let translucent_solid = with(solid, |t, _, _, _| *t = true);
        assert_eq!(translucent_solid.culler_passes(), 2);
        assert!(translucent_solid.may_split_back_faces());

        let edges_with_caps = with(PassSet::plain(ShadeMode::Edges), |_, _, c, _| *c = true);
        assert_eq!(edges_with_caps.culler_passes(), 3);
        assert!(edges_with_caps.may_split_back_faces());
        let crowded = with(edges_with_caps, |t, _, _, _| *t = true);
        assert_eq!(crowded.culler_passes(), 4);
        assert!(!crowded.may_split_back_faces());

        let hidden_line = PassSet::plain(ShadeMode::HiddenLine);
        assert!(hidden_line.may_split_back_faces());
        let dashed = with(hidden_line, |_, d, _, _| *d = true);
        assert_eq!(dashed.culler_passes(), 3);
        assert!(dashed.may_split_back_faces());
        let dashed_silhouettes = with(dashed, |_, _, _, s| *s = true);
        assert_eq!(dashed_silhouettes.culler_passes(), 4);
        assert!(!dashed_silhouettes.may_split_back_faces());

        // Translucent surfaces show their back faces; wireframe draws no surfaces.
        assert!(
            !with(PassSet::plain(ShadeMode::XRay), |t, _, _, _| *t = true).may_split_back_faces()
        );
        assert!(!PassSet::plain(ShadeMode::Wireframe).may_split_back_faces());
        assert!(!PassSet::Pick {
            through_translucent: false,
            inputs: SurfaceInputs::default(),
        }
        .may_split_back_faces());
    }
}
