//! Load a model library at run time and use its model as a built-in one, with no rebuild: a
//! robot the repository does not ship, derived and compiled by `make model`.
//!
//! ```sh
//! make model IR=generated/panda.json OUT=/tmp/models/panda     # or DESC=your_robot.toml
//! cargo run --example load_model -- panda_lib=/tmp/models/panda \
//!     1.384,-0.0037,0.0037,0.1675,0.0357,0.0361,0.0022,7.7e-4,-7.1e-4,7.1e-4,0.055,0,0.3684
//! ```
//!
//! The first argument is the library (its file or the folder `make model` wrote), as
//! `NAME=PATH` to load it under another name (a library of a built-in model must be renamed);
//! the second a tool's parameters in the model's order.

use std::process::ExitCode;

use toolconf::rank::ModelTasks;
use toolconf_integrators::Method;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::loaded;
use toolconf_model::registry::AnyTool;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("load_model: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [library, params] = &args[..] else {
        return Err("usage: load_model [NAME=]LIBRARY P1,P2,...".into());
    };
    // Opens the library, checks its ABI, symbols and metadata, and registers its model.
    let model = loaded::load_entry(library)?;
    let names = model.parameter_names().join(", ");
    println!("{model}: {} joints; parameters {names}", model.dof());
    let params = params.split(',').map(str::parse::<f64>);
    let tool = AnyTool::new(model, &params.collect::<Result<Vec<_>, _>>()?)?;
    // Every task the model was derived with, at its defaults, as `toolconf simulate` runs it.
    for &kind in model.info().tasks {
        let mut spec = TaskSpec::builtin(kind);
        // The command line's and Python's integrator: ode45's steps, Rodas5P once stiff.
        spec.episode.method = Some(Method::Fast);
        let m = ModelTasks::new(&spec).simulate(&tool)?;
        println!(
            "{:<17} ln|Π^U| {:>16.9e}   task error {:>16.9e}   ∫F dt {:>16.9e}",
            kind.name(),
            m.logdet,
            m.task_error,
            m.free_energy
        );
    }
    Ok(())
}
