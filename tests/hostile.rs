//! The hostile-input sweep: the reported examples of each class and more, against the binary
//! (the debug one in `cargo test`; the release one with
//! `TOOLCONF_BIN=target/release/toolconf cargo test --release --test hostile`). Each case runs
//! in a folder of its own, under a 2 GB address-space limit, and must end with its expected
//! status (bad input 2, a failed run 1, a batch with some failed tools or a valid but extreme
//! input 0), never a signal or a panic; a failing status with exactly one line on stderr; no
//! NaN or inf on stdout, nor a JSON null where a number belongs; no temporary file left behind;
//! symbolic links still links and devices still devices.

mod common;

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

fn binary() -> PathBuf {
    std::env::var_os("TOOLCONF_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_toolconf")))
        .canonicalize()
        .expect("the toolconf binary")
}

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(path)
        .display()
        .to_string()
}

/// One hostile input: the files it needs, its arguments, where its stdout goes, and what it
/// must end with.
struct Case {
    name: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    args: Vec<String>,
    stdout: Sink,
    env: Vec<(&'static str, &'static str)>,
    status: i32,
    /// Fragments the stderr line must hold (for a failing status).
    says: Vec<&'static str>,
    /// Paths that must not exist afterwards (an output refused before any work).
    absent: Vec<&'static str>,
    /// Symbolic links to make (name, target).
    links: Vec<(&'static str, &'static str)>,
}

#[derive(Clone, Copy, PartialEq)]
enum Sink {
    Captured,
    Full,
}

fn case(name: &'static str, args: &[&str], status: i32, says: &[&'static str]) -> Case {
    Case {
        name,
        files: Vec::new(),
        args: args.iter().map(|a| a.to_string()).collect(),
        stdout: Sink::Captured,
        env: Vec::new(),
        status,
        says: says.to_vec(),
        absent: Vec::new(),
        links: Vec::new(),
    }
}

impl Case {
    fn file(mut self, name: &'static str, text: impl Into<Vec<u8>>) -> Self {
        self.files.push((name, text.into()));
        self
    }

    fn into_full(mut self) -> Self {
        self.stdout = Sink::Full;
        self
    }

    fn link(mut self, name: &'static str, target: &'static str) -> Self {
        self.links.push((name, target));
        self
    }

    fn absent(mut self, path: &'static str) -> Self {
        self.absent.push(path);
        self
    }

    fn env(mut self, key: &'static str, value: &'static str) -> Self {
        self.env.push((key, value));
        self
    }
}

const ARM: &str = "0.3,0.4,0.5,0.2";

/// The files the cases name, from the repository.
struct Fixtures {
    drawer: String,
    design: String,
    panda_tools: String,
    panda_touch: String,
    panda_task: String,
}

/// Every case, by class of hostile input: tables of one row a case, each row on one line
/// (`#[rustfmt::skip]` keeps them so).
fn cases() -> Vec<Case> {
    let f = Fixtures {
        drawer: repo("examples/tools/drawer.csv"),
        design: repo("examples/design/reach_and_budget.toml"),
        panda_tools: repo("examples/tools/panda_tools.csv"),
        panda_touch: repo("examples/tasks/panda_touch_point.toml"),
        panda_task: std::fs::read_to_string(repo("examples/tasks/panda_wrist_turn.toml")).unwrap(),
    };
    let groups = [
        panics_and_reads(&f),
        results_and_exit_codes(&f),
        output_files(&f),
        design_and_messages(&f),
        evaluation_and_threads(&f),
    ];
    groups.into_iter().flatten().collect()
}

