//! Fuzzing every parser of user input (property-based, on stable Rust with proptest): tools
//! files (CSV and JSON), task files, design files, design constraints and sweeps, `--arm`, and a
//! tool's URDF (`toolconf tool --urdf`, with its links, joints and positions).
//!
//! Each input is a valid example mutated by random edits (characters and tokens that matter to
//! the format: quotes, separators, brackets, `nan`, `1e308`, keys, long runs), or random text.
//! Every parser must return, without a panic, either a value that passes the same checks again
//! (parameters in range, finite numbers) or one error line naming the file (and the line, tool
//! or key where there is one), at most a few hundred characters whatever the input.
//!
//! Cases per parser: 256, or `TOOLCONF_FUZZ_CASES` (the long run, docs/reference/errors.md:
//! `TOOLCONF_FUZZ_CASES=100000 cargo test --release --test fuzz_parsers`).

use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence};
use toolconf::design::polytope::Polytope;
use toolconf::design::sweep::parse_sweep;
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::design_file::constraint::parse_constraint;
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::inputs::tools_file::read_tools_from;
use toolconf_model::registry::ModelKind;
use toolconf_model::validate::TOOL_PARAMETER;
use toolconf_tool_urdf::{check_rigid_body, tool_from_urdf, Request};

/// The longest error line any input may give (values it repeats are clipped).
const MAX_MESSAGE: usize = 600;

fn config() -> Config {
    let cases = std::env::var("TOOLCONF_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256);
    Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..Config::default()
    }
}

/// What the edits insert: the characters and words each format turns on.
const TOKENS: &[&str] = &[
    "\"",
    "'",
    ",",
    "\n",
    "\r\n",
    "[",
    "]",
    "{",
    "}",
    "=",
    ":",
    ".",
    "-",
    "+",
    "*",
    "/",
    "#",
    "\\",
    " ",
    "\t",
    "\0",
    "é",
    "Π",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "1e-308",
    "5e-324",
    "-0",
    "0",
    "1e6",
    "1e-6",
    "0.3",
    "-1",
    "99999999999999999999",
    "true",
    "null",
    "[]",
    "{}",
    "[[1.0, 0.0], [0.0, 1.0]]",
    "<=",
    ">=",
    "==",
    "..",
    "m1",
    "m2",
    "l1",
    "l2",
    "l3",
    "mp",
    "name",
    "model",
    "arm3",
    "msd",
    "kind",
    "goal",
    "precision",
    "episode",
    "bounds",
    "fixed",
    "search",
    "theta",
    "theta_dot",
    "u",
    "t_end",
    "dt",
    "rtol",
    "samples",
    "[episode]",
    "[bounds]",
    "\"\"\"",
];

#[derive(Debug, Clone)]
enum Edit {
    Insert(f64, usize),
    Delete(f64, usize),
    Replace(f64, usize, usize),
    /// A long run of one token (a 100 kB cell, a deep nesting).
    Repeat(f64, usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let at = 0.0..1.0f64;
    let token = 0..TOKENS.len();
    prop_oneof![
        4 => (at.clone(), token.clone()).prop_map(|(a, t)| Edit::Insert(a, t)),
        2 => (at.clone(), 1..8usize).prop_map(|(a, n)| Edit::Delete(a, n)),
        3 => (at.clone(), 1..6usize, token.clone()).prop_map(|(a, n, t)| Edit::Replace(a, n, t)),
        1 => (at, token, 1..20_000usize).prop_map(|(a, t, n)| Edit::Repeat(a, t, n)),
    ]
}

fn apply(base: &str, edits: &[Edit]) -> String {
    let mut chars: Vec<char> = base.chars().collect();
    for e in edits {
        let at = |f: f64, len: usize| ((f * (len + 1) as f64) as usize).min(len);
        match *e {
            Edit::Insert(f, t) => {
                let i = at(f, chars.len());
                chars.splice(i..i, TOKENS[t].chars());
            }
            Edit::Delete(f, n) => {
                let i = at(f, chars.len());
                chars.drain(i..(i + n).min(chars.len()));
            }
            Edit::Replace(f, n, t) => {
                let i = at(f, chars.len());
                chars.splice(i..(i + n).min(chars.len()), TOKENS[t].chars());
            }
            Edit::Repeat(f, t, n) => {
                let i = at(f, chars.len());
                let run: String = TOKENS[t].repeat(n);
                chars.splice(i..i, run.chars());
            }
        }
    }
    chars.into_iter().collect()
}

/// A valid example with 0–6 edits, or random text.
fn mutated(bases: &'static [&'static str]) -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (0..bases.len(), prop::collection::vec(edit(), 0..6))
            .prop_map(move |(b, edits)| apply(bases[b], &edits)),
        1 => "\\PC{0,200}",
        1 => prop::collection::vec(any::<u8>(), 0..300)
            .prop_map(|b| String::from_utf8_lossy(&b).into_owned()),
    ]
}

