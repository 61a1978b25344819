//! The dynamic library of cadr's culling: exports [`cadr_techniques::culling`] for the host to load
//! at run time (the techniques' code lives in `plugins/techniques`).

cadr_plugin_sdk::export_plugin!(entry: cadr_techniques::culling::entry);