/// Panics and unbounded reads.
#[rustfmt::skip]
fn panics_and_reads(f: &Fixtures) -> Vec<Case> {
    let d = f.drawer.as_str();
    let design = f.design.as_str();
    let long_name = "n".repeat(70_000);
    vec![
        // 1. Panics: a long tool name, an unwritable stdout.
        case("long name, CSV", &["rank", "--tools", "long.csv", "--task", "position", "--screen", "1"], 0, &[])
            .file("long.csv", format!("name,m1,m2,l1,l2\n{long_name},0.3,0.4,0.5,0.2\n")),
        case("long name, JSON", &["rank", "--tools", "long.json", "--task", "position"], 0, &[])
            .file("long.json", format!("[{{\"name\": \"{long_name}\", \"m1\": 0.3, \"m2\": 0.4, \"l1\": 0.5, \"l2\": 0.2}}]")),
        case("confidence > /dev/full", &["confidence", "--arm", ARM, "--task", "velocity"], 1, &["cannot write to standard output", "No space left"]).into_full(),
        case("simulate > /dev/full", &["simulate", "--arm", ARM, "--task", "position", "--json"], 1, &["standard output"]).into_full(),
        case("select > /dev/full", &["select", "--tools", "2", "--task", "velocity"], 1, &["standard output"]).into_full(),
        case("rank > /dev/full", &["rank", "--tools", d, "--task", "position", "--screen", "1"], 1, &["standard output"]).into_full(),
        case("design > /dev/full", &["design", "--task", "velocity", "--design", design], 1, &["standard output"]).into_full(),
        case("--help > /dev/full", &["rank", "--help"], 1, &["standard output"]).into_full(),
        // 2. Unbounded reads.
        case("tools /dev/zero", &["rank", "--tools", "/dev/zero", "--task", "position"], 2, &["/dev/zero", "is a device, not a tools file"]),
        case("tools JSON /dev/zero", &["rank", "--tools", "zero.json", "--task", "position"], 2, &["zero.json", "is a device, not a tools file"]),
        case("task /dev/zero", &["rank", "--tools", d, "--task", "/dev/zero"], 2, &["/dev/zero", "is a device, not a task file"]),
        case("task-file /dev/zero", &["confidence", "--arm", ARM, "--task-file", "/dev/zero"], 2, &["/dev/zero", "is a device"]),
        case("design /dev/zero", &["design", "--task", "velocity", "--design", "/dev/zero"], 2, &["/dev/zero", "is a device"]),
        case("a 2 MB row", &["rank", "--tools", "wide.csv", "--task", "position"], 2, &["wide.csv, line 2", "row longer than"])
            .file("wide.csv", format!("name,m1,m2,l1,l2\n{},0.3,0.4,0.5,0.2\n", "w".repeat(2 << 20))),
        case("a 2 MB JSON tool", &["rank", "--tools", "wide.json", "--task", "position"], 2, &["wide.json, line 1", "tool longer than"])
            .file("wide.json", format!("[{{\"name\": \"{}\"}}]", "w".repeat(2 << 20))),
        case("deep JSON", &["rank", "--tools", "deep.json", "--task", "position"], 2, &["deep.json", "recursion limit"])
            .file("deep.json", format!("[{{\"name\": {}", "[".repeat(100_000))),
    ]
}

