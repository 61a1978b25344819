//! The pipelines of a technique combination and pass set ([`TechniquePipelines`]): one per
//! pass, from the assembled shaders ([`super::shader_assembly`]), with the pipeline layout that
//! joins the host's frame set with the paths' sets, and each pass's filter of the instances it
//! draws and, where the opaque surfaces are split by back faces, its route ([`PassFilters`]).

use std::sync::Arc;

use crate::error::RenderResult;
use crate::vk::raw as vk;
use cadr_plugin_abi as abi;

use crate::render::{TransparencyMethod, PICK_FORMAT};
use crate::vk::{
    Blend, ColorTarget, DepthUse, DescriptorSetLayout, Device, GraphicsPipelineDesc,
    MeshPipelineDesc, Pipeline, PipelineLayout, ShaderModule, ShaderStage, VertexLayout,
    COLOR_FORMAT,
};

use super::shader_assembly::{MeshShaders, MethodShaders, PassShader, PassShaders};
use super::surface_passes::{PassSet, ShadeMode};

/// Which surfaces a technique pipeline draws (the vertex shader's `CADR_DRAW_ROLE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DrawRole {
    /// Every surface (frames without translucency, lines, picking).
    All = 0,
    /// Opaque surfaces only.
    Opaque = 1,
    /// Translucent surfaces only.
    Translucent = 2,
}

/// What a pass lets through: its vertex shader's draw role, whether it is the section caps'
/// pass (`CADR_CAPS_PASS`, closed parts a plane cuts only), and whether it is the hidden
/// silhouettes' pass (whose geometry shader yields nothing for a part that is not curved).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PassScope {
    role: DrawRole,
    caps: bool,
    silhouettes: bool,
    /// Surfaces drawn with depth test and depth writes: a closed opaque part's back faces
    /// never show in it (the plugin ABI's `CadrClusterCull::back_faces_hidden`).
    hides_back_faces: bool,
    /// The parts it takes by whether their back faces are culled (`CADR_FACES_*`).
    faces: abi::CadrFaceRoute,
    /// Drawn by a mesh pipeline ([`abi::CADR_PASS_MESH_TRIANGLES`], [`abi::CADR_PASS_MESH_PICK`]).
    mesh: bool,
}

impl PassScope {
    /// The instances the pass needs, as the plugin ABI's filter and exclusion on their flags:
    /// the others its vertex shader clips away whole, so submissions and GPU cullers may skip
    /// them. `xray`: the X-ray mode, where every part not highlighted is translucent.
    /// `textures`: whether textures are drawn; without them a part translucent only by its
    /// texture ([`abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE`]) is opaque.
    fn filter(self, xray: bool, textures: bool) -> (abi::CadrPassFilter, abi::CadrPassExclusion) {
        const HIGHLIGHTED: u32 = abi::CADR_INSTANCE_HIGHLIGHTED;
        const TRANSLUCENT: u32 = abi::CADR_INSTANCE_TRANSLUCENT;
        const BY_TEXTURE: u32 = abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE;
        const ANY: (u32, u32) = (0, 0);
        // Translucent by material: with textures, the flag; without, the flag but not by texture.
        let (material_mask, material_translucent) = if textures {
            (TRANSLUCENT, TRANSLUCENT)
        } else {
            (TRANSLUCENT | BY_TEXTURE, TRANSLUCENT)
        };
        let ((mut mask, mut value), exclusion) = match (self.role, xray) {
            (DrawRole::All, _) => (ANY, ANY),
            // Opaque: not translucent by material (without textures, an exclusion says it).
            (DrawRole::Opaque, false) if textures => ((TRANSLUCENT, 0), ANY),
            (DrawRole::Opaque, false) => (ANY, (material_mask, material_translucent)),
            // Opaque in X-ray: highlighted, and not translucent by material.
            (DrawRole::Opaque, true) if textures => ((HIGHLIGHTED | TRANSLUCENT, HIGHLIGHTED), ANY),
            (DrawRole::Opaque, true) => (
                (HIGHLIGHTED, HIGHLIGHTED),
                (material_mask, material_translucent),
            ),
            (DrawRole::Translucent, false) => ((material_mask, material_translucent), ANY),
            // Translucent in X-ray: not highlighted, or translucent by material: every part
            // but the highlighted opaque ones. Without textures one exclusion cannot also
            // name those translucent by texture only: they are drawn, and clipped.
            (DrawRole::Translucent, true) => (ANY, (HIGHLIGHTED | TRANSLUCENT, HIGHLIGHTED)),
        };
        if self.caps {
            mask |= abi::CADR_INSTANCE_CLOSED;
            value |= abi::CADR_INSTANCE_CLOSED;
        }
        if self.silhouettes {
            mask |= abi::CADR_INSTANCE_CURVED;
            value |= abi::CADR_INSTANCE_CURVED;
        }
        let filter = abi::CadrPassFilter {
            mask,
            value,
            // The caps pass: only parts a plane cuts can show a cap.
            section_cut: u32::from(self.caps),
        };
        let (mask, value) = exclusion;
        (filter, abi::CadrPassExclusion { mask, value })
    }
}

