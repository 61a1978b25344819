//! Counting the heap memory cadr's own code holds: a global allocator that forwards to the
//! system's and keeps the bytes in use. The program that links cadr installs it
//! (`#[global_allocator]`: `libcadr.so` and the `cadr` command do); then every allocation of
//! cadr's Rust code counts, and so does the host memory of every Vulkan object cadr creates,
//! which the drivers allocate through cadr's allocation callbacks
//! ([`crate::vk`]'s `host_memory`), themselves allocating here.
//!
//! What it does not count: a driver's memory allocated without the callbacks (on a CPU driver
//! such as lavapipe, the "device" memory, compiled shaders and the rasterizer's working
//! memory, all in the process's heap), the technique plugins' own heaps, and the host
//! program's. That is what makes it the measure of what cadr itself holds on the host, where
//! the process's heap mixes in the driver's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

/// Bytes allocated through [`CountingAllocator`] and not yet freed.
static BYTES_IN_USE: AtomicU64 = AtomicU64::new(0);

/// The most [`BYTES_IN_USE`] has reached since the start or the last [`reset_peak`].
static PEAK_BYTES: AtomicU64 = AtomicU64::new(0);

/// Counts `bytes` more in use, and the peak.
fn count_allocated(bytes: usize) {
    let now = BYTES_IN_USE.fetch_add(bytes as u64, Ordering::Relaxed) + bytes as u64;
    PEAK_BYTES.fetch_max(now, Ordering::Relaxed);
}

/// The system's allocator, counting the bytes in use.
pub struct CountingAllocator;

// SAFETY: every call is forwarded to `System` with the caller's layout and pointer; the
// counter only observes sizes.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded under the caller's contract.
        let pointer = unsafe { System.alloc(layout) };
        if !pointer.is_null() {
            count_allocated(layout.size());
        }
        pointer
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded under the caller's contract.
        let pointer = unsafe { System.alloc_zeroed(layout) };
        if !pointer.is_null() {
            count_allocated(layout.size());
        }
        pointer
    }

    unsafe fn dealloc(&self, pointer: *mut u8, layout: Layout) {
        // SAFETY: forwarded under the caller's contract (allocated here with `layout`).
        unsafe { System.dealloc(pointer, layout) };
        BYTES_IN_USE.fetch_sub(layout.size() as u64, Ordering::Relaxed);
    }

    unsafe fn realloc(&self, pointer: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded under the caller's contract.
        let moved = unsafe { System.realloc(pointer, layout, new_size) };
        if !moved.is_null() {
            count_allocated(new_size);
            BYTES_IN_USE.fetch_sub(layout.size() as u64, Ordering::Relaxed);
        }
        moved
    }
}

/// Bytes of heap memory cadr holds now in this process (see the module's documentation); 0
/// where the program did not install [`CountingAllocator`].
pub fn bytes_in_use() -> u64 {
    BYTES_IN_USE.load(Ordering::Relaxed)
}

/// The most bytes cadr held at once since the program started or since [`reset_peak`]; 0 where
/// the program did not install [`CountingAllocator`].
pub fn peak_bytes_in_use() -> u64 {
    PEAK_BYTES.load(Ordering::Relaxed)
}

/// Starts measuring the peak again from the bytes in use now.
pub fn reset_peak() {
    PEAK_BYTES.store(bytes_in_use(), Ordering::Relaxed);
}
