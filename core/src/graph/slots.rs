//! Generation-checked slot storage: a handle names a slot and the generation it was created
//! in, so a destroyed (or foreign) handle is detected instead of reaching another object.

use std::marker::PhantomData;

/// A generation-checked reference to an item of type `T`.
#[derive(Debug)]
pub struct Handle<T> {
    index: u32,
    generation: u32,
    kind: PhantomData<fn() -> T>,
}

impl<T> Handle<T> {
    /// The slot index (dense: reused after destruction).
    pub fn index(self) -> u32 {
        self.index
    }

    /// The generation of the slot when the handle was made.
    pub fn generation(self) -> u32 {
        self.generation
    }

    /// Rebuilds a handle from its parts (for handles that crossed the C API).
    pub fn from_parts(index: u32, generation: u32) -> Self {
        Self {
            index,
            generation,
            kind: PhantomData,
        }
    }
}

impl<T> Clone for Handle<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Handle<T> {}
impl<T> PartialEq for Handle<T> {
    fn eq(&self, other: &Self) -> bool {
        (self.index, self.generation) == (other.index, other.generation)
    }
}
impl<T> Eq for Handle<T> {}
impl<T> std::hash::Hash for Handle<T> {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        (self.index, self.generation).hash(state);
    }
}

struct Slot<T> {
    generation: u32,
    item: Option<T>,
}

/// Items addressed by generation-checked handles.
pub struct Slots<T> {
    slots: Vec<Slot<T>>,
    free: Vec<u32>,
    live: usize,
}

impl<T> Default for Slots<T> {
    fn default() -> Self {
        Self {
            slots: Vec::new(),
            free: Vec::new(),
            live: 0,
        }
    }
}

impl<T> Slots<T> {
    /// Stores `item` and returns its handle.
    pub fn insert(&mut self, item: T) -> Handle<T> {
        self.live += 1;
        if let Some(index) = self.free.pop() {
            let slot = &mut self.slots[index as usize];
            slot.item = Some(item);
            return Handle::from_parts(index, slot.generation);
        }
        self.slots.push(Slot {
            generation: 1,
            item: Some(item),
        });
        Handle::from_parts(self.slots.len() as u32 - 1, 1)
    }

    /// Removes the item; its handle (and copies of it) stop working.
    pub fn remove(&mut self, handle: Handle<T>) -> Option<T> {
        let slot = self.slots.get_mut(handle.index as usize)?;
        if slot.generation != handle.generation {
            return None;
        }
        let item = slot.item.take()?;
        slot.generation = slot.generation.wrapping_add(1).max(1);
        self.free.push(handle.index);
        self.live -= 1;
        Some(item)
    }

    /// The item, if the handle is current.
    pub fn get(&self, handle: Handle<T>) -> Option<&T> {
        let slot = self.slots.get(handle.index as usize)?;
        (slot.generation == handle.generation)
            .then_some(slot.item.as_ref())
            .flatten()
    }

    /// The item, mutably, if the handle is current.
    pub fn get_mut(&mut self, handle: Handle<T>) -> Option<&mut T> {
        let slot = self.slots.get_mut(handle.index as usize)?;
        if slot.generation != handle.generation {
            return None;
        }
        slot.item.as_mut()
    }

    /// The item in slot `index`, whatever its generation.
    pub fn get_by_index(&self, index: u32) -> Option<&T> {
        self.slots.get(index as usize).and_then(|s| s.item.as_ref())
    }

    /// The current handle of slot `index`, if it holds an item.
    pub fn handle_at(&self, index: u32) -> Option<Handle<T>> {
        let slot = self.slots.get(index as usize)?;
        slot.item
            .as_ref()
            .map(|_| Handle::from_parts(index, slot.generation))
    }

    /// Number of slots ever used (live or free): the bound of slot indices.
    pub fn capacity(&self) -> usize {
        self.slots.len()
    }

    /// Number of live items.
    pub fn len(&self) -> usize {
        self.live
    }

    /// Whether there are no live items.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Live items with their handles.
    pub fn iter(&self) -> impl Iterator<Item = (Handle<T>, &T)> {
        self.slots.iter().enumerate().filter_map(|(i, s)| {
            s.item
                .as_ref()
                .map(|item| (Handle::from_parts(i as u32, s.generation), item))
        })
    }
}