/// The instances each pass of a frame needs, one filter and one exclusion per pass, in the
/// order of `TechniquePipelines::passes` (see `PassScope::filter`).
#[derive(Clone, Debug, Default)]
pub struct PassFilters {
    /// What each pass keeps.
    pub filters: Vec<abi::CadrPassFilter>,
    /// Of those, what each pass does not need.
    pub exclusions: Vec<abi::CadrPassExclusion>,
    /// Per pass, 1 where the back faces of closed opaque parts never show in it.
    pub back_faces_hidden: Vec<u32>,
    /// Per pass, the parts it takes by whether their back faces are culled (`CADR_FACES_*`).
    pub face_routes: Vec<abi::CadrFaceRoute>,
    /// Whether the two passes of a split share one stream whose commands name their pass
    /// (the plugin ABI's `CadrSharedFaceStreams`).
    pub shared_face_stream: bool,
}

impl PassFilters {
    /// Whether some pass takes only part of the instances by their faces: the culler must
    /// route them.
    pub fn routes_faces(&self) -> bool {
        self.face_routes
            .iter()
            .any(|&route| route != abi::CADR_FACES_ANY)
    }
}

/// The pipeline layout of a combination's pipelines: the frame set, then the paths' sets up to
/// the last one used (an empty set standing for a path without one), and 128 bytes of push
/// constants for the vertex stage (152 with mesh shading, see below). Returns the empty set's
/// layout too, which must live as long.
fn technique_layout(
    device: &Arc<Device>,
    inputs: &PipelineInputs<'_>,
) -> RenderResult<(PipelineLayout, DescriptorSetLayout)> {
    let empty_set_layout = DescriptorSetLayout::new(device, "empty set layout", &[])?;
    let used = inputs
        .path_set_layouts
        .iter()
        .rposition(|l| *l != vk::DescriptorSetLayout::null())
        .map_or(1, |i| i + 2);
    let mut sets = vec![inputs.frame_set_layout];
    sets.extend(inputs.path_set_layouts.iter().map(|&l| {
        if l == vk::DescriptorSetLayout::null() {
            empty_set_layout.raw()
        } else {
            l
        }
    }));
    sets.truncate(used);
    // With mesh shading, one range for the vertex, task and mesh stages: the paths' 128 bytes
    // (paths that announce mesh shading push none), then the submission's CadrMeshTaskPush.
    let (push_bytes, push_stages) = if inputs.shaders.mesh.is_some() {
        (
            abi::CADR_MESH_TASK_PUSH_OFFSET + std::mem::size_of::<abi::CadrMeshTaskPush>() as u32,
            vk::ShaderStageFlags::VERTEX
                | vk::ShaderStageFlags::TASK_EXT
                | vk::ShaderStageFlags::MESH_EXT,
        )
    } else {
        (128, vk::ShaderStageFlags::VERTEX)
    };
    let layout = PipelineLayout::new(device, "technique layout", &sets, push_bytes, push_stages)?;
    Ok((layout, empty_set_layout))
}

