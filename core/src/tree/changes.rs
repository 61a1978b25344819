//! What changed in the scene tree, for each of its readers. The tree marks changes in one set
//! of bit arrays ([`ChangeBits`]); when a reader asks, the marks are handed on to every
//! reader's own log and that reader's log is turned into a [`TreeChanges`]. So several
//! renderers (or views) of one scene each see what changed since their own last frame, and
//! two renderers drawing one scene alternately upload only what changed.

use std::sync::{Arc, Weak};

use super::BitSet;

/// What changed since a reader's last look. Ids are dense and reused: apply `removed` before
/// `added`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TreeChanges {
    /// Instances created (alive now).
    pub added: Vec<u32>,
    /// Instance ids whose instance was destroyed (the id may be alive again in `added`).
    pub removed: Vec<u32>,
    /// Live instances, not added, whose material or geometry changed.
    pub changed: Vec<u32>,
    /// Live instances, not added, whose visibility changed.
    pub visibility_changed: Vec<u32>,
    /// Live tree nodes whose world matrix changed (the matrix slots to upload).
    pub dirty_matrices: Vec<u32>,
    /// Live tree nodes whose local matrix moved without anything else changing: the world
    /// matrices of their whole subtrees changed but are not listed in `dirty_matrices` (the
    /// GPU transform hierarchy recomputes them; a reader that keeps world matrices on the host
    /// walks the subtrees, see [`super::SceneTree::refresh_worlds`]).
    pub moved: Vec<u32>,
    /// Material slots whose parameters changed.
    pub dirty_materials: Vec<u32>,
    /// Geometry slots whose data was replaced.
    pub dirty_geometries: Vec<u32>,
}

impl TreeChanges {
    /// Whether nothing changed.
    pub fn is_empty(&self) -> bool {
        self.added.is_empty()
            && self.removed.is_empty()
            && self.changed.is_empty()
            && self.visibility_changed.is_empty()
            && self.dirty_matrices.is_empty()
            && self.moved.is_empty()
            && self.dirty_materials.is_empty()
            && self.dirty_geometries.is_empty()
    }
}

/// Change marks as bit arrays: the tree's pending marks, and each reader's log.
#[derive(Clone, Debug, Default)]
pub(super) struct ChangeBits {
    pub(super) created: BitSet,
    pub(super) destroyed: BitSet,
    pub(super) changed: BitSet,
    pub(super) visibility_changed: BitSet,
    pub(super) dirty_matrices: BitSet,
    pub(super) moved: BitSet,
    pub(super) dirty_materials: BitSet,
    pub(super) dirty_geometries: BitSet,
}

impl ChangeBits {
    fn sets(&self) -> [&BitSet; 8] {
        [
            &self.created,
            &self.destroyed,
            &self.changed,
            &self.visibility_changed,
            &self.dirty_matrices,
            &self.moved,
            &self.dirty_materials,
            &self.dirty_geometries,
        ]
    }

    fn sets_mut(&mut self) -> [&mut BitSet; 8] {
        [
            &mut self.created,
            &mut self.destroyed,
            &mut self.changed,
            &mut self.visibility_changed,
            &mut self.dirty_matrices,
            &mut self.moved,
            &mut self.dirty_materials,
            &mut self.dirty_geometries,
        ]
    }

    fn is_empty(&self) -> bool {
        self.sets().iter().all(|s| s.is_empty())
    }

    fn union_with(&mut self, other: &ChangeBits) {
        for (mine, theirs) in self.sets_mut().into_iter().zip(other.sets()) {
            mine.union_with(theirs);
        }
    }

    fn clear(&mut self) {
        for set in self.sets_mut() {
            set.clear();
        }
    }

    /// Turns the marks into lists, given which instances and tree nodes are alive now, and
    /// clears them.
    pub(super) fn take(&mut self, instance_alive: &BitSet, node_alive: &BitSet) -> TreeChanges {
        let created = &self.created;
        let live_not_created = |i: &u32| instance_alive.contains(*i) && !created.contains(*i);
        let changes = TreeChanges {
            added: created
                .iter()
                .filter(|&i| instance_alive.contains(i))
                .collect(),
            removed: self.destroyed.iter().collect(),
            changed: self.changed.iter().filter(live_not_created).collect(),
            visibility_changed: self
                .visibility_changed
                .iter()
                .filter(live_not_created)
                .collect(),
            dirty_matrices: self
                .dirty_matrices
                .iter()
                .filter(|&t| node_alive.contains(t))
                .collect(),
            moved: self
                .moved
                .iter()
                .filter(|&t| node_alive.contains(t))
                .collect(),
            dirty_materials: self.dirty_materials.iter().collect(),
            dirty_geometries: self.dirty_geometries.iter().collect(),
        };
        self.clear();
        changes
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.sets().iter().map(|s| s.memory_bytes()).sum()
    }
}

/// A reader of a scene tree's changes, made by [`super::SceneTree::subscribe`]: it sees what
/// changed since its own last [`super::SceneTree::changes_for`]. Dropping it unsubscribes (the
/// tree forgets its log at its next hand-out).
#[derive(Debug)]
pub struct ChangeReader {
    token: Arc<()>,
}

/// The readers' logs.
#[derive(Debug, Default)]
pub(super) struct ChangeLogs {
    /// Marks not yet handed to the readers.
    pub(super) pending: ChangeBits,
    /// The tree's own reader (`take_changes`).
    own: ChangeBits,
    readers: Vec<(Weak<()>, ChangeBits)>,
}

impl ChangeLogs {
    pub(super) fn subscribe(&mut self) -> ChangeReader {
        self.hand_out();
        let token = Arc::new(());
        self.readers
            .push((Arc::downgrade(&token), ChangeBits::default()));
        ChangeReader { token }
    }

    /// Hands the pending marks to every live reader and forgets readers that were dropped.
    fn hand_out(&mut self) {
        self.readers.retain(|(owner, _)| owner.strong_count() > 0);
        if self.pending.is_empty() {
            return;
        }
        for (_, log) in &mut self.readers {
            log.union_with(&self.pending);
        }
        self.own.union_with(&self.pending);
        self.pending.clear();
    }

    /// The log of `reader`, or `None` if it does not read this tree.
    pub(super) fn log_of(&mut self, reader: &ChangeReader) -> Option<&mut ChangeBits> {
        self.hand_out();
        let token = Arc::downgrade(&reader.token);
        self.readers
            .iter_mut()
            .find(|(owner, _)| owner.ptr_eq(&token))
            .map(|(_, log)| log)
    }

    /// The tree's own log.
    pub(super) fn own_log(&mut self) -> &mut ChangeBits {
        self.hand_out();
        &mut self.own
    }

    /// Number of live readers besides the tree's own.
    pub(super) fn reader_count(&self) -> usize {
        self.readers
            .iter()
            .filter(|(owner, _)| owner.strong_count() > 0)
            .count()
    }

    pub(super) fn memory_bytes(&self) -> usize {
        self.pending.memory_bytes()
            + self.own.memory_bytes()
            + self
                .readers
                .iter()
                .map(|(_, log)| log.memory_bytes())
                .sum::<usize>()
    }
}
