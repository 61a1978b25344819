//! Dynamic rendering into one colour and one depth image (and the extra colour targets of a
//! transparency method): the layout transitions before and after, the cleared attachments, and
//! the viewport covering the target. A pass may be suspended (the depth made readable by
//! compute shaders) and resumed, for frames drawn in phases (GPU occlusion culling). An overlay
//! pass draws over the finished colour image without depth (the transparency merge). With
//! MSAA the pass draws into multisampled images and resolves them into the one-sample ones
//! whenever it ends or is suspended (colours averaged, depth by the device's resolve mode), so
//! everything after the pass (readback, overlay, GPU cullers, presentation) reads one sample.

use ash::vk;

use super::{transition, Device, Image};

/// What a pass renders into. Both images are cleared when it begins; the colour image ends in
/// `TRANSFER_SRC_OPTIMAL` for readback or presentation, the depth image too when it is kept.
pub struct RenderingTarget<'a> {
    /// The colour (or id) attachment.
    pub color: &'a Image,
    /// Its clear value.
    pub clear_color: vk::ClearColorValue,
    /// The depth attachment (cleared to 1.0).
    pub depth: &'a Image,
    /// Whether the depth is stored and made readable after the pass.
    pub keep_depth: bool,
    /// Whether the depth is stored (resolved, with MSAA) and left readable by fragment
    /// shaders in `SHADER_READ_ONLY_OPTIMAL` after the pass (screen-space ambient occlusion).
    pub shade_from_depth: bool,
    /// Whether the depth is stored (the pass will be suspended and its depth read); with
    /// MSAA the multisampled colours are then stored too, for the pass to resume on.
    pub store_depth: bool,
    /// The area rendered.
    pub extent: vk::Extent2D,
    /// Whether the pass's contents come from secondary command buffers (which set their own
    /// viewport and scissor).
    pub secondary: bool,
    /// Whether this continues a pass that [`suspend_rendering`] suspended: both attachments
    /// are loaded instead of cleared.
    pub resume: bool,
    /// Colour attachments after the first, with their clear values: cleared when the pass
    /// begins (loaded when it resumes) and left in `SHADER_READ_ONLY_OPTIMAL` for fragment
    /// shaders when it ends.
    pub extra_colors: &'a [(&'a Image, vk::ClearColorValue)],
    /// With MSAA, the images drawn into, resolved into `color`, `depth` and `extra_colors`.
    pub multisampled: Option<Multisampled<'a>>,
}

/// The multisampled attachments of a pass (all of one sample count), each resolved into the
/// one-sample image of the same role.
#[derive(Clone, Copy)]
pub struct Multisampled<'a> {
    /// Drawn into instead of [`RenderingTarget::color`]; averaged into it.
    pub color: &'a Image,
    /// Drawn into instead of [`RenderingTarget::depth`]; resolved into it with `depth_resolve`.
    pub depth: &'a Image,
    /// Drawn into instead of [`RenderingTarget::extra_colors`], in their order; averaged.
    pub extra_colors: &'a [&'a Image],
    /// How the depth is resolved ([`Device::depth_resolve_mode`]).
    pub depth_resolve: vk::ResolveModeFlags,
}

/// Where a resolve writes a one-sample depth image: resolves of every aspect run in the
/// colour attachment output stage as colour attachment writes.
const DEPTH_RESOLVE_WRITE: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw()
            | vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT.as_raw(),
    ),
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
            | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw(),
    ),
);

/// The layout the depth image is in while a pass is suspended.
pub const SUSPENDED_DEPTH_LAYOUT: vk::ImageLayout = vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL;

