//! `toolconf tool --urdf` as a user runs it: the output parses as CSV with the documented
//! columns and finite numbers; bad input (a bad file, flag, link or joint) is status 2 and one
//! line naming it, never a panic, unbounded memory (each run under a 2 GB address-space limit) or
//! a harmed file. Agreement with Pinocchio is python/tests/test_tool_urdf.py's.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use toolconf_tool_urdf::COLUMNS;

const PANDA: &str = "derive/robots/panda_description/urdf/panda.urdf";

/// The Franka Hand of the URDF `urdf`, its fingers `opening` apart.
fn hand_of<'a>(urdf: &'a str, opening: &'a str) -> [&'a str; 8] {
    let (root, tip) = ("panda_hand", "panda_hand_tcp");
    [
        "--urdf",
        urdf,
        "--root",
        root,
        "--tip",
        tip,
        "--opening",
        opening,
    ]
}

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(path)
        .display()
        .to_string()
}

fn scratch(name: &str) -> PathBuf {
    common::fresh_dir(&format!("tool_urdf/{name}"))
}

/// `toolconf tool ARGS` in `dir`, under a 2 GB address-space limit.
fn tool(dir: &Path, args: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_toolconf"));
    cmd.arg("tool")
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null());
    common::limit_memory(&mut cmd)
        .output()
        .expect("run toolconf")
}

