//! Models loaded at run time (crates/model/src/loaded/, `--model-path`,
//! `TOOLCONF_MODEL_PATH`): refusals of what is not a model library, each one line and status 2;
//! and, with the libraries `make loaded-models-test` builds (every model of the repository,
//! `make model IR=generated/<model>.json`), the loaded models equal the built-in ones bit for
//! bit through every operation of the registry and every subcommand.
//!
//! The tests that need the libraries are ignored by plain `cargo test`: `make
//! loaded-models-test` (part of `make test`) builds them into a temporary folder and runs them
//! with `TOOLCONF_TEST_LIBRARIES` naming it. Without it they fail, never pass.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use toolconf_model::closed_loop::EpisodeOptions;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::loaded;
use toolconf_model::registry::{ModelKind, Rows};

const BIN: &str = env!("CARGO_BIN_EXE_toolconf");

/// The folder of model libraries, one sub-folder per model (`<folder>/<model>/`).
fn libraries() -> PathBuf {
    match std::env::var_os("TOOLCONF_TEST_LIBRARIES") {
        Some(p) => PathBuf::from(p),
        None => panic!("TOOLCONF_TEST_LIBRARIES is not set: run `make loaded-models-test`"),
    }
}

/// Valid tools of `model`, drawn from its sample box (each checked by its rule).
fn tools(model: ModelKind, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for _ in 0..10_000 {
        let p: Vec<f64> = model
            .sample_box()
            .iter()
            .map(|&(lo, hi)| {
                if lo == hi {
                    lo
                } else {
                    rng.random_range(lo..hi)
                }
            })
            .collect();
        if model.model().check_tool(&p).is_ok() {
            out.push(p);
        }
        if out.len() == count {
            return out;
        }
    }
    panic!("{model}: no {count} valid tools in 10 000 draws");
}

/// `value`'s Debug text with the loaded model's name as the built-in one's: equal texts are
/// equal bits (Rust prints every f64 so that it reads back to the same bits; -0.0 and NaN
/// print as themselves).
fn text(value: impl std::fmt::Debug, loaded: ModelKind, builtin: ModelKind) -> String {
    format!("{value:?}").replace(loaded.name(), builtin.name())
}

/// Compares one operation on both models, counting the comparisons.
struct Same {
    builtin: ModelKind,
    loaded: ModelKind,
    compared: usize,
}

impl Same {
    fn check(&mut self, what: &str, b: impl std::fmt::Debug, l: impl std::fmt::Debug) {
        let (b, l) = (
            text(b, self.builtin, self.builtin),
            text(l, self.loaded, self.builtin),
        );
        assert_eq!(b, l, "{}: {what}: the loaded model differs", self.builtin);
        self.compared += 1;
    }
}

/// Every operation of the registry ([`toolconf_model::registry::Model`], [`toolconf_model::registry::
/// BoundTask`]) on the built-in model and on its library, loaded as `<model>_loaded`.
fn compare(builtin: ModelKind, library: &Path) -> usize {
    let name = format!("{}_loaded", builtin.name());
    let loaded = loaded::load(library, Some(&name)).unwrap_or_else(|e| panic!("{e}"));
    assert!(loaded.is_loaded() && !builtin.is_loaded());
    assert_eq!(loaded.name(), name);
    let (bi, li) = (builtin.info(), loaded.info());
    let mut same = Same {
        builtin,
        loaded,
        compared: 0,
    };
    let mut info = *li;
    info.name = bi.name;
    same.check("metadata", bi, info);
    let tools = tools(builtin, 6, 7);
    let (b, l) = (builtin.model(), loaded.model());
    for kind in bi.tasks {
        let spec = TaskSpec::builtin(*kind);
        let (bt, lt) = (b.bind(&spec).unwrap(), l.bind(&spec).unwrap());
        for p in &tools {
            let what = format!("{kind:?} {p:?}");
            same.check(&what, bt.logdet(p), lt.logdet(p));
            same.check(&what, bt.logdet_and_gradient(p), lt.logdet_and_gradient(p));
            same.check(&what, bt.linearisation(p), lt.linearisation(p));
            same.check(&what, bt.simulate(p), lt.simulate(p));
            same.check(&what, bt.trace(p), lt.trace(p));
            let common = EpisodeOptions::default();
            same.check(
                &what,
                b.paper_evaluation(p, *kind, &common),
                l.paper_evaluation(p, *kind, &common),
            );
        }
        let flat: Vec<f64> = tools.concat();
        same.check("confidences", bt.confidences(&flat), lt.confidences(&flat));
    }
    // The robot's own dynamics and the tip at random states, one tool per state.
    let run = |m: ModelKind| dynamics_and_tip(m, &tools);
    same.check("dynamics and tip", run(builtin), run(loaded));
    same.compared
}

