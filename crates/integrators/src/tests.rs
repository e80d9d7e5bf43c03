use super::*;
use nalgebra::vector;

fn decay(_t: f64, y: &SVector<f64, 1>) -> SVector<f64, 1> {
    -y
}

fn solve_err(grid: &[f64], options: &Options) -> IntegrationError {
    solve_grid(decay, &vector![1.0], grid, options, |_, _, _| {}).unwrap_err()
}

#[test]
fn uniform_grid_hits_tf_exactly_without_accumulation() {
    let g = uniform_grid(0.0, 5.0, 0.05);
    assert_eq!(g.len(), 101);
    assert_eq!(g[0], 0.0);
    assert_eq!(*g.last().unwrap(), 5.0);
    assert_eq!(g[37], 37.0 * 0.05);
    assert!(g.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(
        uniform_grid(0.0, 1.0, 0.3),
        vec![0.0, 0.3, 0.6, 0.3 * 3.0, 1.0]
    );
    assert_eq!(uniform_grid(1.0, 1.5, 2.0), vec![1.0, 1.5]);
    assert!(uniform_grid(0.0, 1.0, 0.0).is_empty());
    assert!(uniform_grid(1.0, 0.0, 0.1).is_empty());
    assert!(uniform_grid(0.0, f64::NAN, 0.1).is_empty());
}

#[test]
fn invalid_grids_are_rejected() {
    let o = Options::default();
    for grid in [
        &[][..],
        &[0.0],
        &[0.0, 1.0, 1.0],
        &[0.0, 2.0, 1.0],
        &[0.0, f64::NAN],
        &[0.0, f64::INFINITY],
    ] {
        assert!(
            matches!(solve_err(grid, &o), IntegrationError::InvalidGrid { .. }),
            "{grid:?}"
        );
    }
    assert!(matches!(
        solve_grid(
            decay,
            &vector![1.0],
            &uniform_grid(1.0, 0.0, 0.1),
            &o,
            |_, _, _| {}
        ),
        Err(IntegrationError::InvalidGrid { .. })
    ));
}

#[test]
fn invalid_options_are_rejected() {
    let d = Options::default();
    let bad = [
        Options { rtol: 0.0, ..d },
        Options { rtol: -1e-3, ..d },
        Options {
            rtol: f64::NAN,
            ..d
        },
        Options { atol: 0.0, ..d },
        Options {
            atol: f64::INFINITY,
            ..d
        },
        Options {
            initial_step: Some(0.0),
            ..d
        },
        Options {
            max_step: Some(-0.1),
            ..d
        },
        Options {
            max_step: Some(f64::NAN),
            ..d
        },
        Options { max_steps: 0, ..d },
    ];
    for o in bad {
        assert!(
            matches!(
                solve_err(&[0.0, 1.0], &o),
                IntegrationError::InvalidOptions { .. }
            ),
            "{o:?}"
        );
    }
}

#[test]
fn non_finite_initial_state_is_an_error() {
    let e = solve_grid(
        decay,
        &vector![f64::NAN],
        &[0.5, 1.0],
        &Options::default(),
        |_, _, _| {},
    );
    assert_eq!(e, Err(IntegrationError::NonFinite { t: 0.5 }));
}

#[test]
fn messages_name_time_and_reason() {
    let e = IntegrationError::NonFinite { t: 1.234 };
    assert_eq!(
        e.to_string(),
        "integration failed at t = 1.234 s: state became non-finite"
    );
    let e = IntegrationError::StepSizeTooSmall { t: 0.5, h: 1e-15 };
    assert!(e
        .to_string()
        .starts_with("integration failed at t = 0.5 s: step size 1e-15 s"));
    let e = IntegrationError::TooManySteps {
        t: 2.0,
        max_steps: 7,
        h: 1e-3,
        state: vec![1.0],
    };
    assert_eq!(
        e.to_string(),
        "integration failed at t = 2 s: exceeded the limit of 7 step attempts (step size 1e-3 s)"
    );
    let e = solve_err(&[0.0, 0.0], &Options::default());
    assert!(
        e.to_string()
            .starts_with("invalid time grid: not strictly increasing"),
        "{e}"
    );
    let e = solve_err(
        &[0.0, 1.0],
        &Options {
            rtol: -1.0,
            ..Options::default()
        },
    );
    assert_eq!(
        e.to_string(),
        "invalid integrator options: rtol = -1 must be finite and > 0"
    );
}

#[test]
fn output_is_called_once_per_grid_point_in_order() {
    let grid = uniform_grid(0.0, 2.0, 0.1);
    let y0 = vector![1.0];
    let mut seen = Vec::new();
    solve_grid(
        decay,
        &y0,
        &grid,
        &Options::default(),
        |i, t, y: &SVector<f64, 1>| seen.push((i, t, y[0])),
    )
    .unwrap();
    assert_eq!(seen.len(), grid.len());
    for (k, &(i, t, _)) in seen.iter().enumerate() {
        assert_eq!((i, t), (k, grid[k]));
    }
    assert_eq!(seen[0].2, 1.0);
    assert!((seen[grid.len() - 1].2 - (-2.0f64).exp()).abs() < 1e-3);
}
