//! Giving memory the process freed back to the system. glibc keeps what a program frees in
//! its arenas (one per thread that allocates: cadr's workers, the driver's queue threads) for
//! later allocations, and each time a transient allocation no longer fits in what it kept, the
//! resident size steps up and stays: a CAD tool that loads and unloads models all day ends up
//! holding the peak of its largest loads in every arena, though cadr's live heap is flat
//! (`docs/BENCHMARKS.md`, the soak). So after a scene sync that uploaded much geometry or
//! refreshed many instances (a model loaded or unloaded), once its transient buffers are
//! freed, cadr asks the allocator to return the free pages of every arena, at most once a
//! second.

use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Bytes of geometry a sync must upload, or instance entries it must refresh, for cadr to
/// return freed memory after it: loads and unloads of models, not the few parts a host edits
/// frame by frame.
pub const RETURN_AFTER_UPLOAD_BYTES: u64 = 8 << 20;
/// See [`RETURN_AFTER_UPLOAD_BYTES`].
pub const RETURN_AFTER_INSTANCES: u64 = 1024;
/// The least time between two returns: returning walks the heap and gives back pages that a
/// host changing thousands of parts every frame would fault in again.
pub const RETURN_AT_MOST_EVERY: Duration = Duration::from_secs(1);

/// When memory was last returned (process-wide, as the allocator is).
static LAST_RETURN: Mutex<Option<Instant>> = Mutex::new(None);

/// Returns the pages the C allocator keeps free, in every arena, to the system (glibc's
/// `malloc_trim`); elsewhere nothing. Any thread may call it; it costs a walk of the heap's
/// free chunks, so call it after large transient work only.
pub fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn malloc_trim(pad: usize) -> std::ffi::c_int;
        }
        // SAFETY: glibc's `malloc_trim` takes the padding to keep and touches only the
        // allocator's own state, under the allocator's locks.
        unsafe { malloc_trim(0) };
    }
}

/// Whether a sync that uploaded `geometry_bytes` of geometry and refreshed `instances` instance
/// entries is large enough to be a load or an unload.
pub fn is_large(geometry_bytes: u64, instances: u64) -> bool {
    geometry_bytes >= RETURN_AFTER_UPLOAD_BYTES || instances >= RETURN_AFTER_INSTANCES
}

/// Whether memory last returned at `last` may be returned again at `now`.
fn may_return(last: Option<Instant>, now: Instant) -> bool {
    last.is_none_or(|last| now.saturating_duration_since(last) >= RETURN_AT_MOST_EVERY)
}

/// [`return_freed_memory`] after a scene sync where it [`is_large`], unless memory was
/// returned less than [`RETURN_AT_MOST_EVERY`] ago. Returns whether it did.
pub fn after_sync(geometry_bytes: u64, instances: u64) -> bool {
    if !is_large(geometry_bytes, instances) {
        return false;
    }
    let now = Instant::now();
    {
        let mut last = LAST_RETURN
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if !may_return(*last, now) {
            return false;
        }
        *last = Some(now);
    }
    return_freed_memory();
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_loads_and_unloads_return_memory() {
        assert!(!is_large(0, 0));
        assert!(!is_large(
            RETURN_AFTER_UPLOAD_BYTES - 1,
            RETURN_AFTER_INSTANCES - 1
        ));
        assert!(is_large(RETURN_AFTER_UPLOAD_BYTES, 0));
        assert!(is_large(0, RETURN_AFTER_INSTANCES));
    }

    #[test]
    fn memory_is_returned_at_most_once_a_second() {
        let start = Instant::now();
        assert!(may_return(None, start));
        assert!(!may_return(Some(start), start + Duration::from_millis(999)));
        assert!(may_return(Some(start), start + RETURN_AT_MOST_EVERY));
    }

    /// Resident bytes of this process (`/proc/self/statm`).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn resident_bytes() -> u64 {
        let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
        let pages: u64 = statm
            .split_whitespace()
            .nth(1)
            .and_then(|field| field.parse().ok())
            .unwrap_or(0);
        pages * 4096
    }

    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn freed_memory_kept_in_a_threads_arena_goes_back_to_the_system() {
        // 64 MiB in small blocks (below the allocator's mmap threshold, so they stay in the
        // thread's arena when freed), written so that they are resident; every sixteenth is
        // kept, so that the freed ones lie between live blocks, where the allocator does not
        // give them back by itself as it does with the free end of an arena.
        let kept = std::thread::spawn(|| {
            let blocks: Vec<Vec<u8>> = (0..16_384).map(|_| vec![1u8; 4096]).collect();
            blocks.into_iter().step_by(16).collect::<Vec<_>>()
        })
        .join()
        .expect("the allocating thread");
        let before = resident_bytes();
        return_freed_memory();
        let after = resident_bytes();
        assert!(
            before.saturating_sub(after) >= 32 << 20,
            "resident {before} bytes before returning freed memory, {after} after"
        );
        drop(kept);
    }
}
