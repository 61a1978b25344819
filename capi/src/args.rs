//! Reading the C caller's arguments: strings, arrays and out-parameters, with the argument's
//! name in every error.

use std::ffi::{c_char, CStr};

use crate::error::{CadrResult, Failure};

/// Fails with `CADR_RESULT_NULL_ARGUMENT` when `pointer` is null.
pub(crate) fn non_null<T>(pointer: *const T, name: &str) -> Result<(), Failure> {
    if pointer.is_null() {
        Err(Failure::new(
            CadrResult::NullArgument,
            format!("{name} is NULL"),
        ))
    } else {
        Ok(())
    }
}

/// Reads a required C string argument.
///
/// # Safety
/// `text` is null or points to a NUL-terminated string that stays valid during the call.
pub(crate) unsafe fn required_str<'a>(text: *const c_char, name: &str) -> Result<&'a str, Failure> {
    non_null(text, name)?;
    // SAFETY: non-null, and the caller guarantees a valid NUL-terminated string.
    unsafe { CStr::from_ptr(text) }
        .to_str()
        .map_err(|_| Failure::invalid(format!("{name} is not valid UTF-8")))
}

/// Reads an optional C string argument (NULL gives `None`).
///
/// # Safety
/// As [`required_str`].
pub(crate) unsafe fn optional_str<'a>(
    text: *const c_char,
    name: &str,
) -> Result<Option<&'a str>, Failure> {
    if text.is_null() {
        return Ok(None);
    }
    // SAFETY: forwarded contract.
    unsafe { required_str(text, name) }.map(Some)
}

/// Reads an array argument of `count` items; NULL is allowed only with `count` 0.
///
/// # Safety
/// `items` is null or points to `count` readable, initialised items valid during the call.
pub(crate) unsafe fn slice<'a, T>(
    items: *const T,
    count: usize,
    name: &str,
) -> Result<&'a [T], Failure> {
    if count == 0 {
        return Ok(&[]);
    }
    non_null(items, name)?;
    // SAFETY: non-null with `count` items (the caller's contract).
    Ok(unsafe { std::slice::from_raw_parts(items, count) })
}

/// Reads a list of C strings.
///
/// # Safety
/// `items` is null or points to `count` pointers, each null or a valid NUL-terminated string.
pub(crate) unsafe fn string_list(
    items: *const *const c_char,
    count: usize,
    name: &str,
) -> Result<Vec<String>, Failure> {
    // SAFETY: forwarded contract.
    let pointers = unsafe { slice(items, count, name) }?;
    pointers
        .iter()
        .enumerate()
        // SAFETY: each pointer is null or a valid string (forwarded contract).
        .map(|(i, &p)| unsafe { required_str(p, &format!("{name}[{i}]")) }.map(str::to_owned))
        .collect()
}

/// Writes an out-parameter once the call has succeeded; NULL gives
/// `CADR_RESULT_NULL_ARGUMENT` naming it.
///
/// # Safety
/// `out` is null, or aligned and writable.
pub(crate) unsafe fn deliver<T>(out: *mut T, name: &str, value: T) -> Result<(), Failure> {
    non_null(out, name)?;
    // SAFETY: non-null here; aligned and writable by the caller's contract.
    unsafe { write(out, value) };
    Ok(())
}

/// Copies `text` into the caller's `buffer` of `capacity` bytes as a NUL-terminated string and
/// its length without the NUL into `*length`. With `buffer` NULL or `capacity` too small,
/// writes only the capacity it needs (length + 1) into `*length` and returns
/// `CADR_RESULT_BUFFER_TOO_SMALL`; with `length` NULL, `CADR_RESULT_NULL_ARGUMENT`.
///
/// # Safety
/// `buffer` is null or writable for `capacity` bytes; `length` is null or writable.
pub(crate) unsafe fn copy_string_out(
    text: &str,
    buffer: *mut c_char,
    capacity: usize,
    length: *mut usize,
) -> CadrResult {
    if length.is_null() {
        return CadrResult::NullArgument;
    }
    let bytes = text.as_bytes();
    if buffer.is_null() || capacity < bytes.len() + 1 {
        // SAFETY: length is non-null and writable (the caller's contract).
        unsafe { *length = bytes.len() + 1 };
        return CadrResult::BufferTooSmall;
    }
    // SAFETY: buffer is writable for capacity >= len + 1 bytes; the regions cannot overlap
    // (`text` is cadr's own).
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr(), buffer.cast::<u8>(), bytes.len());
        *buffer.add(bytes.len()) = 0;
        *length = bytes.len();
    }
    CadrResult::Ok
}