/// Non-finite results, and the exit codes of bad options.
#[rustfmt::skip]
fn results_and_exit_codes(f: &Fixtures) -> Vec<Case> {
    let d = f.drawer.as_str();
    let design = f.design.as_str();
    let panda_tools = f.panda_tools.as_str();
    let panda_task = &f.panda_task;
    vec![
        // 3. Non-finite results.
        case("arm 1e308", &["confidence", "--arm", "1e308,1e308,1e308,1e308", "--task", "velocity"], 2, &["m1 = 1e308", "[1e-6, 1e6]"]),
        case("arm at the range's edge", &["confidence", "--arm", "1e-6,1e-6,1e-6,1e6", "--task", "velocity", "--json"], 1, &["ill-conditioned"]),
        case("arm at the box's light corner", &["confidence", "--arm", "1e-6,1e-6,1e-6,1e-6", "--task", "velocity", "--json"], 0, &[]),
        case("precision 1e300", &["confidence", "--arm", ARM, "--task-file", "p.toml"], 2, &["p.toml", "key precision.theta", "1e300"])
            .file("p.toml", "kind = \"position\"\n[precision]\ntheta = 1e300\n"),
        case("goal 1e300", &["simulate", "--arm", ARM, "--task-file", "g.toml"], 2, &["g.toml", "key goal.theta", "1e300"])
            .file("g.toml", "kind = \"position\"\n[goal]\ntheta = [1e300, 0.0]\n"),
        // Starts and goals a joint can have: an angle of 1e6 rad cost 10⁶ step attempts a tool.
        case("Panda initial_theta 1e6", &["rank", "--tools", panda_tools, "--task", "far.toml"], 2, &["far.toml", "key episode.initial_theta", "1e6 must be a number in [-4π, 4π] rad"])
            .file("far.toml", format!("{}initial_theta = [1e6, 0.0, 0.0, -1.5, 0.0, 1.5, 0.8]\n", panda_task)),
        case("goal rate 1e3", &["simulate", "--arm", ARM, "--task-file", "fast.toml"], 2, &["fast.toml", "key goal.theta_dot", "[-100, 100] rad/s"])
            .file("fast.toml", "kind = \"velocity\"\n[goal]\ntheta_dot = [0.0, 1e3]\n"),
        case("goal acceleration 1e5", &["simulate", "--arm", ARM, "--task-file", "jerk.toml"], 2, &["jerk.toml", "key goal.theta_ddot", "[-1e4, 1e4] rad/s²"])
            .file("jerk.toml", "kind = \"acceleration\"\n[goal]\ntheta_ddot = [0.0, 1e5]\n"),
        // The work budget: within range, but dynamics no episode can follow (ode45 on a
        // micrometre arm; a millimetre arm flung past any joint's rate) stop after 10⁵ attempts.
        case("an episode out of work", &["simulate", "--arm", "1e-6,1e-6,1e-6,1e-6", "--task", "position", "--method", "explicit"], 1, &["episode stopped after 100000 step attempts", "the step size had fallen to"]),
        case("an episode out of the joints' range", &["simulate", "--arm", "1e-3,1e-3,1e-3,1e-3", "--task", "position", "--method", "explicit"], 1, &["episode stopped after 100000 step attempts", "the state left the joints' range, θ̇"]),
        case("tools file 1e200", &["rank", "--tools", "big.csv", "--task", "position"], 2, &["big.csv, line 2", "l1 = 1e200"])
            .file("big.csv", "name,m1,m2,l1,l2\ngiant,0.3,0.3,1e200,1e200\n"),
        // 4. Exit codes: bad options are 2 before any work, in every command.
        case("simulate mpc horizon 1e6", &["simulate", "--arm", ARM, "--task", "position", "--controller", "mpc", "--horizon", "1e6"], 2, &["--horizon", "at most 10000"]),
        case("simulate mpc horizon 1e-9", &["simulate", "--arm", ARM, "--task", "position", "--controller", "mpc", "--horizon", "1e-9"], 2, &["horizon = 1e-9"]),
        case("select dt 0", &["select", "--tools", "2", "--task", "position", "--dt", "0"], 2, &["--dt: 0 must be a number in [1e-6, 1e6] s"]),
        case("select gamma 0", &["select", "--tools", "2", "--task", "position", "--gamma", "0"], 2, &["--gamma"]),
        case("select gamma 1e308", &["select", "--tools", "2", "--task", "position", "--gamma", "1e308"], 2, &["--gamma: 1e308"]),
        case("select perturb nan", &["select", "--tools", "2", "--task", "position", "--perturb", "nan"], 2, &["--perturb: NaN"]),
        case("select t-end 1e9", &["select", "--tools", "2", "--task", "position", "--t-end", "1e9"], 2, &["--t-end: 1e9"]),
        case("select t-end 1e5", &["select", "--tools", "2", "--task", "position", "--t-end", "1e5"], 2, &["episode too long"]),
        case("select mpc observer gain 2", &["select", "--tools", "2", "--task", "position", "--mpc", "--observer-gain", "2"], 2, &["--observer-gain: 2"]),
        case("select zero precisions", &["select", "--tools", "2", "--task-file", "zero.toml"], 2, &["zero.toml", "key precision", "cannot be positive definite"])
            .file("zero.toml", "kind = \"acceleration\"\n[precision]\ntheta_ddot = 0.0\nu = 0.0\n"),
        case("rank zero precisions", &["rank", "--tools", d, "--task", "zero.toml"], 2, &["zero.toml", "key precision"])
            .file("zero.toml", "kind = \"velocity\"\n[precision]\ntheta_dot = 0.0\ntheta_ddot = 0.0\nu = 0.0\n"),
        case("design zero precisions", &["design", "--task", "zero.toml", "--design", design], 2, &["zero.toml", "key precision"])
            .file("zero.toml", "kind = \"acceleration\"\n[precision]\ntheta_ddot = 0.0\nu = 0.0\n"),
        case("every tool of select fails", &["select", "--tools", "2", "--task-file", "wild.toml"], 1, &["every one of the 2 tools failed"])
            .file("wild.toml", WILD),
        case("every tool of rank fails", &["rank", "--tools", "three.csv", "--task", "wild.toml"], 1, &["every one of the 3 simulated tools failed"])
            .file("wild.toml", WILD)
            .file("three.csv", THREE),
        case("a simulation fails", &["simulate", "--arm", "0.3,0.4,0.25,0.2", "--task-file", "wild.toml"], 1, &["diverged at t = 0.01 s"])
            .file("wild.toml", WILD),
    ]
}

