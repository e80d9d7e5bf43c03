//! The files of one run, checked together before any work: no output may be an input (written
//! through a link or a hard link included) and no two outputs may be one file, since either
//! would replace what the user gave or what the run itself wrote.
//!
//! Files are told apart as the file system does, by device and inode, for what exists (links
//! followed), and by their resolved path for what does not yet. Devices, FIFOs and names of
//! open descriptors (`/dev/stdout`) are written in place, never replaced, so they clash with
//! nothing: `--tools /dev/stdin --csv /dev/stdout` on one terminal is fine.

use std::fs;
use std::path::{Component, Path, PathBuf};

use crate::file::{check_file, check_folder, names_a_descriptor};

/// What tells two paths apart.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    /// An existing regular file or folder: its device and inode.
    Inode(u64, u64),
    /// A path that does not exist yet, resolved (links in its existing folders followed).
    New(PathBuf),
    /// Written in place, or unreadable: compared with nothing.
    InPlace,
}

#[cfg(unix)]
fn inode(m: &fs::Metadata) -> Identity {
    use std::os::unix::fs::MetadataExt;
    Identity::Inode(m.dev(), m.ino())
}

#[cfg(not(unix))]
fn inode(_: &fs::Metadata) -> Identity {
    Identity::InPlace
}

/// `path` with its longest existing ancestor canonicalised and the rest appended.
pub(crate) fn resolved(path: &Path) -> PathBuf {
    let mut rest = Vec::new();
    let mut head = path;
    loop {
        if let Ok(real) = fs::canonicalize(if head.as_os_str().is_empty() {
            Path::new(".")
        } else {
            head
        }) {
            let mut out = real;
            for part in rest.iter().rev() {
                match part {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    other => out.push(other),
                }
            }
            return out;
        }
        match (head.parent(), head.components().next_back()) {
            (Some(parent), Some(last)) => {
                rest.push(last);
                head = parent;
            }
            _ => return path.to_path_buf(),
        }
    }
}

fn identity(path: &Path) -> Identity {
    if names_a_descriptor(path) {
        return Identity::InPlace;
    }
    match fs::metadata(path) {
        Ok(m) if m.is_file() || m.is_dir() => inode(&m),
        Ok(_) => Identity::InPlace,
        Err(_) => match fs::symlink_metadata(path) {
            // A link to nothing, refused by the file's own check.
            Ok(_) => Identity::InPlace,
            Err(_) => Identity::New(resolved(path)),
        },
    }
}

/// One file or folder named by a flag.
struct Named {
    flag: String,
    path: PathBuf,
    /// For an output folder, the names of the files the run writes into it.
    files: Option<Vec<String>>,
}

impl Named {
    fn label(&self) -> String {
        format!("{} {}", self.flag, self.path.display())
    }
}

/// The inputs and outputs of one run.
#[derive(Default)]
pub struct RunFiles {
    inputs: Vec<Named>,
    outputs: Vec<Named>,
}

impl RunFiles {
    pub fn new() -> Self {
        Self::default()
    }

    /// A file the run reads, named by `flag` (`--tools`).
    pub fn input(&mut self, flag: &str, path: &Path) -> &mut Self {
        self.inputs.push(Named {
            flag: flag.into(),
            path: path.into(),
            files: None,
        });
        self
    }

    /// A file the run writes, named by `flag` (`--csv`).
    pub fn output_file(&mut self, flag: &str, path: &Path) -> &mut Self {
        self.outputs.push(Named {
            flag: flag.into(),
            path: path.into(),
            files: None,
        });
        self
    }

    /// A folder the run writes `files` into (created if missing), named by `flag` (`--report`).
    pub fn output_folder<S: AsRef<str>>(
        &mut self,
        flag: &str,
        dir: &Path,
        files: &[S],
    ) -> &mut Self {
        self.outputs.push(Named {
            flag: flag.into(),
            path: dir.into(),
            files: Some(files.iter().map(|f| f.as_ref().to_string()).collect()),
        });
        self
    }

