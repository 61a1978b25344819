//! Transparency: how translucent surfaces are blended, whatever the order they are drawn in
//! (CAD scenes cannot be sorted per triangle).
//!
//! - `weighted-blended` (built in, the default): McGuire and Bavoil's weighted blended
//!   order-independent transparency (JCGT 2013). One pass accumulates premultiplied colours
//!   weighted by depth and the product of the transmittances; the merge divides them out. Exact
//!   for one translucent layer, an approximation where layers of different colours overlap;
//!   costs two extra colour targets and no storage.
//! - `per-pixel-lists` (plugin library): every translucent fragment goes into a linked list per
//!   pixel; the merge sorts each pixel's list by depth and composites it front to back. Exact up
//!   to [`MAX_LAYERS`] layers per pixel and [`NODES_PER_PIXEL`] fragments per pixel on average
//!   (fragments beyond are dropped); needs `fragmentStoresAndAtomics`.

use std::ffi::CStr;
use std::sync::Arc;

use crate::{KEEPS_FRAME_SLOTS, REPLAYABLE};
use cadr_plugin_sdk::abi::{self, CadrBlend, CadrTransparencyTarget};
use cadr_plugin_sdk::{technique_library, vk, Gpu, Technique, Transparency};

/// Fragments per pixel, on average over the target, that `per-pixel-lists` has room for.
pub const NODES_PER_PIXEL: u32 = 4;
/// The nearest layers per pixel that `per-pixel-lists` composites.
pub const MAX_LAYERS: u32 = 32;

fn blend(src: vk::BlendFactor, dst: vk::BlendFactor) -> CadrBlend {
    CadrBlend {
        src_color: src.as_raw(),
        dst_color: dst.as_raw(),
        color_op: vk::BlendOp::ADD.as_raw(),
        src_alpha: src.as_raw(),
        dst_alpha: dst.as_raw(),
        alpha_op: vk::BlendOp::ADD.as_raw(),
    }
}

/// Weighted blended order-independent transparency.
pub struct WeightedBlended;

impl Technique for WeightedBlended {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self)
    }
}

impl Transparency for WeightedBlended {
    fn targets(&self) -> Vec<CadrTransparencyTarget> {
        vec![
            // The weighted sum of premultiplied colours (rgb) and of opacities (a).
            CadrTransparencyTarget {
                format: vk::Format::R16G16B16A16_SFLOAT.as_raw(),
                blend: blend(vk::BlendFactor::ONE, vk::BlendFactor::ONE),
                clear: [0.0; 4],
            },
            // The product of the layers' transmittances (1 − opacity).
            CadrTransparencyTarget {
                format: vk::Format::R16_SFLOAT.as_raw(),
                blend: blend(vk::BlendFactor::ZERO, vk::BlendFactor::ONE_MINUS_SRC_COLOR),
                clear: [1.0, 0.0, 0.0, 0.0],
            },
        ]
    }

    fn fragment_snippet(&self) -> &CStr {
        c"
// The weight favours near layers (McGuire and Bavoil, equation 10, on the depth buffer's
// value) and is clamped so that half floats neither overflow nor vanish.
void cadr_transparent_fragment(vec4 color, float view_depth) {
    float weight = color.a * clamp(3e3 * pow(1.0 - gl_FragCoord.z, 3.0), 1e-2, 3e3);
    cadr_target_0 = color * weight;
    cadr_target_1 = vec4(color.a);
}
"
    }

    fn merge_snippet(&self) -> &CStr {
        c"
vec4 cadr_merge() {
    float transmittance = cadr_target_texel(1).r;
    if (transmittance >= 1.0) {
        return vec4(0.0);
    }
    vec4 sum = cadr_target_texel(0);
    // A sum that overflowed half floats: keep its hue rather than infinity.
    if (isinf(max(max(abs(sum.r), abs(sum.g)), abs(sum.b)))) {
        sum.rgb = vec3(sum.a);
    }
    vec3 average = sum.rgb / max(sum.a, 1e-5);
    float coverage = 1.0 - transmittance;
    return vec4(average * coverage, coverage);
}
"
    }
}

