//! The documentation cannot drift from the program: every command README.md and docs/ show is
//! run here, or names the test that covers it.
//!
//! - A fenced block whose info string is `sh run` (GitHub highlights it as `sh`) is run command by
//!   command (a line ending in `\` continues), with `toolconf` meaning this test's own binary, in
//!   a temporary folder that sees the repository's `examples/` and `derive/` through symbolic
//!   links, so that nothing in the repository is written. Each command must end with status 0, or
//!   with the block's `status=N` (```` ```sh run status=2 ````).
//! - Any other `sh` block is preceded by a comment `<!-- not run … -->` that says why and names at
//!   least one file of the repository: the test, script or target that runs it.
//! - Every relative link and image resolves to a file (and a `#fragment` to one of its headings),
//!   every docs page is reachable from the README's index, README.md has at most 250 lines and no
//!   docs page more than 400.
//! - docs/reference/cli.md names every long flag each subcommand's `--help` lists, and
//!   docs/reference/outputs.md every JSON key and CSV column of the outputs it describes.
//! - No page cites a tracker's entry (its word followed by a number, or its possessive): a page
//!   states the requirement itself.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const README_LINES: usize = 250;
const PAGE_LINES: usize = 400;

/// One fenced code block of a page.
struct Block {
    page: PathBuf,
    /// 1-based line of the opening fence.
    line: usize,
    info: String,
    body: Vec<String>,
    /// The HTML comment right before the fence (blank lines skipped), if any.
    comment: Option<String>,
}

impl Block {
    fn at(&self) -> String {
        format!("{}:{}", rel(&self.page), self.line)
    }

    fn words(&self) -> Vec<&str> {
        self.info.split_whitespace().collect()
    }
}

fn rel(path: &Path) -> String {
    path.strip_prefix(ROOT)
        .unwrap_or(path)
        .display()
        .to_string()
}

/// README.md and every Markdown file under docs/, in a fixed order.
fn pages() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut out = vec![Path::new(ROOT).join("README.md")];
    walk(&Path::new(ROOT).join("docs"), &mut out);
    out
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", rel(path)))
}

/// The fence that opens a block (three or more backticks), with its indentation.
fn fence(line: &str) -> Option<(usize, usize, &str)> {
    let trimmed = line.trim_start();
    let ticks = trimmed.chars().take_while(|&c| c == '`').count();
    (ticks >= 3).then(|| (line.len() - trimmed.len(), ticks, trimmed[ticks..].trim()))
}

/// The fenced blocks of a page, and its lines outside them (for links).
fn parse(page: &Path) -> (Vec<Block>, Vec<(usize, String)>) {
    let text = read(page);
    let lines: Vec<&str> = text.lines().collect();
    let (mut blocks, mut prose) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < lines.len() {
        let Some((indent, ticks, info)) = fence(lines[i]) else {
            prose.push((i + 1, lines[i].to_string()));
            i += 1;
            continue;
        };
        let mut body = Vec::new();
        let mut j = i + 1;
        while j < lines.len()
            && !fence(lines[j]).is_some_and(|(_, t, rest)| t >= ticks && rest.is_empty())
        {
            let line = lines[j];
            let cut = line.len() - line.trim_start().len();
            body.push(line[cut.min(indent)..].to_string());
            j += 1;
        }
        blocks.push(Block {
            page: page.to_path_buf(),
            line: i + 1,
            info: info.to_string(),
            body,
            comment: comment_before(&lines, i),
        });
        i = j + 1;
    }
    (blocks, prose)
}

fn comment_before(lines: &[&str], fence_at: usize) -> Option<String> {
    let mut k = fence_at;
    while k > 0 && lines[k - 1].trim().is_empty() {
        k -= 1;
    }
    if k == 0 || !lines[k - 1].trim_end().ends_with("-->") {
        return None;
    }
    let end = k;
    while k > 0 {
        k -= 1;
        if lines[k].contains("<!--") {
            return Some(lines[k..end].join("\n"));
        }
    }
    None
}

/// A block's commands: one per line, a trailing `\` joining the next; comments and blank lines
/// skipped.
fn commands(block: &Block) -> Vec<String> {
    let mut out = Vec::new();
    let mut current = String::new();
    for line in &block.body {
        let line = line.trim_end();
        if current.is_empty() && (line.trim().is_empty() || line.trim_start().starts_with('#')) {
            continue;
        }
        match line.strip_suffix('\\') {
            Some(head) => current.push_str(head),
            None => {
                current.push_str(line);
                out.push(std::mem::take(&mut current));
            }
        }
    }
    assert!(
        current.is_empty(),
        "a command continues past its block's end"
    );
    out
}

fn all_blocks() -> Vec<Block> {
    pages().iter().flat_map(|p| parse(p).0).collect()
}

