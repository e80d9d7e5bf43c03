//! Every text field of an IR holding hostile text (quotes, backslashes, `*/`, a `"]; #[used] ...`
//! that would close a literal and add an item, newlines, carriage returns, Unicode line and
//! paragraph separators, NUL, a byte-order mark, bidirectional controls, Markdown code blocks a
//! doctest would run, very long text) is rendered into every file the renderer makes (the
//! model's Rust and report, the registry's crate, a model library's crate and C header), and
//! each comes out as nothing but a literal or a comment:
//!
//! - each Rust file has exactly the tokens of the same render of the untouched IR, but for
//!   string literals (doc comments are `#[doc = "..."]` literals to the lexer): a payload never
//!   adds, removes or changes an identifier, a punctuation or a bracket; each changed string
//!   literal reads back holding one of the payloads whole, and each changed doc comment is one line, with no
//!   refused character, no Markdown code fence and no indentation (nothing rustdoc would run);
//! - the header preprocesses to exactly what the untouched one does (its text is in comments);
//! - each TOML file parses with the same keys;
//! - the Markdown report has the same number of lines.
//!
//! Which fields are text is found, not listed: each string of the IR is a text field if any
//! one-line text is accepted there by the IR's types and [`ir_check::check_ir`] (names, file
//! names and code are not). The reader refuses the control characters among the payloads before
//! any rendering ([`ir_check::check_text`]); this renders past it, to test the escaping itself.

use std::path::{Path, PathBuf};

use proc_macro2::{Delimiter, TokenStream, TokenTree};
use serde_json::Value;
use toolconf_render::cabi::{render_library, LibraryPackage};
use toolconf_render::escape::refused;
use toolconf_render::{
    ir_check, load_template_tree, load_templates, render, render_registry, Ir, Package,
};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

const LONG: usize = 5000;

fn payloads() -> Vec<String> {
    vec![
        r#"kg", "", ""]; #[used] #[link_section = ".init_array"] static INIT: extern "C" fn() = evil; const _X: [&str; 3] = [""#.into(),
        "a\n#[no_mangle] pub extern \"C\" fn evil() {}\n//".into(),
        "*/ int evil; /* \" \\ ' ` ??/".into(),
        "x\r\ny\rz".into(),
        "\u{2028}fn line() {}\u{2029}\u{85}".into(),
        "nul\0here".into(),
        "\u{feff}bom \u{202e}bidi\u{2066}".into(),
        "    std::process::exit(3); // an indented doctest".into(),
        "```\nstd::process::exit(4);\n```".into(),
        "~~~ rust".into(),
        "-     std::process::exit(5);".into(),
        "{{ model.name }} {% raw %}".into(),
        "\\u{41} \\\" \\".into(),
        "\u{1}\u{1b}[31m\u{7f}".into(),
        "é θ̇ 中文 🦀".into(),
        "x".repeat(LONG),
    ]
}

/// Each string of `value` with its key (`a.b[2].c`), as ir_check names them.
fn leaves(value: &Value) -> Vec<String> {
    let mut out = Vec::new();
    let mut pending = vec![(String::new(), value)];
    while let Some((key, v)) = pending.pop() {
        match v {
            Value::String(_) => out.push(key),
            Value::Array(items) => pending.extend(
                items
                    .iter()
                    .enumerate()
                    .map(|(i, x)| (format!("{key}[{i}]"), x)),
            ),
            Value::Object(map) => pending.extend(map.iter().map(|(k, x)| {
                (
                    if key.is_empty() {
                        k.clone()
                    } else {
                        format!("{key}.{k}")
                    },
                    x,
                )
            })),
            _ => {}
        }
    }
    out.sort();
    out
}

fn at<'a>(value: &'a mut Value, key: &str) -> &'a mut Value {
    let mut v = value;
    for part in key.split('.') {
        let (name, indices) = part.split_once('[').map_or((part, ""), |(n, i)| (n, i));
        v = &mut v[name];
        for i in indices.split('[').filter(|s| !s.is_empty()) {
            v = &mut v[i.trim_end_matches(']').parse::<usize>().unwrap()];
        }
    }
    v
}

/// The IR of a document, its shape checked (the types) but not its fields.
fn shaped(value: &Value) -> Option<Ir> {
    toolconf_render::ir::parse_shape(&value.to_string()).ok()
}