/// Writes an out-parameter that was checked to be non-null.
///
/// # Safety
/// `out` is non-null, aligned and writable.
pub(crate) unsafe fn write<T>(out: *mut T, value: T) {
    // SAFETY: the caller's contract; `write` does not read or drop the old contents.
    unsafe { out.write(value) }
}

/// A 4×4 double matrix from 16 column-major values; non-finite values are refused by name.
///
/// # Safety
/// `values` is null or points to 16 readable doubles.
pub(crate) unsafe fn matrix(values: *const f64, name: &str) -> Result<glam::DMat4, Failure> {
    // SAFETY: forwarded contract.
    let values = unsafe { slice(values, 16, name) }?;
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(Failure::invalid(format!(
            "{name}[{i}] is {} (matrices must be finite)",
            values[i]
        )));
    }
    let mut columns = [0.0; 16];
    columns.copy_from_slice(values);
    Ok(glam::DMat4::from_cols_array(&columns))
}

/// Three doubles as a vector; non-finite values are refused by name.
///
/// # Safety
/// `values` is null or points to 3 readable doubles.
pub(crate) unsafe fn vector3(values: *const f64, name: &str) -> Result<glam::DVec3, Failure> {
    // SAFETY: forwarded contract.
    let values = unsafe { slice(values, 3, name) }?;
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(Failure::invalid(format!("{name}[{i}] is not finite")));
    }
    Ok(glam::DVec3::new(values[0], values[1], values[2]))
}

/// Writes `value` into the host's struct at `out` up to the size the host gave in its first
/// field (a `uint32_t size`): the fields after the size that fit, and zeros in whatever the host
/// knows beyond this library's struct, as a struct that grows is filled for an older or newer
/// host. The host's size stays as it is. `name` names the struct in the error about a size too
/// small to hold even the size.
///
/// # Safety
/// `out` is null or points at `size` writable bytes, the first four holding `size`; `T` is a
/// `#[repr(C)]` struct of plain data whose first field is its `u32` size.
pub(crate) unsafe fn deliver_sized<T: Copy>(
    out: *mut T,
    name: &str,
    value: T,
) -> Result<(), Failure> {
    // SAFETY: null or at least its size readable (the caller's contract).
    let size = unsafe { host_size(out, name) }?;
    let header = std::mem::size_of::<u32>();
    let known = std::mem::size_of::<T>();
    let copied = size.min(known);
    let source = std::ptr::from_ref(&value).cast::<u8>();
    // SAFETY: bytes `header..copied` lie within both `value` and the `size` bytes the caller
    // made writable, and the two do not overlap.
    unsafe {
        std::ptr::copy_nonoverlapping(
            source.add(header),
            out.cast::<u8>().add(header),
            copied - header,
        )
    };
    if size > known {
        // SAFETY: bytes `known..size` lie within the `size` bytes the caller made writable.
        unsafe { std::ptr::write_bytes(out.cast::<u8>().add(known), 0, size - known) };
    }
    Ok(())
}

/// Refuses an output struct that will own cadr's allocations when its host `size` is below
/// `first_size`, the struct's size in its first version (which every later header's size
/// reaches): a smaller struct would lose arrays cadr hands out.
///
/// # Safety
/// `out` is null or points at least at a readable `u32` size.
pub(crate) unsafe fn check_owning_size<T>(
    out: *const T,
    (name, type_name): (&str, &str),
    first_size: usize,
) -> Result<(), Failure> {
    // SAFETY: null or at least its size readable (the caller's contract).
    let size = unsafe { host_size(out, name) }?;
    if size < first_size {
        return Err(Failure::invalid(format!(
            "{name}->size is {size}; set it to sizeof({type_name}) (at least {first_size} bytes)"
        )));
    }
    Ok(())
}

