//! The files a glTF document names by URI (buffers, images), read beside it.

use std::path::{Path, PathBuf};

/// Reads the first `length` bytes of a buffer's file. Only a regular file is read, and no more
/// than the buffer declares: a URI naming a device or a pipe (`/dev/zero`) must not hang cadr
/// or take all of its memory.
pub(super) fn read_buffer_file(file: &Path, length: usize) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    let opened = std::fs::File::open(file)?;
    let metadata = opened.metadata()?;
    if !metadata.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "it is not a regular file",
        ));
    }
    let wanted = (length as u64).min(metadata.len());
    let mut data = Vec::with_capacity(wanted as usize);
    opened.take(wanted).read_to_end(&mut data)?;
    Ok(data)
}

pub(super) fn percent_decode(uri: &str) -> PathBuf {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}
