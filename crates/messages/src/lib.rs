//! # toolconf-messages
//!
//! How a value the user gave is shown back in a message: numbers in a short form, long text
//! clipped. A message is one line a reader can take in, whatever was typed.

use core::fmt;

pub use toolconf_core::display::Short;

/// The most values of a list a message repeats.
pub const LIST_VALUES: usize = 8;

/// Numbers as a message lists them: `[0.1, 2e-9]`, the first [`LIST_VALUES`] of a longer list
/// and how many there are.
pub struct ShortList<'a>(pub &'a [f64]);

impl fmt::Display for ShortList<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_clipped(f, self.0, "values", |f, x| write!(f, "{}", Short(*x)))
    }
}

/// `[a, b, …]`: the first [`LIST_VALUES`] of `items`, each by `each`, then how many `items`
/// (counted as `unit`) there are when that is more.
fn write_clipped<T>(
    f: &mut fmt::Formatter<'_>,
    items: &[T],
    unit: &str,
    each: impl Fn(&mut fmt::Formatter<'_>, &T) -> fmt::Result,
) -> fmt::Result {
    f.write_str("[")?;
    for (i, item) in items.iter().take(LIST_VALUES).enumerate() {
        if i > 0 {
            f.write_str(", ")?;
        }
        each(f, item)?;
    }
    if items.len() > LIST_VALUES {
        write!(f, ", … ({} {unit})", items.len())?;
    }
    f.write_str("]")
}

/// A matrix given row by row, as a message shows it: `[[80, 5], [1, 80]]`, clipped as
/// [`ShortList`] is.
pub struct ShortRows<'a>(pub &'a [Vec<f64>]);

impl fmt::Display for ShortRows<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_clipped(f, self.0, "rows", |f, row| write!(f, "{}", ShortList(row)))
    }
}

/// The most characters of a user's text a message repeats.
pub const CLIP_CHARS: usize = 60;

/// The most characters of another crate's message (toml's, serde_json's) a message repeats:
/// such a message may itself repeat a user's key or value.
pub const CLIP_MESSAGE_CHARS: usize = 300;

/// A user's text as a message repeats it: whole if short, else its first [`CLIP_CHARS`]
/// characters and how long it was (a 10 MB header cell is not echoed), with line breaks and
/// other control characters shown as `\n`, `\u{0}`, … so that the message stays one line.
pub struct Clip<'a>(pub &'a str);

/// Another crate's message, clipped as [`Clip`] is but at [`CLIP_MESSAGE_CHARS`].
pub struct ClipMessage<'a>(pub &'a str);

/// The most characters of a file's path a message repeats: any real path (Linux's PATH_MAX is
/// 4096 bytes) fits, a hostile argument does not.
pub const CLIP_PATH_CHARS: usize = 4096;

/// A file's path as a message names it: whole, control characters escaped as [`Clip`] does; a
/// longer one keeps its last [`CLIP_PATH_CHARS`] characters, so the file's own name is always
/// there, whatever folder it sits in.
pub struct ClipPath<'a>(pub &'a str);

impl fmt::Display for ClipPath<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let total = self.0.chars().count();
        let skip = total.saturating_sub(CLIP_PATH_CHARS);
        if skip > 0 {
            write!(f, "… ({total} characters) ")?;
        }
        let tail: String = self.0.chars().skip(skip).collect();
        clip(f, &tail, usize::MAX)
    }
}

impl fmt::Display for Clip<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        clip(f, self.0, CLIP_CHARS)
    }
}

impl fmt::Display for ClipMessage<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        clip(f, self.0, CLIP_MESSAGE_CHARS)
    }
}

/// `text` up to `most` characters as shown (an escape counts as its length).
fn clip(f: &mut fmt::Formatter<'_>, text: &str, most: usize) -> fmt::Result {
    let mut shown = 0;
    for c in text.chars() {
        let escaped = c.is_control().then(|| c.escape_default().to_string());
        let width = escaped.as_ref().map_or(1, |e| e.chars().count());
        if shown + width > most {
            return write!(f, "… ({} characters)", text.chars().count());
        }
        match escaped {
            Some(e) => f.write_str(&e)?,
            None => write!(f, "{c}")?,
        }
        shown += width;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extreme_numbers_are_short() {
        assert_eq!(Short(5e-324).to_string(), "5e-324");
        assert_eq!(Short(1e308).to_string(), "1e308");
        assert_eq!(Short(0.05).to_string(), "0.05");
        assert_eq!(Short(-1234.5).to_string(), "-1234.5");
        assert_eq!(Short(f64::NAN).to_string(), "NaN");
        assert_eq!(Short(f64::NEG_INFINITY).to_string(), "-inf");
        assert_eq!(Short(-0.0).to_string(), "0");
        assert_eq!(ShortList(&[0.1, 2e-9]).to_string(), "[0.1, 2e-9]");
        assert_eq!(
            ShortList(&[1.0; 100]).to_string(),
            "[1, 1, 1, 1, 1, 1, 1, 1, … (100 values)]"
        );
        assert_eq!(
            ShortRows(&[vec![80.0, 5.0], vec![1.0, 80.0]]).to_string(),
            "[[80, 5], [1, 80]]"
        );
        assert_eq!(Short(1e9).to_string(), "1e9");
        assert_eq!(Short(999999.5).to_string(), "999999.5");
        for x in [0.1 + 0.2, 1e-300, 123456789.125, 3e16] {
            assert_eq!(Short(x).to_string().parse::<f64>().unwrap(), x);
        }
    }

    #[test]
    fn long_text_is_clipped_and_stays_one_line() {
        assert_eq!(Clip("m9").to_string(), "m9");
        let long = "x".repeat(10_000_000);
        let shown = Clip(&long).to_string();
        assert_eq!(
            shown,
            format!("{}… (10000000 characters)", "x".repeat(CLIP_CHARS))
        );
        assert_eq!(Clip("a\nb\0").to_string(), "a\\nb\\u{0}");
        // Escapes count as what they show: never more than CLIP_CHARS of message.
        let zeros = Clip(&"\0".repeat(100)).to_string();
        assert!(zeros.chars().count() <= CLIP_CHARS + 20, "{zeros}");
    }

    #[test]
    fn a_path_keeps_its_file_name_however_deep() {
        let deep = format!("/{}/panda.urdf", "d".repeat(200));
        assert_eq!(ClipPath(&deep).to_string(), deep);
        let hostile = format!("/{}/panda.urdf", "d".repeat(10_000));
        let shown = ClipPath(&hostile).to_string();
        assert!(shown.ends_with("/panda.urdf"), "{shown}");
        assert!(shown.starts_with("… (10012 characters) "), "{shown}");
        assert_eq!(ClipPath("a\nb.urdf").to_string(), "a\\nb.urdf");
    }
}
