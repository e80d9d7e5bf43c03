//! Writing result files (CSVs, reports, figures) without harming what is already there.
//!
//! What a path names decides how it is written:
//! * nothing yet, or a regular file: a temporary file beside it (`.NAME.XXXXXX.partial`),
//!   renamed over it once whole, so that a reader sees the old file or the whole new one; a
//!   file written row by row ([`create_streaming`]) too, its rows going to the temporary;
//! * a symbolic link: written through to its target by the same rules, and the link stays a
//!   link (a link to nothing is refused, as "a link to nothing: PATH -> TARGET", as a link to a
//!   folder is);
//! * a device, a FIFO, a socket, or a name of an open descriptor (`/dev/stdout`, `/dev/fd/N`,
//!   anything under `/proc`): written in place, never replaced: `--csv /dev/null` discards,
//!   `--csv /dev/full` fails with "No space left on device" and the device stays a device, even
//!   for root. A FIFO is opened without blocking: one nothing reads is refused, not waited on;
//! * a folder: refused, as "is a folder, not a file".
//!
//! The temporary file is removed on every failure path, and on SIGINT, SIGTERM or SIGHUP where
//! the command line asked for it ([`crate::partial::remove_on_interrupt`]); only a process
//! killed outright (SIGKILL) can leave one, named `.NAME.*.partial` beside the target.
//! [`check_file`] and [`check_folder`] tell the command line, before any work, whether a path can
//! be written at all, so that a bad path is bad input (status 2), not a failed run; which outputs
//! clash with each other or with an input is [`crate::run_files`]'s.

use std::fs::{self, File, OpenOptions, Permissions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use crate::partial::Partial;

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

pub(crate) fn refused(message: &str) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message.to_string())
}

/// The words for a symbolic link whose target does not exist.
fn link_to_nothing(path: &Path) -> io::Error {
    let target = fs::read_link(path).map_or_else(|_| "?".into(), |t| t.display().to_string());
    refused(&format!(
        "a link to nothing: {} -> {target}",
        path.display()
    ))
}

/// Whether `path` names an open descriptor (`/dev/stdout` is a link to `/proc/self/fd/1`):
/// what it leads to is the descriptor's file, which a rename would not reach.
pub(crate) fn names_a_descriptor(path: &Path) -> bool {
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
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Err(link_to_nothing(path)),
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
        #[cfg(unix)]
        Ok(Target::InPlace) if is_fifo(path) => hold_fifo(path).map_err(|e| e.to_string()),
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
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            // `create_dir_all` onto a link to nothing says only "File exists".
            match fs::symlink_metadata(path) {
                Ok(m) if m.file_type().is_symlink() => Err(link_to_nothing(path).to_string()),
                _ => Ok(()),
            }
        }
        Err(e) => Err(e.to_string()),
    }
}

/// Creates the folder `dir` (and its parents) to write into; an existing file there is refused
/// as "is a file, not a folder" (`create_dir_all` alone says "File exists").
pub fn create_folder(dir: &Path) -> io::Result<()> {
    check_folder(dir).map_err(|m| refused(&m))?;
    fs::create_dir_all(dir)
}

pub(crate) fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Opens a device, FIFO or descriptor name to be written where it is. A FIFO is opened without
/// blocking, so that one nothing reads is refused ("no process reads this FIFO"), not waited
/// on; once open, writes block as usual.
fn open_in_place(path: &Path) -> io::Result<File> {
    let mut options = OpenOptions::new();
    options.write(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| {
        #[cfg(unix)]
        if e.raw_os_error() == Some(libc::ENXIO) && is_fifo(path) {
            return refused("is a FIFO that no process reads");
        }
        e
    })?;
    #[cfg(unix)]
    blocking(&file)?;
    Ok(file)
}

/// FIFOs opened by [`check_file`], open until the process ends: closing one would tell its
/// reader the output had ended before it was written.
#[cfg(unix)]
static HELD_FIFOS: std::sync::Mutex<Vec<File>> = std::sync::Mutex::new(Vec::new());

/// Whether a process reads the FIFO at `path` now: opened without blocking, and held.
#[cfg(unix)]
fn hold_fifo(path: &Path) -> io::Result<()> {
    let file = open_in_place(path)?;
    HELD_FIFOS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .push(file);
    Ok(())
}

#[cfg(unix)]
fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// Clears `O_NONBLOCK` on an open file (a full pipe then waits for its reader, as any write).
#[cfg(unix)]
fn blocking(file: &File) -> io::Result<()> {
    use std::os::fd::AsRawFd;
    let fd = file.as_raw_fd();
    // SAFETY: fcntl on a descriptor this function's caller owns and keeps open.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    // SAFETY: as above; only the O_NONBLOCK bit changes.
    if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) } < 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Writes `contents` as the whole file at `path`, by the module's rules.
pub fn write_whole(path: &Path, contents: &[u8]) -> io::Result<()> {
    let mut out = create_streaming(path)?;
    out.write_all(contents)?;
    out.finish()
}