/// One line, not too long, naming `file` first.
fn one_line(message: &str, file: &str) -> Result<(), TestCaseError> {
    prop_assert!(
        !message.contains('\n') && !message.contains('\r'),
        "{message:?}"
    );
    prop_assert!(
        message.chars().count() <= MAX_MESSAGE,
        "{} chars",
        message.len()
    );
    prop_assert!(
        message.starts_with(file),
        "{message:?} does not name {file}"
    );
    Ok(())
}

const CSV: &[&str] = &[
    "name,model,m1,m2,l1,l2\nshort hammer,arm2,0.30,0.40,0.25,0.20\n\"rod, exact\",arm2_exact,0.3,0.3,0.4,0.4\n",
    "m1,m2,l1,l2,m3,l3,model\n0.3,0.3,0.2,0.3,0.3,0.2,arm3\n0.1,0.1,0.1,0.1,,,\n",
    "name,model,m,k,c\nspring,msd,1,2,0.5\n",
];

const JSON: &[&str] = &[
    r#"[{"name": "hammer", "model": "arm2", "m1": 0.3, "m2": 0.4, "l1": 0.5, "l2": 0.2}]"#,
    r#"[{"model": "arm3", "m1": 0.3, "m2": 0.3, "m3": 0.2, "l1": 0.3, "l2": 0.3, "l3": 0.2},
        {"name": "pay", "model": "arm2_payload", "m1": 0.3, "m2": 0.4, "l1": 0.5, "l2": 0.2, "mp": 0.1}]"#,
];

fn check_tools(text: &str, is_json: bool) -> Result<(), TestCaseError> {
    let file = if is_json { "fuzz.json" } else { "fuzz.csv" };
    let (mut rows, mut skipped) = (Vec::new(), Vec::new());
    let result = read_tools_from(text.as_bytes(), file, is_json, |row| match row {
        Ok(row) => {
            rows.push(row);
            Ok(())
        }
        // Skipped, as --skip-bad-rows does, to reach the rest of the file.
        Err(e) if e.row_level => {
            skipped.push(e);
            Ok(())
        }
        Err(e) => Err(e),
    });
    if let Err(e) = result {
        one_line(&e.to_string(), file)?;
    }
    for e in skipped {
        one_line(&e.to_string(), file)?;
        prop_assert!(
            e.place.starts_with("line ") || e.place.starts_with("tool "),
            "{e}"
        );
    }
    for row in rows {
        for (name, v) in row.tool.named_parameters() {
            prop_assert!(TOOL_PARAMETER.contains(v), "{name} = {v} accepted");
        }
    }
    Ok(())
}

const TASKS: &[&str] = &[
    "kind = \"position\"\ndescription = \"reach 45°\"\n[goal]\ntheta = [0.785, 0.0]\n[precision]\ntheta = [[120.0, 20.0], [20.0, 60.0]]\ntheta_dot = 50.0\nu = 1.0\n[episode]\nt_end = 5.0\ndt = 0.05\nperturbation = [0.3, -0.2]\ninitial_torque = 0.1\nlearning_rate = 1.0\nrtol = 1e-3\natol = 1e-6\n",
    "kind = \"velocity\"\n[goal]\ntheta_dot = [0.0, 2.0, 1.0]\n[precision]\ntheta_ddot = 1.0\n[episode]\ninitial_theta = [-1.5, -1.5, -1.5]\n",
    "kind = \"acceleration\"\n[precision]\ntheta_ddot = 10.0\nu = 0.0\n",
];

fn check_task(text: &str) -> Result<(), TestCaseError> {
    match TaskSpec::parse(text, "fuzz.toml") {
        Err(e) => one_line(&e.to_string(), "fuzz.toml"),
        Ok(spec) => {
            // Every model binds the task or says why, naming the file and key.
            let tasks = ModelTasks::new(&spec);
            for model in ModelKind::all() {
                if let Err(e) = tasks.check(model) {
                    one_line(&e.to_string(), "fuzz.toml")?;
                    prop_assert!(e.place.starts_with("key "), "{e}");
                }
            }
            prop_assert!(spec.episode.check().is_ok());
            Ok(())
        }
    }
}