/// How a pass rasterizes, beyond its shaders and topology.
#[derive(Clone, Copy, Debug, Default)]
struct Raster {
    /// Translucent surfaces, blended into the method's targets (depth tested, not written).
    translucent: bool,
    /// Pushed back so that edge lines win the depth test.
    depth_bias: bool,
    /// Triangles drawn as their edges.
    triangle_outlines: bool,
    /// Depth only, no colour.
    depth_only: bool,
    /// Drawn only behind the surfaces (depth GREATER, not written): hidden lines.
    behind: bool,
    /// Drawn only on the surface each pixel shows (depth EQUAL, not written): the caps pass,
    /// whose vertex shader (`CADR_CAPS_PASS`) also clips away every part that cannot show a
    /// cap (open, or crossed by no plane).
    on_surfaces: bool,
    /// Depth tested, not written: the lines under the caps pass, which must find the
    /// surfaces' depth where lines were drawn.
    keeps_depth: bool,
    /// Triangles turned into their silhouette segments by the geometry shader
    /// (`shaders/silhouette_lines.geom`): lines, not surfaces.
    silhouette_lines: bool,
    /// The parts it takes by their faces (`CADR_FACES_*`): with [`abi::CADR_FACES_CULLED`]
    /// its rasterizer culls back faces.
    faces: abi::CadrFaceRoute,
}

/// The pipelines and layout of one combination and pass set; destroyed together.
pub struct TechniquePipelines {
    device: Arc<Device>,
    // Dropped in this order: the pipelines, then the layouts they were made with.
    pipelines: Vec<Pipeline>,
    /// The transparency merge, for a pass set with translucent surfaces.
    pub merge: Option<Pipeline>,
    /// The shared layout.
    pub layout: PipelineLayout,
    /// The merge's layout: the frame set, then the method's targets.
    pub merge_layout: Option<PipelineLayout>,
    /// Stands in for the sets a path does not use below one it does.
    _empty_set_layout: DescriptorSetLayout,
    /// What they draw.
    pub pass_set: PassSet,
    /// The passes, in order.
    pub passes: Vec<abi::CadrPass>,
    /// The instances each pass needs, in the same order (see [`PassScope::filter`]): with
    /// textures off (`[0]`) and on (`[1]`). Made with the passes, so a frame only picks one.
    filters: [PassFilters; 2],
    /// The colour attachment's format (the pick pass draws ids).
    pub color_format: vk::Format,
    /// The formats of the colour attachments after the first (the transparency method's
    /// targets, while translucent surfaces are drawn).
    pub extra_color_formats: Vec<vk::Format>,
    /// The transparency method's targets (empty without translucent surfaces).
    targets: Vec<abi::CadrTransparencyTarget>,
}

/// What a combination's pipelines are built from.
pub struct PipelineInputs<'a> {
    /// The host's set 0 layout.
    pub frame_set_layout: vk::DescriptorSetLayout,
    /// The merge's set 1 layout: the transparency targets as sampled images.
    pub merge_set_layout: vk::DescriptorSetLayout,
    /// Set layouts 1 and 2 (parameter path) and 3 (vertex path); null for none.
    pub path_set_layouts: [vk::DescriptorSetLayout; 3],
    /// The vertex path's input.
    pub vertex_input: abi::CadrVertexInput,
    /// The vertex and fragment shaders of the passes.
    pub shaders: &'a PassShaders,
    /// The passes to build.
    pub passes: PassSet,
    /// The kind the pick pass is given: [`abi::CADR_PASS_PICK`] when every active technique
    /// knows it (ABI 1.2 or later), else [`abi::CADR_PASS_TRIANGLES`].
    pub pick_kind: abi::CadrPassKind,
    /// The active transparency method.
    pub method: Option<&'a TransparencyMethod>,
}

impl TechniquePipelines {
    /// The device they were built on.
    pub(crate) fn device(&self) -> &Arc<Device> {
        &self.device
    }

