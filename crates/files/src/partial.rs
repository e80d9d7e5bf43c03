//! The temporary files of outputs being written (`.NAME.XXXXXX.partial`, beside their
//! targets), and what an interrupt does with them.
//!
//! Every live temporary is listed in one registry. It is renamed over its target, or removed,
//! while the registry is locked, and the interrupt handler ([`remove_on_interrupt`]) takes the
//! same lock before it removes what is listed and exits: so a signal finds each output either
//! still old (its temporary then goes) or whole and new, never half-written, and nothing is
//! renamed after the handler has run.

use std::fs::{File, Permissions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use tempfile::NamedTempFile;

/// The temporaries that exist now.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<PathBuf>> {
    // A panic elsewhere while the list was held leaves a list that is still whole.
    LIVE.lock().unwrap_or_else(PoisonError::into_inner)
}

fn forget(live: &mut Vec<PathBuf>, path: &Path) {
    if let Some(i) = live.iter().position(|p| p == path) {
        live.swap_remove(i);
    }
}

/// A temporary file beside `target`, to be renamed over it once whole ([`Partial::persist`]);
/// dropped unrenamed, it is removed and the target is left as it was.
pub(crate) struct Partial {
    file: Option<NamedTempFile>,
    target: PathBuf,
}

impl Partial {
    /// Creates the temporary with `permissions` (the old file's), or, for a new file, 0666 less
    /// the umask, as any file the user creates.
    pub(crate) fn create(target: &Path, permissions: Option<Permissions>) -> io::Result<Self> {
        let name = target
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".partial");
        #[cfg(unix)]
        if permissions.is_none() {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(Permissions::from_mode(0o666));
        }
        let folder = crate::file::parent(target);
        // Listed before the lock is let go, so that no signal can come between.
        let mut live = live();
        let file = builder.tempfile_in(folder)?;
        live.push(file.path().to_path_buf());
        drop(live);
        let partial = Self {
            file: Some(file),
            target: target.to_path_buf(),
        };
        if let Some(p) = permissions {
            partial.as_file().set_permissions(p)?;
        }
        Ok(partial)
    }

    pub(crate) fn as_file(&self) -> &File {
        self.file.as_ref().expect("live until persisted").as_file()
    }

    /// Renames the whole file over its target.
    pub(crate) fn persist(mut self) -> io::Result<()> {
        let file = self.file.take().expect("live until persisted");
        let mut live = live();
        let path = file.path().to_path_buf();
        let renamed = file.persist(&self.target);
        // A failed rename gives the temporary back; it is removed here, with the lock held.
        let result = renamed.map(drop).map_err(|e| e.error);
        forget(&mut live, &path);
        result
    }
}

impl Drop for Partial {
    fn drop(&mut self) {
        if let Some(file) = self.file.take() {
            let mut live = live();
            let path = file.path().to_path_buf();
            drop(file);
            forget(&mut live, &path);
        }
    }
}

/// How many temporaries exist now (for tests).
pub fn live_count() -> usize {
    live().len()
}

/// Ends the process on SIGINT, SIGTERM or SIGHUP with status 128 + the signal, as a shell
/// reports a process the signal ended, after removing every live temporary: each output is then
/// the old file or the whole new one. For a command line; a library's host (Python) keeps its
/// own handlers. Calls after the first do nothing.
#[cfg(unix)]
pub fn remove_on_interrupt() -> io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    let mut result = Ok(());
    INSTALLED.call_once(|| {
        result =
            signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]).and_then(|mut s| {
                std::thread::Builder::new()
                    .name("interrupt".into())
                    .spawn(move || {
                        if let Some(signal) = s.forever().next() {
                            // Held until the process ends: nothing is renamed after this.
                            let live = live();
                            for path in live.iter() {
                                let _ = std::fs::remove_file(path);
                            }
                            std::process::exit(128 + signal);
                        }
                    })
                    .map(drop)
            });
    });
    result
}

/// Nothing to install where there are no such signals.
#[cfg(not(unix))]
pub fn remove_on_interrupt() -> io::Result<()> {
    Ok(())
}
