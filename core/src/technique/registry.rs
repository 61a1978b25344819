//! Finding and loading technique plugins: the built-in library (the simplest technique of
//! each kind, linked statically) comes first, then every library in the plugin directories is
//! opened, its ABI version negotiated before any struct is read, its techniques listed and
//! checked against the device. Both go through one registration, so a built-in technique is
//! read through the ABI exactly as a plugin's. Libraries are never unloaded (their code may
//! still be referenced by techniques alive or destroyed). What cannot be used is kept as a [`Refusal`] that says why.

use std::ffi::{c_char, CStr};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use cadr_plugin_abi as abi;

use crate::vk::Capabilities;

/// The environment variable with extra plugin directories (separated like `PATH`).
pub const PLUGIN_PATH_VARIABLE: &str = "CADR_PLUGIN_PATH";

/// The size of `$type` up to and including `$field`: what a writer that knew `$field` as the
/// last field wrote.
macro_rules! size_through {
    ($type:ty, $field:ident) => {{
        fn field_size<T, F>(_: impl Fn(&T) -> &F) -> usize {
            std::mem::size_of::<F>()
        }
        std::mem::offset_of!($type, $field) + field_size(|s: &$type| &s.$field)
    }};
}

/// What [`TechniqueEntry::library`] says for the built-in techniques.
pub const BUILT_IN_LIBRARY: &str = "built-in";

/// Which of the four technique kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TechniqueKind {
    /// How vertices reach the shader.
    Vertex,
    /// How matrices and materials reach the shader.
    Parameters,
    /// Which draws are issued and how.
    Submission,
    /// Which instances are drawn.
    Culling,
    /// How translucent surfaces are blended (ABI 1.7).
    Transparency,
}

impl TechniqueKind {
    /// Every kind, in the order combinations are written.
    pub const ALL: [TechniqueKind; 5] = [
        TechniqueKind::Vertex,
        TechniqueKind::Parameters,
        TechniqueKind::Submission,
        TechniqueKind::Culling,
        TechniqueKind::Transparency,
    ];

    /// The name used on the command line and in messages.
    pub fn name(self) -> &'static str {
        match self {
            TechniqueKind::Vertex => "vertex",
            TechniqueKind::Parameters => "params",
            TechniqueKind::Submission => "submit",
            TechniqueKind::Culling => "cull",
            TechniqueKind::Transparency => "transparency",
        }
    }

    fn from_abi(kind: abi::CadrTechniqueKind) -> Option<Self> {
        match kind {
            abi::CADR_KIND_VERTEX_PATH => Some(TechniqueKind::Vertex),
            abi::CADR_KIND_PARAMETER_PATH => Some(TechniqueKind::Parameters),
            abi::CADR_KIND_SUBMISSION => Some(TechniqueKind::Submission),
            abi::CADR_KIND_CULLING => Some(TechniqueKind::Culling),
            abi::CADR_KIND_TRANSPARENCY => Some(TechniqueKind::Transparency),
            _ => None,
        }
    }

    /// The size of this kind's vtable in this host's ABI.
    fn vtable_size(self) -> usize {
        match self {
            TechniqueKind::Vertex => std::mem::size_of::<abi::CadrVertexPathVtable>(),
            TechniqueKind::Parameters => std::mem::size_of::<abi::CadrParameterPathVtable>(),
            TechniqueKind::Submission => std::mem::size_of::<abi::CadrSubmissionVtable>(),
            TechniqueKind::Culling => std::mem::size_of::<abi::CadrCullingVtable>(),
            TechniqueKind::Transparency => std::mem::size_of::<abi::CadrTransparencyVtable>(),
        }
    }

    /// The size this kind's vtable had in ABI 1.0, the least a library of this major version
    /// may hand out (fields added by later minors default to none).
    fn first_vtable_size(self) -> usize {
        match self {
            TechniqueKind::Vertex => size_through!(abi::CadrVertexPathVtable, bind_draw),
            TechniqueKind::Parameters => size_through!(abi::CadrParameterPathVtable, bind_draw),
            TechniqueKind::Submission => size_through!(abi::CadrSubmissionVtable, record),
            TechniqueKind::Culling => size_through!(abi::CadrCullingVtable, cull),
            TechniqueKind::Transparency => size_through!(abi::CadrTransparencyVtable, method),
        }
    }
}

