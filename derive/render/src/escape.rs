//! Text reaches generated files only through these functions, one per context the templates put
//! it in: a Rust string literal, a Rust comment (doc or plain, one line), a C comment or string
//! in the header `toolconf_model.h`, a TOML string, a file name. The views ([`crate::model_view`],
//! [`crate::registry`], [`crate::cabi`], ...) apply them; the templates only insert the results.
//!
//! The IR reader refuses text holding a [`refused`] character before anything is rendered
//! ([`crate::ir_check`]); these functions are the second line, so that whatever text reaches a
//! view comes out as the literal or comment it is put in, and nothing else.

/// A character no one-line text field may hold: the control characters (C0, DEL, C1: a newline
/// included), the Unicode line and paragraph separators, the bidirectional controls (which
/// rustc refuses in literals and comments) and the byte-order mark.
pub fn refused(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{2028}'
                | '\u{2029}'
                | '\u{061c}'
                | '\u{200e}'
                | '\u{200f}'
                | '\u{202a}'..='\u{202e}'
                | '\u{2066}'..='\u{2069}'
                | '\u{feff}'
        )
}

/// A Rust string literal of `text`, quotes included: `str`'s `Debug`, which escapes quotes,
/// backslashes and every character that is not printable (`\n`, `\u{202e}`, ...).
pub fn rust_string(text: &str) -> String {
    format!("{text:?}")
}

/// `text` as the text of a one-line Rust comment (`/// …`, `//! …`, `// …`) or TOML comment:
/// each [`refused`] character written as `\u{…}`, runs of spaces made one and the ends trimmed
/// (so that no line of a doc comment is indented into a Markdown code block, which rustdoc
/// would compile and run as a doctest), and each backtick or tilde of a run of three or more
/// escaped with a backslash (no code fence either). Text a derivation writes is unchanged.
pub fn comment(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let chars: Vec<char> = text.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        if refused(c) {
            out += &format!("\\u{{{:x}}}", c as u32);
        } else if c == ' ' {
            if !out.is_empty() && !out.ends_with(' ') {
                out.push(' ');
            }
        } else if (c == '`' || c == '~') && fence_run(&chars, i) {
            out.push('\\');
            out.push(c);
        } else {
            out.push(c);
        }
    }
    out.truncate(out.trim_end_matches(' ').len());
    out
}

/// Whether the character at `i` belongs to a run of three or more of itself.
fn fence_run(chars: &[char], i: usize) -> bool {
    let c = chars[i];
    let before = chars[..i].iter().rev().take_while(|&&x| x == c).count();
    let after = chars[i + 1..].iter().take_while(|&&x| x == c).count();
    before + 1 + after >= 3
}

/// `text` inside a C block comment of the header: [`comment`], with `*/` and `/*` broken up
/// (`* /`, `/ *`) so that the comment neither ends nor nests.
pub fn c_comment(text: &str) -> String {
    let mut out = comment(text);
    while out.contains("*/") || out.contains("/*") {
        out = out.replace("*/", "* /").replace("/*", "/ *");
    }
    out
}

/// A C string literal of `text`, quotes included: printable ASCII as it is but for `"`, `\` and
/// `?` (no trigraph), every other byte of its UTF-8 as a three-digit octal escape.
pub fn c_string(text: &str) -> String {
    let mut out = String::from("\"");
    for b in text.bytes() {
        match b {
            b'"' | b'\\' | b'?' => {
                out.push('\\');
                out.push(b as char);
            }
            0x20..=0x7e => out.push(b as char),
            _ => out += &format!("\\{b:03o}"),
        }
    }
    out.push('"');
    out
}

