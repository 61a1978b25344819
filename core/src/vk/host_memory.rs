//! Counting `VkAllocationCallbacks`: the host memory of every Vulkan object that cadr creates
//! (and, through the plugin ABI, every object a plugin creates) is allocated here. The live
//! count proves that nothing leaks, and with the `fault-injection` feature any of these
//! allocations can be made to fail (`CADR_FAULT=host-memory:N`), as a driver sees it when the
//! process runs out of memory.
//!
//! cadr's own objects share one process-wide count ([`live_object_allocations`]); each plugin
//! technique set gets callbacks of its own counting into its own counter
//! ([`counting_callbacks`]), so that a test can tell which side leaked.

use std::alloc::Layout;
use std::ffi::c_void;
use std::sync::atomic::{AtomicI64, Ordering};

use ash::vk;

use super::fault::{self, FaultKind};

/// Alignment and size kept in front of each allocation.
const HEADER: usize = 16;

/// Zero-byte requests get no memory: they are answered with the (aligned, never mapped) address
/// equal to the alignment, which `free` recognises. Some layers ask for zero bytes and never
/// free them; nothing is then lost.
const ZERO_SIZE_LIMIT: usize = 1 << 16;

/// Live host allocations of cadr's own Vulkan objects.
static CORE_OBJECT_ALLOCATIONS: AtomicI64 = AtomicI64::new(0);

/// The callbacks of cadr's own objects, in a static so that creation and destruction always
/// pass the same ones (Vulkan requires compatible callbacks at both).
struct SharedCallbacks(vk::AllocationCallbacks<'static>);

// SAFETY: the callbacks hold function pointers and a pointer to an atomic counter, all of
// which may be used from any thread.
unsafe impl Sync for SharedCallbacks {}

static CORE_CALLBACKS: SharedCallbacks =
    SharedCallbacks(counting_callbacks(&CORE_OBJECT_ALLOCATIONS));

/// The callbacks of cadr's own command pools: counted like the others, but never failed by
/// fault injection. The driver allocates the memory of recorded commands through them, and
/// Mesa 22.3's lavapipe uses some of it unchecked (vkCmdBindDescriptorSets copies the sets
/// into a failed allocation): an injected failure there crashes the driver instead of
/// testing cadr.
static CORE_COMMAND_POOL_CALLBACKS: SharedCallbacks =
    SharedCallbacks(callbacks::<false>(&CORE_OBJECT_ALLOCATIONS));

/// The callbacks to pass to every `vkCreate*` and `vkDestroy*` of cadr's own objects.
pub(crate) fn core_callbacks() -> Option<&'static vk::AllocationCallbacks<'static>> {
    Some(&CORE_CALLBACKS.0)
}

/// The callbacks to create and destroy cadr's own command pools with (see
/// `CORE_COMMAND_POOL_CALLBACKS`).
pub(crate) fn core_command_pool_callbacks() -> Option<&'static vk::AllocationCallbacks<'static>> {
    Some(&CORE_COMMAND_POOL_CALLBACKS.0)
}

/// Live host allocations of cadr's own Vulkan objects, in the whole process (0 once every
/// device and instance is gone).
pub fn live_object_allocations() -> i64 {
    CORE_OBJECT_ALLOCATIONS.load(Ordering::Relaxed)
}

/// Callbacks that count live allocations into `counter`, which must outlive every object
/// created with them (and be destroyed with the same callbacks).
pub const fn counting_callbacks(counter: *const AtomicI64) -> vk::AllocationCallbacks<'static> {
    callbacks::<true>(counter)
}

/// Counting callbacks whose allocations fault injection may fail (`MAY_FAIL`) or not.
const fn callbacks<const MAY_FAIL: bool>(
    counter: *const AtomicI64,
) -> vk::AllocationCallbacks<'static> {
    vk::AllocationCallbacks {
        p_user_data: counter.cast_mut().cast(),
        pfn_allocation: Some(allocate::<MAY_FAIL>),
        pfn_reallocation: Some(reallocate::<MAY_FAIL>),
        pfn_free: Some(free),
        pfn_internal_allocation: None,
        pfn_internal_free: None,
        _marker: std::marker::PhantomData,
    }
}