/// The IR with every text field holding a payload (in turn), and the keys of those fields: a
/// string where one line of text passes the types and the fields' check.
fn hostile(base: &Value) -> (Value, Vec<String>) {
    let payloads = payloads();
    let mut text_fields = Vec::new();
    let mut out = base.clone();
    for key in leaves(base) {
        let mut probe = base.clone();
        *at(&mut probe, &key) = Value::String("one line of text".into());
        match shaped(&probe) {
            Some(ir) if ir_check::check_ir(&ir).is_ok() => {}
            _ => continue,
        }
        let payload = &payloads[text_fields.len() % payloads.len()];
        *at(&mut out, &key) = Value::String(payload.clone());
        text_fields.push(key);
    }
    (out, text_fields)
}

/// A token of a file with its groups' brackets in line: a bracket, a literal, or any other
/// token by its text.
enum Flat {
    Bracket(char),
    Literal(proc_macro2::Literal),
    Other(String),
}

fn flat(stream: TokenStream, out: &mut Vec<Flat>) {
    for tree in stream {
        match tree {
            TokenTree::Group(g) => {
                let (open, close) = match g.delimiter() {
                    Delimiter::Parenthesis => ('(', ')'),
                    Delimiter::Brace => ('{', '}'),
                    Delimiter::Bracket => ('[', ']'),
                    Delimiter::None => ('«', '»'),
                };
                out.push(Flat::Bracket(open));
                flat(g.stream(), out);
                out.push(Flat::Bracket(close));
            }
            TokenTree::Literal(l) => out.push(Flat::Literal(l)),
            other => out.push(Flat::Other(other.to_string())),
        }
    }
}

fn lexed(source: &str, file: &str) -> Vec<Flat> {
    let stream: TokenStream = source
        .parse()
        .unwrap_or_else(|e| panic!("{file} does not lex as Rust: {e:?}"));
    let mut out = Vec::new();
    flat(stream, &mut out);
    // rustfmt keeps a trailing comma where it breaks a list over lines, which a long literal
    // makes it do: not a token the text added.
    let mut kept: Vec<Flat> = Vec::with_capacity(out.len());
    for t in out {
        if matches!(t, Flat::Bracket(')' | ']' | '}'))
            && matches!(kept.last(), Some(Flat::Other(c)) if c == ",")
        {
            kept.pop();
        }
        kept.push(t);
    }
    kept
}

/// Whether a doc comment's line (its text after `///`) starts an indented Markdown code block,
/// which rustdoc would compile and run: indented four spaces (beyond the one after `///`), or
/// a list item or block quote whose content is.
fn indented(line: &str) -> bool {
    let text = line.strip_prefix(' ').unwrap_or(line);
    if text.starts_with(' ') {
        return true;
    }
    let marker = text
        .find(|c: char| !(c.is_ascii_digit() || "-*+>.)".contains(c)))
        .unwrap_or(text.len());
    marker > 0 && text[marker..].starts_with("  ")
}

/// The check of one Rust file (module docs).
fn same_rust(base: &str, hostile: &str, file: &str, payloads: &[String]) -> usize {
    let (a, b) = (lexed(base, file), lexed(hostile, file));
    if std::env::var_os("HOSTILE_DUMP").is_some() {
        std::fs::write(format!("/tmp/hostile-{}", file.replace('/', "-")), hostile).unwrap();
    }
    let mut changed = 0;
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        match (x, y) {
            (Flat::Literal(l), Flat::Literal(m)) => {
                if l.to_string() == m.to_string() {
                    continue;
                }
                let lit: syn::LitStr = syn::parse_str(&m.to_string())
                    .unwrap_or_else(|e| panic!("{file}: a changed literal {m} is no string: {e}"));
                let value = lit.value();
                let is_doc = i >= 2 && matches!(&b[i - 2], Flat::Other(d) if d == "doc");
                if is_doc {
                    assert!(
                        !value.chars().any(refused)
                            && !value.contains("```")
                            && !value.contains("~~~"),
                        "{file}: a doc comment holds a refused character or a fence: {value:?}"
                    );
                    assert!(
                        !indented(&value),
                        "{file}: a doc comment is indented: {value:?}"
                    );
                } else {
                    assert!(
                        payloads.iter().any(|p| value.contains(p.as_str())),
                        "{file}: a string literal does not read back holding a payload: {value:?}"
                    );
                }
                changed += 1;
            }
            (Flat::Bracket(x), Flat::Bracket(y)) => assert_eq!(x, y, "{file}: token {i} changed"),
            (Flat::Other(x), Flat::Other(y)) => assert_eq!(x, y, "{file}: token {i} changed"),
            _ => panic!("{file}: token {i} changed its kind"),
        }
    }
    assert_eq!(
        a.len(),
        b.len(),
        "{file}: the hostile text changed the number of tokens"
    );
    changed
}

