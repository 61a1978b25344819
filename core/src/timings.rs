//! Where a process's time goes before and around its first picture: instance and device
//! creation, loading, building the scene, uploading it, compiling shaders, creating pipelines,
//! the first frame, reading it back and encoding the PNG.
//!
//! Each phase is measured where it happens (`Device::new`, the loaders, the graph and tree
//! builders, the GPU scene upload, the shader cache, the pipeline constructors, the first frame
//! of each renderer, the readback and the PNG writer), so `cadr render --timings` and
//! `cadr_timings` in the C API report the same figures. Totals are process-wide and
//! exclusive: a phase that runs inside another (pipelines built during the first frame) counts
//! only for itself, so the phases add up to at most the wall time.

use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// A phase of a process's work.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phase {
    /// Vulkan instance and device creation (with the validation layers when asked).
    Device,
    /// Reading and parsing scene files, or generating a scene.
    Load,
    /// Flattening the scene and building the scene graph and tree.
    SceneBuild,
    /// Uploading the scene to the GPU.
    Upload,
    /// Compiling shaders (or reading them from the disk cache).
    ShaderCompile,
    /// Creating pipelines.
    PipelineCreation,
    /// A renderer's first frame, less the shaders and pipelines it built.
    FirstFrame,
    /// Reading a picture back from the GPU.
    Readback,
    /// Encoding and writing PNG files.
    PngEncode,
}

impl Phase {
    /// Every phase, in the order a run meets them.
    pub const ALL: [Phase; 9] = [
        Phase::Device,
        Phase::Load,
        Phase::SceneBuild,
        Phase::Upload,
        Phase::ShaderCompile,
        Phase::PipelineCreation,
        Phase::FirstFrame,
        Phase::Readback,
        Phase::PngEncode,
    ];

    /// A short name for tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Device => "device",
            Phase::Load => "load",
            Phase::SceneBuild => "scene build",
            Phase::Upload => "upload",
            Phase::ShaderCompile => "shader compile",
            Phase::PipelineCreation => "pipeline creation",
            Phase::FirstFrame => "first frame",
            Phase::Readback => "readback",
            Phase::PngEncode => "png encode",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Nanoseconds spent in each phase by the whole process.
static TOTALS: [AtomicU64; Phase::ALL.len()] = [const { AtomicU64::new(0) }; Phase::ALL.len()];

thread_local! {
    /// Time measured on this thread by the phases running now, which the phase around them
    /// subtracts from its own.
    static NESTED: Cell<Duration> = const { Cell::new(Duration::ZERO) };
}

/// Runs `work` as `phase`: its wall time, less that of phases measured inside it on this
/// thread, is added to the phase's total.
pub fn time<T>(phase: Phase, work: impl FnOnce() -> T) -> T {
    let nested_before = NESTED.with(Cell::get);
    let start = Instant::now();
    let result = work();
    let elapsed = start.elapsed();
    let nested_inside = NESTED.with(Cell::get).saturating_sub(nested_before);
    record(phase, elapsed.saturating_sub(nested_inside));
    NESTED.with(|nested| nested.set(nested_before + elapsed));
    result
}

/// Adds `duration` to `phase` (for work not wrapped by [`time`]).
pub fn record(phase: Phase, duration: Duration) {
    let nanos = u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX);
    TOTALS[phase.index()].fetch_add(nanos, Ordering::Relaxed);
}

/// The totals so far.
pub fn snapshot() -> PhaseTimes {
    PhaseTimes {
        nanos: std::array::from_fn(|i| TOTALS[i].load(Ordering::Relaxed)),
    }
}

/// Forgets the totals (for a host that measures one stretch of its run).
pub fn reset() {
    for total in &TOTALS {
        total.store(0, Ordering::Relaxed);
    }
}

/// Time spent in each phase.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhaseTimes {
    nanos: [u64; Phase::ALL.len()],
}

impl PhaseTimes {
    /// The time spent in `phase`.
    pub fn get(&self, phase: Phase) -> Duration {
        Duration::from_nanos(self.nanos[phase.index()])
    }

    /// Milliseconds spent in `phase`.
    pub fn ms(&self, phase: Phase) -> f64 {
        self.get(phase).as_secs_f64() * 1e3
    }

    /// The sum over every phase.
    pub fn total(&self) -> Duration {
        Duration::from_nanos(self.nanos.iter().sum())
    }

    /// What was spent after `earlier` was taken.
    pub fn since(&self, earlier: &PhaseTimes) -> PhaseTimes {
        PhaseTimes {
            nanos: std::array::from_fn(|i| self.nanos[i].saturating_sub(earlier.nanos[i])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_phases_count_only_for_themselves() {
        let before = snapshot();
        time(Phase::FirstFrame, || {
            std::thread::sleep(Duration::from_millis(20));
            time(Phase::PipelineCreation, || {
                std::thread::sleep(Duration::from_millis(300));
            });
        });
        let spent = snapshot().since(&before);
        let frame = spent.get(Phase::FirstFrame);
        let pipelines = spent.get(Phase::PipelineCreation);
        // Other tests may add to the totals at the same time, never take from them.
        assert!(pipelines >= Duration::from_millis(300), "{pipelines:?}");
        assert!(frame >= Duration::from_millis(20), "{frame:?}");
        assert!(
            frame < Duration::from_millis(200),
            "the nested 300 ms must not count twice: {frame:?}"
        );
    }
}
