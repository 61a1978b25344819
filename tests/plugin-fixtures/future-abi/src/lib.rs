//! A library that claims plugin ABI 2.0: the host must refuse it after the version call,
//! before reading any struct (its entry point would crash if called).

/// ABI 2.0.
#[no_mangle]
pub extern "C" fn cadr_plugin_abi_version() -> u32 {
    2 << 16
}

/// Must never be called: it aborts the process.
#[no_mangle]
pub extern "C" fn cadr_plugin_entry(_library: *mut std::ffi::c_void) -> i32 {
    std::process::abort()
}
