//! One closed-loop episode: the paper's 2-link arm holding a tool, driven from hanging straight
//! down to the position task's goal by the active-inference controller (U̇ = −γ ∂F/∂U).
//!
//! ```sh
//! cargo run --example episode
//! ```
//!
//! `toolconf simulate --arm 0.35,0.35,0.35,0.35 --task position --method auto` prints the same
//! numbers.

use toolconf_model::closed_loop::{simulate, EpisodeOptions};
use toolconf_model::{Arm, Task, TaskKind, Term};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The tool: link masses m1, m2 [kg] and lengths l1, l2 [m], checked once here.
    let arm = Arm::new([0.35, 0.35, 0.35, 0.35])?;
    // The paper's task 1: bring θ to (π/3, π/6) rad, with its goals and precisions.
    let task = Task::paper(TaskKind::Position);
    // The paper's episode: 5 s from the equilibrium θ = (−π/2, −π/2), ode45's tolerances; keep
    // the trajectory on its 0.05 s output grid.
    let options = EpisodeOptions {
        record_trajectory: true,
        ..EpisodeOptions::default()
    };
    let episode = simulate(&arm, &task, &options)?;

    let method = options.integrator.method.name();
    println!("tool: {arm}    method: {method}");
    let trajectory = episode.trajectory.expect("record_trajectory keeps it");
    let theta = trajectory.of(Term::Theta);
    for (t, th) in trajectory.t.iter().zip(theta).step_by(20) {
        println!("t = {t:.1} s    θ = ({:+.4}, {:+.4}) rad", th[0], th[1]);
    }
    // The numbers tools are ranked by: the summed task error, ∫F dt, ∫J dt (∫F without the
    // confidence term) and the control confidence ln|Π^U|.
    let m = &episode.metrics;
    println!("task error    {:.9e}", m.task_error);
    println!("∫F dt         {:.9e}", m.free_energy);
    println!("∫J dt         {:.9e}", m.cost_j);
    println!("ln|Π^U|       {:.9e}", m.logdet);
    Ok(())
}
