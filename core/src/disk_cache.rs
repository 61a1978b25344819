//! The on-disk cache that makes a second run start fast: compiled SPIR-V (keyed by the
//! assembled source, the stage, the includes and the compiler) and the Vulkan pipeline cache
//! of each device.
//!
//! It lives in `$CADR_CACHE_DIR`, else `$XDG_CACHE_HOME/cadr`, else `$HOME/.cache/cadr`, and
//! can be turned off for the process ([`set_enabled`], the CLI's `--no-cache`). Every entry is
//! wrapped in an envelope (magic, format version, length, checksum) and written to a unique
//! temporary file that is then renamed over the entry, so concurrent processes never see half
//! an entry. An entry that is missing, truncated, corrupt or not ours is ignored and rewritten,
//! never trusted; a cache that cannot be written is skipped silently (it is only a cache).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// The environment variable that names the cache directory.
pub const CACHE_DIR_VARIABLE: &str = "CADR_CACHE_DIR";

/// The first bytes of every entry.
const MAGIC: &[u8; 8] = b"CADRCACH";
/// The envelope's format version (2: XXH3 checksums and keys, where 1 had FNV-1a; a version 1
/// entry is not ours and is rewritten).
const FORMAT: u32 = 2;
/// Magic, format, payload length, checksum.
const HEADER_BYTES: usize = 8 + 4 + 8 + 8;

static DISABLED: AtomicBool = AtomicBool::new(false);
static TEMPORARY_FILES: AtomicU64 = AtomicU64::new(0);

/// Turns the user's cache on or off for this process (on by default).
pub fn set_enabled(enabled: bool) {
    DISABLED.store(!enabled, Ordering::Relaxed);
}

/// Whether the user's cache is on for this process.
pub fn enabled() -> bool {
    !DISABLED.load(Ordering::Relaxed)
}

/// A cache directory and what it holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DiskCache {
    dir: PathBuf,
}

impl DiskCache {
    /// The cache in `dir` (created on the first write).
    pub fn at(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The user's cache: `$CADR_CACHE_DIR`, else `$XDG_CACHE_HOME/cadr`, else
    /// `$HOME/.cache/cadr`; `None` when turned off or when no directory can be named.
    pub fn user() -> Option<Self> {
        if !enabled() {
            return None;
        }
        let non_empty = |name: &str| std::env::var_os(name).filter(|value| !value.is_empty());
        let dir = non_empty(CACHE_DIR_VARIABLE)
            .map(PathBuf::from)
            .or_else(|| non_empty("XDG_CACHE_HOME").map(|base| Path::new(&base).join("cadr")))
            .or_else(|| non_empty("HOME").map(|home| Path::new(&home).join(".cache/cadr")))?;
        Some(Self::at(dir))
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn path(&self, kind: &str, name: &str) -> PathBuf {
        self.dir.join(kind).join(name)
    }

    /// The payload of entry `name` of `kind`, if it is there and whole.
    pub fn read(&self, kind: &str, name: &str) -> Option<Vec<u8>> {
        let bytes = std::fs::read(self.path(kind, name)).ok()?;
        open_envelope(&bytes).map(<[u8]>::to_vec)
    }

    /// Stores `payload` as entry `name` of `kind` (atomically: a reader sees the old entry or
    /// the new one). Failures are ignored: the next run compiles again.
    pub fn write(&self, kind: &str, name: &str, payload: &[u8]) {
        let _ = self.try_write(kind, name, payload);
    }

    fn try_write(&self, kind: &str, name: &str, payload: &[u8]) -> std::io::Result<()> {
        let dir = self.dir.join(kind);
        std::fs::create_dir_all(&dir)?;
        let temporary = dir.join(format!(
            ".{name}.{}.{}.tmp",
            std::process::id(),
            TEMPORARY_FILES.fetch_add(1, Ordering::Relaxed)
        ));
        let written = (|| {
            let mut file = std::fs::File::create(&temporary)?;
            file.write_all(&envelope(payload))?;
            file.sync_data()
        })();
        match written.and_then(|()| std::fs::rename(&temporary, dir.join(name))) {
            Ok(()) => Ok(()),
            Err(error) => {
                let _ = std::fs::remove_file(&temporary);
                Err(error)
            }
        }
    }
}

/// `payload` in its envelope.
fn envelope(payload: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER_BYTES + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&FORMAT.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&checksum(payload).to_le_bytes());
    bytes.extend_from_slice(payload);
    bytes
}

/// The payload of a whole, uncorrupted envelope.
fn open_envelope(bytes: &[u8]) -> Option<&[u8]> {
    let header = bytes.get(..HEADER_BYTES)?;
    let word = |range: std::ops::Range<usize>| header.get(range);
    if word(0..8)? != MAGIC || u32::from_le_bytes(word(8..12)?.try_into().ok()?) != FORMAT {
        return None;
    }
    let length = u64::from_le_bytes(word(12..20)?.try_into().ok()?);
    let expected = u64::from_le_bytes(word(20..28)?.try_into().ok()?);
    let payload = &bytes[HEADER_BYTES..];
    (payload.len() as u64 == length && checksum(payload) == expected).then_some(payload)
}

/// The payload's checksum: XXH3 (64 bits), which reads gigabytes a second, so that checking a
/// large entry costs little next to reading it.
fn checksum(payload: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(payload)
}

/// A 128-bit key (32 hex digits) of `parts`, each length-prefixed so that no two different
/// lists of parts give the same bytes. XXH3-128, a fast non-cryptographic hash whose output
/// its specification fixes (so keys stay valid from one build to the next): the key of a
/// geometry's clusters reads all its vertices and indices.
pub fn key(parts: &[&[u8]]) -> String {
    let mut hasher = xxhash_rust::xxh3::Xxh3::new();
    for part in parts {
        hasher.update(&(part.len() as u64).to_le_bytes());
        hasher.update(part);
    }
    format!("{:032x}", hasher.digest128())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn envelopes_round_trip_and_reject_damage() {
        let payload = b"spir-v words".to_vec();
        let bytes = envelope(&payload);
        assert_eq!(open_envelope(&bytes), Some(&payload[..]));
        for cut in 0..bytes.len() {
            assert_eq!(open_envelope(&bytes[..cut]), None, "cut at {cut}");
        }
        for flip in 0..bytes.len() {
            let mut damaged = bytes.clone();
            damaged[flip] ^= 0x10;
            assert_eq!(open_envelope(&damaged), None, "byte {flip} flipped");
        }
    }

    #[test]
    fn keys_separate_their_parts() {
        assert_ne!(key(&[b"ab", b"c"]), key(&[b"a", b"bc"]));
        assert_eq!(key(&[b"ab", b"c"]), key(&[b"ab", b"c"]));
        assert_eq!(key(&[b"x"]).len(), 32);
    }
}