    /// Creates the layout and the passes' pipelines.
    pub fn new(device: &Arc<Device>, inputs: &PipelineInputs<'_>) -> RenderResult<Self> {
        let (layout, empty_set_layout) = technique_layout(device, inputs)?;
        let translucent_method = match (inputs.passes, inputs.method) {
            (
                PassSet::Shaded {
                    translucent: true, ..
                },
                Some(method),
            ) => Some(method),
            _ => None,
        };
        let mut this = Self {
            device: Arc::clone(device),
            pipelines: Vec::new(),
            merge: None,
            layout,
            merge_layout: None,
            _empty_set_layout: empty_set_layout,
            pass_set: inputs.passes,
            passes: Vec::new(),
            filters: Default::default(),
            color_format: match inputs.passes {
                PassSet::Pick { .. } => PICK_FORMAT,
                PassSet::Shaded { .. } => COLOR_FORMAT,
            },
            extra_color_formats: translucent_method.map_or_else(Vec::new, |m| m.target_formats()),
            targets: translucent_method.map_or_else(Vec::new, |m| m.targets.clone()),
        };
        let shared_face_stream = this.face_pipelines_picked_by_gpu();
        for filters in &mut this.filters {
            filters.shared_face_stream = shared_face_stream;
        }
        let fragment = |shader: PassShader| inputs.shaders.shader(shader);
        let triangles = vk::PrimitiveTopology::TRIANGLE_LIST;
        let plain = Raster::default();
        match inputs.passes {
            PassSet::Shaded {
                mode: ShadeMode::Solid,
                ..
            } => {
                let solid = fragment(PassShader::Solid)?;
                this.add_surfaces(inputs, solid, plain)?;
            }
            PassSet::Shaded {
                mode: mode @ (ShadeMode::Edges | ShadeMode::HiddenLine | ShadeMode::XRay),
                ..
            } => this.add_edge_mode_passes(inputs, mode)?,
            PassSet::Shaded {
                mode: ShadeMode::Wireframe,
                ..
            } => {
                let outlines = Raster {
                    triangle_outlines: true,
                    ..plain
                };
                let edges = fragment(PassShader::Edges)?;
                let pipeline = this.pipeline(inputs, edges, triangles, outlines)?;
                this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            }
            PassSet::Pick { .. } => {
                let pick = fragment(PassShader::Pick)?;
                let pipeline = this.pipeline(inputs, pick, triangles, plain)?;
                this.add(pipeline, inputs.pick_kind);
            }
        }
        if let (Some(shaders), Some(_)) = (inputs.shaders.method.as_ref(), translucent_method) {
            let translucent = Raster {
                translucent: true,
                ..plain
            };
            let pipeline = this.pipeline(inputs, &shaders.translucent, triangles, translucent)?;
            this.add(pipeline, abi::CADR_PASS_TRIANGLES);
            this.add_merge(inputs, shaders)?;
        }
        Ok(this)
    }

    /// The passes of the modes that draw feature edges (edges, hidden-line, X-ray): the
    /// surfaces pushed back under the lines (depth only in hidden-line), with dashed hidden
    /// edges the hidden lines and hidden silhouettes, the visible lines, and while section caps
    /// show the caps painted again over the lines.
    fn add_edge_mode_passes(
        &mut self,
        inputs: &PipelineInputs<'_>,
        mode: ShadeMode,
    ) -> RenderResult<()> {
        let triangles = vk::PrimitiveTopology::TRIANGLE_LIST;
        let lines = vk::PrimitiveTopology::LINE_LIST;
        let plain = Raster::default();
        let under_lines = Raster {
            depth_bias: true,
            ..plain
        };
        let surfaces = Raster {
            depth_only: mode == ShadeMode::HiddenLine,
            ..under_lines
        };
        let solid = inputs.shaders.shader(PassShader::Solid)?;
        self.add_surfaces(inputs, solid, surfaces)?;
        if let PassSet::Shaded {
            dashed_hidden: true,
            ..
        } = inputs.passes
        {
            // Before the visible lines, which win where the two cross.
            let hidden = Raster {
                behind: true,
                ..plain
            };
            let dashed = inputs.shaders.shader(PassShader::HiddenEdges)?;
            let pipeline = self.pipeline(inputs, dashed, lines, hidden)?;
            self.add(pipeline, abi::CADR_PASS_EDGES);
            if let PassSet::Shaded {
                hidden_silhouettes: true,
                ..
            } = inputs.passes
            {
                // The triangles, each turned into its silhouette segment, if any.
                let silhouettes = Raster {
                    silhouette_lines: true,
                    ..hidden
                };
                let pipeline = self.pipeline(inputs, dashed, triangles, silhouettes)?;
                self.add(pipeline, abi::CADR_PASS_TRIANGLES);
            }
        }
        let caps_over_lines = matches!(
            inputs.passes,
            PassSet::Shaded {
                caps_over_lines: true,
                ..
            }
        );
        let visible_lines = Raster {
            keeps_depth: caps_over_lines,
            ..plain
        };
        let edges = inputs.shaders.shader(PassShader::Edges)?;
        let pipeline = self.pipeline(inputs, edges, lines, visible_lines)?;
        self.add(pipeline, abi::CADR_PASS_EDGES);
        if caps_over_lines {
            // The surfaces' own vertex shader, role and depth bias: depth EQUAL finds
            // the surface each pixel shows.
            let caps = Raster {
                on_surfaces: true,
                ..under_lines
            };
            let caps_fragment = inputs.shaders.shader(PassShader::Caps)?;
            let pipeline = self.pipeline(inputs, caps_fragment, triangles, caps)?;
            self.add(pipeline, abi::CADR_PASS_TRIANGLES);
        }
        Ok(())
    }

