//! Writing result files (CSVs, reports, figures) without harming what is already there.
//!
//! What a path names decides how it is written:
//! * nothing yet, or a regular file: a temporary file beside it (`.NAME.XXXXXX.partial`),
//!   renamed over it once whole, so that a reader sees the old file or the whole new one;
//! * a symbolic link: written through to its target by the same rules, and the link stays a
//!   link (a link to nothing is refused, as a link to a folder is);
//! * a device, a FIFO, a socket, or a name of an open descriptor (`/dev/stdout`, `/dev/fd/N`,
//!   anything under `/proc`): written in place, never replaced: `--csv /dev/null` discards,
//!   `--csv /dev/full` fails with "No space left on device" and the device stays a device, even
//!   for root;
//! * a folder: refused, as "is a folder, not a file".
//!
//! The temporary file is removed on every failure path (the `tempfile` crate removes it when it
//! is dropped unrenamed); only a process killed outright (SIGKILL, or Ctrl-C, which ends the
//! process without unwinding) can leave one, named `.NAME.*.partial` beside the target.
//! [`check_file`] and [`check_folder`] tell the command line, before any work, whether a path can
//! be written at all, so that a bad path is bad input (status 2), not a failed run.

use std::fs::{self, File, OpenOptions, Permissions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// How a path is to be written.
#[derive(Debug)]
enum Target {
    /// Through a temporary file renamed over `path` (the link's target, for a link), created
    /// with `permissions` (the old file's, or the default 0666 less the umask).
    Replace {
        path: PathBuf,
        permissions: Option<Permissions>,
    },
    /// Opened and written where it is.
    InPlace,
}

fn refused(message: &str) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message.to_string())
}

/// Whether `path` names an open descriptor (`/dev/stdout` is a link to `/proc/self/fd/1`):
/// what it leads to is the descriptor's file, which a rename would not reach.
fn names_a_descriptor(path: &Path) -> bool {
    ["/proc", "/dev/fd", "/dev/stdout", "/dev/stderr"]
        .iter()
        .any(|p| path.starts_with(p))
}

/// How `path` is written, or why it cannot be.
fn target(path: &Path) -> io::Result<Target> {
    if names_a_descriptor(path) {
        return Ok(Target::InPlace);
    }
    let meta = match fs::symlink_metadata(path) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Ok(Target::Replace {
                path: path.to_path_buf(),
                permissions: None,
            })
        }
        Err(e) => return Err(e),
        Ok(m) => m,
    };
    let (meta, resolved) = if meta.file_type().is_symlink() {
        match fs::metadata(path) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                return Err(refused("is a symbolic link to a file that does not exist"))
            }
            Err(e) => return Err(e),
            Ok(m) if m.is_file() => (m, fs::canonicalize(path)?),
            Ok(m) => (m, path.to_path_buf()),
        }
    } else {
        (meta, path.to_path_buf())
    };
    if meta.is_dir() {
        Err(refused("is a folder, not a file"))
    } else if meta.is_file() {
        Ok(Target::Replace {
            path: resolved,
            permissions: Some(meta.permissions()),
        })
    } else {
        Ok(Target::InPlace)
    }
}

/// Whether a file can be written at `path`, in words for the command line's error: what it
/// names, and that its folder exists. Nothing is created.
pub fn check_file(path: &Path) -> Result<(), String> {
    match target(path) {
        Err(e) => Err(e.to_string()),
        Ok(Target::InPlace) => Ok(()),
        Ok(Target::Replace { path, .. }) => {
            let folder = parent(&path);
            match fs::metadata(folder) {
                Ok(m) if m.is_dir() => Ok(()),
                Ok(_) => Err(format!("{} is not a folder", folder.display())),
                Err(e) => Err(format!("its folder {}: {e}", folder.display())),
            }
        }
    }
}

/// Whether `path` can be a folder to write into: absent (it will be created) or a folder.
pub fn check_folder(path: &Path) -> Result<(), String> {
    match fs::metadata(path) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err("is a file, not a folder".into()),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e.to_string()),
    }
}

