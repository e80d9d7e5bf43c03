//! A tool's row of a tools file from the tool's own URDF (`toolconf tool --urdf FILE --root LINK
//! --tip LINK`, `toolconf.tool_from_urdf`): mass, centre of mass, full rotational inertia and
//! tool-centre point, in the flange frame.
//!
//! **What is merged.** The rigid bodies of the root link and of every link below it (the subtree
//! the joints' `<parent>`/`<child>` make). Fixed joints are rigid; a revolute, continuous or
//! prismatic joint is held at a stated position: the request's `joints` (`--joint NAME=VALUE`)
//! for that joint, else `opening` (`--opening VALUE`) for every one-axis joint that is not a
//! `<mimic>`; a mimic joint follows `multiplier · value + offset` of the joint it mimics (the
//! Franka Hand's `panda_finger_joint2` mimics `panda_finger_joint1`). A held position outside
//! a revolute or prismatic joint's `<limit lower upper>` (an absent bound 0, the URDF
//! specification's default) is refused; a floating or planar joint below the root is refused (it
//! has no one position).
//!
//! **Frames and conventions** (the URDF specification's, as urdfdom and Pinocchio read it). A
//! joint places its child link at `parent · origin(xyz, rpy) · motion(q)`, the motion a rotation
//! by q about the unit `<axis>` (revolute, continuous) or a translation q · axis (prismatic), the
//! axis in the joint's frame, normalised (default `1 0 0`). `rpy` is fixed-axis roll, pitch,
//! yaw: R = Rz(yaw) · Ry(pitch) · Rx(roll). A link's `<inertial>` has its centre of mass at its
//! `<origin xyz>` and its `<inertia>` in the axes of that origin's `rpy`, so in link axes it is
//! R I Rᵀ; a link without `<inertial>` is massless. The composite's rotational inertia is taken
//! about the composite centre of mass (parallel-axis theorem, I = Σ Iᵢ + mᵢ(|dᵢ|² E − dᵢdᵢᵀ),
//! dᵢ from the composite centre of mass to link i's), in the flange's axes; `tool_ixy` is the
//! matrix entry I[0][1], as URDF's `<inertia ixy>` is. The flange frame is the root link's, or
//! with `flange` an ancestor link's, reached from the root through fixed joints only. The tip is
//! the origin of the `tip` link, which must be the root or below it, in the flange frame.
//!
//! **The result is checked**: mass > 0, every number finite, the inertia positive definite
//! (smallest principal moment above 1e-12 of the largest) and its principal moments obeying the
//! triangle inequality (each at most the sum of the other two, within 1e-9 of their sum, the
//! slack printed decimals need). Anything else, and every flaw of the file (not XML, no
//! `<robot>`, a link or joint named twice, a link with two parents, a loop or a second root
//! link anywhere in the file, a revolute or prismatic joint without `<limit>`, a joint naming a
//! link that is not there, a number that is not an ASCII decimal or not finite, an `xyz` or
//! `rpy` of other than three numbers, a negative mass), is one line naming the file, the line of
//! the element, the link or joint and the value ([`UrdfToolError`]). The file rules are the
//! derivation's reader's too (derive/toolconf_derive/urdf.py): both are tested on one corpus,
//! tests/fixtures/urdf/ (tests/urdf_corpus.rs, derive/tests/test_urdf_corpus.py). The file is
//! opened without blocking and must be a regular file (a FIFO with no writer is refused).
//!
//! **Why roxmltree.** The XML is read with `roxmltree` (a small, widely used read-only XML tree
//! with no dependencies but memchr, already the runtime's): it keeps every node's byte range, so
//! a message names the line of the element at fault, it refuses DTDs (no entity expansion
//! bombs) and takes a node limit, and it parses without recursion. `urdf-rs` was the other
//! candidate: its serde-derived reader fills missing attributes with defaults without saying
//! so, rejects nothing it does not model, and its errors are serde-xml's, which name neither the
//! link nor the line; what this module needs of URDF (links, joints, inertials, origins, axes,
//! limits, mimics) is small enough to read by hand from the tree, with every check ours.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::path::Path;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::display::{Clip, ClipMessage, ClipPath, Short};

/// The largest URDF read: a tool's description is kilobytes (the Panda's with its hand is
/// 15 kB); a whole robot's with inline comments rarely reaches a megabyte.
pub const MAX_URDF_BYTES: u64 = 8 << 20;

/// The most XML nodes a file may have (elements, attributes' owners, text): far above any
/// robot's, and a bound on the tree's memory whatever the file.
const MAX_XML_NODES: u32 = 1 << 22;

/// The columns of the row, in order.
pub const COLUMNS: [&str; 15] = [
    "name",
    "model",
    "tool_mass",
    "tool_com_x",
    "tool_com_y",
    "tool_com_z",
    "tool_ixx",
    "tool_iyy",
    "tool_izz",
    "tool_ixy",
    "tool_ixz",
    "tool_iyz",
    "tool_tip_x",
    "tool_tip_y",
    "tool_tip_z",
];

/// Relative slack of the triangle inequality of the principal moments (printed decimals).
pub const TRIANGLE_SLACK: f64 = 1e-9;

/// The smallest principal moment, relative to the largest, of a positive definite inertia.
pub const DEFINITE_RATIO: f64 = 1e-12;

/// What to merge and where: the links, the frame, the held joint positions.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Request {
    /// The tool's root link: it and every link below it are merged.
    pub root: String,
    /// The link whose origin is the tool-centre point.
    pub tip: String,
    /// An ancestor link of the root whose frame is the flange frame (None: the root's).
    pub flange: Option<String>,
    /// The position of every one-axis joint below the root that is not a mimic and not in
    /// `joints` (m or rad).
    pub opening: Option<f64>,
    /// Positions of named joints (m or rad), each joint at most once.
    pub joints: Vec<(String, f64)>,
}

