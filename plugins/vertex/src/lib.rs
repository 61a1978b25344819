//! The dynamic library of cadr's vertex paths: exports [`cadr_techniques::vertex`] for the host to load
//! at run time (the techniques' code lives in `plugins/techniques`).

cadr_plugin_sdk::export_plugin!(entry: cadr_techniques::vertex::entry);
