//! Progress bars on stderr for runs of many episodes (indicatif), drawn only when asked for (on a
//! terminal): `reproduce` and `rank` share this one.

pub use indicatif::ProgressBar;

/// A bar counting `total` episodes, with the elapsed time, rate and estimate, and the current
/// message (the experiment's id); hidden unless `visible`.
pub fn episodes(visible: bool, total: u64) -> ProgressBar {
    if !visible {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{elapsed_precise} [{bar:40}] {pos}/{len} episodes ({per_sec}, eta {eta}) {msg}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
