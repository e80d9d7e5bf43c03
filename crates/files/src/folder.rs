//! A generated folder, `make crate`'s crate: the rule by which a folder of generated files is
//! replaced, the folder counterpart of [`crate::file`].
//!
//! * The folder holds an ownership manifest, [`MANIFEST`], listing every file written into it
//!   with its SHA-256 (as `sha256sum` writes them, under a first line of its own).
//! * OUT must not exist, or be an empty folder, or be a folder this rule made whose files are all
//!   still as listed, with nothing else in it but cargo's [`CARGO_PRODUCTS`] (`Cargo.lock`,
//!   `target/`), which the new folder keeps: a `Cargo.toml` that looks generated is no licence,
//!   and nothing the run did not write is ever deleted or replaced.
//! * OUT may not be a symbolic link, lie inside the repository or hold it, or hold or be inside
//!   an input (the descriptions, their URDFs, the task file), and none of the files it would
//!   replace may be an input by another name (a hard link).
//! * The new folder is made in a temporary folder beside OUT ([`CrateFolder::stage`]) and renamed
//!   into place ([`CrateFolder::install`]); the old one is moved aside first and removed only once
//!   the new one is in place. SIGINT, SIGTERM and SIGHUP wait while the folders are swapped, so an
//!   interrupt finds the old folder or the new one, never neither.
//!
//! Nothing in OUT is opened but regular files (a FIFO there is refused, not waited on), and each
//! refusal is one line naming the path ([`FolderError::Refused`], status 2 for a command line).

use std::collections::BTreeMap;
use std::fs;
use std::io;
use std::path::{Component, Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::run_files::resolved;
use crate::WriteError;

/// The ownership manifest in every folder this rule makes.
pub const MANIFEST: &str = ".toolconf-crate";
/// What cargo makes in a crate it builds or tests: kept across a replacement, never deleted.
pub const CARGO_PRODUCTS: [&str; 2] = ["Cargo.lock", "target"];

/// Why a folder was not made.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// Bad input, refused before anything changed: one line naming the path.
    #[error("{0}")]
    Refused(String),
    /// A failure while writing.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// What is at OUT before the new folder goes there.
#[derive(Debug, PartialEq, Eq)]
pub enum Previous {
    Nothing,
    Empty,
    /// A folder this rule made, unchanged: the files its manifest lists, with their hashes.
    Ours(BTreeMap<String, String>),
}

/// The rule for one generated folder, OUT, and the files of the run that makes it.
#[derive(Debug)]
pub struct CrateFolder {
    label: String,
    out: PathBuf,
    command: String,
    repository: Option<PathBuf>,
    inputs: Vec<(String, PathBuf)>,
}

/// A folder being made beside OUT; removed when dropped, unless installed.
pub struct Staging(tempfile::TempDir);

impl Staging {
    pub fn path(&self) -> &Path {
        self.0.path()
    }
}

fn refused(message: String) -> FolderError {
    FolderError::Refused(message)
}

fn write_error(path: &Path) -> impl FnOnce(io::Error) -> FolderError + '_ {
    move |e| WriteError::at(path)(e).into()
}

/// Whether `path` is `folder` or under it (both absolute, normalised).
fn inside(path: &Path, folder: &Path) -> bool {
    path.starts_with(folder)
}

/// `out` made absolute, `.` and `..` taken as written, its folder's links resolved but not its
/// own: a link is refused, and the folder is named after the name given.
fn out_path(out: &Path) -> Option<PathBuf> {
    let mut normal = PathBuf::new();
    for part in std::path::absolute(out).ok()?.components() {
        match part {
            Component::ParentDir => {
                normal.pop();
            }
            Component::CurDir => {}
            other => normal.push(other),
        }
    }
    let name = normal.file_name()?.to_owned();
    Some(resolved(normal.parent()?).join(name))
}

