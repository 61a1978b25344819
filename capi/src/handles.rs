//! Generation-checked handles for the C API's objects.
//!
//! A handle the host holds is never a pointer cadr dereferences: it encodes a type tag, a slot
//! index and the slot's generation. Looking it up checks all three, so a destroyed handle, a
//! handle of another type or a made-up value is reported with its own result code instead of
//! touching freed memory.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use crate::error::{CadrResult, Failure};

#[cfg(not(target_pointer_width = "64"))]
compile_error!("the C API's handle encoding needs 64-bit pointers");

/// The objects of one type, each behind its own lock.
pub(crate) struct Registry<T> {
    tag: u8,
    type_name: &'static str,
    slots: Mutex<Vec<Slot<T>>>,
}

struct Slot<T> {
    generation: u32,
    object: Option<Arc<Mutex<T>>>,
}

/// Locks a mutex, ignoring poisoning: every C API body runs inside a panic guard, and objects
/// stay usable after a caught panic (the panic is reported as `CADR_RESULT_PANIC`).
pub(crate) fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Bits 0..8 of a handle: the type tag; bits 8..32: slot index + 1; bits 32..64: generation.
const INDEX_LIMIT: usize = (1 << 24) - 1;

impl<T> Registry<T> {
    pub(crate) const fn new(tag: u8, type_name: &'static str) -> Self {
        Self {
            tag,
            type_name,
            slots: Mutex::new(Vec::new()),
        }
    }

    /// Stores `object` and returns its handle value.
    pub(crate) fn insert(&self, object: T) -> Result<u64, Failure> {
        let mut slots = lock(&self.slots);
        let index = match slots.iter().position(|s| s.object.is_none()) {
            Some(index) => index,
            None if slots.len() < INDEX_LIMIT => {
                slots.push(Slot {
                    generation: 0,
                    object: None,
                });
                slots.len() - 1
            }
            None => {
                return Err(Failure::new(
                    CadrResult::InvalidArgument,
                    format!("too many live {} objects", self.type_name),
                ))
            }
        };
        let slot = &mut slots[index];
        slot.generation = slot.generation.wrapping_add(1);
        slot.object = Some(Arc::new(Mutex::new(object)));
        Ok(u64::from(slot.generation) << 32 | ((index as u64 + 1) << 8) | u64::from(self.tag))
    }

    fn decode(&self, value: u64, what: &str) -> Result<(usize, u32), Failure> {
        let tag = (value & 0xff) as u8;
        let index = ((value >> 8) & 0xff_ffff) as usize;
        if tag != self.tag || index == 0 {
            return Err(Failure::new(
                CadrResult::ForeignHandle,
                format!("{what} is not a {} handle", self.type_name),
            ));
        }
        Ok((index - 1, (value >> 32) as u32))
    }

    /// The live object of a handle.
    pub(crate) fn get(&self, value: u64, what: &str) -> Result<Arc<Mutex<T>>, Failure> {
        if value == 0 {
            return Err(Failure::new(
                CadrResult::NullArgument,
                format!("{what} is NULL"),
            ));
        }
        let (index, generation) = self.decode(value, what)?;
        let slots = lock(&self.slots);
        match slots.get(index) {
            None => Err(Failure::new(
                CadrResult::ForeignHandle,
                format!("{what} is not a {} handle", self.type_name),
            )),
            Some(slot) => match &slot.object {
                Some(object) if slot.generation == generation => Ok(Arc::clone(object)),
                _ => Err(Failure::new(
                    CadrResult::DestroyedHandle,
                    format!("{what} is a destroyed {} handle", self.type_name),
                )),
            },
        }
    }

    /// Removes the object of a handle and returns it (to be dropped outside the registry's
    /// lock). NULL is a no-op.
    pub(crate) fn remove(&self, value: u64, what: &str) -> Result<Option<Arc<Mutex<T>>>, Failure> {
        if value == 0 {
            return Ok(None);
        }
        let (index, generation) = self.decode(value, what)?;
        let mut slots = lock(&self.slots);
        match slots.get_mut(index) {
            None => Err(Failure::new(
                CadrResult::ForeignHandle,
                format!("{what} is not a {} handle", self.type_name),
            )),
            Some(slot) if slot.generation == generation && slot.object.is_some() => {
                Ok(slot.object.take())
            }
            Some(_) => Err(Failure::new(
                CadrResult::DestroyedHandle,
                format!("{what} is a destroyed {} handle", self.type_name),
            )),
        }
    }
}
