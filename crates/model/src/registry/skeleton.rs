//! The arm's joint axes and flange frame along a motion, from the model's own tip kinematics
//! ([`Model::tip`](super::Model::tip)): what a 3-D view draws the arm by.
//!
//! A model with a tool at a URDF flange (parameters `tool_tip_x/y/z`, the tip's offset in the
//! flange frame) has y(q; t) = o_f(q) + R_f(q) t, with the geometric Jacobian's column of a
//! revolute joint i J_i = z_i × (y − o_i). So, with no second derivation of the kinematics:
//!
//! - the flange: o_f = y(q; 0) and R_f's column k = (y(q; s e_k) − o_f) / s;
//! - joint i's axis direction: (J_i(s e_k) − J_i(0)) / s = z_i × R_f e_k, i.e. [z_i]× = D Rᵀ_f;
//! - a point on joint i's axis: J_i(0) = z_i × (o_f − o_i), so o_f − J_i(0) × z_i lies on it
//!   (the axis point nearest the flange).

use nalgebra::{Matrix3, Vector3};

use super::{ModelKind, Rows};

/// The tip offset's parameters: a model whose tools have them has a flange frame.
const TIP_OFFSET: [&str; 3] = ["tool_tip_x", "tool_tip_y", "tool_tip_z"];

/// The probe offsets' length s (m): short enough for any tool rule, long enough that
/// differences keep ~12 digits.
const PROBE: f64 = 0.01;

/// One joint's axis in the base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointAxis {
    /// The point of the axis nearest the flange's origin.
    pub point: Vector3<f64>,
    /// The unit direction z_i (zero for a joint that is not revolute).
    pub direction: Vector3<f64>,
}

/// The arm at one instant, in the base frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmPose {
    pub axes: Vec<JointAxis>,
    pub flange: Vector3<f64>,
    /// The flange frame's axes as columns: a flange-frame vector v is `flange_axes · v`.
    pub flange_axes: Matrix3<f64>,
}

/// The indices of `model`'s tip offset parameters, if its tools sit at a URDF flange.
pub fn tip_offset_parameters(model: ModelKind) -> Option<[usize; 3]> {
    let names = model.parameter_names();
    let mut found = [0; 3];
    for (slot, name) in found.iter_mut().zip(TIP_OFFSET) {
        *slot = names.iter().position(|n| *n == name)?;
    }
    Some(found)
}

/// The arm's pose at each row of `q` (one row of N joint angles per instant) with the tool
/// `params`, or why there is none (a model without a flange frame, a bad tool or state).
pub fn arm_poses(model: ModelKind, params: &[f64], q: &[Vec<f64>]) -> Result<Vec<ArmPose>, String> {
    let offsets = tip_offset_parameters(model)
        .ok_or_else(|| format!("model {model} has no tool at a URDF flange (no tool_tip_x/y/z)"))?;
    let n = model.info().dof;
    if let Some(row) = q.iter().find(|row| row.len() != n) {
        return Err(format!("a state has {} joint angles, not {n}", row.len()));
    }
    let k = q.len();
    let flat: Vec<f64> = q.iter().flatten().copied().collect();
    // The tip and its Jacobian with the tip at the flange, then moved by s along each axis.
    let probes: Vec<(Vec<f64>, Vec<f64>)> = (0..4)
        .map(|probe| {
            let mut p = params.to_vec();
            for (axis, &i) in offsets.iter().enumerate() {
                p[i] = if probe == axis + 1 { PROBE } else { 0.0 };
            }
            let (mut y, mut jac) = (vec![0.0; 3 * k], vec![0.0; 3 * n * k]);
            let rows = |data, width| Rows {
                data,
                width,
                shared: false,
            };
            let params = Rows {
                data: &p,
                width: p.len(),
                shared: true,
            };
            model
                .model()
                .tip(k, &params, &rows(&flat, n), &mut y, &mut jac)
                .map(|()| (y, jac))
                .map_err(|e| format!("{e:?}"))
        })
        .collect::<Result<_, _>>()?;
    Ok((0..k).map(|i| pose(&probes, i, n)).collect())
}

/// Instant `i`'s pose from the four probes' tips and Jacobians.
fn pose(probes: &[(Vec<f64>, Vec<f64>)], i: usize, n: usize) -> ArmPose {
    let tip = |p: usize| Vector3::from_column_slice(&probes[p].0[3 * i..3 * i + 3]);
    let column = |p: usize, j: usize| {
        let jac = &probes[p].1[3 * n * i..3 * n * (i + 1)];
        Vector3::new(jac[j], jac[n + j], jac[2 * n + j])
    };
    let flange = tip(0);
    let flange_axes = Matrix3::from_columns(&[1, 2, 3].map(|p| (tip(p) - flange) / PROBE));
    let axes = (0..n)
        .map(|j| {
            let d =
                Matrix3::from_columns(&[1, 2, 3].map(|p| (column(p, j) - column(0, j)) / PROBE));
            let s = d * flange_axes.transpose();
            let z = 0.5
                * Vector3::new(
                    s[(2, 1)] - s[(1, 2)],
                    s[(0, 2)] - s[(2, 0)],
                    s[(1, 0)] - s[(0, 1)],
                );
            let direction = if z.norm() > 0.5 {
                z.normalize()
            } else {
                Vector3::zeros()
            };
            JointAxis {
                point: flange - column(0, j).cross(&direction),
                direction,
            }
        })
        .collect();
    ArmPose {
        axes,
        flange,
        flange_axes,
    }
}

