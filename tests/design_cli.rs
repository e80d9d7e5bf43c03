//! `toolconf design` as a user runs it: the example of docs/tutorials/design-a-tool.md, JSON keys, the report and sweep
//! files, determinism across thread counts, and bad input as one line with exit status 2.

mod common;

use std::process::Command;

use serde_json::Value;

const EXAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/design/reach_and_budget.toml"
);

fn toolconf(args: &[&str], threads: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .expect("run toolconf")
}

fn design_json(threads: &str) -> Value {
    let out = toolconf(
        &[
            "design", "--model", "arm2", "--task", "velocity", "--design", EXAMPLE, "--json",
        ],
        threads,
    );
    common::json_ok(&out)
}

#[test]
fn example_design_prints_params_logdet_and_verification() {
    let v = design_json("2");
    for key in ["m1", "m2", "l1", "l2"] {
        assert!(v["params"][key].as_f64().unwrap() > 0.0, "params.{key}");
    }
    let logdet = v["logdet"].as_f64().unwrap();
    assert!(logdet >= v["random"]["best_logdet"].as_f64().unwrap());
    assert_eq!(v["random"]["feasible"], 100_000);
    let rows = v["verification"].as_array().unwrap();
    assert_eq!(rows[0]["tool"], "design");
    assert!(rows
        .iter()
        .all(|r| r["task_error"].is_f64() && r["sensitivity"].is_f64()));
    assert!(v["gradient_check"].as_f64().unwrap() < 1e-6);
    assert_eq!(v, design_json("1"), "thread count changed the result");
}

#[test]
fn report_and_sweep_write_csv_and_svg() {
    let dir = std::env::temp_dir().join(format!("toolconf-design-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = toolconf(
        &[
            "design",
            "--task",
            "velocity",
            "--design",
            EXAMPLE,
            "--sweep",
            "m1 + m2 <= 0.1..0.9:5",
            "--report",
            dir.to_str().unwrap(),
        ],
        "2",
    );
    common::assert_ok(&out);
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "budget,logdet,kkt_residual,m1,m2,l1,l2,error");
    assert_eq!(lines.len(), 6);
    // m1 + m2 <= 0.1 is infeasible with both masses >= 0.1; the front never falls as the budget grows.
    assert!(lines[1].ends_with("infeasible"), "{}", lines[1]);
    let front: Vec<f64> = lines[2..]
        .iter()
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    assert!(front.windows(2).all(|w| w[1] >= w[0] - 1e-9), "{front:?}");
    assert!(std::fs::read_to_string(dir.join("sweep.svg"))
        .unwrap()
        .starts_with("<svg"));
    assert!(std::fs::read_to_string(dir.join("report.md"))
        .unwrap()
        .contains("Trade-off"));
    let _ = std::fs::remove_dir_all(&dir);
}

fn refused(design: &str, extra: &[&str]) -> String {
    let path = std::env::temp_dir().join(format!(
        "toolconf-bad-design-{}-{}.toml",
        std::process::id(),
        design.len()
    ));
    std::fs::write(&path, design).unwrap();
    let mut args = vec![
        "design",
        "--task",
        "velocity",
        "--design",
        path.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = toolconf(&args, "2");
    let _ = std::fs::remove_file(&path);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(out.stdout.is_empty());
    err
}

#[test]
fn bad_input_is_one_line_and_status_2() {
    let good = std::fs::read_to_string(EXAMPLE).unwrap();
    let e = refused(&good.replace("l1 + l2 >= 0.7", "l1 + l3 >= 0.7"), &[]);
    assert!(
        e.contains("key constraints[0]") && e.contains("unknown parameter 'l3'"),
        "{e}"
    );
    let e = refused(&good.replace("l1 + l2 >= 0.7", "l1 + l2 >= 1.5"), &[]);
    assert!(
        e.contains("infeasible") && e.contains("l1 + l2 >= 1.5"),
        "{e}"
    );
    let e = refused(&good.replace("m1 = [0.1, 0.6]", "m1 = [0.0, 0.6]"), &[]);
    assert!(e.contains("key bounds.m1"), "{e}");
    let e = refused(&good.replace("\"confidence\"", "\"cheapest\""), &[]);
    assert!(e.contains("key objective") && e.contains("cheapest"), "{e}");
    let e = refused(&good, &["--sweep", "m1 + m2 <= 0.3..0.9"]);
    assert!(e.contains("--sweep"), "{e}");
    let e = refused(&good, &["--model", "arm9"]);
    assert!(e.contains("unknown model 'arm9'"), "{e}");
}

/// A thin feasible set that gives fewer random tools than asked for says so on stderr (an
/// optimum that did not converge does too: tests/design.rs finds one).
#[test]
fn a_thin_set_is_warned_about() {
    let thin = common::fresh_file(
        "design-warn",
        "thin.toml",
        "constraints = [\"m1 + m2 <= 0.2000001\", \"m1 + m2 >= 0.2\"]\n[bounds]\n\
         m1 = [0.1, 0.6]\nm2 = [0.1, 0.6]\nl1 = [0.1, 0.6]\nl2 = [0.1, 0.6]\n[search]\nsamples = 50\n",
    );
    let out = toolconf(
        &[
            "design",
            "--task",
            "velocity",
            "--design",
            thin.to_str().unwrap(),
        ],
        "2",
    );
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("toolconf: warning: only 0 of the 50 random feasible tools asked for")
            && stderr.contains("in 50000 draws"),
        "{stderr}"
    );
    std::fs::remove_dir_all(thin.parent().unwrap()).unwrap();
}
