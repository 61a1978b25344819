//! What several renderers share, held weakly so that a shared object lives as long as one of
//! them holds it: the attachments and storage a frame uses only until it ends (the renderers of
//! one device), and the GPU scene of one tree (its views, `view.rs`).

use std::sync::{Arc, Mutex, MutexGuard, PoisonError, Weak};

/// The objects of one kind that renderers share, found by what they fit.
pub struct Shared<T> {
    held: Mutex<Vec<Weak<T>>>,
}

impl<T> Shared<T> {
    /// An empty registry (for a `static`).
    pub const fn new() -> Self {
        Self {
            held: Mutex::new(Vec::new()),
        }
    }

    /// The live objects' references, the dead ones dropped.
    fn live(&self) -> MutexGuard<'_, Vec<Weak<T>>> {
        let mut held = self.held.lock().unwrap_or_else(PoisonError::into_inner);
        held.retain(|item| item.strong_count() > 0);
        held
    }

    /// A held object that `fits`, if any.
    pub fn find(&self, fits: impl Fn(&T) -> bool) -> Option<Arc<T>> {
        fitting(&self.live(), fits)
    }

    /// A held object that `fits`, or the one `make` makes, held for the next caller (both under
    /// one lock: two callers never make two).
    pub fn get_or_make<E>(
        &self,
        fits: impl Fn(&T) -> bool,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        let mut held = self.live();
        if let Some(item) = fitting(&held, fits) {
            return Ok(item);
        }
        let item = Arc::new(make()?);
        held.push(Arc::downgrade(&item));
        Ok(item)
    }

    /// Holds `item` for later callers.
    pub fn hold(&self, item: &Arc<T>) {
        self.live().push(Arc::downgrade(item));
    }

    /// Whether `item` is held.
    pub fn holds(&self, item: &Arc<T>) -> bool {
        self.live()
            .iter()
            .any(|held| std::ptr::eq(held.as_ptr(), Arc::as_ptr(item)))
    }

    /// How many objects are alive.
    pub fn len(&self) -> usize {
        self.live().len()
    }

    /// Whether none is alive.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The first of `held` alive that `fits`.
fn fitting<T>(held: &[Weak<T>], fits: impl Fn(&T) -> bool) -> Option<Arc<T>> {
    held.iter()
        .filter_map(Weak::upgrade)
        .find(|item| fits(item))
}

impl<T> Default for Shared<T> {
    fn default() -> Self {
        Self::new()
    }
}