/// A joint below the root held at a position.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldJoint {
    pub name: String,
    /// m (prismatic) or rad.
    pub position: f64,
    /// The joint it mimics, if it does.
    pub mimics: Option<String>,
}

/// The merged tool, in the flange frame (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfTool {
    /// kg.
    pub mass: f64,
    /// Centre of mass, m.
    pub com: [f64; 3],
    /// Rotational inertia about the centre of mass, kg m², symmetric.
    pub inertia: [[f64; 3]; 3],
    /// The tip link's origin, m.
    pub tip: [f64; 3],
    /// The links merged (the root first, then depth first in file order).
    pub links: Vec<String>,
    /// The one-axis joints below the root and the positions they were held at, in the same
    /// order.
    pub held: Vec<HeldJoint>,
    /// The flange link's name (the root's when none was asked for).
    pub flange: String,
}

impl UrdfTool {
    /// The numbers of the row, by column name, in [`COLUMNS`]' order after `name` and `model`.
    pub fn values(&self) -> [(&'static str, f64); 13] {
        let (c, i, t) = (self.com, self.inertia, self.tip);
        [
            ("tool_mass", self.mass),
            ("tool_com_x", c[0]),
            ("tool_com_y", c[1]),
            ("tool_com_z", c[2]),
            ("tool_ixx", i[0][0]),
            ("tool_iyy", i[1][1]),
            ("tool_izz", i[2][2]),
            ("tool_ixy", i[0][1]),
            ("tool_ixz", i[0][2]),
            ("tool_iyz", i[1][2]),
            ("tool_tip_x", t[0]),
            ("tool_tip_y", t[1]),
            ("tool_tip_z", t[2]),
        ]
    }

    /// Where the row came from, for the `#` comment line above it (one line, whatever the
    /// names hold).
    pub fn provenance(&self, file: &str, request: &Request) -> String {
        let held = if self.held.is_empty() {
            "no movable joint".to_string()
        } else {
            self.held
                .iter()
                .map(|h| match &h.mimics {
                    Some(m) => format!("{} = {} (mimics {})", Clip(&h.name), h.position, Clip(m)),
                    None => format!("{} = {}", Clip(&h.name), h.position),
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        let opening = request
            .opening
            .map_or(String::new(), |o| format!(" at opening {o}"));
        let links: Vec<String> = self.links.iter().map(|l| Clip(l).to_string()).collect();
        format!(
            "from {}: links {} merged{opening} ({held}); tip {}, in the frame of {}",
            ClipPath(file),
            links.join(", "),
            Clip(&request.tip),
            Clip(&self.flange),
        )
    }

    /// The tools file: the `#` comment, the header and the row, each a line.
    pub fn tools_file(
        &self,
        file: &str,
        request: &Request,
        name: &str,
        model: Option<&str>,
    ) -> String {
        use toolconf_files::csv::format_number;
        let text = |s: &str| {
            let s: String = s
                .chars()
                .map(|c| if c.is_control() { ' ' } else { c })
                .collect();
            if s.contains([',', '"']) || s.starts_with('#') {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s
            }
        };
        let mut cells = vec![text(name), model.map_or(String::new(), text)];
        cells.extend(self.values().iter().map(|&(_, v)| format_number(v)));
        format!(
            "# {}\n{}\n{}\n",
            self.provenance(file, request),
            COLUMNS.join(","),
            cells.join(",")
        )
    }
}

/// The generated models whose tool is a URDF tool at a flange (their parameters are the row's
/// `tool_mass`, ...: `panda`, `ur5`).
pub fn flange_models() -> Vec<&'static str> {
    crate::registry::ModelKind::all()
        .iter()
        .filter(|m| m.parameter_names().contains(&"tool_mass"))
        .map(|m| m.name())
        .collect()
}

/// The row's `model`: one of [`flange_models`] (case and blanks ignored), or why not.
pub fn flange_model(name: &str) -> Result<&'static str, String> {
    let models = flange_models();
    match crate::registry::lookup(name) {
        Ok(kind) if models.contains(&kind.name()) => Ok(kind.name()),
        _ => Err(format!(
            "'{}' is not a model with a tool at a URDF flange ({})",
            Clip(name),
            models.join(", ")
        )),
    }
}

/// Bad input: one line naming the file and, where there is one, the line of the element, the
/// link or joint, the attribute and the value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UrdfToolError {
    /// The file as the user named it (clipped).
    pub file: String,
    /// The 1-based line of the element at fault, if one is.
    pub line: Option<u32>,
    /// What is wrong (`joint 'j': ...`).
    pub message: String,
}

impl fmt::Display for UrdfToolError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}, line {line}: {}", self.file, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for UrdfToolError {}