/// The size of [`abi::CadrPluginLibrary`] in ABI 1.0.
fn first_library_size() -> usize {
    size_through!(abi::CadrPluginLibrary, techniques)
}

/// The extension kinds this host knows (`CADR_EXTENSION_*`): those of ABI 1.14, 1.15, 1.18 to
/// 1.22 and 1.24.
const KNOWN_EXTENSIONS: &[abi::CadrExtensionKind] = &[
    abi::CADR_EXTENSION_SCENE_CLUSTERS,
    abi::CADR_EXTENSION_CLUSTER_CULL,
    abi::CADR_EXTENSION_FRAME_SLOT,
    abi::CADR_EXTENSION_BACK_FACE_PASSES,
    abi::CADR_EXTENSION_SHARED_FACE_STREAMS,
    abi::CADR_EXTENSION_SCENE_CLUSTER_BOXES,
    abi::CADR_EXTENSION_SCENE_PART_BOXES,
    abi::CADR_EXTENSION_SCENE_STREAMING,
    abi::CADR_EXTENSION_PARAMETER_BLOCKS,
    abi::CADR_EXTENSION_EMPTY_COMMAND_TAILS,
];

/// Refuses a technique that requires an extension this host does not know, naming it.
fn check_required_extensions(info: &abi::CadrTechniqueInfo) -> Result<(), String> {
    if info.required_extension_count == 0 {
        return Ok(());
    }
    if info.required_extensions.is_null() {
        return Err(format!(
            "it requires {} extensions but does not say which",
            info.required_extension_count
        ));
    }
    // SAFETY: checked non-null; the library promises `required_extension_count` kinds that
    // live as long as the process.
    let required = unsafe {
        std::slice::from_raw_parts(
            info.required_extensions,
            info.required_extension_count as usize,
        )
    };
    match required
        .iter()
        .find(|kind| !KNOWN_EXTENSIONS.contains(kind))
    {
        None => Ok(()),
        Some(unknown) => Err(format!(
            "it requires plugin ABI extension {unknown:#x}, which this cadr (plugin ABI {}.{}) \
             does not know",
            abi::CADR_PLUGIN_ABI_MAJOR,
            abi::CADR_PLUGIN_ABI_MINOR
        )),
    }
}

/// The size of [`abi::CadrTechniqueInfo`] in ABI 1.0.
fn first_info_size() -> usize {
    size_through!(abi::CadrTechniqueInfo, vtable)
}

/// A plugin's vtable copied into this host's layout: the bytes the plugin wrote, and none for
/// the functions of later minors it did not know. 8-byte words, as the vtables hold pointers.
#[derive(Debug)]
struct VtableCopy(Box<[u64]>);

impl VtableCopy {
    /// Copies `written` bytes of the vtable at `source` into a zeroed vtable of `full` bytes.
    ///
    /// # Safety
    /// `source` points at least `written` readable bytes.
    unsafe fn new(source: *const std::ffi::c_void, written: usize, full: usize) -> Self {
        let mut words = vec![0u64; full.div_ceil(8)].into_boxed_slice();
        // SAFETY: the caller vouches for `written` bytes at `source`; the copy takes at most
        // `full` of them, which the zeroed words hold. Every vtable field is an integer or an
        // optional function pointer, for which zero is valid (none).
        unsafe {
            std::ptr::copy_nonoverlapping(
                source.cast::<u8>(),
                words.as_mut_ptr().cast::<u8>(),
                written.min(full),
            );
        }
        Self(words)
    }

