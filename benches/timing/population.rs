//! Ranking throughput on a population of tools, old and new integration paths side by side:
//! `benches/population.sh` runs it and writes its table into `docs/explanation/performance-population.md`.
//!
//! For each task, every method ranks the same `--tools` tools drawn by `draw_tools(n, seed)` on
//! one thread at the paper's defaults; the methods alternate tool by tool (each tool: one warm-up
//! episode per method, then `--repeat` timed rounds, the methods in turn within a round), so
//! that drift of the shared machine hits every method alike. Per method it prints the mean and
//! p50/p90/p99/max of the per-tool time (µs, the tool's median over rounds), the mean
//! right-hand-side, Jacobian and LU counts, and the worst relative difference of each tool's
//! task error, ∫F dt and ∫J dt from a reference run at rtol 1e-10, atol 1e-12 (DP5), plus
//! whether ranking by each objective reproduces the reference ranking.
//!
//! ```sh
//! cargo run --release --example population -- [--tools 2000] [--seed 1] [--repeat 3]
//!     [--tasks position,velocity,acceleration] [--methods explicit,auto,stiff,fast] [--markdown]
//! ```

mod common;

use std::process::ExitCode;
use std::time::Instant;

use toolconf::select::draw_tools;
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{simulate, EpisodeOptions, Metrics};
use toolconf_model::{Arm, Task, TaskKind};

struct Args {
    tools: usize,
    seed: u64,
    repeat: usize,
    tasks: Vec<TaskKind>,
    methods: Vec<Method>,
    markdown: bool,
    /// Skip the rtol-1e-10 reference (for profiling the timed episodes alone).
    no_reference: bool,
    /// rtol for `Method::Fast` (default: the paper's 1e-3, as for every other method).
    fast_rtol: Option<f64>,
}

fn method_name(m: Method) -> String {
    format!("{m:?}")
}

fn parse_method(s: &str) -> Result<Method, String> {
    match s {
        "explicit" => Ok(Method::Explicit),
        "stiff" => Ok(Method::Stiff),
        "auto" => Ok(Method::Auto),
        "fast" => Ok(Method::Fast),
        _ => Err(format!("unknown method {s}")),
    }
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        tools: 2000,
        seed: 1,
        repeat: 3,
        tasks: TaskKind::ALL.to_vec(),
        methods: vec![Method::Explicit, Method::default()],
        markdown: false,
        no_reference: false,
        fast_rtol: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--tools" => args.tools = value()?.parse().map_err(|e| format!("--tools: {e}"))?,
            "--seed" => args.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--repeat" => args.repeat = value()?.parse().map_err(|e| format!("--repeat: {e}"))?,
            "--tasks" => args.tasks = common::task_kinds(&value()?)?,
            "--methods" => {
                args.methods = value()?
                    .split(',')
                    .map(parse_method)
                    .collect::<Result<_, _>>()?
            }
            "--markdown" => args.markdown = true,
            "--no-reference" => args.no_reference = true,
            "--fast-rtol" => {
                args.fast_rtol = Some(value()?.parse().map_err(|e| format!("--fast-rtol: {e}"))?)
            }
            _ => return Err(format!("unknown argument {flag}")),
        }
    }
    if args.repeat == 0 || args.tools == 0 {
        return Err("--repeat and --tools must be ≥ 1".into());
    }
    Ok(args)
}

fn options_for(method: Method, fast_rtol: Option<f64>) -> EpisodeOptions {
    let mut o = EpisodeOptions::default();
    o.integrator.method = method;
    if let (Method::Fast, Some(rtol)) = (method, fast_rtol) {
        o.integrator.rtol = rtol;
    }
    o
}

fn reference(tools: &[Arm], task: &Task) -> Result<Vec<Metrics>, String> {
    let mut o = options_for(Method::Explicit, None);
    o.integrator.rtol = 1e-10;
    o.integrator.atol = 1e-12;
    tools
        .iter()
        .map(|a| {
            simulate(a, task, &o)
                .map(|e| e.metrics)
                .map_err(|e| e.to_string())
        })
        .collect()
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i]
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Rank order (indices, best first) by one objective; ties by index.
fn order(values: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..values.len()).collect();
    idx.sort_by(|&a, &b| values[a].total_cmp(&values[b]).then(a.cmp(&b)));
    idx
}

/// Pairs of tools that the candidate orders the other way round from the reference, not
/// explained by a tie: the reference values differ by more than `tol` relative.
fn unexplained_swaps(reference: &[f64], candidate: &[f64], tol: f64) -> usize {
    let order = order(reference);
    let mut swaps = 0;
    for (x, &a) in order.iter().enumerate() {
        for &b in &order[x + 1..] {
            let gap = reference[b] - reference[a];
            if gap > tol * reference[a].abs().max(reference[b].abs()) && candidate[a] > candidate[b]
            {
                swaps += 1;
            }
        }
    }
    swaps
}

