//! Models loaded at run time: a model library built by `make model` (a shared library with
//! toolconf's C ABI, crates/cabi), opened, checked and registered next to the built-in models,
//! so that every entry point (the command line's `--model-path`, `TOOLCONF_MODEL_PATH`,
//! Python's `toolconf.load_model`, Dask's workers) runs it by name with no rebuild.
//!
//! * **Checked before use.** The file must be a regular file that starts as a shared library
//!   does; then, in this order: `toolconf_abi_version()` equals [`toolconf_cabi::ABI_VERSION`],
//!   every symbol of the ABI is there, the task list's fingerprint is this toolconf's, and the
//!   metadata is whole and consistent (sizes, names, finite numbers). Each failure is one
//!   [`LoadError`] naming the file and what is wrong.
//! * **Trusted as native code.** Opening a library runs its initialisers and every call runs
//!   its code with the process's privileges: nothing here can make an untrusted library safe
//!   (docs/reference/c-abi.md, "What a loaded library is trusted with"). Load only libraries you built.
//! * **The same numbers.** A loaded model runs the same const-generic runtime as a built-in one
//!   ([`table::Loaded`]), and the library's functions are the same generated code: the
//!   results are the built-in model's, bit for bit (tests/loaded_models.rs).
//! * **Never unloaded.** A library stays mapped for the life of the process (the registry hands
//!   out `'static` models); loading the same file under the same name again returns the model
//!   loaded before.

mod elf;
mod metadata;
mod table;

use std::ffi::CStr;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use toolconf_cabi::{Exports, ABI_VERSION};

use crate::registry::{self, ModelKind};

pub use table::{Loaded, SIZES, SLOTS};

/// The environment variable naming model libraries to load at start, separated by `:` as
/// `PATH` is; each entry a library file or the folder `make model` wrote it into, or
/// `NAME=PATH` to load it under another name.
pub const ENVIRONMENT: &str = "TOOLCONF_MODEL_PATH";

/// Why a model library was not loaded: the file and what is wrong with it, in one line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadError {
    pub path: String,
    pub reason: String,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "model library {}: {}", self.path, self.reason)
    }
}

impl std::error::Error for LoadError {}

/// An opened library and its exports.
pub(crate) struct Library {
    pub exports: Exports,
}

/// What was loaded, by (canonical file, the name asked for): loading it again returns its
/// model, with no second copy of its metadata.
static LOADED: Mutex<Vec<(PathBuf, Option<String>, ModelKind)>> = Mutex::new(Vec::new());

/// Loads the model library at `path` (the file, or the folder `make model` wrote, holding one
/// `libtoolconf_model_*` library) and registers its model under `name`, or under its own name
/// when `name` is `None`; returns its handle. Loading the same file under the same name again
/// returns the same handle.
pub fn load(path: &Path, name: Option<&str>) -> Result<ModelKind, LoadError> {
    let shown = toolconf_messages::ClipPath(&path.display().to_string()).to_string();
    let fail = |reason: String| LoadError {
        path: shown.clone(),
        reason,
    };
    let file = library_file(path).map_err(&fail)?;
    let canonical = file
        .canonicalize()
        .map_err(|e| fail(format!("cannot resolve: {e}")))?;
    // One load at a time: the slots and the registry are filled in order.
    let mut loaded = LOADED.lock().unwrap_or_else(|p| p.into_inner());
    let asked = name.map(str::to_string);
    if let Some((_, _, kind)) = loaded
        .iter()
        .find(|(p, n, _)| *p == canonical && *n == asked)
    {
        return Ok(*kind);
    }
    let (handle, library) = open(&canonical).map_err(&fail)?;
    let metadata = metadata::read(&library.exports, name).map_err(&fail)?;
    room_for(&metadata, &loaded).map_err(&fail)?;
    let model = table::install(&library, metadata.leak()).map_err(&fail)?;
    let kind = registry::register(model).map_err(fail)?;
    // The library stays loaded: its functions back a 'static model.
    std::mem::forget(handle);
    loaded.push((canonical, asked, kind));
    Ok(kind)
}

/// The exports of the model library at `path` (as [`load`] takes it), checked as [`load`]
/// checks them but not registered as a model: for a program that calls a library's C ABI
/// itself (tests/loaded_models.rs fuzzes libraries with each other's controllers). The
/// library stays loaded.
pub fn open_exports(path: &Path) -> Result<Exports, LoadError> {
    let fail = |reason: String| LoadError {
        path: toolconf_messages::ClipPath(&path.display().to_string()).to_string(),
        reason,
    };
    let file = library_file(path).map_err(&fail)?;
    let (handle, library) = open(&file).map_err(&fail)?;
    std::mem::forget(handle);
    Ok(library.exports)
}

