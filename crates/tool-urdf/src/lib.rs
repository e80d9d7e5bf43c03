//! # toolconf-tool-urdf
//!
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

mod held;
mod merge;
mod pose;
mod robot;
mod source;

use std::fmt;
use std::path::Path;

use nalgebra::{Matrix3, SymmetricEigen};

use toolconf_messages::{Clip, ClipMessage, ClipPath, Short};

pub use pose::rpy_matrix;
use robot::Robot;
use source::Source;

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
    let source = Source {
        file: &file,
        doc: &doc,
    };
    let robot = Robot::read(&source)?;
    robot.merge(&source, request)
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
    let shown = toolconf_messages::ShortList(&moments).to_string();
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
        // The rod turned by `yaw` about z.
        let turned = |yaw: f64| {
            let urdf = format!(
                r#"<robot name="rod"><link name="rod"><inertial><origin xyz="0.1 0.2 0.3" rpy="0 0 {yaw}"/><mass value="2"/><inertia ixx="{t}" iyy="{l}" izz="{l}" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#
            );
            tool_from_urdf(&urdf, "rod.urdf", &request("rod", "rod")).unwrap()
        };
        let tool = turned(std::f64::consts::FRAC_PI_2);
        let i = tool.inertia;
        assert!(
            close(i[0][0], l) && close(i[1][1], t) && close(i[2][2], l),
            "{i:?}"
        );
        assert!(i[0][1].abs() < 1e-17 && i[0][2].abs() < 1e-17 && i[1][2].abs() < 1e-17);
        assert_eq!(tool.com, [0.1, 0.2, 0.3]);
        assert_eq!(tool.mass, 2.0);
        let i = turned(std::f64::consts::FRAC_PI_4).inertia;
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

    /// A valid file: two links on a fixed joint, the one [`BAD_EDITS`] and [`bad_files`] spoil.
    const OK: &str = r#"<robot name="x"><link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link><link name="b"/><joint name="j" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 1"/></joint></robot>"#;

    /// One edit of [`OK`] (its first `from` made `to`) and what the message then says.
    const BAD_EDITS: &[(&str, &str, &str)] = &[
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

    /// What a message must say: all of it, or a part.
    enum Says {
        Exactly(&'static str),
        Part(&'static str),
    }

    /// Bad files and requests beyond one edit, each with the request made of it and what the
    /// message says.
    fn bad_files() -> Vec<(String, Request, Says)> {
        let flange = Request {
            flange: Some("b".into()),
            ..request("a", "b")
        };
        // Finite numbers whose composite is not: 1e300 kg, 1e10 m apart.
        let body = r#"<inertial><mass value="1e300"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>"#;
        let huge = format!(
            r#"<robot name="x"><link name="a">{body}</link><link name="b">{body}</link><joint name="j" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 1e10"/></joint></robot>"#
        );
        // Two parents; a loop.
        let two = OK.replace(
            "</robot>",
            r#"<link name="c"/><joint name="k" type="fixed"><parent link="c"/><child link="b"/></joint></robot>"#,
        );
        let cycle = OK.replace(
            "</robot>",
            r#"<joint name="k" type="fixed"><parent link="b"/><child link="a"/></joint></robot>"#,
        );
        use Says::*;
        vec![
            (
                OK.into(),
                request("b", "a"),
                Exactly("x.urdf: --tip 'a' is not --root 'b' or a link below it"),
            ),
            (
                OK.into(),
                request("zz", "a"),
                Part("--root 'zz' is no link of the file"),
            ),
            (
                OK.into(),
                flange,
                Exactly("x.urdf: --flange 'b' is not an ancestor of --root 'a'"),
            ),
            (
                OK.replace("robot", "rob"),
                request("a", "b"),
                Exactly("x.urdf, line 1: the top element is <rob>, not <robot>: not a URDF file"),
            ),
            (
                huge,
                request("a", "b"),
                Part("that is not finite (mass 2e300 kg)"),
            ),
            (two, request("a", "b"), Part("link 'b' has two parents")),
            (
                cycle,
                request("a", "b"),
                Part("leads back to link 'a': the links form a loop"),
            ),
        ]
    }

    #[test]
    fn bad_files_are_one_line_naming_the_element() {
        assert!(tool_from_urdf(OK, "x.urdf", &request("a", "b")).is_ok());
        for (from, to, expected) in BAD_EDITS {
            let bad = OK.replacen(from, to, 1);
            let e = tool_from_urdf(&bad, "x.urdf", &request("a", "b"))
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("x.urdf"), "{e}");
            assert!(e.contains(expected), "{from} -> {to}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        for (file, request, says) in bad_files() {
            let e = tool_from_urdf(&file, "x.urdf", &request)
                .unwrap_err()
                .to_string();
            match says {
                Says::Exactly(expected) => assert_eq!(e, expected),
                Says::Part(expected) => assert!(e.contains(expected), "{e}"),
            }
        }
    }
}
