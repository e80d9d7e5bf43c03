//! Hairer's stiffness detection for Dormand–Prince 5(4), as in `DOPRI5` (Hairer, Nørsett &
//! Wanner, "Solving ODEs I", §II.10, and "Solving ODEs II", §IV.2).
//!
//! Stages 6 and 7 of the Dormand–Prince tableau are both evaluated at `t + h`, at the points
//! `y6` and `y7 = y_new`, so `‖k7 − k6‖ / ‖y7 − y6‖` estimates the dominant eigenvalue |λ| of
//! ∂f/∂y along the step. DP5's stability region meets the negative real axis near −3.3, so an
//! `h·|λ|` near that boundary means the step size is limited by stability, not accuracy: the
//! problem is stiff there. As in `DOPRI5`, the problem is declared stiff when `h·|λ| > 3.25` on
//! 15 accepted steps, with the count reset by 6 consecutive steps below that bound.

use nalgebra::SVector;

/// `h·|λ|` above this is taken as a step at DP5's stability boundary (`DOPRI5`: 3.25).
const STABILITY_BOUND: f64 = 3.25;
/// Steps at the boundary before the problem is declared stiff (`DOPRI5`: 15).
const STIFF_STEPS: u32 = 15;
/// Steps at the boundary before [`super::Method::Fast`] hands over to Rodas5P: chosen on
/// `draw_tools(2000, 1)` by the work model of `docs/explanation/performance-population.md` (patience 3, 6, 10, 15:
/// task 1 favours the shorter, task 2 the longer; 10 is within 5 % of the best of both).
pub(super) const FAST_STIFF_STEPS: u32 = 10;
/// Consecutive steps inside the boundary that clear the count (`DOPRI5`: 6).
const NONSTIFF_STEPS: u32 = 6;

/// The counters of `DOPRI5`'s test (`IASTI`, `NONSTI`, `HLAMB`).
#[derive(Debug, Clone, Copy)]
pub(super) struct StiffnessDetector {
    /// Steps at the boundary before the problem is declared stiff ([`STIFF_STEPS`] by default).
    patience: u32,
    stiff: u32,
    nonstiff: u32,
    h_lambda: f64,
}

impl Default for StiffnessDetector {
    fn default() -> Self {
        Self::with_patience(STIFF_STEPS)
    }
}

impl StiffnessDetector {
    /// A detector that fires after `patience` steps at the boundary instead of `DOPRI5`'s 15.
    pub(super) fn with_patience(patience: u32) -> Self {
        Self {
            patience,
            stiff: 0,
            nonstiff: 0,
            h_lambda: 0.0,
        }
    }

    /// Looks at one accepted DP5 step of size `h` (with stage 6 `k6 = f(t + h, y6)` and the FSAL
    /// stage `k7 = f(t + h, y7)`) and says whether the problem is now declared stiff.
    pub(super) fn stiff_after<const D: usize>(
        &mut self,
        h: f64,
        y6: &SVector<f64, D>,
        y7: &SVector<f64, D>,
        k6: &SVector<f64, D>,
        k7: &SVector<f64, D>,
    ) -> bool {
        let num = (k7 - k6).norm_squared();
        let den = (y7 - y6).norm_squared();
        // DOPRI5 keeps the previous estimate when y7 = y6 (e.g. f constant along the step).
        if den > 0.0 {
            self.h_lambda = h.abs() * (num / den).sqrt();
        }
        if self.h_lambda > STABILITY_BOUND {
            self.nonstiff = 0;
            self.stiff += 1;
            self.stiff >= self.patience
        } else {
            self.nonstiff += 1;
            if self.nonstiff == NONSTIFF_STEPS {
                self.stiff = 0;
            }
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::vector;

    #[test]
    fn fires_after_fifteen_boundary_steps_and_resets_after_six_inside() {
        let mut d = StiffnessDetector::default();
        let (y6, y7) = (vector![0.0], vector![1.0]);
        let (k6, k7) = (vector![0.0], vector![-100.0]);
        // h·|λ| = 0.04·100 = 4 > 3.25.
        for _ in 0..14 {
            assert!(!d.stiff_after(0.04, &y6, &y7, &k6, &k7));
        }
        // Five steps inside the boundary do not clear the count, the sixth does.
        for _ in 0..5 {
            assert!(!d.stiff_after(0.01, &y6, &y7, &k6, &k7));
        }
        assert!(d.stiff_after(0.04, &y6, &y7, &k6, &k7));

        let mut d = StiffnessDetector::default();
        for _ in 0..14 {
            assert!(!d.stiff_after(0.04, &y6, &y7, &k6, &k7));
        }
        for _ in 0..6 {
            assert!(!d.stiff_after(0.01, &y6, &y7, &k6, &k7));
        }
        for _ in 0..14 {
            assert!(!d.stiff_after(0.04, &y6, &y7, &k6, &k7));
        }
        assert!(d.stiff_after(0.04, &y6, &y7, &k6, &k7));
    }

    #[test]
    fn identical_stage_points_keep_the_previous_estimate() {
        let mut d = StiffnessDetector::default();
        let y = vector![2.0, 3.0];
        let k = vector![1.0, 1.0];
        for _ in 0..20 {
            assert!(!d.stiff_after(1.0, &y, &y, &k, &k));
        }
    }
}