/// A folder holding `toolconf` (this test's binary) and a working folder that sees the
/// repository's `examples/` and `derive/`.
struct Sandbox {
    _dir: tempfile::TempDir,
    bin: PathBuf,
    work: PathBuf,
}

impl Sandbox {
    fn new() -> Sandbox {
        let dir = tempfile::tempdir().unwrap();
        let (bin, work) = (dir.path().join("bin"), dir.path().join("work"));
        std::fs::create_dir(&bin).unwrap();
        std::fs::create_dir(&work).unwrap();
        std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_toolconf"), bin.join("toolconf")).unwrap();
        for shared in ["examples", "derive"] {
            std::os::unix::fs::symlink(Path::new(ROOT).join(shared), work.join(shared)).unwrap();
        }
        Sandbox {
            _dir: dir,
            bin,
            work,
        }
    }

    fn run(&self, command: &str) -> (Option<i32>, String) {
        let path = format!(
            "{}:{}",
            self.bin.display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let out = Command::new("bash")
            .args(["-o", "pipefail", "-c", command])
            .current_dir(&self.work)
            .env("PATH", path)
            .env_remove("TOOLCONF_MODEL_PATH")
            .output()
            .unwrap();
        let tail = String::from_utf8_lossy(&out.stderr)
            .lines()
            .rev()
            .take(5)
            .collect::<Vec<_>>()
            .join(" | ");
        (out.status.code(), tail)
    }
}

fn expected_status(block: &Block) -> i32 {
    block
        .words()
        .iter()
        .find_map(|w| w.strip_prefix("status="))
        .map(|s| {
            s.parse()
                .unwrap_or_else(|_| panic!("{}: status={s} is not a number", block.at()))
        })
        .unwrap_or(0)
}

#[test]
fn every_runnable_command_in_the_docs_succeeds() {
    let runnable: Vec<Block> = all_blocks()
        .into_iter()
        .filter(|b| b.words().starts_with(&["sh", "run"]))
        .collect();
    assert!(
        runnable.len() >= 10,
        "only {} runnable blocks found",
        runnable.len()
    );
    let mut failures = Vec::new();
    for block in &runnable {
        let sandbox = Sandbox::new();
        let want = expected_status(block);
        for command in commands(block) {
            let start = Instant::now();
            let (status, stderr) = sandbox.run(&command);
            eprintln!(
                "{} ({:.1} s): {command}",
                block.at(),
                start.elapsed().as_secs_f64()
            );
            if status != Some(want) {
                failures.push(format!(
                    "{}: `{command}` ended with {status:?}, not {want}: {stderr}",
                    block.at()
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} commands failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// A path of the repository named in a comment (a word with a `/` or a `.`, that exists).
fn names_a_file(comment: &str) -> bool {
    comment
        .split(|c: char| c.is_whitespace() || "(),;:`'\"".contains(c))
        .map(|w| w.trim_end_matches(['.', '-', '>']))
        .filter(|w| w.contains('/') || w.contains('.'))
        .any(|w| !w.is_empty() && Path::new(ROOT).join(w).is_file())
}

#[test]
fn every_shell_block_not_run_names_what_covers_it() {
    let mut problems = Vec::new();
    for block in all_blocks() {
        let words = block.words();
        let shell = matches!(words.first(), Some(&("sh" | "bash" | "shell" | "console")));
        if shell && words.get(1) != Some(&"run") {
            match &block.comment {
                Some(c) if c.contains("<!-- not run") && names_a_file(c) => {}
                Some(c) if c.contains("<!-- not run") => problems.push(format!("{}: its comment names no file of the repository", block.at())),
                _ => problems.push(format!("{}: an `sh` block that is neither `sh run` nor preceded by `<!-- not run … -->`", block.at())),
            }
        }
        // A command shown without a language would escape both rules.
        let looks_like_commands = block.body.iter().any(|l| {
            ["toolconf ", "make ", "cargo ", "pip "]
                .iter()
                .any(|p| l.starts_with(p))
        });
        if words.is_empty() && looks_like_commands {
            problems.push(format!("{}: commands in a block without `sh`", block.at()));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(page: &Path) -> BTreeSet<String> {
    parse(page)
        .1
        .iter()
        .filter_map(|(_, l)| l.strip_prefix('#').map(|h| slug(h.trim_start_matches('#'))))
        .collect()
}

/// The targets of `[text](target)` and `![alt](target)` on a line, inline code spans skipped.
fn link_targets(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let unquoted: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
    let mut rest = unquoted.as_str();
    while let Some(at) = rest.find("](") {
        let tail = &rest[at + 2..];
        let Some(end) = tail.find(')') else { break };
        // Mathematics such as `[I O](A² + AB)` has spaces; a link target has none.
        if !tail[..end].contains(char::is_whitespace) {
            out.push(tail[..end].to_string());
        }
        rest = &tail[end..];
    }
    out
}

#[test]
fn every_relative_link_resolves() {
    let mut problems = Vec::new();
    for page in pages() {
        for (line, text) in parse(&page).1 {
            for target in link_targets(&text) {
                if target.contains("://") || target.starts_with("mailto:") {
                    continue;
                }
                let (path, fragment) = target
                    .split_once('#')
                    .map_or((target.as_str(), None), |(p, f)| (p, Some(f)));
                let file = if path.is_empty() {
                    page.clone()
                } else {
                    page.parent().unwrap().join(path)
                };
                let at = format!("{}:{line}", rel(&page));
                if !file.exists() {
                    problems.push(format!("{at}: {target}: no such file"));
                } else if let Some(f) = fragment {
                    if file.extension().is_some_and(|e| e == "md") && !anchors(&file).contains(f) {
                        problems.push(format!("{at}: {target}: no heading #{f} in {}", rel(&file)));
                    }
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_docs_page_is_reachable_from_the_readme() {
    let canonical = |p: &Path| p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
    let root = canonical(Path::new(ROOT));
    let mut seen = BTreeSet::new();
    let mut queue = vec![root.join("README.md")];
    while let Some(page) = queue.pop() {
        if !seen.insert(page.clone()) {
            continue;
        }
        for (_, text) in parse(&page).1 {
            for target in link_targets(&text) {
                let path = target.split('#').next().unwrap_or("");
                if path.ends_with(".md") && !path.contains("://") {
                    let file = canonical(&page.parent().unwrap().join(path));
                    if file.starts_with(&root) && file.is_file() {
                        queue.push(file);
                    }
                }
            }
        }
    }
    let unreached: Vec<String> = pages()
        .iter()
        .filter(|p| !seen.contains(&canonical(p)))
        .map(|p| rel(p))
        .collect();
    assert!(
        unreached.is_empty(),
        "pages no link from README.md leads to: {unreached:?}"
    );
}

#[test]
fn no_page_is_too_long() {
    let mut problems = Vec::new();
    for page in pages() {
        let lines = read(&page).lines().count();
        let limit = if page.ends_with("README.md") && page.parent() == Some(Path::new(ROOT)) {
            README_LINES
        } else {
            PAGE_LINES
        };
        if lines > limit {
            problems.push(format!("{}: {lines} lines, more than {limit}", rel(&page)));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// A reader cannot resolve a tracker's number: the docs state the requirement itself.
/// The tracker's word for an entry, spelled here in parts so that this file passes its own rule.
const TRACKER_WORD: &str = concat!("iss", "ue");

#[test]
fn no_page_cites_a_tracker() {
    let mut problems = Vec::new();
    for page in pages() {
        for (n, line) in read(&page).lines().enumerate() {
            let lower = line.to_lowercase();
            let entry = format!("{TRACKER_WORD} ");
            let numbered = lower
                .match_indices(&entry)
                .any(|(i, m)| lower[i + m.len()..].starts_with(|c: char| c.is_ascii_digit()));
            let possessive = ["'s", "’s"]
                .iter()
                .any(|s| lower.contains(&format!("the {TRACKER_WORD}{s}")));
            if numbered || possessive {
                problems.push(format!("{}:{}: {line}", rel(&page), n + 1));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The long flags a `--help` text lists (`--flag` at the start of an option line).
fn long_flags(help: &str) -> BTreeSet<String> {
    help.lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l
                .strip_prefix('-')
                .filter(|r| !r.starts_with('-'))
                .map_or(l, |r| r.split_once(", ").map_or(r, |(_, b)| b));
            l.strip_prefix("--").map(|r| {
                format!(
                    "--{}",
                    r.split(|c: char| !(c.is_alphanumeric() || c == '-'))
                        .next()
                        .unwrap()
                )
            })
        })
        .filter(|f| f != "--help" && f != "--version")
        .collect()
}

#[test]
fn the_cli_reference_names_every_flag() {
    let reference = read(&Path::new(ROOT).join("docs/reference/cli.md"));
    let toolconf = env!("CARGO_BIN_EXE_toolconf");
    let mut missing = Vec::new();
    for sub in [
        "confidence",
        "simulate",
        "select",
        "rank",
        "design",
        "reproduce",
        "tool",
    ] {
        let out = Command::new(toolconf)
            .args([sub, "--help"])
            .output()
            .unwrap();
        assert!(out.status.success(), "toolconf {sub} --help failed");
        let section = reference
            .split("\n## ")
            .find(|s| {
                s.starts_with(&format!("`toolconf {sub}`")) || s.starts_with(&format!("`{sub}`"))
            })
            .unwrap_or_else(|| panic!("docs/reference/cli.md has no section `toolconf {sub}`"));
        for flag in long_flags(&String::from_utf8_lossy(&out.stdout)) {
            let named = section.contains(&format!("`{flag}`"))
                || section.contains(&format!("`{flag} "))
                || section.contains(&format!("`{flag}="))
                || reference.contains(&format!("`{flag}` (every subcommand"));
            if !named {
                missing.push(format!("toolconf {sub} {flag}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "flags docs/reference/cli.md does not name:\n{}",
        missing.join("\n")
    );
}

/// A JSON value's keys, and those of the objects `paths` lead to (`tools.0`, `timing.confidence_stage`).
fn keys(value: &serde_json::Value, paths: &[&str]) -> BTreeSet<String> {
    let mut out: BTreeSet<String> = value
        .as_object()
        .map(|o| o.keys().cloned().collect())
        .unwrap_or_default();
    for path in paths {
        let inner = path.split('.').try_fold(value, |v, k| {
            k.parse::<usize>().map_or_else(|_| v.get(k), |i| v.get(i))
        });
        let inner = inner.unwrap_or_else(|| panic!("no {path} in the output"));
        out.extend(
            inner
                .as_object()
                .unwrap_or_else(|| panic!("{path} is not an object"))
                .keys()
                .cloned(),
        );
    }
    out
}

/// A column or key as the page writes it: per-joint names with `<i>` for the joint's number
/// (`theta3_dot` is `theta<i>_dot`).
fn documented_as(name: &str) -> String {
    for head in ["theta", "u"] {
        if let Some(rest) = name.strip_prefix(head) {
            let tail = rest.trim_start_matches(|c: char| c.is_ascii_digit());
            if tail.len() < rest.len() {
                return format!("{head}<i>{tail}");
            }
        }
    }
    name.to_string()
}

/// The commands whose JSON docs/reference/outputs.md documents, each with the paths below the
/// top level whose keys it documents too (`tools.0`: the first tool's).
const JSON_OUTPUTS: &[(&str, &[&str])] = &[
    (
        "toolconf confidence --arm 0.3,0.4,0.5,0.2 --task velocity --json",
        &[],
    ),
    (
        "toolconf simulate --arm 0.3,0.4,0.5,0.2 --task position --json --csv arm.csv",
        &[],
    ),
    (
        "toolconf simulate --model panda --params 0.73,0,0,0.06,3e-3,3e-3,1e-3 --task tip_position --json --csv tip.csv",
        &[],
    ),
    (
        "toolconf select --task velocity --tools 3 --json",
        &["tools.0", "choice"],
    ),
    (
        "toolconf rank --tools examples/tools/drawer.csv --task examples/tasks/reach_45.toml --screen 3 --json --csv ranked.csv",
        &[
            "tools.0",
            "timing",
            "timing.confidence_stage",
            "timing.simulation_stage",
        ],
    ),
    (
        "toolconf design --task velocity --design examples/design/reach_and_budget.toml --json",
        &["verification.0"],
    ),
];

/// The CSV files the commands of [`JSON_OUTPUTS`] write, whose columns the page documents.
const CSV_OUTPUTS: [&str; 3] = ["arm.csv", "tip.csv", "ranked.csv"];

/// `command`'s standard output as JSON, run by bash in the sandbox with its `toolconf` first on
/// the PATH; it must succeed.
fn json_of(sandbox: &Sandbox, command: &str) -> serde_json::Value {
    let path = format!(
        "{}:{}",
        sandbox.bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .args(["-c", command])
        .current_dir(&sandbox.work)
        .env("PATH", path)
        .output()
        .unwrap();
    common::assert_ok_with(&out, &format!("{command}: "));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{command}: {e}"))
}

/// The columns of a CSV file the sandbox's commands wrote (its first line that is not a
/// comment), as the page writes them.
fn csv_columns(sandbox: &Sandbox, file: &str) -> BTreeSet<String> {
    let text = read(&sandbox.work.join(file));
    text.lines()
        .find(|l| !l.starts_with('#'))
        .unwrap()
        .split(',')
        .map(documented_as)
        .collect()
}

#[test]
fn the_outputs_reference_names_every_key_and_column() {
    let reference = read(&Path::new(ROOT).join("docs/reference/outputs.md"));
    let sandbox = Sandbox::new();
    let mut names = BTreeSet::new();
    for (command, nested) in JSON_OUTPUTS {
        names.extend(keys(&json_of(&sandbox, command), nested));
    }
    for file in CSV_OUTPUTS {
        names.extend(csv_columns(&sandbox, file));
    }
    let missing: Vec<&String> = names
        .iter()
        .filter(|n| !reference.contains(&format!("`{n}`")))
        .collect();
    assert!(
        missing.is_empty(),
        "keys and columns docs/reference/outputs.md does not name: {missing:?}"
    );
}