/// The most bytes a host's input struct may have beyond this library's: a newer header's
/// additions, well above what a minor version adds, and a guard against a `size` the host left
/// uninitialised.
const MAX_NEWER_BYTES: usize = 4096;

/// The `size` a host gave in the first field of its struct `T` at `pointer`, refused when it
/// cannot be one: below the size field itself, or more than [`MAX_NEWER_BYTES`] beyond this
/// library's `T`. `name` is the argument, for the errors, which name the struct as C does.
///
/// # Safety
/// `pointer` is null or points at least at a readable `u32`.
unsafe fn host_size<T>(pointer: *const T, name: &str) -> Result<usize, Failure> {
    non_null(pointer, name)?;
    // SAFETY: non-null; the caller's contract makes the size readable.
    let size = unsafe { pointer.cast::<u32>().read_unaligned() } as usize;
    let known = std::mem::size_of::<T>();
    if size < std::mem::size_of::<u32>() || size > known + MAX_NEWER_BYTES {
        // The C name: the Rust type's, without its module path.
        let full = std::any::type_name::<T>();
        let type_name = full.rsplit("::").next().unwrap_or(full);
        return Err(Failure::invalid(format!(
            "{name}->size is {size}; set it to sizeof({type_name}) ({known} bytes in this library)"
        )));
    }
    Ok(size)
}

/// Reads the host's input struct at `input` whose first field is its `u32` size, as a struct
/// that grows is read: a host compiled against an older header gives a smaller `size`, and the
/// fields it does not know take their values from `defaults`; a newer host gives a larger one,
/// accepted when the bytes this library does not know are all zero (a field added later keeps
/// its old behaviour at 0) and refused, naming them, otherwise. `name` is the argument and
/// `type_name` the struct's C name, for the errors. The result's size is this library's.
///
/// # Safety
/// `input` is null or points at `size` readable bytes, the first four holding `size`; `T` is a
/// `#[repr(C)]` struct of plain data whose first field is its `u32` size.
pub(crate) unsafe fn read_sized<T: Copy>(
    input: *const T,
    (name, type_name): (&str, &str),
    defaults: T,
) -> Result<T, Failure> {
    // SAFETY: null or at least its size readable (the caller's contract).
    let size = unsafe { host_size(input, name) }?;
    let header = std::mem::size_of::<u32>();
    let known = std::mem::size_of::<T>();
    let bytes = input.cast::<u8>();
    if size > known {
        // SAFETY: bytes `known..size` lie within the `size` readable bytes.
        let newer = unsafe { std::slice::from_raw_parts(bytes.add(known), size - known) };
        if let Some(first) = newer.iter().position(|&b| b != 0) {
            return Err(Failure::invalid(format!(
                "{name} sets byte {} of {type_name}, which this library ({} bytes, version {}) does not know: link a newer libcadr or leave the newer fields 0",
                known + first,
                known,
                env!("CARGO_PKG_VERSION")
            )));
        }
    }
    let mut value = defaults;
    let copied = size.min(known);
    // SAFETY: bytes `header..copied` lie within both the host's `size` readable bytes and
    // `value`, which do not overlap; `T` is plain data laid out as the header's struct, so the
    // host's bytes form a value (a C `bool` holds 0 or 1, as Rust's does).
    unsafe {
        std::ptr::copy_nonoverlapping(
            bytes.add(header),
            std::ptr::from_mut(&mut value).cast::<u8>().add(header),
            copied - header,
        )
    };
    // SAFETY: `value` is a `T` whose first field is its u32 size.
    unsafe {
        std::ptr::from_mut(&mut value)
            .cast::<u32>()
            .write(known as u32)
    };
    Ok(value)
}