    fn as_ptr(&self) -> *const std::ffi::c_void {
        self.0.as_ptr().cast()
    }
}

/// One technique a library offers.
#[derive(Debug)]
pub struct TechniqueEntry {
    /// Its kind.
    pub kind: TechniqueKind,
    /// Its name (unique within the kind).
    pub name: String,
    /// What it does.
    pub description: String,
    /// The library it comes from ([`BUILT_IN_LIBRARY`] for the built-in techniques).
    pub library: PathBuf,
    /// The plugin ABI version (major, minor) its library was built for; an older minor's
    /// structs are read by their size, the fields it did not know taking defaults.
    pub abi_version: (u32, u32),
    /// Device features it needs (`CADR_FEATURE_*`).
    pub required_features: u64,
    /// What it offers its partners (`CADR_TRAIT_*`).
    pub provides: u64,
    /// What it needs from its partners (`CADR_TRAIT_*`).
    pub needs: u64,
    /// `Err(why)` when this device cannot run it.
    pub support: Result<(), String>,
    vtable: VtableCopy,
}

// SAFETY: the vtable copy is immutable; its function pointers point into a library that is
// never unloaded.
unsafe impl Send for TechniqueEntry {}
// SAFETY: as above.
unsafe impl Sync for TechniqueEntry {}

impl TechniqueEntry {
    /// An entry of ABI 1.`minor` with no functions, described only by its traits: what
    /// combination checks read.
    #[cfg(test)]
    pub(crate) fn described(
        kind: TechniqueKind,
        name: &str,
        minor: u32,
        (provides, needs): (u64, u64),
    ) -> Self {
        Self {
            kind,
            name: name.into(),
            description: String::new(),
            library: PathBuf::from("described.so"),
            abi_version: (abi::CADR_PLUGIN_ABI_MAJOR, minor),
            required_features: 0,
            provides,
            needs,
            support: Ok(()),
            vtable: VtableCopy(Box::new([])),
        }
    }

    /// Whether it is one of the built-in techniques (no plugin library needed).
    pub fn is_built_in(&self) -> bool {
        self.library.as_os_str() == BUILT_IN_LIBRARY
    }

    /// Whether it announces `trait_bit`, a `CADR_TRAIT_*` announcement that ABI 1.`since`
    /// introduced (see [`announces`]).
    pub(crate) fn announces(&self, trait_bit: abi::CadrTraitBits, since: u32) -> bool {
        announces((self.provides, self.abi_version.1), trait_bit, since)
    }

    /// The vtable, in this host's layout for the entry's kind (fields the plugin's ABI minor
    /// did not have are none).
    pub(crate) fn vtable(&self) -> *const std::ffi::c_void {
        self.vtable.as_ptr()
    }

    /// The common part of the vtable.
    pub(crate) fn common(&self) -> &abi::CadrCommonVtable {
        // SAFETY: every kind's vtable starts with the common part; the copy is as large as
        // this host's vtable of the entry's kind.
        unsafe { &*self.vtable().cast::<abi::CadrCommonVtable>() }
    }
}

/// Whether a technique that `provides` these traits, from a library of ABI minor `minor`,
/// announces `trait_bit`, which ABI 1.`since` introduced: a library built before then could not
/// have said so, whatever its bits.
pub(crate) fn announces(
    (provides, minor): (abi::CadrTraitBits, u32),
    trait_bit: abi::CadrTraitBits,
    since: u32,
) -> bool {
    minor >= since && provides & trait_bit != 0
}

/// A library or technique that cannot be used, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refusal {
    /// The library.
    pub library: PathBuf,
    /// The technique, when the refusal is about one technique.
    pub technique: Option<String>,
    /// Why.
    pub reason: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.technique {
            Some(name) => write!(f, "{} ({name}): {}", self.library.display(), self.reason),
            None => write!(f, "{}: {}", self.library.display(), self.reason),
        }
    }
}