/// Transitions the target's images for rendering and begins rendering into them.
pub fn begin_rendering(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    target: &RenderingTarget<'_>,
) {
    transition_for_rendering(device, command_buffer, target);
    let load_op = if target.resume {
        vk::AttachmentLoadOp::LOAD
    } else {
        vk::AttachmentLoadOp::CLEAR
    };
    let color_attachment = color_attachments(target, load_op);
    let depth_attachment = depth_attachment(target, load_op);
    let area = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent: target.extent,
    };
    let flags = if target.secondary {
        vk::RenderingFlags::CONTENTS_SECONDARY_COMMAND_BUFFERS
    } else {
        vk::RenderingFlags::empty()
    };
    let rendering = vk::RenderingInfo::default()
        .flags(flags)
        .render_area(area)
        .layer_count(1)
        .color_attachments(&color_attachment)
        .depth_attachment(&depth_attachment);
    // SAFETY: command_buffer is recording; the target's images outlive the submission.
    unsafe { device.raw().cmd_begin_rendering(command_buffer, &rendering) };
    if !target.secondary {
        cover(device, command_buffer, area);
    }
}

/// Transitions the target's images (colour, depth, the multisampled ones and the extra
/// colours) for rendering: freshly, or when the pass resumes, after what it drew before its
/// suspension.
fn transition_for_rendering(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    target: &RenderingTarget<'_>,
) {
    let color_before = if target.resume {
        (
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        )
    } else {
        // The last frame's image may still be copied or blitted (a readback, a window's
        // present) by work submitted before this frame: wait for those reads, not for more.
        (
            vk::ImageLayout::UNDEFINED,
            vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::NONE,
        )
    };
    transition(
        device,
        command_buffer,
        target.color.raw(),
        vk::ImageAspectFlags::COLOR,
        color_before,
        (
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
        ),
    );
    let depth_before = if target.resume {
        (
            SUSPENDED_DEPTH_LAYOUT,
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_SAMPLED_READ,
        )
    } else {
        // Whatever used the depth last, this target's frame or another's that shares it
        // (`offscreen.rs`), may still be running: its depth tests and writes, its resolve, a
        // pick's readback, a GPU culler's pyramid or ambient occlusion reading it.
        (
            vk::ImageLayout::UNDEFINED,
            vk::PipelineStageFlags2::COPY
                | vk::PipelineStageFlags2::FRAGMENT_SHADER
                | vk::PipelineStageFlags2::COMPUTE_SHADER
                | vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
                | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS
                | DEPTH_RESOLVE_WRITE.0,
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE | DEPTH_RESOLVE_WRITE.1,
        )
    };
    let depth_attachment_use = (
        vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | DEPTH_RESOLVE_WRITE.0,
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
            | DEPTH_RESOLVE_WRITE.1,
    );
    transition(
        device,
        command_buffer,
        target.depth.raw(),
        vk::ImageAspectFlags::DEPTH,
        depth_before,
        depth_attachment_use,
    );
    if let Some(multisampled) = &target.multisampled {
        begin_multisampled(device, command_buffer, multisampled, target.resume);
    }
    if !target.resume {
        for (image, _) in target.extra_colors {
            // The last frame's merge may still read them, and its translucent pass (this
            // target's or another's that shares them) write them.
            transition(
                device,
                command_buffer,
                image.raw(),
                vk::ImageAspectFlags::COLOR,
                (
                    vk::ImageLayout::UNDEFINED,
                    vk::PipelineStageFlags2::FRAGMENT_SHADER
                        | vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                ),
                (
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE
                        | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
                ),
            );
        }
    }
}

/// The colour attachments of a rendering into `target`: the picture and the extra colours,
/// drawn into their multisampled images and resolved into them where the target has those.
fn color_attachments<'a>(
    target: &RenderingTarget<'a>,
    load_op: vk::AttachmentLoadOp,
) -> Vec<vk::RenderingAttachmentInfo<'a>> {
    std::iter::once((target.color, target.clear_color))
        .chain(target.extra_colors.iter().copied())
        .enumerate()
        .map(|(i, (image, clear))| {
            let info = vk::RenderingAttachmentInfo::default()
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(load_op)
                .clear_value(vk::ClearValue { color: clear });
            let drawn = target.multisampled.as_ref().and_then(|m| {
                if i == 0 {
                    Some(m.color)
                } else {
                    m.extra_colors.get(i - 1).copied()
                }
            });
            match drawn {
                // A multisampled colour is kept only while the pass is resumed later.
                Some(drawn) => info
                    .image_view(drawn.view())
                    .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                    .resolve_image_view(image.view())
                    .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .store_op(if target.store_depth {
                        vk::AttachmentStoreOp::STORE
                    } else {
                        vk::AttachmentStoreOp::DONT_CARE
                    }),
                None => info
                    .image_view(image.view())
                    .store_op(vk::AttachmentStoreOp::STORE),
            }
        })
        .collect()
}