impl CrateFolder {
    /// The rule for the folder `out`, named `label` in messages (`OUT`), made by `command`
    /// (`make crate`, in the manifest and the messages).
    pub fn new(label: &str, out: &Path, command: &str) -> Result<Self, FolderError> {
        let normal = out_path(out)
            .ok_or_else(|| refused(format!("{label}={}: names no folder", out.display())))?;
        Ok(Self {
            label: label.into(),
            out: normal,
            command: command.into(),
            repository: None,
            inputs: Vec::new(),
        })
    }

    /// The repository, whose files OUT may not lie among (`make derive` owns them).
    pub fn repository(&mut self, dir: &Path) -> &mut Self {
        self.repository = Some(resolved(dir));
        self
    }

    /// A file or folder the run reads, named `label` in messages (`TASKS=tasks.toml`).
    pub fn input(&mut self, label: &str, path: &Path) -> &mut Self {
        self.inputs.push((label.into(), path.into()));
        self
    }

    /// OUT as checked: absolute, its folder's links resolved.
    pub fn out(&self) -> &Path {
        &self.out
    }

    fn says(&self, what: impl std::fmt::Display) -> FolderError {
        refused(format!("{}={}: {what}", self.label, self.out.display()))
    }

    fn header(&self) -> String {
        format!(
            "# files written by `{}`; the crate is replaced only while they are as listed",
            self.command
        )
    }

    /// Everything the rule asks of OUT, before any work: where it is, then what is there.
    pub fn check(&self) -> Result<Previous, FolderError> {
        self.check_place()?;
        let previous = self.previous()?;
        if let Previous::Ours(owned) = &previous {
            self.check_same_files(owned)?;
        }
        Ok(previous)
    }

    /// OUT is outside the repository, is no input, holds none and is inside none.
    fn check_place(&self) -> Result<(), FolderError> {
        let out = &self.out;
        if let Some(repo) = &self.repository {
            if inside(out, repo) || inside(repo, out) {
                return Err(self.says(format_args!(
                    "inside the repository {}; give a folder outside it",
                    repo.display()
                )));
            }
        }
        for (label, path) in &self.inputs {
            let real = resolved(path);
            if inside(&real, out) {
                return Err(self.says(format_args!(
                    "{label} is inside it; the crate would replace it"
                )));
            }
            if inside(out, &real) {
                return Err(self.says(format_args!(
                    "it is inside {label}; the crate would replace it"
                )));
            }
        }
        let folder = crate::file::parent(out);
        if !folder.is_dir() {
            return Err(self.says(format_args!(
                "the folder {} does not exist",
                folder.display()
            )));
        }
        Ok(())
    }

    /// No file the new folder replaces is an input by another name (a hard link to it).
    fn check_same_files(&self, owned: &BTreeMap<String, String>) -> Result<(), FolderError> {
        for (label, input) in &self.inputs {
            let Ok(meta) = fs::metadata(input) else {
                continue;
            };
            for name in owned.keys() {
                let path = self.out.join(name);
                if fs::symlink_metadata(&path).is_ok_and(|m| same_file(&m, &meta)) {
                    return Err(self.says(format_args!(
                        "{} is the same file as {label}; the crate would replace it",
                        path.display()
                    )));
                }
            }
        }
        Ok(())
    }

