//! The tool of `confidence` and `simulate`: the paper's arm (`--arm`), or a tool of any model
//! (`--model M --params P1,P2,…`), declared once so the two commands take it alike.

use toolconf_model::registry::ModelKind;
use toolconf_model::Arm;

use super::{parse_arm, parse_model};

#[derive(clap::Args)]
pub struct ToolArgs {
    /// The tool: link masses and lengths M1,M2,L1,L2 (kg, m), all > 0, of the paper's arm.
    #[arg(long, value_parser = parse_arm, allow_hyphen_values = true,
          required_unless_present = "model", conflicts_with_all = ["model", "params"])]
    pub arm: Option<Arm>,
    /// A tool of any generated model instead of --arm (with --params).
    #[arg(long, value_parser = parse_model, requires = "params", help = format!(
        "A tool of any generated model instead of --arm: {} (with --params)",
        toolconf_generated::MODEL_NAMES.join(", ")))]
    pub model: Option<ModelKind>,
    /// The model's parameters in its order, comma-separated (e.g. m1,m2,l1,l2,mp for
    /// arm2_payload; `toolconf select --help` lists every model's).
    #[arg(long, requires = "model", allow_hyphen_values = true)]
    pub params: Option<String>,
}

/// `confidence`'s help for `--params`, which names the URDF arms' parameters (the tools its
/// users look at most), where `simulate`'s gives a 2-link example.
pub const CONFIDENCE_PARAMS_HELP: &str = "The model's parameters in its order, comma-separated \
    (panda, ur5: tool_mass, tool_com_x, tool_com_y, tool_com_z, tool_ixx, tool_iyy, tool_izz; \
    `toolconf select --help` lists every model's)";