    /// Whether the GPU picks between the two surface pipelines of a split, per part.
    fn face_pipelines_picked_by_gpu(&self) -> bool {
        matches!(
            self.pass_set,
            PassSet::Shaded {
                back_faces_culled: true,
                face_pipelines_picked_by_gpu: true,
                ..
            }
        )
    }

    /// The surfaces' pass of `raster`: where the pass set culls back faces, two passes, the
    /// closed parts' with their back faces culled, then the others'.
    fn add_surfaces(
        &mut self,
        inputs: &PipelineInputs<'_>,
        fragment: &[u32],
        raster: Raster,
    ) -> RenderResult<()> {
        let triangles = vk::PrimitiveTopology::TRIANGLE_LIST;
        let routes: &[abi::CadrFaceRoute] = match self.pass_set {
            PassSet::Shaded {
                back_faces_culled: true,
                ..
            } => &[abi::CADR_FACES_CULLED, abi::CADR_FACES_KEPT],
            _ => &[abi::CADR_FACES_ANY],
        };
        for &faces in routes {
            let pipeline =
                self.pipeline(inputs, fragment, triangles, Raster { faces, ..raster })?;
            self.add(pipeline, abi::CADR_PASS_TRIANGLES);
        }
        Ok(())
    }

    fn add(&mut self, (pipeline, scope): (Pipeline, PassScope), kind: abi::CadrPassKind) {
        use crate::vk::raw::Handle;
        self.passes.push(abi::CadrPass {
            pipeline: pipeline.raw().as_raw(),
            kind: match (scope.mesh, kind) {
                (false, kind) => kind,
                (true, abi::CADR_PASS_PICK) => abi::CADR_PASS_MESH_PICK,
                (true, _) => abi::CADR_PASS_MESH_TRIANGLES,
            },
        });
        let xray = matches!(
            self.pass_set,
            PassSet::Shaded {
                mode: ShadeMode::XRay,
                ..
            }
        );
        for (filters, textures) in self.filters.iter_mut().zip([false, true]) {
            let (filter, exclusion) = scope.filter(xray, textures);
            filters.filters.push(filter);
            filters.exclusions.push(exclusion);
            filters
                .back_faces_hidden
                .push(u32::from(scope.hides_back_faces));
            filters.face_routes.push(scope.faces);
        }
        self.pipelines.push(pipeline);
    }

    /// The instances each pass needs (see [`PassScope::filter`]), in the order of
    /// [`TechniquePipelines::passes`].
    pub fn pass_filters(&self, textures: bool) -> &PassFilters {
        &self.filters[usize::from(textures)]
    }

