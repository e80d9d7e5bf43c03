//! The 3-D view of a report (`report.html` alone): the arm of a model with a URDF flange and its
//! tool, drawn from the model's own kinematics ([`toolconf_model::registry::skeleton`]), with the goal,
//! the best and the worst tool's episodes side by side under one time slider, and the tip's
//! trail. The page is self-contained: three.js (vendored, `assets/three/`) and the data are
//! inlined, so it opens from disk with no network. `report.md` keeps the static figures and says
//! where the view is.

mod frames;
mod three;

use serde_json::json;
use toolconf::rank::TaskTrace;
use toolconf_generated::Read;
use toolconf_model::registry::skeleton::tip_offset_parameters;
use toolconf_model::registry::AnyTool;
use toolconf_model::TaskKind;

use crate::experiments::report::Block;

pub use frames::{inertia_box, InertiaBox};

/// The vendored three.js: its release and the sha256 of `assets/three/three.module.min.js`
/// (assets/three/README.md).
pub const THREE_RELEASE: &str = "r170";
pub const THREE_SHA256: &str = "08fd7545d13d2c7fb65ab691530a802dafefd638596501854f267d0fb13c39e7";
const THREE_MODULE: &str = include_str!("../../assets/three/three.module.min.js");
const SCENE_JS: &str = include_str!("scene.js");

/// The most bytes the view may add to `report.html`: three.js (692 kB) and some 1,000 frames of
/// two 7-joint episodes (0.8 kB a frame). A longer view is refused, with a line saying so.
pub const BUDGET: usize = 1_500_000;

/// One episode the view shows.
pub struct Shown<'a> {
    /// What the pane's title says (`best: #1 ...`).
    pub label: String,
    pub tool: &'a AnyTool,
    pub trace: &'a TaskTrace,
}

/// The goal point of a tip position task (`kind`), as the first shown episode has it; none for
/// another task, whose goal is no point in space.
pub fn tip_goal(kind: TaskKind, shown: &[Shown]) -> Option<[f64; 3]> {
    let s = shown.first()?;
    if !matches!(kind.error_term().read(), Read::Tip { order: 0 }) {
        return None;
    }
    Some([
        *s.trace.goal.first()?,
        *s.trace.goal.get(1)?,
        *s.trace.goal.get(2)?,
    ])
}

/// The view's blocks for the best and the worst episode (`shown`, one or two): a heading, a
/// paragraph and the view; or, where there can be none (a model without a URDF flange, a view
/// over [`BUDGET`]), one paragraph saying why.
pub fn section(goal: Option<[f64; 3]>, shown: &[Shown]) -> Vec<Block> {
    section_within(goal, shown, BUDGET)
}

/// [`section`] with another budget (the tests' way to exceed it).
pub fn section_within(goal: Option<[f64; 3]>, shown: &[Shown], budget: usize) -> Vec<Block> {
    let Some(first) = shown.first() else {
        return vec![Block::p("There is no 3-D view: no episode to show.")];
    };
    for shown in shown {
        let model = shown.tool.model();
        if tip_offset_parameters(model).is_none() {
            return vec![Block::p(format!(
                "There is no 3-D view: model `{model}` has no URDF (its tool is not at a URDF \
                 flange), so the figures above are the whole picture."
            ))];
        }
    }
    let episodes: Result<Vec<_>, String> = shown
        .iter()
        .map(|s| frames::episode(&s.label, s.tool, s.trace))
        .collect();
    let data = match episodes {
        Ok(episodes) => json!({ "goal": goal, "episodes": episodes }),
        Err(e) => return vec![Block::p(format!("There is no 3-D view: {e}."))],
    };
    let html = match page(&data.to_string()) {
        Ok(html) => html,
        Err(e) => return vec![Block::p(format!("There is no 3-D view: {e}."))],
    };
    if html.len() > budget {
        return vec![Block::p(format!(
            "The 3-D view is not written: it would add {} bytes to report.html, over its budget \
             of {budget} bytes ({} output times per episode; a shorter episode or a longer output \
             step dt fits).",
            html.len(),
            first.trace.t.len()
        ))];
    }
    vec![
        Block::Heading(2, "The arm at work, in 3-D".into()),
        Block::Html {
            markdown: "`report.html` shows these episodes in 3-D: the arm drawn from the \
                       model's kinematics, the tool as its inertia box with its tip, the goal, \
                       and the tip's trail, animated under a time slider."
                .into(),
            html: format!(
                "<p>Two episodes side by side (left, blue; right, red; each named above it): the \
                 arm drawn from the model's own kinematics (links between its joints' axes), the \
                 tool as the box of its mass and inertia with its tip (black), the goal (green) \
                 and the tip's trail. Drag the slider or press play; drag nothing else \
                 (three.js {THREE_RELEASE}, inlined).</p>\n{html}"
            ),
        },
    ]
}

/// The view's markup: the canvas and its controls, the data, three.js and the scene's script.
fn page(data: &str) -> Result<String, String> {
    // Inside <script>, only "</" could end the element early: JSON escapes "<" as \u003c.
    let data = data.replace('<', "\\u003c");
    let library = three::as_classic(THREE_MODULE)?;
    Ok(format!(
        "<section id=\"view3d\">\n\
         <p id=\"view3d-status\" data-state=\"loading\">3-D view: loading (it needs JavaScript and WebGL)</p>\n\
         <div style=\"display:flex;max-width:960px\"><b id=\"view3d-label-0\" style=\"flex:1\"></b>\
         <b id=\"view3d-label-1\" style=\"flex:1\"></b></div>\n\
         <canvas id=\"view3d-canvas\" width=\"960\" height=\"440\" style=\"max-width:100%\"></canvas>\n\
         <div><button id=\"view3d-play\" type=\"button\">pause</button> \
         <input id=\"view3d-slider\" type=\"range\" min=\"0\" max=\"0\" value=\"0\" style=\"width:60%\"> \
         <span id=\"view3d-time\"></span></div>\n\
         <script type=\"application/json\" id=\"view3d-data\">{data}</script>\n\
         <script type=\"module\">\n{library}\n{SCENE_JS}</script>\n</section>"
    ))
}