/// Reads the URDF at `path` (at most [`MAX_URDF_BYTES`], UTF-8) and merges the tool.
pub fn tool_from_urdf_file(path: &Path, request: &Request) -> Result<UrdfTool, UrdfToolError> {
    let file = ClipPath(&path.to_string_lossy()).to_string();
    let fail = |message: String| UrdfToolError {
        file: file.clone(),
        line: None,
        message,
    };
    // Opened without blocking and required to be a regular file: a FIFO with no writer is
    // refused, not waited on.
    let bytes = toolconf_files::input::read_regular(path, MAX_URDF_BYTES).map_err(|e| match e {
        toolconf_files::input::InputError::NotAFile(what) => {
            fail(format!("is {what}, not a URDF file"))
        }
        toolconf_files::input::InputError::TooLarge(_) => fail(format!(
            "is larger than {MAX_URDF_BYTES} bytes (8 MiB), more than any tool's URDF needs"
        )),
        toolconf_files::input::InputError::Io(e) => fail(format!("cannot read the URDF file: {e}")),
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        fail(format!(
            "is not UTF-8 text (an invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ))
    })?;
    tool_from_urdf(&text, &path.to_string_lossy(), request)
}

/// Merges the tool from a URDF's text; `file` names it in errors.
pub fn tool_from_urdf(
    text: &str,
    file: &str,
    request: &Request,
) -> Result<UrdfTool, UrdfToolError> {
    let file = ClipPath(file).to_string();
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_XML_NODES,
        ..roxmltree::ParsingOptions::default()
    };
    let doc =
        roxmltree::Document::parse_with_options(text, options).map_err(|e| UrdfToolError {
            file: file.clone(),
            line: None,
            message: format!(
                "not a well-formed XML file: {}",
                ClipMessage(&e.to_string())
            ),
        })?;
    let cx = Cx {
        file: &file,
        doc: &doc,
    };
    let robot = Robot::read(&cx)?;
    robot.merge(&cx, request)
}

/// The file and its tree, for messages.
struct Cx<'a, 'input> {
    file: &'a str,
    doc: &'a roxmltree::Document<'input>,
}

impl Cx<'_, '_> {
    fn line(&self, node: roxmltree::Node) -> u32 {
        self.doc.text_pos_at(node.range().start).row
    }

    /// An error at `node`'s line.
    fn at(&self, node: roxmltree::Node, message: impl fmt::Display) -> UrdfToolError {
        UrdfToolError {
            file: self.file.to_string(),
            line: Some(self.line(node)),
            message: message.to_string(),
        }
    }

    /// An error of the request or of the whole file.
    fn whole(&self, message: impl fmt::Display) -> UrdfToolError {
        UrdfToolError {
            file: self.file.to_string(),
            line: None,
            message: message.to_string(),
        }
    }
}

/// A rigid transform: a point's coordinates in the child frame x map to `r · x + p` in the
/// parent's.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pose {
    r: Matrix3<f64>,
    p: Vector3<f64>,
}

impl Pose {
    fn identity() -> Self {
        Pose {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// `self · child`.
    fn then(&self, child: &Pose) -> Pose {
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
fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let k = Matrix3::new(
        0.0, -axis.z, axis.y, axis.z, 0.0, -axis.x, -axis.y, axis.x, 0.0,
    );
    let (s, c) = angle.sin_cos();
    Matrix3::identity() + k * s + k * k * (1.0 - c)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Fixed,
    Revolute,
    Continuous,
    Prismatic,
    Floating,
    Planar,
}

impl Kind {
    fn movable(self) -> bool {
        matches!(self, Kind::Revolute | Kind::Continuous | Kind::Prismatic)
    }

    fn name(self) -> &'static str {
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

struct Inertial {
    mass: f64,
    /// The centre of mass and the inertia's axes in the link frame.
    origin: Pose,
    /// In the inertial frame's axes.
    inertia: Matrix3<f64>,
}

struct Link<'a, 'input> {
    name: &'a str,
    node: roxmltree::Node<'a, 'input>,
    inertial: Option<Inertial>,
}

struct Mimic<'a> {
    joint: &'a str,
    multiplier: f64,
    offset: f64,
}

struct Joint<'a, 'input> {
    name: &'a str,
    node: roxmltree::Node<'a, 'input>,
    kind: Kind,
    parent: usize,
    child: usize,
    origin: Pose,
    axis: Vector3<f64>,
    limit: Option<(f64, f64)>,
    mimic: Option<Mimic<'a>>,
}

struct Robot<'a, 'input> {
    links: Vec<Link<'a, 'input>>,
    link_index: HashMap<&'a str, usize>,
    joints: Vec<Joint<'a, 'input>>,
    joint_index: HashMap<&'a str, usize>,
    /// The joint whose child each link is.
    parent_joint: Vec<Option<usize>>,
    /// The joints whose parent each link is, in file order.
    child_joints: Vec<Vec<usize>>,
}

/// URDF elements: no namespace (a `xacro:` or `gazebo` element is not one).
fn is(node: &roxmltree::Node, tag: &str) -> bool {
    node.is_element() && node.tag_name().name() == tag && node.tag_name().namespace().is_none()
}

/// The one `<tag>` child of `node`, if any; two are refused.
fn only_child<'a, 'input>(
    cx: &Cx,
    node: roxmltree::Node<'a, 'input>,
    owner: &str,
    tag: &str,
) -> Result<Option<roxmltree::Node<'a, 'input>>, UrdfToolError> {
    let mut found = node.children().filter(|c| is(c, tag));
    let first = found.next();
    if let Some(second) = found.next() {
        return Err(cx.at(second, format!("{owner} has a second <{tag}>")));
    }
    Ok(first)
}

/// A required attribute.
fn attribute<'a>(
    cx: &Cx,
    node: roxmltree::Node<'a, '_>,
    owner: &str,
    attr: &str,
) -> Result<&'a str, UrdfToolError> {
    node.attribute(attr).ok_or_else(|| {
        cx.at(
            node,
            format!(
                "{owner}<{}> has no {attr} attribute",
                node.tag_name().name()
            ),
        )
    })
}

/// A finite number, `default` when the attribute is absent (required when None).
fn number(
    cx: &Cx,
    node: roxmltree::Node,
    owner: &str,
    attr: &str,
    default: Option<f64>,
) -> Result<f64, UrdfToolError> {
    let Some(text) = node.attribute(attr) else {
        return default.ok_or_else(|| {
            cx.at(
                node,
                format!(
                    "{owner}<{}> has no {attr} attribute",
                    node.tag_name().name()
                ),
            )
        });
    };
    let tag = node.tag_name().name();
    match text.trim_matches(xml_blank).parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(cx.at(
            node,
            format!("{owner}<{tag}> {attr} = '{}' is not finite", Clip(text)),
        )),
        Err(_) => Err(cx.at(
            node,
            format!("{owner}<{tag}> {attr} = '{}' is not a number", Clip(text)),
        )),
    }
}

