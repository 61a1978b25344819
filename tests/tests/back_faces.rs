//! Closed parts drawn with their back faces culled by the rasterizer: the GPU cullers route
//! them into a pass of their own (`CadrBackFacePasses`), and the picture is the one drawing
//! both faces of every part shows, also where back faces can show: an open part seen from
//! inside, an inside-out mesh, a mirrored copy, a part a section plane cuts, a part holding the
//! eye, and in the edge modes: edges over the surfaces, caps painted over the lines of a cut,
//! hidden-line (depth-only surfaces), and hidden-line with dashed hidden lines, whose frame has
//! no room for the split.
#![allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.

use cadr_core::technique::ShadeMode;
use cadr_tests::back_face_cases::{draw, CASES};
use cadr_tests::images::{compare, SAME_PICTURE};

#[test]
fn closed_parts_drawn_without_back_faces_look_as_with_them_and_the_others_keep_theirs() {
    for case in &CASES {
        // No culler: every part in one pass, both faces drawn.
        let (reference, all) = draw(case, "individual-indirect-count", "none");
        for culling in ["gpu-frustum", "gpu-occlusion", "gpu-clusters"] {
            let (image, stats) = draw(case, "individual-indirect-count", culling);
            let difference = compare(&image, &reference).unwrap();
            assert!(
                difference.within(SAME_PICTURE),
                "{}, {culling}: {difference:?}",
                case.name
            );
            // The solid surfaces are split in two passes, each with its own pipeline, in every
            // phase of the culler (gpu-occlusion and gpu-clusters draw in two).
            if case.mode == ShadeMode::Solid {
                let phases = if culling == "gpu-frustum" { 1 } else { 2 };
                assert_eq!(
                    stats.pipeline_binds,
                    phases * (all.pipeline_binds + 1),
                    "{}, {culling}: two surface pipelines in each phase",
                    case.name
                );
            } else if culling == "gpu-frustum" {
                // One phase, and the passes over the picture bound once: the split's pass is
                // one bind more, where the frame has room for it.
                assert_eq!(
                    stats.pipeline_binds,
                    all.pipeline_binds + u64::from(case.split),
                    "{}, {culling}: the surfaces split {}",
                    case.name,
                    if case.split { "in two" } else { "not at all" }
                );
            }
        }
    }
}