/// Model `m`'s rigid-body dynamics, tip and tip bias for `tools` at random states (the same
/// for every model of the same size), one tool per state, as text.
fn dynamics_and_tip(m: ModelKind, tools: &[Vec<f64>]) -> String {
    let (n, k) = (m.dof(), tools.len());
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut random =
        |len: usize| -> Vec<f64> { (0..len).map(|_| rng.random_range(-1.5..1.5)).collect() };
    let (x, u) = (random(k * 2 * n), random(k * n));
    let params = tools.concat();
    fn rows(data: &[f64], width: usize) -> Rows<'_> {
        Rows {
            data,
            width,
            shared: false,
        }
    }
    let mut f = vec![0.0; k * 2 * n];
    let r = m.model().rigid_body_dynamics(
        k,
        &rows(&params, params.len() / k),
        &rows(&x, 2 * n),
        &rows(&u, n),
        &mut f,
    );
    let (mut y, mut j, mut bias) = (vec![0.0; k * 3], vec![0.0; k * 3 * n], vec![0.0; k * 3]);
    let q: Vec<f64> = x.chunks(2 * n).flat_map(|s| s[..n].to_vec()).collect();
    let q_dot: Vec<f64> = x.chunks(2 * n).flat_map(|s| s[n..].to_vec()).collect();
    let t = m.model().tip(
        k,
        &rows(&params, params.len() / k),
        &rows(&q, n),
        &mut y,
        &mut j,
    );
    let tb = m.model().tip_bias(
        k,
        &rows(&params, params.len() / k),
        &rows(&q, n),
        &rows(&q_dot, n),
        &mut bias,
    );
    format!("{r:?} {f:?} {t:?} {y:?} {j:?} {tb:?} {bias:?}")
}

#[test]
#[ignore = "needs the model libraries: make loaded-models-test"]
fn every_model_loaded_equals_built_in_bit_for_bit() {
    let folder = libraries();
    let mut total = 0;
    for builtin in ModelKind::BUILT_IN {
        let compared = compare(builtin, &folder.join(builtin.name()));
        eprintln!("{builtin}: {compared} results equal, bit for bit");
        total += compared;
    }
    // Loading again is the same model; under a name taken, a refusal naming it.
    let panda = folder.join("panda");
    let again = loaded::load(&panda, Some("panda_loaded")).unwrap();
    assert_eq!(again.name(), "panda_loaded");
    let refusal = |library: &std::path::Path, name: Option<&str>| {
        loaded::load(library, name).unwrap_err().to_string()
    };
    let taken = refusal(&panda, None);
    assert!(taken.contains("'panda' is already built in"), "{taken}");
    let again = refusal(&folder.join("ur5"), Some("panda_loaded"));
    assert!(
        again.contains("'panda_loaded' is already loaded from"),
        "{again}"
    );
    let bad = refusal(&panda, Some("Bad Name"));
    assert!(
        bad.contains("the model name 'Bad Name' is not one"),
        "{bad}"
    );
    // A name in capitals is refused as given, never lower-cased into another model's name.
    let upper = refusal(&panda, Some("Panda_C"));
    assert!(
        upper.contains("the model name 'Panda_C' is not one") && upper.contains("('panda_c' is)"),
        "{upper}"
    );
    assert!(!ModelKind::all().iter().any(|k| k.name() == "panda_c"));
    eprintln!(
        "{total} comparisons over {} models",
        ModelKind::BUILT_IN.len()
    );
}

