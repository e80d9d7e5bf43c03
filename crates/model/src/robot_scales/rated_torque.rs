//! Each joint's rated torque of a URDF arm, read from the URDF its model description names: the
//! `<limit effort>` of every moving joint from the description's `[urdf] base` to its `flange`,
//! in that order (N m for a revolute joint, N for a prismatic one).
//!
//! The derivation does not carry the efforts into the generated model, so they are read here,
//! at run time, from the files the model was derived from: the description at
//! [`ModelInfo::description`](crate::registry::ModelInfo) (a path relative to the repository
//! when it lies inside it, as `make derive` and `make model` record it) and its `[urdf] file`,
//! relative to the description's folder. Both are data: TOML and XML read with the bounded
//! readers, the XML without DTDs (no entity expansion).

use std::path::{Path, PathBuf};

use crate::inputs::bounded_read::read_text_file;
use toolconf_messages::{Clip, ClipMessage, ClipPath};

/// The most bytes of a URDF read: the derivation's own limit for an arm's URDF.
const MAX_URDF_BYTES: u64 = 4 << 20;
/// The most XML nodes a URDF may have (the Panda's has about 1300).
const MAX_XML_NODES: u32 = 1_000_000;
/// Joint types that move, and so carry a rated effort.
const MOVING: [&str; 3] = ["revolute", "continuous", "prismatic"];

/// The rated torques and where they were read.
#[derive(Debug, Clone, PartialEq)]
pub struct RatedTorques {
    /// One per joint, base to flange.
    pub values: Vec<f64>,
    /// "derive/robots/…/panda.urdf, <limit effort> of panda_joint1 … panda_joint7".
    pub source: String,
}

/// Where a relative description path is looked for: the repository this crate was built in
/// (`make derive` records the built-in models' descriptions relative to it), then the working
/// folder.
fn candidates(description: &str) -> Vec<PathBuf> {
    let path = Path::new(description);
    if path.is_absolute() {
        return vec![path.to_path_buf()];
    }
    let repository = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    vec![repository.join(path), path.to_path_buf()]
}

/// The rated torques of the URDF arm described at `description` with `dof` joints; `Ok(None)`
/// when the description is not a URDF arm's (the planar arms, the mass-spring-damper).
pub fn read(description: &str, dof: usize) -> Result<Option<RatedTorques>, String> {
    let Some(path) = candidates(description).into_iter().find(|p| p.is_file()) else {
        return Err(format!(
            "its model description {} is not found (looked for beside the repository toolconf \
             was built in and in the working folder)",
            ClipPath(description)
        ));
    };
    let shown = ClipPath(description).to_string();
    let text = read_text_file(&path, "model description").map_err(|e| format!("{shown} {e}"))?;
    let table: toml::Table = toml::from_str(&text)
        .map_err(|e| format!("{shown}: {}", ClipMessage(e.message().trim())))?;
    let text_at = |section: &str, key: &str| -> Option<String> {
        table.get(section)?.get(key)?.as_str().map(String::from)
    };
    if text_at("dynamics", "kind").as_deref() != Some("urdf") {
        return Ok(None);
    }
    let (Some(file), Some(base), Some(flange)) = (
        text_at("urdf", "file"),
        text_at("urdf", "base"),
        text_at("urdf", "flange"),
    ) else {
        return Err(format!("{shown}: [urdf] needs file, base and flange"));
    };
    let urdf = path.parent().unwrap_or(Path::new(".")).join(&file);
    let urdf_shown = ClipPath(&urdf.to_string_lossy()).to_string();
    let xml = read_urdf(&urdf).map_err(|e| format!("{urdf_shown} {e}"))?;
    let (values, joints) =
        efforts(&xml, &base, &flange).map_err(|e| format!("{urdf_shown}: {e}"))?;
    if values.len() != dof {
        return Err(format!(
            "{urdf_shown}: {} moving joints from {base} to {flange}, but the model has {dof}",
            values.len()
        ));
    }
    Ok(Some(RatedTorques {
        values,
        source: format!(
            "{}, <limit effort> of {}",
            ClipPath(&relative_to_repository(&urdf)),
            joints.join(", ")
        ),
    }))
}

/// The URDF's text: at most [`MAX_URDF_BYTES`], UTF-8.
fn read_urdf(path: &Path) -> Result<String, String> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
    let mut bytes = Vec::new();
    file.take(MAX_URDF_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot be read: {e}"))?;
    if bytes.len() as u64 > MAX_URDF_BYTES {
        return Err(format!("is larger than {MAX_URDF_BYTES} bytes"));
    }
    String::from_utf8(bytes).map_err(|_| "is not UTF-8 text".into())
}