    /// The merge: a full-screen triangle blending the method's result over the picture.
    fn add_merge(
        &mut self,
        inputs: &PipelineInputs<'_>,
        shaders: &MethodShaders,
    ) -> RenderResult<()> {
        let layout = PipelineLayout::new(
            &self.device,
            "transparency merge layout",
            &[inputs.frame_set_layout, inputs.merge_set_layout],
            0,
            vk::ShaderStageFlags::FRAGMENT,
        )?;
        let vertex = ShaderModule::from_spirv(
            &self.device,
            "merge.vert",
            &shaders.merge_vertex,
            ShaderStage::Vertex,
        )?;
        let fragment = ShaderModule::from_spirv(
            &self.device,
            "merge.frag",
            &shaders.merge,
            ShaderStage::Fragment,
        )?;
        self.merge = Some(Pipeline::fullscreen(
            &self.device,
            &layout,
            (&vertex, &fragment),
            Blend::PREMULTIPLIED_OVER,
            "transparency merge",
        )?);
        self.merge_layout = Some(layout);
        Ok(())
    }

    /// The colour attachments of a pipeline drawing `raster`: the picture, then the method's
    /// targets, each written only by the pipelines that draw into it.
    fn colors(&self, raster: Raster) -> Vec<ColorTarget> {
        let picture = if raster.translucent || raster.depth_only {
            ColorTarget::untouched(self.color_format)
        } else {
            ColorTarget::replaced(self.color_format)
        };
        std::iter::once(picture)
            .chain(self.targets.iter().map(|target| {
                if raster.translucent {
                    ColorTarget {
                        format: vk::Format::from_raw(target.format),
                        writes: true,
                        blend: Some(blend_of(&target.blend)),
                    }
                } else {
                    ColorTarget::untouched(vk::Format::from_raw(target.format))
                }
            }))
            .collect()
    }

    fn pipeline(
        &self,
        inputs: &PipelineInputs<'_>,
        fragment: &[u32],
        topology: vk::PrimitiveTopology,
        raster: Raster,
    ) -> RenderResult<(Pipeline, PassScope)> {
        let fragment = ShaderModule::from_spirv(
            &self.device,
            "technique fragment",
            fragment,
            ShaderStage::Fragment,
        )?;
        let geometry = if raster.silhouette_lines {
            Some(ShaderModule::from_spirv(
                &self.device,
                "silhouette_lines.geom",
                inputs.shaders.shader(PassShader::SilhouetteLines)?,
                ShaderStage::Geometry,
            )?)
        } else {
            None
        };
        let input = inputs.vertex_input;
        let count = (input.attribute_count as usize).min(input.formats.len());
        let attributes: Vec<(vk::Format, u32)> = (0..count)
            .map(|i| (vk::Format::from_raw(input.formats[i]), input.offsets[i]))
            .collect();
        let surfaces = topology == vk::PrimitiveTopology::TRIANGLE_LIST
            && !raster.triangle_outlines
            && !raster.silhouette_lines;
        let role = self.draw_role(raster, surfaces);
        let colors = self.colors(raster);
        let depth = if raster.behind {
            DepthUse::TestBehind
        } else if raster.on_surfaces {
            DepthUse::TestEqual
        } else if raster.translucent || raster.keeps_depth {
            DepthUse::Test
        } else {
            DepthUse::TestAndWrite
        };
        let mesh = inputs.shaders.mesh.as_ref().filter(|_| {
            topology == vk::PrimitiveTopology::TRIANGLE_LIST && !raster.silhouette_lines
        });
        let scope = PassScope {
            role,
            caps: raster.on_surfaces,
            silhouettes: raster.silhouette_lines,
            hides_back_faces: surfaces
                && role != DrawRole::Translucent
                && depth == DepthUse::TestAndWrite,
            faces: raster.faces,
            mesh: mesh.is_some(),
        };
        let name = if raster.translucent {
            "translucent technique pipeline"
        } else {
            "technique pipeline"
        };
        let constants = [role as u32, u32::from(raster.on_surfaces)];
        if let Some(shaders) = mesh {
            let targets = MeshTargets {
                colors: &colors,
                depth,
                constants: &constants,
                name,
            };
            let pipeline = self.mesh_pipeline(shaders, &fragment, raster, &targets)?;
            return Ok((pipeline, scope));
        }
        let vertex = ShaderModule::from_spirv(
            &self.device,
            "technique.vert",
            &inputs.shaders.vertex,
            ShaderStage::Vertex,
        )?;
        let pipeline = Pipeline::graphics(
            &self.device,
            &GraphicsPipelineDesc {
                layout: &self.layout,
                vertex: &vertex,
                geometry: geometry.as_ref(),
                fragment: &fragment,
                vertex_layout: (input.stride != 0).then_some(VertexLayout {
                    stride: input.stride,
                    attributes: &attributes,
                }),
                topology,
                depth_bias: raster.depth_bias,
                triangle_outlines: raster.triangle_outlines,
                cull_back_faces: raster.faces == abi::CADR_FACES_CULLED,
                indirect_bindable: raster.faces != abi::CADR_FACES_ANY
                    && self.face_pipelines_picked_by_gpu(),
                colors: &colors,
                depth,
                vertex_constants: &constants,
                samples: self.pass_set.samples(),
                name,
            },
        )?;
        Ok((pipeline, scope))
    }