const DESIGNS: &[&str] = &[
    "objective = \"confidence\"\nconstraints = [\"l1 + l2 >= 0.7\", \"m1 + m2 <= 0.5\"]\n[bounds]\nm1 = [0.1, 0.6]\nm2 = [0.1, 0.6]\nl1 = [0.1, 0.6]\nl2 = [0.1, 0.6]\n[search]\nseed = 3\nstarts = 2\nsamples = 10\nsimulate = 1\nperturbation = -0.8\n",
    "constraints = [\"2*m1 - m2 <= 0.1\", \"0.5 l1 >= l2 - 0.1\"]\n[bounds]\nm1 = [1e-6, 1e6]\nm2 = [0.1, 0.6]\nl1 = [0.1, 0.6]\n[fixed]\nl2 = 0.3\n",
];

const NAMES: &[&str] = &["m1", "m2", "l1", "l2"];

fn check_design(text: &str) -> Result<(), TestCaseError> {
    match DesignSpec::parse(text, "fuzz.toml", ModelKind::Arm2) {
        Err(e) => one_line(&e.to_string(), "fuzz.toml"),
        Ok(spec) => {
            for &(lo, hi) in &spec.bounds {
                prop_assert!(TOOL_PARAMETER.contains(lo) && TOOL_PARAMETER.contains(hi));
            }
            // The feasible set's centre is an LP for Clarabel: a point, or a one-line reason.
            let polytope = Polytope::new(&spec);
            if let Err(e) = polytope.centre(&spec.file) {
                one_line(&e.to_string(), "fuzz.toml")?;
            }
            Ok(())
        }
    }
}

const CONSTRAINTS: &[&str] = &[
    "l1 + l2 >= 0.7",
    "2*m1 - m2 <= 0.1",
    "0.5 l1 >= l2 - 0.1",
    "m1 / 4 + 3 * l2 - 1e-3 <= m2",
];

fn check_constraint(text: &str) -> Result<(), TestCaseError> {
    match parse_constraint(text, NAMES) {
        Ok(c) => {
            prop_assert!(c.coefficients.iter().all(|v| v.is_finite()));
            prop_assert!(c.bound.is_finite());
        }
        Err(m) => {
            prop_assert!(
                !m.contains('\n') && m.chars().count() <= MAX_MESSAGE,
                "{m:?}"
            )
        }
    }
    let sweep = format!("{text}..2:3");
    if let Err(m) = parse_sweep(&sweep, NAMES) {
        prop_assert!(m.starts_with("--sweep '") && !m.contains('\n'), "{m:?}");
        prop_assert!(m.chars().count() <= MAX_MESSAGE, "{} chars", m.len());
    }
    Ok(())
}

const ARMS: &[&str] = &["0.3,0.4,0.5,0.2", "1e-6,1e6,0.1,0.1"];

/// The bounded reader's CSV rows against the csv crate's: cells of any text (quotes, commas,
/// line breaks) written by `csv::Writer` are read back whole through the limit, every row ends
/// where the writer ended it, and no quote is left open; the same file cut inside a quoted cell
/// is "never closed".
fn check_csv_rows(cells: &[Vec<String>]) -> Result<(), TestCaseError> {
    use std::io::Read;
    use toolconf_model::inputs::bounded_read::{record_error, CsvRows, RecordLimit};
    let mut writer = csv::WriterBuilder::new()
        .flexible(true)
        .from_writer(Vec::new());
    for row in cells {
        writer.write_record(row).unwrap();
    }
    let bytes = writer.into_inner().unwrap();
    let mut read = Vec::new();
    let mut limited = RecordLimit::new(&bytes[..], CsvRows::default());
    prop_assert!(limited.read_to_end(&mut read).is_ok());
    prop_assert_eq!(&read, &bytes);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(RecordLimit::new(&bytes[..], CsvRows::default()));
    let back: Vec<Vec<String>> = reader
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect();
    prop_assert_eq!(&back[..], cells);
    // The writer's first quote opens a cell: cut just after it, the file ends inside that cell.
    if let Some(at) = bytes.iter().position(|&b| b == b'"') {
        let e = RecordLimit::new(&bytes[..=at], CsvRows::default())
            .read_to_end(&mut Vec::new())
            .unwrap_err();
        prop_assert!(record_error(&e).is_some_and(|(_, m)| m.contains("never closed")));
    }
    Ok(())
}