/// The JSON of a subcommand's run with the timings taken out.
fn json(args: &[&str], env: Option<(&str, &str)>) -> serde_json::Value {
    let mut command = Command::new(BIN);
    command.args(args).env_remove(loaded::ENVIRONMENT);
    if let Some((k, v)) = env {
        command.env(k, v);
    }
    let out = command.output().unwrap();
    common::assert_ok_with(&out, &format!("{args:?}: "));
    let mut value: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    strip(&mut value);
    value
}

/// Removes what differs between two runs of the same work: timings and file names.
fn strip(value: &mut serde_json::Value) {
    match value {
        serde_json::Value::Object(map) => {
            map.retain(|k, _| !k.contains("timing") && !k.ends_with("_file") && k != "elapsed_s");
            map.values_mut().for_each(strip);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(strip),
        serde_json::Value::String(s) => *s = s.replace("panda_lib", "panda"),
        _ => {}
    }
}

#[test]
#[ignore = "needs the model libraries: make loaded-models-test"]
fn every_subcommand_runs_a_loaded_model_as_the_built_in_one() {
    let library = libraries().join("panda");
    let path = format!("panda_lib={}", library.display());
    let dir = tempfile::tempdir().unwrap();
    let tools = dir.path().join("tools.csv");
    let text = std::fs::read_to_string("examples/tools/panda_tools.csv").unwrap();
    std::fs::write(&tools, text.replace(",panda,", ",panda_lib,")).unwrap();
    let tools = tools.to_str().unwrap();
    let params = "0.5,0.01,0,0.08,0.002,0.002,0.001,0,0,0,0,0,0.16";
    let design = dir.path().join("design.toml");
    let design_text = std::fs::read_to_string("examples/design/panda_tool.toml").unwrap();
    std::fs::write(&design, design_text).unwrap();
    let design = design.to_str().unwrap();
    let runs: [Vec<&str>; 5] = [
        vec!["rank", "--tools", "examples/tools/panda_tools.csv"],
        vec!["simulate", "--model", "panda", "--params", params],
        vec!["confidence", "--model", "panda", "--params", params],
        vec![
            "select", "--models", "panda", "--tools", "12", "--seed", "3",
        ],
        vec!["design", "--model", "panda", "--design", design],
    ];
    // The same run on the library: its model's name, its tools file.
    let on_library = |args: &[&str]| -> Vec<String> {
        args.iter()
            .map(|a| match *a {
                "panda" => "panda_lib",
                "examples/tools/panda_tools.csv" => tools,
                a => a,
            })
            .map(String::from)
            .collect()
    };
    for task in [
        "examples/tasks/panda_touch_point.toml",
        "examples/tasks/panda_push_off.toml",
    ] {
        for builtin in &runs {
            if builtin[0] == "select" && task.ends_with("push_off.toml") {
                continue;
            }
            let with_library = on_library(builtin);
            // `rank` and `design` take a task file as --task; the others as --task-file.
            let flag = match builtin[0] {
                "rank" | "design" => "--task",
                _ => "--task-file",
            };
            let task_args = [flag, task, "--json"];
            let b: Vec<&str> = builtin.iter().copied().chain(task_args).collect();
            let l: Vec<&str> = with_library
                .iter()
                .map(String::as_str)
                .chain(task_args)
                .collect();
            let expected = json(&b, None);
            let by_flag: Vec<&str> = ["--model-path", path.as_str()]
                .into_iter()
                .chain(l.iter().copied())
                .collect();
            assert_eq!(json(&by_flag, None), expected, "{l:?} with --model-path");
            let by_environment = json(&l, Some((loaded::ENVIRONMENT, &path)));
            assert_eq!(
                by_environment,
                expected,
                "{l:?} with {}",
                loaded::ENVIRONMENT
            );
        }
    }
}

/// Runs the command line with `--model-path entry` and returns (status, stderr).
fn refused(entry: &str) -> (i32, String) {
    let out = Command::new(BIN)
        .args(["--model-path", entry, "confidence", "--model", "arm2"])
        .args(["--params", "1,1,1,1", "--task", "position"])
        .env_remove(loaded::ENVIRONMENT)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A shared library compiled from `source` by the C compiler (`cc`, as make test needs).
fn c_library(dir: &Path, name: &str, source: &str) -> PathBuf {
    let c = dir.join(format!("{name}.c"));
    std::fs::write(&c, source).unwrap();
    let so = dir.join(format!("lib{name}.so"));
    let status = Command::new("cc")
        .args(["-shared", "-fPIC", "-o"])
        .arg(&so)
        .arg(&c)
        .status()
        .expect("cc (make test needs a C compiler)");
    assert!(status.success());
    so
}

/// `entry`'s refusal (naming `why`) through the library, and from the environment variable.
fn refused_elsewhere(entry: &str, why: &str) {
    let e = loaded::load_entry(entry).unwrap_err().to_string();
    assert!(e.contains(why), "{e}");
    let out = Command::new(BIN)
        .args([
            "confidence",
            "--model",
            "arm2",
            "--params",
            "1,1,1,1",
            "--task",
            "position",
        ])
        .env(loaded::ENVIRONMENT, entry)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.starts_with("toolconf: error: TOOLCONF_MODEL_PATH: model library ")
            && stderr.contains(why)
            && stderr.lines().count() == 1,
        "{stderr}"
    );
}

#[test]
fn what_is_not_a_model_library_is_one_line_and_status_2() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = d.join("notes.txt");
    std::fs::write(&text, "not a library").unwrap();
    let empty = d.join("empty");
    std::fs::create_dir(&empty).unwrap();
    let no_symbols = c_library(d, "plain", "int toolconf_something_else = 1;\n");
    let other_version = c_library(
        d,
        "future",
        "unsigned toolconf_abi_version(void) { return 99; }\n",
    );
    let version = format!(
        "unsigned toolconf_abi_version(void) {{ return {}; }}\n",
        toolconf_cabi::ABI_VERSION
    );
    let half = c_library(d, "half", &version);
    let truncated = d.join("libtruncated.so");
    std::fs::write(&truncated, &std::fs::read(&half).unwrap()[..300]).unwrap();
    let cases: [(String, &str); 9] = [
        (d.join("missing").display().to_string(), "cannot read"),
        (empty.display().to_string(), "holds no model library"),
        (text.display().to_string(), "is not a shared library"),
        ("/dev/null".into(), "is not a file or a folder"),
        (
            no_symbols.display().to_string(),
            "no symbol toolconf_abi_version",
        ),
        (other_version.display().to_string(), "C ABI is version 99"),
        (
            half.display().to_string(),
            "no symbol toolconf_tasks_fingerprint",
        ),
        (truncated.display().to_string(), "is truncated or damaged"),
        (format!("Bad Name={}", half.display()), "no symbol"),
    ];
    for (entry, why) in cases {
        let (code, stderr) = refused(&entry);
        assert_eq!(code, 2, "{entry}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{entry}: {stderr}");
        assert!(
            stderr.starts_with("toolconf: error: --model-path: model library ")
                && stderr.contains(why),
            "{entry}: expected '{why}': {stderr}"
        );
        // The same refusal through the library, and from the environment variable.
        refused_elsewhere(&entry, why);
    }
}