impl ArmPose {
    /// A point per joint to draw the links between: on each axis, the foot of its common
    /// perpendicular with the next axis (as Denavit–Hartenberg frames place them); where the two
    /// are parallel, or for the last joint, the point nearest the one before (the base's origin
    /// before the first).
    pub fn link_points(&self) -> Vec<Vector3<f64>> {
        let mut points: Vec<Vector3<f64>> = Vec::with_capacity(self.axes.len());
        for (j, axis) in self.axes.iter().enumerate() {
            let before = points.last().copied().unwrap_or_else(Vector3::zeros);
            let next = self.axes.get(j + 1).filter(|_| axis.direction.norm() > 0.0);
            let point = next
                .and_then(|b| foot_towards(axis, b))
                .unwrap_or_else(|| nearest_on(axis, &before));
            points.push(point);
        }
        points
    }
}

/// The point of `axis` nearest `p` (`p`'s projection; the axis point for a non-revolute joint).
fn nearest_on(axis: &JointAxis, p: &Vector3<f64>) -> Vector3<f64> {
    axis.point + axis.direction * axis.direction.dot(&(p - axis.point))
}

/// The foot on `a` of the common perpendicular of the lines `a` and `b`, unless they are
/// (nearly) parallel.
fn foot_towards(a: &JointAxis, b: &JointAxis) -> Option<Vector3<f64>> {
    let (u, v, w) = (a.direction, b.direction, a.point - b.point);
    let c = u.dot(&v);
    let denominator = 1.0 - c * c;
    if denominator < 1e-9 {
        return None;
    }
    let s = (c * v.dot(&w) - u.dot(&w)) / denominator;
    Some(a.point + u * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Panda's joint origins at q = 0, from its URDF's offsets by hand (metres): each on its
    /// joint's axis, and each the foot of the common perpendicular to the next axis.
    const PANDA_POINTS_AT_ZERO: [[f64; 3]; 7] = [
        [0.0, 0.0, 0.333],
        [0.0, 0.0, 0.333],
        [0.0, 0.0, 0.649],
        [0.0825, 0.0, 0.649],
        [0.0, 0.0, 1.033],
        [0.0, 0.0, 1.033],
        [0.088, 0.0, 1.033],
    ];

    /// The Panda at q = 0, against its URDF (derive/robots/panda_description/urdf/panda.urdf)
    /// composed by hand: joint origins z 0.333, 0.333 + 0.316, x 0.0825, z + 0.384, x 0.088;
    /// frames turned by ±90° about x; the flange 0.107 along joint 7's axis, which points down.
    #[test]
    fn the_pandas_axes_and_flange_at_zero_are_its_urdfs() {
        let panda = super::super::lookup("panda").unwrap();
        let tool = [
            1.0, 0.0, 0.0, 0.05, 0.01, 0.01, 0.01, 0.0, 0.0, 0.0, 0.02, -0.01, 0.1,
        ];
        let pose = &arm_poses(panda, &tool, &[vec![0.0; 7]]).unwrap()[0];
        let origins = PANDA_POINTS_AT_ZERO;
        let directions = [
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, -1.0],
        ];
        for (j, axis) in pose.axes.iter().enumerate() {
            let z = Vector3::from(directions[j]);
            assert!(
                (axis.direction - z).norm() < 1e-9,
                "joint {}: {:?}",
                j + 1,
                axis.direction
            );
            // The URDF's joint origin lies on the recovered axis line.
            let off = (Vector3::from(origins[j]) - axis.point).cross(&z).norm();
            assert!(off < 1e-9, "joint {}: origin {off} m off the axis", j + 1);
        }
        assert!((pose.flange - Vector3::new(0.088, 0.0, 0.926)).norm() < 1e-9);
        let down = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
        assert!(
            (pose.flange_axes - down).norm() < 1e-9,
            "{}",
            pose.flange_axes
        );
        // The tool's own tip, y(q; p) from the registry, is the flange frame's image of its offset.
        let (mut y, mut jac) = ([0.0; 3], [0.0; 21]);
        fn row(data: &[f64]) -> Rows<'_> {
            Rows {
                data,
                width: data.len(),
                shared: true,
            }
        }
        panda
            .model()
            .tip(1, &row(&tool), &row(&[0.0; 7]), &mut y, &mut jac)
            .unwrap();
        let offset = Vector3::new(0.02, -0.01, 0.1);
        assert!((pose.flange + pose.flange_axes * offset - Vector3::from(y)).norm() < 1e-12);
    }

    /// The link points of the Panda at zero: the feet of the common perpendiculars, which the
    /// URDF's offsets place at these heights.
    #[test]
    fn the_pandas_link_points_at_zero() {
        let panda = super::super::lookup("panda").unwrap();
        let tool = [
            1.0, 0.0, 0.0, 0.05, 0.01, 0.01, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1,
        ];
        let points = arm_poses(panda, &tool, &[vec![0.0; 7]]).unwrap()[0].link_points();
        let expected = PANDA_POINTS_AT_ZERO;
        for (j, p) in points.iter().enumerate() {
            assert!(
                (p - Vector3::from(expected[j])).norm() < 1e-9,
                "joint {}: {p}",
                j + 1
            );
        }
    }

    #[test]
    fn a_planar_arm_has_no_flange_frame() {
        let arm2 = super::super::lookup("arm2").unwrap();
        let e = arm_poses(arm2, &[1.0; 6], &[vec![0.0; 2]]).unwrap_err();
        assert!(e.contains("no tool at a URDF flange"), "{e}");
    }
}