/// Output files: folders, links, devices, an output that is an input.
#[rustfmt::skip]
fn output_files(f: &Fixtures) -> Vec<Case> {
    let d = f.drawer.as_str();
    let design = f.design.as_str();
    vec![
        // 5. Output files.
        case("--csv a folder", &["simulate", "--arm", ARM, "--task", "position", "--csv", "out"], 2, &["--csv out: is a folder, not a file"]),
        case("rank --csv a folder", &["rank", "--tools", d, "--task", "position", "--csv", "out"], 2, &["is a folder"]),
        case("--csv a missing folder", &["simulate", "--arm", ARM, "--task", "position", "--csv", "no/such.csv"], 2, &["its folder no"]),
        case("--csv a link", &["simulate", "--arm", ARM, "--task", "position", "--csv", "link.csv"], 0, &[]),
        case("--csv a dangling link", &["simulate", "--arm", ARM, "--task", "position", "--csv", "dangling.csv"], 2, &["--csv dangling.csv: a link to nothing: dangling.csv -> missing.csv"]),
        case("--report a dangling link", &["rank", "--tools", d, "--task", "position", "--report", "dangling.csv"], 2, &["--report dangling.csv: a link to nothing: dangling.csv -> missing.csv"]),
        case("--out a dangling link", &["reproduce", "--quick", "--out", "dangling.csv"], 2, &["a link to nothing"]),
        // An output that is an input, or another output: refused before any work, the input
        // as it was (every file a case gives is checked afterwards).
        case("rank --csv the --tools file", &["rank", "--tools", "three.csv", "--task", "position", "--csv", "three.csv"], 2, &["--csv three.csv is the same file as --tools three.csv"])
            .file("three.csv", THREE),
        case("rank --csv the --task file", &["rank", "--tools", "three.csv", "--task", "task.toml", "--csv", "./task.toml"], 2, &["--csv ./task.toml", "--task task.toml"])
            .file("three.csv", THREE)
            .file("task.toml", "kind = \"position\"\n"),
        case("rank --csv a link to the --tools file", &["rank", "--tools", "target.csv", "--task", "position", "--csv", "link.csv"], 2, &["--csv link.csv is the same file as --tools target.csv"]),
        case("rank --report over the --tools file", &["rank", "--tools", "out/report.md", "--task", "position", "--report", "out"], 2, &["--report out (its report.md) is the same file as --tools out/report.md"])
            .file("out/report.md", THREE),
        case("simulate --csv the --task-file", &["simulate", "--arm", ARM, "--task-file", "g.toml", "--csv", "g.toml"], 2, &["--csv g.toml is the same file as --task-file g.toml"])
            .file("g.toml", "kind = \"position\"\n"),
        case("design --report over the --design file", &["design", "--task", "velocity", "--design", "report.md", "--report", "."], 2, &["--report . (its report.md) is the same file as --design report.md"])
            .file("report.md", THIN),
        case("rank --csv X --report X", &["rank", "--tools", d, "--task", "position", "--csv", "x", "--report", "x"], 2, &["--csv x and --report x are the same file"])
            .absent("x"),
        case("rank --csv into its own report", &["rank", "--tools", d, "--task", "position", "--csv", "out/report.html", "--report", "out"], 2, &["--csv out/report.html and --report out (its report.html)"])
            .absent("out/report.html"),
        case("reproduce two outputs through a link", &["reproduce", "--quick", "--only", "fig2", "--out", "out"], 2, &["--out out (its fig2_confidence_vs_error.csv) and --out out (its report.md)"])
            .file("out/report.md", "my notes\n")
            .link("out/fig2_confidence_vs_error.csv", "report.md"),
        // A link among reproduce's outputs is the user's: written through, never removed.
        case("reproduce into a link to /dev/null", &["reproduce", "--quick", "--only", "fig2", "--out", "out"], 0, &[])
            .link("out/fig2_confidence_vs_error.csv", "/dev/null"),
        case("--csv /dev/full", &["simulate", "--arm", ARM, "--task", "position", "--csv", "/dev/full"], 1, &["/dev/full", "No space left"]),
        case("rank --csv /dev/full", &["rank", "--tools", d, "--task", "position", "--screen", "1", "--csv", "/dev/full"], 1, &["No space left"]),
        case("--csv /dev/null", &["simulate", "--arm", ARM, "--task", "position", "--csv", "/dev/null"], 0, &[]),
        case("--out a file", &["reproduce", "--quick", "--out", "file.txt"], 2, &["--out file.txt: is a file, not a folder"]).file("file.txt", ""),
        case("--report a file", &["rank", "--tools", d, "--task", "position", "--report", "file.txt"], 2, &["is a file, not a folder"]).file("file.txt", ""),
        case("design --report a file", &["design", "--task", "velocity", "--design", design, "--report", "file.txt"], 2, &["is a file, not a folder"]).file("file.txt", ""),
    ]
}