#[test]
fn an_unknown_model_names_the_models_and_how_to_load_one() {
    // An unknown model still names the models there are, and how to load one.
    let out = Command::new(BIN)
        .args([
            "confidence",
            "--model",
            "xarm7",
            "--params",
            "1",
            "--task",
            "position",
        ])
        .env_remove(loaded::ENVIRONMENT)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr.contains("unknown model 'xarm7'") && stderr.contains("--model-path"),
        "{stderr}"
    );
}

/// (offset, size in the file) of every program header of a 64-bit little-endian ELF file, read
/// by hand from its header (e_phoff at 0x20, e_phentsize at 0x36, e_phnum at 0x38; p_offset at
/// +8, p_filesz at +32 of each entry): independent of the reader the loader uses.
fn segments(elf: &[u8]) -> Vec<(usize, usize)> {
    let word = |at: usize, n: usize| -> usize {
        elf[at..at + n]
            .iter()
            .rev()
            .fold(0usize, |v, b| (v << 8) | usize::from(*b))
    };
    let (phoff, phentsize, phnum) = (word(0x20, 8), word(0x36, 2), word(0x38, 2));
    (0..phnum)
        .map(|i| {
            let at = phoff + i * phentsize;
            (word(at + 8, 8), word(at + 32, 8))
        })
        .collect()
}

