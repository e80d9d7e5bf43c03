//! Rank a drawer of tools on a task: `toolconf rank`'s two stages through the library.
//!
//! The cheap stage reads every tool and computes its control confidence ln|Π^U| in closed form,
//! without simulating; the expensive one runs each tool's closed-loop episode (on all cores) and
//! ranks the tools by the free energy ∫F dt, the paper's objective.
//!
//! ```sh
//! cargo run --example rank_drawer [-- TOOLS.csv TASK.toml]   # default: the drawer on reach_45
//! ```

use std::convert::Infallible;
use std::path::PathBuf;
use std::process::ExitCode;

use toolconf::rank::{ranking, screen_file, simulate_all, ModelTasks};
use toolconf::select::Objective;
use toolconf_integrators::Method;
use toolconf_model::inputs::task_file::TaskSpec;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rank_drawer: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let tools = PathBuf::from(args.next().unwrap_or("examples/tools/drawer.csv".into()));
    let task = PathBuf::from(args.next().unwrap_or("examples/tasks/reach_45.toml".into()));

    // The task file: goals, precisions and the episode's options (time, perturbation, ...).
    let mut spec = TaskSpec::from_file(&task)?;
    // `toolconf rank`'s default integrator: ode45's steps, Rodas5P once the loop turns stiff.
    spec.episode.method = Some(Method::Fast);
    // The task bound to every model, since a drawer may mix models (arm2 and arm2_exact here).
    let tasks = ModelTasks::new(&spec);

    // Stage 1: every row read, checked and given its ln|Π^U|; `None` keeps them all (no screen).
    let label = task.display().to_string();
    let (screen, _) = screen_file(&tools, &tasks, &label, None, false, |_| {})?;
    // Stage 2: the kept tools' episodes, in parallel; the results come back in file order.
    let results = simulate_all(screen.finish(), &tasks, |_| Ok::<(), Infallible>(()))?;

    println!("rank  name                  ln|Π^U|    task error         ∫F dt");
    for (k, &i) in ranking(&results, Objective::FreeEnergy).iter().enumerate() {
        let (tool, name) = (&results[i], results[i].row.label());
        match (&tool.logdet, &tool.episode) {
            (Ok(logdet), Ok(m)) => println!(
                "{:>4}  {name:<20} {logdet:>8.4} {:>13.6e} {:>13.6e}",
                k + 1,
                m.task_error,
                m.free_energy
            ),
            (_, Err(e)) => println!("{:>4}  {name:<20} failed: {e}", k + 1),
            (Err(e), _) => println!("{:>4}  {name:<20} no confidence: {e}", k + 1),
        }
    }
    Ok(())
}