/// `design`, and the messages of bad input.
#[rustfmt::skip]
fn design_and_messages(f: &Fixtures) -> Vec<Case> {
    let d = f.drawer.as_str();
    let design = f.design.as_str();
    vec![
        // 6. design.
        case("design, a thin feasible set", &["design", "--task", "velocity", "--design", "thin.toml", "--json"], 0, &[])
            .file("thin.toml", THIN),
        case("design, bounds [1e-9, 1e9]", &["design", "--task", "velocity", "--design", "wider.toml"], 2, &["wider.toml, key bounds.l1", "[1e-9, 1e9]", "goes outside"])
            .file("wider.toml", WIDE.replace("1e-6", "1e-9").replace("1e6", "1e9")),
        case("design, huge coefficient", &["design", "--task", "velocity", "--design", "huge.toml"], 2, &["huge.toml, key constraints[0]", "coefficient of m1"])
            .file("huge.toml", format!("constraints = [\"1e300 m1 + l1 <= 1e300\"]\n{}", &WIDE[WIDE.find("[bounds]").unwrap()..])),
        case("design, a sweep out of range", &["design", "--task", "velocity", "--design", design, "--sweep", "m1 + m2 <= 1e20..1e21:3"], 2, &["--sweep", "constant side"]),
        // 7. Messages.
        case("dt 5e-324", &["simulate", "--arm", ARM, "--task", "position", "--dt", "5e-324"], 2, &["--dt: 5e-324 must be"]),
        case("mpc period 1e-9", &["simulate", "--arm", ARM, "--task", "position", "--controller", "mpc", "--mpc-period", "1e-9"], 2, &["--mpc-period: 1e-9"]),
        case("select --tools -1", &["select", "--tools", "-1", "--task", "position"], 2, &["'--tools <TOOLS>'"]),
        case("rank --screen -1", &["rank", "--tools", d, "--task", "position", "--screen", "-1"], 2, &["'--screen <SCREEN>'"]),
        case("a 10 MB header cell", &["rank", "--tools", "cell.csv", "--task", "position"], 2, &["cell.csv, line 1", "row longer than"])
            .file("cell.csv", format!("{},m1\n", "h".repeat(10 << 20))),
        case("a 500 kB header cell", &["rank", "--tools", "cell.csv", "--task", "position"], 2, &["cell.csv, line 1 (header)", "unknown column", "(500000 characters)"])
            .file("cell.csv", format!("{},m1\n", "h".repeat(500_000))),
        case("an unterminated quote", &["rank", "--tools", "quote.csv", "--task", "position"], 2, &["quote.csv, line 3", "never closed"])
            .file("quote.csv", "name,m1,m2,l1,l2\nok,0.3,0.4,0.5,0.2\n\"open,0.3,0.4,0.5,0.2\nnext,0.3,0.4,0.5,0.2\n"),
        case("a JSON key twice", &["rank", "--tools", "twice.json", "--task", "position"], 2, &["twice.json, tool 1", "key 'm1' appears twice"])
            .file("twice.json", "[{\"m1\": 0.3, \"m1\": 0.9, \"m2\": 0.4, \"l1\": 0.5, \"l2\": 0.2}]"),
        case("a folder as tools file", &["rank", "--tools", "out", "--task", "position"], 2, &["out: is a folder, not a tools file"]),
        case("a task file under a file", &["rank", "--tools", d, "--task", "file.txt/task.toml"], 2, &["cannot read the task file", "Not a directory"]).file("file.txt", ""),
        case("rtol = atol = 1e10", &["simulate", "--arm", ARM, "--task", "position", "--rtol", "1e10", "--atol", "1e10"], 2, &["--rtol: 1e10 must be a number in [1e-12, 0.1]"]),
        case("task file rtol 1e10", &["simulate", "--arm", ARM, "--task-file", "tol.toml"], 2, &["tol.toml, key episode.rtol"])
            .file("tol.toml", "kind = \"position\"\n[episode]\nrtol = 1e10\natol = 1e10\n"),
        case("an unknown flag", &["simulate", "--arm", ARM, "--task", "position", "--torque", "3"], 2, &["unexpected argument '--torque'"]),
        case("an unknown task", &["select", "--task", "sideways"], 2, &["unknown task 'sideways'"]),
        case("a long bad --arm", &["confidence", "--arm", &"9,".repeat(50_000), "--task", "position"], 2, &["invalid value '9,9,", "…"]),
    ]
}

