//! Progress bars on stderr for runs of many episodes (indicatif), drawn only when asked for (on a
//! terminal): `reproduce` and `rank` share this one.

pub use indicatif::ProgressBar;

/// A bar counting `total` episodes, with the elapsed time, rate and estimate, and the current
/// message (the experiment's id); hidden unless `visible`.
pub fn episodes(visible: bool, total: u64) -> ProgressBar {
    counting(visible, total, "episodes ({per_sec}, eta {eta}) {msg}")
}

/// A bar counting `total` items, `counts` following `{pos}/{len}` in the template (e.g.
/// `random tools ({per_sec}, eta {eta})`); hidden unless `visible`.
pub fn counting(visible: bool, total: u64, counts: &str) -> ProgressBar {
    if !visible {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    let template = format!("{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {counts}");
    if let Ok(style) = indicatif::ProgressStyle::with_template(&template) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
