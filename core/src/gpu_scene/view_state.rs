//! What each view of a GPU scene keeps of its own, so that several views (renderers of one
//! scene) share one GPU scene: culling's bits, the drawn set and its triangles, a draws
//! generation, and the matrix and material slots changed since the view's last frame. The
//! scene keeps, per following view, the changes that view has not seen yet ([`Unseen`]); a
//! view takes them when it draws ([`ViewState::catch_up`]), however many syncs (by itself or
//! by other views) came in between.

use std::sync::{Arc, Weak};

use cadr_plugin_abi as abi;

/// The first draws generation of the next view state (each counts within its own 2^32, apart
/// from the scenes' generations, which start at 1 << 32 multiples from the other end).
static NEXT_VIEW_GENERATIONS: std::sync::atomic::AtomicU64 =
    std::sync::atomic::AtomicU64::new(u64::MAX / 2);

/// What one view keeps of the GPU scene it draws.
pub struct ViewState {
    /// While this lives, the scene it follows keeps the changes it has not seen.
    token: Arc<()>,
    /// The scene followed (its identity), none before the first catch-up.
    scene: Option<u64>,
    /// Culling's result as last applied: set where the culler keeps the id (all set until a
    /// culler says otherwise).
    culled: Vec<u64>,
    /// Drawn by this view: a candidate that culling keeps.
    drawn: Vec<u64>,
    /// Triangles of the drawn instances.
    triangles: u64,
    /// The draws generation techniques see: moves with the scene's and with this view's
    /// culling.
    draws: u64,
    /// The scene's draws generation when this view last caught up.
    scene_draws: u64,
    /// Matrix slots changed since this view's last frame.
    dirty_matrices: Vec<u32>,
    /// Material slots changed since this view's last frame.
    dirty_materials: Vec<u32>,
}

impl Default for ViewState {
    fn default() -> Self {
        Self::new()
    }
}

/// Changes to the scene that a view has not seen yet.
#[derive(Default)]
pub(super) struct Unseen {
    /// Everything was rebuilt: the view starts over (the lists below are then moot).
    pub all: bool,
    /// Matrix slots written.
    pub matrices: Vec<u32>,
    /// Material slots written.
    pub materials: Vec<u32>,
    /// Instances whose entries were replaced, each with its entry's triangles before.
    pub touched: Vec<(u32, u32)>,
}

impl Unseen {
    /// Adds `later` to what is unseen; past `limit` entries, everything is (a view that does
    /// not draw while parts move every frame would otherwise gather lists without end).
    fn extend(&mut self, later: &Unseen, limit: usize) {
        let entries = self.matrices.len() + self.materials.len() + self.touched.len();
        let later_entries = later.matrices.len() + later.materials.len() + later.touched.len();
        if self.all || later.all || entries + later_entries > limit {
            *self = Unseen {
                all: true,
                ..Unseen::default()
            };
            return;
        }
        self.matrices.extend_from_slice(&later.matrices);
        self.materials.extend_from_slice(&later.materials);
        self.touched.extend_from_slice(&later.touched);
    }
}

/// A view following a scene, with what it has not seen.
struct Follower {
    token: Weak<()>,
    unseen: Unseen,
}

/// The views following one scene, and what the current sync changed.
#[derive(Default)]
pub(super) struct Followers {
    /// What the current sync changed, handed to every following view at its end.
    pub changes: Unseen,
    views: Vec<Follower>,
}

impl Followers {
    /// Hands what the sync changed to every following view, forgetting views that are gone,
    /// and starts the next sync's list. A view's unseen changes past `limit` entries (the
    /// scene's slots: catching up with everything costs no more) become "everything".
    pub fn deliver(&mut self, limit: usize) {
        let changes = std::mem::take(&mut self.changes);
        self.views
            .retain(|follower| follower.token.strong_count() > 0);
        for follower in &mut self.views {
            follower.unseen.extend(&changes, limit);
        }
    }

    /// Takes what `view` has not seen: everything for a view that did not follow yet (it
    /// follows from now on).
    fn take(&mut self, view: &ViewState) -> Unseen {
        let token = Arc::downgrade(&view.token);
        match self
            .views
            .iter_mut()
            .find(|f| Weak::ptr_eq(&f.token, &token))
        {
            Some(follower) => std::mem::take(&mut follower.unseen),
            None => {
                self.views.push(Follower {
                    token,
                    unseen: Unseen::default(),
                });
                Unseen {
                    all: true,
                    ..Unseen::default()
                }
            }
        }
    }
}

/// What a view reads of the scene when it catches up.
pub(super) struct SceneFacts<'a> {
    /// The scene's identity (its first generation).
    pub identity: u64,
    /// The scene's draws generation (instances and their entries).
    pub draws: u64,
    /// Candidate bits (alive, visible, with triangles).
    pub candidate: &'a [u64],
    /// Triangles of every candidate.
    pub candidate_triangles: u64,
    /// The instance entries.
    pub instances: &'a [abi::CadrInstance],
    /// Matrix and material slots.
    pub slots: (usize, usize),
}

/// Whether bit `id` of `bits` is set (false past the end).
pub(super) fn bit(bits: &[u64], id: u32) -> bool {
    bits.get(id as usize / 64)
        .is_some_and(|word| word >> (id % 64) & 1 == 1)
}

