//! The dynamic library of cadr's exact transparency method: exports
//! [`cadr_techniques::transparency`] for the host to load at run time (the techniques' code
//! lives in `plugins/techniques`).

cadr_plugin_sdk::export_plugin!(entry: cadr_techniques::transparency::entry);
