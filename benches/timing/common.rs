//! What the timing programs share: the median of the repeated runs, the check of `--repeat`, the
//! list of tasks, and the way a program ends (its JSON on stdout, or its error and status 2).
#![allow(dead_code)] // each program uses its own part of this module

use std::process::ExitCode;

use serde_json::Value;
use toolconf_model::TaskKind;

/// The median, the mean of the two middle values for an even count.
pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// `--repeat`'s value: a whole number of at least 1.
pub fn repeat_count(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(r) if r > 0 => Ok(r),
        Ok(_) => Err("--repeat must be ≥ 1".into()),
        Err(e) => Err(format!("--repeat: {e}")),
    }
}

/// `--tasks`' value: task names separated by commas.
pub fn task_kinds(text: &str) -> Result<Vec<TaskKind>, String> {
    text.split(',')
        .map(|t| t.parse::<TaskKind>().map_err(|e| e.to_string()))
        .collect()
}

/// `v` on stdout, pretty-printed.
pub fn print_json(v: &Value) {
    println!(
        "{}",
        serde_json::to_string_pretty(v).expect("finite numbers")
    );
}

/// Success, or `program: error` on stderr and status 2.
pub fn exit_code(program: &str, result: Result<(), String>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{program}: {e}");
            ExitCode::from(2)
        }
    }
}
