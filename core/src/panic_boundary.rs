//! The last line of defence around reading files: a panic while a file is read (in cadr's
//! readers or in a dependency such as the glTF or image crates) is caught at the load's
//! boundary and becomes an error that names the file, so that a host never unwinds into its own
//! code and the command line never prints a backtrace for a bad file.
//!
//! A caught panic is still a bug: its message and location are kept in [`CaughtPanic`] (the
//! loader logs them), and the fuzz targets fail on it as they fail on an uncaught one.
//!
//! How the location is kept: the first [`catch`] installs a process-wide panic hook that wraps
//! the one installed before it. A panic on a thread inside a boundary (the thread that called
//! [`catch`], or a worker of [`crate::parallel`] started from it) is recorded for the boundary
//! and not printed; every other panic goes to the previous hook as before. A host that installs
//! its own hook after cadr's replaces this one: panics are still caught, but their location is
//! then unknown and the host's hook reports them.

use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Mutex, Once};

/// A panic caught at a boundary: what it said and where it was raised.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CaughtPanic {
    /// The panic's message (its payload, when that is a string).
    pub message: String,
    /// `file:line:column` of the code that panicked, when the hook saw it.
    pub location: Option<String>,
}

impl std::fmt::Display for CaughtPanic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.location {
            Some(location) => write!(f, "panicked at {location}: {}", self.message),
            None => write!(f, "panicked: {}", self.message),
        }
    }
}

/// Where the hook records the first panic raised inside one boundary (shared by its workers).
type Report = Arc<Mutex<Option<CaughtPanic>>>;

thread_local! {
    /// The boundary this thread runs inside, if any.
    static BOUNDARY: RefCell<Option<Report>> = const { RefCell::new(None) };
}

/// Runs `work`, turning a panic inside it (on this thread or on a worker it starts through
/// [`crate::parallel`]) into a [`CaughtPanic`]. Boundaries nest: a panic is reported to the
/// innermost one.
pub fn catch<R>(work: impl FnOnce() -> R) -> Result<R, CaughtPanic> {
    install_hook();
    let report: Report = Arc::default();
    let outcome = {
        let _inside = Entered::new(Some(report.clone()));
        catch_unwind(AssertUnwindSafe(work))
    };
    outcome.map_err(|payload| {
        let recorded = report.lock().ok().and_then(|mut slot| slot.take());
        recorded.unwrap_or_else(|| CaughtPanic {
            message: payload_text(payload.as_ref()),
            location: None,
        })
    })
}

/// The boundary of the calling thread, to be entered by a worker thread it starts
/// ([`Inherited::enter`]), so that a panic on the worker is reported to the same boundary.
pub(crate) fn inherit() -> Inherited {
    Inherited(BOUNDARY.with(|boundary| boundary.borrow().clone()))
}

/// A boundary handed from a thread to the workers it starts; see [`inherit`].
pub(crate) struct Inherited(Option<Report>);

impl Inherited {
    /// Makes the calling (worker) thread part of the boundary until the guard is dropped.
    pub(crate) fn enter(&self) -> impl Drop {
        Entered::new(self.0.clone())
    }
}

/// While alive, the thread runs inside `report`'s boundary; dropping it restores the one the
/// thread was in before (boundaries nest).
struct Entered {
    previous: Option<Report>,
}

impl Entered {
    fn new(report: Option<Report>) -> Self {
        let previous = BOUNDARY.with(|boundary| boundary.replace(report));
        Self { previous }
    }
}

impl Drop for Entered {
    fn drop(&mut self) {
        let previous = self.previous.take();
        BOUNDARY.with(|boundary| *boundary.borrow_mut() = previous);
    }
}

/// Installs, once per process, the hook that records panics raised inside a boundary and
/// hands every other panic to the hook that was installed before.
fn install_hook() {
    static INSTALLED: Once = Once::new();
    INSTALLED.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            // `try_with`: a panic while the thread's locals are being destroyed has no boundary.
            let boundary = BOUNDARY
                .try_with(|boundary| boundary.try_borrow().ok().and_then(|b| b.clone()))
                .ok()
                .flatten();
            let Some(report) = boundary else {
                previous(info);
                return;
            };
            let caught = CaughtPanic {
                message: payload_text(info.payload()),
                location: info
                    .location()
                    .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column())),
            };
            // The first panic is the cause; a worker's panic resumed on the boundary's thread
            // does not call the hook again.
            if let Ok(mut slot) = report.lock() {
                slot.get_or_insert(caught);
            };
        }));
    });
}

/// A panic payload's text: the `&str` or `String` it carries, else a placeholder.
pub fn payload_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|text| (*text).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_owned())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
mod tests {
    use super::*;

    #[test]
    fn a_panic_inside_becomes_an_error_with_its_message_and_location() {
        let line = line!() + 1;
        let caught = catch(|| -> u32 { panic!("the reader broke on item {}", 7) }).unwrap_err();
        assert_eq!(caught.message, "the reader broke on item 7");
        let location = caught.location.expect("the hook saw the location");
        assert!(
            location.starts_with(&format!("{}:{line}:", file!())),
            "{location}"
        );
        assert_eq!(catch(|| 5), Ok(5), "no panic, the value");
    }

    #[test]
    fn boundaries_nest_and_end_with_their_scope() {
        let outer = catch(|| {
            let inner = catch(|| panic!("inner")).unwrap_err();
            assert_eq!(inner.message, "inner");
            panic!("outer after {}", inner.message)
        })
        .unwrap_err();
        assert_eq!(outer.message, "outer after inner");
        assert!(
            BOUNDARY.with(|boundary| boundary.borrow().is_none()),
            "the thread is outside every boundary again"
        );
    }
}
