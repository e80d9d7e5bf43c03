//! What the screen keeps ([`ScreenBy`]): the most confident tools, or those whose episode the
//! linearised closed loop predicts cheapest ([`toolconf_model::prediction`]).

use crate::select::Objective;
use toolconf_model::prediction::{Prediction, PredictionError};

/// The screen's criterion (`rank --screen-by`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ScreenBy {
    /// The largest ln|Π^U| (eq. control_conf), computed in closed form.
    #[default]
    Confidence,
    /// The lowest predicted cost of the episode the ranking minimises: predicted ∫J dt when it
    /// ranks by ∫J dt, else predicted ∫F dt (eq. free_energy). A tool without a prediction (its
    /// linearised loop unstable) comes after every tool with one, in file order.
    Predicted(Objective),
}

impl ScreenBy {
    /// `predicted` or `confidence`, as the command line and JSON spell it.
    pub fn name(self) -> &'static str {
        match self {
            ScreenBy::Confidence => "confidence",
            ScreenBy::Predicted(_) => "predicted",
        }
    }

    /// Whether the screen needs each tool's prediction.
    pub fn needs_prediction(self) -> bool {
        matches!(self, ScreenBy::Predicted(_))
    }

    /// The screen's key, larger kept first: ln|Π^U|, or minus the predicted cost; a tool without
    /// a prediction gets −∞ (every prediction is finite, [`toolconf_model::prediction::predict`]), so
    /// such tools tie among themselves and the earlier row wins.
    pub fn key(self, logdet: f64, prediction: Option<&Result<Prediction, PredictionError>>) -> f64 {
        match self {
            ScreenBy::Confidence => logdet,
            ScreenBy::Predicted(objective) => match prediction {
                Some(Ok(p)) => -predicted_cost(objective, p),
                _ => f64::NEG_INFINITY,
            },
        }
    }
}

/// The predicted value a screen by prediction minimises for `objective`'s ranking.
pub fn predicted_cost(objective: Objective, p: &Prediction) -> f64 {
    match objective {
        Objective::CostJ => p.cost_j,
        Objective::FreeEnergy | Objective::Confidence => p.free_energy,
    }
}
