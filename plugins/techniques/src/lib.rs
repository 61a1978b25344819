//! cadr's own techniques, written against the plugin SDK. Each module defines one technique
//! library (a `technique_library!` entry function, nothing exported): [`builtin`] is linked
//! into the host statically; the others are exported as the dynamic libraries in
//! `plugins/vertex`, `plugins/parameters`, `plugins/submission`, `plugins/culling` and `plugins/transparency`, which
//! the host finds and loads at run time.

pub mod builtin;
pub mod culling;
pub mod gpu_culling;
pub mod parameters;
pub mod submission;
pub mod transparency;
pub mod vertex;