    /// What is at OUT: nothing, an empty folder, or a folder of ours still as it was made;
    /// anything else is refused.
    pub fn previous(&self) -> Result<Previous, FolderError> {
        let out = &self.out;
        let meta = match fs::symlink_metadata(out) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Previous::Nothing),
            Err(e) => return Err(self.says(e)),
            Ok(m) => m,
        };
        if meta.file_type().is_symlink() {
            let to = fs::read_link(out).map_or_else(|_| "?".into(), |t| t.display().to_string());
            return Err(self.says(format_args!(
                "a symbolic link (to {to}); give the folder itself"
            )));
        }
        if !meta.is_dir() {
            return Err(self.says("exists and is not a folder"));
        }
        if fs::read_dir(out)
            .map_err(|e| self.says(e))?
            .next()
            .is_none()
        {
            return Ok(Previous::Empty);
        }
        let owned = self.owned_files().ok_or_else(|| {
            self.says(format_args!(
                "a folder with other files in it and no {MANIFEST} of `{}`; give a new or empty folder",
                self.command
            ))
        })?;
        self.check_listed(&owned, out, true)?;
        Ok(Previous::Ours(owned))
    }

    /// The files OUT's manifest lists, with their hashes; None without a manifest of ours.
    fn owned_files(&self) -> Option<BTreeMap<String, String>> {
        let text = read_regular(&self.out.join(MANIFEST)).ok()?;
        let text = String::from_utf8(text).ok()?;
        let mut lines = text.lines();
        if lines.next()? != self.header() {
            return None;
        }
        let mut files = BTreeMap::new();
        for line in lines {
            let (digest, name) = line.split_once("  ")?;
            let hex = digest.len() == 64
                && digest
                    .bytes()
                    .all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
            if !hex || name.starts_with('/') || name.split('/').any(|part| part == "..") {
                return None;
            }
            files.insert(name.to_string(), digest.to_string());
        }
        Some(files)
    }

    /// Every entry of `dir` is listed (a folder: something under it is), and every listed file
    /// is as written; then the same for each folder in it. At the top, cargo's products and the
    /// manifest are not looked at (target/ can hold thousands of files).
    fn check_listed(
        &self,
        owned: &BTreeMap<String, String>,
        dir: &Path,
        top: bool,
    ) -> Result<(), FolderError> {
        let mut entries = Vec::new();
        for entry in
            fs::read_dir(dir).map_err(|e| self.says(format_args!("{}: {e}", dir.display())))?
        {
            let entry = entry.map_err(|e| self.says(format_args!("{}: {e}", dir.display())))?;
            let name = entry.file_name();
            if top && (CARGO_PRODUCTS.iter().any(|p| name == *p) || name == MANIFEST) {
                continue;
            }
            let kind = entry.file_type().map_err(|e| self.says(e))?;
            entries.push((!kind.is_dir(), name, kind));
        }
        // Folders first, each group by name: the first problem found is the one named.
        entries.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
        for (_, name, kind) in &entries {
            self.check_entry(owned, &dir.join(name), kind)?;
        }
        for (_, name, kind) in &entries {
            if kind.is_dir() {
                self.check_listed(owned, &dir.join(name), false)?;
            }
        }
        Ok(())
    }
}

impl CrateFolder {
    /// One entry of OUT is listed (a folder: something under it is) and, a file, as written.
    fn check_entry(
        &self,
        owned: &BTreeMap<String, String>,
        path: &Path,
        kind: &fs::FileType,
    ) -> Result<(), FolderError> {
        let rel = relative(path, &self.out);
        let listed = if kind.is_dir() {
            owned.keys().any(|f| f.starts_with(&format!("{rel}/")))
        } else {
            kind.is_file() && owned.contains_key(&rel)
        };
        if !listed {
            return Err(self.says(format_args!(
                "{} was not written by `{}`; move it out first",
                path.display(),
                self.command
            )));
        }
        if !kind.is_file() {
            return Ok(());
        }
        let digest =
            sha256(path).map_err(|e| self.says(format_args!("{}: {e}", path.display())))?;
        if owned.get(&rel) != Some(&digest) {
            return Err(self.says(format_args!(
                "{} was changed since `{}` wrote it; move it out first",
                path.display(),
                self.command
            )));
        }
        Ok(())
    }
}

/// `path` relative to `base`, with `/` between its parts, as the manifest names files.
fn relative(path: &Path, base: &Path) -> String {
    let rel = path.strip_prefix(base).unwrap_or(path);
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts.join("/")
}

#[cfg(unix)]
fn same_file(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.is_file() && (a.dev(), a.ino()) == (b.dev(), b.ino())
}

#[cfg(not(unix))]
fn same_file(_: &fs::Metadata, _: &fs::Metadata) -> bool {
    false
}

