//! The layers as crates (docs/explanation/pipeline.md, "Crates"): each depends only on the ones below it, and the low
//! ones carry little. Checked with `cargo tree` on the manifests, as a user would look.

mod common;

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

/// What a robot, a microcontroller or the Python package must not pull in.
const HEAVY: [&str; 10] = [
    "clap",
    "rayon",
    "plotters",
    "clarabel",
    "indicatif",
    "csv",
    "toml",
    "serde_json",
    "tera",
    "toolconf-report",
];

/// The package names of `cargo tree` on `manifest` with `args`.
fn tree(manifest: &str, args: &[&str]) -> BTreeSet<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(root)
        .args([
            "tree",
            "--manifest-path",
            manifest,
            "--prefix",
            "none",
            "--format",
            "{p}",
        ])
        .args(args)
        .output()
        .expect("run cargo tree");
    common::assert_ok_with(&out, &format!("cargo tree {manifest}: "));
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(String::from))
        .collect()
}

fn no_std_root(file: &str) -> bool {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(file)).unwrap();
    text.lines().any(|l| l.trim() == "#![no_std]")
}

#[test]
fn the_generated_crate_is_no_std_on_nalgebra_alone() {
    assert!(no_std_root("generated/src/lib.rs"));
    let direct = tree("generated/Cargo.toml", &["-e", "normal", "--depth", "1"]);
    let expected: BTreeSet<String> = ["toolconf-generated", "nalgebra", "libm"]
        .map(String::from)
        .into();
    assert_eq!(direct, expected);
    // nalgebra without default features: none of its std-only or optional dependencies.
    let all = tree("generated/Cargo.toml", &["-e", "normal"]);
    for std_only in ["matrixmultiply", "serde", "rand", "wide", "rayon"] {
        assert!(!all.contains(std_only), "{std_only} in {all:?}");
    }
}

#[test]
fn the_core_is_no_std_on_the_generated_crate() {
    assert!(no_std_root("crates/core/src/lib.rs"));
    let direct = tree("crates/core/Cargo.toml", &["-e", "normal", "--depth", "1"]);
    let expected: BTreeSet<String> = [
        "toolconf-core",
        "toolconf-generated",
        "nalgebra",
        "libm",
        "thiserror",
    ]
    .map(String::from)
    .into();
    assert_eq!(direct, expected);
}

#[test]
fn what_a_robot_links_has_nothing_heavy() {
    assert!(no_std_root("examples/on_robot/src/lib.rs"));
    // All edges, dev and build included: the crate's whole tree.
    let all = tree("examples/on_robot/Cargo.toml", &[]);
    assert!(all.contains("toolconf-core") && all.contains("toolconf-generated"));
    for heavy in HEAVY.iter().chain(&["toolconf", "toolconf-files"]) {
        assert!(
            !all.contains(*heavy),
            "{heavy} in the on-robot tree {all:?}"
        );
    }
}

#[test]
fn the_c_abi_is_on_the_core_alone_without_its_std_feature() {
    let direct = tree("crates/cabi/Cargo.toml", &["-e", "normal", "--depth", "1"]);
    let expected: BTreeSet<String> = ["toolconf-cabi", "toolconf-core", "nalgebra", "sha2"]
        .map(String::from)
        .into();
    assert_eq!(direct, expected);
    let all = tree("crates/cabi/Cargo.toml", &["-e", "normal"]);
    for heavy in HEAVY.iter().chain(&["toolconf", "toolconf-files"]) {
        assert!(!all.contains(*heavy), "{heavy} in the C ABI's tree {all:?}");
    }
    // ln|Π^U| through the C ABI is the on-robot controller's (the libm crate's), not the std
    // runtime's: a model library's ticks are that controller's, bit for bit.
    let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "--manifest-path",
            "crates/cabi/Cargo.toml",
            "-e",
            "normal",
        ])
        .args(["--prefix", "none", "--format", "{p} features=[{f}]"])
        .output()
        .expect("run cargo tree");
    let text = String::from_utf8_lossy(&out.stdout);
    let core: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("toolconf-core "))
        .collect();
    assert!(
        !core.is_empty() && core.iter().all(|l| l.ends_with("features=[]")),
        "{text}"
    );
}

