//! What the integration tests share: running the built `toolconf` and failing with its stderr
//! when it did not succeed.
#![allow(dead_code)] // each test binary uses its own part of this module

use std::process::{Command, Output};

use serde_json::Value;

/// The `toolconf` built for these tests, run from the repository's root (where the examples'
/// relative paths point).
pub fn toolconf_command() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_toolconf"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd
}

/// Fails the calling test, with the command's stderr, unless the command exited with status 0.
#[track_caller]
pub fn assert_ok(out: &Output) {
    assert_ok_with(out, "");
}

/// As [`assert_ok`], the failure message starting with `context`.
#[track_caller]
pub fn assert_ok_with(out: &Output, context: &str) {
    assert!(
        out.status.success(),
        "{context}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The command's stdout as JSON, once [`assert_ok`] has passed.
#[track_caller]
pub fn json_ok(out: &Output) -> Value {
    assert_ok(out);
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

/// `toolconf ARGS`, run from the repository's root.
pub fn toolconf(args: &[&str]) -> Output {
    toolconf_command()
        .args(args)
        .output()
        .expect("run toolconf")
}

/// `toolconf ARGS`'s stdout as JSON, the run having succeeded.
#[track_caller]
pub fn toolconf_json(args: &[&str]) -> Value {
    json_ok(&toolconf(args))
}

/// `name` under cargo's temporary folder for the tests, emptied: a folder of one test's own.
pub fn fresh_dir(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` to the file `name` in `dir`: its path.
pub fn write_file(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A [`fresh_dir`] `dir` holding one file, `name` with `text`: the file's path.
pub fn fresh_file(dir: &str, name: &str, text: &str) -> std::path::PathBuf {
    write_file(&fresh_dir(dir), name, text)
}

/// `result` is the refusal of precisions under which Π^U has rank 0 for every tool of `joints`
/// joints.
#[track_caller]
pub fn assert_rank_zero<T: std::fmt::Debug>(
    result: Result<T, toolconf_model::model::Error>,
    joints: usize,
) {
    assert!(
        matches!(
            &result,
            Err(toolconf_model::model::Error::ConfidenceRank { rank: 0, joints: j, .. }) if *j == joints
        ),
        "{result:?}"
    );
}

/// Caps `cmd`'s address space at 2 GB, so that an allocation beyond it aborts the run rather
/// than taking the machine's memory.
pub fn limit_memory(cmd: &mut Command) -> &mut Command {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec only setrlimit, which is async-signal-safe.
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 2 << 30,
                rlim_max: 2 << 30,
            };
            libc::setrlimit(libc::RLIMIT_AS, &limit);
            Ok(())
        });
    }
    cmd
}

/// The files of a folder by name, with their bytes.
pub fn folder_files(dir: &std::path::Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// ∂f/∂z by central differences, column j with the step `1e-6·max(1, |z_j|)`, divided by the
/// increment as represented.
pub fn central_differences<const N: usize>(
    f: impl Fn(&nalgebra::SVector<f64, N>) -> nalgebra::SVector<f64, N>,
    z: &nalgebra::SVector<f64, N>,
) -> nalgebra::SMatrix<f64, N, N> {
    let mut j = nalgebra::SMatrix::<f64, N, N>::zeros();
    for c in 0..N {
        let h = 1e-6 * z[c].abs().max(1.0);
        let (mut plus, mut minus) = (*z, *z);
        plus[c] += h;
        minus[c] -= h;
        let width = plus[c] - minus[c];
        j.set_column(c, &((f(&plus) - f(&minus)) / width));
    }
    j
}

/// `each` of the tools of `rank`'s or `select`'s JSON, in its order.
pub fn each_tool<T>(v: &Value, each: impl FnMut(&Value) -> T) -> Vec<T> {
    v["tools"]
        .as_array()
        .expect("a tools list")
        .iter()
        .map(each)
        .collect()
}

/// The generated 2-link Ẋ's accelerations (its last two entries) against a textbook's q̈, to
/// 1e-11 of max(|q̈|, 1): the two formulas differ only in the order of their operations.
pub fn accelerations_match_the_textbook(
    x_dot: &nalgebra::SVector<f64, 4>,
    q_ddot: &nalgebra::Vector2<f64>,
) -> Result<(), proptest::test_runner::TestCaseError> {
    let scale = q_ddot.amax().max(1.0);
    proptest::prop_assert!(
        (x_dot[2] - q_ddot[0]).abs() <= 1e-11 * scale
            && (x_dot[3] - q_ddot[1]).abs() <= 1e-11 * scale,
        "generated {x_dot} vs textbook {q_ddot}"
    );
    Ok(())
}