/// Every technique found, and what was refused.
#[derive(Debug, Default)]
pub struct PluginRegistry {
    techniques: Vec<Arc<TechniqueEntry>>,
    refusals: Vec<Refusal>,
}

/// The `CADR_FEATURE_*` bits a device has enabled.
pub fn feature_bits(capabilities: Capabilities) -> u64 {
    let mut bits = 0;
    for (has, bit) in [
        (
            capabilities.multi_draw_indirect,
            abi::CADR_FEATURE_MULTI_DRAW_INDIRECT,
        ),
        (
            capabilities.draw_indirect_first_instance,
            abi::CADR_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE,
        ),
        (
            capabilities.draw_indirect_count,
            abi::CADR_FEATURE_DRAW_INDIRECT_COUNT,
        ),
        (capabilities.multi_draw, abi::CADR_FEATURE_MULTI_DRAW),
        (
            capabilities.buffer_device_address,
            abi::CADR_FEATURE_BUFFER_DEVICE_ADDRESS,
        ),
        (
            capabilities.shader_draw_parameters,
            abi::CADR_FEATURE_SHADER_DRAW_PARAMETERS,
        ),
        (
            capabilities.fragment_stores_and_atomics,
            abi::CADR_FEATURE_FRAGMENT_STORES_AND_ATOMICS,
        ),
        (capabilities.mesh_shader, abi::CADR_FEATURE_MESH_SHADER),
        (
            capabilities.device_generated_commands && capabilities.buffer_device_address,
            abi::CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT,
        ),
    ] {
        if has {
            bits |= bit;
        }
    }
    bits
}

/// Names of `CADR_FEATURE_*` bits, for messages.
pub fn feature_names(bits: u64) -> Vec<&'static str> {
    [
        (abi::CADR_FEATURE_MULTI_DRAW_INDIRECT, "multiDrawIndirect"),
        (
            abi::CADR_FEATURE_DRAW_INDIRECT_FIRST_INSTANCE,
            "drawIndirectFirstInstance",
        ),
        (abi::CADR_FEATURE_DRAW_INDIRECT_COUNT, "drawIndirectCount"),
        (abi::CADR_FEATURE_MULTI_DRAW, "VK_EXT_multi_draw"),
        (
            abi::CADR_FEATURE_BUFFER_DEVICE_ADDRESS,
            "bufferDeviceAddress",
        ),
        (
            abi::CADR_FEATURE_SHADER_DRAW_PARAMETERS,
            "shaderDrawParameters",
        ),
        (abi::CADR_FEATURE_MESH_SHADER, "VK_EXT_mesh_shader"),
        (
            abi::CADR_FEATURE_DEVICE_GENERATED_COMMANDS,
            "VK_NV_device_generated_commands",
        ),
        (
            abi::CADR_FEATURE_FRAGMENT_STORES_AND_ATOMICS,
            "fragmentStoresAndAtomics",
        ),
        (
            abi::CADR_FEATURE_DEVICE_GENERATED_COMMANDS_EXT,
            "VK_EXT_device_generated_commands",
        ),
    ]
    .into_iter()
    .filter(|&(bit, _)| bits & bit != 0)
    .map(|(_, name)| name)
    .collect()
}

/// The directory of the file this code was loaded from: the executable, or the shared library
/// (such as the C API's `libcadr.so`) that cadr-core is linked into. Linux only (read from
/// `/proc/self/maps`); `None` elsewhere.
fn loaded_from_dir() -> Option<PathBuf> {
    let address = loaded_from_dir as fn() -> Option<PathBuf> as usize;
    let maps = std::fs::read_to_string("/proc/self/maps").ok()?;
    maps.lines().find_map(|line| {
        let mut fields = line.split_whitespace();
        let (start, end) = fields.next()?.split_once('-')?;
        let start = usize::from_str_radix(start, 16).ok()?;
        let end = usize::from_str_radix(end, 16).ok()?;
        let path = fields.nth(4)?;
        ((start..end).contains(&address) && path.starts_with('/'))
            .then(|| Path::new(path).parent().map(Path::to_path_buf))
            .flatten()
    })
}

