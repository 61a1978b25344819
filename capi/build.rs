//! Gives the shared library its SONAME (`libcadr.so.MAJOR`), so that installed hosts link
//! against the ABI version rather than the file.

fn main() {
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_else(|_| "0".into());
    if std::env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "linux") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libcadr.so.{major}");
    }
}