    /// Which surfaces a pipeline drawing `raster` lets through (`surfaces`: it draws filled
    /// triangles, not lines or outlines).
    fn draw_role(&self, raster: Raster, surfaces: bool) -> DrawRole {
        let translucent_frame = matches!(
            self.pass_set,
            PassSet::Shaded {
                translucent: true,
                ..
            }
        );
        let through_translucent = matches!(
            self.pass_set,
            PassSet::Pick {
                through_translucent: true,
                ..
            }
        );
        let lines_through_translucent = matches!(
            self.pass_set,
            PassSet::Shaded {
                lines_through_translucent: true,
                ..
            }
        );
        match (translucent_frame, raster.translucent, surfaces) {
            (false, _, _) if through_translucent => DrawRole::Opaque,
            (false, _, true) if lines_through_translucent => DrawRole::Opaque,
            (false, _, _) => DrawRole::All,
            (true, true, _) => DrawRole::Translucent,
            (true, false, true) => DrawRole::Opaque,
            (true, false, false) => DrawRole::All,
        }
    }

    /// The mesh pipeline of a triangle pass (a mesh-shading submission draws it): the host's
    /// task shader, the mesh shader assembled from the paths' snippets, and `fragment`.
    fn mesh_pipeline(
        &self,
        shaders: &MeshShaders,
        fragment: &ShaderModule,
        raster: Raster,
        targets: &MeshTargets<'_>,
    ) -> RenderResult<Pipeline> {
        let task = ShaderModule::from_spirv(
            &self.device,
            "technique.task",
            &shaders.task,
            ShaderStage::Task,
        )?;
        let mesh = ShaderModule::from_spirv(
            &self.device,
            "technique.mesh",
            &shaders.mesh,
            ShaderStage::Mesh,
        )?;
        Ok(Pipeline::mesh(
            &self.device,
            &MeshPipelineDesc {
                layout: &self.layout,
                task: Some(&task),
                mesh: &mesh,
                fragment,
                depth_bias: raster.depth_bias,
                triangle_outlines: raster.triangle_outlines,
                cull_back_faces: raster.faces == abi::CADR_FACES_CULLED,
                mesh_constants: targets.constants,
                colors: targets.colors,
                depth: targets.depth,
                samples: self.pass_set.samples(),
                name: targets.name,
            },
        )?)
    }
}

/// A method's blend state as the Vulkan layer takes it.
fn blend_of(blend: &abi::CadrBlend) -> Blend {
    Blend {
        src_color: vk::BlendFactor::from_raw(blend.src_color),
        dst_color: vk::BlendFactor::from_raw(blend.dst_color),
        color_op: vk::BlendOp::from_raw(blend.color_op),
        src_alpha: vk::BlendFactor::from_raw(blend.src_alpha),
        dst_alpha: vk::BlendFactor::from_raw(blend.dst_alpha),
        alpha_op: vk::BlendOp::from_raw(blend.alpha_op),
    }
}

