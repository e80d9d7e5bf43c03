//! The URDF's XML as the reader sees it: the file's name and tree for messages ([`Source`]),
//! and the elements, attributes and numbers read by the file's rules (numbers ASCII decimals
//! separated by XML's blanks, as the derivation's reader has them).

use std::fmt;

use nalgebra::Vector3;
use toolconf_messages::Clip;

use crate::pose::{rpy_matrix, Pose};
use crate::UrdfToolError;

/// The URDF being read: its name as messages give it and its XML tree, so that an error names
/// the file and the line of the element at fault.
pub(crate) struct Source<'a, 'input> {
    pub(crate) file: &'a str,
    pub(crate) doc: &'a roxmltree::Document<'input>,
}

impl Source<'_, '_> {
    pub(crate) fn line(&self, node: roxmltree::Node) -> u32 {
        self.doc.text_pos_at(node.range().start).row
    }

    /// An error at `node`'s line.
    pub(crate) fn at(&self, node: roxmltree::Node, message: impl fmt::Display) -> UrdfToolError {
        UrdfToolError {
            file: self.file.to_string(),
            line: Some(self.line(node)),
            message: message.to_string(),
        }
    }

    /// An error of the request or of the whole file.
    pub(crate) fn whole(&self, message: impl fmt::Display) -> UrdfToolError {
        UrdfToolError {
            file: self.file.to_string(),
            line: None,
            message: message.to_string(),
        }
    }
}

/// URDF elements: no namespace (a `xacro:` or `gazebo` element is not one).
pub(crate) fn is(node: &roxmltree::Node, tag: &str) -> bool {
    node.is_element() && node.tag_name().name() == tag && node.tag_name().namespace().is_none()
}

/// The one `<tag>` child of `node`, if any; two are refused.
pub(crate) fn only_child<'a, 'input>(
    src: &Source,
    node: roxmltree::Node<'a, 'input>,
    owner: &str,
    tag: &str,
) -> Result<Option<roxmltree::Node<'a, 'input>>, UrdfToolError> {
    let mut found = node.children().filter(|c| is(c, tag));
    let first = found.next();
    if let Some(second) = found.next() {
        return Err(src.at(second, format!("{owner} has a second <{tag}>")));
    }
    Ok(first)
}

/// A required attribute.
pub(crate) fn attribute<'a>(
    src: &Source,
    node: roxmltree::Node<'a, '_>,
    owner: &str,
    attr: &str,
) -> Result<&'a str, UrdfToolError> {
    node.attribute(attr).ok_or_else(|| {
        src.at(
            node,
            format!(
                "{owner}<{}> has no {attr} attribute",
                node.tag_name().name()
            ),
        )
    })
}

/// A finite number, `default` when the attribute is absent (required when None).
pub(crate) fn number(
    src: &Source,
    node: roxmltree::Node,
    owner: &str,
    attr: &str,
    default: Option<f64>,
) -> Result<f64, UrdfToolError> {
    let Some(text) = node.attribute(attr) else {
        return default.ok_or_else(|| {
            src.at(
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
        Ok(_) => Err(src.at(
            node,
            format!("{owner}<{tag}> {attr} = '{}' is not finite", Clip(text)),
        )),
        Err(_) => Err(src.at(
            node,
            format!("{owner}<{tag}> {attr} = '{}' is not a number", Clip(text)),
        )),
    }
}

/// XML's blanks (space, tab, CR, LF), which alone separate and surround a URDF's numbers: no
/// other space (U+00A0, ...), as the derivation's reader (derive/toolconf_derive/urdf.py) has it.
pub(crate) fn xml_blank(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\r' | '\n')
}

/// Three finite numbers separated by blanks, `default` when the attribute is absent.
pub(crate) fn triple(
    src: &Source,
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
        return Err(src.at(
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
                return Err(src.at(
                    node,
                    format!(
                        "{owner}<{tag}> {attr} = '{}': '{}' is not finite",
                        Clip(text),
                        Clip(w)
                    ),
                ))
            }
            Err(_) => {
                return Err(src.at(
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
pub(crate) fn origin(
    src: &Source,
    node: Option<roxmltree::Node>,
    owner: &str,
) -> Result<Pose, UrdfToolError> {
    let Some(node) = node else {
        return Ok(Pose::identity());
    };
    let p = triple(src, node, owner, "xyz", [0.0; 3])?;
    let rpy = triple(src, node, owner, "rpy", [0.0; 3])?;
    Ok(Pose {
        r: rpy_matrix(rpy.x, rpy.y, rpy.z),
        p,
    })
}