/// Whether the model `metadata` describes can be registered: its name free, its size one the
/// runtime was compiled for ([`SIZES`]), a slot of that size free.
fn room_for(
    metadata: &metadata::Metadata,
    loaded: &[(PathBuf, Option<String>, ModelKind)],
) -> Result<(), String> {
    let all = ModelKind::all();
    if let Some(other) = all.into_iter().find(|k| k.name() == metadata.name) {
        let whose = match loaded.iter().find(|(_, _, k)| *k == other) {
            Some((p, _, _)) => format!(
                "loaded from {}",
                toolconf_messages::ClipPath(&p.display().to_string())
            ),
            None => "built in".to_string(),
        };
        return Err(format!(
            "a model named '{}' is already {whose}: load this one under another name \
             (NAME=PATH on the command line and in {ENVIRONMENT}, name= in Python)",
            metadata.name
        ));
    }
    let size = (metadata.dof, metadata.parameter_count());
    if !SIZES.contains(&size) {
        let sizes: Vec<String> = SIZES.iter().map(|(n, p)| format!("({n}, {p})")).collect();
        return Err(format!(
            "{} joints and {} tool parameters: this toolconf runs loaded models of the sizes \
             (joints, parameters) {}",
            size.0,
            size.1,
            sizes.join(", ")
        ));
    }
    if !table::slot_free(size) {
        return Err(format!(
            "{SLOTS} models of {} joints and {} tool parameters are loaded already, the most one \
             process holds",
            size.0, size.1
        ));
    }
    Ok(())
}

/// One entry of `--model-path` or [`ENVIRONMENT`] as (path, name): `PATH`, or `NAME=PATH` (a
/// name has no `/`, so a path with `=` in a folder's name stays a path).
pub fn parse_entry(entry: &str) -> (&str, Option<&str>) {
    match entry.split_once('=') {
        Some((name, path)) if !name.is_empty() && !name.contains('/') => (path, Some(name)),
        _ => (entry, None),
    }
}

/// Loads one entry of `--model-path` or [`ENVIRONMENT`] ([`parse_entry`]).
pub fn load_entry(entry: &str) -> Result<ModelKind, LoadError> {
    let (path, name) = parse_entry(entry);
    load(Path::new(path), name)
}

/// The entries of [`ENVIRONMENT`] (`:`-separated, empty entries skipped), in order, each as
/// [`parse_entry`] reads it; none when it is not set.
pub fn environment_entries() -> Result<Vec<(String, Option<String>)>, LoadError> {
    let Some(value) = std::env::var_os(ENVIRONMENT) else {
        return Ok(Vec::new());
    };
    let value = value.to_str().ok_or_else(|| LoadError {
        path: toolconf_messages::ClipPath(&value.to_string_lossy()).to_string(),
        reason: "is not valid UTF-8".into(),
    })?;
    Ok(value
        .split(':')
        .filter(|e| !e.trim().is_empty())
        .map(|e| {
            let (path, name) = parse_entry(e);
            (path.to_string(), name.map(str::to_string))
        })
        .collect())
}

/// Loads every entry of [`ENVIRONMENT`], in order.
pub fn load_environment() -> Result<Vec<ModelKind>, LoadError> {
    environment_entries()?
        .iter()
        .map(|(path, name)| load(Path::new(path), name.as_deref()))
        .collect()
}

/// The library file `path` names: `path` itself if it is a file, the one
/// `libtoolconf_model_*` library in it if it is a folder.
fn library_file(path: &Path) -> Result<PathBuf, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read: {e}"))?;
    if meta.is_file() {
        return Ok(path.to_path_buf());
    }
    if !meta.is_dir() {
        return Err("is not a file or a folder (a device, a pipe or a socket)".into());
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| format!("cannot list the folder: {e}"))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.starts_with("libtoolconf_model_")
                && (name.ends_with(".so") || name.ends_with(".dylib"))
                && p.is_file()
        })
        .collect();
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => Err(
            "holds no model library (make model writes libtoolconf_model_<model>.so into its \
                  OUT folder)"
                .into(),
        ),
        _ => Err(format!(
            "holds {} model libraries: name one of them",
            found.len()
        )),
    }
}

/// Opens `file` once, checks it through that descriptor (a regular file, a shared library of
/// this system whose headers fit in it: [`elf::check`]), has the dynamic loader map the very
/// file it checked (`/proc/self/fd/<n>`, not the path again, which may meanwhile name another
/// file), and reads its exports: the ABI version first, then every symbol, then the task
/// list's fingerprint.
///
/// What remains: a file changed in place after the check (truncated, or overwritten by `cp`)
/// can still fault while or after it is mapped, as any shared library can; `make model`
/// replaces a library by renaming a new file over it, which leaves a loaded one intact.
fn open(file: &Path) -> Result<(libloading::Library, Library), String> {
    use std::os::unix::fs::OpenOptionsExt;
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(file)
        .map_err(|e| format!("cannot read: {e}"))?;
    let meta = f.metadata().map_err(|e| format!("cannot read: {e}"))?;
    if !meta.is_file() {
        return Err("is not a file or a folder (a device, a pipe or a socket)".into());
    }
    let mut ident = [0u8; 6];
    let read = std::os::unix::fs::FileExt::read_at(&f, &mut ident, 0)
        .map_err(|e| format!("cannot read: {e}"))?;
    let magic = [ident[0], ident[1], ident[2], ident[3]];
    if read >= 6 && magic == *b"\x7fELF" {
        elf::check(&f, meta.len(), &ident)?;
    } else if read < 4 || !is_mach_o(magic) {
        return Err(
            "is not a shared library (no ELF or Mach-O header): make model writes \
                    libtoolconf_model_<model>.so"
                .into(),
        );
    } else if !cfg!(target_vendor = "apple") {
        return Err("is a Mach-O library (macOS): this system loads ELF libraries".into());
    }
    let handle = dlopen(f, file)?;
    let exports = checked_exports(&handle)?;
    Ok((handle, Library { exports }))
}

