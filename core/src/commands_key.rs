//! Commands keys: 64-bit digests of what a recording depends on (the frame's replay key, the
//! upload prologue's key), folded one value at a time. Equal inputs give equal keys; a key is
//! compared, never decoded.

/// Folds `value` into `key`. The value is spread over all 64 bits first: the inputs are
/// mostly small counters (generations, epochs), and folding them in raw let two of them that
/// changed together cancel out (epoch 6 with generation 7 and epoch 7 with generation 6 gave
/// one key, so a swapped technique replayed the last technique's recording). Folding is a
/// bijection of the key for each value and of the value for each key, so inputs that differ
/// in one value always give different keys.
pub(crate) fn mix(key: u64, value: u64) -> u64 {
    (key ^ spread(value))
        .wrapping_mul(0x100_0000_01b3)
        .rotate_left(17)
}

/// SplitMix64's finalizer: a bijection of u64 whose outputs for nearby inputs differ in about
/// half their bits.
fn spread(value: u64) -> u64 {
    let mut z = value.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::mix;
    use std::collections::HashSet;

    #[test]
    fn small_counters_that_change_together_give_different_keys() {
        // Every (epoch, generation) pair of small counters, folded as a frame folds them.
        let keys: HashSet<u64> = (0..256u64)
            .flat_map(|epoch| (0..256u64).map(move |generation| mix(mix(epoch, generation), 640)))
            .collect();
        assert_eq!(keys.len(), 256 * 256);
        assert_ne!(mix(6, 7), mix(7, 6));
        assert_ne!(mix(mix(0, 3), 4), mix(mix(0, 4), 3));
    }
}