/// The evaluation on a model, and the thread count.
#[rustfmt::skip]
fn evaluation_and_threads(f: &Fixtures) -> Vec<Case> {
    let panda_tools = f.panda_tools.as_str();
    let panda_touch = f.panda_touch.as_str();
    vec![
        // 9. The evaluation on a model (reproduce --model): bad input is one line naming the
        // flag or key, before any episode.
        case("reproduce, an unknown model", &["reproduce", "--model", "kuka", "--task", "tip_position", "--out", "out"], 2, &["unknown model 'kuka'"]),
        case("reproduce, a task of another model", &["reproduce", "--model", "ur5", "--task-file", panda_touch, "--sample", "5", "--out", "out"], 2, &["panda_touch_point.toml, key precision.u", "model ur5 has 6 components"]),
        case("reproduce, a population of 0", &["reproduce", "--model", "panda", "--task", "tip_position", "--sample", "0", "--out", "out"], 2, &["--sample 0: no tools"]),
        case("reproduce, a population of 10⁹", &["reproduce", "--model", "panda", "--task", "tip_position", "--sample", "1000000000", "--out", "out"], 2, &["--sample 1000000000", "more than the 1000000"]),
        case("reproduce, a box the model lacks", &["reproduce", "--model", "panda", "--task", "tip_position", "--sample", "5", "--box", "tool_lenght=0.1:0.2", "--out", "out"], 2, &["--box tool_lenght", "no parameter 'tool_lenght'"]),
        case("reproduce, a relative goal on a joint task", &["reproduce", "--model", "panda", "--task-file", "joint.toml", "--sample", "5", "--out", "out"], 2, &["joint.toml, key goal.tip_offset", "a position task has no such goal"])
            .file("joint.toml", "kind = \"position\"\n[goal]\ntip_offset = [0.05, 0.0, 0.0]\n"),
        case("reproduce, --task without --model", &["reproduce", "--task", "tip_position", "--out", "out"], 2, &["--task is for an evaluation on a model"]),
        case("reproduce, --only with --model", &["reproduce", "--model", "panda", "--task", "tip_position", "--only", "fig2", "--out", "out"], 2, &["'--model <MODEL>' cannot be used with '--only <ONLY>'"]),
        case("reproduce, trials of one tool", &["reproduce", "--model", "panda", "--task", "tip_position", "--trial-tools", "1", "--out", "out"], 2, &["--trial-tools: 1 must be a count in [2, 100000]"]),
        case("reproduce, a tools file of another model", &["reproduce", "--model", "ur5", "--task", "tip_position", "--tools", panda_tools, "--out", "out"], 2, &["panda_tools.csv, tool 1", "a panda tool, but the evaluation is of model ur5"]),
        case("reproduce, a zero ΔT", &["reproduce", "--model", "panda", "--task-file", "still.toml", "--sample", "5", "--out", "out"], 2, &["still.toml, key episode.perturbation", "ΔT is 0 on every joint"])
            .file("still.toml", "kind = \"tip_position\"\n[goal]\ntip_offset = [0.05, 0.0, 0.0]\n[episode]\nperturbation = 0.0\n"),
        // 8. Threads.
        case("RAYON_NUM_THREADS=5000", &["select", "--tools", "3", "--task", "velocity", "--json"], 0, &[])
            .env("RAYON_NUM_THREADS", "5000"),
    ]
}