/// A TOML basic string of `text`, quotes included.
pub fn toml_string(text: &str) -> String {
    let mut s = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => s += "\\\"",
            '\\' => s += "\\\\",
            c if refused(c) => s += &format!("\\u{:04X}", c as u32),
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

/// The longest name of a model, a parameter, a coordinate, a term, a task or a generated
/// function or value: a model's name is part of its library's file name
/// (`libtoolconf_model_<name>.so`) and of cargo's artefacts beside it, which a file system
/// limits to 255 bytes.
pub const MAX_NAME: usize = 64;

/// Why `name` is not a lower-case ASCII name (a letter, then letters, digits or `_`, at most
/// `most` characters, no Rust keyword): the rule of every name a model description gives
/// (description.py's `_check_identifier`, with [`MAX_NAME`]), which becomes a Rust (and C) name
/// and, for a model, part of file names.
pub fn name_problem(name: &str, most: usize) -> Option<String> {
    let ok = name.len() <= most
        && name.bytes().next().is_some_and(|b| b.is_ascii_lowercase())
        && name
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_');
    if !ok {
        return Some(format!(
            "'{}' is not a name: a lower-case ASCII letter, then letters, digits or _, at most \
             {most} characters",
            shown(name)
        ));
    }
    is_keyword(name).then(|| format!("'{name}' is a Rust keyword"))
}

/// Why `name` is not a file name a model's crate holds: ASCII letters, digits, `_`, `-` and
/// `.`, not starting with `.`, at most 128 characters, ending in `suffix`; no folder, so it
/// names a file beside the IR and nowhere else.
pub fn file_name_problem(name: &str, suffix: &str) -> Option<String> {
    let ok = name.len() <= 128
        && !name.starts_with('.')
        && name.ends_with(suffix)
        && name.len() > suffix.len()
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_-.".contains(&b));
    (!ok).then(|| {
        format!(
            "'{}' is not a file name beside the IR (ASCII letters, digits, _, - and ., not \
             starting with ., ending in {suffix}; no folder)",
            shown(name)
        )
    })
}

/// Every edition's strict and reserved keywords (the Rust Reference, "Keywords"), as
/// description.py's RUST_KEYWORDS lists them.
pub const RUST_KEYWORDS: [&str; 52] = [
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "gen", "Self",
];

pub fn is_keyword(word: &str) -> bool {
    RUST_KEYWORDS.contains(&word)
}

/// A value quoted in a message: its first 60 characters, the refused ones escaped.
pub fn shown(text: &str) -> String {
    let mut out: String = text.chars().take(60).flat_map(char::escape_debug).collect();
    let count = text.chars().count();
    if count > 60 {
        out += &format!("… ({count} characters)");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_comment_is_one_line_with_no_markdown_block() {
        assert_eq!(comment("mass of link 1"), "mass of link 1");
        assert_eq!(comment("a\nb\r\u{2028}c"), "a\\u{a}b\\u{d}\\u{2028}c");
        assert_eq!(comment("    indented  code  "), "indented code");
        assert_eq!(comment("```rust"), "\\`\\`\\`rust");
        assert_eq!(comment("`x` and ``y``"), "`x` and ``y``");
        assert_eq!(comment("~~~~"), "\\~\\~\\~\\~");
        assert_eq!(comment("\u{202e}\u{feff}\0"), "\\u{202e}\\u{feff}\\u{0}");
    }

    #[test]
    fn a_c_comment_cannot_end_and_a_c_string_is_ascii() {
        assert_eq!(c_comment("a */ b /* c **/"), "a * / b / * c ** /");
        assert_eq!(c_comment("*//*"), "* // *");
        assert_eq!(
            c_string("a\"b\\c??/é\n"),
            "\"a\\\"b\\\\c\\?\\?/\\303\\251\\012\""
        );
    }

    #[test]
    fn names_and_file_names_follow_their_grammar() {
        assert!(name_problem("arm2_exact", MAX_NAME).is_none());
        for bad in [
            "",
            "Arm",
            "2a",
            "a-b",
            "../../evil",
            "é",
            "fn",
            &"a".repeat(65),
        ] {
            assert!(name_problem(bad, MAX_NAME).is_some(), "{bad}");
        }
        assert!(file_name_problem("arm2.vectors.json", ".vectors.json").is_none());
        for bad in [
            "../x.vectors.json",
            "/etc/x.vectors.json",
            ".vectors.json",
            "a/b.vectors.json",
            "x.json",
        ] {
            assert!(file_name_problem(bad, ".vectors.json").is_some(), "{bad}");
        }
    }

    #[test]
    fn a_toml_string_escapes_what_toml_refuses() {
        assert_eq!(toml_string("a\"\\\n\u{7f}"), "\"a\\\"\\\\\\u000A\\u007F\"");
    }
}
