//! A message buffer of our own, for calls into the host.

use std::ffi::c_char;

use cadr_plugin_abi as abi;

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
