//! What the renderers of one device share because each frame uses it only until it ends
//! (attachments cleared at a frame's start, storage zeroed there): a registry of weak
//! references, so a shared object lives as long as a renderer holds it.

use std::sync::{Arc, Mutex, PoisonError, Weak};

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

    /// A held object that `fits`, or the one `make` makes, registered for the next caller.
    pub fn get_or_make<E>(
        &self,
        fits: impl Fn(&T) -> bool,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<Arc<T>, E> {
        let mut held = self.held.lock().unwrap_or_else(PoisonError::into_inner);
        held.retain(|item| item.strong_count() > 0);
        if let Some(item) = held
            .iter()
            .filter_map(Weak::upgrade)
            .find(|item| fits(item))
        {
            return Ok(item);
        }
        let item = Arc::new(make()?);
        held.push(Arc::downgrade(&item));
        Ok(item)
    }
}

impl<T> Default for Shared<T> {
    fn default() -> Self {
        Self::new()
    }
}