/// XML's blanks (space, tab, CR, LF), which alone separate and surround a URDF's numbers: no
/// other space (U+00A0, ...), as the derivation's reader (derive/toolconf_derive/urdf.py) has it.
fn xml_blank(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\r' | '\n')
}

/// Three finite numbers separated by blanks, `default` when the attribute is absent.
fn triple(
    cx: &Cx,
    node: roxmltree::Node,
    owner: &str,
    attr: &str,
    default: [f64; 3],
) -> Result<Vector3<f64>, UrdfToolError> {
    let Some(text) = node.attribute(attr) else {
        return Ok(Vector3::from(default));
    };
    let tag = node.tag_name().name();
    let words: Vec<&str> = text.split(xml_blank).filter(|w| !w.is_empty()).collect();
    if words.len() != 3 {
        return Err(cx.at(
            node,
            format!(
                "{owner}<{tag}> {attr} = '{}' has {} numbers, not 3",
                Clip(text),
                words.len()
            ),
        ));
    }
    let mut v = Vector3::zeros();
    for (i, w) in words.iter().enumerate() {
        v[i] = match w.parse::<f64>() {
            Ok(x) if x.is_finite() => x,
            Ok(_) => {
                return Err(cx.at(
                    node,
                    format!(
                        "{owner}<{tag}> {attr} = '{}': '{}' is not finite",
                        Clip(text),
                        Clip(w)
                    ),
                ))
            }
            Err(_) => {
                return Err(cx.at(
                    node,
                    format!(
                        "{owner}<{tag}> {attr} = '{}': '{}' is not a number",
                        Clip(text),
                        Clip(w)
                    ),
                ))
            }
        };
    }
    Ok(v)
}

/// An `<origin xyz rpy>` (absent: the identity; absent attributes: zeros).
fn origin(cx: &Cx, node: Option<roxmltree::Node>, owner: &str) -> Result<Pose, UrdfToolError> {
    let Some(node) = node else {
        return Ok(Pose::identity());
    };
    let p = triple(cx, node, owner, "xyz", [0.0; 3])?;
    let rpy = triple(cx, node, owner, "rpy", [0.0; 3])?;
    Ok(Pose {
        r: rpy_matrix(rpy.x, rpy.y, rpy.z),
        p,
    })
}

