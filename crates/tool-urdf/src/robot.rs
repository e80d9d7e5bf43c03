//! The URDF's links and joints as a tree: read from the XML with every rule of the file checked
//! (names given once, one parent per link, no loop, one root, joints' types, ends, axes, limits
//! and mimics), and the walks the merge needs (the subtree below the root, the flange above it).

use std::collections::{HashMap, HashSet};

use nalgebra::{Matrix3, Vector3};
use toolconf_messages::{Clip, Short};

use crate::pose::Pose;
use crate::source::{attribute, is, number, only_child, origin, triple, Source};
use crate::UrdfToolError;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Fixed,
    Revolute,
    Continuous,
    Prismatic,
    Floating,
    Planar,
}

impl Kind {
    pub(crate) fn movable(self) -> bool {
        matches!(self, Kind::Revolute | Kind::Continuous | Kind::Prismatic)
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Kind::Fixed => "fixed",
            Kind::Revolute => "revolute",
            Kind::Continuous => "continuous",
            Kind::Prismatic => "prismatic",
            Kind::Floating => "floating",
            Kind::Planar => "planar",
        }
    }
}

pub(crate) struct Inertial {
    pub(crate) mass: f64,
    /// The centre of mass and the inertia's axes in the link frame.
    pub(crate) origin: Pose,
    /// In the inertial frame's axes.
    pub(crate) inertia: Matrix3<f64>,
}

pub(crate) struct Link<'a, 'input> {
    pub(crate) name: &'a str,
    pub(crate) node: roxmltree::Node<'a, 'input>,
    pub(crate) inertial: Option<Inertial>,
}

pub(crate) struct Mimic<'a> {
    pub(crate) joint: &'a str,
    pub(crate) multiplier: f64,
    pub(crate) offset: f64,
}

pub(crate) struct Joint<'a, 'input> {
    pub(crate) name: &'a str,
    pub(crate) node: roxmltree::Node<'a, 'input>,
    pub(crate) kind: Kind,
    pub(crate) parent: usize,
    pub(crate) child: usize,
    pub(crate) origin: Pose,
    pub(crate) axis: Vector3<f64>,
    pub(crate) limit: Option<(f64, f64)>,
    pub(crate) mimic: Option<Mimic<'a>>,
}

pub(crate) struct Robot<'a, 'input> {
    pub(crate) links: Vec<Link<'a, 'input>>,
    pub(crate) link_index: HashMap<&'a str, usize>,
    pub(crate) joints: Vec<Joint<'a, 'input>>,
    pub(crate) joint_index: HashMap<&'a str, usize>,
    /// The joint whose child each link is.
    pub(crate) parent_joint: Vec<Option<usize>>,
    /// The joints whose parent each link is, in file order.
    pub(crate) child_joints: Vec<Vec<usize>>,
}

impl<'a, 'input> Robot<'a, 'input> {
    pub(crate) fn read(src: &Source<'a, 'input>) -> Result<Self, UrdfToolError> {
        let root = src.doc.root_element();
        if !is(&root, "robot") {
            return Err(src.at(
                root,
                format!(
                    "the top element is <{}>, not <robot>: not a URDF file",
                    Clip(root.tag_name().name())
                ),
            ));
        }
        let mut robot = Robot {
            links: Vec::new(),
            link_index: HashMap::new(),
            joints: Vec::new(),
            joint_index: HashMap::new(),
            parent_joint: Vec::new(),
            child_joints: Vec::new(),
        };
        robot.read_links(src, root)?;
        robot.read_joints(src, root)?;
        robot.check_tree(src)?;
        Ok(robot)
    }

    /// The `<link>` elements, each name once, with their inertials.
    fn read_links(
        &mut self,
        src: &Source<'a, 'input>,
        root: roxmltree::Node<'a, 'input>,
    ) -> Result<(), UrdfToolError> {
        for node in root.children().filter(|n| is(n, "link")) {
            let first = |i: usize| self.links[i].node;
            let (name, owner) = unique_name(src, node, "link", &self.link_index, first)?;
            let inertial = match only_child(src, node, &owner, "inertial")? {
                None => None,
                Some(inertial) => Some(read_inertial(src, inertial, &owner)?),
            };
            self.link_index.insert(name, self.links.len());
            self.links.push(Link {
                name,
                node,
                inertial,
            });
        }
        Ok(())
    }