struct Row {
    method: Method,
    times: Vec<f64>,
    metrics: Vec<Metrics>,
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    let tools = draw_tools(args.tools, args.seed);
    println!(
        "{} tools (draw_tools({}, {})), one thread, {} timed round(s) per tool, per-tool time = median of rounds",
        tools.len(),
        args.tools,
        args.seed,
        args.repeat
    );
    for kind in &args.tasks {
        let task = Task::paper(*kind);
        let refs = if args.no_reference {
            Vec::new()
        } else {
            reference(&tools, &task)?
        };
        let mut rows: Vec<Row> = args
            .methods
            .iter()
            .map(|&method| Row {
                method,
                times: Vec::with_capacity(tools.len()),
                metrics: Vec::with_capacity(tools.len()),
            })
            .collect();
        for arm in &tools {
            let mut runs = vec![Vec::with_capacity(args.repeat); rows.len()];
            for row in rows.iter_mut() {
                let m = simulate(arm, &task, &options_for(row.method, args.fast_rtol))
                    .map_err(|e| format!("{:?}: {e}", row.method))?;
                row.metrics.push(m.metrics);
            }
            for _ in 0..args.repeat {
                for (row, r) in rows.iter().zip(runs.iter_mut()) {
                    let o = options_for(row.method, args.fast_rtol);
                    let start = Instant::now();
                    let m = simulate(std::hint::black_box(arm), &task, &o);
                    r.push(start.elapsed().as_secs_f64() * 1e6);
                    std::hint::black_box(m).ok();
                }
            }
            for (row, r) in rows.iter_mut().zip(runs.iter_mut()) {
                row.times.push(median(r));
            }
        }
        print_task(*kind, &rows, &refs, args.markdown);
    }
    Ok(())
}

fn worst_rel(refs: &[Metrics], got: &[Metrics], f: impl Fn(&Metrics) -> f64) -> f64 {
    if refs.is_empty() {
        return f64::NAN;
    }
    refs.iter()
        .zip(got)
        .map(|(r, g)| ((f(g) - f(r)) / f(r)).abs())
        .fold(0.0, f64::max)
}

fn print_task(kind: TaskKind, rows: &[Row], refs: &[Metrics], markdown: bool) {
    let base = rows[0].times.iter().sum::<f64>() / rows[0].times.len() as f64;
    if markdown {
        println!("\n| task | method | mean µs/tool | × first | p50 | p90 | p99 | max | mean RHS | mean Jac | mean LU | worst rel. task error / ∫F / ∫J | ranking swaps (task error / ∫F / ∫J) |");
        println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    } else {
        println!("\ntask {} ({})", kind.name(), kind.name());
    }
    for row in rows {
        let n = row.times.len() as f64;
        let mut sorted = row.times.clone();
        sorted.sort_by(f64::total_cmp);
        let mean = sorted.iter().sum::<f64>() / n;
        let avg =
            |f: &dyn Fn(&Metrics) -> usize| row.metrics.iter().map(f).sum::<usize>() as f64 / n;
        let (rhs, jac, lu) = (
            avg(&|m| m.rhs_evals),
            avg(&|m| m.jacobian_evals),
            avg(&|m| m.factorisations),
        );
        let errs = [
            worst_rel(refs, &row.metrics, |m| m.task_error),
            worst_rel(refs, &row.metrics, |m| m.free_energy),
            worst_rel(refs, &row.metrics, |m| m.cost_j),
        ];
        let col = |f: fn(&Metrics) -> f64| -> Vec<f64> { refs.iter().map(f).collect() };
        let got = |f: fn(&Metrics) -> f64| -> Vec<f64> { row.metrics.iter().map(f).collect() };
        let swaps = [
            unexplained_swaps(&col(|m| m.task_error), &got(|m| m.task_error), 1e-4),
            unexplained_swaps(&col(|m| m.free_energy), &got(|m| m.free_energy), 1e-4),
            unexplained_swaps(&col(|m| m.cost_j), &got(|m| m.cost_j), 1e-4),
        ];
        let q = |p| quantile(&sorted, p);
        if markdown {
            println!(
                "| {} | {} | {:.1} | {:.2} | {:.1} | {:.1} | {:.1} | {:.0} | {:.0} | {:.1} | {:.1} | {:.1e} / {:.1e} / {:.1e} | {} / {} / {} |",
                kind.name(), method_name(row.method), mean, mean / base, q(0.5), q(0.9), q(0.99), q(1.0),
                rhs, jac, lu, errs[0], errs[1], errs[2], swaps[0], swaps[1], swaps[2]
            );
        } else {
            println!(
                "  {:<10} mean {:>7.1} µs ({:.2}×)  p50 {:>6.1}  p90 {:>6.1}  p99 {:>6.1}  max {:>7.0}  RHS {:>6.0}  Jac {:>5.1}  LU {:>5.1}  worst rel {:.1e}/{:.1e}/{:.1e}  swaps {}/{}/{}",
                method_name(row.method), mean, mean / base, q(0.5), q(0.9), q(0.99), q(1.0),
                rhs, jac, lu, errs[0], errs[1], errs[2], swaps[0], swaps[1], swaps[2]
            );
        }
    }
}

fn main() -> ExitCode {
    common::exit_code("population", run())
}