#[test]
fn the_runtime_and_the_python_package_have_no_command_line_plots_or_progress_bars() {
    for manifest in [
        "crates/model/Cargo.toml",
        "crates/toolconf/Cargo.toml",
        "python/Cargo.toml",
    ] {
        let normal = tree(manifest, &["-e", "normal"]);
        for top in [
            "clap",
            "plotters",
            "indicatif",
            "toolconf-report",
            "toolconf-cli",
        ] {
            assert!(!normal.contains(top), "{top} in {manifest}'s tree");
        }
    }
    let runtime = tree(
        "crates/toolconf/Cargo.toml",
        &["-e", "normal", "--depth", "1"],
    );
    assert!(runtime.contains("toolconf-core") && runtime.contains("toolconf-generated"));
}

#[test]
fn the_files_crate_is_a_leaf_that_the_runtime_and_the_renderer_share() {
    let all = tree("crates/files/Cargo.toml", &["-e", "normal"]);
    let ours: Vec<&String> = all.iter().filter(|p| p.starts_with("toolconf")).collect();
    assert_eq!(ours, ["toolconf-files"], "{all:?}");
    for heavy in HEAVY {
        assert!(!all.contains(heavy), "{heavy} in the files crate's tree");
    }
    // One output-file rule: the command line and the reports reach it through the runtime,
    // make crate through the renderer.
    for manifest in ["crates/toolconf/Cargo.toml", "derive/render/Cargo.toml"] {
        let direct = tree(manifest, &["-e", "normal", "--depth", "1"]);
        assert!(direct.contains("toolconf-files"), "{manifest}: {direct:?}");
    }
}

/// What a robot links builds for a microcontroller without std or an allocator (a Cortex-M4F),
/// where the rustup target is installed (`rustup target add thumbv7em-none-eabihf`).
#[test]
fn the_on_robot_controller_builds_for_a_bare_metal_target() {
    let target = "thumbv7em-none-eabihf";
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sysroot = Command::new("rustc").args(["--print", "sysroot"]).output();
    let installed = sysroot.is_ok_and(|o| {
        let lib = Path::new(String::from_utf8_lossy(&o.stdout).trim())
            .join("lib/rustlib")
            .join(target);
        lib.is_dir()
    });
    if !installed {
        eprintln!("skipped: the {target} target is not installed");
        return;
    }
    let out = Command::new(cargo)
        .current_dir(root)
        .args([
            "build",
            "--quiet",
            "--lib",
            "--target",
            target,
            "--manifest-path",
            "examples/on_robot/Cargo.toml",
        ])
        .output()
        .expect("run cargo build");
    common::assert_ok(&out);
}

/// The toolconf crates each crate depends on directly (normal edges): (manifest, package, the
/// toolconf packages it may import), every name but the runtime's `toolconf` without its
/// `toolconf-` prefix. One direction of flow, each part of the runtime's former whole on only
/// what is below it. A new edge is a decision about the layers, taken here. The Python
/// package's `workspace-hack` is not imported: it only sets features
/// (crates/workspace-hack/Cargo.toml).
#[rustfmt::skip]
const LAYERS: &[(&str, &str, &[&str])] = &[
    ("crates/files", "files", &[]),
    ("crates/stats", "stats", &[]),
    ("crates/messages", "messages", &["core"]),
    ("crates/integrators", "integrators", &["core"]),
    ("crates/tool-urdf", "tool-urdf", &["files", "messages"]),
    ("crates/model", "model", &["cabi", "core", "files", "generated", "integrators", "messages"]),
    ("crates/toolconf", "toolconf",
        &["core", "files", "generated", "integrators", "messages", "model", "stats"]),
    ("crates/report", "report",
        &["toolconf", "files", "generated", "integrators", "model", "stats"]),
    ("python", "python",
        &["toolconf", "files", "generated", "integrators", "messages", "model", "tool-urdf",
          "workspace-hack"]),
    (".", "cli",
        &["toolconf", "files", "generated", "integrators", "messages", "model", "report",
          "tool-urdf"]),
];

/// `toolconf` for the runtime, `toolconf-NAME` for every other short name of [`LAYERS`].
fn package(name: &str) -> String {
    match name {
        "toolconf" => name.to_string(),
        _ => format!("toolconf-{name}"),
    }
}

/// The crates that carry nothing heavy ([`HEAVY`]): the integrators, the statistics, the
/// messages and the URDF reader.
const LIGHT: [&str; 4] = [
    "crates/integrators/Cargo.toml",
    "crates/stats/Cargo.toml",
    "crates/messages/Cargo.toml",
    "crates/tool-urdf/Cargo.toml",
];