/// A file being written: rows go to a temporary file renamed over the target at
/// [`Streaming::finish`] (dropped unfinished, the temporary goes and the old file stays), or,
/// for a device or FIFO, to the file itself.
pub struct Streaming {
    out: Out,
}

enum Out {
    Replace(Partial),
    InPlace(File),
}

impl Streaming {
    /// Makes the file whole: renames the temporary over the target (or flushes a device).
    pub fn finish(self) -> io::Result<()> {
        match self.out {
            Out::Replace(partial) => partial.persist(),
            Out::InPlace(mut file) => file.flush(),
        }
    }
}

impl Write for Streaming {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.out {
            Out::Replace(partial) => partial.as_file().write(buf),
            Out::InPlace(file) => file.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.out {
            Out::Replace(partial) => partial.as_file().flush(),
            Out::InPlace(file) => file.flush(),
        }
    }
}

/// Opens `path` to be written row by row (a CSV whose rows are appended as they are computed),
/// by the module's rules: the rows of a new or regular file go to its temporary until
/// [`Streaming::finish`]; a device or FIFO is written in place; a link is written through; a
/// folder or a link to nothing is refused.
pub fn create_streaming(path: &Path) -> io::Result<Streaming> {
    let out = match target(path)? {
        Target::InPlace => Out::InPlace(open_in_place(path)?),
        Target::Replace { path, permissions } => Out::Replace(Partial::create(&path, permissions)?),
    };
    Ok(Streaming { out })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_support::entries;

    fn scratch(name: &str) -> crate::test_support::Scratch {
        crate::test_support::scratch("out", name)
    }

    /// [`scratch`] and the path of a file `file` in it.
    fn scratch_file(name: &str, file: &str) -> (crate::test_support::Scratch, PathBuf) {
        let dir = scratch(name);
        let path = dir.join(file);
        (dir, path)
    }

    /// `path` holds `bytes` and is all `dir` holds: no temporary file left beside it.
    #[track_caller]
    fn assert_alone(dir: &Path, path: &Path, bytes: &[u8]) {
        assert_eq!(fs::read(path).unwrap(), bytes);
        let name = path.file_name().unwrap().to_string_lossy();
        assert_eq!(entries(dir), [name]);
    }

    #[test]
    fn new_and_regular_files_are_replaced_whole() {
        let (dir, path) = scratch_file("regular", "a.csv");
        write_whole(&path, b"one\n").unwrap();
        write_whole(&path, b"two\n").unwrap();
        assert_alone(&dir, &path, b"two\n");
    }

    #[cfg(unix)]
    #[test]
    fn a_link_is_written_through_and_stays_a_link() {
        let (dir, target) = scratch_file("link", "target.csv");
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
        assert_eq!(
            e.to_string(),
            format!(
                "a link to nothing: {} -> {}",
                dangling.display(),
                dir.join("missing.csv").display()
            )
        );
        assert_eq!(check_folder(&dangling), Err(e.to_string()));
        assert_eq!(entries(&dir), ["dangling.csv", "link.csv", "target.csv"]);
    }

    #[test]
    fn a_folder_is_refused_and_leaves_nothing_behind() {
        let (dir, sub) = scratch_file("folder", "sub");
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

    #[test]
    fn rows_go_to_the_temporary_and_an_unfinished_file_keeps_the_old_one() {
        let (dir, path) = scratch_file("streaming", "rows.csv");
        fs::write(&path, b"old\n").unwrap();
        let mut out = create_streaming(&path).unwrap();
        out.write_all(b"row 1\n").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"old\n");
        assert_eq!(entries(&dir).len(), 2, "{:?}", entries(&dir));
        drop(out);
        assert_alone(&dir, &path, b"old\n");
        let mut out = create_streaming(&path).unwrap();
        out.write_all(b"row 1\nrow 2\n").unwrap();
        out.finish().unwrap();
        assert_alone(&dir, &path, b"row 1\nrow 2\n");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_nothing_reads_is_refused_not_waited_on() {
        let (dir, fifo) = scratch_file("fifo", "report.md");
        let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
        assert_eq!(
            check_file(&fifo),
            Err("is a FIFO that no process reads".into())
        );
        let e = write_whole(&fifo, b"x").unwrap_err();
        assert_eq!(e.to_string(), "is a FIFO that no process reads");
        // With a reader it is written in place, and stays a FIFO.
        let reader = std::thread::spawn({
            let fifo = fifo.clone();
            move || fs::read(fifo).unwrap()
        });
        let written = loop {
            match write_whole(&fifo, b"through the pipe") {
                Err(e) if e.to_string().contains("no process reads") => std::thread::yield_now(),
                other => break other,
            }
        };
        written.unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe");
        use std::os::unix::fs::FileTypeExt;
        assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        assert_eq!(entries(&dir), ["report.md"]);
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