/// `path` relative to the repository when inside it (as the generated files name paths).
fn relative_to_repository(path: &Path) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    match (path.canonicalize(), root.canonicalize()) {
        (Ok(p), Ok(r)) => p
            .strip_prefix(&r)
            .map_or(p.clone(), Path::to_path_buf)
            .to_string_lossy()
            .into_owned(),
        _ => path.to_string_lossy().into_owned(),
    }
}

/// The efforts of the moving joints from `base` to `flange` (base first) and their names.
fn efforts(xml: &str, base: &str, flange: &str) -> Result<(Vec<f64>, Vec<String>), String> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_XML_NODES,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(xml, options).map_err(|e| {
        format!(
            "not a well-formed XML file: {}",
            ClipMessage(&e.to_string())
        )
    })?;
    let joints: Vec<roxmltree::Node> = doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("joint"))
        .collect();
    let link_of = |joint: &roxmltree::Node, tag: &str| {
        joint
            .children()
            .find(|c| c.has_tag_name(tag))
            .and_then(|c| c.attribute("link"))
            .map(String::from)
    };
    let (mut values, mut names, mut link) = (Vec::new(), Vec::new(), flange.to_string());
    while link != base {
        let Some(joint) = joints
            .iter()
            .find(|j| link_of(j, "child").as_deref() == Some(link.as_str()))
        else {
            return Err(format!(
                "no joint leads to link '{}' on the way from {} to {}",
                Clip(&link),
                Clip(base),
                Clip(flange)
            ));
        };
        let name = joint.attribute("name").unwrap_or("?").to_string();
        if MOVING.contains(&joint.attribute("type").unwrap_or("")) {
            values.push(effort(joint, &name)?);
            names.push(name.clone());
        }
        link = link_of(joint, "parent")
            .ok_or_else(|| format!("joint '{}' has no parent", Clip(&name)))?;
        if values.len() > joints.len() {
            return Err("the joints form a loop".into());
        }
    }
    values.reverse();
    names.reverse();
    Ok((values, names))
}

/// A moving joint's `<limit effort>`: a finite number > 0.
fn effort(joint: &roxmltree::Node, name: &str) -> Result<f64, String> {
    let text = joint
        .children()
        .find(|c| c.has_tag_name("limit"))
        .and_then(|l| l.attribute("effort"))
        .ok_or_else(|| format!("joint '{}' has no <limit effort>", Clip(name)))?;
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "joint '{}': <limit effort> = '{}' is not a number > 0",
            Clip(name),
            Clip(text)
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CHAIN: &str = r#"<robot name="r">
      <link name="base"/><link name="a"/><link name="b"/><link name="tool"/>
      <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
        <limit effort="12" lower="-1" upper="1" velocity="1"/></joint>
      <joint name="j1" type="continuous"><parent link="base"/><child link="a"/>
        <limit effort="87.0" velocity="1"/></joint>
      <joint name="fix" type="fixed"><parent link="b"/><child link="tool"/></joint>
    </robot>"#;

    #[test]
    fn efforts_are_read_from_the_base_to_the_flange() {
        let (values, names) = efforts(CHAIN, "base", "tool").unwrap();
        assert_eq!(values, [87.0, 12.0]);
        assert_eq!(names, ["j1", "j2"]);
        let e = efforts(CHAIN, "base", "elsewhere").unwrap_err();
        assert!(e.contains("no joint leads to link 'elsewhere'"), "{e}");
        let bad = CHAIN.replace("effort=\"12\"", "effort=\"-3\"");
        let e = efforts(&bad, "base", "tool").unwrap_err();
        assert!(e.contains("j2") && e.contains("-3"), "{e}");
        let e = efforts(
            &CHAIN.replace("<robot", "<!DOCTYPE r [<!ENTITY x \"y\">]><robot"),
            "base",
            "tool",
        )
        .unwrap_err();
        assert!(e.contains("XML"), "{e}");
    }

    #[test]
    fn the_built_in_arms_carry_their_urdfs_efforts() {
        let panda = read("derive/models/panda.toml", 7).unwrap().unwrap();
        assert_eq!(panda.values, [87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0]);
        assert!(panda.source.contains("panda.urdf"), "{}", panda.source);
        let ur5 = read("derive/models/ur5.toml", 6).unwrap().unwrap();
        assert_eq!(ur5.values, [150.0, 150.0, 150.0, 28.0, 28.0, 28.0]);
        assert_eq!(read("derive/models/arm2.toml", 2).unwrap(), None);
        assert!(read("derive/models/panda.toml", 6)
            .unwrap_err()
            .contains("has 6"));
        assert!(read("no/such/model.toml", 2)
            .unwrap_err()
            .contains("not found"));
    }
}
