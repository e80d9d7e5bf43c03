//! A model's generated functions with their const-generic sizes: the Panda's linearisation A, B
//! and control confidence Π^U for a tool, from toolconf-core on toolconf-generated alone (both
//! no_std, no allocation), without the runtime or its registry of models: what a robot's
//! controller links.
//!
//! ```sh
//! cargo run --example generated_functions
//! ```

use nalgebra::SMatrix;
use toolconf_core::generated::panda::{DOF, STATE_DIM};
use toolconf_core::{control_confidence, ArmModel, Panda, PandaTool, TaskKind};

fn main() -> Result<(), toolconf_core::Error> {
    // A hammer at the flange, in the order of `panda::PARAMETER_NAMES`: mass [kg], centre of
    // mass [m], moments and products of inertia [kg m²] and the tip [m], in the flange frame.
    let hammer = PandaTool::new([
        1.384, -0.0037, 0.0037, 0.1675, 0.0357, 0.0361, 0.0022, 7.7e-4, -7.1e-4, 7.1e-4, 0.055,
        0.0, 0.3684,
    ])?;
    println!("tool: {hammer}");
    // The sizes are the generated module's constants (7 joints, 14 states), checked by the
    // compiler: Ẋ ≈ A (X − Xᵉ) + B (U − Uᵉ) about the equilibrium.
    let a: SMatrix<f64, STATE_DIM, STATE_DIM> = hammer.state_matrix();
    let b: SMatrix<f64, STATE_DIM, DOF> = hammer.input_matrix();
    // The position task with the Panda's own goal and the paper's precisions, and its Π^U.
    let task = Panda::paper_task(TaskKind::Position);
    let confidence = control_confidence(&hammer, &task)?;
    show("A", &a);
    show("B", &b);
    show("Pi^U", &confidence.pi_u);
    println!("ln|Pi^U| = {:.12}", confidence.logdet);
    Ok(())
}

/// An R × C matrix, one row a line.
fn show<const R: usize, const C: usize>(name: &str, m: &SMatrix<f64, R, C>) {
    println!("{name} ({R} x {C}):");
    for row in m.row_iter() {
        let row: Vec<String> = row.iter().map(|x| format!("{x:>11.4e}")).collect();
        println!("  {}", row.join(" "));
    }
}