/// Torques at the edge of their range throw every arm past the divergence bound at t = 0.01 s.
const WILD: &str =
    "kind = \"position\"\n[episode]\nperturbation = 1e6\ninitial_torque = 1e6\nt_end = 0.01\ndt = 0.01\n";
const THREE: &str = "name,m1,m2,l1,l2\nshort hammer,0.30,0.40,0.25,0.20\nlong hammer,0.30,0.40,0.55,0.45\nmallet,0.25,0.60,0.40,0.15\n";
const THIN: &str = "constraints = [\"m1 + m2 <= 0.2000001\", \"m1 + m2 >= 0.2\", \"l1 - l2 <= 0.0000001\", \"l1 - l2 >= 0\"]\n[bounds]\nm1 = [0.1, 0.6]\nm2 = [0.1, 0.6]\nl1 = [0.1, 0.6]\nl2 = [0.1, 0.6]\n[search]\nsamples = 1000\n";
const WIDE: &str =
    "[bounds]\nl1 = [1e-6, 1e6]\nl2 = [1e-6, 1e6]\nm1 = [1e-6, 1e6]\nm2 = [1e-6, 1e6]\n\
                    [search]\nstarts = 2\nsamples = 100\nsimulate = 1\n";

/// Runs a case in `dir` under a 2 GB address-space limit (an allocation beyond it aborts).
fn run(c: &Case, dir: &Path) -> Output {
    let mut cmd = Command::new(binary());
    cmd.args(&c.args).current_dir(dir).stdin(Stdio::null());
    cmd.stdout(match c.stdout {
        Sink::Captured => Stdio::piped(),
        Sink::Full => Stdio::from(std::fs::File::create("/dev/full").expect("/dev/full")),
    });
    cmd.stderr(Stdio::piped());
    for (k, v) in &c.env {
        cmd.env(k, v);
    }
    common::limit_memory(&mut cmd)
        .output()
        .expect("run toolconf")
}

/// The paths under `dir` whose names mark a temporary file.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.contains(".partial") || name.contains(".tmp") {
            found.push(name);
        }
        if entry.file_type().unwrap().is_dir() {
            found.extend(leftovers(&entry.path()));
        }
    }
    found
}

/// Nulls are names, a task file not given, a screen not asked for, or a choice nobody won.
fn no_null_numbers(v: &Value, key: &str) -> Result<(), String> {
    match v {
        Value::Null if ["name", "task_file", "screen"].contains(&key) => Ok(()),
        Value::Null => Err(format!("null at key {key}")),
        Value::Number(n) if !n.as_f64().is_some_and(f64::is_finite) => Err(format!("{n} at {key}")),
        Value::Array(a) => a.iter().try_for_each(|x| no_null_numbers(x, key)),
        Value::Object(o) => o.iter().try_for_each(|(k, x)| {
            if key == "choice" && x.is_null() {
                Ok(())
            } else {
                no_null_numbers(x, k)
            }
        }),
        _ => Ok(()),
    }
}

