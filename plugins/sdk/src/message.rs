//! Messages across the boundary: writing into the host's buffer, and a buffer of our own for
//! calls into the host.

use std::ffi::c_char;

use cadr_plugin_abi as abi;

/// Writes `text` into the host's message buffer, cut to fit, NUL-terminated.
///
/// # Safety
/// `message` is null or points at a valid [`abi::CadrMessage`].
pub unsafe fn write_message(message: *mut abi::CadrMessage, text: &str) {
    // SAFETY: per the contract.
    let Some(message) = (unsafe { message.as_mut() }) else {
        return;
    };
    if message.text.is_null() || message.capacity == 0 {
        return;
    }
    let mut length = text.len().min(message.capacity - 1);
    while !text.is_char_boundary(length) {
        length -= 1;
    }
    // SAFETY: length + 1 <= capacity bytes are writable at text.
    unsafe {
        std::ptr::copy_nonoverlapping(text.as_ptr(), message.text.cast::<u8>(), length);
        *message.text.add(length) = 0;
    }
}

/// A message buffer of our own, for calls into the host.
pub(crate) struct MessageBuffer {
    bytes: [u8; 512],
    abi: abi::CadrMessage,
}

impl MessageBuffer {
    pub(crate) fn new() -> Box<Self> {
        let mut buffer = Box::new(Self {
            bytes: [0; 512],
            abi: abi::CadrMessage {
                text: std::ptr::null_mut(),
                capacity: 0,
            },
        });
        buffer.abi.text = buffer.bytes.as_mut_ptr().cast::<c_char>();
        buffer.abi.capacity = buffer.bytes.len();
        buffer
    }

    pub(crate) fn as_abi(&mut self) -> *mut abi::CadrMessage {
        &mut self.abi
    }

    pub(crate) fn text(&self) -> String {
        let end = self.bytes.iter().position(|&b| b == 0).unwrap_or(0);
        String::from_utf8_lossy(&self.bytes[..end]).into_owned()
    }
}
