//! Reading a file a user names, whole and bounded: opened without blocking (a FIFO with no
//! writer would otherwise wait for ever), required to be a regular file once open (what is read
//! is what was checked), and read up to a limit, so that `/dev/zero`, a FIFO, a folder or a
//! file of gigabytes is one clear refusal instead of a hang or an exhausted memory.

use std::fmt;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Read};
use std::path::Path;

/// Why a file could not be read.
#[derive(Debug)]
pub enum InputError {
    /// Not a regular file: what it is ("a folder", "a FIFO", ...).
    NotAFile(&'static str),
    /// Larger than the limit, in bytes.
    TooLarge(u64),
    Io(io::Error),
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InputError::NotAFile(what) => write!(f, "is {what}, not a regular file"),
            InputError::TooLarge(limit) => write!(f, "is larger than {}", bytes(*limit)),
            InputError::Io(e) => write!(f, "cannot read it: {e}"),
        }
    }
}

impl std::error::Error for InputError {}

/// `limit` bytes in words: "8 MiB", "1024 bytes".
pub fn bytes(limit: u64) -> String {
    if limit >= 1 << 20 && limit % (1 << 20) == 0 {
        format!("{} MiB", limit >> 20)
    } else {
        format!("{limit} bytes")
    }
}

fn kind(meta: &fs::Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO");
        }
        if t.is_socket() {
            return Some("a socket");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
    }
    Some("not a regular file")
}

/// Opens the regular file at `path` for reading (links followed), without blocking on a FIFO.
pub fn open_regular(path: &Path) -> Result<File, InputError> {
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| {
        // A folder cannot be opened everywhere; a socket never: say what it is.
        match fs::metadata(path).ok().as_ref().and_then(kind) {
            Some(what) => InputError::NotAFile(what),
            None => InputError::Io(e),
        }
    })?;
    let meta = file.metadata().map_err(InputError::Io)?;
    if let Some(what) = kind(&meta) {
        return Err(InputError::NotAFile(what));
    }
    Ok(file)
}

/// Opens a file a user names as input that may also be a pipe or FIFO (`--task <(...)`):
/// without blocking on a FIFO that has no writer (it then reads as empty, at once), refusing a
/// folder, a device or a socket; a pipe's reads block again once it is open.
pub fn open_stream(path: &Path) -> Result<File, InputError> {
    match open_regular(path) {
        Err(InputError::NotAFile("a FIFO")) => open_fifo(path),
        other => other,
    }
}

#[cfg(unix)]
fn open_fifo(path: &Path) -> Result<File, InputError> {
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    let file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(InputError::Io)?;
    // What was opened is what was checked: a FIFO replaced by another file in between is refused.
    if !std::os::unix::fs::FileTypeExt::is_fifo(
        &file.metadata().map_err(InputError::Io)?.file_type(),
    ) {
        return Err(InputError::NotAFile("not a regular file"));
    }
    // SAFETY: fcntl on a descriptor this function owns, with integer flags only.
    let flags = unsafe { libc::fcntl(file.as_raw_fd(), libc::F_GETFL) };
    // SAFETY: as above.
    if flags < 0
        || unsafe { libc::fcntl(file.as_raw_fd(), libc::F_SETFL, flags & !libc::O_NONBLOCK) } < 0
    {
        return Err(InputError::Io(io::Error::last_os_error()));
    }
    Ok(file)
}

#[cfg(not(unix))]
fn open_fifo(_path: &Path) -> Result<File, InputError> {
    Err(InputError::NotAFile("a FIFO"))
}

/// The bytes of the regular file at `path`, at most `limit` of them ([`open_regular`]).
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, InputError> {
    let file = open_regular(path)?;
    let mut data = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(InputError::Io)?;
    if data.len() as u64 > limit {
        return Err(InputError::TooLarge(limit));
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_a_fifo_and_a_large_file_are_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        assert!(matches!(
            read_regular(dir.path(), 10),
            Err(InputError::NotAFile("a folder"))
        ));
        let big = dir.path().join("big");
        fs::write(&big, [b'x'; 11]).unwrap();
        assert!(matches!(
            read_regular(&big, 10),
            Err(InputError::TooLarge(10))
        ));
        assert_eq!(read_regular(&big, 11).unwrap().len(), 11);
        #[cfg(unix)]
        {
            let fifo = dir.path().join("fifo");
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            // SAFETY: mkfifo on a NUL-terminated path this test owns.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            assert!(matches!(
                read_regular(&fifo, 10),
                Err(InputError::NotAFile("a FIFO"))
            ));
            assert!(matches!(
                read_regular(Path::new("/dev/zero"), 10),
                Err(InputError::NotAFile("a device"))
            ));
        }
        assert_eq!(bytes(128 << 20), "128 MiB");
    }
}