    /// The `<joint>` elements, each name once, each link the child of at most one.
    fn read_joints(
        &mut self,
        src: &Source<'a, 'input>,
        root: roxmltree::Node<'a, 'input>,
    ) -> Result<(), UrdfToolError> {
        self.parent_joint = vec![None; self.links.len()];
        self.child_joints = vec![Vec::new(); self.links.len()];
        for node in root.children().filter(|n| is(n, "joint")) {
            let first = |i: usize| self.joints[i].node;
            let (name, owner) = unique_name(src, node, "joint", &self.joint_index, first)?;
            let joint = self.read_joint(src, node, name, &owner)?;
            let index = self.joints.len();
            if let Some(other) = self.parent_joint[joint.child] {
                return Err(src.at(
                    node,
                    format!(
                        "{owner}link '{}' has two parents: it is the child of joint '{}' \
                         (line {}) too",
                        Clip(self.links[joint.child].name),
                        Clip(self.joints[other].name),
                        src.line(self.joints[other].node)
                    ),
                ));
            }
            self.parent_joint[joint.child] = Some(index);
            self.child_joints[joint.parent].push(index);
            self.joint_index.insert(name, index);
            self.joints.push(joint);
        }
        Ok(())
    }

    /// The links form one tree, as the URDF specification (and urdfdom, and the derivation's
    /// reader) has them: no loop anywhere in the file, one root link.
    pub(crate) fn check_tree(&self, src: &Source) -> Result<(), UrdfToolError> {
        // Each link is walked up from once: `walk[l]` is 1 + the start of the walk that reached it.
        let mut done = vec![false; self.links.len()];
        let mut walk = vec![0usize; self.links.len()];
        for start in 0..self.links.len() {
            let mut walked: Vec<usize> = Vec::new();
            let mut link = start;
            while !done[link] {
                let Some(j) = self.parent_joint[link] else {
                    break;
                };
                if walk[link] == start + 1 {
                    let last = walked[walked.len() - 1];
                    let joint = self.parent_joint[last].expect("walked up");
                    return Err(self.loop_at(src, joint, link));
                }
                walk[link] = start + 1;
                walked.push(link);
                link = self.joints[j].parent;
            }
            for l in walked {
                done[l] = true;
            }
        }
        let roots: Vec<&str> = (0..self.links.len())
            .filter(|&l| self.parent_joint[l].is_none())
            .map(|l| self.links[l].name)
            .collect();
        if roots.len() != 1 {
            let mut shown: Vec<String> = roots
                .iter()
                .take(4)
                .map(|r| format!("'{}'", Clip(r)))
                .collect();
            if roots.len() > 4 {
                shown.push("...".into());
            }
            return Err(src.whole(format!(
                "{} root links ({}): a URDF's links form one tree with one root",
                roots.len(),
                shown.join(", ")
            )));
        }
        Ok(())
    }

    pub(crate) fn read_joint(
        &self,
        src: &Source<'a, 'input>,
        node: roxmltree::Node<'a, 'input>,
        name: &'a str,
        owner: &str,
    ) -> Result<Joint<'a, 'input>, UrdfToolError> {
        let kind = read_kind(src, node, owner)?;
        let end = |tag: &str| -> Result<usize, UrdfToolError> {
            let element = only_child(src, node, owner, tag)?
                .ok_or_else(|| src.at(node, format!("{owner}no <{tag}> link")))?;
            let link = attribute(src, element, owner, "link")?;
            self.link_index.get(link).copied().ok_or_else(|| {
                src.at(
                    element,
                    format!(
                        "{owner}<{tag}> link = '{}' is no link of the file",
                        Clip(link)
                    ),
                )
            })
        };
        let parent = end("parent")?;
        let child = end("child")?;
        if parent == child {
            return Err(src.at(
                node,
                format!(
                    "{owner}joins link '{}' to itself",
                    Clip(self.links[parent].name)
                ),
            ));
        }
        let origin = origin(src, only_child(src, node, owner, "origin")?, owner)?;
        let axis = read_axis(src, node, owner, kind)?;
        let limit = read_limit(src, node, owner, kind)?;
        let mimic = read_mimic(src, node, owner)?;
        Ok(Joint {
            name,
            node,
            kind,
            parent,
            child,
            origin,
            axis,
            limit,
            mimic,
        })
    }