/// Where to cut `bytes` for the truncation tests: at every program header's start and end and
/// one byte short of its end, in the ELF header, and at a few lengths drawn from a seed.
fn cuts(bytes: &[u8], seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut cuts: Vec<usize> = segments(bytes)
        .into_iter()
        .flat_map(|(offset, size)| [offset, offset + size, (offset + size).saturating_sub(1)])
        .chain([1, 5, 63, 64, 300])
        .chain((0..5).map(|_| rng.random_range(1..bytes.len())))
        .filter(|c| (1..bytes.len()).contains(c))
        .collect();
    cuts.sort_unstable();
    cuts.dedup();
    cuts
}

/// The library `whole` cut at each of [`cuts`] into `dir`: each is refused in one line naming
/// the file, status 2, by `--model-path` and `TOOLCONF_MODEL_PATH`, and in this process;
/// never a crash (the command line's status would be 135, SIGBUS, and this test would die).
fn truncations_are_refused(whole: &Path, dir: &Path, seed: u64) -> usize {
    let bytes = std::fs::read(whole).unwrap();
    let cuts = cuts(&bytes, seed);
    for (i, cut) in cuts.iter().enumerate() {
        let t = dir.join(format!("t{i}.so"));
        std::fs::write(&t, &bytes[..*cut]).unwrap();
        let entry = t.display().to_string();
        let (code, stderr) = refused(&entry);
        let why = ["is truncated or damaged", "is not a shared library"];
        assert!(
            code == 2
                && stderr.lines().count() == 1
                && stderr.contains(&format!("model library {entry}: "))
                && why.iter().any(|w| stderr.contains(w)),
            "cut at {cut} of {}: status {code}: {stderr}",
            bytes.len()
        );
        let out = Command::new(BIN)
            .args(["confidence", "--model", "arm2", "--params", "1,1,1,1"])
            .args(["--task", "position"])
            .env(loaded::ENVIRONMENT, &entry)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.code() == Some(2) && stderr.lines().count() == 1,
            "{loaded_env} cut at {cut}: {:?}: {stderr}",
            out.status,
            loaded_env = loaded::ENVIRONMENT
        );
        let e = loaded::load_entry(&entry).unwrap_err().to_string();
        assert!(why.iter().any(|w| e.contains(w)), "{e}");
    }
    cuts.len()
}

#[test]
fn a_truncated_library_is_one_line_and_status_2_never_a_crash() {
    let dir = tempfile::tempdir().unwrap();
    // Data enough for a segment of its own beyond the first pages.
    let source = format!(
        "unsigned toolconf_abi_version(void) {{ return {}; }}\nint table[8192] = {{1}};\n",
        toolconf_cabi::ABI_VERSION
    );
    let whole = c_library(dir.path(), "whole", &source);
    let cut = truncations_are_refused(&whole, dir.path(), 1);
    assert!(cut >= 10, "{cut} cuts");
    // The whole library gets past the headers to its symbols.
    let (code, stderr) = refused(&whole.display().to_string());
    assert!(
        code == 2 && stderr.contains("no symbol toolconf_tasks_fingerprint"),
        "{stderr}"
    );
}

/// The library file in `make model`'s folder `dir`.
fn library_in(dir: &Path) -> PathBuf {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "so"))
        .expect("a library in the folder")
}