/// Opens `path` only if it is a regular file: not through a link, and without blocking on a
/// FIFO put there since it was looked at.
fn open_regular(path: &Path) -> io::Result<fs::File> {
    let mut options = fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW);
    }
    let file = options.open(path)?;
    if !file.metadata()?.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file",
        ));
    }
    Ok(file)
}

fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    io::Read::read_to_end(&mut open_regular(path)?, &mut bytes)?;
    Ok(bytes)
}

/// The SHA-256 of the file at `path`, in lowercase hex.
fn sha256(path: &Path) -> io::Result<String> {
    let mut hasher = Sha256::new();
    io::copy(&mut open_regular(path)?, &mut hasher)?;
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

impl CrateFolder {
    /// A temporary folder beside OUT (`.NAME-partial-XXXXXX`) to make the new folder in: on one
    /// file system with OUT, so that it is renamed into place, and removed if never installed.
    pub fn stage(&self) -> Result<Staging, FolderError> {
        let folder = crate::file::parent(&self.out);
        let name = self.out.file_name().unwrap_or_default().to_string_lossy();
        tempfile::Builder::new()
            .prefix(&format!(".{name}-partial-"))
            .tempdir_in(folder)
            .map(Staging)
            .map_err(write_error(folder))
    }

    /// Checks OUT again ([`Self::check`]: it may have changed while the folder was made), lists
    /// the staged files in the manifest, and moves `staging` into place.
    pub fn install_staged(&self, staging: Staging) -> Result<(), FolderError> {
        self.install(staging.path())?;
        // Renamed to OUT: nothing is left at the temporary path to remove.
        let _ = staging.0.keep();
        Ok(())
    }

    /// As [`Self::install_staged`], for a folder made elsewhere beside OUT; on failure it stays
    /// where it is, for its maker to remove.
    pub fn install(&self, staging: &Path) -> Result<(), FolderError> {
        self.check_staging(staging)?;
        let previous = self.check()?;
        self.write_manifest(staging)?;
        user_permissions(staging)?;
        let _blocked = BlockedInterrupts::new();
        match previous {
            Previous::Nothing => fs::rename(staging, &self.out).map_err(write_error(&self.out)),
            Previous::Empty | Previous::Ours(_) => self.replace(staging),
        }
    }

    /// `staging` is a folder (not a link to one) beside OUT: renamed, it becomes OUT whole.
    fn check_staging(&self, staging: &Path) -> Result<(), FolderError> {
        let folder = fs::symlink_metadata(staging).is_ok_and(|m| m.is_dir());
        let beside = resolved(crate::file::parent(staging)) == crate::file::parent(&self.out);
        let real = resolved(staging);
        let holds_input = self.inputs.iter().any(|(_, i)| inside(&resolved(i), &real));
        if folder && beside && real != self.out && !holds_input {
            return Ok(());
        }
        Err(self.says(format_args!(
            "{} is not a folder beside it to make the crate in",
            staging.display()
        )))
    }

    /// Lists every file under `staging` (the new folder, before it is moved into place).
    fn write_manifest(&self, staging: &Path) -> Result<(), FolderError> {
        let mut files = Vec::new();
        regular_files(staging, &mut files).map_err(write_error(staging))?;
        files.sort();
        let mut text = self.header() + "\n";
        for path in &files {
            let digest = sha256(path).map_err(write_error(path))?;
            text += &format!("{digest}  {}\n", relative(path, staging));
        }
        let manifest = staging.join(MANIFEST);
        fs::write(&manifest, text).map_err(write_error(&manifest))
    }

    /// Swaps the old folder for the new: the old one is moved aside, the new one renamed into
    /// place, cargo's products moved from the old into the new, and only then the old removed.
    fn replace(&self, staging: &Path) -> Result<(), FolderError> {
        let out = &self.out;
        let name = out.file_name().unwrap_or_default().to_string_lossy();
        let aside = tempfile::Builder::new()
            .prefix(&format!(".{name}-old-"))
            .tempdir_in(crate::file::parent(out))
            .map_err(write_error(out))?;
        let old = aside.path().join("crate");
        fs::rename(out, &old).map_err(write_error(out))?;
        if let Err(e) = fs::rename(staging, out) {
            if let Err(back) = fs::rename(&old, out) {
                let why = format!("{e}, and the old folder could not be put back ({back})");
                return Err(kept_aside(out, aside, &why));
            }
            return Err(write_error(out)(e));
        }
        for product in CARGO_PRODUCTS {
            let from = old.join(product);
            if fs::symlink_metadata(&from).is_ok() {
                if let Err(e) = fs::rename(&from, out.join(product)) {
                    // The new folder is in place; the old one stays, with what it still holds.
                    let why = format!("{product} could not be moved into it ({e})");
                    return Err(kept_aside(out, aside, &why));
                }
            }
        }
        aside.close().map_err(write_error(out))
    }
}

/// The failure of a swap that could not be undone: the folder moved aside is kept, not removed
/// (it holds what the run did not create), and named.
fn kept_aside(out: &Path, aside: tempfile::TempDir, why: &str) -> FolderError {
    let kept = aside.keep().join("crate");
    let message = format!("{why}; the old folder is kept as {}", kept.display());
    WriteError::at(out)(io::Error::other(message)).into()
}

/// The regular files under `dir`, links not followed.
fn regular_files(dir: &Path, files: &mut Vec<PathBuf>) -> io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        let kind = entry.file_type()?;
        if kind.is_dir() {
            regular_files(&entry.path(), files)?;
        } else if kind.is_file() {
            files.push(entry.path());
        }
    }
    Ok(())
}