/// Sets or clears bit `id` of `bits`.
pub(super) fn set_bit(bits: &mut [u64], id: u32, on: bool) {
    let (word, bit) = (id as usize / 64, id % 64);
    if on {
        bits[word] |= 1 << bit;
    } else {
        bits[word] &= !(1 << bit);
    }
}

fn triangles_of(instances: &[abi::CadrInstance], id: u32) -> u64 {
    instances
        .get(id as usize)
        .map_or(0, |entry| u64::from(entry.index_count / 3))
}

impl ViewState {
    /// A view that follows no scene yet.
    pub fn new() -> Self {
        Self {
            token: Arc::new(()),
            scene: None,
            culled: Vec::new(),
            drawn: Vec::new(),
            triangles: 0,
            draws: NEXT_VIEW_GENERATIONS.fetch_add(1 << 32, std::sync::atomic::Ordering::Relaxed),
            scene_draws: 0,
            dirty_matrices: Vec::new(),
            dirty_materials: Vec::new(),
        }
    }

    /// Applies what this view has not seen of the scene (`followers` keep it), before a frame.
    pub(super) fn catch_up(&mut self, followers: &mut Followers, scene: &SceneFacts) {
        let mut unseen = followers.take(self);
        if self.scene != Some(scene.identity) {
            self.scene = Some(scene.identity);
            unseen.all = true;
        }
        if unseen.all {
            self.culled = vec![u64::MAX; scene.candidate.len()];
            self.drawn = scene.candidate.to_vec();
            self.triangles = scene.candidate_triangles;
            self.dirty_matrices = (0..scene.slots.0 as u32).collect();
            self.dirty_materials = (0..scene.slots.1 as u32).collect();
        } else {
            // Out of the drawn set with their old entries, back in with the new ones.
            for &(id, triangles) in &unseen.touched {
                if bit(&self.drawn, id) {
                    set_bit(&mut self.drawn, id, false);
                    self.triangles -= u64::from(triangles);
                }
            }
            for &(id, _) in &unseen.touched {
                let on = bit(scene.candidate, id) && bit(&self.culled, id);
                if on && !bit(&self.drawn, id) {
                    set_bit(&mut self.drawn, id, true);
                    self.triangles += triangles_of(scene.instances, id);
                }
            }
            for list in [&mut unseen.matrices, &mut unseen.materials] {
                list.sort_unstable();
                list.dedup();
            }
            self.dirty_matrices = unseen.matrices;
            self.dirty_materials = unseen.materials;
        }
        if unseen.all || !unseen.touched.is_empty() || self.scene_draws != scene.draws {
            self.scene_draws = scene.draws;
            self.draws += 1;
        }
    }

    /// Applies culling's result: `visible` bits and the bits that `changed` since the last
    /// frame; only changed ids are touched.
    pub(super) fn apply_culling(
        &mut self,
        (candidate, instances): (&[u64], &[abi::CadrInstance]),
        visible: &[u64],
        changed: &[u64],
    ) {
        let mut any = false;
        for (word, &bits) in changed.iter().enumerate() {
            let mut bits = bits;
            while bits != 0 {
                let bit_index = bits.trailing_zeros();
                bits &= bits - 1;
                let id = word as u32 * 64 + bit_index;
                if id as usize >= instances.len() {
                    continue;
                }
                let on = visible.get(word).is_some_and(|w| w >> bit_index & 1 == 1);
                set_bit(&mut self.culled, id, on);
                let drawn = on && bit(candidate, id);
                if bit(&self.drawn, id) != drawn {
                    set_bit(&mut self.drawn, id, drawn);
                    let triangles = triangles_of(instances, id);
                    if drawn {
                        self.triangles += triangles;
                    } else {
                        self.triangles -= triangles;
                    }
                }
                any = true;
            }
        }
        if any {
            self.draws += 1;
        }
    }

    /// Culling's bits as last applied.
    pub fn culled_bits(&self) -> &[u64] {
        &self.culled
    }

    /// Drawn bits by instance id.
    pub fn drawn_bits(&self) -> &[u64] {
        &self.drawn
    }

    /// Instances this view draws.
    pub fn drawn_count(&self) -> usize {
        self.drawn.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Triangles of the instances this view draws.
    pub fn drawn_triangles(&self) -> u64 {
        self.triangles
    }

    /// The draws generation techniques see.
    pub(super) fn draws_generation(&self) -> u64 {
        self.draws
    }

    /// Matrix and material slots changed since this view's last frame.
    pub(super) fn dirty_slots(&self) -> (&[u32], &[u32]) {
        (&self.dirty_matrices, &self.dirty_materials)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_that_does_not_draw_gathers_no_more_than_the_scene_has_slots() {
        let view = ViewState::new();
        let mut followers = Followers::default();
        assert!(
            followers.take(&view).all,
            "a new follower starts from everything"
        );
        // Below the limit the lists are kept as they are.
        followers.changes.matrices.push(7);
        followers.deliver(64);
        let unseen = followers.take(&view);
        assert!(!unseen.all && unseen.matrices == [7]);
        // A view that never draws while parts move: bounded, then everything.
        for step in 0..100u32 {
            followers.changes.matrices.extend([step, step + 1]);
            followers.deliver(64);
            let unseen = &followers.views[0].unseen;
            assert!(unseen.all || unseen.matrices.len() <= 64, "step {step}");
        }
        assert!(followers.take(&view).all);
        // A view that is gone is forgotten at the next delivery.
        drop(view);
        followers.deliver(64);
        assert!(followers.views.is_empty());
    }
}