/// Has the dynamic loader map the file open as `f`, by its descriptor where /proc gives one.
/// Once the loader has taken it, the descriptor is never closed, whether the library is then
/// registered or refused: the loader keeps `/proc/self/fd/<n>` among the names of what it
/// loaded (as an alias of an already loaded library, when it is the same file), and would
/// answer a later file opened under the same number with that library.
fn dlopen(f: std::fs::File, file: &Path) -> Result<libloading::Library, String> {
    use std::os::fd::{AsRawFd, IntoRawFd};
    let by_fd = PathBuf::from(format!("/proc/self/fd/{}", f.as_raw_fd()));
    let target = match by_fd.exists() {
        true => by_fd.clone(),
        false => file.to_path_buf(),
    };
    // SAFETY: opening a library runs its initialisers: a model library is trusted native code
    // (the module's documentation).
    let handle = unsafe { libloading::Library::new(&target) }.map_err(|e| {
        let message = e
            .to_string()
            .replace(&*by_fd.to_string_lossy(), &file.to_string_lossy());
        format!(
            "cannot be loaded: {}",
            toolconf_messages::ClipMessage(&message)
        )
    })?;
    if target == by_fd {
        let _never_closed = f.into_raw_fd();
    }
    Ok(handle)
}

/// The exports of an opened library: the ABI version first, then every symbol, then the
/// task list's fingerprint.
fn checked_exports(handle: &libloading::Library) -> Result<Exports, String> {
    // SAFETY: the symbol's type is the ABI's; the value is copied while `handle` is alive, and
    // `handle` outlives every use (it is never closed once the model is registered).
    let version = unsafe { handle.get::<extern "C" fn() -> u32>(b"toolconf_abi_version\0") }
        .map_err(|_| {
            "is not a toolconf model library: it has no symbol toolconf_abi_version".to_string()
        })?;
    let version = version();
    if version != ABI_VERSION {
        return Err(format!(
            "its C ABI is version {version}, this toolconf reads version {ABI_VERSION}: rebuild \
             it with make model from this toolconf"
        ));
    }
    let exports = exports(handle)?;
    // SAFETY: the function returns a NUL-terminated string owned by the library.
    let theirs = unsafe { c_text((exports.tasks_fingerprint)()) };
    let ours = toolconf_cabi::fingerprint::hex();
    if theirs.as_deref() != Some(ours) {
        return Err(format!(
            "it was derived with another task list (fingerprint {}, this toolconf's {}): rebuild \
             it with make model from this toolconf",
            theirs
                .as_deref()
                .map_or("unreadable", |t| &t[..t.len().min(16)]),
            &ours[..16]
        ));
    }
    Ok(exports)
}

fn is_mach_o(magic: [u8; 4]) -> bool {
    matches!(
        u32::from_le_bytes(magic),
        0xfeed_facf | 0xcffa_edfe | 0xcafe_babe | 0xbeba_feca
    )
}

/// Every export by its symbol, or the first missing one named.
fn exports(handle: &libloading::Library) -> Result<Exports, String> {
    macro_rules! symbols {
        ($($field:ident),* $(,)?) => {{
            Exports {
                $($field: {
                    // The C name is the field's (exports.rs: `toolconf_<field>`).
                    let name = concat!("toolconf_", stringify!($field));
                    // SAFETY: the symbol's type is the one the ABI gives it ([`Exports`]); the
                    // pointer is used only while the library is loaded.
                    *unsafe { handle.get(concat!("toolconf_", stringify!($field), "\0").as_bytes()) }
                        .map_err(|_| format!("is not a whole toolconf model library: it has no symbol {name}"))?
                },)*
            }
        }};
    }
    Ok(symbols!(
        abi_version,
        tasks_fingerprint,
        model_info,
        last_error,
        status_name,
        check_tool,
        dynamics,
        dynamics_jacobian,
        rigid_body_dynamics,
        tip,
        tip_bias,
        state_matrix,
        input_matrix,
        task_defaults,
        sensitivities,
        pi_u,
        logdet_gradient,
        control_confidence,
        controller_create,
        controller_destroy,
        controller_tick,
        controller_tick_with_acceleration,
        controller_pi_u,
    ))
}

/// The longest string read from a library's metadata.
const MAX_TEXT: usize = 4096;

/// A C string from a library as UTF-8 text, `None` if NULL, too long or not UTF-8.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string.
pub(crate) unsafe fn c_text(p: *const core::ffi::c_char) -> Option<String> {
    if p.is_null() {
        return None;
    }
    let s = CStr::from_ptr(p).to_str().ok()?;
    (s.len() <= MAX_TEXT).then(|| s.to_string())
}