impl<'a, 'input> Robot<'a, 'input> {
    fn read(cx: &Cx<'a, 'input>) -> Result<Self, UrdfToolError> {
        let root = cx.doc.root_element();
        if !is(&root, "robot") {
            return Err(cx.at(
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
        for node in root.children().filter(|n| is(n, "link")) {
            let name = node
                .attribute("name")
                .ok_or_else(|| cx.at(node, "a <link> has no name attribute"))?;
            let owner = format!("link '{}': ", Clip(name));
            if let Some(&before) = robot.link_index.get(name) {
                return Err(cx.at(
                    node,
                    format!(
                        "a second link named '{}' (the first is on line {})",
                        Clip(name),
                        cx.line(robot.links[before].node)
                    ),
                ));
            }
            let inertial = match only_child(cx, node, &owner, "inertial")? {
                None => None,
                Some(inertial) => Some(read_inertial(cx, inertial, &owner)?),
            };
            robot.link_index.insert(name, robot.links.len());
            robot.links.push(Link {
                name,
                node,
                inertial,
            });
        }
        robot.parent_joint = vec![None; robot.links.len()];
        robot.child_joints = vec![Vec::new(); robot.links.len()];
        for node in root.children().filter(|n| is(n, "joint")) {
            let name = node
                .attribute("name")
                .ok_or_else(|| cx.at(node, "a <joint> has no name attribute"))?;
            let owner = format!("joint '{}': ", Clip(name));
            if let Some(&before) = robot.joint_index.get(name) {
                return Err(cx.at(
                    node,
                    format!(
                        "a second joint named '{}' (the first is on line {})",
                        Clip(name),
                        cx.line(robot.joints[before].node)
                    ),
                ));
            }
            let joint = robot.read_joint(cx, node, name, &owner)?;
            let index = robot.joints.len();
            if let Some(other) = robot.parent_joint[joint.child] {
                return Err(cx.at(
                    node,
                    format!(
                        "{owner}link '{}' has two parents: it is the child of joint '{}' \
                         (line {}) too",
                        Clip(robot.links[joint.child].name),
                        Clip(robot.joints[other].name),
                        cx.line(robot.joints[other].node)
                    ),
                ));
            }
            robot.parent_joint[joint.child] = Some(index);
            robot.child_joints[joint.parent].push(index);
            robot.joint_index.insert(name, index);
            robot.joints.push(joint);
        }
        robot.check_tree(cx)?;
        Ok(robot)
    }

    /// The links form one tree, as the URDF specification (and urdfdom, and the derivation's
    /// reader) has them: no loop anywhere in the file, one root link.
    fn check_tree(&self, cx: &Cx) -> Result<(), UrdfToolError> {
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
                    let joint = &self.joints[self.parent_joint[last].expect("walked up")];
                    return Err(cx.at(
                        joint.node,
                        format!(
                            "joint '{}' leads back to link '{}': the links form a loop",
                            Clip(joint.name),
                            Clip(self.links[link].name)
                        ),
                    ));
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
            return Err(cx.whole(format!(
                "{} root links ({}): a URDF's links form one tree with one root",
                roots.len(),
                shown.join(", ")
            )));
        }
        Ok(())
    }

    fn read_joint(
        &self,
        cx: &Cx<'a, 'input>,
        node: roxmltree::Node<'a, 'input>,
        name: &'a str,
        owner: &str,
    ) -> Result<Joint<'a, 'input>, UrdfToolError> {
        let kind_text = attribute(cx, node, owner, "type")?;
        let kind = match kind_text {
            "fixed" => Kind::Fixed,
            "revolute" => Kind::Revolute,
            "continuous" => Kind::Continuous,
            "prismatic" => Kind::Prismatic,
            "floating" => Kind::Floating,
            "planar" => Kind::Planar,
            other => {
                return Err(cx.at(
                    node,
                    format!(
                        "{owner}type = '{}' is not a URDF joint type (fixed, revolute, \
                         continuous, prismatic, floating, planar)",
                        Clip(other)
                    ),
                ))
            }
        };
        let end = |tag: &str| -> Result<usize, UrdfToolError> {
            let element = only_child(cx, node, owner, tag)?
                .ok_or_else(|| cx.at(node, format!("{owner}no <{tag}> link")))?;
            let link = attribute(cx, element, owner, "link")?;
            self.link_index.get(link).copied().ok_or_else(|| {
                cx.at(
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
            return Err(cx.at(
                node,
                format!(
                    "{owner}joins link '{}' to itself",
                    Clip(self.links[parent].name)
                ),
            ));
        }
        let origin = origin(cx, only_child(cx, node, owner, "origin")?, owner)?;
        let axis = match only_child(cx, node, owner, "axis")? {
            None => Vector3::x(),
            Some(element) => {
                let axis = triple(cx, element, owner, "xyz", [1.0, 0.0, 0.0])?;
                let norm = axis.norm();
                if kind.movable() && !(norm.is_finite() && norm > 1e-12) {
                    return Err(cx.at(
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
        };
        let limit = match only_child(cx, node, owner, "limit")? {
            // The URDF specification's rule (urdfdom's, the derivation reader's).
            None if matches!(kind, Kind::Revolute | Kind::Prismatic) => {
                return Err(cx.at(
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
                number(cx, element, owner, "lower", Some(0.0))?,
                number(cx, element, owner, "upper", Some(0.0))?,
            )),
        };
        let mimic = match only_child(cx, node, owner, "mimic")? {
            None => None,
            Some(element) => Some(Mimic {
                joint: attribute(cx, element, owner, "joint")?,
                multiplier: number(cx, element, owner, "multiplier", Some(1.0))?,
                offset: number(cx, element, owner, "offset", Some(0.0))?,
            }),
        };
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

    fn link(&self, cx: &Cx, flag: &str, name: &str) -> Result<usize, UrdfToolError> {
        self.link_index.get(name).copied().ok_or_else(|| {
            let mut names: Vec<&str> = self.links.iter().map(|l| l.name).take(6).collect();
            if self.links.len() > 6 {
                names.push("…");
            }
            cx.whole(format!(
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

    /// The root and the links below it, depth first in file order, each with the joint
    /// leading to it (None for the root); a loop back to a link already reached is refused.
    fn subtree(&self, cx: &Cx, root: usize) -> Result<Vec<(usize, Option<usize>)>, UrdfToolError> {
        let mut seen = vec![false; self.links.len()];
        let mut order = Vec::new();
        let mut stack = vec![(root, None)];
        while let Some((link, via)) = stack.pop() {
            if seen[link] {
                let joint: &Joint = &self.joints[via.expect("the root is reached first")];
                return Err(cx.at(
                    joint.node,
                    format!(
                        "joint '{}' leads back to link '{}': the links form a loop",
                        Clip(joint.name),
                        Clip(self.links[link].name)
                    ),
                ));
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
    fn flange_to_root(&self, cx: &Cx, flange: usize, root: usize) -> Result<Pose, UrdfToolError> {
        let mut chain = Vec::new();
        let mut link = root;
        let mut seen = HashSet::new();
        while link != flange {
            if !seen.insert(link) {
                return Err(cx.whole(format!(
                    "the links above '{}' form a loop, through link '{}'",
                    Clip(self.links[root].name),
                    Clip(self.links[link].name)
                )));
            }
            let Some(j) = self.parent_joint[link] else {
                return Err(cx.whole(format!(
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
                return Err(cx.at(
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

    /// The held position of every joint of the subtree that moves (None for the others).
    fn positions(
        &self,
        cx: &Cx,
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
                .ok_or_else(|| cx.whole(format!("{flag}: no joint of the file is named so")))?;
            let joint = &self.joints[j];
            if !value.is_finite() {
                return Err(cx.whole(format!("{flag}: the position is not finite")));
            }
            if !below[joint.parent] {
                return Err(cx.whole(format!(
                    "{flag}: joint '{}' is not below --root '{root_name}'",
                    Clip(name)
                )));
            }
            if !joint.kind.movable() {
                return Err(cx.whole(format!(
                    "{flag}: joint '{}' is {}, it has no position to hold",
                    Clip(name),
                    joint.kind.name()
                )));
            }
            if let Some(m) = &joint.mimic {
                return Err(cx.whole(format!(
                    "{flag}: joint '{}' mimics joint '{}': give the position of '{}'",
                    Clip(name),
                    Clip(m.joint),
                    Clip(m.joint)
                )));
            }
            if given.insert(j, *value).is_some() {
                return Err(cx.whole(format!("{flag}: joint '{}' is given twice", Clip(name))));
            }
        }
        if let Some(o) = request.opening {
            if !o.is_finite() {
                return Err(cx.whole(format!("--opening {}: not finite", Short(o))));
            }
        }
        let mut held = vec![None; self.joints.len()];
        for (j, joint) in self.joints.iter().enumerate() {
            if !below[joint.parent] || joint.kind == Kind::Fixed {
                continue;
            }
            if !joint.kind.movable() {
                return Err(cx.at(
                    joint.node,
                    format!(
                        "joint '{}' below --root '{root_name}' is {}: a tool's joints must be \
                         fixed, revolute, continuous or prismatic to be held at a position",
                        Clip(joint.name),
                        joint.kind.name()
                    ),
                ));
            }
            held[j] = Some(self.held_position(cx, request, &given, below, j)?);
        }
        Ok(held)
    }

    /// Joint `j`'s position: given, the opening, or its mimicked joint's (followed through
    /// chains of mimics, a loop refused), then checked against its limits.
    fn held_position(
        &self,
        cx: &Cx,
        request: &Request,
        given: &HashMap<usize, f64>,
        below: &[bool],
        j: usize,
    ) -> Result<f64, UrdfToolError> {
        // The chain of mimics from j to a joint that mimics none.
        let mut chain = vec![j];
        let mut seen = HashSet::from([j]);
        loop {
            let joint = &self.joints[*chain.last().unwrap()];
            let Some(m) = &joint.mimic else { break };
            let &k = self.joint_index.get(m.joint).ok_or_else(|| {
                cx.at(
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
                return Err(cx.at(
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
                return Err(cx.at(
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
                return Err(cx.at(
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
        let source = *chain.last().unwrap();
        let mut value = match given.get(&source).copied().or(request.opening) {
            Some(v) => v,
            None => {
                let joint = &self.joints[source];
                return Err(cx.at(
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
                    return Err(cx.at(
                        joint.node,
                        format!(
                            "joint '{}': its <mimic> position is not finite",
                            Clip(joint.name)
                        ),
                    ));
                }
            }
            self.check_limit(cx, k, value)?;
        }
        Ok(value)
    }

    fn check_limit(&self, cx: &Cx, j: usize, value: f64) -> Result<(), UrdfToolError> {
        let joint = &self.joints[j];
        if joint.kind == Kind::Continuous {
            return Ok(());
        }
        let Some((lower, upper)) = joint.limit else {
            return Err(cx.at(
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
            return Err(cx.at(
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

    fn merge(&self, cx: &Cx, request: &Request) -> Result<UrdfTool, UrdfToolError> {
        let root = self.link(cx, "--root", &request.root)?;
        let tip = self.link(cx, "--tip", &request.tip)?;
        let flange = match &request.flange {
            Some(f) => self.link(cx, "--flange", f)?,
            None => root,
        };
        let subtree = self.subtree(cx, root)?;
        let mut below = vec![false; self.links.len()];
        for &(l, _) in &subtree {
            below[l] = true;
        }
        if !below[tip] {
            return Err(cx.whole(format!(
                "--tip '{}' is not --root '{}' or a link below it",
                Clip(&request.tip),
                Clip(&request.root)
            )));
        }
        let flange_pose = self.flange_to_root(cx, flange, root)?;
        let held = self.positions(cx, request, root, &below)?;
        // Each link's pose in the flange frame, parents before children.
        let mut pose = vec![None; self.links.len()];
        pose[root] = Some(flange_pose);
        for &(l, via) in &subtree {
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
        // Each massive link's mass, centre of mass and inertia about it, in flange axes.
        let mut bodies = Vec::new();
        for &(l, _) in &subtree {
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
            return Err(cx.whole(format!(
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
        let tip_p = pose[tip].expect("the tip is below the root").p;
        let finite = mass.is_finite()
            && com.iter().all(|v| v.is_finite())
            && inertia.iter().all(|v| v.is_finite())
            && tip_p.iter().all(|v| v.is_finite());
        if !finite {
            return Err(cx.whole(format!(
                "the links at and below --root '{root_name}' give a mass, centre of mass, \
                 inertia or tip that is not finite (mass {} kg): the file's numbers are too large",
                Short(mass)
            )));
        }
        check_rigid_body(&inertia).map_err(|why| {
            cx.whole(format!(
                "the links at and below --root '{root_name}' merge to an inertia that {why}"
            ))
        })?;
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
}

fn read_inertial(cx: &Cx, node: roxmltree::Node, owner: &str) -> Result<Inertial, UrdfToolError> {
    let owner = format!("{owner}<inertial>");
    let origin = origin(cx, only_child(cx, node, &owner, "origin")?, &owner)?;
    let mass_node = only_child(cx, node, &owner, "mass")?
        .ok_or_else(|| cx.at(node, format!("{owner} has no <mass>")))?;
    let mass = number(cx, mass_node, &owner, "value", None)?;
    if mass < 0.0 {
        return Err(cx.at(
            mass_node,
            format!("{owner}<mass> value = {} is negative", Short(mass)),
        ));
    }
    let i = only_child(cx, node, &owner, "inertia")?
        .ok_or_else(|| cx.at(node, format!("{owner} has no <inertia>")))?;
    let get = |a: &str| number(cx, i, &owner, a, None);
    let (ixx, iyy, izz) = (get("ixx")?, get("iyy")?, get("izz")?);
    let (ixy, ixz, iyz) = (get("ixy")?, get("ixz")?, get("iyz")?);
    Ok(Inertial {
        mass,
        origin,
        inertia: Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz),
    })
}

/// Why a symmetric inertia about a centre of mass is no rigid body's: not positive definite,
/// or principal moments breaking the triangle inequality ([`DEFINITE_RATIO`],
/// [`TRIANGLE_SLACK`]).
pub fn check_rigid_body(inertia: &Matrix3<f64>) -> Result<(), String> {
    let mut moments: Vec<f64> = SymmetricEigen::new(*inertia)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    moments.sort_by(f64::total_cmp);
    let [a, b, c] = [moments[0], moments[1], moments[2]];
    let shown = crate::display::ShortList(&moments).to_string();
    if !(c > 0.0 && a > DEFINITE_RATIO * c) {
        return Err(format!(
            "is not positive definite: principal moments {shown} kg m²"
        ));
    }
    if c > (a + b) * (1.0 + TRIANGLE_SLACK) {
        return Err(format!(
            "no rigid body has: principal moments {shown} kg m² break the triangle inequality \
             ({} > {} + {})",
            Short(c),
            Short(a),
            Short(b)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(root: &str, tip: &str) -> Request {
        Request {
            root: root.into(),
            tip: tip.into(),
            ..Request::default()
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-15 * (1.0 + a.abs().max(b.abs()))
    }

    /// Two small solid cubes (side s, mass m each) 2a apart on a fixed joint: the composite's
    /// centre of mass is halfway, its inertia the cubes' own m s²/6 each plus m a² each about
    /// the axes across the line joining them (textbook parallel-axis values).
    #[test]
    fn two_boxes_on_a_fixed_joint_give_the_parallel_axis_values() {
        let (m, s, a) = (0.5, 0.01, 0.1);
        let own = m * s * s / 6.0;
        let urdf = format!(
            r#"<robot name="two">
  <link name="base"><inertial><mass value="{m}"/><inertia ixx="{own}" iyy="{own}" izz="{own}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="far"><inertial><mass value="{m}"/><inertia ixx="{own}" iyy="{own}" izz="{own}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tcp"/>
  <joint name="j" type="fixed"><parent link="base"/><child link="far"/><origin xyz="{x} 0 0"/></joint>
  <joint name="t" type="fixed"><parent link="far"/><child link="tcp"/><origin xyz="0 0 0.05"/></joint>
</robot>"#,
            x = 2.0 * a
        );
        let tool = tool_from_urdf(&urdf, "two.urdf", &request("base", "tcp")).unwrap();
        assert!(close(tool.mass, 2.0 * m));
        assert!(close(tool.com[0], a) && tool.com[1] == 0.0 && tool.com[2] == 0.0);
        let i = tool.inertia;
        assert!(close(i[0][0], 2.0 * own), "{i:?}");
        assert!(close(i[1][1], 2.0 * own + 2.0 * m * a * a), "{i:?}");
        assert!(close(i[2][2], 2.0 * own + 2.0 * m * a * a), "{i:?}");
        assert_eq!([i[0][1], i[0][2], i[1][2]], [0.0; 3]);
        assert_eq!(tool.tip, [2.0 * a, 0.0, 0.05]);
        assert_eq!(tool.links, ["base", "far", "tcp"]);
    }

    /// A rod (inertia diag(0, L, L) in its own axes, thin along x) whose `<inertial>` is turned
    /// 90° about z (rpy 0 0 π/2) lies along y in link axes: R I Rᵀ = diag(L, 0, L) (+ a small
    /// thickness so that it is definite); turned 45° about z it has the product
    /// ixy = -(L - t)/2 and ixx = iyy = (L + t)/2.
    #[test]
    fn a_rotated_inertial_origin_is_rotated_into_link_axes() {
        let (l, t) = (0.02, 0.001);
        let link = |rpy: &str| {
            format!(
                r#"<robot name="rod"><link name="rod"><inertial><origin xyz="0.1 0.2 0.3" rpy="{rpy}"/><mass value="2"/><inertia ixx="{t}" iyy="{l}" izz="{l}" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#
            )
        };
        let q = std::f64::consts::FRAC_PI_2;
        let tool = tool_from_urdf(
            &link(&format!("0 0 {q}")),
            "rod.urdf",
            &request("rod", "rod"),
        )
        .unwrap();
        let i = tool.inertia;
        assert!(
            close(i[0][0], l) && close(i[1][1], t) && close(i[2][2], l),
            "{i:?}"
        );
        assert!(i[0][1].abs() < 1e-17 && i[0][2].abs() < 1e-17 && i[1][2].abs() < 1e-17);
        assert_eq!(tool.com, [0.1, 0.2, 0.3]);
        assert_eq!(tool.mass, 2.0);
        let e = std::f64::consts::FRAC_PI_4;
        let tool = tool_from_urdf(
            &link(&format!("0 0 {e}")),
            "rod.urdf",
            &request("rod", "rod"),
        )
        .unwrap();
        let i = tool.inertia;
        assert!(
            close(i[0][0], (l + t) / 2.0) && close(i[1][1], (l + t) / 2.0),
            "{i:?}"
        );
        assert!(close(i[0][1], -(l - t) / 2.0), "{i:?}");
        // URDF's fixed-axis rpy is nalgebra's Euler angles (roll, then pitch, then yaw).
        let r = rpy_matrix(0.3, -0.7, 1.1);
        let expected = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        assert!((r - expected.matrix()).norm() < 1e-15);
    }

    #[test]
    fn a_moving_joint_is_held_and_its_mimic_follows() {
        let urdf = r#"<robot name="g">
  <link name="palm"><inertial><mass value="1"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="a"><inertial><mass value="0.5"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="0.5"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="ja" type="prismatic"><parent link="palm"/><child link="a"/><axis xyz="0 2 0"/><limit lower="0" upper="0.05"/></joint>
  <joint name="jb" type="prismatic"><parent link="palm"/><child link="b"/><axis xyz="0 -1 0"/><limit lower="0" upper="0.05"/><mimic joint="ja" multiplier="1" offset="0.01"/></joint>
</robot>"#;
        let mut r = request("palm", "b");
        let e = tool_from_urdf(urdf, "g.urdf", &r).unwrap_err().to_string();
        assert!(
            e.starts_with("g.urdf, line 5: joint 'ja' is prismatic and has no position"),
            "{e}"
        );
        r.opening = Some(0.02);
        let tool = tool_from_urdf(urdf, "g.urdf", &r).unwrap();
        assert!(close(tool.tip[1], -0.03), "{:?}", tool.tip);
        assert!(close(tool.com[1], (0.5 * 0.02 - 0.5 * 0.03) / 2.0));
        assert_eq!(tool.held[1].mimics.as_deref(), Some("ja"));
        r.opening = Some(0.045);
        let e = tool_from_urdf(urdf, "g.urdf", &r).unwrap_err().to_string();
        assert_eq!(
            e,
            "g.urdf, line 6: joint 'jb': position 0.055 m is outside its limits [0, 0.05]"
        );
        r.joints = vec![("jb".into(), 0.01)];
        let e = tool_from_urdf(urdf, "g.urdf", &r).unwrap_err().to_string();
        assert!(
            e.contains("mimics joint 'ja': give the position of 'ja'"),
            "{e}"
        );
    }

    #[test]
    fn bad_files_are_one_line_naming_the_element() {
        let ok = r#"<robot name="x"><link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link><link name="b"/><joint name="j" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 1"/></joint></robot>"#;
        assert!(tool_from_urdf(ok, "x.urdf", &request("a", "b")).is_ok());
        let cases: &[(&str, &str, &str)] = &[
            ("<robot", "", "not a well-formed XML file"),
            (
                "xyz=\"0 0 1\"",
                "xyz=\"0 0\"",
                "xyz = '0 0' has 2 numbers, not 3",
            ),
            ("xyz=\"0 0 1\"", "xyz=\"0 0 nan\"", "'nan' is not finite"),
            (
                "value=\"1\"",
                "value=\"-1\"",
                "<mass> value = -1 is negative",
            ),
            (
                "value=\"1\"",
                "value=\"heavy\"",
                "value = 'heavy' is not a number",
            ),
            (
                "<child link=\"b\"/>",
                "<child link=\"c\"/>",
                "link = 'c' is no link of the file",
            ),
            (
                "<child link=\"b\"/>",
                "<child link=\"a\"/>",
                "joins link 'a' to itself",
            ),
            (
                "type=\"fixed\"",
                "type=\"hinge\"",
                "'hinge' is not a URDF joint type",
            ),
            (
                "<link name=\"b\"/>",
                "<link name=\"a\"/>",
                "a second link named 'a'",
            ),
            ("ixx=\"1\"", "ixx=\"10\"", "break the triangle inequality"),
            ("ixx=\"1\"", "ixx=\"0\"", "is not positive definite"),
            ("value=\"1\"", "value=\"0\"", "have no mass"),
        ];
        for (from, to, expected) in cases {
            let bad = ok.replacen(from, to, 1);
            let e = tool_from_urdf(&bad, "x.urdf", &request("a", "b"))
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("x.urdf"), "{e}");
            assert!(e.contains(expected), "{from} -> {to}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let e = tool_from_urdf(ok, "x.urdf", &request("b", "a"))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "x.urdf: --tip 'a' is not --root 'b' or a link below it");
        let e = tool_from_urdf(ok, "x.urdf", &request("zz", "a"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--root 'zz' is no link of the file"), "{e}");
        let mut r = request("a", "b");
        r.flange = Some("b".into());
        let e = tool_from_urdf(ok, "x.urdf", &r).unwrap_err().to_string();
        assert_eq!(e, "x.urdf: --flange 'b' is not an ancestor of --root 'a'");
        let e = tool_from_urdf(&ok.replace("robot", "rob"), "x.urdf", &request("a", "b"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "x.urdf, line 1: the top element is <rob>, not <robot>: not a URDF file"
        );
        // Finite numbers whose composite is not: 1e300 kg, 1e10 m apart.
        let body = r#"<inertial><mass value="1e300"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>"#;
        let huge = format!(
            r#"<robot name="x"><link name="a">{body}</link><link name="b">{body}</link><joint name="j" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 1e10"/></joint></robot>"#
        );
        let e = tool_from_urdf(&huge, "x.urdf", &request("a", "b"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("that is not finite (mass 2e300 kg)"), "{e}");
        // Two parents; a loop.
        let two = ok.replace(
            "</robot>",
            r#"<link name="c"/><joint name="k" type="fixed"><parent link="c"/><child link="b"/></joint></robot>"#,
        );
        let e = tool_from_urdf(&two, "x.urdf", &request("a", "b"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("link 'b' has two parents"), "{e}");
        let cycle = ok.replace(
            "</robot>",
            r#"<joint name="k" type="fixed"><parent link="b"/><child link="a"/></joint></robot>"#,
        );
        let e = tool_from_urdf(&cycle, "x.urdf", &request("a", "b"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("leads back to link 'a': the links form a loop"),
            "{e}"
        );
    }
}