/// A temporary folder is made 0700; a folder the user makes gets 0777 less the umask.
#[cfg(unix)]
fn user_permissions(folder: &Path) -> Result<(), FolderError> {
    use std::os::unix::fs::PermissionsExt;
    // SAFETY: umask only swaps the process's mask; the old one is put back at once.
    let mask = unsafe {
        let mask = libc::umask(0);
        libc::umask(mask);
        mask
    };
    #[allow(clippy::useless_conversion)] // mode_t is u16 on macOS
    let mode = 0o777 & !u32::from(mask);
    fs::set_permissions(folder, fs::Permissions::from_mode(mode)).map_err(write_error(folder))
}

#[cfg(not(unix))]
fn user_permissions(_: &Path) -> Result<(), FolderError> {
    Ok(())
}

/// SIGINT, SIGTERM and SIGHUP held back, in this thread, while it lives: one that comes is
/// delivered when it is dropped, after the swap. A process with other threads must block them
/// there too (the renderer has none; `make crate` blocks them in itself while it waits).
struct BlockedInterrupts {
    #[cfg(unix)]
    old: libc::sigset_t,
}

impl BlockedInterrupts {
    #[cfg(unix)]
    fn new() -> Self {
        // SAFETY: sigset_t is plain data that sigemptyset initialises; pthread_sigmask only
        // changes this thread's mask and writes the old one into `old`.
        unsafe {
            let mut set: libc::sigset_t = std::mem::zeroed();
            let mut old: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut set);
            for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                libc::sigaddset(&mut set, signal);
            }
            libc::pthread_sigmask(libc::SIG_BLOCK, &set, &mut old);
            Self { old }
        }
    }

    #[cfg(not(unix))]
    fn new() -> Self {
        Self {}
    }
}

