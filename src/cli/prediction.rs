//! The prediction's fields in `confidence --json` and `rank`'s JSON, CSV and table
//! (`toolconf_model::prediction`): numbers, or `null` with the reason; never NaN.

use serde_json::{json, Value};
use toolconf_files::csv::Cell;
use toolconf_model::prediction::{Prediction, PredictionError};

/// The JSON fields: `predicted_task_error`, `predicted_free_energy`, `predicted_cost_j`,
/// `predicted_perturbation_effect` (each `null` without a prediction) and `prediction_note`
/// (`null`, or why there is no prediction).
pub fn add_prediction(v: &mut Value, p: &Result<Prediction, PredictionError>) {
    let values = p.as_ref().ok();
    let field = |f: fn(&Prediction) -> f64| values.map_or(Value::Null, |p| json!(f(p)));
    v["predicted_task_error"] = field(|p| p.task_error);
    v["predicted_free_energy"] = field(|p| p.free_energy);
    v["predicted_cost_j"] = field(|p| p.cost_j);
    v["predicted_perturbation_effect"] = field(|p| p.perturbation_effect);
    v["prediction_note"] = p.as_ref().err().map_or(Value::Null, |e| json!(e.reason()));
}

/// The CSV columns [`csv_cells`] fills.
pub const CSV_COLUMNS: [&str; 3] = [
    "predicted_task_error",
    "predicted_free_energy",
    "prediction_note",
];

/// The CSV cells: the predicted task error and ∫F dt (empty without a prediction) and the
/// reason there is none.
pub fn csv_cells(p: &Result<Prediction, PredictionError>) -> [Cell; 3] {
    match p {
        Ok(p) => [
            Cell::from(p.task_error),
            Cell::from(p.free_energy),
            Cell::Empty,
        ],
        Err(e) => [Cell::Empty, Cell::Empty, Cell::from(e.reason())],
    }
}

/// The table's cell: the predicted task error, or `-` without one.
pub fn table_cell(p: &Result<Prediction, PredictionError>) -> String {
    match p {
        Ok(p) => format!("{:>14.6e}", p.task_error),
        Err(_) => format!("{:>14}", "-"),
    }
}
