//! The positions the joints below the root are held at: given by name, the opening, or
//! followed from the joint a `<mimic>` names, each checked against its `<limit>`.

use std::collections::{HashMap, HashSet};

use toolconf_messages::{Clip, Short};

use crate::robot::{Kind, Robot};
use crate::source::Source;
use crate::{Request, UrdfToolError};

impl<'a, 'input> Robot<'a, 'input> {
    /// The held position of every joint of the subtree that moves (None for the others).
    pub(crate) fn positions(
        &self,
        src: &Source,
        request: &Request,
        root: usize,
        below: &[bool],
    ) -> Result<Vec<Option<f64>>, UrdfToolError> {
        let root_name = Clip(self.links[root].name);
        let mut given: HashMap<usize, f64> = HashMap::new();
        for (name, value) in &request.joints {
            let flag = format!("--joint {}={}", Clip(name), Short(*value));
            let &j = self
                .joint_index
                .get(name.as_str())
                .ok_or_else(|| src.whole(format!("{flag}: no joint of the file is named so")))?;
            let joint = &self.joints[j];
            if !value.is_finite() {
                return Err(src.whole(format!("{flag}: the position is not finite")));
            }
            if !below[joint.parent] {
                return Err(src.whole(format!(
                    "{flag}: joint '{}' is not below --root '{root_name}'",
                    Clip(name)
                )));
            }
            if !joint.kind.movable() {
                return Err(src.whole(format!(
                    "{flag}: joint '{}' is {}, it has no position to hold",
                    Clip(name),
                    joint.kind.name()
                )));
            }
            if let Some(m) = &joint.mimic {
                return Err(src.whole(format!(
                    "{flag}: joint '{}' mimics joint '{}': give the position of '{}'",
                    Clip(name),
                    Clip(m.joint),
                    Clip(m.joint)
                )));
            }
            if given.insert(j, *value).is_some() {
                return Err(src.whole(format!("{flag}: joint '{}' is given twice", Clip(name))));
            }
        }
        if let Some(o) = request.opening {
            if !o.is_finite() {
                return Err(src.whole(format!("--opening {}: not finite", Short(o))));
            }
        }
        let mut held = vec![None; self.joints.len()];
        for (j, joint) in self.joints.iter().enumerate() {
            if !below[joint.parent] || joint.kind == Kind::Fixed {
                continue;
            }
            if !joint.kind.movable() {
                return Err(src.at(
                    joint.node,
                    format!(
                        "joint '{}' below --root '{root_name}' is {}: a tool's joints must be \
                         fixed, revolute, continuous or prismatic to be held at a position",
                        Clip(joint.name),
                        joint.kind.name()
                    ),
                ));
            }
            held[j] = Some(self.held_position(src, request, &given, below, j)?);
        }
        Ok(held)
    }

    /// Joint `j`'s position: given, the opening, or its mimicked joint's (followed through
    /// chains of mimics, a loop refused), then checked against its limits.
    pub(crate) fn held_position(
        &self,
        src: &Source,
        request: &Request,
        given: &HashMap<usize, f64>,
        below: &[bool],
        j: usize,
    ) -> Result<f64, UrdfToolError> {
        let chain = self.mimic_chain(src, request, below, j)?;
        let source = *chain.last().unwrap();
        let mut value = match given.get(&source).copied().or(request.opening) {
            Some(v) => v,
            None => {
                let joint = &self.joints[source];
                return Err(src.at(
                    joint.node,
                    format!(
                        "joint '{}' is {} and has no position: give --opening VALUE or \
                         --joint {}=VALUE",
                        Clip(joint.name),
                        joint.kind.name(),
                        Clip(joint.name)
                    ),
                ));
            }
        };
        // Down the chain: each mimic follows the one it mimics.
        for &k in chain.iter().rev() {
            let joint = &self.joints[k];
            if k != source {
                let m = joint.mimic.as_ref().expect("a mimic in the chain");
                value = m.multiplier * value + m.offset;
                if !value.is_finite() {
                    return Err(src.at(
                        joint.node,
                        format!(
                            "joint '{}': its <mimic> position is not finite",
                            Clip(joint.name)
                        ),
                    ));
                }
            }
            self.check_limit(src, k, value)?;
        }
        Ok(value)
    }

    /// The chain of mimics from joint `j` to a joint that mimics none (`j` first), each
    /// mimicked joint movable and below the root, a loop refused.
    fn mimic_chain(
        &self,
        src: &Source,
        request: &Request,
        below: &[bool],
        j: usize,
    ) -> Result<Vec<usize>, UrdfToolError> {
        let mut chain = vec![j];
        let mut seen = HashSet::from([j]);
        loop {
            let joint = &self.joints[*chain.last().unwrap()];
            let Some(m) = &joint.mimic else { break };
            let &k = self.joint_index.get(m.joint).ok_or_else(|| {
                src.at(
                    joint.node,
                    format!(
                        "joint '{}': <mimic> joint = '{}' is no joint of the file",
                        Clip(joint.name),
                        Clip(m.joint)
                    ),
                )
            })?;
            let mimicked = &self.joints[k];
            if !mimicked.kind.movable() {
                return Err(src.at(
                    joint.node,
                    format!(
                        "joint '{}' mimics joint '{}', which is {}",
                        Clip(joint.name),
                        Clip(m.joint),
                        mimicked.kind.name()
                    ),
                ));
            }
            if !below[mimicked.parent] {
                return Err(src.at(
                    joint.node,
                    format!(
                        "joint '{}' mimics joint '{}', which is not below --root '{}'",
                        Clip(joint.name),
                        Clip(m.joint),
                        Clip(&request.root)
                    ),
                ));
            }
            if !seen.insert(k) {
                return Err(src.at(
                    joint.node,
                    format!(
                        "joint '{}': the <mimic> joints form a loop through '{}'",
                        Clip(self.joints[j].name),
                        Clip(m.joint)
                    ),
                ));
            }
            chain.push(k);
        }
        Ok(chain)
    }

    pub(crate) fn check_limit(
        &self,
        src: &Source,
        j: usize,
        value: f64,
    ) -> Result<(), UrdfToolError> {
        let joint = &self.joints[j];
        if joint.kind == Kind::Continuous {
            return Ok(());
        }
        let Some((lower, upper)) = joint.limit else {
            return Err(src.at(
                joint.node,
                format!(
                    "joint '{}' is {} and has no <limit>",
                    Clip(joint.name),
                    joint.kind.name()
                ),
            ));
        };
        if !(lower <= value && value <= upper) {
            let unit = if joint.kind == Kind::Prismatic {
                "m"
            } else {
                "rad"
            };
            return Err(src.at(
                joint.node,
                format!(
                    "joint '{}': position {} {unit} is outside its limits [{}, {}]",
                    Clip(joint.name),
                    Short(value),
                    Short(lower),
                    Short(upper)
                ),
            ));
        }
        Ok(())
    }
}