/// Per-pixel linked lists of translucent fragments, sorted and composited exactly.
pub struct PerPixelLists;

impl Technique for PerPixelLists {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self)
    }
}

impl Transparency for PerPixelLists {
    fn targets(&self) -> Vec<CadrTransparencyTarget> {
        Vec::new()
    }

    /// One header word (the fragment count), then per pixel the head of its list (cleared)
    /// and room for [`NODES_PER_PIXEL`] fragments of 4 words (colour as two half2, depth, next).
    fn storage_words(&self) -> (u32, u32, u32) {
        (1, 1 + NODES_PER_PIXEL * 4, 1)
    }

    fn fragment_snippet(&self) -> &CStr {
        c"
const uint CADR_NODES_PER_PIXEL = 4u;

// Storage: [0] fragments stored; [1, 1 + pixels) each pixel's first node + 1 (0: none);
// then the nodes, 4 words each: colour rg and ba as half floats, depth, next node + 1.
void cadr_transparent_fragment(vec4 color, float view_depth) {
    uint pixels = cadr_pixel_count();
    uint node = atomicAdd(cadr_storage[0], 1u);
    if (node >= pixels * CADR_NODES_PER_PIXEL) {
        return; // no room: the fragment is dropped
    }
    uint at = 1u + pixels + node * 4u;
    cadr_storage[at] = packHalf2x16(color.rg);
    cadr_storage[at + 1u] = packHalf2x16(color.ba);
    cadr_storage[at + 2u] = floatBitsToUint(gl_FragCoord.z);
    cadr_storage[at + 3u] = atomicExchange(cadr_storage[1u + cadr_pixel_index()], node + 1u);
}
"
    }

    fn merge_snippet(&self) -> &CStr {
        c"
const int CADR_MAX_LAYERS = 32;
const uint CADR_MAX_WALK = 4096u;

// The pixel's nearest layers, sorted by depth (insertion), composited front to back.
vec4 cadr_merge() {
    uint pixels = cadr_pixel_count();
    vec4 colors[CADR_MAX_LAYERS];
    float depths[CADR_MAX_LAYERS];
    int count = 0;
    uint next = cadr_storage[1u + cadr_pixel_index()];
    for (uint walked = 0u; next != 0u && walked < CADR_MAX_WALK; ++walked) {
        uint at = 1u + pixels + (next - 1u) * 4u;
        vec4 color = vec4(unpackHalf2x16(cadr_storage[at]), unpackHalf2x16(cadr_storage[at + 1u]));
        float depth = uintBitsToFloat(cadr_storage[at + 2u]);
        next = cadr_storage[at + 3u];
        if (count == CADR_MAX_LAYERS && depth >= depths[CADR_MAX_LAYERS - 1]) {
            continue;
        }
        int i = count < CADR_MAX_LAYERS ? count++ : CADR_MAX_LAYERS - 1;
        while (i > 0 && depths[i - 1] > depth) {
            colors[i] = colors[i - 1];
            depths[i] = depths[i - 1];
            --i;
        }
        colors[i] = color;
        depths[i] = depth;
    }
    vec4 result = vec4(0.0);
    for (int i = 0; i < count; ++i) {
        result += (1.0 - result.a) * colors[i];
    }
    return result;
}
"
    }
}

technique_library! {
    pub fn entry;
    library: "cadr transparency",
    techniques: [
        transparency PerPixelLists {
            name: "per-pixel-lists",
            description: "Exact: translucent fragments in a linked list per pixel, sorted by depth and composited front to back (up to 32 layers).",
            features: abi::CADR_FEATURE_FRAGMENT_STORES_AND_ATOMICS,
            provides: REPLAYABLE | KEEPS_FRAME_SLOTS,
            needs: 0,
        },
    ]
}