fn check(c: &Case, dir: &Path, out: &Output) -> Result<(), String> {
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let status = out
        .status
        .code()
        .ok_or_else(|| format!("ended by a signal: {:?}; stderr {stderr}", out.status))?;
    if stderr.contains("panicked") {
        return Err(format!("panicked: {stderr}"));
    }
    if status != c.status {
        return Err(format!(
            "status {status}, not {}; stderr: {}",
            c.status,
            stderr.chars().take(500).collect::<String>()
        ));
    }
    if status != 0 {
        one_error_line(c, &stderr)?;
    }
    for word in stdout.split(|ch: char| !ch.is_alphanumeric()) {
        if ["NaN", "nan", "inf", "Infinity"].contains(&word) {
            return Err(format!("{word} on stdout"));
        }
    }
    if c.args.iter().any(|a| a == "--json") && status == 0 {
        let v: Value =
            serde_json::from_str(&stdout).map_err(|e| format!("stdout is not JSON: {e}"))?;
        no_null_numbers(&v, "")?;
    }
    files_unharmed(c, dir)
}

/// A failure's stderr: one line, `toolconf: error: `, not too long, holding the case's words.
fn one_error_line(c: &Case, stderr: &str) -> Result<(), String> {
    let lines: Vec<&str> = stderr.lines().collect();
    if lines.len() != 1 || !lines[0].starts_with("toolconf: error: ") {
        return Err(format!("stderr is not one error line: {stderr:?}"));
    }
    if lines[0].chars().count() > 700 {
        return Err(format!(
            "an error line of {} characters",
            lines[0].chars().count()
        ));
    }
    for fragment in &c.says {
        if !lines[0].contains(fragment) {
            return Err(format!("stderr lacks {fragment:?}: {}", lines[0]));
        }
    }
    Ok(())
}

/// The case's files as they were, its links links, nothing created that should not be, no
/// temporary file left, and the devices still devices.
fn files_unharmed(c: &Case, dir: &Path) -> Result<(), String> {
    for (name, text) in &c.files {
        if std::fs::read(dir.join(name)).ok().as_ref() != Some(text) {
            return Err(format!("{name} changed"));
        }
    }
    for (name, _) in &c.links {
        if !std::fs::symlink_metadata(dir.join(name)).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(format!("{name} is no longer a symbolic link"));
        }
    }
    for name in &c.absent {
        if std::fs::symlink_metadata(dir.join(name)).is_ok() {
            return Err(format!("{name} was created"));
        }
    }
    let left = leftovers(dir);
    if !left.is_empty() {
        return Err(format!("temporary files left: {left:?}"));
    }
    if !std::fs::symlink_metadata(dir.join("link.csv"))
        .unwrap()
        .file_type()
        .is_symlink()
    {
        return Err("link.csv is no longer a symbolic link".into());
    }
    if !std::fs::metadata("/dev/full")
        .unwrap()
        .file_type()
        .is_char_device()
        || !std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    {
        return Err("a device is no longer a device".into());
    }
    Ok(())
}

#[test]
fn hostile_inputs_end_in_their_status_with_one_line_and_harm_nothing() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hostile");
    let _ = std::fs::remove_dir_all(&root);
    let mut failures = Vec::new();
    let cases = cases();
    for (i, c) in cases.iter().enumerate() {
        let dir = root.join(format!("case{i:02}"));
        std::fs::create_dir_all(dir.join("out")).unwrap();
        std::fs::write(dir.join("target.csv"), "old\n").unwrap();
        std::os::unix::fs::symlink("target.csv", dir.join("link.csv")).unwrap();
        std::os::unix::fs::symlink("missing.csv", dir.join("dangling.csv")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", dir.join("zero.json")).unwrap();
        for (name, text) in &c.files {
            std::fs::write(dir.join(name), text).unwrap();
        }
        for (name, target) in &c.links {
            std::os::unix::fs::symlink(target, dir.join(name)).unwrap();
        }
        let started = Instant::now();
        let out = run(c, &dir);
        let took = started.elapsed();
        if std::env::var_os("TOOLCONF_HOSTILE_TIMES").is_some() {
            eprintln!("{took:>10.3?}  {}", c.name);
        }
        if let Err(why) = check(c, &dir, &out) {
            failures.push(format!("{}: {why}", c.name));
        }
        if took > Duration::from_secs(60) {
            failures.push(format!("{}: took {took:?}", c.name));
        }
    }
    // Writing through the link replaced the target's contents, not the link.
    let linked = cases.iter().position(|c| c.name == "--csv a link").unwrap();
    let target = std::fs::read_to_string(root.join(format!("case{linked:02}/target.csv"))).unwrap();
    assert!(target.starts_with("t,"), "{target}");
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
