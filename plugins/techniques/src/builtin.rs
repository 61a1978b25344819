//! The built-in technique library: the simplest technique of each kind, the seeds' baseline
//! (one draw per part, vertex buffers re-bound per geometry, matrix and material pushed per
//! draw, no culling). Hosts register it statically, so it works without any plugin library;
//! every other technique is measured against it.

use crate::{KEEPS_FRAME_SLOTS, REPLAYABLE, SHARES_PIPELINES};
use cadr_plugin_sdk::abi;
use cadr_plugin_sdk::technique_library;

use crate::culling::NoCulling;
use crate::parameters::Push;
use crate::submission::Individual;
use crate::transparency::WeightedBlended;
use crate::vertex::{PerGeometry, GEOMETRY};

/// The name the built-in library describes itself with.
pub const LIBRARY_NAME: &str = "cadr built-in techniques";

technique_library! {
    pub fn entry;
    library: "cadr built-in techniques",
    techniques: [
        vertex PerGeometry {
            name: "per-geometry",
            description: "Vertex and index buffers bound per geometry, re-bound only when the geometry changes.",
            features: 0, provides: GEOMETRY | REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES, needs: 0,
        },
        parameters Push {
            name: "push",
            description: "Matrix and material values pushed with every draw (push constants; the seeds' glUniform/ubosub); with dgc and a gpu- culler, the GPU writes them into the command stream.",
            features: 0,
            provides: abi::CADR_TRAIT_PARAMETERS_IN_COMMANDS | abi::CADR_TRAIT_PARAMETER_BLOCKS | abi::CADR_TRAIT_READS_HOST_MATRICES | abi::CADR_TRAIT_REPLAYABLE | KEEPS_FRAME_SLOTS | SHARES_PIPELINES,
            needs: 0,
        },
        submission Individual {
            name: "individual",
            description: "One vkCmdDrawIndexed per part in scene order, recorded every frame (the seeds' baseline strategy).",
            features: 0, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
        culling NoCulling {
            name: "none",
            description: "No culling: every visible part is drawn.",
            features: 0, provides: REPLAYABLE | abi::CADR_TRAIT_CULLS_WHATEVER_THE_VIEW | KEEPS_FRAME_SLOTS, needs: 0,
        },
        transparency WeightedBlended {
            name: "weighted-blended",
            description: "Weighted blended order-independent transparency (McGuire and Bavoil): one pass, exact for one layer, approximate where layers overlap.",
            features: 0, provides: REPLAYABLE | KEEPS_FRAME_SLOTS, needs: 0,
        },
    ]
}
