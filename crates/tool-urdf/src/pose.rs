//! Rigid transforms and URDF's rotations.

use nalgebra::{Matrix3, Vector3};

/// A rigid transform: a point's coordinates in the child frame x map to `r · x + p` in the
/// parent's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pose {
    pub(crate) r: Matrix3<f64>,
    pub(crate) p: Vector3<f64>,
}

impl Pose {
    pub(crate) fn identity() -> Self {
        Pose {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// `self · child`.
    pub(crate) fn then(&self, child: &Pose) -> Pose {
        Pose {
            r: self.r * child.r,
            p: self.r * child.p + self.p,
        }
    }
}

/// URDF's rpy: fixed-axis roll about x, then pitch about y, then yaw about z,
/// R = Rz(yaw) Ry(pitch) Rx(roll).
pub fn rpy_matrix(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    rz * ry * rx
}

/// The rotation by `angle` about the unit `axis` (Rodrigues).
pub(crate) fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let k = Matrix3::new(
        0.0, -axis.z, axis.y, axis.z, 0.0, -axis.x, -axis.y, axis.x, 0.0,
    );
    let (s, c) = angle.sin_cos();
    Matrix3::identity() + k * s + k * k * (1.0 - c)
}