impl Drop for BlockedInterrupts {
    fn drop(&mut self) {
        #[cfg(unix)]
        // SAFETY: restores the mask saved by `new`.
        unsafe {
            libc::pthread_sigmask(libc::SIG_SETMASK, &self.old, std::ptr::null_mut());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_support::entries;

    const COMMAND: &str = "make crate";

    /// A scratch folder holding `models/m.toml`, an input.
    fn scratch() -> (tempfile::TempDir, PathBuf) {
        let base = tempfile::tempdir().unwrap();
        let models = base.path().join("models");
        fs::create_dir(&models).unwrap();
        fs::write(models.join("m.toml"), "[model]\n").unwrap();
        (base, models)
    }

    /// [`scratch`] with the crate already made by the rule at `mine`, its OUT.
    fn made() -> (tempfile::TempDir, PathBuf, PathBuf) {
        let (base, models) = scratch();
        let out = base.path().join("mine");
        make(&rule(&out, &models), &CRATE).unwrap();
        (base, models, out)
    }

    fn rule(out: &Path, models: &Path) -> CrateFolder {
        let mut rule = CrateFolder::new("OUT", out, COMMAND).unwrap();
        rule.input("MODELS=models", models)
            .input("description m.toml", &models.join("m.toml"));
        rule
    }

    /// The file at `path` holds `text`.
    #[track_caller]
    fn assert_holds(path: &Path, text: &str) {
        assert_eq!(
            fs::read_to_string(path).unwrap(),
            text,
            "{}",
            path.display()
        );
    }

    /// Makes the crate `files` (name, contents) at OUT by the rule.
    fn make(rule: &CrateFolder, files: &[(&str, &str)]) -> Result<(), FolderError> {
        let staging = rule.stage()?;
        for (name, contents) in files {
            let path = staging.path().join(name);
            fs::create_dir_all(path.parent().unwrap()).unwrap();
            fs::write(path, contents).unwrap();
        }
        rule.install_staged(staging)
    }

    fn refusal(result: Result<impl std::fmt::Debug, FolderError>) -> String {
        match result {
            Err(FolderError::Refused(m)) => m,
            other => panic!("not refused: {other:?}"),
        }
    }

    const CRATE: [(&str, &str); 2] = [("Cargo.toml", "[package]\n"), ("src/lib.rs", "// one\n")];

    #[test]
    fn a_new_folder_is_made_with_its_manifest_and_the_users_permissions() {
        let (base, models, out) = made();
        let manifest = fs::read_to_string(out.join(MANIFEST)).unwrap();
        let lines: Vec<&str> = manifest.lines().collect();
        assert_eq!(lines[0], rule(&out, &models).header());
        assert_eq!(lines.len(), 3, "{manifest}");
        assert!(lines[1].ends_with("  Cargo.toml") && lines[2].ends_with("  src/lib.rs"));
        assert_eq!(&lines[1][..64], sha256(&out.join("Cargo.toml")).unwrap());
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            // SAFETY: as in user_permissions.
            let mask = unsafe {
                let m = libc::umask(0);
                libc::umask(m);
                m
            };
            let mode = fs::metadata(&out).unwrap().permissions().mode() & 0o777;
            #[allow(clippy::useless_conversion)]
            let expected = 0o777 & !u32::from(mask);
            assert_eq!(mode, expected);
        }
        assert_eq!(entries(base.path()), ["mine", "models"]);
    }

    #[test]
    fn a_folder_of_ours_is_replaced_and_cargos_products_are_kept() {
        let (base, models, out) = made();
        fs::write(out.join("Cargo.lock"), "lock").unwrap();
        fs::create_dir_all(out.join("target/debug")).unwrap();
        fs::write(out.join("target/debug/build"), "built").unwrap();
        make(
            &rule(&out, &models),
            &[("Cargo.toml", "[package]\n"), ("src/new.rs", "")],
        )
        .unwrap();
        assert_eq!(
            entries(&out),
            [MANIFEST, "Cargo.lock", "Cargo.toml", "src", "target"]
        );
        assert_eq!(entries(&out.join("src")), ["new.rs"]);
        assert_holds(&out.join("Cargo.lock"), "lock");
        assert_holds(&out.join("target/debug/build"), "built");
        // No temporary or old folder is left beside it.
        assert_eq!(entries(base.path()), ["mine", "models"]);
        // An empty folder is replaced too.
        let empty = base.path().join("empty");
        fs::create_dir(&empty).unwrap();
        make(&rule(&empty, &models), &CRATE).unwrap();
        assert!(empty.join("src/lib.rs").is_file());
    }

    #[test]
    fn cargos_products_that_cannot_be_moved_stay_in_the_old_folder_which_is_named() {
        let (_base, models, out) = made();
        fs::create_dir_all(out.join("target/debug")).unwrap();
        fs::write(out.join("target/debug/build"), "built").unwrap();
        // A new crate with a target/ of its own, which the old one's cannot replace.
        let e = make(&rule(&out, &models), &[("target/own", "")]).unwrap_err();
        let FolderError::Write(e) = e else {
            panic!("{e}")
        };
        assert_eq!(e.path, out);
        let message = e.to_string();
        let kept = message
            .rsplit_once("kept as ")
            .map(|(_, k)| PathBuf::from(k));
        let kept = kept.unwrap_or_else(|| panic!("{message}"));
        assert!(
            message.contains("target could not be moved into it"),
            "{message}"
        );
        assert_holds(&kept.join("target/debug/build"), "built");
        assert!(out.join("target/own").is_file());
    }

    #[test]
    fn a_foreign_file_in_out_is_refused_and_kept() {
        let (base, models) = scratch();
        let out = base.path().join("theirs");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("thesis.tex"), "years of work").unwrap();
        let e = refusal(make(&rule(&out, &models), &CRATE));
        assert!(e.contains("other files") && e.contains(MANIFEST), "{e}");
        // With a manifest that does not list it.
        let mine = base.path().join("mine");
        make(&rule(&mine, &models), &CRATE).unwrap();
        fs::write(mine.join("notes.txt"), "mine").unwrap();
        let e = refusal(make(&rule(&mine, &models), &CRATE));
        assert!(e.starts_with(&format!("OUT={}: ", mine.display())), "{e}");
        assert!(
            e.contains("notes.txt was not written by `make crate`"),
            "{e}"
        );
        assert_holds(&out.join("thesis.tex"), "years of work");
        assert_holds(&mine.join("notes.txt"), "mine");
        assert_eq!(entries(base.path()), ["mine", "models", "theirs"]);
    }