fn is_zero_size(memory: *mut c_void) -> bool {
    (memory as usize) <= ZERO_SIZE_LIMIT
}

fn counter(user: *mut c_void) -> Option<&'static AtomicI64> {
    // SAFETY: `user` is null or the counter the callbacks were made with, which outlives them.
    unsafe { user.cast::<AtomicI64>().as_ref() }
}

unsafe extern "system" fn allocate<const MAY_FAIL: bool>(
    user: *mut c_void,
    size: usize,
    alignment: usize,
    _scope: vk::SystemAllocationScope,
) -> *mut c_void {
    if MAY_FAIL && fault::fails(FaultKind::HostMemory) {
        if std::env::var_os(fault::TRACE_ENV).is_some() {
            eprintln!(
                "injected host-memory failure at\n{}",
                std::backtrace::Backtrace::force_capture()
            );
        }
        return std::ptr::null_mut();
    }
    if size == 0 && alignment <= ZERO_SIZE_LIMIT {
        return std::ptr::without_provenance_mut(alignment.max(1));
    }
    let alignment = alignment.max(HEADER);
    let Some(layout) = size
        .checked_add(alignment)
        .and_then(|total| Layout::from_size_align(total, alignment).ok())
    else {
        return std::ptr::null_mut();
    };
    // SAFETY: the layout has a non-zero size.
    let base = unsafe { std::alloc::alloc(layout) };
    if base.is_null() {
        return base.cast();
    }
    // SAFETY: `alignment >= 16` bytes precede the returned pointer: size and alignment go there.
    unsafe {
        let user_pointer = base.add(alignment);
        user_pointer.cast::<usize>().sub(1).write_unaligned(size);
        user_pointer
            .cast::<usize>()
            .sub(2)
            .write_unaligned(alignment);
        if let Some(count) = counter(user) {
            count.fetch_add(1, Ordering::Relaxed);
        }
        user_pointer.cast()
    }
}

unsafe extern "system" fn free(user: *mut c_void, memory: *mut c_void) {
    if memory.is_null() || is_zero_size(memory) {
        return;
    }
    // SAFETY: `memory` came from `allocate`, which stored size and alignment in front.
    unsafe {
        let size = memory.cast::<usize>().sub(1).read_unaligned();
        let alignment = memory.cast::<usize>().sub(2).read_unaligned();
        let base = memory.cast::<u8>().sub(alignment);
        std::alloc::dealloc(
            base,
            Layout::from_size_align_unchecked(size + alignment, alignment),
        );
    }
    if let Some(count) = counter(user) {
        count.fetch_sub(1, Ordering::Relaxed);
    }
}

unsafe extern "system" fn reallocate<const MAY_FAIL: bool>(
    user: *mut c_void,
    original: *mut c_void,
    size: usize,
    alignment: usize,
    scope: vk::SystemAllocationScope,
) -> *mut c_void {
    if original.is_null() || is_zero_size(original) {
        // SAFETY: forwarded (a zero-size original holds nothing to copy).
        return unsafe { allocate::<MAY_FAIL>(user, size, alignment, scope) };
    }
    if size == 0 {
        // SAFETY: forwarded.
        unsafe { free(user, original) };
        return std::ptr::null_mut();
    }
    // SAFETY: forwarded; `original` came from `allocate`. On failure the original stays
    // allocated, as Vulkan requires.
    unsafe {
        let fresh = allocate::<MAY_FAIL>(user, size, alignment, scope);
        if !fresh.is_null() {
            let old_size = original.cast::<usize>().sub(1).read_unaligned();
            std::ptr::copy_nonoverlapping(
                original.cast::<u8>(),
                fresh.cast::<u8>(),
                old_size.min(size),
            );
            free(user, original);
        }
        fresh
    }
}