    pub(crate) fn link(
        &self,
        src: &Source,
        flag: &str,
        name: &str,
    ) -> Result<usize, UrdfToolError> {
        self.link_index.get(name).copied().ok_or_else(|| {
            let mut names: Vec<&str> = self.links.iter().map(|l| l.name).take(6).collect();
            if self.links.len() > 6 {
                names.push("…");
            }
            src.whole(format!(
                "{flag} '{}' is no link of the file (its {} links: {})",
                Clip(name),
                self.links.len(),
                names
                    .iter()
                    .map(|n| Clip(n).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
    }

    /// Joint `joint` leading back to link `link`: the links form a loop.
    fn loop_at(&self, src: &Source, joint: usize, link: usize) -> UrdfToolError {
        let joint = &self.joints[joint];
        src.at(
            joint.node,
            format!(
                "joint '{}' leads back to link '{}': the links form a loop",
                Clip(joint.name),
                Clip(self.links[link].name)
            ),
        )
    }

    /// The root and the links below it, depth first in file order, each with the joint
    /// leading to it (None for the root); a loop back to a link already reached is refused.
    pub(crate) fn subtree(
        &self,
        src: &Source,
        root: usize,
    ) -> Result<Vec<(usize, Option<usize>)>, UrdfToolError> {
        let mut seen = vec![false; self.links.len()];
        let mut order = Vec::new();
        let mut stack = vec![(root, None)];
        while let Some((link, via)) = stack.pop() {
            if seen[link] {
                let joint = via.expect("the root is reached first");
                return Err(self.loop_at(src, joint, link));
            }
            seen[link] = true;
            order.push((link, via));
            for &j in self.child_joints[link].iter().rev() {
                stack.push((self.joints[j].child, Some(j)));
            }
        }
        Ok(order)
    }

    /// The flange's pose and the fixed joints from the flange down to the root.
    pub(crate) fn flange_to_root(
        &self,
        src: &Source,
        flange: usize,
        root: usize,
    ) -> Result<Pose, UrdfToolError> {
        let mut chain = Vec::new();
        let mut link = root;
        let mut seen = HashSet::new();
        while link != flange {
            if !seen.insert(link) {
                return Err(src.whole(format!(
                    "the links above '{}' form a loop, through link '{}'",
                    Clip(self.links[root].name),
                    Clip(self.links[link].name)
                )));
            }
            let Some(j) = self.parent_joint[link] else {
                return Err(src.whole(format!(
                    "--flange '{}' is not an ancestor of --root '{}'",
                    Clip(self.links[flange].name),
                    Clip(self.links[root].name)
                )));
            };
            chain.push(j);
            link = self.joints[j].parent;
        }
        let mut pose = Pose::identity();
        for &j in chain.iter().rev() {
            let joint = &self.joints[j];
            if joint.kind != Kind::Fixed {
                return Err(src.at(
                    joint.node,
                    format!(
                        "joint '{}' between --flange '{}' and --root '{}' is {}, not fixed: \
                         the tool would move on the flange",
                        Clip(joint.name),
                        Clip(self.links[flange].name),
                        Clip(self.links[root].name),
                        joint.kind.name()
                    ),
                ));
            }
            pose = pose.then(&joint.origin);
        }
        Ok(pose)
    }
}

pub(crate) fn read_inertial(
    src: &Source,
    node: roxmltree::Node,
    owner: &str,
) -> Result<Inertial, UrdfToolError> {
    let owner = format!("{owner}<inertial>");
    let origin = origin(src, only_child(src, node, &owner, "origin")?, &owner)?;
    let mass_node = only_child(src, node, &owner, "mass")?
        .ok_or_else(|| src.at(node, format!("{owner} has no <mass>")))?;
    let mass = number(src, mass_node, &owner, "value", None)?;
    if mass < 0.0 {
        return Err(src.at(
            mass_node,
            format!("{owner}<mass> value = {} is negative", Short(mass)),
        ));
    }
    let i = only_child(src, node, &owner, "inertia")?
        .ok_or_else(|| src.at(node, format!("{owner} has no <inertia>")))?;
    let get = |a: &str| number(src, i, &owner, a, None);
    let (ixx, iyy, izz) = (get("ixx")?, get("iyy")?, get("izz")?);
    let (ixy, ixz, iyz) = (get("ixy")?, get("ixz")?, get("iyz")?);
    Ok(Inertial {
        mass,
        origin,
        inertia: Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz),
    })
}

/// A joint's `type`.
fn read_kind(src: &Source, node: roxmltree::Node, owner: &str) -> Result<Kind, UrdfToolError> {
    Ok(match attribute(src, node, owner, "type")? {
        "fixed" => Kind::Fixed,
        "revolute" => Kind::Revolute,
        "continuous" => Kind::Continuous,
        "prismatic" => Kind::Prismatic,
        "floating" => Kind::Floating,
        "planar" => Kind::Planar,
        other => {
            return Err(src.at(
                node,
                format!(
                    "{owner}type = '{}' is not a URDF joint type (fixed, revolute, \
                         continuous, prismatic, floating, planar)",
                    Clip(other)
                ),
            ))
        }
    })
}

/// A joint's unit `<axis>` (default x); a movable joint's must have a direction.
fn read_axis(
    src: &Source,
    node: roxmltree::Node,
    owner: &str,
    kind: Kind,
) -> Result<Vector3<f64>, UrdfToolError> {
    Ok(match only_child(src, node, owner, "axis")? {
        None => Vector3::x(),
        Some(element) => {
            let axis = triple(src, element, owner, "xyz", [1.0, 0.0, 0.0])?;
            let norm = axis.norm();
            if kind.movable() && !(norm.is_finite() && norm > 1e-12) {
                return Err(src.at(
                    element,
                    format!(
                        "{owner}<axis> xyz = '{}' has no direction",
                        Clip(element.attribute("xyz").unwrap_or(""))
                    ),
                ));
            }
            if norm.is_finite() && norm > 1e-12 {
                axis / norm
            } else {
                Vector3::x()
            }
        }
    })
}

/// A joint's `<limit lower upper>`, required of a revolute or prismatic joint.
fn read_limit(
    src: &Source,
    node: roxmltree::Node,
    owner: &str,
    kind: Kind,
) -> Result<Option<(f64, f64)>, UrdfToolError> {
    Ok(match only_child(src, node, owner, "limit")? {
        // The URDF specification's rule (urdfdom's, the derivation reader's).
        None if matches!(kind, Kind::Revolute | Kind::Prismatic) => {
            return Err(src.at(
                node,
                format!(
                    "{owner}is {} and has no <limit> (the URDF specification requires one)",
                    kind.name()
                ),
            ))
        }
        None => None,
        // urdfdom's defaults for absent bounds.
        Some(element) => Some((
            number(src, element, owner, "lower", Some(0.0))?,
            number(src, element, owner, "upper", Some(0.0))?,
        )),
    })
}

/// A joint's `<mimic joint multiplier offset>`, if any.
fn read_mimic<'a>(
    src: &Source,
    node: roxmltree::Node<'a, '_>,
    owner: &str,
) -> Result<Option<Mimic<'a>>, UrdfToolError> {
    Ok(match only_child(src, node, owner, "mimic")? {
        None => None,
        Some(element) => Some(Mimic {
            joint: attribute(src, element, owner, "joint")?,
            multiplier: number(src, element, owner, "multiplier", Some(1.0))?,
            offset: number(src, element, owner, "offset", Some(0.0))?,
        }),
    })
}

/// The name of `node`, a `<kind>` element, and its owner prefix for later messages (`kind
/// 'name': `); refused when missing, or when `index` holds it already (`first` giving that
/// element's node, to name its line).
fn unique_name<'a, 'input>(
    src: &Source<'a, 'input>,
    node: roxmltree::Node<'a, 'input>,
    kind: &str,
    index: &HashMap<&'a str, usize>,
    first: impl Fn(usize) -> roxmltree::Node<'a, 'input>,
) -> Result<(&'a str, String), UrdfToolError> {
    let name = node
        .attribute("name")
        .ok_or_else(|| src.at(node, format!("a <{kind}> has no name attribute")))?;
    if let Some(&before) = index.get(name) {
        return Err(src.at(
            node,
            format!(
                "a second {kind} named '{}' (the first is on line {})",
                Clip(name),
                src.line(first(before))
            ),
        ));
    }
    Ok((name, format!("{kind} '{}': ", Clip(name))))
}