    #[test]
    fn an_edited_file_is_refused_and_kept() {
        let (base, models, out) = made();
        fs::write(out.join("src/lib.rs"), "// one\n// my change\n").unwrap();
        let e = refusal(make(&rule(&out, &models), &CRATE));
        assert!(
            e.contains("lib.rs was changed since `make crate` wrote it"),
            "{e}"
        );
        assert!(fs::read_to_string(out.join("src/lib.rs"))
            .unwrap()
            .ends_with("my change\n"));
        // A manifest edited by hand is no manifest of ours.
        fs::write(out.join(MANIFEST), "# mine\n").unwrap();
        assert!(refusal(rule(&out, &models).check()).contains("other files"));
        assert_eq!(entries(base.path()), ["mine", "models"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_or_a_fifo_is_refused_not_followed() {
        let (base, models) = scratch();
        let real = base.path().join("real");
        fs::create_dir(&real).unwrap();
        let link = base.path().join("link");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let e = refusal(make(&rule(&link, &models), &CRATE));
        assert!(
            e.contains("a symbolic link (to ") && e.contains("give the folder itself"),
            "{e}"
        );
        assert!(fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        // A listed file become a FIFO: refused without opening it.
        let out = base.path().join("mine");
        make(&rule(&out, &models), &CRATE).unwrap();
        fs::remove_file(out.join("Cargo.toml")).unwrap();
        let c = std::ffi::CString::new(out.join("Cargo.toml").as_os_str().as_encoded_bytes());
        // SAFETY: a NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.unwrap().as_ptr(), 0o644) }, 0);
        assert!(refusal(rule(&out, &models).check()).contains("Cargo.toml was not written by"));
        assert_eq!(entries(base.path()), ["link", "mine", "models", "real"]);
    }

    #[test]
    fn an_input_inside_out_or_out_inside_an_input_is_refused() {
        let (base, models) = scratch();
        let e = refusal(make(&rule(base.path(), &models), &CRATE));
        assert!(e.contains("MODELS=models is inside it"), "{e}");
        let e = refusal(make(&rule(&models, &models), &CRATE));
        assert!(e.contains("MODELS=models is inside it"), "{e}");
        let e = refusal(make(&rule(&models.join("sub"), &models), &CRATE));
        assert!(e.contains("it is inside MODELS=models"), "{e}");
        // A file of the old crate that is an input by another name.
        let out = base.path().join("mine");
        make(&rule(&out, &models), &CRATE).unwrap();
        let tasks = base.path().join("tasks.toml");
        fs::hard_link(out.join("Cargo.toml"), &tasks).unwrap();
        let mut with_tasks = rule(&out, &models);
        with_tasks.input("TASKS=tasks.toml", &tasks);
        let e = refusal(make(&with_tasks, &CRATE));
        assert!(
            e.contains("Cargo.toml is the same file as TASKS=tasks.toml"),
            "{e}"
        );
        assert_eq!(entries(base.path()), ["mine", "models", "tasks.toml"]);
    }

    #[test]
    fn an_out_inside_the_repository_or_holding_it_is_refused() {
        let (base, models) = scratch();
        let repo = base.path().join("repo");
        fs::create_dir(&repo).unwrap();
        for out in [
            repo.join("mycrate"),
            repo.join("target/mycrate"),
            repo.clone(),
            base.path().into(),
        ] {
            let mut r = rule(&out, &models);
            r.repository(&repo);
            let e = refusal(r.check());
            assert!(e.contains("inside the repository"), "{e}");
        }
        assert_eq!(entries(base.path()), ["models", "repo"]);
        assert!(entries(&repo).is_empty());
    }

    #[test]
    fn a_missing_folder_or_a_file_is_refused_and_a_failed_stage_leaves_nothing() {
        let (base, models) = scratch();
        let e = refusal(rule(&base.path().join("no/such"), &models).check());
        assert!(
            e.contains("the folder") && e.contains("does not exist"),
            "{e}"
        );
        fs::write(base.path().join("file"), "").unwrap();
        let e = refusal(rule(&base.path().join("file"), &models).check());
        assert!(e.ends_with("exists and is not a folder"), "{e}");
        let e = refusal(CrateFolder::new("OUT", Path::new("/"), COMMAND));
        assert_eq!(e, "OUT=/: names no folder");
        // Staged, then refused at the install (OUT changed meanwhile): the stage goes.
        let out = base.path().join("late");
        let r = rule(&out, &models);
        let staging = r.stage().unwrap();
        fs::create_dir(&out).unwrap();
        fs::write(out.join("x"), "").unwrap();
        assert!(refusal(r.install_staged(staging)).contains("other files"));
        assert_eq!(entries(base.path()), ["file", "late", "models"]);
        // Only a folder beside OUT, holding no input, is moved there.
        fs::create_dir(base.path().join("sub")).unwrap();
        let not_beside = "models is not a folder beside it to make the crate in";
        let e = refusal(rule(&base.path().join("sub/new"), &models).install(&models));
        assert!(e.ends_with(not_beside), "{e}");
        let e = refusal(rule(&base.path().join("new"), &models).install(&models));
        assert!(e.ends_with(not_beside), "{e}");
        assert!(models.join("m.toml").is_file());
    }

    #[cfg(unix)]
    #[test]
    fn an_interrupt_during_the_swap_waits_until_it_is_done() {
        let blocked = BlockedInterrupts::new();
        // SAFETY: raise sends SIGHUP to this thread, where it is blocked, so it stays pending
        // until sigwait takes it: it never reaches its (deadly) default action.
        unsafe {
            assert_eq!(libc::raise(libc::SIGHUP), 0);
            let mut pending: libc::sigset_t = std::mem::zeroed();
            libc::sigpending(&mut pending);
            assert_eq!(libc::sigismember(&pending, libc::SIGHUP), 1);
            let mut wanted: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&mut wanted);
            libc::sigaddset(&mut wanted, libc::SIGHUP);
            let mut got = 0;
            assert_eq!(libc::sigwait(&wanted, &mut got), 0);
            assert_eq!(got, libc::SIGHUP);
        }
        drop(blocked);
    }
}
