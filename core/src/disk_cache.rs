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
/// The envelope's format version.
const FORMAT: u32 = 1;
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
    bytes.extend_from_slice(&fnv1a(payload, FNV_OFFSET).to_le_bytes());
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
    let checksum = u64::from_le_bytes(word(20..28)?.try_into().ok()?);
    let payload = &bytes[HEADER_BYTES..];
    (payload.len() as u64 == length && fnv1a(payload, FNV_OFFSET) == checksum).then_some(payload)
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// 64-bit FNV-1a of `bytes` from `state`: the checksum of an entry, and with two starting
/// states the 128-bit key of what it was made from.
fn fnv1a(bytes: &[u8], state: u64) -> u64 {
    bytes.iter().fold(state, |hash, &byte| {
        (hash ^ u64::from(byte)).wrapping_mul(FNV_PRIME)
    })
}

/// A 128-bit key (32 hex digits) of `parts`, each length-prefixed so that no two different
/// lists of parts give the same bytes.
pub fn key(parts: &[&[u8]]) -> String {
    let mut state = [FNV_OFFSET, FNV_OFFSET ^ 0x9e37_79b9_7f4a_7c15];
    for part in parts {
        for hash in &mut state {
            *hash = fnv1a(&(part.len() as u64).to_le_bytes(), *hash);
            *hash = fnv1a(part, *hash);
        }
    }
    format!("{:016x}{:016x}", state[0], state[1])
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
