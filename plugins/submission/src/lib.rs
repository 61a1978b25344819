//! The dynamic library of cadr's draw submission: exports [`cadr_techniques::submission`] for the host to load
//! at run time (the techniques' code lives in `plugins/techniques`).

cadr_plugin_sdk::export_plugin!(entry: cadr_techniques::submission::entry);