#[test]
#[ignore = "needs the model libraries: make loaded-models-test"]
fn a_truncated_model_library_is_one_line_and_status_2_never_a_crash() {
    let dir = tempfile::tempdir().unwrap();
    let panda = library_in(&libraries().join("panda"));
    let cut = truncations_are_refused(&panda, dir.path(), 2);
    // `head -c 300000`, the cut that killed the process with SIGBUS before the check.
    let bytes = std::fs::read(&panda).unwrap();
    let t = dir.path().join("head.so");
    std::fs::write(&t, &bytes[..300_000]).unwrap();
    let (code, stderr) = refused(&t.display().to_string());
    assert!(
        code == 2 && stderr.contains("is truncated or damaged"),
        "{stderr}"
    );
    eprintln!(
        "{} bytes cut at {} places, each refused",
        bytes.len(),
        cut + 1
    );
}

/// Each library's C ABI fuzzed ([`toolconf_cabi::check::fuzz`]) with another library's
/// controllers as the foreign handles, and controllers ticked from several threads at once:
/// the libraries `make model` built, as a C program would call them.
#[test]
#[ignore = "needs the model libraries: make loaded-models-test"]
fn each_librarys_c_abi_refuses_the_others_handles_under_fuzzing() {
    use toolconf_cabi::check::{self, cases::controller_through};
    use toolconf_cabi::toolconf_core::{Arm2, Arm3, ArmModel as _};
    let folder = libraries();
    let arm2 = loaded::open_exports(&folder.join("arm2")).unwrap();
    let arm3 = loaded::open_exports(&folder.join("arm3")).unwrap();
    let cases = check::fuzz_cases(3000);
    let create3 = || controller_through::<Arm3, 3, 6, 6, 9>(&arm3);
    let (calls, seen) = fuzz_against::<Arm2, 2, 4, 4, 6>(&arm2, &arm3, &create3, cases, 3);
    assert!(calls >= cases && seen[toolconf_cabi::status::BAD_HANDLE as usize] > 0);
    let create2 = || controller_through::<Arm2, 2, 4, 4, 6>(&arm2);
    fuzz_against::<Arm3, 3, 6, 6, 9>(&arm3, &arm2, &create2, cases, 4);
    let state = Arm2::equilibrium_state();
    let own = || controller_through::<Arm2, 2, 4, 4, 6>(&arm2);
    check::fuzz_threads(&arm2, &own, state.as_slice(), 2, 4, cases / 8);
}

/// [`toolconf_cabi::check::fuzz`] of library `own` (model `M`) with library `other`'s
/// controllers, made by `create` and destroyed through `other`, as the foreign handles.
fn fuzz_against<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    own: &toolconf_cabi::Exports,
    other: &toolconf_cabi::Exports,
    create: &dyn Fn() -> *mut toolconf_cabi::bodies::Controller,
    cases: usize,
    seed: u64,
) -> (usize, [usize; toolconf_cabi::status::NAMES.len()])
where
    M: toolconf_cabi::toolconf_core::ArmModel<N, NX, NP, NZ> + 'static,
{
    // SAFETY: any handle value is checked.
    let destroy = |h| unsafe { (other.controller_destroy)(h) };
    let foreign = toolconf_cabi::check::Foreign {
        create,
        destroy: &destroy,
    };
    toolconf_cabi::check::fuzz::<M, N, NX, NP, NZ>(own, &foreign, cases, seed)
}

proptest::proptest! {
    #![proptest_config(proptest::test_runner::Config::with_cases(
        std::env::var("TOOLCONF_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256)
    ))]
    /// Any text as a `--model-path` entry: a refusal in one line, never a panic.
    #[test]
    fn any_entry_is_loaded_or_refused_in_one_line(entry in "\\PC{0,40}") {
        if let Err(e) = loaded::load_entry(&entry) {
            let line = e.to_string();
            proptest::prop_assert!(!line.contains('\n'), "{line}");
        }
    }
}