/// A gripper on a flange: a turned fixed joint, an inertial turned in its link, a prismatic
/// finger, a revolute one that mimics it, a continuous wrist, a massless tip.
const GRIPPER: &str = r#"<?xml version="1.0"?>
<robot name="gripper">
  <link name="panda_link8"/>
  <link name="panda_hand">
    <inertial><origin xyz="-0.01 0 0.03" rpy="0.1 -0.2 0.3"/><mass value="0.73"/>
      <inertia ixx="0.001" ixy="1e-5" ixz="-2e-5" iyy="0.0025" iyz="0" izz="0.0017"/></inertial>
  </link>
  <link name="panda_hand_tcp"/>
  <link name="finger_a"><inertial><mass value="0.015"/><inertia ixx="2.4e-6" iyy="2.4e-6" izz="7.5e-7" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_b"><inertial><origin xyz="0 0.01 0.02"/><mass value="0.015"/><inertia ixx="2.4e-6" iyy="2.4e-6" izz="7.5e-7" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="spinner"><inertial><mass value="0.1"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="panda_hand_joint" type="fixed"><parent link="panda_link8"/><child link="panda_hand"/><origin rpy="0 0 -0.7853981633974483" xyz="0 0 0"/></joint>
  <joint name="tcp" type="fixed"><parent link="panda_hand"/><child link="panda_hand_tcp"/><origin xyz="0 0 0.1034"/></joint>
  <joint name="slide" type="prismatic"><parent link="panda_hand"/><child link="finger_a"/><origin xyz="0 0 0.0584"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>
  <joint name="hinge" type="revolute"><parent link="panda_hand"/><child link="finger_b"/><origin xyz="0 0 0.0584" rpy="0 1.5 0"/><axis xyz="1 1 0"/><limit lower="-1" upper="1"/><mimic joint="slide" multiplier="-10" offset="0.1"/></joint>
  <joint name="wrist" type="continuous"><parent link="panda_hand"/><child link="spinner"/><axis xyz="0 0 1"/></joint>
</robot>
"#;

const URDFS: &[&str] = &[
    GRIPPER,
    include_str!("../derive/robots/panda_description/urdf/panda.urdf"),
];

/// What URDF edits insert besides the common tokens: XML's and URDF's own words.
const URDF_TOKENS: &[&str] = &[
    "<",
    ">",
    "/>",
    "</",
    "<!--",
    "-->",
    "&amp;",
    "&#0;",
    "&bogus;",
    "<![CDATA[",
    "<!DOCTYPE r>",
    "<?xml",
    "xmlns=\"u\"",
    "<link name=\"panda_hand\"/>",
    "<link/>",
    "</link>",
    "<joint",
    "</joint>",
    "<inertial>",
    "</inertial>",
    "<origin xyz=\"0 0 0\"/>",
    "<mass value=\"1\"/>",
    "<mimic joint=\"slide\"/>",
    "<mimic joint=\"hinge\"/>",
    "<limit/>",
    "<axis xyz=\"0 0 0\"/>",
    "type=\"floating\"",
    "type=\"fixed\"",
    "type=\"prismatic\"",
    "<parent link=\"panda_hand_tcp\"/>",
    "<child link=\"panda_hand\"/>",
    "xyz=\"",
    "rpy=\"",
    "ixx=\"",
    "value=\"",
    " 1e308",
    " 1e-320",
    " -0.73",
    " 0 0",
    "\"",
    "panda_hand",
    "panda_link8",
    "panda_finger_joint1",
];

/// A URDF with the common edits, then up to 6 of XML's and URDF's tokens inserted.
fn urdf_text() -> impl Strategy<Value = String> {
    (
        mutated(URDFS),
        prop::collection::vec((0.0..1.0f64, 0..URDF_TOKENS.len()), 0..6),
    )
        .prop_map(|(mut text, inserts)| {
            for (at, t) in inserts {
                let mut i = ((at * (text.len() + 1) as f64) as usize).min(text.len());
                while !text.is_char_boundary(i) {
                    i -= 1;
                }
                text.insert_str(i, URDF_TOKENS[t]);
            }
            text
        })
}

