//! Printing matrices as text and as JSON lists of rows.

use nalgebra::SMatrix;
use serde_json::Value;

/// A matrix as a JSON list of rows.
pub fn matrix_rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Value {
    Value::from((0..R).map(|i| (0..C).map(|j| m[(i, j)]).collect::<Vec<f64>>()).collect::<Vec<_>>())
}

/// A titled matrix, one row a line, in a width that keeps columns aligned.
pub fn print_matrix<const R: usize, const C: usize>(title: &str, m: &SMatrix<f64, R, C>) {
    println!("{title}:");
    for i in 0..R {
        let row: Vec<String> = (0..C).map(|j| format!("{:>16.9e}", m[(i, j)])).collect();
        println!("  [{}]", row.join(" "));
    }
}