/// The depth attachment of a rendering into `target` (the multisampled depth, resolved into
/// the one-sample one where a later phase or pass reads it).
fn depth_attachment<'a>(
    target: &RenderingTarget<'a>,
    load_op: vk::AttachmentLoadOp,
) -> vk::RenderingAttachmentInfo<'a> {
    let mut depth_attachment = vk::RenderingAttachmentInfo::default()
        .image_view(target.depth.view())
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(load_op)
        // A suspended pass reads its depth, so every pass but a last unkept one stores it.
        .store_op(
            if target.keep_depth || target.store_depth || target.shade_from_depth {
                vk::AttachmentStoreOp::STORE
            } else {
                vk::AttachmentStoreOp::DONT_CARE
            },
        )
        .clear_value(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        });
    if let Some(multisampled) = &target.multisampled {
        depth_attachment = depth_attachment.image_view(multisampled.depth.view());
        if target.store_depth || target.shade_from_depth || target.keep_depth {
            // GPU cullers read the depth between phases, ambient occlusion after the pass, a
            // host after the frame: the one-sample depth receives it.
            depth_attachment = depth_attachment
                .resolve_mode(multisampled.depth_resolve)
                .resolve_image_view(target.depth.view())
                .resolve_image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
        }
    }
    depth_attachment
}

/// Makes the multisampled attachments ready to draw into: freshly (the last frame's pass may
/// still draw into them) or, when the pass resumes, after what it drew before its suspension.
fn begin_multisampled(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    multisampled: &Multisampled<'_>,
    resume: bool,
) {
    let color_stage = vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT;
    let color_use = (
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        color_stage,
        vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
    );
    // Fresh: after whatever drew into or resolved from them last, this target's frame or
    // another's that shares them (`offscreen.rs`).
    let color_before = if resume {
        color_use
    } else {
        (
            vk::ImageLayout::UNDEFINED,
            color_stage,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        )
    };
    for image in
        std::iter::once(multisampled.color).chain(multisampled.extra_colors.iter().copied())
    {
        transition(
            device,
            command_buffer,
            image.raw(),
            vk::ImageAspectFlags::COLOR,
            color_before,
            color_use,
        );
    }
    let depth_stages = vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
        | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS
        | vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT;
    let depth_use = (
        vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
        depth_stages,
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
    );
    let depth_before = if resume {
        depth_use
    } else {
        (
            vk::ImageLayout::UNDEFINED,
            depth_stages,
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
        )
    };
    transition(
        device,
        command_buffer,
        multisampled.depth.raw(),
        vk::ImageAspectFlags::DEPTH,
        depth_before,
        depth_use,
    );
}

/// Sets the viewport (depth 0..1) and scissor to `area`, inside rendering.
fn cover(device: &Device, command_buffer: vk::CommandBuffer, area: vk::Rect2D) {
    let viewport = [vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: area.extent.width as f32,
        height: area.extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    }];
    // SAFETY: command_buffer is recording inside rendering.
    unsafe {
        device.raw().cmd_set_viewport(command_buffer, 0, &viewport);
        device.raw().cmd_set_scissor(command_buffer, 0, &[area]);
    }
}