/// Creates the folder `dir` (and its parents) to write into; an existing file there is refused
/// as "is a file, not a folder" (`create_dir_all` alone says "File exists").
pub fn create_folder(dir: &Path) -> io::Result<()> {
    check_folder(dir).map_err(|m| refused(&m))?;
    fs::create_dir_all(dir)
}

fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes `contents` as the whole file at `path`, by the module's rules.
pub fn write_whole(path: &Path, contents: &[u8]) -> io::Result<()> {
    let (path, permissions) = match target(path)? {
        Target::InPlace => {
            let mut file = OpenOptions::new().write(true).open(path)?;
            return file.write_all(contents).and_then(|()| file.flush());
        }
        Target::Replace { path, permissions } => (path, permissions),
    };
    let name = path
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
    let mut tmp = builder.tempfile_in(parent(&path))?;
    if let Some(p) = permissions {
        tmp.as_file().set_permissions(p)?;
    }
    tmp.write_all(contents)?;
    tmp.flush()?;
    tmp.persist(&path).map(drop).map_err(|e| e.error)
}

/// Opens `path` to be written row by row (a CSV whose rows appear as they are computed): a
/// regular file is truncated, a device or FIFO written in place, a link written through; a
/// folder or a link to nothing is refused.
pub fn create_streaming(path: &Path) -> io::Result<File> {
    match target(path)? {
        Target::InPlace => OpenOptions::new().write(true).open(path),
        Target::Replace { path, .. } => File::create(path),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("toolconf-out-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn new_and_regular_files_are_replaced_whole() {
        let dir = scratch("regular");
        let path = dir.join("a.csv");
        write_whole(&path, b"one\n").unwrap();
        write_whole(&path, b"two\n").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two\n");
        assert_eq!(entries(&dir), ["a.csv"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_link_is_written_through_and_stays_a_link() {
        let dir = scratch("link");
        let target = dir.join("target.csv");
        fs::write(&target, b"old").unwrap();
        let link = dir.join("link.csv");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_whole(&link, b"new").unwrap();
        assert!(fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read(&target).unwrap(), b"new");
        let dangling = dir.join("dangling.csv");
        std::os::unix::fs::symlink(dir.join("missing.csv"), &dangling).unwrap();
        let e = write_whole(&dangling, b"x").unwrap_err();
        assert!(e.to_string().contains("link to a file that does not exist"));
        assert_eq!(entries(&dir), ["dangling.csv", "link.csv", "target.csv"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_folder_is_refused_and_leaves_nothing_behind() {
        let dir = scratch("folder");
        let sub = dir.join("sub");
        fs::create_dir(&sub).unwrap();
        assert_eq!(
            write_whole(&sub, b"x").unwrap_err().to_string(),
            "is a folder, not a file"
        );
        assert_eq!(check_file(&sub).unwrap_err(), "is a folder, not a file");
        assert!(check_file(&dir.join("missing/out.csv"))
            .unwrap_err()
            .contains("missing"));
        assert_eq!(check_folder(&sub), Ok(()));
        fs::write(dir.join("file"), b"").unwrap();
        assert_eq!(
            check_folder(&dir.join("file")).unwrap_err(),
            "is a file, not a folder"
        );
        assert_eq!(entries(&dir), ["file", "sub"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_under_dev_that_is_a_folder_of_files_follows_the_usual_rules() {
        // /dev/shm is a tmpfs of regular files: a new one there is created, by rename.
        let dir = Path::new("/dev/shm");
        if dir.is_dir() {
            let path = dir.join(format!("toolconf-out-{}.csv", std::process::id()));
            write_whole(&path, b"x\n").unwrap();
            assert_eq!(fs::read(&path).unwrap(), b"x\n");
            fs::remove_file(&path).unwrap();
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_device_is_written_in_place_never_replaced() {
        write_whole(Path::new("/dev/null"), b"discarded").unwrap();
        let e = write_whole(Path::new("/dev/full"), b"x").unwrap_err();
        assert_eq!(e.raw_os_error(), Some(28), "{e}");
        use std::os::unix::fs::FileTypeExt;
        assert!(fs::metadata("/dev/full")
            .unwrap()
            .file_type()
            .is_char_device());
    }
}
