//! A draw list kept up to date per instance: draws are grouped in buckets by (geometry,
//! material), so recording binds each geometry once per bucket run and changes material state
//! as rarely as the scene allows; each instance knows where its draw is, so adding, removing or
//! changing one costs O(1) (swap-remove and push), never a re-sort.

use std::collections::BTreeMap;

/// The state a bucket shares: geometry slot, then material slot.
pub type BucketKey = (u32, u32);

/// Draws of type `D` keyed by instance id, grouped by [`BucketKey`].
#[derive(Debug)]
pub struct DrawBuckets<D> {
    buckets: BTreeMap<BucketKey, Vec<(u32, D)>>,
    /// Per instance id: its bucket and position, if it has a draw.
    location: Vec<Option<(BucketKey, u32)>>,
    len: usize,
}

impl<D> Default for DrawBuckets<D> {
    fn default() -> Self {
        Self {
            buckets: BTreeMap::new(),
            location: Vec::new(),
            len: 0,
        }
    }
}

impl<D> DrawBuckets<D> {
    /// Removes every draw.
    pub fn clear(&mut self) {
        self.buckets.clear();
        self.location.clear();
        self.len = 0;
    }

    /// Sets the draw of instance `id` (replacing any it had).
    pub fn insert(&mut self, id: u32, key: BucketKey, draw: D) {
        self.remove(id);
        let bucket = self.buckets.entry(key).or_default();
        bucket.push((id, draw));
        let index = id as usize;
        if index >= self.location.len() {
            self.location.resize(index + 1, None);
        }
        self.location[index] = Some((key, bucket.len() as u32 - 1));
        self.len += 1;
    }

    /// Removes the draw of instance `id`, if it has one.
    pub fn remove(&mut self, id: u32) {
        let Some((key, position)) = self.location.get_mut(id as usize).and_then(Option::take)
        else {
            return;
        };
        let Some(bucket) = self.buckets.get_mut(&key) else {
            return;
        };
        bucket.swap_remove(position as usize);
        if let Some(&(moved, _)) = bucket.get(position as usize) {
            self.location[moved as usize] = Some((key, position));
        }
        if bucket.is_empty() {
            self.buckets.remove(&key);
        }
        self.len -= 1;
    }

    /// Number of draws.
    pub fn len(&self) -> usize {
        self.len
    }

    /// The draws, bucket after bucket in key order.
    pub fn iter(&self) -> impl Iterator<Item = &D> {
        self.buckets
            .values()
            .flat_map(|bucket| bucket.iter().map(|(_, draw)| draw))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inserts_removes_and_moves_keep_every_location_right() {
        let mut buckets = DrawBuckets::default();
        for id in 0..10_u32 {
            buckets.insert(id, (id % 3, 0), id);
        }
        buckets.remove(0); // swap-removes: the last of bucket (0, 0) moves into place
        buckets.remove(3);
        buckets.insert(4, (7, 7), 4); // moves between buckets
        buckets.remove(42); // no draw: nothing happens
        let mut ids: Vec<u32> = buckets.iter().copied().collect();
        ids.sort_unstable();
        assert_eq!(ids, vec![1, 2, 4, 5, 6, 7, 8, 9]);
        assert_eq!(buckets.len(), 8);
        for id in [6, 9] {
            buckets.remove(id);
        }
        assert_eq!(
            buckets.iter().copied().collect::<Vec<_>>(),
            vec![1, 7, 2, 5, 8, 4]
        );
        buckets.clear();
        assert_eq!(buckets.len(), 0);
    }
}