    /// Every output checked on its own ([`check_file`], [`check_folder`]), then against every
    /// input and every other output; the first problem in words, naming the flags.
    pub fn check(&self) -> Result<(), String> {
        let mut written: Vec<(String, Identity)> = Vec::new();
        for out in &self.outputs {
            match &out.files {
                None => {
                    check_file(&out.path).map_err(|m| format!("{}: {m}", out.label()))?;
                    written.push((out.label(), identity(&out.path)));
                }
                Some(files) => {
                    check_folder(&out.path).map_err(|m| format!("{}: {m}", out.label()))?;
                    written.push((out.label(), identity(&out.path)));
                    for f in files {
                        let path = out.path.join(f);
                        if out.path.is_dir() {
                            check_file(&path)
                                .map_err(|m| format!("{} (its {f}): {m}", out.label()))?;
                        }
                        written.push((format!("{} (its {f})", out.label()), identity(&path)));
                    }
                }
            }
        }
        for (k, (label, id)) in written.iter().enumerate() {
            if *id == Identity::InPlace {
                continue;
            }
            if let Some((first, _)) = written[..k].iter().find(|(_, other)| other == id) {
                return Err(format!(
                    "{first} and {label} are the same file: one output would replace the other"
                ));
            }
            for input in &self.inputs {
                if let Ok(m) = fs::metadata(&input.path) {
                    if m.is_file() && inode(&m) == *id {
                        return Err(format!(
                            "{label} is the same file as {}: the output would replace the input",
                            input.label()
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> crate::test_support::Scratch {
        crate::test_support::scratch("run", name)
    }

    #[test]
    fn an_output_that_is_an_input_is_refused_by_any_name() {
        let dir = scratch("input");
        let tools = dir.join("tools.csv");
        fs::write(&tools, "name,model\n").unwrap();
        fs::hard_link(&tools, dir.join("hard.csv")).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(&tools, dir.join("soft.csv")).unwrap();
        let roundabout = dir.join("sub/../tools.csv");
        fs::create_dir(dir.join("sub")).unwrap();
        for out in ["tools.csv", "hard.csv", "soft.csv"]
            .map(|n| dir.join(n))
            .iter()
            .chain([&roundabout])
        {
            if !out.exists() {
                continue;
            }
            let e = RunFiles::new()
                .input("--tools", &tools)
                .output_file("--csv", out)
                .check()
                .unwrap_err();
            assert!(
                e.starts_with(&format!(
                    "--csv {} is the same file as --tools",
                    out.display()
                )),
                "{e}"
            );
        }
        // Inside a report folder too.
        let e = RunFiles::new()
            .input("--tools", &dir.join("report.md"))
            .output_folder("--report", &dir, &["report.md"])
            .check();
        assert_eq!(e, Ok(()), "a missing input clashes with nothing");
        fs::write(dir.join("report.md"), "mine").unwrap();
        let e = RunFiles::new()
            .input("--task", &dir.join("report.md"))
            .output_folder("--report", &dir, &["report.md"])
            .check()
            .unwrap_err();
        assert!(
            e.contains("(its report.md) is the same file as --task"),
            "{e}"
        );
        assert_eq!(
            RunFiles::new()
                .input("--tools", &tools)
                .output_file("--csv", &dir.join("out.csv"))
                .check(),
            Ok(())
        );
    }

    #[test]
    fn two_outputs_on_one_path_are_refused() {
        let dir = scratch("outputs");
        let x = dir.join("x");
        let e = RunFiles::new()
            .output_file("--csv", &x)
            .output_folder("--report", &x, &["report.md"])
            .check()
            .unwrap_err();
        assert!(
            e.contains("--csv") && e.contains("--report") && e.contains("same file"),
            "{e}"
        );
        fs::create_dir(dir.join("r")).unwrap();
        let e = RunFiles::new()
            .output_file("--csv", &dir.join("r/./report.md"))
            .output_folder("--report", &dir.join("r"), &["report.md", "report.html"])
            .check()
            .unwrap_err();
        assert!(e.contains("(its report.md)"), "{e}");
        assert_eq!(
            RunFiles::new()
                .output_file("--csv", &dir.join("a.csv"))
                .output_folder("--report", &dir.join("r"), &["report.md"])
                .output_file("--also", Path::new("/dev/null"))
                .output_file("--again", Path::new("/dev/null"))
                .check(),
            Ok(())
        );
    }
}