/// What the C preprocessor makes of a header (its comments gone), with `cc` or `CC`.
fn preprocessed(header: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("toolconf_model.h");
    std::fs::write(&path, header).unwrap();
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let out = std::process::Command::new(cc)
        .args(["-E", "-P", "-dD", "-Wall", "-Werror", "-std=c99", "-x", "c"])
        .arg(&path)
        .output()
        .expect("cc runs");
    assert!(
        out.status.success(),
        "cc -E: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn toml_keys(text: &str, file: &str) -> Vec<String> {
    let table: toml::Table =
        toml::from_str(text).unwrap_or_else(|e| panic!("{file} is not TOML: {e}"));
    let value = toml::Value::Table(table);
    let mut keys = Vec::new();
    let mut pending = vec![(String::new(), &value)];
    while let Some((key, v)) = pending.pop() {
        keys.push(key.clone());
        if let toml::Value::Table(t) = v {
            pending.extend(t.iter().map(|(k, x)| (format!("{key}.{k}"), x)));
        }
    }
    keys.sort();
    keys
}

struct Rendered {
    files: Vec<(String, String)>,
}

fn render_all(ir: &Ir) -> Rendered {
    let root = root();
    let templates = load_templates(&root.join("templates")).unwrap();
    let mut files: Vec<(String, String)> = render(ir, &templates)
        .expect("the model's files render")
        .into_iter()
        .map(|f| (f.file_name, f.contents))
        .collect();
    let registry = load_template_tree(&root.join("templates/registry")).unwrap();
    files.extend(
        render_registry(
            std::slice::from_ref(ir),
            &registry,
            &Package::in_repository(),
        )
        .expect("the registry renders")
        .into_iter()
        .map(|f| (format!("registry/{}", f.file_name), f.contents)),
    );
    let package = LibraryPackage::for_model(&ir.model.name, Path::new("/repository"));
    files.extend(
        render_library(ir, &root.join("templates/cabi"), &package)
            .expect("the library renders")
            .into_iter()
            .map(|f| (format!("cabi/{}", f.path.display()), f.contents)),
    );
    Rendered { files }
}

fn compare(base: &Value) {
    let (hostile_value, fields) = hostile(base);
    assert!(fields.len() > 20, "only {} text fields found", fields.len());
    let payloads = payloads();
    let clean = shaped(base).expect("the fixture reads");
    ir_check::check_ir(&clean).expect("the fixture passes");
    let dirty = shaped(&hostile_value).expect("the hostile IR has the IR's shape");
    // The reader itself refuses it: the first text field holds a refused character.
    let value = serde_json::to_value(&hostile_value).unwrap();
    assert!(ir_check::check_text(&value).is_err());
    let (clean, dirty) = (render_all(&clean), render_all(&dirty));
    let mut literals = 0;
    for ((name, a), (_, b)) in clean.files.iter().zip(&dirty.files) {
        assert_ne!(a, b, "{name}: no text reached it: nothing was tested");
        if name.ends_with(".rs") {
            literals += same_rust(a, b, name, &payloads);
        } else if name.ends_with(".h") {
            assert_eq!(
                preprocessed(a),
                preprocessed(b),
                "{name}: the header's code changed"
            );
        } else if name.ends_with(".toml") {
            assert_eq!(toml_keys(a, name), toml_keys(b, name), "{name}");
        } else if name.ends_with(".md") {
            assert_eq!(
                a.lines().count(),
                b.lines().count(),
                "{name}: lines were added"
            );
        }
    }
    assert!(
        literals > 20,
        "only {literals} literals and doc comments took the text"
    );
}

#[test]
fn a_closed_form_models_text_comes_out_only_as_literals_and_comments() {
    let text = std::fs::read_to_string(root().join("tests/fixtures/pendulum.json")).unwrap();
    compare(&serde_json::from_str(&text).unwrap());
}

#[test]
fn a_urdf_models_report_text_comes_out_only_as_text() {
    // The fixture with a URDF arm's report (generated/panda.json's), rendered through the URDF
    // report's template variant.
    let text = std::fs::read_to_string(root().join("tests/fixtures/pendulum.json")).unwrap();
    let mut value: Value = serde_json::from_str(&text).unwrap();
    let panda: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("generated/panda.json")).unwrap(),
    )
    .unwrap();
    value["report"] = panda["report"].clone();
    value["templates"] = panda["templates"].clone();
    compare(&value);
}
