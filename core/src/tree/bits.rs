//! A growable bit array whose set bits are visited with count-trailing-zeros (seed 000:
//! "BitArray::traverseBits"): the cost is one word per 64 ids plus one step per set bit. The
//! set also remembers the range of words it may have bits in, so that a sparse set (a few
//! changed ids among millions) is visited, merged and cleared in proportion to that range,
//! not to its capacity.

/// A set of dense ids as bits.
#[derive(Clone, Debug, Default)]
pub struct BitSet {
    words: Vec<u64>,
    /// Words `touched.0 .. touched.1` may hold set bits; every other word is zero.
    touched: (usize, usize),
}

impl PartialEq for BitSet {
    fn eq(&self, other: &Self) -> bool {
        self.iter().eq(other.iter())
    }
}

impl Eq for BitSet {}

impl BitSet {
    fn touch(&mut self, word: usize) {
        if self.touched.0 >= self.touched.1 {
            self.touched = (word, word + 1);
        } else {
            self.touched = (self.touched.0.min(word), self.touched.1.max(word + 1));
        }
    }

    /// Sets bit `id`.
    pub fn insert(&mut self, id: u32) {
        let word = id as usize / 64;
        if word >= self.words.len() {
            self.words.resize(word + 1, 0);
        }
        self.words[word] |= 1 << (id % 64);
        self.touch(word);
    }

    /// Clears bit `id`.
    pub fn remove(&mut self, id: u32) {
        if let Some(w) = self.words.get_mut(id as usize / 64) {
            *w &= !(1 << (id % 64));
        }
    }

    /// Whether bit `id` is set.
    pub fn contains(&self, id: u32) -> bool {
        self.words
            .get(id as usize / 64)
            .is_some_and(|w| w & (1 << (id % 64)) != 0)
    }

    /// Sets or clears bit `id`.
    pub fn set(&mut self, id: u32, value: bool) {
        if value {
            self.insert(id);
        } else {
            self.remove(id);
        }
    }

    /// The words that may hold set bits, with the index of the first.
    fn touched_words(&self) -> (usize, &[u64]) {
        let (start, end) = self.touched;
        let end = end.min(self.words.len());
        if start >= end {
            return (0, &[]);
        }
        (start, &self.words[start..end])
    }

    /// Clears every bit (keeps the memory); costs the touched range only.
    pub fn clear(&mut self) {
        let (start, end) = self.touched;
        let end = end.min(self.words.len());
        if start < end {
            self.words[start..end].iter_mut().for_each(|w| *w = 0);
        }
        self.touched = (0, 0);
    }

    /// Sets every bit that is set in `other` (a union in place).
    pub fn union_with(&mut self, other: &BitSet) {
        let (start, words) = other.touched_words();
        if words.is_empty() {
            return;
        }
        let end = start + words.len();
        if self.words.len() < end {
            self.words.resize(end, 0);
        }
        for (mine, theirs) in self.words[start..end].iter_mut().zip(words) {
            *mine |= theirs;
        }
        self.touch(start);
        self.touch(end - 1);
    }

    /// Number of set bits.
    pub fn count(&self) -> usize {
        let (_, words) = self.touched_words();
        words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Whether no bit is set.
    pub fn is_empty(&self) -> bool {
        let (_, words) = self.touched_words();
        words.iter().all(|&w| w == 0)
    }

    /// The set bits in increasing order, found by trailing-zero counts.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        let (start, words) = self.touched_words();
        words.iter().enumerate().flat_map(move |(i, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                if bits == 0 {
                    return None;
                }
                let bit = bits.trailing_zeros();
                bits &= bits - 1;
                Some((start + i) as u32 * 64 + bit)
            })
        })
    }

    /// Bytes of memory held.
    pub fn memory_bytes(&self) -> usize {
        self.words.capacity() * 8
    }
}

#[cfg(test)]
mod tests {
    use super::BitSet;

    #[test]
    fn touched_range_covers_every_set_bit() {
        let mut a = BitSet::default();
        for id in [700, 5, 70_000, 64] {
            a.insert(id);
        }
        a.remove(64);
        assert_eq!(a.iter().collect::<Vec<_>>(), vec![5, 700, 70_000]);
        assert_eq!(a.count(), 3);
        let mut b = BitSet::default();
        b.insert(1);
        b.union_with(&a);
        assert_eq!(b.iter().collect::<Vec<_>>(), vec![1, 5, 700, 70_000]);
        a.clear();
        assert!(a.is_empty());
        assert_eq!(a.iter().count(), 0);
        a.insert(3);
        assert_eq!(a.iter().collect::<Vec<_>>(), vec![3]);
        assert!(!b.contains(2) && b.contains(70_000));
    }
}