/// The `#` line, then the header and the one row, parsed by the csv crate.
fn parse(stdout: &str) -> (String, Vec<String>, Vec<String>) {
    let mut lines = stdout.lines();
    let comment = lines.next().unwrap().to_string();
    let rest: String = lines.map(|l| format!("{l}\n")).collect();
    let mut reader = csv::Reader::from_reader(rest.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .unwrap()
        .iter()
        .map(str::to_string)
        .collect();
    let rows: Vec<Vec<String>> = reader
        .records()
        .map(|r| r.unwrap().iter().map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 1, "{stdout}");
    (comment, header, rows[0].clone())
}

#[test]
fn the_franka_hand_row_parses_as_csv_with_the_documented_columns() {
    let dir = scratch("row");
    let panda = repo(PANDA);
    let hand: &[&str] = &[
        &hand_of(&panda, "0.04")[..],
        &[
            "--flange",
            "panda_link8",
            "--model",
            "panda",
            "--name",
            "Franka Hand, open",
        ],
    ]
    .concat();
    let out = tool(&dir, hand);
    common::assert_ok(&out);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let (comment, header, row) = parse(&stdout);
    assert!(comment.starts_with("# from "), "{comment}");
    assert!(
        comment.contains("links panda_hand, panda_hand_tcp, panda_leftfinger, panda_rightfinger"),
        "{comment}"
    );
    assert_eq!(header, COLUMNS);
    assert_eq!(row[0], "Franka Hand, open");
    assert_eq!(row[1], "panda");
    let v: Vec<f64> = row[2..].iter().map(|c| c.parse().unwrap()).collect();
    assert!(v.iter().all(|x| x.is_finite()));
    // The hand (0.73 kg) and its two 15 g fingers; the tool-centre point 0.1034 m out on z.
    assert_eq!(v[0], 0.76);
    assert_eq!(&v[10..], [0.0, 0.0, 0.1034]);
    // In panda_link8's frame (the hand turned -45° about z): ixx = iyy, com_x = -com_y.
    assert!((v[4] - v[5]).abs() < 1e-15 && (v[1] + v[2]).abs() < 1e-15);
    // --out writes the same text, through the output rule (it refuses the URDF itself: below).
    let out = tool(&dir, &[hand, &["--out", "hand.csv"]].concat());
    assert!(out.status.success() && out.stdout.is_empty());
    assert_eq!(
        std::fs::read_to_string(dir.join("hand.csv")).unwrap(),
        stdout
    );
}

#[test]
fn out_never_overwrites_the_urdf_it_reads() {
    let dir = scratch("row_over_urdf");
    std::fs::copy(repo(PANDA), dir.join("copy.urdf")).unwrap();
    let before = std::fs::read(dir.join("copy.urdf")).unwrap();
    let out = tool(
        &dir,
        &[&hand_of("copy.urdf", "0")[..], &["--out", "copy.urdf"]].concat(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read(dir.join("copy.urdf")).unwrap(), before);
}

/// Each bad input: its arguments (the file `x.urdf` holding `urdf`), the fragments its one
/// error line must hold.
#[test]
fn bad_input_is_status_2_and_one_line_naming_it() {
    let panda = std::fs::read_to_string(repo(PANDA)).unwrap();
    let hand = ["--root", "panda_hand", "--tip", "panda_hand_tcp"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v = vec!["--urdf", "x.urdf"];
        v.extend(hand);
        v.extend(extra);
        v
    };
    let deep = format!("<robot>{}", "<a>".repeat(100_000));
    let many_links: String = (0..50_000)
        .map(|i| {
            format!(r#"<link name="l{i}"/><joint name="j{i}" type="fixed"><parent link="l{i}"/><child link="l{}"/></joint>"#, i + 1)
        })
        .collect();
    let chain = format!(
        r#"<robot name="c"><link name="l50000"><inertial><mass value="1"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>{many_links}</robot>"#
    );
    let cases: Vec<(String, Vec<&str>, Vec<&str>)> = vec![
        (panda.clone(), with(&[]), vec!["x.urdf, line 334: joint 'panda_finger_joint1' is prismatic and has no position: give --opening VALUE or --joint panda_finger_joint1=VALUE"]),
        (panda.clone(), with(&["--opening", "0.041"]), vec!["x.urdf, line 334", "position 0.041 m is outside its limits [0, 0.04]"]),
        (panda.clone(), with(&["--opening", "nan"]), vec!["--opening", "'nan' is not finite"]),
        (panda.clone(), with(&["--opening", "wide"]), vec!["'wide' is not a number"]),
        (panda.clone(), with(&["--opening", "0", "--joint", "panda_finger_joint1"]), vec!["'panda_finger_joint1' is not NAME=VALUE"]),
        (panda.clone(), with(&["--opening", "0", "--joint", "nope=0.1"]), vec!["x.urdf: --joint nope=0.1: no joint of the file is named so"]),
        (panda.clone(), with(&["--opening", "0", "--joint", "panda_hand_joint=0.1"]), vec!["is not below --root 'panda_hand'"]),
        (panda.clone(), with(&["--opening", "0", "--joint", "panda_hand_tcp_joint=0.1"]), vec!["'panda_hand_tcp_joint' is fixed, it has no position to hold"]),
        (panda.clone(), with(&["--opening", "0", "--flange", "panda_link6"]), vec!["x.urdf, line 197: joint 'panda_joint7' between --flange 'panda_link6'", "revolute, not fixed"]),
        (panda.clone(), with(&["--opening", "0", "--flange", "panda_rightfinger"]), vec!["--flange 'panda_rightfinger' is not an ancestor of --root 'panda_hand'"]),
        (panda.clone(), with(&["--opening", "0", "--flange", "wrist"]), vec!["--flange 'wrist' is no link of the file (its 13 links: panda_link0"]),
        (panda.clone(), with(&["--opening", "0", "--model", "arm2"]), vec!["--model", "'arm2' is not a model with a tool at a URDF flange (panda, ur5)"]),
        (panda.clone(), vec!["--urdf", "x.urdf", "--root", "panda_hand", "--tip", "panda_link8", "--opening", "0"], vec!["--tip 'panda_link8' is not --root 'panda_hand' or a link below it"]),
        (panda.replace("<mimic joint=\"panda_finger_joint1\"/>", "<mimic joint=\"panda_finger_joint9\"/>"), with(&["--opening", "0"]), vec!["x.urdf, line 342: joint 'panda_finger_joint2': <mimic> joint = 'panda_finger_joint9' is no joint of the file"]),
        (panda.replace("xyz=\"0 0 0.1034\"", "xyz=\"0 0.1034\""), with(&["--opening", "0"]), vec!["x.urdf, line 249: joint 'panda_hand_tcp_joint': <origin> xyz = '0 0.1034' has 2 numbers, not 3"]),
        (panda.replace("xyz=\"0 0 0.1034\"", "xyz=\"0 0 1e999\""), with(&["--opening", "0"]), vec!["line 249", "'1e999' is not finite"]),
        (panda.replace("rpy=\"0 0 -0.7853981633974483\"", "rpy=\"0 0 -pi/4\""), vec!["--urdf", "x.urdf", "--root", "panda_hand", "--tip", "panda_hand_tcp", "--opening", "0", "--flange", "panda_link8"], vec!["line 221", "joint 'panda_hand_joint': <origin> rpy = '0 0 -pi/4': '-pi/4' is not a number"]),
        (panda.replace("<mass value=\"0.73\"/>", "<mass value=\"-0.73\"/>"), with(&["--opening", "0"]), vec!["line 236: link 'panda_hand': <inertial><mass> value = -0.73 is negative"]),
        (panda.replace("ixx=\"0.001\"", "ixx=\"0.01\""), with(&["--opening", "0"]), vec!["merge to an inertia that no rigid body has", "triangle inequality"]),
        (panda.replace("<child link=\"panda_rightfinger\"/>", "<child link=\"panda_leftfinger\"/>"), with(&["--opening", "0"]), vec!["line 342", "link 'panda_leftfinger' has two parents"]),
        (panda.replace("type=\"prismatic\"", "type=\"sliding\""), with(&["--opening", "0"]), vec!["line 334", "type = 'sliding' is not a URDF joint type"]),
        (panda.replace("<link name=\"panda_hand_tcp\">", "<link name=\"panda_hand\">"), with(&["--opening", "0"]), vec!["line 241: a second link named 'panda_hand' (the first is on line 223)"]),
        (panda.replace("</robot>", ""), with(&["--opening", "0"]), vec!["x.urdf: not a well-formed XML file"]),
        (panda.replace("<robot", "<!DOCTYPE robot [<!ENTITY a \"aaaa\">]><robot"), with(&["--opening", "0"]), vec!["not a well-formed XML file", "DTD"]),
        ("<html><body/></html>".into(), with(&[]), vec!["x.urdf, line 1: the top element is <html>, not <robot>"]),
        ("\u{0}\u{1}garbage".into(), with(&[]), vec!["x.urdf: not a well-formed XML file"]),
        (String::new(), with(&[]), vec!["x.urdf: not a well-formed XML file"]),
        (deep, with(&[]), vec!["x.urdf: not a well-formed XML file"]),
        (chain, vec!["--urdf", "x.urdf", "--root", "l0", "--tip", "l49999"], vec!["merge to an inertia", "is not positive definite"]),
        (panda.clone(), vec!["--urdf", "/dev/zero", "--root", "a", "--tip", "b"], vec!["/dev/zero: is a device, not a URDF file"]),
        (panda.clone(), vec!["--urdf", "missing.urdf", "--root", "a", "--tip", "b"], vec!["missing.urdf: cannot read the URDF file"]),
        (panda.clone(), vec!["--urdf", ".", "--root", "a", "--tip", "b"], vec![".: is a folder, not a URDF file"]),
        (panda.clone(), with(&["--opening", "0", "--out", "/"]), vec!["--out /"]),
        (panda.clone(), with(&["--opening", "0", "--out", "no/such/folder/x.csv"]), vec!["--out no/such/folder/x.csv"]),
        (panda.clone(), vec!["--urdf", "x.urdf", "--root", "panda_hand"], vec!["--tip"]),
    ];
    let mut failures = Vec::new();
    for (i, (urdf, args, says)) in cases.iter().enumerate() {
        let dir = scratch(&format!("case{i:02}"));
        std::fs::write(dir.join("x.urdf"), urdf).unwrap();
        let out = tool(&dir, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = stderr.lines().collect();
        let ok = out.status.code() == Some(2)
            && out.stdout.is_empty()
            && lines.len() == 1
            && lines[0].starts_with("toolconf: error: ")
            && lines[0].chars().count() <= 700
            && says.iter().all(|s| lines[0].contains(s))
            && std::fs::read_to_string(dir.join("x.urdf")).unwrap() == *urdf;
        if !ok {
            failures.push(format!(
                "case {i} {args:?}: status {:?}, stderr {:?}",
                out.status.code(),
                stderr.chars().take(400).collect::<String>()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Stdout that cannot be written is one line and status 1, as for every command.
#[test]
fn a_full_standard_output_is_status_1() {
    let dir = scratch("full");
    let panda = repo(PANDA);
    let out = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .arg("tool")
        .args(hand_of(&panda, "0.02"))
        .current_dir(&dir)
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot write to standard output"));
}