/// Every plugin library opened by this process; they stay loaded until it exits.
static KEPT_LIBRARIES: std::sync::Mutex<Vec<&'static libloading::Library>> =
    std::sync::Mutex::new(Vec::new());

/// The default plugin directories: beside the library cadr is linked into and beside the
/// executable (each with its `plugins/` and `cadr/plugins/` folders first; an installed
/// `lib/libcadr.so` finds `lib/cadr/plugins/`), then the directories in
/// [`PLUGIN_PATH_VARIABLE`].
pub fn default_plugin_dirs() -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = Vec::new();
    let exe_dir = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf));
    for dir in [loaded_from_dir(), exe_dir].into_iter().flatten() {
        for candidate in [dir.join("plugins"), dir.join("cadr").join("plugins"), dir] {
            if !dirs.contains(&candidate) {
                dirs.push(candidate);
            }
        }
    }
    if let Some(paths) = std::env::var_os(PLUGIN_PATH_VARIABLE) {
        dirs.extend(std::env::split_paths(&paths).filter(|p| !p.as_os_str().is_empty()));
    }
    dirs
}

/// Whether `path` looks like a cadr plugin library (`*cadr_plugin_*` with the platform's
/// dynamic-library extension).
fn is_plugin_file(path: &Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return false;
    };
    name.contains("cadr_plugin_") && name.ends_with(std::env::consts::DLL_SUFFIX)
}

fn c_text(pointer: *const c_char) -> Option<String> {
    // SAFETY: plugins hand out NUL-terminated strings that live as long as the library.
    (!pointer.is_null()).then(|| {
        unsafe { CStr::from_ptr(pointer) }
            .to_string_lossy()
            .into_owned()
    })
}

