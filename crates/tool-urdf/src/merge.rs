//! The merge: each link of the subtree placed in the flange frame, and the rigid bodies of the
//! massive ones composed into one (mass, centre of mass, inertia about it, tip).

use nalgebra::{Matrix3, Vector3};
use toolconf_messages::{Clip, Short};

use crate::pose::{axis_angle, Pose};
use crate::robot::{Kind, Robot};
use crate::source::Source;
use crate::{check_rigid_body, HeldJoint, Request, UrdfTool, UrdfToolError};

impl<'a, 'input> Robot<'a, 'input> {
    pub(crate) fn merge(&self, src: &Source, request: &Request) -> Result<UrdfTool, UrdfToolError> {
        let root = self.link(src, "--root", &request.root)?;
        let tip = self.link(src, "--tip", &request.tip)?;
        let flange = match &request.flange {
            Some(f) => self.link(src, "--flange", f)?,
            None => root,
        };
        let subtree = self.subtree(src, root)?;
        let mut below = vec![false; self.links.len()];
        for &(l, _) in &subtree {
            below[l] = true;
        }
        if !below[tip] {
            return Err(src.whole(format!(
                "--tip '{}' is not --root '{}' or a link below it",
                Clip(&request.tip),
                Clip(&request.root)
            )));
        }
        let flange_pose = self.flange_to_root(src, flange, root)?;
        let held = self.positions(src, request, root, &below)?;
        let pose = self.place(&subtree, root, flange_pose, &held);
        let tip_p = pose[tip].expect("the tip is below the root").p;
        let (mass, com, inertia) = self.compose(src, request, &subtree, &pose, &tip_p)?;
        let links = subtree
            .iter()
            .map(|&(l, _)| self.links[l].name.to_string())
            .collect();
        let held = subtree
            .iter()
            .filter_map(|&(_, via)| via)
            .filter_map(|j| {
                held[j].map(|q| HeldJoint {
                    name: self.joints[j].name.to_string(),
                    position: q,
                    mimics: self.joints[j].mimic.as_ref().map(|m| m.joint.to_string()),
                })
            })
            .collect();
        let rows = |m: Matrix3<f64>| {
            [
                [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
                [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
                [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
            ]
        };
        Ok(UrdfTool {
            mass,
            com: com.into(),
            inertia: rows(inertia),
            tip: tip_p.into(),
            links,
            held,
            flange: self.links[flange].name.to_string(),
        })
    }

    /// Each link's pose in the flange frame, parents before children (None outside the subtree).
    fn place(
        &self,
        subtree: &[(usize, Option<usize>)],
        root: usize,
        flange_pose: Pose,
        held: &[Option<f64>],
    ) -> Vec<Option<Pose>> {
        let mut pose = vec![None; self.links.len()];
        pose[root] = Some(flange_pose);
        for &(l, via) in subtree {
            let Some(j) = via else { continue };
            let joint = &self.joints[j];
            let parent: Pose = pose[joint.parent].expect("a parent before its children");
            let motion = match (joint.kind, held[j]) {
                (Kind::Revolute | Kind::Continuous, Some(q)) => Pose {
                    r: axis_angle(&joint.axis, q),
                    p: Vector3::zeros(),
                },
                (Kind::Prismatic, Some(q)) => Pose {
                    r: Matrix3::identity(),
                    p: joint.axis * q,
                },
                _ => Pose::identity(),
            };
            pose[l] = Some(parent.then(&joint.origin).then(&motion));
        }
        pose
    }

    /// The composite rigid body of the subtree's massive links: mass, centre of mass and the
    /// inertia about it in flange axes (parallel-axis theorem), checked finite (with the tip)
    /// and a rigid body's.
    fn compose(
        &self,
        src: &Source,
        request: &Request,
        subtree: &[(usize, Option<usize>)],
        pose: &[Option<Pose>],
        tip_p: &Vector3<f64>,
    ) -> Result<(f64, Vector3<f64>, Matrix3<f64>), UrdfToolError> {
        // Each massive link's mass, centre of mass and inertia about it, in flange axes.
        let mut bodies = Vec::new();
        for &(l, _) in subtree {
            if let Some(inertial) = &self.links[l].inertial {
                let frame = pose[l].expect("every link placed").then(&inertial.origin);
                bodies.push((
                    inertial.mass,
                    frame.p,
                    frame.r * inertial.inertia * frame.r.transpose(),
                ));
            }
        }
        let mass: f64 = bodies.iter().map(|b| b.0).sum();
        let root_name = Clip(&request.root);
        if mass.is_nan() || mass <= 0.0 {
            return Err(src.whole(format!(
                "the {} links at and below --root '{root_name}' have no mass (no <inertial> \
                 <mass> above 0)",
                subtree.len()
            )));
        }
        let com = bodies.iter().map(|b| b.1 * b.0).sum::<Vector3<f64>>() / mass;
        let mut inertia = Matrix3::zeros();
        for (m, c, i) in &bodies {
            let d = c - com;
            inertia += i + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * *m;
        }
        let inertia = (inertia + inertia.transpose()) * 0.5;
        let finite = mass.is_finite()
            && com.iter().all(|v| v.is_finite())
            && inertia.iter().all(|v| v.is_finite())
            && tip_p.iter().all(|v| v.is_finite());
        if !finite {
            return Err(src.whole(format!(
                "the links at and below --root '{root_name}' give a mass, centre of mass, \
                 inertia or tip that is not finite (mass {} kg): the file's numbers are too large",
                Short(mass)
            )));
        }
        check_rigid_body(&inertia).map_err(|why| {
            src.whole(format!(
                "the links at and below --root '{root_name}' merge to an inertia that {why}"
            ))
        })?;
        Ok((mass, com, inertia))
    }
}
