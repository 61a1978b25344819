//! The Vulkan layer on its own: device choice, staging uploads and readbacks of buffers and
//! images, all with validation on.

use cadr_core::vk::{
    raw as vk, read_image, Buffer, DepthSharing, DeviceChoice, Image, MemoryLocation,
    OffscreenTarget,
};
use cadr_tests::{assert_no_validation_errors, test_device};

#[test]
fn image_upload_and_readback_round_trip() {
    let device = test_device();
    let extent = vk::Extent2D {
        width: 37,
        height: 11,
    };
    let pixels: Vec<u8> = (0..extent.width * extent.height * 4)
        .map(|i| (i * 7 % 251) as u8)
        .collect();
    let image = Image::with_rgba8(
        &device,
        "round trip",
        extent,
        &pixels,
        vk::ImageUsageFlags::TRANSFER_SRC,
    )
    .expect("upload");
    let back =
        read_image(&device, &image, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL).expect("read back");
    assert_eq!(back, pixels);
    let error = Image::with_rgba8(
        &device,
        "short",
        extent,
        &pixels[..10],
        vk::ImageUsageFlags::empty(),
    )
    .err()
    .expect("too few pixels is refused");
    assert!(
        error.to_string().contains("10 bytes of texels for 37x11"),
        "{error}"
    );
    drop(image);
    assert_no_validation_errors(&device);
}

#[test]
fn buffer_upload_lands_in_device_memory() {
    let device = test_device();
    let data: Vec<u8> = (0..4096_u32).flat_map(|i| i.to_le_bytes()).collect();
    let source = Buffer::with_data(
        &device,
        "uploaded",
        &data,
        vk::BufferUsageFlags::TRANSFER_SRC,
    )
    .expect("upload");
    // Copy it back into a host-visible buffer to check the staging path end to end.
    let readback = Buffer::new(
        &device,
        "check",
        data.len() as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )
    .expect("readback buffer");
    let mut one_shot = cadr_core::vk::OneShot::begin(&device, "copy back").expect("command buffer");
    let region = [vk::BufferCopy::default().size(data.len() as u64)];
    // SAFETY: both buffers live until the wait below; the sizes match.
    unsafe {
        device.raw().cmd_copy_buffer(
            one_shot.command_buffer(),
            source.raw(),
            readback.raw(),
            &region,
        )
    };
    one_shot.submit_and_wait().expect("submit");
    assert_eq!(readback.mapped().expect("mapped"), &data[..]);
    assert_no_validation_errors(&device);
}

#[test]
fn device_choice_by_name_and_index() {
    assert_eq!(DeviceChoice::parse("1"), DeviceChoice::Index(1));
    assert_eq!(
        DeviceChoice::parse(" llvmpipe "),
        DeviceChoice::NameContains("llvmpipe".into())
    );
    let device = test_device();
    let name = device.adapter().name.clone();
    let instance = std::sync::Arc::clone(device.instance());
    let fragment = name
        .split_whitespace()
        .next()
        .expect("a name")
        .to_uppercase();
    let by_name = cadr_core::vk::Device::with_instance(
        instance.clone(),
        &DeviceChoice::NameContains(fragment),
    )
    .expect("choose by name");
    assert_eq!(by_name.adapter().name, name);
    let error = cadr_core::vk::Device::with_instance(
        instance,
        &DeviceChoice::NameContains("no such gpu".into()),
    )
    .err()
    .expect("an unknown name is refused");
    assert!(error.to_string().contains("available: 0:"), "{error}");
}

#[test]
fn offscreen_target_sizes_are_checked() {
    let device = test_device();
    let error = OffscreenTarget::new(&device, (0, 10), 1, DepthSharing::Own)
        .err()
        .expect("zero width is refused");
    assert!(error.to_string().contains("0x10"), "{error}");
    let target =
        OffscreenTarget::new(&device, (3, 2), 1, DepthSharing::Own).expect("a tiny target");
    assert_eq!((target.extent().width, target.extent().height), (3, 2));
    assert_eq!(target.samples(), 1);
    // Every device offers one sample; 3 is no sample count at all.
    assert_eq!(device.sample_counts().first(), Some(&1));
    let error = OffscreenTarget::new(&device, (4, 4), 3, DepthSharing::Own)
        .err()
        .expect("3 samples per pixel are refused");
    assert!(error.to_string().contains("3 samples per pixel"), "{error}");
    for &samples in device.sample_counts().iter().skip(1) {
        let target = OffscreenTarget::new(&device, (4, 4), samples, DepthSharing::Own)
            .expect("an MSAA target");
        assert_eq!(target.samples(), samples);
    }
    assert_no_validation_errors(&device);
}

#[test]
fn buffer_misuse_is_an_error_not_a_panic() {
    let device = test_device();
    let mut host = Buffer::new(
        &device,
        "host",
        16,
        vk::BufferUsageFlags::UNIFORM_BUFFER,
        MemoryLocation::CpuToGpu,
    )
    .expect("host buffer");
    host.write(8, &[1; 8]).expect("in range");
    let error = host
        .write(12, &[1; 8])
        .expect_err("out of range is refused");
    assert!(
        error
            .to_string()
            .contains("bytes 12..20 of a 16-byte buffer"),
        "{error}"
    );
    assert_no_validation_errors(&device);
}