/// What a mesh pipeline draws into and is specialised with, as its pass's vertex pipeline
/// would be.
struct MeshTargets<'a> {
    colors: &'a [ColorTarget],
    depth: DepthUse,
    /// The draw role and the caps pass (the shaders' constants 0 and 1).
    constants: &'a [u32],
    name: &'a str,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether a pass of `scope` draws anything of a part with `flags`: technique.vert's
    /// translucency test, role and caps clipping, as the shader decides them, and for the
    /// hidden silhouettes' pass whether its geometry shader can yield a segment.
    fn pass_draws(scope: PassScope, xray: bool, textures: bool, flags: u32) -> bool {
        let set = |bit: u32| flags & bit != 0;
        let by_material = set(abi::CADR_INSTANCE_TRANSLUCENT)
            && (textures || !set(abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE));
        let translucent = by_material || (xray && !set(abi::CADR_INSTANCE_HIGHLIGHTED));
        let drawn = match scope.role {
            DrawRole::All => true,
            DrawRole::Opaque => !translucent,
            DrawRole::Translucent => translucent,
        };
        drawn
            && (!scope.caps || set(abi::CADR_INSTANCE_CLOSED))
            && (!scope.silhouettes || set(abi::CADR_INSTANCE_CURVED))
    }

    #[test]
    fn a_pass_filter_leaves_out_only_what_its_pass_cannot_draw() {
        use abi::CADR_INSTANCE_CURVED as CURVED;
        use abi::CADR_INSTANCE_TRANSLUCENT as TRANSLUCENT;
        use abi::CADR_INSTANCE_TRANSLUCENT_BY_TEXTURE as BY_TEXTURE;
        use abi::{CADR_INSTANCE_CLOSED as CLOSED, CADR_INSTANCE_HIGHLIGHTED as HIGHLIGHTED};
        let mut every_flags = Vec::new();
        for highlighted in [0, HIGHLIGHTED] {
            for translucency in [0, TRANSLUCENT, TRANSLUCENT | BY_TEXTURE] {
                for closed in [0, CLOSED] {
                    for curved in [0, CURVED] {
                        every_flags.push(highlighted | translucency | closed | curved);
                    }
                }
            }
        }
        let mut kept_needlessly = Vec::new();
        for role in [DrawRole::All, DrawRole::Opaque, DrawRole::Translucent] {
            for (caps, silhouettes) in [(false, false), (true, false), (false, true)] {
                let scope = PassScope {
                    role,
                    caps,
                    silhouettes,
                    hides_back_faces: false,
                    faces: abi::CADR_FACES_ANY,
                    mesh: false,
                };
                for (xray, textures) in [(false, false), (false, true), (true, false), (true, true)]
                {
                    let (filter, exclusion) = scope.filter(xray, textures);
                    let keeps = |flags| filter.keeps(flags) && !exclusion.excludes(flags);
                    for &flags in &every_flags {
                        let drawn = pass_draws(scope, xray, textures, flags);
                        assert!(
                            keeps(flags) || !drawn,
                            "{scope:?} xray {xray} textures {textures}: flags {flags:#x} drawn \
                             but filtered out"
                        );
                        if keeps(flags) && !drawn {
                            let shapeless = flags & !(CLOSED | CURVED);
                            kept_needlessly.push((scope, xray, textures, shapeless));
                        }
                    }
                }
            }
        }
        // Every filter is exact but one: X-ray's translucent pass without textures keeps the
        // highlighted parts translucent by texture only, which one exclusion cannot also name.
        kept_needlessly.dedup();
        let textured_highlighted = HIGHLIGHTED | TRANSLUCENT | BY_TEXTURE;
        assert_eq!(
            kept_needlessly,
            [(false, false), (true, false), (false, true)].map(|(caps, silhouettes)| (
                PassScope {
                    role: DrawRole::Translucent,
                    caps,
                    silhouettes,
                    hides_back_faces: false,
                    faces: abi::CADR_FACES_ANY,
                    mesh: false,
                },
                true,
                false,
                textured_highlighted
            ))
        );
        // The caps pass: only those a plane cuts (for cullers that can tell).
        let caps = PassScope {
            role: DrawRole::All,
            caps: true,
            silhouettes: false,
            hides_back_faces: false,
            faces: abi::CADR_FACES_ANY,
            mesh: false,
        };
        let opaque = PassScope {
            role: DrawRole::Opaque,
            caps: false,
            silhouettes: false,
            hides_back_faces: false,
            faces: abi::CADR_FACES_ANY,
            mesh: false,
        };
        assert_eq!(caps.filter(false, true).0.section_cut, 1);
        assert_eq!(opaque.filter(false, true).0.section_cut, 0);
    }
}
