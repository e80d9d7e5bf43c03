//! One episode as the view draws it: per output time, the arm's link points and joint axes, the
//! flange frame and the tip ([`toolconf_model::registry::skeleton`]); once, the tool's inertia box.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde_json::{json, Value};
use toolconf::rank::TaskTrace;
use toolconf_model::registry::skeleton::{arm_poses, tip_offset_parameters};
use toolconf_model::registry::AnyTool;

/// Numbers per joint per frame: the link point (3) and the axis direction (3).
const PER_JOINT: usize = 6;
/// Numbers per frame besides the joints: the flange's origin (3), its axes (9, column major),
/// the tip (3).
const PER_FRAME: usize = 15;

/// The box of uniform density with the tool's mass and principal moments, in the flange frame:
/// sides a_k = √(6 (I_1 + I_2 + I_3 − 2 I_k) / m) along the principal axes (a box's
/// I_1 = m (a_2² + a_3²) / 12), centred on the centre of mass.
pub struct InertiaBox {
    pub centre: Vector3<f64>,
    /// The principal axes as columns (a right-handed frame).
    pub axes: Matrix3<f64>,
    pub sides: Vector3<f64>,
}

/// The inertia box of `tool`, if its model names mass, centre of mass and inertia tensor.
pub fn inertia_box(tool: &AnyTool) -> Option<InertiaBox> {
    let names = tool.model().parameter_names();
    let value = |name: &str| {
        let i = names.iter().position(|n| *n == name)?;
        Some(tool.parameters()[i])
    };
    let or_zero = |name: &str| value(name).unwrap_or(0.0);
    let mass = value("tool_mass")?;
    let centre = Vector3::new(
        value("tool_com_x")?,
        value("tool_com_y")?,
        value("tool_com_z")?,
    );
    let (ixy, ixz, iyz) = (
        or_zero("tool_ixy"),
        or_zero("tool_ixz"),
        or_zero("tool_iyz"),
    );
    let inertia = Matrix3::new(
        value("tool_ixx")?,
        ixy,
        ixz,
        ixy,
        value("tool_iyy")?,
        iyz,
        ixz,
        iyz,
        value("tool_izz")?,
    );
    let eigen = SymmetricEigen::new(inertia);
    let total = eigen.eigenvalues.sum();
    let sides = eigen
        .eigenvalues
        .map(|moment| (6.0 * (total - 2.0 * moment).max(0.0) / mass).sqrt());
    let mut axes = eigen.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.column_mut(2).neg_mut();
    }
    Some(InertiaBox {
        centre,
        axes,
        sides,
    })
}

/// A number as the page gets it: 0.1 mm is finer than a pixel of the view.
fn round(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

/// The episode of `tool` whose trace is `trace`, as the page's JSON: its label, output times,
/// frames (flat, `stride` numbers each) and inertia box; or why it cannot be drawn.
pub fn episode(label: &str, tool: &AnyTool, trace: &TaskTrace) -> Result<Value, String> {
    let frames = trace.t.len();
    let q: Vec<Vec<f64>> = (0..frames)
        .map(|i| trace.joints.iter().map(|joint| joint[i]).collect())
        .collect();
    let poses = arm_poses(tool.model(), tool.parameters(), &q)?;
    let offsets = tip_offset_parameters(tool.model()).ok_or("the model has no tip offset")?;
    let tip = Vector3::from(offsets.map(|i| tool.parameters()[i]));
    let joints = trace.joints.len();
    let mut data: Vec<f64> = Vec::with_capacity(frames * (PER_JOINT * joints + PER_FRAME));
    for pose in &poses {
        for (point, axis) in pose.link_points().iter().zip(&pose.axes) {
            data.extend(point.iter().chain(axis.direction.iter()));
        }
        data.extend(pose.flange.iter().chain(pose.flange_axes.iter()));
        data.extend((pose.flange + pose.flange_axes * tip).iter());
    }
    if let Some(bad) = data.iter().find(|v| !v.is_finite()) {
        return Err(format!("the arm's pose is not finite ({bad})"));
    }
    let tool_box = inertia_box(tool).map(|b| {
        json!({
            "centre": b.centre.iter().copied().map(round).collect::<Vec<_>>(),
            "axes": b.axes.iter().map(|v| (v * 1e6).round() / 1e6).collect::<Vec<_>>(),
            "sides": b.sides.iter().copied().map(round).collect::<Vec<_>>(),
        })
    });
    Ok(json!({
        "label": label,
        "joints": joints,
        "stride": PER_JOINT * joints + PER_FRAME,
        "t": trace.t.iter().copied().map(round).collect::<Vec<_>>(),
        "frames": data.into_iter().map(round).collect::<Vec<_>>(),
        "tip_offset": tip.iter().copied().map(round).collect::<Vec<_>>(),
        "box": tool_box,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box of sides (a, b, c) and mass m has I = m/12 (b² + c², a² + c², a² + b²): its moments,
    /// turned by a rotation R (I' = R I Rᵀ), give back the sides along R's columns.
    #[test]
    fn the_inertia_box_of_a_turned_box_is_that_box() {
        let (m, a, b, c) = (2.0, 0.3, 0.1, 0.05);
        let principal = Matrix3::from_diagonal(&Vector3::new(
            m / 12.0 * (b * b + c * c),
            m / 12.0 * (a * a + c * c),
            m / 12.0 * (a * a + b * b),
        ));
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.7).into_inner();
        let i = r * principal * r.transpose();
        let panda = toolconf_model::registry::lookup("panda").unwrap();
        let params = [
            m,
            0.01,
            -0.02,
            0.1,
            i[(0, 0)],
            i[(1, 1)],
            i[(2, 2)],
            i[(0, 1)],
            i[(0, 2)],
            i[(1, 2)],
            0.0,
            0.0,
            0.2,
        ];
        let tool = AnyTool::new(panda, &params).unwrap();
        let got = inertia_box(&tool).unwrap();
        assert!((got.centre - Vector3::new(0.01, -0.02, 0.1)).norm() < 1e-15);
        for (k, side) in [a, b, c].into_iter().enumerate() {
            // The side along R's column k is the box's extent along that direction.
            let along = r.column(k);
            let extent: f64 = (0..3)
                .map(|j| got.sides[j] * got.axes.column(j).dot(&along).abs())
                .sum();
            assert!((extent - side).abs() < 1e-9, "side {k}: {extent} vs {side}");
        }
        assert!((got.axes.determinant() - 1.0).abs() < 1e-9);
    }
}