/// The Franka Hand's request (the gripper's names are the hand's), or one of other links, a
/// flange, openings and named positions drawn from the words above.
fn urdf_request() -> impl Strategy<Value = Request> {
    let names = prop::sample::select(vec![
        "panda_link8",
        "panda_hand",
        "panda_hand_tcp",
        "finger_a",
        "panda_leftfinger",
        "slide",
        "hinge",
        "wrist",
        "panda_finger_joint1",
        "panda_finger_joint2",
        "panda_link7",
        "",
        "é\n",
    ]);
    let value = prop_oneof![
        Just(0.0),
        Just(0.02),
        Just(0.04),
        Just(-1.0),
        Just(1e308),
        Just(f64::NAN),
        -2.0..2.0f64,
    ];
    let hand = Request {
        root: "panda_hand".into(),
        tip: "panda_hand_tcp".into(),
        flange: Some("panda_link8".into()),
        opening: Some(0.02),
        joints: vec![("wrist".into(), 1.0)],
    };
    prop_oneof![
        3 => Just(hand),
        1 => (
            names.clone(),
            names.clone(),
            prop::option::of(names.clone()),
            prop::option::of(value.clone()),
            prop::collection::vec((names, value), 0..3),
        )
            .prop_map(|(root, tip, flange, opening, joints)| Request {
                root: root.into(),
                tip: tip.into(),
                flange: flange.map(Into::into),
                opening,
                joints: joints.into_iter().map(|(n, v)| (n.to_string(), v)).collect(),
            }),
    ]
}

/// A merged tool passes its own checks again and prints as three lines with finite numbers; an
/// error is one line naming the file.
fn check_urdf(text: &str, request: &Request) -> Result<(), TestCaseError> {
    match tool_from_urdf(text, "fuzz.urdf", request) {
        Err(e) => one_line(&e.to_string(), "fuzz.urdf"),
        Ok(tool) => {
            prop_assert!(tool.mass > 0.0);
            prop_assert!(tool.values().iter().all(|(_, v)| v.is_finite()), "{tool:?}");
            let i = nalgebra::Matrix3::from_fn(|r, c| tool.inertia[r][c]);
            prop_assert_eq!(i, i.transpose());
            prop_assert!(check_rigid_body(&i).is_ok(), "{tool:?}");
            let file = tool.tools_file("fuzz.urdf", request, &request.root, Some("panda"));
            prop_assert_eq!(file.lines().count(), 3, "{}", file);
            for (column, v) in tool.values() {
                let printed = toolconf_files::csv::format_number(v);
                prop_assert_eq!(printed.parse::<f64>().ok(), Some(v), "{}", column);
                prop_assert!(file.lines().nth(2).unwrap().contains(&printed));
            }
            Ok(())
        }
    }
}

/// The unmutated bases merge, so that the fuzzing starts from tools that pass.
#[test]
fn the_urdf_bases_merge_into_tools() {
    let hand = Request {
        root: "panda_hand".into(),
        tip: "panda_hand_tcp".into(),
        flange: Some("panda_link8".into()),
        opening: Some(0.02),
        joints: vec![],
    };
    let panda = tool_from_urdf(URDFS[1], "panda.urdf", &hand).unwrap();
    assert_eq!(panda.mass, 0.76);
    let gripper = Request {
        joints: vec![("wrist".into(), 1.0)],
        ..hand
    };
    let tool = tool_from_urdf(GRIPPER, "gripper.urdf", &gripper).unwrap();
    assert!((tool.mass - 0.86).abs() < 1e-15);
    assert_eq!(tool.held.len(), 3);
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn tools_csv(text in mutated(CSV)) {
        check_tools(&text, false)?;
    }

    #[test]
    fn tools_json(text in mutated(JSON)) {
        check_tools(&text, true)?;
    }

    #[test]
    fn task_files(text in mutated(TASKS)) {
        check_task(&text)?;
    }

    #[test]
    fn design_files(text in mutated(DESIGNS)) {
        check_design(&text)?;
    }

    #[test]
    fn constraints_and_sweeps(text in mutated(CONSTRAINTS)) {
        check_constraint(&text)?;
    }

    #[test]
    fn csv_rows_end_where_the_csv_crate_ends_them(
        cells in prop::collection::vec(
            prop::collection::vec("[a-c\",\n\r ]{0,6}", 1..4),
            1..6,
        )
    ) {
        check_csv_rows(&cells)?;
    }

    #[test]
    fn arms(text in mutated(ARMS)) {
        match toolconf_model::arm::parse(&text) {
            Ok(arm) => prop_assert!(arm.params().iter().all(|v| TOOL_PARAMETER.contains(*v))),
            Err(e) => {
                let m = e.to_string();
                prop_assert!(!m.contains('\n') && m.chars().count() <= MAX_MESSAGE, "{m:?}");
            }
        }
    }

    #[test]
    fn tool_urdfs(text in urdf_text(), request in urdf_request()) {
        check_urdf(&text, &request)?;
    }
}
