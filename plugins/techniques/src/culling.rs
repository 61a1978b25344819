//! Culling: which candidate instances are drawn.
//!
//! - `none`: every candidate is drawn;
//! - `frustum`: each part's bounding sphere, placed by its f64 world matrix, is tested against
//!   the view frustum and the section planes (a part wholly cut away is culled) on worker
//!   threads; the result and its XOR with the last frame's bits go back, so the host applies
//!   only what changed (seed 000's visibility deltas);
//! - `gpu-frustum`, `gpu-occlusion`, `gpu-clusters`: culling on the GPU
//!   ([`crate::gpu_culling`]).

use std::sync::Arc;

use crate::{KEEPS_FRAME_SLOTS, REPLAYABLE};
use cadr_plugin_sdk::abi::{self, CadrInstance};
use cadr_plugin_sdk::{technique_library, CullInput, CullOutput, Culling, Gpu, Technique};

/// Writes `visible` bits and their XOR with the previous bits (in `output.visible_bits`).
fn write_bits(output: &mut CullOutput<'_>, word: usize, visible: u64) {
    let previous = output.visible_bits[word];
    output.changed_bits[word] = previous ^ visible;
    output.visible_bits[word] = visible;
}

/// Draws every candidate.
pub struct NoCulling;

impl Technique for NoCulling {
    fn create(_gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self)
    }
}

impl Culling for NoCulling {
    fn cull(&mut self, _input: &CullInput<'_>, output: &mut CullOutput<'_>) -> Result<(), String> {
        for word in 0..output.visible_bits.len() {
            write_bits(output, word, u64::MAX);
        }
        Ok(())
    }
}

/// Frustum culling of bounding spheres on worker threads.
pub struct Frustum {
    threads: usize,
}

impl Technique for Frustum {
    fn create(gpu: Arc<Gpu>) -> Result<Self, String> {
        Ok(Self {
            threads: gpu.worker_threads as usize,
        })
    }
}

/// Whether the sphere of `instance`, placed by `world`, touches the inside of every plane
/// (the frustum's, then the section's).
fn inside(instance: &CadrInstance, world: &[f64; 16], planes: &[[f64; 4]]) -> bool {
    let [x, y, z, r] = instance.sphere.map(f64::from);
    let center = [
        world[0] * x + world[4] * y + world[8] * z + world[12],
        world[1] * x + world[5] * y + world[9] * z + world[13],
        world[2] * x + world[6] * y + world[10] * z + world[14],
    ];
    let scale = (0..3)
        .map(|c| {
            (world[c * 4].powi(2) + world[c * 4 + 1].powi(2) + world[c * 4 + 2].powi(2)).sqrt()
        })
        .fold(0.0_f64, f64::max);
    let radius = r * scale;
    planes
        .iter()
        .all(|p| p[0] * center[0] + p[1] * center[1] + p[2] * center[2] + p[3] >= -radius)
}

/// The visible bits of words `words` (candidates only).
fn cull_words(input: &CullInput<'_>, words: std::ops::Range<usize>) -> Vec<u64> {
    let (instances, worlds) = (input.scene().instances(), input.world_matrices());
    // A part wholly outside a section plane is cut away: culled like one outside the frustum.
    let planes: Vec<[f64; 4]> = input
        .planes()
        .iter()
        .chain(input.section_planes())
        .copied()
        .collect();
    let candidates = input.candidate_bits();
    words
        .map(|word| {
            let mut bits = candidates.get(word).copied().unwrap_or(0);
            let mut visible = 0u64;
            while bits != 0 {
                let bit = bits.trailing_zeros();
                bits &= bits - 1;
                let id = word * 64 + bit as usize;
                let passes = match (
                    instances.get(id),
                    instances
                        .get(id)
                        .and_then(|i| worlds.get(i.matrix as usize)),
                ) {
                    (Some(instance), Some(world)) => inside(instance, world, &planes),
                    _ => false,
                };
                if passes {
                    visible |= 1 << bit;
                }
            }
            visible
        })
        .collect()
}

