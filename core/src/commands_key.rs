//! Commands keys: 64-bit digests of what a recording depends on (the frame's replay key, the
//! upload prologue's key), folded one value at a time. Equal inputs give equal keys; a key is
//! compared, never decoded.

/// Folds `value` into `key` (FNV-like).
pub(crate) fn mix(key: u64, value: u64) -> u64 {
    (key ^ value).wrapping_mul(0x100_0000_01b3).rotate_left(17)
}