/// Each crate's direct toolconf dependencies are its row of [`LAYERS`], and the [`LIGHT`]
/// crates' whole trees hold nothing [`HEAVY`].
#[test]
fn each_crate_imports_only_the_layers_below_it() {
    for &(dir, name, expected) in LAYERS {
        let manifest = format!("{dir}/Cargo.toml");
        let direct = tree(&manifest, &["-e", "normal", "--depth", "1"]);
        let ours: BTreeSet<String> = direct
            .into_iter()
            .filter(|p| p.starts_with("toolconf") && *p != package(name))
            .collect();
        let expected: BTreeSet<String> = expected.iter().map(|e| package(e)).collect();
        assert_eq!(ours, expected, "{manifest}'s toolconf dependencies");
    }
    for manifest in LIGHT {
        let all = tree(manifest, &["-e", "normal"]);
        for heavy in HEAVY {
            assert!(!all.contains(heavy), "{heavy} in {manifest}'s tree");
        }
    }
}

/// A crate's root re-exports no other toolconf crate's modules (`pub use toolconf_x as y;`,
/// `use toolconf::{module, ...}` to reach them as `crate::module`): a path says which crate
/// the code is in.
#[test]
fn no_crate_root_reexports_another_crates_modules() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for lib in [
        "crates/files/src/lib.rs",
        "crates/stats/src/lib.rs",
        "crates/messages/src/lib.rs",
        "crates/integrators/src/lib.rs",
        "crates/tool-urdf/src/lib.rs",
        "crates/model/src/lib.rs",
        "crates/toolconf/src/lib.rs",
        "crates/report/src/lib.rs",
        "python/src/lib.rs",
        "src/main.rs",
    ] {
        let text = std::fs::read_to_string(root.join(lib)).unwrap();
        for line in text.lines().map(str::trim) {
            let reexport = line.starts_with("pub use toolconf_files")
                || line.starts_with("pub use toolconf_integrators")
                || line.starts_with("pub use toolconf_stats")
                || line.starts_with("pub use toolconf_tool_urdf")
                || line.starts_with("pub use toolconf_messages as")
                || line.starts_with("pub use toolconf_generated")
                || line.starts_with("pub use toolconf_model")
                || line.starts_with("use toolconf_model::{")
                || line.starts_with("use toolconf::{")
                || line.starts_with("pub use toolconf::");
            assert!(!reexport, "{lib}: {line}");
        }
    }
}

/// Each dependency of the Python extension, with its features, as `cargo tree` resolves it for
/// `maturin develop` (the extension alone), and the same for `cargo test --workspace` (make test's
/// build of every test): what the extension asks for, each with the features the tests' build
/// gave it.
fn features(args: &[&str]) -> BTreeSet<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(root)
        .args(["tree", "--prefix", "none", "--format", "{p} [{f}]"])
        .args(args)
        .output()
        .expect("run cargo tree");
    common::assert_ok_with(&out, "cargo tree: ");
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| l.trim_end_matches(" (*)").to_string())
        .collect()
}

/// make test builds every crate's tests, then the Python extension alone (maturin): a dependency
/// the two ask for with different features is compiled twice, with all that is above it (the
/// model layer and the runtime: 329 CPU-seconds). crates/workspace-hack gives both the same
/// features (and Cargo.toml's build-override the same debug information to the proc macros).
#[test]
fn the_python_extension_reuses_the_tests_builds_of_its_dependencies() {
    let python = features(&["-p", "toolconf-python", "-e", "normal,build"]);
    let tests = features(&[
        "--workspace",
        "--exclude",
        "toolconf-python",
        "-e",
        "normal,build,dev",
    ]);
    // "name vX.Y.Z": the packages both builds compile (pyo3 and numpy are the extension's alone).
    let package = |line: &str| {
        line.split(" [")
            .next()
            .unwrap_or(line)
            .replace(" (proc-macro)", "")
    };
    let shared: BTreeSet<String> = tests.iter().map(|l| package(l)).collect();
    let apart: Vec<&String> = python
        .iter()
        .filter(|p| shared.contains(&package(p)) && !tests.contains(*p))
        .collect();
    assert!(
        apart.is_empty(),
        "the Python extension's build asks for these with features the tests' build does not \
         (add them to crates/workspace-hack/Cargo.toml): {apart:#?}"
    );
}