/// Suspends rendering begun by [`begin_rendering`] (with `store_depth`): ends it and makes the
/// depth readable by compute shaders in [`SUSPENDED_DEPTH_LAYOUT`]; the colour image stays an
/// attachment. Resume with `resume` set.
pub fn suspend_rendering(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    target: &RenderingTarget<'_>,
) {
    // SAFETY: rendering was begun by begin_rendering on this command buffer.
    unsafe { device.raw().cmd_end_rendering(command_buffer) };
    transition(
        device,
        command_buffer,
        target.depth.raw(),
        vk::ImageAspectFlags::DEPTH,
        (
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            DEPTH_RESOLVE_WRITE.0,
            DEPTH_RESOLVE_WRITE.1,
        ),
        (
            SUSPENDED_DEPTH_LAYOUT,
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_SAMPLED_READ,
        ),
    );
}

/// Ends rendering begun by [`begin_rendering`] on `command_buffer` and makes the colour image
/// (and the depth, when kept) ready to be copied from.
pub fn end_rendering(
    device: &Device,
    command_buffer: vk::CommandBuffer,
    target: &RenderingTarget<'_>,
) {
    // SAFETY: rendering was begun by begin_rendering on this command buffer.
    unsafe { device.raw().cmd_end_rendering(command_buffer) };
    color_ready_to_copy(device, command_buffer, target.color);
    for (image, _) in target.extra_colors {
        transition(
            device,
            command_buffer,
            image.raw(),
            vk::ImageAspectFlags::COLOR,
            (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            ),
            (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
                vk::AccessFlags2::SHADER_SAMPLED_READ,
            ),
        );
    }
    // What reads the depth after the pass: ambient occlusion's fragment shader, or the pick
    // readback's copy.
    let depth_reader = if target.shade_from_depth {
        Some((
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            vk::PipelineStageFlags2::FRAGMENT_SHADER,
            vk::AccessFlags2::SHADER_SAMPLED_READ,
        ))
    } else if target.keep_depth {
        Some((
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::PipelineStageFlags2::COPY,
            vk::AccessFlags2::TRANSFER_READ,
        ))
    } else {
        None
    };
    if let Some(reader) = depth_reader {
        transition(
            device,
            command_buffer,
            target.depth.raw(),
            vk::ImageAspectFlags::DEPTH,
            (
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
                DEPTH_RESOLVE_WRITE.0,
                DEPTH_RESOLVE_WRITE.1,
            ),
            reader,
        );
    }
}

/// Begins rendering over `color`, a finished picture in `TRANSFER_SRC_OPTIMAL` (as
/// [`end_rendering`] leaves it): loaded, no depth, the viewport covering it.
pub fn begin_overlay(device: &Device, command_buffer: vk::CommandBuffer, color: &Image) {
    transition(
        device,
        command_buffer,
        color.raw(),
        vk::ImageAspectFlags::COLOR,
        // Chained to end_rendering's transition (whose second scope is copies and blits).
        (
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::NONE,
        ),
        (
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ,
        ),
    );
    let attachment = [vk::RenderingAttachmentInfo::default()
        .image_view(color.view())
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::LOAD)
        .store_op(vk::AttachmentStoreOp::STORE)];
    let area = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent: color.extent(),
    };
    let rendering = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(&attachment);
    // SAFETY: command_buffer is recording outside rendering; the image outlives the submission.
    unsafe { device.raw().cmd_begin_rendering(command_buffer, &rendering) };
    cover(device, command_buffer, area);
}

/// Ends an overlay begun by [`begin_overlay`]: the colour image is ready to be copied from
/// again, as [`end_rendering`] leaves it.
pub fn end_overlay(device: &Device, command_buffer: vk::CommandBuffer, color: &Image) {
    // SAFETY: rendering was begun by begin_overlay on this command buffer.
    unsafe { device.raw().cmd_end_rendering(command_buffer) };
    color_ready_to_copy(device, command_buffer, color);
}

/// Moves a colour attachment that was just drawn into `TRANSFER_SRC_OPTIMAL`: read back by a
/// copy, or blitted into a window's image by a later submission.
fn color_ready_to_copy(device: &Device, command_buffer: vk::CommandBuffer, color: &Image) {
    transition(
        device,
        command_buffer,
        color.raw(),
        vk::ImageAspectFlags::COLOR,
        (
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        ),
        (
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::BLIT,
            vk::AccessFlags2::TRANSFER_READ,
        ),
    );
}