impl PluginRegistry {
    /// Loads every plugin library in `dirs` (missing directories are skipped) and checks its
    /// techniques against a device with `device_features` (`CADR_FEATURE_*`).
    /// The built-in techniques are registered first.
    pub fn discover(dirs: &[PathBuf], device_features: u64) -> Self {
        let mut registry = Self::built_in(device_features);
        let mut seen = std::collections::HashSet::new();
        for dir in dirs {
            let Ok(entries) = std::fs::read_dir(dir) else {
                continue;
            };
            let mut files: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| is_plugin_file(p))
                .collect();
            files.sort();
            for file in files {
                let canonical = file.canonicalize().unwrap_or_else(|_| file.clone());
                let key = canonical.file_name().map(|n| n.to_owned());
                if !seen.insert(key) {
                    continue; // the same library found in two directories: the first wins
                }
                registry.load(&file, device_features);
            }
        }
        registry
    }

    /// Only the built-in techniques, checked against a device with `device_features`.
    pub fn built_in(device_features: u64) -> Self {
        let mut registry = Self::default();
        registry.register(
            Path::new(BUILT_IN_LIBRARY),
            abi::CADR_PLUGIN_ABI_VERSION,
            cadr_techniques::builtin::entry,
            device_features,
        );
        registry
    }

    /// Loads one library.
    pub fn load(&mut self, file: &Path, device_features: u64) {
        let refuse = |reason: String| Refusal {
            library: file.to_owned(),
            technique: None,
            reason,
        };
        // SAFETY: opening a library runs its initialisers; cadr plugins are trusted code the
        // user installed (as any native plugin).
        let library = match unsafe { libloading::Library::new(file) } {
            Ok(library) => library,
            Err(error) => {
                self.refusals
                    .push(refuse(format!("cannot be opened: {error}")));
                return;
            }
        };
        // Never unloaded: techniques keep pointers into it. The list keeps it reachable, so
        // leak checkers see a library that is kept, not lost.
        let library: &'static libloading::Library = Box::leak(Box::new(library));
        KEPT_LIBRARIES
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .push(library);
        // SAFETY: the symbol's type is fixed by the ABI.
        let version = match unsafe {
            library.get::<abi::CadrPluginVersionFn>(abi::CADR_PLUGIN_VERSION_SYMBOL.as_bytes())
        } {
            Ok(symbol) => *symbol,
            Err(_) => {
                self.refusals.push(refuse(format!(
                    "is not a cadr plugin: it exports no `{}`",
                    abi::CADR_PLUGIN_VERSION_SYMBOL
                )));
                return;
            }
        };
        // SAFETY: takes nothing, returns an integer.
        let version = unsafe { version() };
        // SAFETY: the symbol's type is fixed by the ABI (whose version `register` checks before
        // calling it).
        let entry = match unsafe {
            library.get::<abi::CadrPluginEntryFn>(abi::CADR_PLUGIN_ENTRY_SYMBOL.as_bytes())
        } {
            Ok(symbol) => *symbol,
            Err(_) => {
                self.refusals.push(refuse(format!(
                    "exports no `{}`",
                    abi::CADR_PLUGIN_ENTRY_SYMBOL
                )));
                return;
            }
        };
        self.register(file, version, entry, device_features);
    }

    /// Registers the techniques of a library described by `entry`, built for ABI `version`
    /// (major in the high 16 bits): a loaded plugin or the built-in library.
    fn register(
        &mut self,
        file: &Path,
        version: u32,
        entry: abi::CadrPluginEntryFn,
        device_features: u64,
    ) {
        let refuse = |reason: String| Refusal {
            library: file.to_owned(),
            technique: None,
            reason,
        };
        // Any minor of this major: an older one's structs are read by their size, a newer
        // one's by the prefix this host knows (its techniques may require extensions, checked
        // below).
        let (major, minor) = (version >> 16, version & 0xffff);
        if major != abi::CADR_PLUGIN_ABI_MAJOR {
            self.refusals.push(refuse(format!(
                "was built for plugin ABI {major}.{minor}; this cadr speaks {}.{}",
                abi::CADR_PLUGIN_ABI_MAJOR,
                abi::CADR_PLUGIN_ABI_MINOR
            )));
            return;
        }
        let mut described = abi::CadrPluginLibrary {
            size: std::mem::size_of::<abi::CadrPluginLibrary>() as u32,
            abi_major: 0,
            abi_minor: 0,
            name: std::ptr::null(),
            technique_count: 0,
            techniques: std::ptr::null(),
        };
        // SAFETY: `described` is writable and its size set.
        let status = unsafe { entry(&mut described) };
        if status != abi::CADR_STATUS_OK {
            let why = if status == abi::CADR_STATUS_PANICKED {
                "panicked in its entry point"
            } else {
                "its entry point failed"
            };
            self.refusals.push(refuse(why.into()));
            return;
        }
        // The host's struct was zeroed and its size set: a library of an older minor writes
        // a prefix of it, and the fields it did not know stay empty.
        if (described.size as usize) < first_library_size()
            || (described.technique_count > 0 && described.techniques.is_null())
        {
            self.refusals
                .push(refuse("described itself with a truncated struct".into()));
            return;
        }
        // Entries lie `size` bytes apart, the size the library's ABI minor gave them.
        let stride = if described.technique_count == 0 {
            0
        } else {
            // SAFETY: checked non-null; the library promises `technique_count` entries.
            unsafe { (*described.techniques).size as usize }
        };
        if described.technique_count > 0 && stride < first_info_size() {
            self.refusals
                .push(refuse("its technique descriptions are truncated".into()));
            return;
        }
        for index in 0..described.technique_count as usize {
            // SAFETY: the library promises `technique_count` entries of `stride` bytes that
            // live forever; a copy of the bytes it wrote over a zeroed description leaves the
            // fields of later minors empty (every field is an integer or a pointer).
            let info = unsafe {
                let mut info: abi::CadrTechniqueInfo = std::mem::zeroed();
                std::ptr::copy_nonoverlapping(
                    described.techniques.cast::<u8>().add(index * stride),
                    (&mut info as *mut abi::CadrTechniqueInfo).cast::<u8>(),
                    stride.min(std::mem::size_of::<abi::CadrTechniqueInfo>()),
                );
                info
            };
            self.register_technique(file, (major, minor), (&info, stride), device_features);
        }
    }

    /// Registers one technique of a library of ABI `(major, minor)` from its description
    /// (copied into this host's layout from entries `stride` bytes apart, the size of the
    /// library's first description), or records why it is refused.
    fn register_technique(
        &mut self,
        file: &Path,
        (major, minor): (u32, u32),
        (info, stride): (&abi::CadrTechniqueInfo, usize),
        device_features: u64,
    ) {
        let name = c_text(info.name).unwrap_or_default();
        let refuse_technique = |reason: String| Refusal {
            library: file.to_owned(),
            technique: Some(name.clone()),
            reason,
        };
        if info.size as usize != stride {
            self.refusals.push(refuse_technique(
                "its description's size differs from the library's first one".into(),
            ));
            return;
        }
        let Some(kind) = TechniqueKind::from_abi(info.kind) else {
            self.refusals
                .push(refuse_technique(format!("unknown kind {}", info.kind)));
            return;
        };
        if name.is_empty() {
            self.refusals
                .push(refuse_technique("it has no name".into()));
            return;
        }
        if let Err(why) = check_required_extensions(info) {
            self.refusals.push(refuse_technique(why));
            return;
        }
        // SAFETY: checked non-null before reading its size.
        let vtable_size = (!info.vtable.is_null())
            .then(|| unsafe { (*info.vtable.cast::<abi::CadrCommonVtable>()).size });
        let Some(vtable_size) =
            vtable_size.filter(|&size| size as usize >= kind.first_vtable_size())
        else {
            self.refusals.push(refuse_technique(format!(
                "its {} vtable is missing or truncated",
                kind.name()
            )));
            return;
        };
        // Before ABI 1.3 the culling vtable's `record_gpu` was reserved: not read.
        let readable = if kind == TechniqueKind::Culling && minor < 3 {
            (vtable_size as usize).min(kind.first_vtable_size())
        } else {
            vtable_size as usize
        };
        // SAFETY: the vtable's size says how many bytes the library wrote.
        let vtable = unsafe { VtableCopy::new(info.vtable, readable, kind.vtable_size()) };
        if self
            .techniques
            .iter()
            .any(|t| t.kind == kind && t.name == name)
        {
            self.refusals.push(refuse_technique(format!(
                "another library already offers a {} technique named '{name}'",
                kind.name()
            )));
            return;
        }
        let missing = info.required_features & !device_features;
        let support = if missing == 0 {
            Ok(())
        } else {
            Err(format!(
                "the device lacks {}",
                feature_names(missing).join(", ")
            ))
        };
        self.techniques.push(Arc::new(TechniqueEntry {
            kind,
            name,
            description: c_text(info.description).unwrap_or_default(),
            library: file.to_owned(),
            abi_version: (major, minor),
            required_features: info.required_features,
            provides: info.provides,
            needs: info.needs,
            support,
            vtable,
        }));
    }

    /// Every technique found (supported or not), in discovery order.
    pub fn techniques(&self) -> &[Arc<TechniqueEntry>] {
        &self.techniques
    }

    /// Libraries and techniques that were refused while loading.
    pub fn refusals(&self) -> &[Refusal] {
        &self.refusals
    }

    /// The technique of `kind` named `name`.
    pub fn find(&self, kind: TechniqueKind, name: &str) -> Option<&Arc<TechniqueEntry>> {
        self.techniques
            .iter()
            .find(|t| t.kind == kind && t.name == name)
    }

    /// The techniques of one kind.
    pub fn of_kind(&self, kind: TechniqueKind) -> impl Iterator<Item = &Arc<TechniqueEntry>> {
        self.techniques.iter().filter(move |t| t.kind == kind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_extension_kind_of_this_abi_is_known() {
        // Kinds are numbered from 1 without gaps; the newest is ABI 1.24's.
        let newest = abi::CADR_EXTENSION_EMPTY_COMMAND_TAILS;
        for kind in 1..=newest {
            assert!(KNOWN_EXTENSIONS.contains(&kind), "kind {kind}");
        }
        assert_eq!(KNOWN_EXTENSIONS.len(), newest as usize);
    }

    #[test]
    fn plugin_dirs_start_beside_the_binary_and_end_with_the_variable() {
        let dirs = default_plugin_dirs();
        let exe_dir = std::env::current_exe().unwrap_or_default();
        let exe_dir = exe_dir.parent().unwrap_or(Path::new("/"));
        assert!(dirs.contains(&exe_dir.to_path_buf()), "{dirs:?}");
        assert!(dirs.contains(&exe_dir.join("plugins")), "{dirs:?}");
        assert!(is_plugin_file(Path::new("/x/libcadr_plugin_vertex.so")));
        assert!(!is_plugin_file(Path::new("/x/libcadr.so")));
        assert!(!is_plugin_file(Path::new(
            "/x/libcadr_plugin_vertex.so.txt"
        )));
    }

    /// An entry point describing two culling techniques, `first` and `second`, whose
    /// descriptions lie `size_of::<CadrTechniqueInfo>()` bytes apart; `second` says it is 8
    /// bytes shorter.
    unsafe extern "C" fn two_descriptions(library: *mut abi::CadrPluginLibrary) -> abi::CadrStatus {
        // SAFETY: every field of a vtable is an integer or an optional function: zero is none.
        let vtable: &'static mut abi::CadrCullingVtable =
            Box::leak(Box::new(unsafe { std::mem::zeroed() }));
        vtable.common.size = std::mem::size_of::<abi::CadrCullingVtable>() as u32;
        let vtable = (vtable as *const abi::CadrCullingVtable).cast();
        let size = std::mem::size_of::<abi::CadrTechniqueInfo>() as u32;
        let info = |name: &'static CStr, size| abi::CadrTechniqueInfo {
            size,
            kind: abi::CADR_KIND_CULLING,
            name: name.as_ptr(),
            description: c"".as_ptr(),
            required_features: 0,
            provides: 0,
            needs: 0,
            vtable,
            extensions: std::ptr::null(),
            required_extensions: std::ptr::null(),
            required_extension_count: 0,
        };
        let infos = Box::leak(Box::new([info(c"first", size), info(c"second", size - 8)]));
        // SAFETY: the host passes its own writable, sized struct.
        let library = unsafe { &mut *library };
        library.abi_major = abi::CADR_PLUGIN_ABI_MAJOR;
        library.abi_minor = abi::CADR_PLUGIN_ABI_MINOR;
        library.name = c"two".as_ptr();
        library.technique_count = 2;
        library.techniques = infos.as_ptr();
        abi::CADR_STATUS_OK
    }

    #[test]
    fn a_description_whose_size_differs_from_the_first_is_refused() {
        let mut registry = PluginRegistry::default();
        registry.register(
            Path::new("two"),
            abi::CADR_PLUGIN_ABI_VERSION,
            two_descriptions,
            0,
        );
        let names: Vec<&str> = registry.techniques().iter().map(|t| &*t.name).collect();
        assert_eq!(names, ["first"]);
        let refusal = registry.refusals().first().expect("a refusal").to_string();
        assert!(
            refusal.contains("second") && refusal.contains("size differs"),
            "{refusal}"
        );
    }

    #[test]
    fn missing_features_are_named() {
        let bits = abi::CADR_FEATURE_MULTI_DRAW | abi::CADR_FEATURE_MESH_SHADER;
        assert_eq!(
            feature_names(bits),
            vec!["VK_EXT_multi_draw", "VK_EXT_mesh_shader"]
        );
    }
}