/// Shares `CullInput` with worker threads: it only points at data that is immutable during
/// the call.
struct SharedInput<'a>(&'a CullInput<'a>);
// SAFETY: see above.
unsafe impl Sync for SharedInput<'_> {}

impl Culling for Frustum {
    fn cull(&mut self, input: &CullInput<'_>, output: &mut CullOutput<'_>) -> Result<(), String> {
        let words = output.visible_bits.len();
        // Threads pay off from a few thousand instances on.
        let threads = if words < 64 { 1 } else { self.threads.max(1) };
        let per = words.div_ceil(threads);
        let shared = SharedInput(input);
        let chunks: Vec<(usize, Vec<u64>)> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let range = (t * per).min(words)..((t + 1) * per).min(words);
                    let shared = &shared;
                    scope.spawn(move || (range.start, cull_words(shared.0, range)))
                })
                .collect();
            handles.into_iter().filter_map(|h| h.join().ok()).collect()
        });
        if chunks.len() != threads {
            return Err("a culling thread panicked".into());
        }
        for (start, bits) in chunks {
            for (offset, visible) in bits.into_iter().enumerate() {
                write_bits(output, start + offset, visible);
            }
        }
        Ok(())
    }
}

technique_library! {
    pub fn entry;
    library: "cadr culling",
    techniques: [
        culling Frustum {
            name: "frustum",
            description: "CPU frustum culling of part bounding spheres on worker threads; only changed visibility bits are applied.",
            features: 0, provides: abi::CADR_TRAIT_READS_HOST_MATRICES | REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        gpu_culling crate::gpu_culling::GpuFrustum {
            name: "gpu-frustum",
            description: "GPU frustum culling: a compute shader tests every part's sphere and writes the indirect draws and their count; the CPU does nothing per part, moving or not.",
            features: GPU_CULLING_FEATURES, provides: GPU_CULLING_PROVIDES, needs: GPU_CULLING_NEEDS,
        },
        gpu_culling crate::gpu_culling::GpuOcclusion {
            name: "gpu-occlusion",
            description: "GPU frustum and two-phase occlusion culling: draws what was visible last frame, tests the rest against a depth pyramid of it, draws what became visible in the same frame.",
            features: GPU_CULLING_FEATURES, provides: GPU_CULLING_PROVIDES, needs: GPU_CULLING_NEEDS,
        },
        gpu_culling crate::gpu_culling::GpuClusters {
            name: "gpu-clusters",
            description: "GPU cluster culling and level of detail: gpu-occlusion per part, then per cluster of the part's level-of-detail cut (frustum, normal cone, depth pyramid), so the triangles drawn follow the pixels covered.",
            features: GPU_CULLING_FEATURES, provides: GPU_CULLING_PROVIDES, needs: GPU_CULLING_NEEDS,
        },
    ]
}

/// What GPU culling needs of the device: indirect draws of many commands with `firstInstance`
/// (the count the GPU writes is read by `drawIndirectCount` where the submission uses it; a
/// device without it draws the commands by their capacity, `individual-mdi`).
const GPU_CULLING_FEATURES: u64 =
    abi::CADR_FEATURE_MULTI_DRAW_INDIRECT | abi::CADR_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE;
/// What GPU culling offers: replay, frame slots, passes split by the parts' back faces,
/// parameter blocks written before the commands, and empty commands past the counts.
const GPU_CULLING_PROVIDES: u64 = REPLAYABLE
    | KEEPS_FRAME_SLOTS
    | abi::CADR_TRAIT_ROUTES_BACK_FACES
    | abi::CADR_TRAIT_PARAMETER_BLOCKS
    | abi::CADR_TRAIT_EMPTY_COMMAND_TAILS;
/// What GPU culling needs of its partners: a submission that draws its commands, absolute
/// ranges in one scene-wide binding, and parameters found from the instance index.
const GPU_CULLING_NEEDS: u64 = abi::CADR_TRAIT_DRAWS_GPU_COMMANDS
    | abi::CADR_TRAIT_SCENE_SHARES_BINDING
    | abi::CADR_TRAIT_PARAMETERS_FROM_INSTANCE_INDEX;
