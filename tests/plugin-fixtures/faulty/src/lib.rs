//! Techniques that fail on purpose, for the host's refusal tests.

use std::ffi::CStr;
use std::sync::Arc;

use cadr_plugin_sdk::abi::{self, CadrBindState, CadrDrawBase, CadrInstance, CadrVertexInput};
use cadr_plugin_sdk::vk;
use cadr_plugin_sdk::{
    export_plugin, Bind, CullInput, CullOutput, Culling, Gpu, ParameterPath, Technique, VertexPath,
};

/// Panics when created.
pub struct PanicsOnCreate;

impl Technique for PanicsOnCreate {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        panic!("this vertex path always panics")
    }
}

impl VertexPath for PanicsOnCreate {
    fn shader_snippet(&self) -> &CStr {
        c""
    }
    fn vertex_input(&self) -> CadrVertexInput {
        CadrVertexInput::default()
    }
    fn bind_draw(&self, _: &Bind<'_>, _: &CadrInstance, _: &mut CadrBindState) -> CadrDrawBase {
        CadrDrawBase::default()
    }
}

/// Needs `VK_NV_device_generated_commands`, a feature bit no host sets.
pub struct NeedsNvGeneratedCommands;

impl Technique for NeedsNvGeneratedCommands {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self)
    }
}

impl VertexPath for NeedsNvGeneratedCommands {
    fn shader_snippet(&self) -> &CStr {
        c""
    }
    fn vertex_input(&self) -> CadrVertexInput {
        CadrVertexInput::default()
    }
    fn bind_draw(&self, _: &Bind<'_>, _: &CadrInstance, _: &mut CadrBindState) -> CadrDrawBase {
        CadrDrawBase::default()
    }
}

/// Panics while culling.
pub struct PanicsOnCull;

impl Technique for PanicsOnCull {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self)
    }
}

impl Culling for PanicsOnCull {
    fn cull(&mut self, _: &CullInput<'_>, _: &mut CullOutput<'_>) -> Result<(), String> {
        panic!("this culler always panics")
    }
}

/// Panics in every per-draw bind (a thread-safe function called while recording).
pub struct PanicsInBind;

impl Technique for PanicsInBind {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self)
    }
}

impl ParameterPath for PanicsInBind {
    fn shader_snippet(&self) -> &CStr {
        c"CadrObject cadr_object() { CadrObject o; o.world = mat4(1.0); o.base_color = vec4(1.0); o.surface = vec2(0.5); o.flags = 0u; o.instance = 0u; return o; }"
    }
    fn layout(&self) -> ([vk::DescriptorSetLayout; 2], u32) {
        ([vk::DescriptorSetLayout::null(); 2], 0)
    }
    fn bind_draw(&self, _: &Bind<'_>, _: u32, _: &CadrInstance, _: &mut CadrBindState) -> u32 {
        panic!("this parameter path panics while recording")
    }
}

export_plugin! {
    library: "cadr test fixtures",
    techniques: [
        vertex PanicsOnCreate {
            name: "panics-on-create",
            description: "Panics in create.",
            features: 0, provides: abi::CADR_TRAIT_GEOMETRY_SHARES_BINDING, needs: 0,
        },
        vertex NeedsNvGeneratedCommands {
            name: "needs-nv-generated-commands",
            description: "Needs VK_NV_device_generated_commands.",
            features: abi::CADR_FEATURE_DEVICE_GENERATED_COMMANDS, provides: 0, needs: 0,
        },
        culling PanicsOnCull {
            name: "panics-on-cull",
            description: "Panics in cull.",
            features: 0, provides: 0, needs: 0,
        },
        parameters PanicsInBind {
            name: "panics-in-bind",
            description: "Panics in bind_draw.",
            features: 0, provides: 0, needs: 0,
        },
    ]
}
