//! The validation canary: a deliberately invalid Vulkan call must be recorded as an error, so
//! that "zero validation errors" in the other tests means something.

use cadr_core::vk::raw as vk;
use cadr_tests::test_device;

#[test]
fn invalid_usage_is_reported_as_a_validation_error() {
    let device = test_device();
    assert!(device.validation_log().errors().is_empty());
    // A buffer of size 0 violates VUID-VkBufferCreateInfo-size-00912.
    let info = vk::BufferCreateInfo::default()
        .size(0)
        .usage(vk::BufferUsageFlags::VERTEX_BUFFER);
    // SAFETY: deliberately invalid parameters for the canary; the layer reports them, and the
    // handle (if any) is destroyed right away.
    unsafe {
        if let Ok(buffer) = device.raw().create_buffer(&info, None) {
            device.raw().destroy_buffer(buffer, None);
        }
    }
    let errors = device.validation_log().errors();
    assert!(
        errors.iter().any(|e| e.contains("00912")),
        "the canary was not caught: {errors:?}"
    );
}
